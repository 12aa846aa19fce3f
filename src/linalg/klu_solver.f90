!> Sparse LU of shifted iteration matrices c*M - J through KLU.
!>
!> `init` builds once the union pattern of M, J and the full diagonal
!> (flexmbs_linalg_shifted_pattern) and analyses it. Each factorisation only
!> gathers values through the slot maps and calls KLU: no allocation. The
!> real and the complex factorisations share the symbolic analysis and stay
!> alive together.
!>
!> A copy of a `klu_solver_t` made by assignment owns no KLU objects (see
!> flexmbs_linalg_klu) and must be initialised again.
module flexmbs_linalg_klu_solver
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t, fill_nan
    use flexmbs_linalg_shifted_pattern, only: shifted_pattern_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_stats_t, klu_ordering_auto, klu_part_real, &
        klu_ordering_name
    implicit none
    private

    character(len=*), parameter :: who = 'klu solver'

    !> KLU factorisations of c*M - J (real c) and c*M - J (complex c).
    type, extends(linear_solver_t), public :: klu_solver_t
        private
        !> klu_ordering_auto | _amd | _nd (set before init).
        integer, public :: ordering = klu_ordering_auto
        type(klu_factor_t) :: lu                 !! pattern, real and complex factors
        type(shifted_pattern_t) :: pattern       !! union pattern of M, J and diagonal
        real(wp), allocatable :: values(:)       !! c*M - J on the union pattern
        complex(wp), allocatable :: zvalues(:)
    contains
        procedure :: init => klu_solver_init
        procedure :: factor_real => klu_solver_factor_real
        procedure :: factor_complex => klu_solver_factor_complex
        procedure :: solve_real => klu_solver_solve_real
        procedure :: solve_complex => klu_solver_solve_complex
        procedure :: name => klu_solver_name
        procedure :: ordering_used => klu_solver_ordering
        procedure :: stats => klu_solver_stats
        procedure :: nonzeros => klu_solver_nonzeros
        procedure :: factor_nonzeros => klu_solver_factor_nonzeros
        procedure :: destroy => klu_solver_destroy
    end type klu_solver_t

contains

    !> Build the union pattern of M, J and the diagonal with its slot maps,
    !> and analyse it.
    subroutine klu_solver_init(self, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status

        call self%pattern%build(mass, jac, who, status, self%values, self%zvalues)
        if (.not. status%ok()) return
        self%n = self%pattern%order()
        call self%lu%analyse(self%n, self%pattern%column_pointers(), &
            self%pattern%row_indices(), status, self%ordering)
    end subroutine klu_solver_init

    !> Factor c*M - J: afresh the first time, afterwards by KLU's refactor,
    !> which keeps the pivot order while it stays good.
    subroutine klu_solver_factor_real(self, c, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. self%pattern%prepare(mass, jac, who, self%lu%is_analysed(), status)) return
        call self%pattern%real_values(c, self%values)
        call self%lu%refactor(self%values, status)
    end subroutine klu_solver_factor_real

    !> Factor c*M - J with a complex shift c, as the real case.
    subroutine klu_solver_factor_complex(self, c, mass, jac, status)
        class(klu_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        if (.not. self%pattern%prepare(mass, jac, who, self%lu%is_analysed(), status)) return
        call self%pattern%complex_values(c, self%zvalues)
        call self%lu%refactor(self%zvalues, status)
    end subroutine klu_solver_factor_complex

    !> Overwrite b with A⁻¹ b (real factorisation); NaN without a valid
    !> factorisation.
    subroutine klu_solver_solve_real(self, b)
        class(klu_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        type(status_t) :: status
        call self%lu%solve(b, status)
        if (.not. status%ok()) call fill_nan(b)
    end subroutine klu_solver_solve_real

    !> Overwrite b with A⁻¹ b (complex factorisation); NaN on failure.
    subroutine klu_solver_solve_complex(self, b)
        class(klu_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        type(status_t) :: status
        call self%lu%solve(b, status)
        if (.not. status%ok()) call fill_nan(b)
    end subroutine klu_solver_solve_complex

    function klu_solver_name(self) result(name)
        class(klu_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'klu'
    end function klu_solver_name

    !> The ordering of the analysis: 'amd' or 'nd' ('' before it).
    function klu_solver_ordering(self) result(name)
        class(klu_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = klu_ordering_name(self%lu%ordering_used())
    end function klu_solver_ordering

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

    !> Entries of the real L + U (-1 before the first factorisation).
    integer(i8) function klu_solver_factor_nonzeros(self)
        class(klu_solver_t), intent(in) :: self
        klu_solver_factor_nonzeros = self%lu%factor_nonzeros(klu_part_real)
    end function klu_solver_factor_nonzeros

    !> Free the KLU objects now (finalisation does it too); init may follow.
    subroutine klu_solver_destroy(self)
        class(klu_solver_t), intent(inout) :: self
        call self%lu%destroy()
    end subroutine klu_solver_destroy
end module flexmbs_linalg_klu_solver
