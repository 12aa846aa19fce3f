!> RADAU5 core: anchors, orders, accuracy, dense output, counters, failures.
module test_radau5
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, status_bad_input, &
        status_interrupted, reason_step_too_small, reason_max_steps
    use flexmbs_linalg_matrix, only: storage_dense
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_van_der_pol, only: van_der_pol_t, new_van_der_pol
    use reference_integrator, only: reference_ode_t, integrate_reference
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_radau5

    !> y' = −2t y², y(0) = 1: y = 1/(1 + t²) (smooth, nonlinear, analytic).
    type, extends(dae_problem_t) :: riccati_t
    contains
        procedure :: rhs => riccati_rhs
        procedure :: jacobian_storage => riccati_storage
        procedure :: jacobian_dense => riccati_jacobian
    end type riccati_t

    !> y' = −y, but F is NaN once t passes t_bad.
    type, extends(dae_problem_t) :: poisoned_t
        real(wp) :: t_bad = 0.5_wp
    contains
        procedure :: rhs => poisoned_rhs
    end type poisoned_t

    !> Records every accepted step and checks the dense output at its ends.
    type, extends(sink_t) :: step_checker_t
        integer :: nsteps = 0, noutputs = 0
        real(wp) :: max_jump = 0.0_wp   !! |u(t_old) − y_old| over steps
        real(wp) :: max_end = 0.0_wp    !! |u(t) − y| over steps
        real(wp) :: y_old(2) = 0.0_wp
        real(wp) :: last_output_t = -1.0_wp
        integer :: stop_after = huge(1)
    contains
        procedure :: output => checker_output
        procedure :: wants_steps => checker_wants_steps
        procedure :: step => checker_step
    end type step_checker_t

    !> Van der Pol for the independent integrator, written anew from the
    !> equations (not through `van_der_pol_t`).
    type, extends(reference_ode_t) :: vdp_ode_t
        real(wp) :: eps = 1.0e-6_wp
    contains
        procedure :: rhs => vdp_ode_rhs
        procedure :: jacobian => vdp_ode_jacobian
    end type vdp_ode_t

    real(wp), parameter :: vdp_y0(2) = [2.0_wp, -0.66_wp]
    real(wp), parameter :: vdp_t_end = 2.0_wp

    !> Reference y(2) of van der Pol, ε = 1e-6: computed once by `vdp_reference`.
    real(wp), save :: vdp_ref(2) = 0.0_wp

