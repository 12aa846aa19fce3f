!> The condensed Newton systems of the mechanical formulations
!> (docs/theory.md §3.7): a `linear_solver_t` for A = c M_dae − J that
!> eliminates the kinematic rows exactly (flexmbs_mbs_condensed_structure)
!> and factors the matrix S that remains, in the velocities, the kept
!> positions and the multipliers: c M − ∂f/∂v − ∂f/∂q T / c + ... on the
!> pattern of the FE stiffness graph and the joints, not three times it.
!>
!> The formulation hands it to the solvers through the DAE interface
!> (dae_problem_t%iteration_solver), so RADAU5 (real and complex), DDASSL
!> and IDA factor and solve through it without knowing mechanics. Solutions
!> are those of A to round-off: no term is dropped or approximated.
!>
!> S is factored by KLU or MUMPS (`choice`: 'klu', 'mumps' or 'auto', the
!> rule of condensed_auto_*). A copy made by assignment owns no KLU or MUMPS
!> objects and must be initialised again.
module flexmbs_mbs_condensed_newton
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t, fill_nan
    use flexmbs_linalg_sparse_lu, only: sparse_lu_t, sparse_lu_klu, sparse_lu_mumps, &
        sparse_lu_choice
    use flexmbs_mbs_condensed_structure, only: condensed_structure_t, condensed_layout_t, &
        max_eliminated_block_klu, max_eliminated_block_mumps
    use flexmbs_mbs_condensed_kernels, only: factor_blocks, w_values, s_values, &
        condensed_solve
    implicit none
    private

    !> `linear_solver = 'auto'` on the condensed matrices S: MUMPS when
    !> S has order >= condensed_auto_min_order and KLU's AMD analysis
    !> predicts fill (nnz(L) + nnz(U)) / nnz(S) >= condensed_auto_min_fill,
    !> otherwise KLU. flexmbs-bench-newton (1 BLAS thread; one real + one
    !> complex factorisation, KLU (its automatic ordering) / MUMPS, with the
    !> order of S and the predicted fill): five-body (305, 2.1) 1.0 with KLU's
    !> solves 4x faster; coupler 4x8x4 (941, 5.2) 8.1; 6x12x6 (2321, 10.5)
    !> 26; 5x20x5 (2600, 10.7) 18; soft arm 80x2x2 (2291, 1.8) 1.3; 320x2x2
    !> (8771, 1.7) 0.9; cube 12^3 (6084, 8.0) 6.3; cantilever 64x8x8 (15552,
    !> 9.0) 6.4 (docs/linear_algebra.md). MUMPS wins from a fill of about 3,
    !> the two are even on slender bodies, and below order ~500 KLU's
    !> cheaper solves decide.
    integer, parameter, public :: condensed_auto_min_order = 500
    real(wp), parameter, public :: condensed_auto_min_fill = 3.0_wp

    character(len=*), parameter :: who = 'condensed Newton system'

    !> A = c M_dae − J through its condensed matrix (module header).
    type, extends(linear_solver_t), public :: condensed_solver_t
        private
        type(condensed_layout_t) :: lay
        character(len=8) :: choice = 'auto'    !! 'auto' | 'klu' | 'mumps'
        character(len=8) :: ordering = 'auto'  !! 'auto' | 'amd' | 'nd'
        !> allocatable, as every derived-type component here: gfortran 12's
        !> finalization wrapper of a non-allocatable one frees only the first
        !> of its derived-type components (valgrind: five of the six blocks'
        !> patterns lost with every solver)
        type(condensed_structure_t), allocatable :: st
        type(sparse_lu_t), allocatable :: lu
        integer(i8), allocatable :: va_slot(:) !! J's slot of (v_i, a_i): v' = a
        real(wp) :: c_real = 0.0_wp
        complex(wp) :: c_complex = (0.0_wp, 0.0_wp)
        real(wp), allocatable :: lu_r(:), w_r(:), s_r(:), rhs_r(:), g_r(:), prod_r(:)
        real(wp), allocatable :: xe_r(:), xk_r(:), rv_r(:), buf_r(:), res_r(:)
        complex(wp), allocatable :: lu_z(:), w_z(:), s_z(:), rhs_z(:), g_z(:), prod_z(:)
        complex(wp), allocatable :: xe_z(:), xk_z(:), rv_z(:), buf_z(:), res_z(:)
        !> KLU on S: its refactorisations keep the old pivot order, which may
        !> cost a few digits; one step of iterative refinement wins them back
        logical :: refine = .false.
        integer, allocatable :: piv_r(:), piv_z(:)
        integer(i8), allocatable :: pos(:)
    contains
        procedure :: init => condensed_init
        procedure :: factor_real => condensed_factor_real
        procedure :: factor_complex => condensed_factor_complex
        procedure :: solve_real => condensed_solve_real
        procedure :: solve_complex => condensed_solve_complex
        procedure :: name => condensed_name
        procedure :: ordering_used => condensed_ordering
        procedure :: report => condensed_report
        procedure :: order => condensed_order
        procedure :: eliminated => condensed_eliminated
        procedure :: largest_block => condensed_largest_block
        procedure :: nonzeros => condensed_nonzeros
        procedure :: factor_nonzeros => condensed_factor_nonzeros
    end type condensed_solver_t

    public :: new_condensed_solver

