!> One MEXAX macro step (docs/theory.md §7.1–§7.5; §3.3–§3.8 of the
!> reconstruction): the checks before it, the attempt through the columns
!> of the extrapolation tableau in ODEX's order, the restart or rejection
!> after a failed attempt, the projection of the converged column with its
!> rejection test, the accepted point with its dense output and outputs,
!> and the order and step size after it.
module flexmbs_dae_mexax_step
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_step_too_small, &
        reason_max_steps, reason_singular_matrix, reason_non_finite, reason_user_function, &
        reason_det_f
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_singular_matrix, &
        cause_model_refused, cause_projection, cause_unstable
    use flexmbs_dae_sink, only: sink_t, dense_outputs
    use flexmbs_dae_mexax_workspace, only: workspace_t, ev_ok, ev_restart, ev_stop, ev_refused, &
        user_failed
    use flexmbs_dae_mexax_tableau, only: start_point, base_column, extrapolate_column, &
        step_weights, column_error
    use flexmbs_dae_mexax_projection, only: project
    use flexmbs_dae_mexax_state, only: mexax_engine_t, mexax_run_t, mexax_failed_step, &
        mexax_failed_projection, stability_columns, restart_factor, end_factor, epmach, &
        small_step_factor, projection_reject_min, projection_reject_safe, undecided, &
        do_accept, do_reject, do_restart, do_stop
    use flexmbs_dae_mexax_start, only: interrupted
    use flexmbs_dae_mexax_control, only: mexax_control_deuflhard, window_accept, window_reject
    implicit none
    private
    public :: macro_step

