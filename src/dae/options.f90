!> Options common to every DAE solver.
module flexmbs_dae_options
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_linear_solver, only: linear_solver_names, linear_solver_names_text
    implicit none
    private

    !> The options common to the solvers: tolerances (scalar or per
    !> component), step and order limits, the linear solver and the Jacobian's source.
    type, public :: dae_options_t
        real(wp) :: rtol = 1.0e-6_wp
        real(wp) :: atol = 1.0e-6_wp
        real(wp), allocatable :: rtol_vector(:) !! per component; overrides rtol
        real(wp), allocatable :: atol_vector(:) !! per component; overrides atol
        real(wp) :: h0 = 0.0_wp     !! initial step; 0 = automatic
        real(wp) :: hmax = 0.0_wp   !! maximal step; 0 = |t_end - t0|
        integer :: max_steps = 100000
        integer :: pmax = 5         !! maximal BDF order / extrapolation stages
        character(len=8) :: linear_solver = 'auto' !! 'auto' | 'dense' | 'klu' | 'band' | 'mumps'
        !> Bandwidths of M and J for 'band' when the caller knows them; -1:
        !> found from the patterns (a dense Jacobian needs them given).
        integer :: band_lower = -1
        integer :: band_upper = -1
        character(len=8) :: jacobian = 'analytic'  !! 'analytic' | 'fd'
        !> Fill-reducing ordering of KLU: 'auto' (AMD, nested dissection for
        !> large matrices on which AMD predicts much fill), 'amd' or 'nd'.
        character(len=8) :: sparse_ordering = 'auto'
        !> Dense LU in the classic elimination order (column by column,
        !> unblocked) instead of LAPACK's: round-off then does not depend on
        !> the BLAS build. The classic faces set it to repeat the original
        !> programs' counters on round-off-sensitive problems.
        logical :: classic_lu = .false.
        !> 'condensed': a problem that offers its own solver of the iteration
        !> matrices (the mechanical formulations) is solved through it;
        !> 'full': every solver factors c M − ∂F/∂y as it stands
        character(len=9) :: newton_system = 'condensed'
        real(wp), allocatable :: output_times(:)   !! dense output at these times
        logical :: output_steps = .false.          !! also every accepted step
    contains
        procedure :: validate => options_validate
        procedure :: tolerances => options_tolerances
    end type dae_options_t

contains

    !> Check ranges for a problem of size n.
    subroutine options_validate(self, n, status)
        class(dae_options_t), intent(in) :: self
        integer, intent(in) :: n
        type(status_t), intent(out) :: status
        character(len=200) :: msg
        if (allocated(self%rtol_vector)) then
            if (size(self%rtol_vector) /= n) then
                call status%set(status_bad_input, 'options: rtol vector length differs from n')
                return
            end if
            if (any(self%rtol_vector <= 0.0_wp)) then
                call status%set(status_bad_input, 'options: rtol must be positive')
                return
            end if
        else if (.not. self%rtol > 0.0_wp) then
            write (msg, '(a,es12.4,a)') 'options: rtol = ', self%rtol, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (allocated(self%atol_vector)) then
            if (size(self%atol_vector) /= n) then
                call status%set(status_bad_input, 'options: atol vector length differs from n')
                return
            end if
            if (any(self%atol_vector <= 0.0_wp)) then
                call status%set(status_bad_input, 'options: atol must be positive')
                return
            end if
        else if (.not. self%atol > 0.0_wp) then
            write (msg, '(a,es12.4,a)') 'options: atol = ', self%atol, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (self%hmax < 0.0_wp) then
            call status%set(status_bad_input, 'options: hmax must not be negative')
        else if (self%max_steps <= 0) then
            call status%set(status_bad_input, 'options: max_steps must be positive')
        else if (self%pmax < 1) then
            call status%set(status_bad_input, 'options: pmax must be at least 1')
        else if (all(self%linear_solver /= linear_solver_names)) then
            call status%set(status_bad_input, "options: linear_solver = '" // &
                trim(self%linear_solver) // "': must be " // linear_solver_names_text)
        else if (self%band_lower < -1 .or. self%band_upper < -1 .or. &
                 ((self%band_lower == -1) .neqv. (self%band_upper == -1))) then
            write (msg, '(a,i0,a,i0,a)') 'options: band_lower = ', self%band_lower, &
                ', band_upper = ', self%band_upper, &
                ': give both (>= 0) or neither (-1, found from the patterns)'
            call status%set(status_bad_input, trim(msg))
        else if (all(self%jacobian /= [character(len=8) :: 'analytic', 'fd'])) then
            call status%set(status_bad_input, "options: jacobian = '" // &
                trim(self%jacobian) // "': must be 'analytic' or 'fd'")
        else if (all(self%sparse_ordering /= [character(len=8) :: 'auto', 'amd', 'nd'])) then
            call status%set(status_bad_input, "options: sparse_ordering = '" // &
                trim(self%sparse_ordering) // "': must be 'auto', 'amd' or 'nd'")
        else if (all(self%newton_system /= [character(len=9) :: 'condensed', 'full'])) then
            call status%set(status_bad_input, "options: newton_system = '" // &
                trim(self%newton_system) // "': must be 'condensed' or 'full'")
        end if
    end subroutine options_validate

    !> Per-component tolerance vectors of length n.
    pure subroutine options_tolerances(self, rtol, atol)
        class(dae_options_t), intent(in) :: self
        real(wp), intent(out) :: rtol(:), atol(:)
        if (allocated(self%rtol_vector)) then
            rtol = self%rtol_vector
        else
            rtol = self%rtol
        end if
        if (allocated(self%atol_vector)) then
            atol = self%atol_vector
        else
            atol = self%atol
        end if
    end subroutine options_tolerances
end module flexmbs_dae_options
