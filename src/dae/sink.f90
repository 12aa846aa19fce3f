!> Output of a solver: dense output objects and sinks.
!>
!> A solver calls `output` at every requested output time, with values from
!> its dense output, and (when the sink wants it) `step` after every
!> accepted step with the step's dense output. HDF5 files, tables, the
!> progress display and the classic SOLOUT adapters are sinks.
module flexmbs_dae_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    implicit none
    private

    !> Continuous extension of the last accepted step [t_old, t].
    type, abstract, public :: dense_output_t
    contains
        procedure(evaluate_i), deferred :: evaluate
        procedure :: order => default_order
    end type dense_output_t

    abstract interface
        !> y(s) for s in [t_old, t] of the last accepted step.
        subroutine evaluate_i(self, s, y)
            import :: dense_output_t, wp
            class(dense_output_t), intent(in) :: self
            real(wp), intent(in) :: s
            real(wp), intent(out) :: y(:)
        end subroutine evaluate_i
    end interface

    !> Where a solver's output goes: `output` at every requested time is
    !> required; `step` after accepted steps and `finish` are optional no-ops.
    type, abstract, public :: sink_t
    contains
        procedure(output_i), deferred :: output
        procedure :: wants_steps => default_wants_steps
        procedure :: step => default_step
        procedure :: finish => default_finish
    end type sink_t

    abstract interface
        !> The solution at a requested output time.
        subroutine output_i(self, t, y, status)
            import :: sink_t, wp, status_t
            class(sink_t), intent(inout) :: self
            include 'sink_output_arguments.inc'
        end subroutine output_i
    end interface

    public :: finish_sink, dense_outputs

contains

    !> The order of the multistep formula the last step used (BDF: 1..5);
    !> 0 for methods without one such order (Runge–Kutta, extrapolation).
    integer function default_order(self)
        class(dense_output_t), intent(in) :: self
        default_order = 0
    end function default_order

    !> True when `step` should be called after every accepted step.
    logical function default_wants_steps(self)
        class(sink_t), intent(in) :: self
        default_wants_steps = .false.
    end function default_wants_steps

    !> Called after each accepted step [t_old, t] (and once at t0 with
    !> t_old = t). Setting `stop` ends the integration (status interrupted).
    subroutine default_step(self, nr, t_old, t, y, dense, stop, status)
        class(sink_t), intent(inout) :: self
        include 'sink_step_arguments.inc'
    end subroutine default_step

    !> Called once at the end, successful or not.
    subroutine default_finish(self, status)
        class(sink_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
    end subroutine default_finish

    !> The requested output times up to t (in the direction posneg) from a
    !> step's dense output to the sink: options%output_times(iout) on, of
    !> nout, iout moved past them; y holds one value. `failed`: an output
    !> failed (status says why) and the rest were not given.
    subroutine dense_outputs(sink, dense, options, nout, t, posneg, iout, y, status, failed)
        class(sink_t), intent(inout) :: sink
        class(dense_output_t), intent(in) :: dense
        type(dae_options_t), intent(in) :: options
        integer, intent(in) :: nout
        real(wp), intent(in) :: t, posneg
        integer, intent(inout) :: iout
        real(wp), intent(inout) :: y(:)
        type(status_t), intent(inout) :: status
        logical, intent(out) :: failed
        failed = .false.
        do while (iout <= nout)
            if ((options%output_times(iout) - t) * posneg > 0.0_wp) exit
            call dense%evaluate(options%output_times(iout), y)
            call sink%output(options%output_times(iout), y, status)
            iout = iout + 1
            failed = .not. status%ok()
            if (failed) return
        end do
    end subroutine dense_outputs

    !> The end of an integration for a solver's optional sink: `finish` once,
    !> its error reported only when the integration itself succeeded (a
    !> failed run's status says why it stopped).
    subroutine finish_sink(sink, status)
        class(sink_t), intent(inout), optional :: sink
        type(status_t), intent(inout) :: status
        type(status_t) :: sink_status
        if (.not. present(sink)) return
        call sink%finish(sink_status)
        if (status%ok() .and. .not. sink_status%ok()) status = sink_status
    end subroutine finish_sink
end module flexmbs_dae_sink
