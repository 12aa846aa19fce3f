!> IDA's steps and outputs (docs/theory.md §8): the output at t0, then
!> either IDA_NORMAL to each output time (IDA interpolates) or IDA_ONE_STEP
!> so that the sink sees every accepted step; every state reached is
!> checked with the model, which IDA cannot take back.
module flexmbs_dae_ida_stepping
    use, intrinsic :: iso_c_binding, only: c_long, c_double
    use fida_mod, only: FIDASetMaxNumSteps, FIDASolve, FIDAGetNumSteps, IDA_NORMAL, &
        IDA_ONE_STEP, IDA_TSTOP_RETURN
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_solver_failure, status_interrupted, &
        reason_max_steps
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_ida_state, only: ida_engine_t, ida_work_t, check, map_failure
    implicit none
    private
    public :: output_start, to_output_times, step_by_step

contains

    !> The dense output over IDA's interpolant, and the output at t0:
    !> requested times equal to t0 and the step sink.
    subroutine output_start(w, options, status, sink)
        type(ida_work_t), intent(inout), target :: w
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        w%dense%mem = w%mem
        w%dense%vector => w%nv_dky
        w%dense%values => w%dkyw
        if (.not. present(sink)) return
        do while (w%iout <= w%nout)
            if ((options%output_times(w%iout) - w%x) * w%posneg > 0.0_wp) exit
            if (options%output_times(w%iout) == w%x) call sink%output(w%x, w%yw, status)
            w%iout = w%iout + 1
            if (.not. status%ok()) return
        end do
        if (w%want_steps) call sink%step(1, w%x, w%x, w%yw, w%dense, w%stop_requested, status)
        if (.not. status%ok()) return
        if (w%stop_requested) call interrupted(w, status)
    end subroutine output_start

    subroutine interrupted(w, status)
        type(ida_work_t), intent(in) :: w
        type(status_t), intent(inout) :: status
        call status%set(status_interrupted, &
            'ida: interrupted by the output routine at t = ' // real_text(w%x))
    end subroutine interrupted

    !> IDA_NORMAL to each output time, then to t_end (IDA interpolates).
    subroutine to_output_times(self, w, problem, t_end, options, stats, status, sink)
        include 'ida_output_arguments.inc'
        class(sink_t), intent(inout), optional :: sink
        real(c_double) :: tret(1)
        real(wp) :: tout
        integer :: nst_now, retval_solve
        do while (w%iout <= w%nout)
            if ((options%output_times(w%iout) - w%x) * w%posneg > 0.0_wp) exit
            w%iout = w%iout + 1
        end do
        do
            tout = t_end
            if (w%iout <= w%nout) then
                if ((options%output_times(w%iout) - t_end) * w%posneg < 0.0_wp) &
                    tout = options%output_times(w%iout)
            end if
            ! max_steps bounds the whole integration, IDA's limit each call.
            nst_now = accepted_steps(w)
            if (.not. check(w, status, FIDASetMaxNumSteps(w%mem, &
                int(max(options%max_steps - nst_now, 1), c_long)), 'IDASetMaxNumSteps')) &
                return
            retval_solve = FIDASolve(w%mem, tout, tret, w%nv_y, w%nv_yp, IDA_NORMAL)
            w%x = tret(1)
            if (retval_solve < 0) then
                call map_failure(self, w, retval_solve, 'step failed', options, stats, status)
                return
            end if
            if (.not. admissible(w, problem, status)) return
            ! past this output time whether or not a sink takes it (without
            ! one the loop would ask for the same time again forever)
            do while (w%iout <= w%nout)
                if (options%output_times(w%iout) /= tout) exit
                if (present(sink)) call sink%output(tout, w%yw, status)
                w%iout = w%iout + 1
                if (.not. status%ok()) return
            end do
            if (tout == t_end .or. retval_solve == IDA_TSTOP_RETURN) exit
        end do
    end subroutine to_output_times

    !> IDA_ONE_STEP, so that the sink sees every accepted step.
    subroutine step_by_step(self, w, problem, t_end, options, stats, status, sink)
        include 'ida_output_arguments.inc'
        class(sink_t), intent(inout) :: sink
        real(c_double) :: tret(1)
        real(wp) :: x_old
        integer :: nac, retval_solve
        x_old = w%x
        if (.not. check(w, status, FIDASetMaxNumSteps(w%mem, int(options%max_steps, c_long)), &
            'IDASetMaxNumSteps')) return
        do
            nac = accepted_steps(w)
            if (nac >= options%max_steps) then
                call status%set(status_solver_failure, 'ida: more than ' // &
                    int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                    real_text(w%x), reason_max_steps)
                return
            end if
            retval_solve = FIDASolve(w%mem, t_end, tret, w%nv_y, w%nv_yp, IDA_ONE_STEP)
            if (retval_solve < 0) then
                w%x = tret(1)
                call map_failure(self, w, retval_solve, 'step failed', options, stats, status)
                return
            end if
            w%x = tret(1)
            if (.not. admissible(w, problem, status)) return
            do while (w%iout <= w%nout)
                if ((options%output_times(w%iout) - w%x) * w%posneg > 0.0_wp) exit
                if (options%output_times(w%iout) == w%x) then
                    call sink%output(w%x, w%yw, status)
                else
                    call w%dense%evaluate(options%output_times(w%iout), w%dkyw)
                    call sink%output(options%output_times(w%iout), w%dkyw, status)
                end if
                w%iout = w%iout + 1
                if (.not. status%ok()) return
            end do
            call sink%step(accepted_steps(w) + 1, x_old, w%x, w%yw, w%dense, &
                w%stop_requested, status)
            if (.not. status%ok()) return
            if (w%stop_requested) then
                call interrupted(w, status)
                return
            end if
            if (retval_solve == IDA_TSTOP_RETURN .or. w%x == t_end) exit
            x_old = w%x
        end do
    end subroutine step_by_step

    !> IDA cannot take back a step: a state the model refuses (det F <= 0)
    !> ends the run there, with that reason, before it is output.
    logical function admissible(w, problem, status)
        type(ida_work_t), intent(in) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(status_t), intent(inout) :: status
        type(status_t) :: st
        call problem%admissible(w%x, w%yw, st)
        admissible = st%ok()
        if (.not. admissible) call status%set(status_solver_failure, 'ida: the model ' // &
            'refuses the state reached at t = ' // real_text(w%x) // ': ' // st%text(), &
            st%reason)
    end function admissible

    integer function accepted_steps(w)
        type(ida_work_t), intent(in) :: w
        integer(c_long) :: count(1)
        count = 0
        if (FIDAGetNumSteps(w%mem, count) /= 0) count = 0
        accepted_steps = int(count(1))
    end function accepted_steps
end module flexmbs_dae_ida_stepping
