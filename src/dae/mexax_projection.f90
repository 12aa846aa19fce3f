!> MEXAX projection (docs/theory.md §7.4): the extrapolated positions
!> onto g = 0 by simplified Newton and the velocities onto G v + g_I = 0
!> [LNPE95; Lub91; HW96 VII.2], with the ratio c of the rejection test.
module flexmbs_dae_mexax_projection
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_non_finite, &
        reason_projection
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_mexax_workspace, only: workspace_t, mexax_native_t, ev_ok, eval_block, &
        block_mass, block_jacobian, assemble, factor, solve, factor_solve, user_failed, &
        block_times, rms
    implicit none
    private
    public :: project

    ! §3.6: the position iteration stops at ε ≤ EPSREQ, fails when ε grows by
    ! more than 2 or after ITMAX iterations [LNPE95].
    real(wp), parameter :: epsreq = 1.0e-2_wp, projection_growth = 2.0_wp
    integer, parameter :: itmax = 10
    ! §3.6 [R normalisation]: rejection when the projection moved (p, v) by
    ! more than FACP, FACV weighted units (no published normalisation found).
    real(wp), parameter :: facp = 5.0_wp, facv = 5.0_wp

contains

    !> Projection of (w%p, w%v) at time t (§3.6): positions onto g = 0 by
    !> simplified Newton with the matrix at p̃, then velocities onto
    !> G v + g_I = 0 at the projected p. c is the rejection ratio.
    !> The position iteration solves the projection's optimality conditions
    !> M Δ + Gᵀμ = 0, g = 0 for the increment δ of the accumulated correction
    !> Δ and the whole multiplier μ: [M Gᵀ; G 0][δ; μ] = [−M Δ; −g]. Its
    !> iterates are those of the increment form with right-hand side [0; −g],
    !> but the first-row residual is not assumed zero; the product M Δ is
    !> counted in NMULT, as the original's counters show it does (docs/theory.md
    !> §7.7).
    subroutine project(native, problem, w, t, c, status)
        type(mexax_native_t), intent(inout) :: native
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t
        real(wp), intent(out) :: c
        type(status_t), intent(out) :: status
        integer :: m, nq, nv, ev
        real(wp) :: eps, eps_old
        nq = w%nq
        nv = w%nv
        c = 0.0_wp
        w%pn = w%p   ! p̃
        w%vp = w%v   ! ṽ
        call eval_block(problem, w, block_mass, t, w%pn, w%mm, status)
        if (.not. user_failed(status, 'mass')) &
            call eval_block(problem, w, block_jacobian, t, w%pn, w%gm, status)
        if (user_failed(status, 'constraint_jacobian')) return
        native%nfprob = native%nfprob + 1
        call assemble(w, w%mm, w%gm, w%gm)
        call factor(w, status)
        if (.not. status%ok()) then
            status%message = 'augmented matrix [M C^T; C 0] is singular in the position &
                &projection'
            return
        end if
        native%ndec = native%ndec + 1
        eps_old = 0.0_wp
        w%shift = 0.0_wp
        do m = 0, itmax - 1
            call problem%constraint(t, w%p, w%gt, status)
            native%ngcn = native%ngcn + 1
            native%nfprob = native%nfprob + 1
            if (user_failed(status, 'constraint')) return
            call block_times(w, w%mm, w%mpat, w%shift, w%rhs(1:nv))
            native%nmult = native%nmult + 1
            w%rhs(1:nv) = -w%rhs(1:nv)
            w%rhs(nv + 1:) = -w%gt
            call solve(w, w%rhs)
            native%nsol = native%nsol + 1
            ! one FPROB call (flag 5): T(p̃) δ
            call problem%kinematics(t, w%pn, w%rhs(1:nv), w%pdot, status)
            native%nfprob = native%nfprob + 1
            if (user_failed(status, 'kinematics')) return
            w%p = w%p + w%pdot
            w%shift = w%shift + w%rhs(1:nv)
            eps = rms(w%pdot, w%wt(1:nq))
            if (eps <= epsreq) exit
            if (.not. ieee_is_finite(eps) .or. (m >= 1 .and. eps > projection_growth * eps_old) &
                .or. m + 1 >= itmax) then
                call status%set(status_solver_failure, 'position projection did not converge &
                    &(iteration ' // int_text(m + 1) // ', weighted correction ' // &
                    real_text(eps) // ')', reason_projection)
                return
            end if
            eps_old = eps
        end do
        call eval_block(problem, w, block_mass, t, w%p, w%mm, status)
        if (.not. user_failed(status, 'mass')) &
            call eval_block(problem, w, block_jacobian, t, w%p, w%gm, status)
        if (.not. user_failed(status, 'constraint_jacobian')) &
            call problem%constraint_time_derivative(t, w%p, w%gt, status)
        if (user_failed(status, 'constraint_time_derivative')) return
        native%nfprob = native%nfprob + 1
        w%rhs(1:nv) = 0.0_wp
        call block_times(w, w%gm, w%gpat, w%vp, w%rhs(nv + 1:))
        w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt)
        call assemble(w, w%mm, w%gm, w%gm)
        call factor_solve(native, w, 'in the velocity projection', ev, status)
        if (ev /= ev_ok) return
        w%v = w%vp + w%rhs(1:nv)
        c = max(rms(w%p - w%pn, w%wt(1:nq)) / facp, rms(w%v - w%vp, w%wt(nq + 1:)) / facv)
        if (.not. ieee_is_finite(c)) call status%set(status_solver_failure, &
            'non-finite values in the projection', reason_non_finite)
    end subroutine project
end module flexmbs_dae_mexax_projection
