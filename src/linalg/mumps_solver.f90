!> Multifrontal sparse LU of shifted iteration matrices c*M - J through MUMPS.
!>
!> Built like klu_solver_t: `init` forms once the union pattern of M, J and
!> the full diagonal (flexmbs_linalg_shifted_pattern) and analyses it for a
!> real and a complex MUMPS instance; each factorisation only gathers values
!> through the slot maps and calls MUMPS (JOB = 2), with no allocation, and
!> the real and the complex factorisations stay alive together. The right-
!> hand side is solved in place (MUMPS reads and writes it directly).
!>
!> A copy of a `mumps_solver_t` made by assignment owns no MUMPS instances
!> (see flexmbs_linalg_mumps) and must be initialised again.
module flexmbs_linalg_mumps_solver
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t, fill_nan
    use flexmbs_linalg_shifted_pattern, only: shifted_pattern_t
    use flexmbs_linalg_mumps, only: mumps_real_t, mumps_complex_t, mumps_factor_t, mumps_reports, &
        mumps_ordering_auto
    implicit none
    private

    character(len=*), parameter :: who = 'mumps solver'

    !> MUMPS factorisations of c*M - J (real c) and c*M - J (complex c).
    type, extends(linear_solver_t), public :: mumps_solver_t
        private
        !> mumps_ordering_* (set before init).
        integer, public :: ordering = mumps_ordering_auto
        !> MUMPS prints its diagnostics (set before init).
        logical, public :: verbose = .false.
        type(shifted_pattern_t) :: pattern       !! union pattern of M, J and diagonal
        type(mumps_real_t) :: lu                 !! real factorisation
        type(mumps_complex_t) :: zlu             !! complex factorisation
        real(wp), allocatable :: values(:)       !! c*M - J on the union pattern
        complex(wp), allocatable :: zvalues(:)
    contains
        procedure :: init => mumps_solver_init
        procedure :: factor_real => mumps_solver_factor_real
        procedure :: factor_complex => mumps_solver_factor_complex
        procedure :: solve_real => mumps_solver_solve_real
        procedure :: solve_complex => mumps_solver_solve_complex
        procedure :: name => mumps_solver_name
        procedure :: ordering_used => mumps_solver_ordering_used
        procedure :: factor_nonzeros => mumps_solver_factor_nonzeros
        procedure :: nonzeros => mumps_solver_nonzeros
        procedure :: destroy => mumps_solver_destroy
        procedure :: report => mumps_solver_report
    end type mumps_solver_t

contains

    !> Build the union pattern of M, J and the diagonal with its slot maps,
    !> and analyse it for the real and the complex instance.
    subroutine mumps_solver_init(self, mass, jac, status)
        class(mumps_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status

        call self%pattern%build(mass, jac, who, status, self%values, self%zvalues)
        if (.not. status%ok()) return
        self%n = self%pattern%order()
        call analyse(self%lu, self, status)
        if (.not. status%ok()) return
        call analyse(self%zlu, self, status)
    end subroutine mumps_solver_init

    subroutine analyse(lu, self, status)
        class(mumps_factor_t), intent(inout) :: lu
        type(mumps_solver_t), intent(in) :: self
        type(status_t), intent(inout) :: status
        call lu%configure(status, ordering=self%ordering, verbose=self%verbose)
        if (.not. status%ok()) return
        call lu%analyse(self%n, self%pattern%column_pointers(), self%pattern%row_indices(), &
            status)
    end subroutine analyse

    !> Factor c*M - J (real shift).
    subroutine mumps_solver_factor_real(self, c, mass, jac, status)
        class(mumps_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. self%pattern%prepare(mass, jac, who, self%lu%is_analysed(), status)) return
        call self%pattern%real_values(c, self%values)
        call self%lu%factor(self%values, status)
    end subroutine mumps_solver_factor_real

    !> Factor c*M - J with a complex shift c.
    subroutine mumps_solver_factor_complex(self, c, mass, jac, status)
        class(mumps_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. self%pattern%prepare(mass, jac, who, self%zlu%is_analysed(), status)) &
            return
        call self%pattern%complex_values(c, self%zvalues)
        call self%zlu%factor(self%zvalues, status)
    end subroutine mumps_solver_factor_complex

    !> Overwrite b with A⁻¹ b (real factorisation); NaN without a valid
    !> factorisation.
    subroutine mumps_solver_solve_real(self, b)
        class(mumps_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        type(status_t) :: status
        call self%lu%solve(b, status)
        if (.not. status%ok()) call fill_nan(b)
    end subroutine mumps_solver_solve_real

    !> Overwrite b with A⁻¹ b (complex factorisation); NaN on failure.
    subroutine mumps_solver_solve_complex(self, b)
        class(mumps_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        type(status_t) :: status
        call self%zlu%solve(b, status)
        if (.not. status%ok()) call fill_nan(b)
    end subroutine mumps_solver_solve_complex

    function mumps_solver_name(self) result(name)
        class(mumps_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'mumps'
    end function mumps_solver_name

    !> What the factorisations cost (linalg/mumps report).
    function mumps_solver_report(self) result(text)
        class(mumps_solver_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = mumps_reports(self%lu, self%zlu)
    end function mumps_solver_report

    !> The ordering MUMPS chose in the analysis ('scotch', 'pord', 'amf', ...).
    function mumps_solver_ordering_used(self) result(name)
        class(mumps_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = self%lu%ordering_used()
    end function mumps_solver_ordering_used

    !> Entries of the real LU factors (the analysis' estimate before the
    !> first factorisation).
    integer(i8) function mumps_solver_factor_nonzeros(self)
        class(mumps_solver_t), intent(in) :: self
        mumps_solver_factor_nonzeros = self%lu%factor_nonzeros()
    end function mumps_solver_factor_nonzeros

    !> Slots of the union pattern (0 before init).
    pure integer(i8) function mumps_solver_nonzeros(self)
        class(mumps_solver_t), intent(in) :: self
        mumps_solver_nonzeros = self%pattern%nonzeros()
    end function mumps_solver_nonzeros

    !> Terminate the MUMPS instances now (finalisation does it too); init
    !> may follow.
    subroutine mumps_solver_destroy(self)
        class(mumps_solver_t), intent(inout) :: self
        call self%lu%destroy()
        call self%zlu%destroy()
    end subroutine mumps_solver_destroy
end module flexmbs_linalg_mumps_solver
