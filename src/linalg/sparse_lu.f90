!> A sparse LU of matrices on one fixed CSC pattern, real and complex, by
!> KLU or by MUMPS: for callers that form the values themselves (the
!> condensed Newton matrices of the mechanical formulations) rather than
!> the shifted c*M - J of flexmbs_linalg_klu_solver and _mumps_solver.
!>
!> `analyse` takes the pattern once (0-based CSC, no duplicates) and the
!> choice: sparse_lu_klu, sparse_lu_mumps, or sparse_lu_auto, which asks
!> KLU's symbolic analysis (AMD) for the predicted fill and takes MUMPS on
!> large matrices that fill (the thresholds are the caller's, measured on
!> its matrices). The real and the complex factorisation stay alive
!> together; KLU refactors with its old pivot order while that stays good
!> (flexmbs_linalg_klu).
!>
!> A copy made by assignment owns no KLU or MUMPS objects (see
!> flexmbs_linalg_klu and flexmbs_linalg_mumps) and must be analysed again.
module flexmbs_linalg_sparse_lu
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_linalg_linear_solver, only: fill_nan
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_auto, klu_ordering_amd, &
        klu_ordering_nd, klu_part_real, klu_ordering_name
    use flexmbs_linalg_mumps, only: mumps_real_t, mumps_complex_t, mumps_factor_t, mumps_reports, &
        mumps_ordering_auto, mumps_ordering_amd, mumps_ordering_scotch
    implicit none
    private

    !> Which LU: KLU, MUMPS, or the fill rule of `analyse`.
    integer, parameter, public :: sparse_lu_auto = 0
    integer, parameter, public :: sparse_lu_klu = 1
    integer, parameter, public :: sparse_lu_mumps = 2

    public :: sparse_lu_choice

    !> Real and complex LU factors of matrices with one pattern.
    type, public :: sparse_lu_t
        private
        integer :: kind = sparse_lu_klu      !! sparse_lu_klu or _mumps once analysed
        integer :: n = 0
        integer(i8) :: nnz = 0
        real(wp) :: fill = 0.0_wp            !! KLU's predicted fill (auto only)
        type(klu_factor_t) :: klu            !! real and complex (one analysis)
        type(mumps_real_t) :: mumps
        type(mumps_complex_t) :: zmumps
    contains
        procedure :: analyse => lu_analyse
        procedure, private :: factor_real => lu_factor_real
        procedure, private :: factor_complex => lu_factor_complex
        generic :: factor => factor_real, factor_complex
        procedure, private :: solve_real => lu_solve_real
        procedure, private :: solve_complex => lu_solve_complex
        generic :: solve => solve_real, solve_complex
        procedure :: name => lu_name
        procedure :: ordering_used => lu_ordering
        procedure :: order => lu_order
        procedure :: nonzeros => lu_nonzeros
        procedure :: predicted_fill => lu_predicted_fill
        procedure :: factor_nonzeros => lu_factor_nonzeros
        procedure :: destroy => lu_destroy
        procedure :: report => lu_report
    end type sparse_lu_t