contains

    function collect_radau5() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('van_der_pol_anchor_counters', test_vdp_anchor), &
                 new_test('order_5_fixed_steps', test_order5), &
                 new_test('van_der_pol_tolerances_1e-4_to_1e-10', test_vdp_sweep), &
                 new_test('dense_output_continuous', test_dense_output), &
                 new_test('difference_jacobian_same_counters', test_fd_jacobian), &
                 new_test('classical_controller', test_classical), &
                 new_test('non_finite_is_failure', test_non_finite), &
                 new_test('max_steps_reports_time', test_max_steps), &
                 new_test('bad_input', test_bad_input), &
                 new_test('interrupt_by_sink', test_interrupt)]
    end function collect_radau5

    !> Tight reference: RADAU5 at rtol = atol = 1e-14, confirmed by the
    !> independent Lobatto IIIC integrator of `reference_integrator`. Its
    !> global error falls like tol^0.8 (local error per step, value y_h/2
    !> kept), so its runs at 1e-13 and 1e-14 differ by about the error of the
    !> 1e-13 run (measured 1.2e-11 relative); the 1e-14 run is ~6× better.
    !> Together ~1 s (debug), 17 000 and 33 000 steps.
    subroutine vdp_reference(error)
        type(error_t), allocatable, intent(inout) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(vdp_ode_t) :: ode
        real(wp) :: y(2), y_coarse(2), y_fine(2), t, estimate, difference
        integer :: nsteps
        logical :: ok
        character(len=120) :: msg
        if (vdp_ref(1) /= 0.0_wp) return
        call run_vdp(1.0e-14_wp, solver, y, stats, status)
        call check(error, status%ok(), 'reference run failed: ' // status%text())
        t = 0.0_wp
        y_coarse = vdp_y0
        call integrate_reference(ode, t, y_coarse, vdp_t_end, 1.0e-13_wp, 1.0e-13_wp, &
            nsteps, ok, h0=1.0e-6_wp)
        call check(error, ok, 'independent run at 1e-13 failed')
        t = 0.0_wp
        y_fine = vdp_y0
        call integrate_reference(ode, t, y_fine, vdp_t_end, 1.0e-14_wp, 1.0e-14_wp, &
            nsteps, ok, h0=1.0e-6_wp)
        call check(error, ok, 'independent run at 1e-14 failed')
        estimate = maxval(abs(y_coarse - y_fine) / abs(y_fine))
        difference = maxval(abs(y - y_fine) / abs(y))
        write (msg, '(a,es9.2)') 'independent integrator not accurate enough: ', estimate
        call check(error, estimate <= 3.0e-11_wp, trim(msg))
        ! The fine run is within ~estimate/6 ≈ 2e-12, RADAU5 at 1e-14 within
        ! ~1e-12 (measured difference 2.2e-12): 1e-11 leaves a 4× margin.
        write (msg, '(a,es9.2)') 'reference not confirmed by the independent integrator: ', &
            difference
        call check(error, difference <= 1.0e-11_wp, trim(msg))
        vdp_ref = y
    end subroutine vdp_reference

    subroutine run_vdp(rtol, solver, y, stats, status, sink)
        real(wp), intent(in) :: rtol
        type(radau5_t), intent(inout) :: solver
        real(wp), intent(out) :: y(2)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        type(van_der_pol_t) :: problem
        type(dae_options_t) :: options
        real(wp) :: t
        problem = new_van_der_pol(1.0e-6_wp)
        options%rtol = rtol
        options%atol = rtol
        options%h0 = 1.0e-6_wp
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status, sink)
    end subroutine run_vdp

    subroutine test_vdp_anchor(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(2)
        call run_vdp(1.0e-4_wp, solver, y, stats, status)
        call check(error, status%ok(), 'integration failed: ' // status%text())
        call check_close(error, y(1), 1.706161101_wp, 1e-9_wp, 'y1(2)')
        call check_close(error, y(2), -0.8928074777_wp, 1e-9_wp, 'y2(2)')
        ! The anchor of docs/solvers.md: the original's counters, exactly.
        call check(error, solver%native%nfcn == 2218, 'NFCN /= 2218')
        call check(error, solver%native%njac == 161, 'NJAC /= 161')
        call check(error, solver%native%nstep == 275, 'NSTEP /= 275')
        call check(error, solver%native%naccpt == 238, 'NACCPT /= 238')
        call check(error, solver%native%nrejct == 8, 'NREJCT /= 8')
        call check(error, solver%native%ndec == 248, 'NDEC /= 248')
        call check(error, solver%native%nsol == 660, 'NSOL /= 660')
        call check(error, stats%nst == stats%nac + stats%nrj, 'NST /= NAC + NRJ')
        call check(error, stats%nst == 275 .and. stats%nac == 238 .and. stats%nfe == 2218 &
            .and. stats%nje == 161 .and. stats%ndec == 248, 'common counters differ from native')
        call check(error, stats%nsol == 660 + solver%nsol_error, 'common NSOL')
        call check(error, stats%nfe_jac == 0, 'analytic Jacobian made difference calls')
    end subroutine test_vdp_anchor

    !> Fixed steps on y' = −2t y², t in [0, 2]: global error O(h⁵), slope 4.5–5.5.
    subroutine test_order5(error)
        type(error_t), allocatable, intent(out) :: error
        type(riccati_t) :: problem
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(1), errs(3), hs(3), slope
        integer :: k
        character(len=80) :: msg
        problem%n = 1
        solver%fixed_step = .true.
        solver%nit = 30   ! converge Newton fully: no step-size reduction
        ! Tight tolerances: they only set the Newton stopping criterion here.
        options%rtol = 1.0e-13_wp
        options%atol = 1.0e-13_wp
        hs = [0.2_wp, 0.1_wp, 0.05_wp]
        do k = 1, 3
            options%h0 = hs(k)
            t = 0.0_wp
            y = 1.0_wp
            call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
            call check(error, status%ok(), 'fixed-step run failed: ' // status%text())
            errs(k) = abs(y(1) - 0.2_wp)
            call check(error, stats%nac == nint(2.0_wp / hs(k)) .and. stats%nrj == 0, &
                'steps were not fixed')
        end do
        do k = 1, 2
            slope = log(errs(k) / errs(k + 1)) / log(2.0_wp)
            write (msg, '(a,f6.3)') 'order slope out of [4.5, 5.5]: ', slope
            call check(error, slope >= 4.5_wp .and. slope <= 5.5_wp, trim(msg))
        end do
    end subroutine test_order5

    !> rtol = atol = 1e-4 … 1e-10: ERR of eq. (13) ≤ 10 rtol against the
    !> tight reference.
    subroutine test_vdp_sweep(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(2), rtol, err
        integer :: k
        character(len=120) :: msg
        call vdp_reference(error)
        if (allocated(error)) return
        do k = 4, 10
            rtol = 10.0_wp**(-k)
            call run_vdp(rtol, solver, y, stats, status)
            call check(error, status%ok(), 'run failed: ' // status%text())
            err = paper_error(y, vdp_ref, rtol, rtol)
            write (msg, '(a,es8.1,a,es10.3)') 'rtol ', rtol, ': ERR/rtol = ', err / rtol
            call check(error, err <= 10.0_wp * rtol, trim(msg))
            call check(error, stats%nst == stats%nac + stats%nrj, 'NST /= NAC + NRJ')
        end do
    end subroutine test_vdp_sweep

    subroutine test_dense_output(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(step_checker_t) :: sink
        type(van_der_pol_t) :: problem
        type(dae_options_t) :: options
        real(wp) :: t, y(2)
        integer :: k
        problem = new_van_der_pol(1.0e-6_wp)
        options%rtol = 1.0e-6_wp
        options%atol = 1.0e-6_wp
        options%output_times = [(0.1_wp * k, k=0, 20)]
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        sink%y_old = y
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status, sink)
        call check(error, status%ok(), 'run failed: ' // status%text())
        call check(error, sink%nsteps == stats%nac + 1, 'step sink not called per step')
        call check(error, sink%noutputs == 21, 'not every output time was reached')
        call check_close(error, sink%last_output_t, 2.0_wp, 0.0_wp, 'last output time')
        call check(error, sink%max_end == 0.0_wp, 'dense output differs from y at step end')
        ! σ = (t_old − t)/h carries the round-off of t (|t|·eps/h), amplified by
        ! h·y' in van der Pol's fast transients: 1e-8 is far below rtol.
        call check(error, sink%max_jump <= 1.0e-8_wp, 'dense output jumps at step start')
    end subroutine test_dense_output

    !> Difference Jacobian: same trajectory to ~tolerance, calls kept apart.
    subroutine test_fd_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(van_der_pol_t) :: problem
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(2)
        call vdp_reference(error)
        if (allocated(error)) return
        problem = new_van_der_pol(1.0e-6_wp)
        options%rtol = 1.0e-6_wp
        options%atol = 1.0e-6_wp
        options%jacobian = 'fd'
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%ok(), 'fd run failed: ' // status%text())
        call check(error, stats%nfe_jac == 2 * stats%nje, 'one call per column expected')
        call check(error, paper_error(y, vdp_ref, 1.0e-6_wp, 1.0e-6_wp) <= 1.0e-5_wp, &
            'fd run inaccurate')
    end subroutine test_fd_jacobian

    subroutine test_classical(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(2)
        call vdp_reference(error)
        if (allocated(error)) return
        solver%controller = 2
        call run_vdp(1.0e-6_wp, solver, y, stats, status)
        call check(error, status%ok(), 'run failed: ' // status%text())
        call check(error, paper_error(y, vdp_ref, 1.0e-6_wp, 1.0e-6_wp) <= 1.0e-5_wp, &
            'classical controller inaccurate')
    end subroutine test_classical

    !> NaN in F from t = 0.5 on: never accepted, ends as step size too small.
    subroutine test_non_finite(error)
        type(error_t), allocatable, intent(out) :: error
        type(poisoned_t) :: problem
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(1)
        problem%n = 1
        t = 0.0_wp
        y = 1.0_wp
        call solver%integrate(problem, t, y, 1.0_wp, options, stats, status)
        call check(error, status%code == status_solver_failure, 'NaN run did not fail')
        call check(error, status%reason == reason_step_too_small, 'reason: ' // status%text())
        call check(error, all(ieee_is_finite(y)), 'a NaN state was accepted')
        call check(error, t <= 0.5_wp .and. t > 0.4_wp, 'time reached not reported')
        call check_close(error, y(1), exp(-t), 1.0e-5_wp, 'last accepted state', rel=.true.)
        call check(error, index(status%text(), 't = ') > 0, 'message lacks the time')
    end subroutine test_non_finite

    subroutine test_max_steps(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(van_der_pol_t) :: problem
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(2)
        problem = new_van_der_pol(1.0e-6_wp)
        options%max_steps = 50
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%reason == reason_max_steps, 'expected max steps failure')
        ! NST counts the 50 attempts made; the native NSTEP also the 51st it stopped on
        call check(error, stats%nst == 50 .and. solver%native%nstep == 51 .and. &
            stats%rejections%total() == stats%nrj .and. t > 0.0_wp .and. t < 2.0_wp, &
            'statistics or time reached wrong at failure')
        call check(error, index(status%text(), 't =') > 0, 'message lacks the time')
    end subroutine test_max_steps

    subroutine test_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(van_der_pol_t) :: problem
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(2)
        problem = new_van_der_pol(1.0e-6_wp)
        options%rtol = -1.0e-6_wp
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input, 'negative rtol accepted')
        call check(error, index(status%text(), 'rtol') > 0, 'message does not name rtol')
        options%rtol = 1.0e-6_wp
        solver%thet = 2.0_wp
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input, 'thet >= 1 accepted')
        ! SAFE's range is the scene schema's rule (core/rules): both ends open
        solver%thet = 0.001_wp
        solver%safe = 1.0_wp
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'safe must lie in (0.001, 1)') > 0, 'safe = 1: ' // status%text())
        solver%safe = 0.001_wp
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input, 'safe = 0.001 accepted')
        solver%safe = 0.0011_wp
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        ! (inside the range, though no use on van der Pol: the steps stall)
        call check(error, status%code /= status_bad_input, 'safe = 0.0011 refused: ' // &
            status%text())
    end subroutine test_bad_input

    subroutine test_interrupt(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(step_checker_t) :: sink
        real(wp) :: y(2)
        sink%stop_after = 10
        sink%y_old = [2.0_wp, -0.66_wp]
        call run_vdp(1.0e-4_wp, solver, y, stats, status, sink)
        call check(error, status%code == status_interrupted, 'sink stop not honoured')
        call check(error, stats%nac == 9, 'stopped at the wrong step')
    end subroutine test_interrupt

    ! ---- test problems and sinks ----

    subroutine riccati_rhs(self, t, y, f, status)
        class(riccati_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f(1) = -2.0_wp * t * y(1)**2
    end subroutine riccati_rhs

    integer function riccati_storage(self)
        class(riccati_t), intent(in) :: self
        riccati_storage = storage_dense
    end function riccati_storage

    subroutine riccati_jacobian(self, t, y, jac, status)
        class(riccati_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        jac(1, 1) = -4.0_wp * t * y(1)
    end subroutine riccati_jacobian

    subroutine vdp_ode_rhs(self, t, y, f)
        class(vdp_ode_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        f(1) = y(2)
        f(2) = ((1.0_wp - y(1)**2) * y(2) - y(1)) / self%eps
    end subroutine vdp_ode_rhs

    subroutine vdp_ode_jacobian(self, t, y, dfdy)
        class(vdp_ode_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = 0.0_wp
        dfdy(1, 2) = 1.0_wp
        dfdy(2, 1) = -(2.0_wp * y(1) * y(2) + 1.0_wp) / self%eps
        dfdy(2, 2) = (1.0_wp - y(1)**2) / self%eps
    end subroutine vdp_ode_jacobian

    subroutine poisoned_rhs(self, t, y, f, status)
        class(poisoned_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        if (t > self%t_bad) then
            f = ieee_value(1.0_wp, ieee_quiet_nan)
        else
            f = -y
        end if
    end subroutine poisoned_rhs

    subroutine checker_output(self, t, y, status)
        class(step_checker_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        self%noutputs = self%noutputs + 1
        self%last_output_t = t
    end subroutine checker_output

    logical function checker_wants_steps(self)
        class(step_checker_t), intent(in) :: self
        checker_wants_steps = .true.
    end function checker_wants_steps

    subroutine checker_step(self, nr, t_old, t, y, dense, stop, status)
        class(step_checker_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        logical, intent(inout) :: stop
        type(status_t), intent(inout) :: status
        real(wp) :: u(size(y))
        self%nsteps = self%nsteps + 1
        if (nr > 1) then
            call dense%evaluate(t_old, u)
            self%max_jump = max(self%max_jump, maxval(abs(u - self%y_old) / (1 + abs(y))))
            call dense%evaluate(t, u)
            self%max_end = max(self%max_end, maxval(abs(u - y)))
        end if
        self%y_old = y
        if (nr >= self%stop_after) stop = .true.
    end subroutine checker_step
end module test_radau5
