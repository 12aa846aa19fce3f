!> The one error channel of the library: a code, a reason and a message.
!>
!> Library procedures never stop the program; they fill a `status_t` and
!> return. Only `app/` maps codes to exit codes (bad input 2, solver
!> failure 3, I/O error 4, stopped by a signal 128 + its number).
module flexmbs_core_status
    implicit none
    private

    integer, parameter, public :: status_ok = 0
    integer, parameter, public :: status_bad_input = 1
    integer, parameter, public :: status_solver_failure = 2
    integer, parameter, public :: status_io_error = 3
    !> A user callback (e.g. SOLOUT) asked to stop: not an error.
    integer, parameter, public :: status_interrupted = 4
    !> SIGINT or SIGTERM stopped the run (core/signals): outputs flushed and
    !> closed; `reason` is the signal's number.
    integer, parameter, public :: status_signal = 5

    ! Reasons of a solver failure.
    integer, parameter, public :: reason_none = 0
    integer, parameter, public :: reason_step_too_small = 1
    integer, parameter, public :: reason_max_steps = 2
    integer, parameter, public :: reason_singular_matrix = 3
    integer, parameter, public :: reason_newton_failure = 4
    integer, parameter, public :: reason_det_f = 5
    integer, parameter, public :: reason_user_function = 6
    integer, parameter, public :: reason_non_finite = 7
    integer, parameter, public :: reason_projection = 8

    !> Error state: `code` is one of the `status_*` constants, `reason` one of
    !> the `reason_*` constants for solver failures (the signal's number for
    !> status_signal).
    type, public :: status_t
        integer :: code = status_ok
        integer :: reason = reason_none
        character(len=:), allocatable :: message
    contains
        procedure :: ok => status_is_ok
        procedure :: set => status_set
        procedure :: clear => status_clear
        procedure :: text => status_text
    end type status_t

    public :: reason_name

contains

    !> True when no error has been recorded.
    pure logical function status_is_ok(self)
        class(status_t), intent(in) :: self
        status_is_ok = self%code == status_ok
    end function status_is_ok

    !> Record an error with its message (and, for solver failures, a reason).
    pure subroutine status_set(self, code, message, reason)
        class(status_t), intent(inout) :: self
        integer, intent(in) :: code            !! one of status_*
        character(len=*), intent(in) :: message !! what failed, with values
        integer, intent(in), optional :: reason  !! one of reason_*
        self%code = code
        self%message = message
        self%reason = reason_none
        if (present(reason)) self%reason = reason
    end subroutine status_set

    !> Reset to ok.
    pure subroutine status_clear(self)
        class(status_t), intent(inout) :: self
        self%code = status_ok
        self%reason = reason_none
        self%message = ''
    end subroutine status_clear

    !> The message, or 'ok'.
    pure function status_text(self) result(text)
        class(status_t), intent(in) :: self
        character(len=:), allocatable :: text
        if (self%code == status_ok) then
            text = 'ok'
        else if (allocated(self%message)) then
            text = self%message
        else
            text = 'unspecified error'
        end if
    end function status_text

    !> Short name of a failure reason.
    pure function reason_name(reason) result(name)
        integer, intent(in) :: reason
        character(len=:), allocatable :: name
        select case (reason)
        case (reason_step_too_small); name = 'step size too small'
        case (reason_max_steps); name = 'maximum number of steps exceeded'
        case (reason_singular_matrix); name = 'matrix repeatedly singular'
        case (reason_newton_failure); name = 'Newton iteration failed'
        case (reason_det_f); name = 'det F <= 0 at a quadrature point'
        case (reason_user_function); name = 'user function failed'
        case (reason_non_finite); name = 'non-finite value'
        case (reason_projection); name = 'projection did not converge'
        case default; name = 'none'
        end select
    end function reason_name
end module flexmbs_core_status
