!> Why step attempts failed: counts by cause, one meaning for every solver
!> (docs/solvers.md, "Rejection causes").
!>
!> Every attempt that a solver counts in NST and does not accept is counted
!> here exactly once, by the first thing that decided it: so the counts add
!> up to NRJ = NST − NAC. The causes are
!>
!> - `cause_error_test`: the error estimate was too large (or not finite);
!> - `cause_newton_diverged`: the Newton or corrector iteration diverged
!>   (contraction rate too large, or a non-finite increment);
!> - `cause_newton_slow`: it converged too slowly (too many iterations, or a
!>   predicted rate that would need too many);
!> - `cause_singular_matrix`: the iteration (or augmented) matrix was
!>   singular;
!> - `cause_model_refused`: the model refused an evaluation — an error of F,
!>   G or f (det F ≤ 0, a user function failing), a non-finite value that
!>   the model returned, a state `admissible` refused — with the reason
!>   text of the last refusal;
!> - `cause_projection`: a projection failed or moved the solution too far;
!> - `cause_unstable`: MEXAX's extrapolation was unstable (stability check,
!>   growing column errors, non-finite substep values).
module flexmbs_dae_rejections
    use flexmbs_core_status, only: status_t, status_solver_failure
    use flexmbs_core_text, only: int_text
    implicit none
    private

    integer, parameter, public :: cause_error_test = 1
    integer, parameter, public :: cause_newton_diverged = 2
    integer, parameter, public :: cause_newton_slow = 3
    integer, parameter, public :: cause_singular_matrix = 4
    integer, parameter, public :: cause_model_refused = 5
    integer, parameter, public :: cause_projection = 6
    integer, parameter, public :: cause_unstable = 7
    integer, parameter, public :: cause_count = 7
    !> Longest refusal reason kept (fixed: counting allocates nothing).
    integer, parameter, public :: refusal_len = 160

    !> Names of the causes in the order of the cause_* constants: keys (the
    !> records of a sweep), HDF5 attributes, table headers, the statistics
    !> line, and the phrase of a failure message (singular; plural below).
    character(len=15), parameter, public :: cause_keys(cause_count) = [character(len=15) :: &
        'error_test', 'newton_diverged', 'newton_slow', 'singular_matrix', 'model_refused', &
        'projection', 'unstable']
    character(len=19), parameter, public :: cause_attributes(cause_count) = &
        [character(len=19) :: 'NRJ_ERROR_TEST', 'NRJ_NEWTON_DIVERGED', 'NRJ_NEWTON_SLOW', &
        'NRJ_SINGULAR', 'NRJ_REFUSED', 'NRJ_PROJECTION', 'NRJ_UNSTABLE']
    character(len=15), parameter, public :: cause_labels(cause_count) = [character(len=15) :: &
        'error test', 'Newton diverged', 'Newton slow', 'singular', 'refused', 'projection', &
        'unstable']
    character(len=24), parameter :: phrase_one(cause_count) = [character(len=24) :: &
        'error-test failure', 'Newton divergence', 'slow Newton convergence', &
        'singular matrix', 'model refusal', 'projection failure', 'unstable extrapolation']
    character(len=24), parameter :: phrase_many(cause_count) = [character(len=24) :: &
        'error-test failures', 'Newton divergences', 'slow Newton convergences', &
        'singular matrices', 'model refusals', 'projection failures', &
        'unstable extrapolations']

    !> Failed or rejected step attempts by cause, and the reason of the last
    !> model refusal (the one nearest to where a failing run stopped).
    type, public :: rejections_t
        private
        integer :: counts(cause_count) = 0
        character(len=refusal_len) :: refusal = ''
    contains
        procedure :: add => rejections_add
        procedure :: refuse => rejections_refuse
        procedure :: count_of => rejections_count_of
        procedure :: counts_by_cause => rejections_counts
        procedure :: total => rejections_total
        procedure :: refusal_reason => rejections_refusal_reason
        procedure :: restore => rejections_restore
        procedure :: summary => rejections_summary
        procedure :: failure_text => rejections_failure_text
        procedure :: annotate => rejections_annotate
    end type rejections_t

