!> The step sink of the classic faces whose user routine SOLOUT follows the
!> integration step by step (RADAU5, MEXAX; docs/solvers.md).
!>
!> Both originals share one protocol: SOLOUT is called at the start and after
!> every accepted step, no output times are requested, and SOLOUT stops the
!> integration by setting IRTRN < 0. `solout_sink_t` keeps that protocol; a
!> face extends it with the one thing that differs, how its SOLOUT is called.
module flexmbs_legacy_common_solout_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    implicit none
    private

    public :: solout_sink_t

    !> A sink handing every accepted step to the face's SOLOUT.
    type, abstract, extends(sink_t) :: solout_sink_t
    contains
        procedure :: output => no_output
        procedure :: wants_steps => every_step
        procedure :: step => solout_step
        procedure(call_solout_i), deferred :: call_solout
    end type solout_sink_t

    abstract interface
        !> Call SOLOUT with the face's arguments for the step [t_old, t],
        !> passing irtrn as its IRTRN.
        subroutine call_solout_i(self, nr, t_old, t, y, dense, irtrn)
            import :: solout_sink_t, wp, dense_output_t
            class(solout_sink_t), intent(inout) :: self
            integer, intent(in) :: nr                  !! 1 at t0, then accepted steps + 1
            real(wp), intent(in) :: t_old, t, y(:)     !! the step and the solution at t
            class(dense_output_t), intent(in) :: dense !! the step's dense output
            integer, intent(inout) :: irtrn            !! 0 on entry; < 0: stop
        end subroutine call_solout_i
    end interface

contains

    ! SOLOUT sees steps only; no output times are requested.
    subroutine no_output(self, t, y, status)
        class(solout_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
    end subroutine no_output

    logical function every_step(self)
        class(solout_sink_t), intent(in) :: self
        every_step = .true.
    end function every_step

    ! IRTRN < 0 stops the integration (RADAU5: IDID = 2; MEXAX: IERR = 1).
    subroutine solout_step(self, nr, t_old, t, y, dense, stop, status)
        class(solout_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        logical, intent(inout) :: stop
        type(status_t), intent(inout) :: status
        integer :: irtrn
        irtrn = 0
        call self%call_solout(nr, t_old, t, y, dense, irtrn)
        if (irtrn < 0) stop = .true.
    end subroutine solout_step
end module flexmbs_legacy_common_solout_sink
