!> A sink that stops the integration after the accepted step during which
!> SIGINT or SIGTERM came (core/signals): it wants every step, so a stiff
!> run with far-apart output times still stops within one step. The solver
!> then ends with status interrupted; run_scene reports it as
!> status_signal.
module flexmbs_io_signal_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_signals, only: signal_pending
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    implicit none
    private

    !> The sink that turns SIGINT and SIGTERM into a stop after the current step
    !> (see the module); it has no state of its own.
    type, extends(sink_t), public :: signal_sink_t
    contains
        procedure :: output => signal_output
        procedure :: wants_steps => signal_wants_steps
        procedure :: step => signal_step
    end type signal_sink_t

contains

    !> Output times need nothing: every step is checked.
    subroutine signal_output(self, t, y, status)
        class(signal_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
    end subroutine signal_output

    logical function signal_wants_steps(self)
        class(signal_sink_t), intent(in) :: self
        signal_wants_steps = .true.
    end function signal_wants_steps

    subroutine signal_step(self, nr, t_old, t, y, dense, stop, status)
        class(signal_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        if (signal_pending()) stop = .true.
    end subroutine signal_step
end module flexmbs_io_signal_sink
