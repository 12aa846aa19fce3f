!> The Fortran side of ida_observer_shim.c: SUNDIALS' Newton solver given to
!> IDA inside an observer that counts IDA's failed nonlinear solves by
!> cause (docs/solvers.md, "Rejection causes"). IDA's numbers are those of
!> its own Newton solver; the observer only watches.
module flexmbs_dae_ida_observer
    use, intrinsic :: iso_c_binding, only: c_ptr, c_long
    use flexmbs_dae_rejections, only: rejections_t, cause_count, cause_error_test, &
        cause_newton_diverged, cause_newton_slow, cause_singular_matrix, cause_model_refused
    implicit none
    private

    public :: observer_attach, observer_refused, observer_free, observed_rejections

    ! Failed solves by cause, in the order the shim counts them.
    integer, parameter :: observed_causes(4) = [cause_model_refused, cause_singular_matrix, &
        cause_newton_diverged, cause_newton_slow]

    interface
        !> Give IDA (after IDAInit) SUNDIALS' Newton solver, observed; a null
        !> pointer on failure. `y` is IDA's solution N_Vector.
        type(c_ptr) function observer_attach(mem, y, ctx) &
            bind(C, name='flexmbs_ida_observer_attach')
            import :: c_ptr
            type(c_ptr), value :: mem, y, ctx
        end function observer_attach
        !> A callback of the model refused: the cause of the failing solve.
        subroutine observer_refused(nls) bind(C, name='flexmbs_ida_observer_refused')
            import :: c_ptr
            type(c_ptr), value :: nls
        end subroutine observer_refused
        subroutine shim_counts(nls, counts) bind(C, name='flexmbs_ida_observer_counts')
            import :: c_ptr, c_long
            type(c_ptr), value :: nls
            integer(c_long), intent(out) :: counts(4)
        end subroutine shim_counts
        !> Free the solver (after IDAFree).
        subroutine observer_free(nls) bind(C, name='flexmbs_ida_observer_free')
            import :: c_ptr
            type(c_ptr), value :: nls
        end subroutine observer_free
    end interface

contains

    !> IDA's failed attempts by cause: `netf` error-test failures and the
    !> observer's failed solves, with the last refusal's reason.
    function observed_rejections(nls, netf, refusal) result(rejections)
        type(c_ptr), intent(in) :: nls
        integer, intent(in) :: netf
        character(len=*), intent(in) :: refusal
        type(rejections_t) :: rejections
        integer(c_long) :: counts(4)
        integer :: by_cause(cause_count)
        call shim_counts(nls, counts)
        by_cause = 0
        by_cause(cause_error_test) = netf
        by_cause(observed_causes) = int(counts)
        call rejections%restore(by_cause, refusal)
    end function observed_rejections
end module flexmbs_dae_ida_observer
