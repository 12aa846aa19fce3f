!> One RADAU5 attempt (docs/theory.md §5.4–§5.6, §5.8; blocks R3–R7 of
!> §5.5): the checks before it, the Newton iteration, the error estimate
!> and the step-size proposal, then the accepted step with its projection,
!> dense output and outputs and the choice of the next block, or the
!> rejected one.
module flexmbs_dae_radau5_step
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_ok, status_solver_failure, &
        status_interrupted, reason_step_too_small, reason_max_steps, reason_non_finite, &
        reason_det_f
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_model_refused, cause_projection
    use flexmbs_dae_sink, only: sink_t, dense_outputs
    use flexmbs_dae_radau5_state, only: radau5_engine_t, radau5_work_t, eval_f, compute_scal, &
        ieee_nan, c1, c2, c1m1, c2m1, c1mc2, dd1, dd2, dd3, err_floor, first_reject_factor, &
        end_factor, blk_jacobian, blk_factor, blk_attempt
    use flexmbs_dae_radau5_newton, only: starting_values, newton_iteration, &
        unexpected_failure, retry_after_failure
    implicit none
    private
    public :: attempt_block

contains

    !> Block R3, one attempt with the current h and factorisations; it ends
    !> accepted (R4–R6), rejected (R7) or failed (R8), with the next block
    !> set, or it ends the integration (`done`, status set unless at t_end).
    subroutine attempt_block(self, w, problem, y, options, stats, status, sink)
        include 'radau5_step_arguments.inc'
        type(status_t) :: fstatus
        real(wp) :: fac
        integer :: cause, nind1, nind2
        logical :: converged
        self%native%nstep = self%native%nstep + 1
        if (self%native%nstep > options%max_steps) then
            w%abandoned = .true.
            call status%set(status_solver_failure, 'radau5: more than ' // &
                int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                real_text(w%x), reason_max_steps)
            w%done = .true.
            return
        end if
        if (0.1_wp * abs(w%h) <= abs(w%x) * w%uround) then
            w%abandoned = .true.
            ! A model refusal that forced the step down is the reason
            ! (its text closes the message: finish).
            call status%set(status_solver_failure, 'radau5: step size too small, h = ' &
                // real_text(w%h) // ' at t = ' // real_text(w%x), merge(reason_det_f, &
                reason_step_too_small, w%rejection%reason == reason_det_f))
            w%done = .true.
            return
        end if
        ! §1.4: cumulative index scaling of the weights.
        nind1 = w%nind1
        nind2 = w%nind2
        if (nind2 > 0) w%scal(nind1 + 1:nind1 + nind2) = w%scal(nind1 + 1:nind1 + nind2) &
            / w%hhfac
        if (w%nind3 > 0) w%scal(nind1 + nind2 + 1:w%n) = w%scal(nind1 + nind2 + 1:w%n) &
            / (w%hhfac * w%hhfac)
        ! §1.5: starting values.
        call starting_values(self, w)

        ! §1.6: simplified Newton iteration.
        call newton_iteration(self, w, problem, y, stats, converged)
        if (.not. converged) return

        ! §1.7: error estimate.
        if (self%fixed_step) then
            w%err = err_floor
            fstatus%code = status_ok
        else
            call estimate_error(self, w, problem, y, fstatus, cause)
        end if
        if (.not. fstatus%ok()) then
            ! a NaN f0 (F failed at the step start) is the model's refusal
            if (cause == cause_error_test .and. .not. w%f0_status%ok()) then
                fstatus = w%f0_status
                cause = cause_model_refused
            end if
            call unexpected_failure(w, stats, cause, fstatus)
            return
        end if
        ! §1.9: step-size proposal.
        fac = min(self%safe, self%safe * real(1 + 2 * w%nit, wp) / real(w%newt + 2 * w%nit, wp))
        w%quot = max(w%facr, min(w%facl, w%err**0.25_wp / fac))
        w%hnew = w%h / w%quot
        if (self%fixed_step) w%hnew = w%h

        if (w%err < 1.0_wp) then
            call accept_step(self, w, problem, y, options, stats, status, sink)
        else
            call reject_step(self, w, stats)
        end if
    end subroutine attempt_block

    !> §1.7: err from ê = E1⁻¹(f0 + v), v = h⁻¹ M Σ e_i z_i; a second
    !> estimate from f(x, y + ê) on the first step or after a rejection.
    !> A failure's cause: a non-finite err fails the error test, a failed
    !> F is the model's refusal.
    subroutine estimate_error(self, w, problem, y, st, cause)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y(:)
        type(status_t), intent(out) :: st
        integer, intent(out) :: cause
        real(wp) :: hee1, hee2, hee3
        integer :: j
        cause = cause_error_test
        hee1 = dd1 / w%h
        hee2 = dd2 / w%h
        hee3 = dd3 / w%h
        do j = 1, w%n
            w%f1(j) = hee1 * w%z1(j) + hee2 * w%z2(j) + hee3 * w%z3(j)
        end do
        if (w%mass_identity) then
            w%f2 = w%f1
        else
            call w%mass%matvec(w%f1, w%f2)
        end if
        w%cont = w%f2 + w%f0
        call w%ls%solve_real(w%cont)
        self%nsol_error = self%nsol_error + 1
        call weighted_error(w)
        if (.not. ieee_is_finite(w%err)) then
            call st%set(status_solver_failure, 'non-finite error estimate', reason_non_finite)
            return
        end if
        if (w%err < 1.0_wp) return
        if (w%first .or. w%reject) then
            w%cont = y + w%cont
            call eval_f(problem, w%x, w%cont, w%f1, st)
            self%native%nfcn = self%native%nfcn + 1
            if (.not. st%ok()) cause = cause_model_refused
            if (.not. st%ok()) return
            w%cont = w%f1 + w%f2
            call w%ls%solve_real(w%cont)
            self%nsol_error = self%nsol_error + 1
            call weighted_error(w)
            if (.not. ieee_is_finite(w%err)) call st%set(status_solver_failure, &
                'non-finite error estimate', reason_non_finite)
        end if
    end subroutine estimate_error

    subroutine weighted_error(w)
        type(radau5_work_t), intent(inout) :: w
        integer :: j
        w%err = 0.0_wp
        do j = 1, w%n
            w%err = w%err + (w%cont(j) / w%scal(j))**2
        end do
        w%err = sqrt(w%err / real(w%n, wp))
        if (ieee_is_finite(w%err)) w%err = max(w%err, err_floor)
    end subroutine weighted_error

    !> Block R4, accept the step (projection and admissibility may still take it
    !> back), the dense output, the outputs; then R5/R6, or the end at t_end.
    subroutine accept_step(self, w, problem, y, options, stats, status, sink)
        include 'radau5_step_arguments.inc'
        type(status_t) :: fstatus
        real(wp) :: facgus, ak
        integer :: i
        w%first = .false.
        self%native%naccpt = self%native%naccpt + 1
        if (w%pred .and. .not. self%fixed_step) then
            if (self%native%naccpt > 1) then
                facgus = (w%hacc / w%h) * (w%err**2 / w%erracc)**0.25_wp / self%safe
                facgus = max(w%facr, min(w%facl, facgus))
                w%quot = max(w%quot, facgus)
                w%hnew = w%h / w%quot
            end if
            w%hacc = w%h
            w%erracc = max(1.0e-2_wp, w%err)
        end if
        w%xold = w%x
        w%hold_saved = w%hold
        w%hold = w%h
        w%cont = y
        w%x = w%x + w%h
        if (w%last) w%x = w%xend
        do i = 1, w%n
            y(i) = y(i) + w%z3(i)
            ak = (w%z1(i) - w%z2(i)) / c1mc2
            self%dense%cont(i, 1) = (w%z2(i) - w%z3(i)) / c2m1
            self%dense%cont(i, 2) = (ak - self%dense%cont(i, 1)) / c1m1
            self%dense%cont(i, 3) = self%dense%cont(i, 2) - (ak - w%z1(i) / c1) / c2
        end do
        ! §6: projection hook on the accepted step.
        if (problem%has_projection()) then
            call problem%project(w%x, y, fstatus)
            stats%nprj = stats%nprj + 1
            if (.not. fstatus%ok() .or. .not. all(ieee_is_finite(y))) then
                call undo_step(self, w, y, stats, cause_projection, fstatus)
                return
            end if
        end if
        ! A state the model cannot hold (det F <= 0) is never accepted.
        call problem%admissible(w%x, y, fstatus)
        if (.not. fstatus%ok()) then
            call undo_step(self, w, y, stats, cause_model_refused, fstatus)
            return
        end if
        call w%rejection%clear()
        self%dense%cont(:, 0) = y
        self%dense%x = w%x
        self%dense%h = w%h
        stats%t_reached = w%x
        stats%h_last = w%h
        call compute_scal(w, y)
        if (present(sink)) then
            call emit_outputs(self, w, y, options, status, sink)
            if (.not. status%ok()) then
                w%done = .true.
                return
            end if
            if (w%stop_requested) then
                call status%set(status_interrupted, &
                    'radau5: interrupted by the output routine at t = ' // real_text(w%x))
                w%done = .true.
                return
            end if
        end if
        w%caljac = .false.
        if (w%last) then
            self%h_opt = w%hopt
            w%done = .true.
            return
        end if
        call eval_f(problem, w%x, y, w%f0, fstatus)
        self%native%nfcn = self%native%nfcn + 1
        ! A failing f0 shows up as a non-finite error estimate next step.
        w%f0_status = fstatus
        if (.not. fstatus%ok()) w%f0 = ieee_nan()
        call next_step(self, w)
    end subroutine accept_step

    !> Block R5, the next h (the last step ends at t_end); h and the LU kept when
    !> h_new/h lies in [quot1, quot2] and J converged well. R6: refactor,
    !> with a new J unless θ ≤ thet.
    subroutine next_step(self, w)
        class(radau5_engine_t), intent(in) :: self
        type(radau5_work_t), intent(inout) :: w
        real(wp) :: qt
        w%hnew = w%posneg * min(abs(w%hnew), w%hmaxn)
        w%hopt = min(w%h, w%hnew)
        if (w%reject) w%hnew = w%posneg * min(abs(w%hnew), abs(w%h))
        w%reject = .false.
        if ((w%x + w%hnew / self%quot1 - w%xend) * w%posneg >= 0.0_wp .or. (self%fixed_step &
            .and. (w%x + w%hnew * end_factor - w%xend) * w%posneg >= 0.0_wp)) then
            w%h = w%xend - w%x
            w%last = .true.
        else
            qt = w%hnew / w%h
            w%hhfac = w%h
            if (w%theta <= w%thet .and. qt >= self%quot1 .and. qt <= self%quot2) then
                w%block = blk_attempt
                return
            end if
            w%h = w%hnew
        end if
        ! ---- R6 ----
        w%hhfac = w%h
        if (w%theta <= w%thet) then
            w%block = blk_factor
        else
            w%block = blk_jacobian
        end if
    end subroutine next_step

    !> Block R7, the error test failed; h/10 before any acceptance, else h_new.
    subroutine reject_step(self, w, stats)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        type(dae_stats_t), intent(inout) :: stats
        w%reject = .true.
        w%last = .false.
        if (w%first) then
            w%h = w%h * first_reject_factor
            w%hhfac = first_reject_factor
        else
            w%hhfac = w%hnew / w%h
            w%h = w%hnew
        end if
        if (self%native%naccpt >= 1) self%native%nrejct = self%native%nrejct + 1
        call stats%rejections%add(cause_error_test)
        call retry_after_failure(w)
    end subroutine reject_step

    !> Take back the step just accepted and retry with h/2, counted like R8
    !> (`cause`: its projection failed, or the model refused its state;
    !> `why` says how).
    subroutine undo_step(self, w, y, stats, cause, why)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        real(wp), intent(inout) :: y(:)
        type(dae_stats_t), intent(inout) :: stats
        integer, intent(in) :: cause
        type(status_t), intent(in) :: why
        y = w%cont
        w%x = w%xold
        w%hold = w%hold_saved
        self%native%naccpt = self%native%naccpt - 1
        call unexpected_failure(w, stats, cause, why)
    end subroutine undo_step

    !> Dense output at requested times in (xold, x], then the step sink.
    subroutine emit_outputs(self, w, y, options, status, sink)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        real(wp), intent(in) :: y(:)
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout) :: sink
        logical :: failed
        call dense_outputs(sink, self%dense, options, w%nout, w%x, w%posneg, w%iout, w%ytmp, &
                           status, failed)
        if (failed) return
        if (w%want_steps) call sink%step(self%native%naccpt + 1, w%xold, w%x, y, self%dense, &
            w%stop_requested, status)
    end subroutine emit_outputs
end module flexmbs_dae_radau5_step
