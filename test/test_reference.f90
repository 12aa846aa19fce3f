!> The independent reference integrator itself: orders and analytic solutions.
module test_reference
    use flexmbs_core_kinds, only: wp
    use reference_integrator, only: reference_ode_t, integrate_reference, integrate_fixed, &
        reference_order, lobatto_iiic_3, radau_iia_2
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_reference

    !> A coupled nonlinear pair with y = (1/(1 + t²), e^(−t)):
    !>   y1' = −2t y1² y2 e^t,  y2' = −(1 + t²) y1 y2.
    type, extends(reference_ode_t) :: coupled_t
    contains
        procedure :: rhs => coupled_rhs
        procedure :: jacobian => coupled_jacobian
    end type coupled_t

    !> Prothero–Robinson, y' = λ (y − cos t) − sin t, y(0) = 1: y = cos t,
    !> stiff for λ = −1e6.
    type, extends(reference_ode_t) :: prothero_robinson_t
        real(wp) :: lambda = -1.0e6_wp
    contains
        procedure :: rhs => pr_rhs
        procedure :: jacobian => pr_jacobian
    end type prothero_robinson_t

contains

    function collect_reference() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('lobatto_iiic_order_4_fixed_steps', test_order_lobatto), &
                 new_test('radau_iia_2_order_3_fixed_steps', test_order_radau), &
                 new_test('adaptive_reproduces_analytic', test_analytic), &
                 new_test('stiff_prothero_robinson', test_stiff), &
                 new_test('bad_input_not_ok', test_bad_input)]
    end function collect_reference

    subroutine test_order_lobatto(error)
        type(error_t), allocatable, intent(out) :: error
        call check_order(error, lobatto_iiic_3)
    end subroutine test_order_lobatto

    subroutine test_order_radau(error)
        type(error_t), allocatable, intent(out) :: error
        call check_order(error, radau_iia_2)
    end subroutine test_order_radau

    !> Fixed steps h = 1/8, 1/16, 1/32, 1/64 on t in [0, 1]: the global error
    !> falls like h^p, slopes within p ± 0.3 (measured 3.95–3.97, 2.84–2.96).
    subroutine check_order(error, method)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: method
        type(coupled_t) :: ode
        real(wp) :: t, y(2), errs(4), slope
        integer :: k, p
        logical :: ok
        character(len=80) :: msg
        p = reference_order(method)
        do k = 1, 4
            t = 0.0_wp
            y = 1.0_wp
            call integrate_fixed(ode, t, y, 1.0_wp, 2**(k + 2), ok, method)
            call check(error, ok, 'Newton failed')
            errs(k) = maxval(abs(y - coupled_exact(1.0_wp)))
        end do
        do k = 1, 3
            slope = log(errs(k) / errs(k + 1)) / log(2.0_wp)
            write (msg, '(a,i0,a,f6.3)') 'order ', p, ': slope ', slope
            call check(error, abs(slope - p) <= 0.3_wp, trim(msg))
        end do
    end subroutine check_order

    !> rtol = atol = 1e-6 … 1e-12 over [0, 2] and back. The error per step
    !> is held below tol, so the global error grows like tol·(steps) ∝
    !> tol^(p/(p+1)) = tol^0.8: within 10 tol^0.8 (measured 0.4 … 3), slope
    !> over the sweep 0.7 … 0.9 (measured 0.82 forward).
    subroutine test_analytic(error)
        type(error_t), allocatable, intent(out) :: error
        type(coupled_t) :: ode
        real(wp) :: t, y(2), tol, err, err_first, slope
        integer :: k, nsteps
        logical :: ok
        character(len=80) :: msg
        do k = 6, 12, 2
            tol = 10.0_wp**(-k)
            t = 0.0_wp
            y = 1.0_wp
            call integrate_reference(ode, t, y, 2.0_wp, tol, tol, nsteps, ok)
            call check(error, ok .and. t == 2.0_wp, 'forward run failed')
            err = maxval(abs(y - coupled_exact(2.0_wp)) / abs(coupled_exact(2.0_wp)))
            write (msg, '(a,es8.1,a,es10.3)') 'forward, tol ', tol, ': error/tol^0.8 = ', &
                err / expected_error(tol)
            call check(error, err <= 10.0_wp * expected_error(tol), trim(msg))
            if (k == 6) err_first = err
            call integrate_reference(ode, t, y, 0.0_wp, tol, tol, nsteps, ok)
            call check(error, ok .and. t == 0.0_wp, 'backward run failed')
            write (msg, '(a,es8.1,a,es10.3)') 'back, tol ', tol, ': error/tol^0.8 = ', &
                maxval(abs(y - 1.0_wp)) / expected_error(tol)
            call check(error, maxval(abs(y - 1.0_wp)) <= 10.0_wp * expected_error(tol), &
                trim(msg))
        end do
        slope = log10(err_first / err) / 6.0_wp
        write (msg, '(a,f6.3)') 'error against tolerance: slope ', slope
        call check(error, slope >= 0.7_wp .and. slope <= 0.9_wp, trim(msg))
    end subroutine test_analytic

    !> Prothero–Robinson, λ = −1e6, t in [0, 10], tol = 1e-6 … 1e-12:
    !> accurate (within 10 tol^0.8), and the steps follow cos t, not λ
    !> (L-stability; an explicit method would need ~1e7).
    subroutine test_stiff(error)
        type(error_t), allocatable, intent(out) :: error
        type(prothero_robinson_t) :: ode
        real(wp) :: t, y(1), tol, err
        integer :: k, nsteps
        logical :: ok
        character(len=80) :: msg
        do k = 6, 12, 2
            tol = 10.0_wp**(-k)
            t = 0.0_wp
            y = 1.0_wp
            call integrate_reference(ode, t, y, 10.0_wp, tol, tol, nsteps, ok)
            call check(error, ok, 'run failed')
            err = abs(y(1) - cos(10.0_wp))
            write (msg, '(a,es8.1,a,es10.3,a,i0)') 'tol ', tol, ': error/tol^0.8 = ', &
                err / expected_error(tol), ', steps ', nsteps
            call check(error, err <= 10.0_wp * expected_error(tol), trim(msg))
            call check(error, nsteps <= 1000, trim(msg))
        end do
    end subroutine test_stiff

    subroutine test_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(coupled_t) :: ode
        real(wp) :: t, y(2)
        integer :: nsteps
        logical :: ok
        t = 0.0_wp
        y = 1.0_wp
        call integrate_reference(ode, t, y, 1.0_wp, 0.0_wp, 1.0e-6_wp, nsteps, ok)
        call check(error, .not. ok .and. t == 0.0_wp, 'rtol = 0 accepted')
        call integrate_reference(ode, t, y, 1.0_wp, 1.0e-6_wp, 1.0e-6_wp, nsteps, ok, method=0)
        call check(error, .not. ok .and. t == 0.0_wp, 'unknown method accepted')
    end subroutine test_bad_input

    !> tol^(p/(p+1)) of the default method: the scale of the global error.
    pure real(wp) function expected_error(tol)
        real(wp), intent(in) :: tol
        expected_error = tol**(4.0_wp / 5.0_wp)
    end function expected_error

    pure function coupled_exact(t) result(y)
        real(wp), intent(in) :: t
        real(wp) :: y(2)
        y = [1.0_wp / (1.0_wp + t**2), exp(-t)]
    end function coupled_exact

    subroutine coupled_rhs(self, t, y, f)
        class(coupled_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        f(1) = -2.0_wp * t * y(1)**2 * y(2) * exp(t)
        f(2) = -(1.0_wp + t**2) * y(1) * y(2)
    end subroutine coupled_rhs

    subroutine coupled_jacobian(self, t, y, dfdy)
        class(coupled_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = -4.0_wp * t * y(1) * y(2) * exp(t)
        dfdy(1, 2) = -2.0_wp * t * y(1)**2 * exp(t)
        dfdy(2, 1) = -(1.0_wp + t**2) * y(2)
        dfdy(2, 2) = -(1.0_wp + t**2) * y(1)
    end subroutine coupled_jacobian

    subroutine pr_rhs(self, t, y, f)
        class(prothero_robinson_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        f(1) = self%lambda * (y(1) - cos(t)) - sin(t)
    end subroutine pr_rhs

    subroutine pr_jacobian(self, t, y, dfdy)
        class(prothero_robinson_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = self%lambda
    end subroutine pr_jacobian
end module test_reference