contains

    !> One more attempt failed by `cause` (a cause_* constant). A model
    !> refusal should come through `refuse`, which keeps its reason.
    pure subroutine rejections_add(self, cause)
        class(rejections_t), intent(inout) :: self
        integer, intent(in) :: cause
        self%counts(cause) = self%counts(cause) + 1
    end subroutine rejections_add

    !> One more attempt failed because the model refused it, for `reason`
    !> (e.g. 'flexible body: element 17: det F = -1.2E-02').
    pure subroutine rejections_refuse(self, reason)
        class(rejections_t), intent(inout) :: self
        character(len=*), intent(in) :: reason
        self%counts(cause_model_refused) = self%counts(cause_model_refused) + 1
        self%refusal = reason
    end subroutine rejections_refuse

    pure integer function rejections_count_of(self, cause) result(n)
        class(rejections_t), intent(in) :: self
        integer, intent(in) :: cause
        n = self%counts(cause)
    end function rejections_count_of

    !> The counts in the order of the cause_* constants.
    pure function rejections_counts(self) result(counts)
        class(rejections_t), intent(in) :: self
        integer :: counts(cause_count)
        counts = self%counts
    end function rejections_counts

    !> Attempts failed for any cause: NRJ when the solver counted them all.
    pure integer function rejections_total(self) result(n)
        class(rejections_t), intent(in) :: self
        n = sum(self%counts)
    end function rejections_total

    !> The reason of the last model refusal ('' when none).
    pure function rejections_refusal_reason(self) result(reason)
        class(rejections_t), intent(in) :: self
        character(len=:), allocatable :: reason
        reason = trim(self%refusal)
    end function rejections_refusal_reason

    !> Set every count and the refusal reason at once (statistics read back
    !> from a record, or taken from another counter such as IDA's).
    pure subroutine rejections_restore(self, counts, refusal)
        class(rejections_t), intent(inout) :: self
        integer, intent(in) :: counts(cause_count)
        character(len=*), intent(in) :: refusal
        self%counts = counts
        self%refusal = refusal
    end subroutine rejections_restore

    !> 'error test 30, Newton slow 5, refused 2': the nonzero causes for the
    !> statistics line ('' when no attempt failed).
    pure function rejections_summary(self) result(text)
        class(rejections_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = cause_list(self, failure=.false.)
    end function rejections_summary

    !> ' after 12 Newton divergences, 3 model refusals (det F ...)': the
    !> nonzero causes for a failure message ('' when no attempt failed).
    pure function rejections_failure_text(self) result(text)
        class(rejections_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = cause_list(self, failure=.true.)
    end function rejections_failure_text

    !> The nonzero causes joined by ', ': labels and counts for the
    !> statistics line, or counts and phrases after ' after ' for a failure.
    pure function cause_list(self, failure) result(text)
        type(rejections_t), intent(in) :: self
        logical, intent(in) :: failure
        character(len=:), allocatable :: text
        integer :: c
        text = ''
        do c = 1, cause_count
            if (self%counts(c) == 0) cycle
            if (len(text) > 0) then
                text = text // ', '
            else if (failure) then
                text = ' after '
            end if
            if (failure) then
                text = text // int_text(self%counts(c)) // ' ' // &
                    trim(merge(phrase_one(c), phrase_many(c), self%counts(c) == 1))
                if (c == cause_model_refused .and. len_trim(self%refusal) > 0) &
                    text = text // ' (' // trim(self%refusal) // ')'
            else
                text = text // trim(cause_labels(c)) // ' ' // int_text(self%counts(c))
            end if
        end do
    end function cause_list

    !> Append the failure text to a solver failure's message.
    pure subroutine rejections_annotate(self, status)
        class(rejections_t), intent(in) :: self
        type(status_t), intent(inout) :: status
        if (status%code /= status_solver_failure .or. .not. allocated(status%message)) return
        status%message = status%message // rejections_failure_text(self)
    end subroutine rejections_annotate
end module flexmbs_dae_rejections
