!> MEXAX extrapolation tableau (docs/theory.md §7.1, §7.2): the columns
!> T_{j,1} of the half-explicit base methods (Euler (E), midpoint (M)) over
!> one macro step, their Aitken–Neville extrapolation in h or h², and the
!> error estimate err_j of the diagonal with its divergence test.
module flexmbs_dae_mexax_tableau
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_non_finite, &
        reason_user_function, reason_det_f, reason_singular_matrix
    use flexmbs_core_text, only: real_text
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_mexax_control, only: mexax_base_euler, mexax_control_deuflhard
    use flexmbs_dae_mexax_workspace, only: workspace_t, mexax_native_t, ev_ok, ev_restart, &
        ev_stop, ev_refused, eval_block, block_mass, block_jacobian, copy_block, assemble, &
        factor, solve, factor_solve, user_failed, block_times, rms
    implicit none
    private
    public :: start_point, base_column, extrapolate_column, step_weights, column_error

    ! §3.5 [R]: stability check ‖v2 − v1‖ > 2 ‖v2‖ in the first columns; the
    ! ratio 2 of the norms and the columns 1..2 are ODEX's (HNW93 II.9: the
    ! squared ratio 4 of the derivative differences, lines 1..JSTAB = 2); the
    ! compared quantities are reconstructed.
    real(wp), parameter :: stability_ratio = 2.0_wp

