!> Sparse LU of shifted iteration matrices c*M - J through KLU.
!>
!> `init` builds once the union pattern of M, J and the full diagonal (the
!> shift c*M must always find its slots, and KLU then sees a zero-free
!> diagonal), with maps from the CSC slots of J and M into it, and analyses
!> it. Each factorisation only scatters values through the maps and calls
!> KLU: no allocation. The real and the complex factorisations share the
!> symbolic analysis and stay alive together.
!>
!> A copy of a `klu_solver_t` made by assignment owns no KLU objects (see
!> flexmbs_linalg_klu) and must be initialised again.
!>
!> A dense M or J makes the union pattern full (n² slots): the factory only
!> chooses KLU for a sparse J, and a dense mass matrix is small in practice.
module flexmbs_linalg_klu_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_stats_t, klu_ordering_auto
    implicit none
    private

    !> KLU factorisations of c*M - J (real c) and c*M - J (complex c).
    type, extends(linear_solver_t), public :: klu_solver_t
        private
        !> klu_ordering_auto | _amd | _nd (set before init).
        integer, public :: ordering = klu_ordering_auto
        type(klu_factor_t) :: lu                 !! pattern, real and complex factors
        logical :: full_pattern = .false.        !! union pattern is all n² slots
        integer :: jac_storage = storage_none    !! storages seen at init
        integer :: mass_storage = storage_none
        integer(i8) :: jac_nnz = 0, mass_nnz = 0 !! CSC sizes seen at init
        integer(i8), allocatable :: jac_slot(:)  !! J's CSC slot -> union slot (1-based)
        integer(i8), allocatable :: mass_slot(:) !! M's CSC slot -> union slot
        integer(i8), allocatable :: diag_slot(:) !! diagonal i -> union slot
        real(wp), allocatable :: values(:)       !! c*M - J on the union pattern
        complex(wp), allocatable :: zvalues(:)
    contains
        procedure :: init => klu_solver_init
        procedure :: factor_real => klu_solver_factor_real
        procedure :: factor_complex => klu_solver_factor_complex
        procedure :: solve_real => klu_solver_solve_real
        procedure :: solve_complex => klu_solver_solve_complex
        procedure :: name => klu_solver_name
        procedure :: stats => klu_solver_stats
        procedure :: nonzeros => klu_solver_nonzeros
        procedure :: destroy => klu_solver_destroy
    end type klu_solver_t