contains

    !> Analyse the n x n pattern for `choice` (sparse_lu_*). `ordering`:
    !> 'auto', 'amd' or 'nd' (KLU's nested dissection by METIS; SCOTCH for
    !> MUMPS). With sparse_lu_auto, MUMPS is taken when n >= min_order and
    !> KLU's AMD analysis predicts (nnz(L) + nnz(U)) / nnz(A) >= min_fill.
    subroutine lu_analyse(self, n, colptr, rowind, choice, status, ordering, min_order, min_fill)
        class(sparse_lu_t), intent(inout) :: self
        integer, intent(in) :: n
        integer(i8), intent(in) :: colptr(:), rowind(:) !! 0-based CSC
        integer, intent(in) :: choice
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: ordering
        integer, intent(in), optional :: min_order
        real(wp), intent(in), optional :: min_fill
        character(len=8) :: order
        integer :: klu_order

        call default_blas_threads()
        order = 'auto'
        if (present(ordering)) order = ordering
        select case (trim(order))
        case ('auto'); klu_order = klu_ordering_auto
        case ('amd'); klu_order = klu_ordering_amd
        case ('nd'); klu_order = klu_ordering_nd
        case default
            call status%set(status_bad_input, "sparse lu: ordering = '" // trim(order) // &
                "': unknown; use 'auto', 'amd' or 'nd'")
            return
        end select
        self%n = n
        self%nnz = colptr(n + 1)
        self%fill = 0.0_wp
        self%kind = choice
        if (choice == sparse_lu_auto) then
            self%kind = sparse_lu_klu
            if (present(min_order) .and. present(min_fill)) then
                self%kind = sparse_lu_choice(n, colptr, rowind, min_order, min_fill, &
                    self%fill, status)
                if (.not. status%ok()) return
            end if
        end if
        select case (self%kind)
        case (sparse_lu_klu)
            call self%klu%analyse(n, colptr, rowind, status, klu_order)
        case (sparse_lu_mumps)
            call self%klu%destroy()
            call analyse_mumps(self%mumps, status)
            if (status%ok()) call analyse_mumps(self%zmumps, status)
        case default
            call status%set(status_bad_input, 'sparse lu: unknown choice of LU')
        end select
    contains
        subroutine analyse_mumps(lu, st)
            class(mumps_factor_t), intent(inout) :: lu
            type(status_t), intent(inout) :: st
            integer :: mumps_order
            mumps_order = mumps_ordering_auto
            if (klu_order == klu_ordering_amd) mumps_order = mumps_ordering_amd
            if (klu_order == klu_ordering_nd) mumps_order = mumps_ordering_scotch
            call lu%configure(st, ordering=mumps_order)
            if (st%ok()) call lu%analyse(n, colptr, rowind, st)
        end subroutine analyse_mumps
    end subroutine lu_analyse

    !> The rule of sparse_lu_auto: sparse_lu_mumps when n >= min_order and
    !> KLU's symbolic analysis with AMD predicts fill (nnz(L) + nnz(U)) /
    !> nnz(A) >= min_fill (returned; 0 when not analysed), else sparse_lu_klu.
    !> Costs one AMD ordering, no factorisation.
    integer function sparse_lu_choice(n, colptr, rowind, min_order, min_fill, fill, status) &
        result(kind)
        integer, intent(in) :: n, min_order
        integer(i8), intent(in) :: colptr(:), rowind(:) !! 0-based CSC
        real(wp), intent(in) :: min_fill
        real(wp), intent(out) :: fill
        type(status_t), intent(inout) :: status
        type(klu_factor_t) :: probe
        real(wp) :: lnz, unz
        kind = sparse_lu_klu
        fill = 0.0_wp
        if (n < min_order) return
        call probe%analyse(n, colptr, rowind, status, klu_ordering_amd)
        if (.not. status%ok()) return
        call probe%predicted_fill(lnz, unz)
        fill = (lnz + unz) / real(max(colptr(n + 1), 1_i8), wp)
        if (fill >= min_fill) kind = sparse_lu_mumps
    end function sparse_lu_choice

    !> Factor real values (one per pattern slot).
    subroutine lu_factor_real(self, values, status)
        class(sparse_lu_t), intent(inout) :: self
        real(wp), intent(in) :: values(:)
        type(status_t), intent(out) :: status
        if (self%kind == sparse_lu_mumps) then
            call self%mumps%factor(values, status)
        else
            call self%klu%refactor(values, status)
        end if
    end subroutine lu_factor_real

    !> Factor complex values (one per pattern slot).
    subroutine lu_factor_complex(self, values, status)
        class(sparse_lu_t), intent(inout) :: self
        complex(wp), intent(in) :: values(:)
        type(status_t), intent(out) :: status
        if (self%kind == sparse_lu_mumps) then
            call self%zmumps%factor(values, status)
        else
            call self%klu%refactor(values, status)
        end if
    end subroutine lu_factor_complex

    !> b ← A⁻¹ b with the real factorisation; NaN without one.
    subroutine lu_solve_real(self, b)
        class(sparse_lu_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        type(status_t) :: status
        if (self%kind == sparse_lu_mumps) then
            call self%mumps%solve(b, status)
        else
            call self%klu%solve(b, status)
        end if
        if (.not. status%ok()) call fill_nan(b)
    end subroutine lu_solve_real

    !> b ← A⁻¹ b with the complex factorisation; NaN without one.
    subroutine lu_solve_complex(self, b)
        class(sparse_lu_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        type(status_t) :: status
        if (self%kind == sparse_lu_mumps) then
            call self%zmumps%solve(b, status)
        else
            call self%klu%solve(b, status)
        end if
        if (.not. status%ok()) call fill_nan(b)
    end subroutine lu_solve_complex

    !> 'klu' or 'mumps'.
    function lu_name(self) result(name)
        class(sparse_lu_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = merge('mumps', 'klu  ', self%kind == sparse_lu_mumps)
        name = trim(name)
    end function lu_name

    !> What MUMPS's factorisations cost (linalg/mumps report); '' for KLU.
    function lu_report(self) result(text)
        class(sparse_lu_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = ''
        if (self%kind == sparse_lu_mumps) text = mumps_reports(self%mumps, self%zmumps)
    end function lu_report

    !> The ordering of the analysis ('amd', 'nd', 'scotch', ...).
    function lu_ordering(self) result(name)
        class(sparse_lu_t), intent(in) :: self
        character(len=:), allocatable :: name
        if (self%kind == sparse_lu_mumps) then
            name = self%mumps%ordering_used()
        else
            name = klu_ordering_name(self%klu%ordering_used())
        end if
    end function lu_ordering

    pure integer function lu_order(self)
        class(sparse_lu_t), intent(in) :: self
        lu_order = self%n
    end function lu_order

    !> Slots of the pattern.
    pure integer(i8) function lu_nonzeros(self)
        class(sparse_lu_t), intent(in) :: self
        lu_nonzeros = self%nnz
    end function lu_nonzeros

    !> KLU's predicted fill ratio behind an 'auto' choice (0 when not asked).
    pure real(wp) function lu_predicted_fill(self)
        class(sparse_lu_t), intent(in) :: self
        lu_predicted_fill = self%fill
    end function lu_predicted_fill

    !> Entries of the real LU factors (MUMPS: its estimate before the first
    !> factorisation).
    integer(i8) function lu_factor_nonzeros(self)
        class(sparse_lu_t), intent(in) :: self
        if (self%kind == sparse_lu_mumps) then
            lu_factor_nonzeros = self%mumps%factor_nonzeros()
        else
            lu_factor_nonzeros = self%klu%factor_nonzeros(klu_part_real)
        end if
    end function lu_factor_nonzeros

    !> Free the factors now (finalisation does it too); analyse may follow.
    subroutine lu_destroy(self)
        class(sparse_lu_t), intent(inout) :: self
        call self%klu%destroy()
        call self%mumps%destroy()
        call self%zmumps%destroy()
    end subroutine lu_destroy
end module flexmbs_linalg_sparse_lu
