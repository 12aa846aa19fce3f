!> One DDASSL step (docs/theory.md §6, §2.2–§2.7): the checks before it,
!> the BDF coefficients, predictor and corrector, the error test with the
!> choice of order and step after it, and the rules after a failed attempt.
module flexmbs_dae_ddassl_stepper
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text
    use flexmbs_core_status, only: status_t, status_solver_failure, status_interrupted, &
        reason_step_too_small, reason_singular_matrix, reason_newton_failure, &
        reason_user_function, reason_non_finite, reason_det_f
    use flexmbs_dae_residual_problem, only: residual_problem_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_model_refused
    use flexmbs_dae_ddassl_state, only: ddassl_engine_t, ddassl_work_t, set_weights, vnorm, &
        enorm, s_fresh, conv_tol, cj_ratio_low, roundoff_conv, est_offset, half, r_raise, &
        r_min, r_max, fail_safety, fail_min, fail_quarter, max_ncf, max_nsf, nef_after_conv, &
        hmin_factor, ddassl_fail_tolerances, ddassl_fail_weights, ddassl_fail_error_test, &
        ddassl_fail_corrector, ddassl_fail_singular, ddassl_fail_after_error_test, &
        ddassl_fail_residual, ddassl_fail_stop
    use flexmbs_dae_ddassl_corrector, only: corrector
    implicit none
    private
    public :: before_step, take_step

