!> DDASSL's iteration matrix and Newton corrector (docs/theory.md §6, §2.3):
!> PD = ∂G/∂y + cj ∂G/∂y' from the problem or by differences, factored;
!> the residual with its checks; the modified Newton iteration from the
!> predictor. Failures the model causes are kept in `work%model_failure`.
module flexmbs_dae_ddassl_corrector
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_solver_failure, status_interrupted, &
        reason_non_finite
    use flexmbs_dae_residual_problem, only: residual_problem_t
    use flexmbs_dae_rejections, only: cause_newton_diverged, cause_newton_slow, &
        cause_singular_matrix, cause_model_refused
    use flexmbs_dae_ddassl_state, only: ddassl_engine_t, newton_norm, s_fresh, rate_max, &
        conv_tol, max_iter, roundoff_conv
    implicit none
    private
    public :: form_pd, residual_ok, corrector, rate_test

contains

    !> Form and factor PD at (tn, y, yp) with cj; delta holds G there.
    !> `refused`: the last PD failed in the model, not in the LU.
    subroutine form_pd(self, res, y, yp, singular, refused)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:) !! perturbed and restored by differences
        logical, intent(out) :: singular, refused
        integer :: j
        real(wp) :: del, ysafe, ypsafe, squr
        type(status_t) :: fst
        singular = .true.
        refused = .true.
        associate (w => self%work)
            if (w%fd) then
                ! §2.3: column j = (G(y + δ_j e_j, y' + cj δ_j e_j) − δ)/δ_j; held as −PD.
                squr = sqrt(w%uround)
                do j = 1, w%n
                    del = squr * max(abs(y(j)), abs(w%h * yp(j)), w%wt(j))
                    del = sign(del, w%h * yp(j))
                    del = (y(j) + del) - y(j)
                    ysafe = y(j)
                    ypsafe = yp(j)
                    y(j) = y(j) + del
                    yp(j) = yp(j) + w%cj * del
                    call res%residual(w%tn, y, yp, w%yptmp, fst)
                    self%nfe_jac = self%nfe_jac + 1
                    y(j) = ysafe
                    yp(j) = ypsafe
                    if (.not. fst%ok()) then
                        w%model_failure = fst
                        return
                    end if
                    w%bmat%dense(:, j) = -(w%yptmp - w%delta) / del
                end do
                if (.not. all(ieee_is_finite(w%bmat%dense))) then
                    call w%model_failure%set(status_solver_failure, 'non-finite residual in ' &
                        // 'the difference iteration matrix at t = ' // real_text(w%tn), &
                        reason_non_finite)
                    return
                end if
                call w%ls%factor_real(0.0_wp, w%amat, w%bmat, fst)
            else if (w%direct) then
                call res%iteration_matrix(w%tn, y, yp, w%cj, w%bmat%dense, fst)
                if (.not. fst%ok()) then
                    w%model_failure = fst
                    return
                end if
                w%bmat%dense = -w%bmat%dense
                call w%ls%factor_real(0.0_wp, w%amat, w%bmat, fst)
            else
                call res%partials(w%tn, y, yp, w%amat, w%bmat, fst)
                if (.not. fst%ok()) then
                    w%model_failure = fst
                    return
                end if
                call w%ls%factor_real(w%cj, w%amat, w%bmat, fst)
            end if
        end associate
        refused = .false.
        singular = .not. fst%ok()
        if (.not. singular) self%ndec = self%ndec + 1
    end subroutine form_pd

    !> g = G(tn, y, yp) into delta; false on failure or non-finite values
    !> (both the model's refusal, kept in model_failure).
    logical function residual_ok(self, res, y, yp)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(in) :: y(:), yp(:)
        type(status_t) :: fst
        integer :: j
        associate (w => self%work)
            self%native%nre = self%native%nre + 1
            call res%residual(w%tn, y, yp, w%delta, fst)
            ! IRES = −2 of the classic code: the residual asks to stop.
            if (fst%code == status_interrupted) w%ires_stop = .true.
            if (.not. fst%ok()) w%model_failure = fst
            residual_ok = fst%ok()
            if (.not. residual_ok) return
            do j = 1, w%n
                if (ieee_is_finite(w%delta(j))) cycle
                call w%model_failure%set(status_solver_failure, 'non-finite residual in ' // &
                    'component ' // int_text(j) // ' at t = ' // real_text(w%tn), &
                    reason_non_finite)
                residual_ok = .false.
                return
            end do
        end associate
    end function residual_ok

    !> §2.3: the corrector iteration from the predictor in (y, yp); `why`
    !> is the cause (cause_*) of a failure.
    subroutine corrector(self, res, y, yp, pnorm, converged, singular, early, why)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: pnorm
        logical, intent(out) :: converged, singular, early
        integer, intent(out) :: why
        integer :: m
        real(wp) :: d, d0
        logical :: refused, diverged
        converged = .false.
        singular = .false.
        early = .false.
        why = cause_model_refused
        if (.not. residual_ok(self, res, y, yp)) then
            early = .true.
            return
        end if
        associate (w => self%work)
            if (w%jcalc == -1) then
                self%native%nje = self%native%nje + 1
                w%jcalc = 0
                call form_pd(self, res, y, yp, singular, refused)
                w%cjold = w%cj
                w%s = s_fresh
                if (singular .and. .not. refused) why = cause_singular_matrix
                if (singular) return
                w%nsf = 0
            end if
            why = cause_newton_diverged
            w%e = 0.0_wp
            m = 0
            d0 = 0.0_wp
            do
                w%delta = w%delta * (2.0_wp / (1.0_wp + w%cj / w%cjold))
                call w%ls%solve_real(w%delta)
                self%nsol = self%nsol + 1
                y = y - w%delta
                w%e = w%e - w%delta
                yp = yp - w%cj * w%delta
                d = newton_norm(w, w%delta)
                if (.not. ieee_is_finite(d)) return
                if (d <= roundoff_conv * w%uround * pnorm .and. &
                    (.not. self%netlib .or. m == 0)) then
                    converged = .true.
                    return
                end if
                call rate_test(m, d, d0, w%s, converged, diverged)
                if (converged .or. diverged) return
                m = m + 1
                why = cause_newton_slow
                if (m >= max_iter) return
                why = cause_model_refused
                if (.not. residual_ok(self, res, y, yp)) return
                why = cause_newton_diverged
            end do
        end associate
    end subroutine corrector

    !> §2.3: the rate test after correction m + 1 (m = 0, 1, ...) of norm d,
    !> d0 that of the first: ρ = (d/d0)^(1/m) > 0.9 diverges, else
    !> s = ρ/(1 − ρ), and s·d ≤ 0.33 converges (s as it stands at m = 0).
    subroutine rate_test(m, d, d0, s, converged, diverged)
        integer, intent(in) :: m
        real(wp), intent(in) :: d
        real(wp), intent(inout) :: d0, s
        logical, intent(out) :: converged, diverged
        real(wp) :: rate
        converged = .false.
        diverged = .false.
        if (m == 0) then
            d0 = d
        else
            rate = (d / d0)**(1.0_wp / real(m, wp))
            diverged = rate > rate_max
            if (diverged) return
            s = rate / (1.0_wp - rate)
        end if
        converged = s * d <= conv_tol
    end subroutine rate_test
end module flexmbs_dae_ddassl_corrector