contains

    !> Build the union pattern of M, J and the diagonal with its slot maps,
    !> and analyse it.
    subroutine klu_solver_init(self, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer(i8), allocatable :: colptr(:), rowind(:)
        integer :: n

        n = jac%n
        call check_operands(n, mass, jac, status)
        if (.not. status%ok()) return
        self%n = n
        self%jac_storage = jac%storage
        self%mass_storage = mass%storage
        self%jac_nnz = 0
        self%mass_nnz = 0
        if (jac%storage == storage_sparse) self%jac_nnz = jac%csc%nnz
        if (mass%storage == storage_sparse) self%mass_nnz = mass%csc%nnz
        self%full_pattern = jac%storage == storage_dense .or. mass%storage == storage_dense
        if (allocated(self%jac_slot)) deallocate (self%jac_slot)
        if (allocated(self%mass_slot)) deallocate (self%mass_slot)
        if (allocated(self%diag_slot)) deallocate (self%diag_slot)
        if (allocated(self%values)) deallocate (self%values)
        if (allocated(self%zvalues)) deallocate (self%zvalues)
        allocate (self%jac_slot(self%jac_nnz), self%mass_slot(self%mass_nnz), self%diag_slot(n))

        if (self%full_pattern) then
            call full_union(self, n, mass, jac, colptr, rowind)
        else
            call sparse_union(self, n, mass, jac, colptr, rowind, status)
            if (.not. status%ok()) return
        end if
        allocate (self%values(colptr(n + 1)), self%zvalues(colptr(n + 1)))
        call self%lu%analyse(n, colptr, rowind, status, self%ordering)
    end subroutine klu_solver_init

    !> Orders and storages must agree; KLU needs J itself, not a difference
    !> quotient to come. A missing M (storage_none) counts as zero, as in the
    !> dense solver.
    subroutine check_operands(n, mass, jac, status)
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        character(len=200) :: msg
        if (n <= 0) then
            write (msg, '(a,i0,a)') 'klu solver: order of J n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        select case (jac%storage)
        case (storage_dense, storage_sparse)
        case default
            call status%set(status_bad_input, 'klu solver: J must be given in dense or ' // &
                "sparse storage; use linear_solver = 'dense' for a difference Jacobian")
            return
        end select
        if (.not. operand_fits(n, jac)) then
            write (msg, '(a,i0)') 'klu solver: J storage does not have order n = ', n
            call status%set(status_bad_input, trim(msg))
        else if (.not. operand_fits(n, mass)) then
            write (msg, '(a,i0)') 'klu solver: M storage does not have the order of J, n = ', n
            call status%set(status_bad_input, trim(msg))
        end if
    end subroutine check_operands

    logical function operand_fits(n, a)
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: a
        select case (a%storage)
        case (storage_dense)
            operand_fits = .false.
            if (allocated(a%dense)) operand_fits = all(shape(a%dense) == [n, n])
        case (storage_sparse)
            operand_fits = a%csc%is_built() .and. a%csc%nrow == n .and. a%csc%ncol == n
        case default
            operand_fits = .true.
        end select
    end function operand_fits

    !> All n² slots, column by column; slot of (i, j) is (j-1)*n + i.
    subroutine full_union(self, n, mass, jac, colptr, rowind)
        type(klu_solver_t), intent(inout) :: self
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        integer(i8), allocatable, intent(out) :: colptr(:), rowind(:)
        integer :: i, j
        allocate (colptr(n + 1), rowind(int(n, i8) * n))
        do j = 1, n
            colptr(j) = int(j - 1, i8) * n
            do i = 1, n
                rowind(colptr(j) + i) = i - 1
            end do
            self%diag_slot(j) = colptr(j) + j
        end do
        colptr(n + 1) = int(n, i8) * n
        if (jac%storage == storage_sparse) call map_full(jac%csc, n, self%jac_slot)
        if (mass%storage == storage_sparse) call map_full(mass%csc, n, self%mass_slot)
    end subroutine full_union

    subroutine map_full(a, n, slot)
        type(csc_matrix_t), intent(in) :: a
        integer, intent(in) :: n
        integer(i8), intent(out) :: slot(:)
        integer :: j
        integer(i8) :: p
        do j = 1, n
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                slot(p) = int(j - 1, i8) * n + a%rowind(p) + 1
            end do
        end do
    end subroutine map_full

    !> Union of sparse J, sparse or identity M and the diagonal: the entries
    !> are listed as triplets (diagonal, then J's slots, then M's) and merged
    !> by csc_matrix_t%build, whose triplet map is exactly the slot maps.
    subroutine sparse_union(self, n, mass, jac, colptr, rowind, status)
        type(klu_solver_t), intent(inout) :: self
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        integer(i8), allocatable, intent(out) :: colptr(:), rowind(:)
        type(status_t), intent(inout) :: status
        type(csc_matrix_t) :: union
        integer, allocatable :: rows(:), cols(:)
        integer(i8) :: nt, k
        integer :: i

        nt = n + self%jac_nnz + self%mass_nnz
        allocate (rows(nt), cols(nt))
        do i = 1, n
            rows(i) = i
            cols(i) = i
        end do
        k = n
        call list_slots(jac%csc, n, rows, cols, k)
        if (mass%storage == storage_sparse) call list_slots(mass%csc, n, rows, cols, k)
        call union%build(n, n, rows, cols, status)
        if (.not. status%ok()) return
        self%diag_slot = union%triplet_map(1:n)
        self%jac_slot = union%triplet_map(n + 1:n + self%jac_nnz)
        self%mass_slot = union%triplet_map(n + self%jac_nnz + 1:nt)
        call move_alloc(union%colptr, colptr)
        call move_alloc(union%rowind, rowind)
    end subroutine sparse_union

    !> Append the (row, column) of every CSC slot of a, in slot order.
    subroutine list_slots(a, n, rows, cols, k)
        type(csc_matrix_t), intent(in) :: a
        integer, intent(in) :: n
        integer, intent(inout) :: rows(:), cols(:)
        integer(i8), intent(inout) :: k !! last filled triplet
        integer :: j
        integer(i8) :: p
        do j = 1, n
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                k = k + 1
                rows(k) = int(a%rowind(p)) + 1
                cols(k) = j
            end do
        end do
    end subroutine list_slots

    !> Factor c*M - J: afresh the first time, afterwards by KLU's refactor,
    !> which keeps the pivot order while it stays good.
    subroutine klu_solver_factor_real(self, c, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: i, j
        integer(i8) :: p

        if (.not. same_layout(self, mass, jac, status)) return
        self%values = 0.0_wp
        select case (jac%storage)
        case (storage_dense)
            do j = 1, self%n
                do i = 1, self%n
                    p = int(j - 1, i8) * self%n + i
                    self%values(p) = -jac%dense(i, j)
                end do
            end do
        case (storage_sparse)
            do p = 1, self%jac_nnz
                self%values(self%jac_slot(p)) = self%values(self%jac_slot(p)) &
                    - jac%csc%values(p)
            end do
        end select
        select case (mass%storage)
        case (storage_identity)
            do i = 1, self%n
                self%values(self%diag_slot(i)) = self%values(self%diag_slot(i)) + c
            end do
        case (storage_dense)
            do j = 1, self%n
                do i = 1, self%n
                    p = int(j - 1, i8) * self%n + i
                    self%values(p) = self%values(p) + c * mass%dense(i, j)
                end do
            end do
        case (storage_sparse)
            do p = 1, self%mass_nnz
                self%values(self%mass_slot(p)) = self%values(self%mass_slot(p)) &
                    + c * mass%csc%values(p)
            end do
        end select
        call self%lu%refactor(self%values, status)
    end subroutine klu_solver_factor_real

    !> Factor c*M - J with a complex shift c, as the real case.
    subroutine klu_solver_factor_complex(self, c, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: i, j
        integer(i8) :: p

        if (.not. same_layout(self, mass, jac, status)) return
        self%zvalues = (0.0_wp, 0.0_wp)
        select case (jac%storage)
        case (storage_dense)
            do j = 1, self%n
                do i = 1, self%n
                    p = int(j - 1, i8) * self%n + i
                    self%zvalues(p) = -jac%dense(i, j)
                end do
            end do
        case (storage_sparse)
            do p = 1, self%jac_nnz
                self%zvalues(self%jac_slot(p)) = self%zvalues(self%jac_slot(p)) &
                    - jac%csc%values(p)
            end do
        end select
        select case (mass%storage)
        case (storage_identity)
            do i = 1, self%n
                self%zvalues(self%diag_slot(i)) = self%zvalues(self%diag_slot(i)) + c
            end do
        case (storage_dense)
            do j = 1, self%n
                do i = 1, self%n
                    p = int(j - 1, i8) * self%n + i
                    self%zvalues(p) = self%zvalues(p) + c * mass%dense(i, j)
                end do
            end do
        case (storage_sparse)
            do p = 1, self%mass_nnz
                self%zvalues(self%mass_slot(p)) = self%zvalues(self%mass_slot(p)) &
                    + c * mass%csc%values(p)
            end do
        end select
        call self%lu%refactor(self%zvalues, status)
    end subroutine klu_solver_factor_complex

    !> M and J must keep the storages and CSC sizes they had at init: the
    !> slot maps were built for those.
    logical function same_layout(self, mass, jac, status)
        type(klu_solver_t), intent(in) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        same_layout = .false.
        if (.not. self%lu%is_analysed()) then
            call status%set(status_bad_input, 'klu solver: factor called before init ' // &
                '(a copy made by assignment holds no KLU objects: call init on it)')
        else if (jac%storage /= self%jac_storage .or. mass%storage /= self%mass_storage) then
            call status%set(status_bad_input, &
                'klu solver: storage of M or J changed since init; call init again')
        else if (jac%n /= self%n) then
            call status%set(status_bad_input, &
                'klu solver: order of J changed since init; call init again')
        else if (.not. csc_size_is(jac, self%jac_nnz) &
                 .or. .not. csc_size_is(mass, self%mass_nnz)) then
            call status%set(status_bad_input, &
                'klu solver: sparsity pattern of M or J changed since init; call init again')
        else
            same_layout = .true.
        end if
    end function same_layout

    pure logical function csc_size_is(a, nnz)
        type(matrix_t), intent(in) :: a
        integer(i8), intent(in) :: nnz
        csc_size_is = .true.
        if (a%storage == storage_sparse) csc_size_is = a%csc%nnz == nnz
    end function csc_size_is

    !> Overwrite b with A⁻¹ b (real factorisation). Without a valid
    !> factorisation b becomes NaN, so that the failure cannot pass unseen.
    subroutine klu_solver_solve_real(self, b)
        class(klu_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        type(status_t) :: status
        call self%lu%solve(b, status)
        if (.not. status%ok()) b = ieee_value(1.0_wp, ieee_quiet_nan)
    end subroutine klu_solver_solve_real

    !> Overwrite b with A⁻¹ b (complex factorisation); NaN on failure.
    subroutine klu_solver_solve_complex(self, b)
        class(klu_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        type(status_t) :: status
        real(wp) :: nan
        call self%lu%solve(b, status)
        if (.not. status%ok()) then
            nan = ieee_value(1.0_wp, ieee_quiet_nan)
            b = cmplx(nan, nan, kind=wp)
        end if
    end subroutine klu_solver_solve_complex

    function klu_solver_name(self) result(name)
        class(klu_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'klu'
    end function klu_solver_name

    !> KLU statistics of the real (klu_part_real) or complex
    !> (klu_part_complex) factorisation.
    function klu_solver_stats(self, part) result(stats)
        class(klu_solver_t), intent(in) :: self
        integer, intent(in) :: part !! klu_part_real or klu_part_complex
        type(klu_stats_t) :: stats
        stats = self%lu%stats(part)
    end function klu_solver_stats

    !> Slots of the union pattern (0 before init).
    pure integer(i8) function klu_solver_nonzeros(self)
        class(klu_solver_t), intent(in) :: self
        klu_solver_nonzeros = self%lu%nonzeros()
    end function klu_solver_nonzeros

    !> Free the KLU objects now (finalisation does it too); init may follow.
    subroutine klu_solver_destroy(self)
        class(klu_solver_t), intent(inout) :: self
        call self%lu%destroy()
    end subroutine klu_solver_destroy
end module flexmbs_linalg_klu_solver