contains

    !> §2.7, before every step, items 2–6. `tout` enters hmin; with
    !> `limited` the step never passes tlimit.
    subroutine before_step(self, tout, limited, tlimit, status)
        class(ddassl_engine_t), intent(inout) :: self
        real(wp), intent(in) :: tout
        logical, intent(in) :: limited
        real(wp), intent(in) :: tlimit
        type(status_t), intent(out) :: status
        real(wp) :: r, dir
        associate (w => self%work)
            dir = sign(1.0_wp, w%h)
            call set_weights(w, w%phi(:, 1))
            if (any(.not. w%wt > 0.0_wp)) then
                call fail(w, status, 'a weight rtol*|y| + atol became non-positive', &
                    reason_non_finite, ddassl_fail_weights)
                return
            end if
            r = roundoff_conv * w%uround * vnorm(w, w%phi(:, 1))
            if (r > 1.0_wp) then
                ! The classic code scales the tolerances and reports −2.
                w%rtol = r * w%rtol
                w%atol = r * w%atol
                w%tol_scale = r
                call fail(w, status, 'tolerances too small for the machine precision ' // &
                    '(rtol, atol scaled by ' // real_text(r) // ')', reason_step_too_small, &
                    ddassl_fail_tolerances)
                return
            end if
            w%hmin = hmin_factor * w%uround * max(abs(w%tn), abs(tout))
            if (abs(w%h) > w%hmax) w%h = w%h / (abs(w%h) / w%hmax)
            if (limited .and. (w%tn + w%h - tlimit) * dir > 0.0_wp) w%h = tlimit - w%tn
        end associate
    end subroutine before_step

    subroutine fail(w, status, reason, code, idid)
        type(ddassl_work_t), intent(inout) :: w
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: reason
        integer, intent(in) :: code, idid
        call status%set(status_solver_failure, 'ddassl: ' // reason // ' at t = ' // &
            real_text(w%tn) // ' (h = ' // real_text(w%h) // ')', code)
        w%failure = idid
    end subroutine fail

    !> One step of §2.2–§2.6; on return either accepted or st says why not.
    subroutine take_step(self, res, y, yp, st)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:) !! the last iterate
        type(status_t), intent(out) :: st
        real(wp) :: ck
        logical :: converged, singular, early, passed
        integer :: why

        self%work%nef = 0
        self%work%ncf = 0
        self%work%nsf = 0
        call self%work%model_failure%clear()
        attempt: do
            call update_coefficients(self%work, ck)
            call predict_correct(self, res, y, yp, converged, singular, early, why)
            passed = .false.
            if (converged) then
                call error_test(self%work, ck, passed)
                if (self%fixed_step) passed = .true.
                if (passed) exit attempt
            end if
            call after_failure(self, converged, singular, early, why, st)
            if (.not. st%ok()) return
        end do attempt
        call after_success(self)
    end subroutine take_step

    !> §2.2: the coefficients of order k and step h (recomputed only while
    !> the steps of the last k + 1 differ), the β scaling of the history and
    !> t_n + h; ck = max(|α_{k+1} + α_s − α⁰|, α_{k+1}) weights the error test.
    subroutine update_coefficients(w, ck)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(out) :: ck
        integer :: i, j
        real(wp) :: temp1, temp2, alphas, alpha0
        if (w%h /= w%hold .or. w%k /= w%kold) w%ns = 0
        w%ns = min(w%ns + 1, w%kold + 2)
        if (w%k + 1 >= w%ns) then
            w%beta(1) = 1.0_wp
            w%alpha(1) = 1.0_wp
            w%sigma(1) = 1.0_wp
            w%gamma(1) = 0.0_wp
            temp1 = w%h
            do i = 2, w%k + 1
                temp2 = w%psi(i - 1)
                w%psi(i - 1) = temp1
                w%beta(i) = w%beta(i - 1) * w%psi(i - 1) / temp2
                temp1 = temp2 + w%h
                w%alpha(i) = w%h / temp1
                w%sigma(i) = real(i - 1, wp) * w%sigma(i - 1) * w%alpha(i)
                w%gamma(i) = w%gamma(i - 1) + w%alpha(i - 1) / w%h
            end do
            w%psi(w%k + 1) = temp1
        end if
        alphas = 0.0_wp
        alpha0 = 0.0_wp
        do i = 1, w%k
            alphas = alphas - 1.0_wp / real(i, wp)
            alpha0 = alpha0 - w%alpha(i)
        end do
        w%cjlast = w%cj
        w%cj = -alphas / w%h
        ck = max(abs(w%alpha(w%k + 1) + alphas - alpha0), w%alpha(w%k + 1))
        ! §2.3: a new PD when cj moved too far from that of the current PD.
        temp1 = w%cj / w%cjold
        if (temp1 < cj_ratio_low .or. temp1 > 1.0_wp / cj_ratio_low) w%jcalc = -1
        if (w%cj /= w%cjlast) w%s = s_fresh
        do j = w%ns + 1, w%k + 1
            w%phi(:, j) = w%beta(j) * w%phi(:, j)
        end do
        w%tn = w%tn + w%h
    end subroutine update_coefficients

    !> §2.2 predictor, §2.3 corrector (redone once with a fresh PD when an
    !> old one failed), then the model's and the user's checks of the
    !> corrected state; e holds the correction.
    subroutine predict_correct(self, res, y, yp, converged, singular, early, why)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:)
        logical, intent(out) :: converged, singular, early
        integer, intent(out) :: why !! cause_* of a failure
        real(wp) :: pnorm
        integer :: j
        type(status_t) :: refusal
        associate (w => self%work)
            do
                y = w%phi(:, 1)
                yp = 0.0_wp
                do j = 2, w%k + 1
                    y = y + w%phi(:, j)
                    yp = yp + w%gamma(j) * w%phi(:, j)
                end do
                pnorm = vnorm(w, y)
                call corrector(self, res, y, yp, pnorm, converged, singular, early, why)
                if (converged .or. w%jcalc /= 1 .or. early) exit
                w%jcalc = -1
            end do
            w%jcalc = 1
            ! A corrected state the model cannot hold (det F <= 0) is a
            ! corrector failure: h/4, as for IRES = -1.
            if (converged) then
                call res%admissible(w%tn, y, refusal)
                if (.not. refusal%ok()) then
                    converged = .false.
                    why = cause_model_refused
                    w%model_failure = refusal
                end if
            end if
            if (converged .and. self%nonnegative) then
                w%delta = min(y, 0.0_wp)
                if (vnorm(w, w%delta) > conv_tol) then
                    ! the user's rule y ≥ 0 refuses the corrected state
                    converged = .false.
                    why = cause_model_refused
                    call w%model_failure%set(status_solver_failure, 'negative components ' &
                        // '(nonnegative) at t = ' // real_text(w%tn), reason_newton_failure)
                else
                    w%e = w%e - w%delta
                end if
            end if
        end associate
    end subroutine predict_correct

    !> §2.4: error estimates at orders k−2..k (knew and est: the order the
    !> estimates favour and its estimate) and the test ck ‖e‖ ≤ 1.
    subroutine error_test(w, ck, passed)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(in) :: ck
        logical, intent(out) :: passed
        real(wp) :: enrm, erk, err, erkm2, terkm2
        enrm = enorm(w, w%e)
        erk = w%sigma(w%k + 1) * enrm
        w%terk = real(w%k + 1, wp) * erk
        w%est = erk
        w%knew = w%k
        if (w%k >= 2) then
            w%delta = w%phi(:, w%k + 1) + w%e
            w%erkm1 = w%sigma(w%k) * enorm(w, w%delta)
            w%terkm1 = real(w%k, wp) * w%erkm1
            if (w%k > 2) then
                w%delta = w%phi(:, w%k) + w%delta
                erkm2 = w%sigma(w%k - 1) * enorm(w, w%delta)
                terkm2 = real(w%k - 1, wp) * erkm2
                if (max(w%terkm1, terkm2) <= w%terk) then
                    w%knew = w%k - 1
                    w%est = w%erkm1
                end if
            else if (w%terkm1 <= half * w%terk) then
                w%knew = w%k - 1
                w%est = w%erkm1
            end if
        end if
        err = ck * enrm
        if (.not. ieee_is_finite(err) .or. .not. ieee_is_finite(w%est)) then
            w%est = huge(1.0_wp)
            passed = .false.
        else
            passed = err <= 1.0_wp
        end if
    end subroutine error_test

    !> §2.4 after an accepted step: the order and step of the next one (both
    !> raised while in the initial phase, then chosen from the estimates at
    !> orders k−1..k+1), and the history updated with e.
    subroutine after_success(self)
        class(ddassl_engine_t), intent(inout) :: self
        integer :: j, kdiff
        real(wp) :: r, hnew, erkp1, terkp1
        self%native%nst = self%native%nst + 1
        associate (w => self%work)
            kdiff = w%k - w%kold
            w%kold = w%k
            w%hold = w%h
            hnew = w%h
            if (self%fixed_step) then
                w%k = min(w%k + 1, w%pmax)
            else
                if (w%knew == w%k - 1 .or. w%k == w%pmax) w%iphase = 1
                if (w%iphase == 0) then
                    w%k = w%k + 1
                    hnew = 2.0_wp * w%h
                else
                    if (w%knew == w%k - 1) then
                        w%k = w%k - 1
                        w%est = w%erkm1
                    else if (.not. (w%k == w%pmax .or. w%k + 1 >= w%ns .or. kdiff == 1)) then
                        w%delta = w%e - w%phi(:, w%k + 2)
                        erkp1 = enorm(w, w%delta) / real(w%k + 2, wp)
                        terkp1 = real(w%k + 2, wp) * erkp1
                        if (w%k == 1) then
                            if (terkp1 < half * w%terk) then
                                w%k = w%k + 1
                                w%est = erkp1
                            end if
                        else if (w%terkm1 <= min(w%terk, terkp1)) then
                            w%k = w%k - 1
                            w%est = w%erkm1
                        else if (terkp1 < w%terk) then
                            w%k = w%k + 1
                            w%est = erkp1
                        end if
                    end if
                    r = (2.0_wp * w%est + est_offset)**(-1.0_wp / real(w%k + 1, wp))
                    if (r >= r_raise) then
                        hnew = 2.0_wp * w%h
                    else if (r <= 1.0_wp) then
                        hnew = w%h * min(max(r, r_min), r_max)
                    end if
                end if
            end if
            ! History, with kold the order used in this step.
            if (w%kold /= w%pmax) w%phi(:, w%kold + 2) = w%e
            w%phi(:, w%kold + 1) = w%phi(:, w%kold + 1) + w%e
            do j = w%kold, 1, -1
                w%phi(:, j) = w%phi(:, j) + w%phi(:, j + 1)
            end do
            w%h = hnew
        end associate
    end subroutine after_success

    !> §2.6: a failed attempt; the history restored, then the rule of its
    !> cause reduces h (and k), or st says why the step is given up.
    subroutine after_failure(self, converged, singular, early, why, st)
        class(ddassl_engine_t), intent(inout) :: self
        logical, intent(in) :: converged   !! the corrector converged: the error test failed
        logical, intent(in) :: singular, early
        integer, intent(in) :: why
        type(status_t), intent(out) :: st
        real(wp) :: h_failed
        associate (w => self%work)
            if (self%fixed_step) then
                call st%set(status_solver_failure, 'ddassl: fixed-step corrector ' // &
                    'failed at t = ' // real_text(w%tn - w%h), reason_newton_failure)
                w%failure = ddassl_fail_corrector
                call restore(w)
                return
            end if
            call restore(w)
            h_failed = w%h
            if (converged) then
                call error_test_failed(self, st)
            else
                call corrector_failed(self, singular, early, why, st)
            end if
            if (.not. st%ok()) return
            if (self%netlib .and. w%kold == 0) then
                ! §2.9: rescale the first-step history to the new h.
                w%psi(1) = w%h
                w%phi(:, 2) = (w%h / h_failed) * w%phi(:, 2)
            end if
        end associate
    end subroutine after_failure

    !> §2.6 after an error-test failure: k and h from the estimate the first
    !> time, h/4 the second, then order 1 and h/4.
    subroutine error_test_failed(self, st)
        class(ddassl_engine_t), intent(inout) :: self
        type(status_t), intent(inout) :: st
        real(wp) :: r
        associate (w => self%work)
            w%nef = w%nef + 1
            self%native%netf = self%native%netf + 1
            call self%rejections%add(cause_error_test)
            if (w%nef == 1) then
                w%k = w%knew
                r = fail_safety * (2.0_wp * w%est + est_offset)**(-1.0_wp / real(w%k + 1, wp))
                r = min(max(r, fail_min), r_max)
                w%h = w%h * r
            else if (w%nef == 2) then
                w%k = w%knew
                w%h = w%h * fail_quarter
            else
                w%k = 1
                w%h = w%h * fail_quarter
            end if
            if (abs(w%h) < w%hmin) then
                call st%set(status_solver_failure, 'ddassl: error test failed ' // &
                    'repeatedly, step size too small at t = ' // real_text(w%tn) // &
                    ' (h = ' // real_text(w%h) // ')', reason_step_too_small)
                w%failure = ddassl_fail_error_test
            end if
        end associate
    end subroutine error_test_failed

    !> §2.6 after a corrector failure: its cause recorded, then h/4 until
    !> the singular or the convergence failures repeat too often.
    subroutine corrector_failed(self, singular, early, why, st)
        class(ddassl_engine_t), intent(inout) :: self
        logical, intent(in) :: singular, early
        integer, intent(in) :: why
        type(status_t), intent(inout) :: st
        associate (w => self%work)
            self%native%ncfn = self%native%ncfn + 1
            if (w%ires_stop) then
                call self%rejections%refuse('the residual asked to stop (IRES = -2)')
            else if (why == cause_model_refused) then
                call self%rejections%refuse(w%model_failure%text())
            else
                call self%rejections%add(why)
            end if
            if (w%ires_stop) then
                call st%set(status_interrupted, 'ddassl: the residual asked to stop ' &
                    // 'at t = ' // real_text(w%tn + w%h))
                w%failure = ddassl_fail_stop
            else if (singular) then
                w%nsf = w%nsf + 1
                w%h = w%h * fail_quarter
                if (w%nsf >= max_nsf .or. abs(w%h) < w%hmin) then
                    call st%set(status_solver_failure, 'ddassl: iteration matrix ' // &
                        'repeatedly singular at t = ' // real_text(w%tn) // ' (h = ' // &
                        real_text(w%h) // ')', reason_singular_matrix)
                    w%failure = ddassl_fail_singular
                end if
            else
                w%ncf = w%ncf + 1
                w%h = w%h * fail_quarter
                if (w%ncf >= max_ncf .or. abs(w%h) < w%hmin) then
                    if (w%nef >= nef_after_conv) then
                        call st%set(status_solver_failure, 'ddassl: corrector failed ' // &
                            'after repeated error-test failures at t = ' // &
                            real_text(w%tn) // ' (h = ' // real_text(w%h) // ')', &
                            reason_newton_failure)
                        w%failure = ddassl_fail_after_error_test
                    else if (w%model_failure%reason == reason_det_f) then
                        call st%set(status_solver_failure, 'ddassl: step size too ' // &
                            'small at t = ' // real_text(w%tn) // ' (h = ' // &
                            real_text(w%h) // '): the model refused every corrected ' // &
                            'state: ' // w%model_failure%text(), reason_det_f)
                        w%failure = ddassl_fail_residual
                    else if (early) then
                        call st%set(status_solver_failure, 'ddassl: residual failed ' // &
                            'repeatedly at t = ' // real_text(w%tn) // ' (h = ' // &
                            real_text(w%h) // ')', reason_user_function)
                        w%failure = ddassl_fail_residual
                    else
                        call st%set(status_solver_failure, 'ddassl: corrector ' // &
                            'failed repeatedly at t = ' // real_text(w%tn) // ' (h = ' // &
                            real_text(w%h) // ')', reason_newton_failure)
                        w%failure = ddassl_fail_corrector
                    end if
                end if
            end if
        end associate
    end subroutine corrector_failed

    !> §2.6: undo the β scaling, t_n and ψ of the failed attempt.
    subroutine restore(w)
        type(ddassl_work_t), intent(inout) :: w
        integer :: i, j
        w%iphase = 1
        w%tn = w%tn - w%h
        do j = w%ns + 1, w%k + 1
            w%phi(:, j) = w%phi(:, j) / w%beta(j)
        end do
        do i = 2, w%k + 1
            w%psi(i - 1) = w%psi(i) - w%h
        end do
    end subroutine restore
end module flexmbs_dae_ddassl_stepper