contains

    !> One macro step from r%t with H: attempted until accepted, or ended
    !> for a restart, a rejection (the next call retries) or a stop
    !> (`r%done`, status set, or at t_end).
    subroutine macro_step(self, r, problem, t_end, options, stats, status, sink)
        include 'mexax_step_arguments.inc'
        if (r%need_start) then
            call start_point(self%native, problem, r%w, r%t, status, accelerations=.false.)
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_step
                r%done = .true.
                return
            end if
            r%need_start = .false.
        end if
        if (abs(r%h) <= small_step_factor * epmach * max(abs(r%t), r%tscale)) then
            call too_small(r, status)
            r%done = .true.
            return
        end if
        if ((r%t + end_factor * r%h - t_end) * r%posneg >= 0.0_wp) then
            r%h = t_end - r%t
            r%last = .true.
        end if
        self%native%nstep = self%native%nstep + 1
        if (self%native%nstep > options%max_steps) then
            self%native%nstep = self%native%nstep - 1
            call status%set(status_solver_failure, 'mexax: more than ' // &
                int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                real_text(r%t), reason_max_steps)
            r%done = .true.
            return
        end if

        ! ---- one attempt: ODEX's column sequence (§3.4) or Deuflhard's window ----
        r%decision = undecided
        if (r%w%ctl%scheme == mexax_control_deuflhard) then
            call attempt_window(self, r, problem, status)
        else
            call attempt(self, r, problem, status)
        end if

        select case (r%decision)
        case (do_stop)
            call count_failure(r, stats, r%fst)
            r%done = .true.
            return
        case (do_restart)
            ! §3.3/§3.5: H/2, counted in NSTEP, not in NREJCT (ODEX). Only
            ! the very first attempt and the last step take the first-step path.
            call count_failure(r, stats, r%fst)
            self%nstab = self%nstab + 1
            r%h = r%h * restart_factor
            r%reject = .true.
            r%last = .false.
            r%first = .false.
            r%basic_entry = .false.
            return
        case (do_reject)
            call r%w%ctl%order_after_reject(r%kc, r%k, r%h)
            r%h = r%posneg * r%h
            self%native%nrejct = self%native%nrejct + 1
            call stats%rejections%add(cause_error_test)
            r%reject = .true.
            r%last = .false.
            r%basic_entry = .true.
            return
        end select

        ! ---- converged: project (§3.6), then accept ----
        call project_converged(self, r, problem, stats, status)
        if (r%decision == do_stop) r%done = .true.
        if (r%decision /= do_accept) return
        call accept_step(self, r, problem, t_end, options, stats, status, sink)
    end subroutine macro_step

    !> The step-too-small stop, naming non-finite values or the model's
    !> refusal when they drove H down.
    subroutine too_small(r, status)
        type(mexax_run_t), intent(in) :: r
        type(status_t), intent(inout) :: status
        if (r%nstab_nonfinite > 0) then
            call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                // real_text(r%h) // ', at t = ' // real_text(r%t) // ' after ' // &
                int_text(r%nstab_nonfinite) // ' steps with non-finite values (NaN/Inf)', &
                reason_non_finite)
        else if (r%refusal%reason == reason_det_f) then
            call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                // real_text(r%h) // ', at t = ' // real_text(r%t) // &
                '; the model refused the last attempt: ' // r%refusal%text(), reason_det_f)
        else
            call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                // real_text(r%h) // ', at t = ' // real_text(r%t), reason_step_too_small)
        end if
    end subroutine too_small

    !> One attempt from t with H and the planned column k: the columns in
    !> the order of ODEX (§3.4); r%decision (undecided on entry) and r%kc
    !> say how it ended.
    subroutine attempt(self, r, problem, status)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        type(status_t), intent(inout) :: status
        integer :: j
        if (.not. r%basic_entry .and. (r%first .or. r%last)) then
            do j = 1, r%k
                if (.not. column(self, r, problem, j, status)) exit
                if (j >= 2 .and. r%w%ctl%err(j) <= 1.0_wp) then
                    r%kc = j
                    r%decision = do_accept
                    exit
                end if
            end do
            if (r%decision == undecided) then
                r%kc = r%k
                call hope(self, r, problem, status)
            end if
        else
            do j = 1, r%k - 1
                if (.not. column(self, r, problem, j, status)) exit
            end do
            if (r%decision == undecided .and. r%k /= 2 .and. .not. r%reject) then
                ! convergence monitor on column k−1
                r%kc = r%k - 1
                if (r%w%ctl%err(r%k - 1) <= 1.0_wp) then
                    r%decision = do_accept
                else if (r%w%ctl%monitor_rejects(r%k)) then
                    r%decision = do_reject
                end if
            end if
            if (r%decision == undecided) then
                if (column(self, r, problem, r%k, status)) then
                    r%kc = r%k
                    if (r%w%ctl%err(r%k) <= 1.0_wp) then
                        r%decision = do_accept
                    else
                        call hope(self, r, problem, status)
                    end if
                end if
            end if
        end if
    end subroutine attempt

    !> One attempt under Deuflhard's control (docs/theory.md §7.3): the
    !> columns 1, 2, … with the convergence monitor on each, until it
    !> accepts or rejects; the planned column k is the window's centre.
    subroutine attempt_window(self, r, problem, status)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        type(status_t), intent(inout) :: status
        integer :: j
        do j = 1, r%w%ctl%qmax
            if (.not. column(self, r, problem, j, status)) return
            r%kc = j
            select case (r%w%ctl%window(j, r%k, r%first, r%h))
            case (window_accept)
                r%decision = do_accept
                return
            case (window_reject)
                r%decision = do_reject
                return
            end select
        end do
    end subroutine attempt_window

    !> Column j of the tableau; false (with r%decision set) on a restart
    !> or a stop.
    logical function column(self, r, problem, j, status) result(ok)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        integer, intent(in) :: j
        type(status_t), intent(inout) :: status
        integer :: ev
        call base_column(self%native, problem, r%w, r%t, r%h, r%w%ctl%nj(j), &
                         j <= stability_columns, ev, r%fst)
        if (ev == ev_ok) then
            call extrapolate_column(r%w, j)
            if (j >= 2) call column_error(r%w, j, r%h, r%hmax, ev)
            if (ev == ev_restart .and. .not. ieee_is_finite(r%w%ctl%err(j))) &
                r%nstab_nonfinite = r%nstab_nonfinite + 1
        else if (ev /= ev_stop .and. r%fst%reason == reason_non_finite) then
            r%nstab_nonfinite = r%nstab_nonfinite + 1
        end if
        if (ev == ev_refused) r%refusal = r%fst
        r%cause = merge(cause_model_refused, cause_unstable, ev == ev_refused)
        select case (ev)
        case (ev_restart, ev_refused)
            r%decision = do_restart
        case (ev_stop)
            r%cause = merge(cause_singular_matrix, cause_model_refused, &
                r%fst%reason == reason_singular_matrix)
            self%failed_in = mexax_failed_step
            status = r%fst
            status%message = 'mexax: ' // r%fst%message // ' at t = ' // real_text(r%t) // &
                ' (step H = ' // real_text(r%h) // ')'
            r%decision = do_stop
        end select
        ok = ev == ev_ok
    end function column

    !> Hope for convergence in column k+1 (§3.4).
    subroutine hope(self, r, problem, status)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        type(status_t), intent(inout) :: status
        if (r%w%ctl%hope_rejects(r%k)) then
            r%decision = do_reject
        else if (column(self, r, problem, r%k + 1, status)) then
            r%kc = r%k + 1
            r%decision = merge(do_accept, do_reject, r%w%ctl%err(r%k + 1) <= 1.0_wp)
        end if
    end subroutine hope

    !> Count the failed attempt by r%cause; a refusal (`why` says by
    !> whom) keeps its reason. A failed projection is the model's when
    !> a user function failed in it, and a singular matrix's.
    subroutine count_failure(r, stats, why)
        type(mexax_run_t), intent(inout) :: r
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(in) :: why
        if (r%cause == cause_projection .and. why%reason == reason_singular_matrix) then
            r%cause = cause_singular_matrix
        else if (r%cause == cause_projection .and. (why%reason == reason_user_function .or. &
                                                     why%reason == reason_det_f)) then
            r%cause = cause_model_refused
        end if
        if (r%cause == cause_model_refused) then
            call stats%rejections%refuse(why%text())
        else
            call stats%rejections%add(r%cause)
        end if
    end subroutine count_failure

    !> Project the converged column kc at t + H (§3.6) and apply the
    !> rejection test; r%decision stays do_accept, or becomes do_reject
    !> (H reduced) or do_stop (status set).
    subroutine project_converged(self, r, problem, stats, status)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        associate (w => r%w)
            w%p = w%tab(1:w%nq, r%kc)
            w%v = w%tab(w%nq + 1:w%nq + w%nv, r%kc)
            call step_weights(w, r%kc)
            call project(self%native, problem, w, r%t + r%h, r%c, status)
            stats%nprj = stats%nprj + 1
            if (.not. status%ok()) then
                r%cause = cause_projection
                call count_failure(r, stats, status)
                self%failed_in = mexax_failed_projection
                status%message = 'mexax: ' // status%message // ' at t = ' // &
                    real_text(r%t + r%h) // ' (step from t = ' // real_text(r%t) // ')'
                r%decision = do_stop
                return
            end if
            ! A state the model cannot hold (det F <= 0) is rejected like a
            ! projection that moved too far.
            call problem%admissible(w%p, r%fst)
        end associate
        if (.not. r%fst%ok()) then
            r%refusal = r%fst
            r%c = huge(1.0_wp)
            call stats%rejections%refuse(r%fst%text())
        else if (r%c > 1.0_wp) then
            call stats%rejections%add(cause_projection)
        end if
        if (r%c > 1.0_wp) then
            self%nprj_reject = self%nprj_reject + 1
            self%native%nrejct = self%native%nrejct + 1
            r%h = r%h * max(projection_reject_min, projection_reject_safe / r%c)
            r%reject = .true.
            r%last = .false.
            r%basic_entry = .true.
            r%decision = do_reject
        end if
    end subroutine project_converged

    !> The projected point accepted: the new point, the outputs, then the
    !> order and step size after acceptance (§3.4); at t_end the loop ends.
    subroutine accept_step(self, r, problem, t_end, options, stats, status, sink)
        include 'mexax_step_arguments.inc'
        self%native%naccpt = self%native%naccpt + 1
        call r%refusal%clear()
        r%t_old = r%t
        r%t = r%t + r%h
        if (r%last) r%t = t_end
        call accept_point(self, problem, r%w, r%kc, r%t_old, r%t, r%need_start, status)
        if (.not. status%ok()) then
            self%failed_in = mexax_failed_step
            r%done = .true.
            return
        end if
        stats%t_reached = r%t
        stats%h_last = r%h
        r%first = .false.
        if (present(sink)) then
            call emit_outputs(self, r, options, status, sink)
            if (status%ok() .and. r%stop_requested) call interrupted(r, status)
            if (.not. status%ok()) then
                r%done = .true.
                return
            end if
        end if

        ! ---- order and step size after acceptance (§3.4) ----
        r%h = abs(r%h)
        call r%w%ctl%order_after_accept(r%kc, r%k, r%reject, r%h, r%hmax)
        r%reject = .false.
        r%h = r%posneg * min(abs(r%h), r%hmax)
        self%h_next = r%h
        self%column = r%k
        if (r%last) r%done = .true.
        r%basic_entry = .false.
    end subroutine accept_step

    !> Take the projected (w%p, w%v) and the extrapolated a, λ of column kc
    !> as the new point, and update the dense output.
    subroutine accept_point(self, problem, w, kc, t_old, t, need_start, status)
        class(mexax_engine_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: kc
        real(wp), intent(in) :: t_old, t
        logical, intent(out) :: need_start !! start_point still to be evaluated at t
        type(status_t), intent(out) :: status
        integer :: nq, nv, nc
        nq = w%nq
        nv = w%nv
        nc = w%nc
        associate (dn => self%dense)
            dn%t_old = t_old
            dn%t = t
            dn%y0 = dn%y1
            dn%d0 = dn%d1
            w%p0 = w%p
            w%v0 = w%v
            w%a0 = w%tab(nq + nv + 1:nq + 2 * nv, kc)
            w%lam0 = w%tab(nq + 2 * nv + 1:, kc)
            need_start = .true.
            if (self%consistent_accelerations) then
                ! f, T v, M, G at t serve the next step as well
                call start_point(self%native, problem, w, t, status, accelerations=.true.)
                if (.not. status%ok()) return
                need_start = .false.
                w%pdot = w%pdot0
            else
                call problem%kinematics(t, w%p0, w%v0, w%pdot, status)
                if (user_failed(status, 'kinematics')) return
            end if
            dn%y1(1:nq) = w%p0
            dn%y1(nq + 1:nq + nv) = w%v0
            dn%y1(nq + nv + 1:) = w%lam0
            dn%d1(1:nq) = w%pdot
            dn%d1(nq + 1:nq + nv) = w%a0
            if (nc > 0) then
                ! λ linear on the step: both end slopes are the secant.
                dn%d1(nq + nv + 1:) = (dn%y1(nq + nv + 1:) - dn%y0(nq + nv + 1:)) / (t - t_old)
                dn%d0(nq + nv + 1:) = dn%d1(nq + nv + 1:)
            end if
        end associate
        if (.not. all(ieee_is_finite(self%dense%y1))) then
            call status%set(status_solver_failure, 'mexax: non-finite values accepted at t = ' &
                // real_text(t), reason_non_finite)
        end if
    end subroutine accept_point

    !> Dense output at requested times in (t_old, t], then the step sink.
    subroutine emit_outputs(self, r, options, status, sink)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout) :: sink
        logical :: failed
        call dense_outputs(sink, self%dense, options, r%nout, r%t, r%posneg, r%iout, r%yout, &
                           status, failed)
        if (failed) return
        if (r%want_steps) call sink%step(self%native%naccpt + 1, r%t_old, r%t, self%dense%y1, &
            self%dense, r%stop_requested, status)
    end subroutine emit_outputs
end module flexmbs_dae_mexax_step