contains

    !> f, T v, M and G at the start point of a macro step: shared by every
    !> column and every attempt from this point (§3.2). With `accelerations`
    !> also a and λ there from [M Gᵀ; G 0][a; λ] = [f; −γ] when the problem
    !> provides the curvature γ (otherwise a and λ stay as they are).
    subroutine start_point(native, problem, w, t, status, accelerations)
        type(mexax_native_t), intent(inout) :: native
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t
        type(status_t), intent(out) :: status
        logical, intent(in) :: accelerations
        type(status_t) :: cst
        integer :: nv
        call problem%forces(t, w%p0, w%v0, w%f0, status)
        if (status%ok()) call problem%kinematics(t, w%p0, w%v0, w%pdot0, status)
        if (status%ok()) call eval_block(problem, w, block_mass, t, w%p0, w%m0, status)
        if (status%ok()) call eval_block(problem, w, block_jacobian, t, w%p0, w%g0, status)
        native%nfprob = native%nfprob + 1
        native%nfcn = native%nfcn + 1
        if (.not. status%ok()) then
            status%message = 'mexax: user function failed at the step start t = ' // &
                real_text(t) // ': ' // status%text()
            status%code = status_solver_failure
            if (status%reason /= reason_det_f) status%reason = reason_user_function
            return
        end if
        if (.not. accelerations) return
        nv = w%nv
        call problem%constraint_curvature(t, w%p0, w%v0, w%gt, cst)
        if (.not. cst%ok()) return
        call assemble(w, w%m0, w%g0, w%g0)
        call factor(w, cst)
        if (.not. cst%ok()) then
            call status%set(status_solver_failure, 'mexax: augmented matrix [M G^T; G 0] &
                &is singular at t = ' // real_text(t), reason_singular_matrix)
            return
        end if
        native%ndec = native%ndec + 1
        w%rhs(1:nv) = w%f0
        w%rhs(nv + 1:) = -w%gt
        call solve(w, w%rhs)
        native%nsol = native%nsol + 1
        w%a0 = w%rhs(1:nv)
        w%lam0 = w%rhs(nv + 1:)
    end subroutine start_point

    !> T_{j,1} in w%x = (q, v, a, λ) after n substeps of the base method.
    !> ev_restart on non-finite values or a failed stability check (§3.5),
    !> ev_refused when the model refused a substep (det F ≤ 0, non-finite
    !> forces), ev_stop (status set) on a singular matrix or a failed user
    !> function.
    subroutine base_column(native, problem, w, t, big_h, n, check_stability, ev, status)
        type(mexax_native_t), intent(inout) :: native
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t, big_h
        integer, intent(in) :: n
        logical, intent(in) :: check_stability
        integer, intent(out) :: ev
        type(status_t), intent(out) :: status
        integer :: nq, nv
        nq = w%nq
        nv = w%nv
        w%wst = w%rtol(nq + 1:) * abs(w%v0) + w%atol(nq + 1:)
        if (w%base == mexax_base_euler) then
            call euler_substeps(native, problem, w, t, big_h, n, check_stability, ev, status)
        else
            call midpoint_substeps(native, problem, w, t, big_h, n, check_stability, ev, status)
        end if
        ! a substep loop left by a failed user function: refused or stop
        if (ev == ev_ok .and. .not. status%ok()) ev = merge(ev_refused, ev_stop, &
            status%reason == reason_det_f .or. status%reason == reason_non_finite)
        if (ev /= ev_ok) return
        w%x(1:nq) = w%p
        w%x(nq + 1:nq + nv) = w%v
        w%x(nq + nv + 1:nq + 2 * nv) = w%acc
        w%x(nq + 2 * nv + 1:) = w%lam
    end subroutine base_column

    !> (E), §3.2: p_{i+1} = p_i + h T v_i, then one augmented solve for
    !> (v_{i+1}, h λ_{i+1}) with the matrices at p_{i+1}.
    subroutine euler_substeps(native, problem, w, t, big_h, n, check_stability, ev, status)
        include 'mexax_substeps.inc'
        nv = w%nv
        h = big_h / n
        w%p = w%p0
        w%v = w%v0
        w%f = w%f0
        ev = ev_ok
        do i = 0, n - 1
            ti = t + big_h * real(i, wp) / n
            tn = t + big_h * real(i + 1, wp) / n
            if (i > 0) then
                ! one FPROB call (flags 4, 5): f and T v at (t_i, p_i, v_i)
                call problem%forces(ti, w%p, w%v, w%f, status)
                native%nfcn = native%nfcn + 1
                native%nfprob = native%nfprob + 1
                if (user_failed(status, 'forces', w%f)) exit
                call problem%kinematics(ti, w%p, w%v, w%pdot, status)
                if (user_failed(status, 'kinematics')) exit
            else
                w%pdot = w%pdot0   ! shared start point (§3.2)
            end if
            w%pn = w%p + h * w%pdot
            call eval_block(problem, w, block_mass, tn, w%pn, w%mm, status)
            if (user_failed(status, 'mass')) exit
            call eval_block(problem, w, block_jacobian, tn, w%pn, w%gm, status)
            if (user_failed(status, 'constraint_jacobian')) exit
            call problem%constraint_time_derivative(tn, w%pn, w%gt, status)
            if (user_failed(status, 'constraint_time_derivative')) exit
            native%nfprob = native%nfprob + 1
            call block_times(w, w%mm, w%mpat, w%v, w%rhs(1:nv))
            w%rhs(1:nv) = w%rhs(1:nv) + h * w%f
            native%nmult = native%nmult + 1
            w%rhs(nv + 1:) = -w%gt
            call assemble(w, w%mm, w%gm, w%gm)
            call factor_solve(native, w, 'in a step', ev, status)
            if (ev /= ev_ok) return
            w%vp = w%v
            w%v = w%rhs(1:nv)
            w%lam = w%rhs(nv + 1:) / h
            w%acc = (w%v - w%vp) / h
            w%p = w%pn
            if (unstable(w, i, check_stability, ev, status)) return
        end do
    end subroutine euler_substeps

    !> (M), §3.2: an explicit start step, then q_{i+1} = q_{i−1} + 2h T v_i,
    !> v_{i+1} = v_{i−1} + 2h a_i with [M(q_i) G(q_i)ᵀ; G(q_{i+1}) 0].
    subroutine midpoint_substeps(native, problem, w, t, big_h, n, check_stability, ev, status)
        include 'mexax_substeps.inc'
        nv = w%nv
        h = big_h / n
        ev = ev_ok
        tn = t + big_h / n
        w%pp = w%p0
        w%vp = w%v0
        w%p = w%p0 + h * w%pdot0
        call eval_block(problem, w, block_jacobian, tn, w%p, w%gn, status)
        if (user_failed(status, 'constraint_jacobian')) then
            ev = ev_stop
            return
        end if
        call problem%constraint_time_derivative(tn, w%p, w%gt, status)
        if (user_failed(status, 'constraint_time_derivative')) then
            ev = ev_stop
            return
        end if
        native%nfprob = native%nfprob + 1
        w%rhs(1:nv) = w%f0
        call block_times(w, w%gn, w%gpat, w%v0, w%rhs(nv + 1:))
        w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt) / h
        call assemble(w, w%m0, w%g0, w%gn)
        call factor_solve(native, w, 'in a step', ev, status)
        if (ev /= ev_ok) return
        w%acc = w%rhs(1:nv)
        w%lam = w%rhs(nv + 1:)
        w%v = w%v0 + h * w%acc
        call copy_block(w%gm, w%gn)
        do i = 1, n - 1
            ti = t + big_h * real(i, wp) / n
            tn = t + big_h * real(i + 1, wp) / n
            ! one FPROB call (flags 1, 4, 5) at (t_i, q_i, v_i), one (2, 8) at q_{i+1}
            call problem%forces(ti, w%p, w%v, w%f, status)
            native%nfcn = native%nfcn + 1
            native%nfprob = native%nfprob + 1
            if (user_failed(status, 'forces', w%f)) exit
            call eval_block(problem, w, block_mass, ti, w%p, w%mm, status)
            if (user_failed(status, 'mass')) exit
            call problem%kinematics(ti, w%p, w%v, w%pdot, status)
            if (user_failed(status, 'kinematics')) exit
            w%pn = w%pp + 2.0_wp * h * w%pdot
            call eval_block(problem, w, block_jacobian, tn, w%pn, w%gn, status)
            if (user_failed(status, 'constraint_jacobian')) exit
            call problem%constraint_time_derivative(tn, w%pn, w%gt, status)
            if (user_failed(status, 'constraint_time_derivative')) exit
            native%nfprob = native%nfprob + 1
            w%rhs(1:nv) = w%f
            call block_times(w, w%gn, w%gpat, w%vp, w%rhs(nv + 1:))
            w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt) / (2.0_wp * h)
            call assemble(w, w%mm, w%gm, w%gn)
            call factor_solve(native, w, 'in a step', ev, status)
            if (ev /= ev_ok) return
            w%acc = w%rhs(1:nv)
            w%lam = w%rhs(nv + 1:)
            w%pp = w%p
            w%p = w%pn
            ! v_{i+1} = v_{i−1} + 2h a_i; vp becomes v_i
            w%f = w%vp + 2.0_wp * h * w%acc
            w%vp = w%v
            w%v = w%f
            call copy_block(w%gm, w%gn)
            if (unstable(w, i, check_stability, ev, status)) return
        end do
    end subroutine midpoint_substeps

    !> Non-finite values, or the §3.5 check after the second substep
    !> (i = 1): ‖v2 − v1‖ > 2 ‖v2‖ in the weights of the step start.
    logical function unstable(w, i, check_stability, ev, status)
        type(workspace_t), intent(in) :: w
        integer, intent(in) :: i
        logical, intent(in) :: check_stability
        integer, intent(inout) :: ev
        type(status_t), intent(inout) :: status
        unstable = .not. (all(ieee_is_finite(w%v)) .and. all(ieee_is_finite(w%p)))
        if (unstable) then
            call status%set(status_solver_failure, 'non-finite values', reason_non_finite)
        else if (check_stability .and. i == 1) then
            unstable = rms(w%v - w%vp, w%wst) > stability_ratio * rms(w%v, w%wst)
        end if
        if (unstable) ev = ev_restart
    end function unstable

    !> Aitken–Neville: w%tab(:, l) holds T_{j−1,l}; afterwards T_{j,l}.
    subroutine extrapolate_column(w, j)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        integer :: l
        real(wp) :: ratio
        do l = 1, j - 1
            ratio = (real(w%ctl%nj(j), wp) / real(w%ctl%nj(j - l), wp))**w%ctl%varpi
            w%d = (w%x - w%tab(:, l)) / (ratio - 1.0_wp)
            w%tab(:, l) = w%x
            w%x = w%x + w%d
        end do
        w%tab(:, j) = w%x
    end subroutine extrapolate_column

    !> Weights rtol max(|y0|, |T_{j,j}|) + atol on (q, v) (§3.3).
    subroutine step_weights(w, j)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        w%wt(1:w%nq) = w%rtol(1:w%nq) * max(abs(w%p0), abs(w%tab(1:w%nq, j))) &
            + w%atol(1:w%nq)
        w%wt(w%nq + 1:) = w%rtol(w%nq + 1:) * max(abs(w%v0), abs(w%tab(w%nq + 1:w%ne, j))) &
            + w%atol(w%nq + 1:)
    end subroutine step_weights

    !> err_j of column j (§3.3), then the column step size H_j and the work
    !> W_j (§3.4); ev_restart on divergence, a non-finite err_j or err_j ≥
    !> 1/uround (ODEX).
    subroutine column_error(w, j, big_h, hmax, ev)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        real(wp), intent(in) :: big_h, hmax
        integer, intent(out) :: ev
        real(wp) :: err
        ev = ev_ok
        call step_weights(w, j)
        associate (d => w%tab(1:w%ne, j) - w%tab(1:w%ne, j - 1))
            if (w%ctl%scheme == mexax_control_deuflhard) then
                ! the largest scaled component (docs/theory.md §7.3: the RMS
                ! norm let the longer chains' errors reach 90 TOL)
                err = maxval(abs(d) / w%wt)
            else
                err = rms(d, w%wt)
            end if
        end associate
        w%ctl%err(j) = err
        if (.not. ieee_is_finite(err) .or. err * epsilon(1.0_wp) >= 1.0_wp) then
            ev = ev_restart
        else if (w%ctl%diverged(j)) then
            ev = ev_restart
        else
            call w%ctl%column_step(j, big_h, hmax)
        end if
    end subroutine column_error
end module flexmbs_dae_mexax_tableau
