!> RADAU5's Newton iteration (docs/theory.md §5.2, §5.7, §5.8): the
!> Jacobian (block R1), the factorisations of E1 and E2 (R2), the starting
!> values and the simplified Newton iteration on the stage equations, and
!> the rule after an unexpected failure (R8).
module flexmbs_dae_radau5_newton
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix, reason_non_finite
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_newton_diverged, cause_newton_slow, &
        cause_singular_matrix, cause_model_refused
    use flexmbs_dae_radau5_state, only: radau5_engine_t, radau5_work_t, eval_f, c1, c2, &
        c1m1, c2m1, u1, alph, beta, t11, t12, t13, t21, t22, t23, t31, ti11, ti12, ti13, &
        ti21, ti22, ti23, ti31, ti32, ti33, theta_fail, failure_factor, max_singular, &
        blk_jacobian, blk_factor, blk_attempt
    implicit none
    private
    public :: jacobian_block, factor_block, starting_values, newton_iteration, &
        unexpected_failure, retry_after_failure

contains

    !> Block R1, a new J at (x, y); a failure ends the integration (`done`).
    subroutine jacobian_block(self, w, problem, y, stats, status)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y(:)
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        type(status_t) :: fstatus
        self%native%njac = self%native%njac + 1
        call compute_jacobian(w, problem, y, stats, fstatus)
        if (.not. fstatus%ok()) then
            call status%set(status_solver_failure, 'radau5: Jacobian failed at t = ' &
                // real_text(w%x) // ': ' // fstatus%text(), fstatus%reason)
            w%done = .true.
            return
        end if
        w%caljac = .true.
        w%block = blk_factor
    end subroutine jacobian_block

    !> J at (x, y): analytic, or by forward differences (§1.12; these
    !> calls are not counted in NFCN).
    subroutine compute_jacobian(w, problem, y, stats, st)
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y(:)
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(out) :: st
        integer :: j
        real(wp) :: delt, ysafe
        if (w%fd_jacobian) then
            w%ytmp = y
            do j = 1, w%n
                ysafe = w%ytmp(j)
                delt = sqrt(w%uround * max(1.0e-5_wp, abs(ysafe)))
                w%ytmp(j) = ysafe + delt
                call eval_f(problem, w%x, w%ytmp, w%cont, st)
                stats%nfe_jac = stats%nfe_jac + 1
                if (.not. st%ok()) return
                w%jac%dense(:, j) = (w%cont - w%f0) / delt
                w%ytmp(j) = ysafe
            end do
            if (.not. all(ieee_is_finite(w%jac%dense))) call st%set(status_solver_failure, &
                'non-finite difference Jacobian', reason_non_finite)
            return
        end if
        select case (w%jac%storage)
        case (storage_sparse)
            call problem%jacobian_sparse(w%x, y, w%jac%csc%values, st)
            if (st%ok() .and. .not. all(ieee_is_finite(w%jac%csc%values))) &
                call st%set(status_solver_failure, 'non-finite Jacobian', reason_non_finite)
        case (storage_dense)
            call problem%jacobian_dense(w%x, y, w%jac%dense, st)
            if (st%ok() .and. .not. all(ieee_is_finite(w%jac%dense))) &
                call st%set(status_solver_failure, 'non-finite Jacobian', reason_non_finite)
        end select
    end subroutine compute_jacobian

    !> Block R2, E1 = (γ/h) M − J and E2 = ((α + iβ)/h) M − J factored; a singular
    !> one halves h (R8) up to max_singular times in a row.
    subroutine factor_block(self, w, stats, status)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        type(status_t) :: fstatus
        logical :: singular
        w%fac1 = u1 / w%h
        w%alphn = alph / w%h
        w%betan = beta / w%h
        call w%ls%factor_real(w%fac1, w%mass, w%jac, fstatus)
        singular = .not. fstatus%ok()
        if (.not. singular) then
            call w%ls%factor_complex(cmplx(w%alphn, w%betan, kind=wp), w%mass, w%jac, fstatus)
            singular = .not. fstatus%ok()
        end if
        ! Misuse (e.g. J outside the band fixed at init) is no singularity.
        if (fstatus%code == status_bad_input) then
            status = fstatus
            w%done = .true.
            return
        end if
        if (singular) then
            ! an attempt at this h that failed before R3: counted in NST
            w%nsing = w%nsing + 1
            if (w%nsing >= max_singular) then
                call stats%rejections%add(cause_singular_matrix)
                call status%set(status_solver_failure, &
                    'radau5: matrix is repeatedly singular at t = ' // real_text(w%x), &
                    reason_singular_matrix)
                w%done = .true.
                return
            end if
            call unexpected_failure(w, stats, cause_singular_matrix, fstatus)
            return
        end if
        self%native%ndec = self%native%ndec + 1
        w%block = blk_attempt
    end subroutine factor_block

    !> §1.5: starting values of the stage increments, zero or from the
    !> collocation polynomial of the last step.
    subroutine starting_values(self, w)
        class(radau5_engine_t), intent(in) :: self
        type(radau5_work_t), intent(inout) :: w
        real(wp) :: c3q, sig1, sig2, sig3, ak1, ak2, ak3
        integer :: i
        if (w%first .or. self%zero_start) then
            w%z1 = 0.0_wp; w%z2 = 0.0_wp; w%z3 = 0.0_wp
            w%w1 = 0.0_wp; w%w2 = 0.0_wp; w%w3 = 0.0_wp
        else
            c3q = w%h / w%hold
            sig1 = c1 * c3q
            sig2 = c2 * c3q
            sig3 = c3q
            do i = 1, w%n
                ak1 = self%dense%cont(i, 1)
                ak2 = self%dense%cont(i, 2)
                ak3 = self%dense%cont(i, 3)
                w%z1(i) = sig1 * (ak1 + (sig1 - c2m1) * (ak2 + (sig1 - c1m1) * ak3))
                w%z2(i) = sig2 * (ak1 + (sig2 - c2m1) * (ak2 + (sig2 - c1m1) * ak3))
                w%z3(i) = sig3 * (ak1 + (sig3 - c2m1) * (ak2 + (sig3 - c1m1) * ak3))
                w%w1(i) = ti11 * w%z1(i) + ti12 * w%z2(i) + ti13 * w%z3(i)
                w%w2(i) = ti21 * w%z1(i) + ti22 * w%z2(i) + ti23 * w%z3(i)
                w%w3(i) = ti31 * w%z1(i) + ti32 * w%z2(i) + ti33 * w%z3(i)
            end do
        end if
    end subroutine starting_values

    !> §1.6: simplified Newton iteration. Not `converged`: the failure has
    !> been counted and the next block set (R8, or a smaller h with the same
    !> Jacobian when convergence is too slow).
    subroutine newton_iteration(self, w, problem, y, stats, converged)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y(:)
        type(dae_stats_t), intent(inout) :: stats
        logical, intent(out) :: converged
        type(status_t) :: fstatus
        real(wp) :: dyno, thq, dyth, qnewt, ak1, ak2, ak3
        integer :: i, n, nit
        n = w%n
        nit = w%nit
        converged = .false.
        w%faccon = max(w%faccon, w%uround)**0.8_wp
        w%theta = abs(w%thet)
        w%newt = 0
        newton: do
            if (w%newt >= nit) then
                call unexpected_failure(w, stats, cause_newton_slow, fstatus)
                return
            end if
            w%ytmp = y + w%z1
            call eval_f(problem, w%x + c1 * w%h, w%ytmp, w%f1, fstatus)
            w%ytmp = y + w%z2
            if (fstatus%ok()) call eval_f(problem, w%x + c2 * w%h, w%ytmp, w%f2, fstatus)
            w%ytmp = y + w%z3
            if (fstatus%ok()) call eval_f(problem, w%x + w%h, w%ytmp, w%f3, fstatus)
            self%native%nfcn = self%native%nfcn + 3
            if (.not. fstatus%ok()) then
                call unexpected_failure(w, stats, cause_model_refused, fstatus)
                return
            end if
            ! G = (T⁻¹ ⊗ I) F, then the transformed residuals r1, r2 + i r3.
            do i = 1, n
                ak1 = w%f1(i); ak2 = w%f2(i); ak3 = w%f3(i)
                w%f1(i) = ti11 * ak1 + ti12 * ak2 + ti13 * ak3
                w%f2(i) = ti21 * ak1 + ti22 * ak2 + ti23 * ak3
                w%f3(i) = ti31 * ak1 + ti32 * ak2 + ti33 * ak3
            end do
            call newton_residual(w)
            call w%ls%solve_real(w%f1)
            w%zc = cmplx(w%f2, w%f3, kind=wp)
            call w%ls%solve_complex(w%zc)
            w%f2 = real(w%zc, wp)
            w%f3 = aimag(w%zc)
            self%native%nsol = self%native%nsol + 1
            w%newt = w%newt + 1
            dyno = 0.0_wp
            do i = 1, n
                dyno = dyno + (w%f1(i) / w%scal(i))**2 + (w%f2(i) / w%scal(i))**2 &
                    + (w%f3(i) / w%scal(i))**2
            end do
            dyno = sqrt(dyno / real(3 * n, wp))
            if (.not. ieee_is_finite(dyno)) then
                call unexpected_failure(w, stats, cause_newton_diverged, fstatus)
                return
            end if
            if (w%newt > 1 .and. w%newt < nit) then
                thq = dyno / w%dynold
                if (w%newt == 2) then
                    w%theta = thq
                else
                    w%theta = sqrt(thq * w%thqold)
                end if
                w%thqold = thq
                if (w%theta < theta_fail) then
                    w%faccon = w%theta / (1.0_wp - w%theta)
                    dyth = w%faccon * dyno * w%theta**(nit - 1 - w%newt) / w%fnewt
                    if (dyth >= 1.0_wp) then
                        ! Convergence too slow: smaller h, same Jacobian.
                        qnewt = max(1.0e-4_wp, min(20.0_wp, dyth))
                        w%hhfac = 0.8_wp * qnewt**(-1.0_wp / real(4 + nit - 1 - w%newt, wp))
                        w%h = w%hhfac * w%h
                        call stats%rejections%add(cause_newton_slow)
                        w%reject = .true.
                        w%last = .false.
                        call retry_after_failure(w)
                        return
                    end if
                else
                    call unexpected_failure(w, stats, cause_newton_diverged, fstatus)
                    return
                end if
            end if
            w%dynold = max(dyno, w%uround)
            do i = 1, n
                w%w1(i) = w%w1(i) + w%f1(i)
                w%w2(i) = w%w2(i) + w%f2(i)
                w%w3(i) = w%w3(i) + w%f3(i)
                w%z1(i) = t11 * w%w1(i) + t12 * w%w2(i) + t13 * w%w3(i)
                w%z2(i) = t21 * w%w1(i) + t22 * w%w2(i) + t23 * w%w3(i)
                w%z3(i) = t31 * w%w1(i) + w%w2(i)
            end do
            if (w%faccon * dyno <= w%fnewt) exit newton
        end do newton
        converged = .true.
    end subroutine newton_iteration

    !> r1 = G1 − (γ/h) M w1; r2 = G2 − (α/h) M w2 + (β/h) M w3;
    !> r3 = G3 − (β/h) M w2 − (α/h) M w3 (§1.3 step 2).
    subroutine newton_residual(w)
        type(radau5_work_t), intent(inout) :: w
        integer :: j
        real(wp) :: s2, s3
        if (w%mass_identity) then
            do j = 1, w%n
                s2 = -w%w2(j)
                s3 = -w%w3(j)
                w%f1(j) = w%f1(j) - w%w1(j) * w%fac1
                w%f2(j) = w%f2(j) + s2 * w%alphn - s3 * w%betan
                w%f3(j) = w%f3(j) + s3 * w%alphn + s2 * w%betan
            end do
        else
            call w%mass%matvec(w%w1, w%mw)
            w%f1 = w%f1 - w%fac1 * w%mw
            call w%mass%matvec(w%w2, w%mw)
            w%f2 = w%f2 - w%alphn * w%mw
            w%f3 = w%f3 - w%betan * w%mw
            call w%mass%matvec(w%w3, w%mw)
            w%f2 = w%f2 + w%betan * w%mw
            w%f3 = w%f3 - w%alphn * w%mw
        end if
    end subroutine newton_residual

    !> §1.10 R8: h/2 after a Newton failure, a singular matrix, a refusal
    !> (`why` says why) or a non-finite value, counted by `cause`.
    subroutine unexpected_failure(w, stats, cause, why)
        type(radau5_work_t), intent(inout) :: w
        type(dae_stats_t), intent(inout) :: stats
        integer, intent(in) :: cause
        type(status_t), intent(in) :: why
        if (cause == cause_model_refused) then
            w%rejection = why
            call stats%rejections%refuse(why%text())
        else
            call stats%rejections%add(cause)
        end if
        w%h = w%h * failure_factor
        w%hhfac = failure_factor
        w%reject = .true.
        w%last = .false.
        call retry_after_failure(w)
    end subroutine unexpected_failure

    !> Retry with the new h: refactor if J is fresh, else a new J first.
    subroutine retry_after_failure(w)
        type(radau5_work_t), intent(inout) :: w
        if (w%caljac) then
            w%block = blk_factor
        else
            w%block = blk_jacobian
        end if
    end subroutine retry_after_failure
end module flexmbs_dae_radau5_newton