contains

    !> A solver for the layout `lay`; `choice` and `ordering` as the
    !> options' linear_solver ('auto', 'klu', 'mumps') and sparse_ordering.
    function new_condensed_solver(lay, choice, ordering) result(self)
        type(condensed_layout_t), intent(in) :: lay
        character(len=*), intent(in) :: choice, ordering
        type(condensed_solver_t) :: self
        self%lay = lay
        self%choice = choice
        self%ordering = ordering
    end function new_condensed_solver

    !> Structure, patterns and the analysis of S, once. The LU comes first;
    !> 'auto' decides on S with GGL's joint components kept. KLU then gets
    !> them eliminated (max_eliminated_block_klu), MUMPS keeps them.
    subroutine condensed_init(self, mass, jac, status)
        class(condensed_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: kind
        real(wp) :: fill
        if (mass%storage /= storage_sparse .or. jac%storage /= storage_sparse) then
            call status%set(status_bad_input, who // ': needs M and J in sparse storage')
            return
        end if
        select case (trim(self%choice))
        case ('klu')
            kind = sparse_lu_klu
        case ('mumps', 'auto')
            kind = sparse_lu_mumps
        case default
            call status%set(status_bad_input, who // ": linear_solver = '" // &
                trim(self%choice) // "': use 'auto', 'klu' or 'mumps'")
            return
        end select
        if (.not. allocated(self%lu)) allocate (self%lu)
        call build_structure(kind)
        if (.not. status%ok()) return
        if (trim(self%choice) == 'auto') then
            kind = sparse_lu_choice(self%st%nk, self%st%s%colptr, self%st%s%rowind, &
                condensed_auto_min_order, condensed_auto_min_fill, fill, status)
            if (.not. status%ok()) return
            if (kind == sparse_lu_klu) call build_structure(kind)
            if (.not. status%ok()) return
        end if
        self%n = self%lay%n
        call allocate_values(self, jac, status)
        if (.not. status%ok()) return
        call self%lu%analyse(self%st%nk, self%st%s%colptr, self%st%s%rowind, kind, status, &
            self%ordering)
        self%refine = kind == sparse_lu_klu
    contains
        !> self%st for the LU `lu_kind`: its limit on the blocks eliminated
        subroutine build_structure(lu_kind)
            integer, intent(in) :: lu_kind
            if (allocated(self%st)) deallocate (self%st)
            allocate (self%st)
            call self%st%build(self%lay, mass%csc, jac%csc, merge(max_eliminated_block_klu, &
                max_eliminated_block_mumps, lu_kind == sparse_lu_klu), status)
        end subroutine build_structure
    end subroutine condensed_init

    !> The value and work arrays for the structure in self%st.
    subroutine allocate_values(self, jac, status)
        type(condensed_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: jac
        type(status_t), intent(inout) :: status
        integer :: stat, i, nr
        associate (st => self%st)
            nr = max(st%comp_ptr(st%ncomp + 1) - 1, 1)
            allocate (self%lu_r(st%lu_size()), self%lu_z(st%lu_size()), self%piv_r(nr), &
                self%piv_z(nr), self%w_r(st%w%nnz), self%w_z(st%w%nnz), self%s_r(st%s%nnz), &
                self%s_z(st%s%nnz), self%rhs_r(st%rhs_size()), self%rhs_z(st%rhs_size()), &
                self%g_r(st%gather_size()), self%g_z(st%gather_size()), &
                self%prod_r(st%product_size()), self%prod_z(st%product_size()), &
                self%xe_r(st%ne), self%xe_z(st%ne), self%xk_r(st%nk), self%xk_z(st%nk), &
                self%res_r(st%nk), self%res_z(st%nk), &
                self%rv_r(st%nv), self%rv_z(st%nv), self%buf_r(max(st%max_block, 1)), &
                self%buf_z(max(st%max_block, 1)), self%pos(st%nk), &
                self%va_slot(merge(st%nv, 0, st%accelerations)), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, who // ' values', 4 * (st%w%nnz + st%s%nnz) + &
                    4 * st%lu_size() + 4 * st%rhs_size() + 3 * st%gather_size() + &
                    3 * st%product_size(), 8)
                return
            end if
            ! the gathered J_KE blocks: their slots outside J_KE's pattern stay zero
            self%g_r = 0.0_wp
            self%g_z = 0.0_wp
            if (st%accelerations) then
                do i = 1, st%nv
                    self%va_slot(i) = jac%csc%find(st%ov + i, st%oa + i)
                end do
            end if
        end associate
    end subroutine allocate_values

    !> The blocks of J and M at this evaluation; false (status set) when the
    !> v rows do not read v' = a.
    logical function gathered(self, mass, jac, status)
        type(condensed_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        integer :: i
        gathered = .false.
        if (.not. allocated(self%pos)) then
            call status%set(status_bad_input, who // ': factor before init')
            return
        end if
        do i = 1, size(self%va_slot)
            if (jac%csc%values(self%va_slot(i)) /= 1.0_wp) then
                call status%set(status_bad_input, who // ': the v rows of J are not v'' = a')
                return
            end if
        end do
        call self%st%jee%gather(jac%csc%values)
        call self%st%jek%gather(jac%csc%values)
        call self%st%jke%gather(jac%csc%values)
        call self%st%jkk%gather(jac%csc%values)
        call self%st%jka%gather(jac%csc%values)
        call self%st%mkk%gather(mass%csc%values)
        gathered = .true.
    end function gathered

    !> Factor A = c M_dae − J (real c): the kinematic blocks, W, S.
    subroutine condensed_factor_real(self, c, mass, jac, status)
        class(condensed_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. gathered(self, mass, jac, status)) return
        self%c_real = c
        call factor_blocks(self%st, c, self%lu_r, self%piv_r, status)
        if (.not. status%ok()) return
        call w_values(self%st, c, self%lu_r, self%piv_r, self%rhs_r, self%w_r)
        call s_values(self%st, c, self%w_r, self%rhs_r, self%g_r, self%prod_r, self%s_r, &
            self%pos)
        call self%lu%factor(self%s_r, status)
    end subroutine condensed_factor_real

    !> Factor A = c M_dae − J with a complex shift c.
    subroutine condensed_factor_complex(self, c, mass, jac, status)
        class(condensed_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. gathered(self, mass, jac, status)) return
        self%c_complex = c
        call factor_blocks(self%st, c, self%lu_z, self%piv_z, status)
        if (.not. status%ok()) return
        call w_values(self%st, c, self%lu_z, self%piv_z, self%rhs_z, self%w_z)
        call s_values(self%st, c, self%w_z, self%rhs_z, self%g_z, self%prod_z, self%s_z, &
            self%pos)
        call self%lu%factor(self%s_z, status)
    end subroutine condensed_factor_complex

    !> b ← A⁻¹ b with the real factorisation.
    subroutine condensed_solve_real(self, b)
        class(condensed_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        if (.not. allocated(self%pos)) then
            call fill_nan(b)
            return
        end if
        call condensed_solve(self%st, self%c_real, self%lu_r, self%piv_r, self%lu, self%s_r, &
            self%refine, b, self%xe_r, self%xk_r, self%res_r, self%rv_r, self%buf_r)
    end subroutine condensed_solve_real

    !> b ← A⁻¹ b with the complex factorisation.
    subroutine condensed_solve_complex(self, b)
        class(condensed_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        if (.not. allocated(self%pos)) then
            call fill_nan(b)
            return
        end if
        call condensed_solve(self%st, self%c_complex, self%lu_z, self%piv_z, self%lu, &
            self%s_z, self%refine, b, self%xe_z, self%xk_z, self%res_z, self%rv_z, self%buf_z)
    end subroutine condensed_solve_complex

    !> 'condensed klu' or 'condensed mumps'.
    function condensed_name(self) result(name)
        class(condensed_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'condensed'
        if (allocated(self%lu)) name = 'condensed ' // self%lu%name()
    end function condensed_name

    !> What the factorisations of S cost (linalg/sparse_lu report).
    function condensed_report(self) result(text)
        class(condensed_solver_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = ''
        if (allocated(self%lu)) text = self%lu%report()
    end function condensed_report

    !> The ordering of S's analysis.
    function condensed_ordering(self) result(name)
        class(condensed_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = ''
        if (allocated(self%lu)) name = self%lu%ordering_used()
    end function condensed_ordering

    !> Order of S.
    pure integer function condensed_order(self)
        class(condensed_solver_t), intent(in) :: self
        condensed_order = 0
        if (allocated(self%st)) condensed_order = self%st%nk
    end function condensed_order

    !> Positions eliminated (the accelerations are eliminated too).
    pure integer function condensed_eliminated(self)
        class(condensed_solver_t), intent(in) :: self
        condensed_eliminated = 0
        if (allocated(self%st)) condensed_eliminated = self%st%ne
    end function condensed_eliminated

    !> Order of the largest kinematic block with a dense LU of its own.
    pure integer function condensed_largest_block(self)
        class(condensed_solver_t), intent(in) :: self
        condensed_largest_block = 0
        if (allocated(self%st)) condensed_largest_block = self%st%max_block
    end function condensed_largest_block

    !> Slots of S's pattern.
    pure integer(i8) function condensed_nonzeros(self)
        class(condensed_solver_t), intent(in) :: self
        condensed_nonzeros = 0
        if (allocated(self%st)) condensed_nonzeros = self%st%s%nnz
    end function condensed_nonzeros

    !> Entries of S's real LU factors.
    integer(i8) function condensed_factor_nonzeros(self)
        class(condensed_solver_t), intent(inout) :: self
        condensed_factor_nonzeros = 0
        if (allocated(self%lu)) condensed_factor_nonzeros = self%lu%factor_nonzeros()
    end function condensed_factor_nonzeros
end module flexmbs_mbs_condensed_newton
