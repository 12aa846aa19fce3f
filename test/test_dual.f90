!> Forward-mode AD: derivatives of compositions of the overloaded operations and
!> intrinsics against analytic derivatives, array helpers, and the rotation formulas
!> on duals against the hand-coded identities.
module test_dual
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, dual_size, dual_variable, dual_constant, &
        dual_seed, dual_value, operator(+), operator(-), operator(*), operator(/), &
        operator(**), operator(==), operator(/=), operator(<), operator(<=), &
        operator(>), operator(>=), assignment(=), sqrt, exp, log, sin, cos, tan, &
        asin, acos, atan, atan2, sinh, cosh, tanh, abs, max, min, dot_product, matmul, &
        sum, norm2
    use flexmbs_mbs_rotation, only: rotation_matrix, rotated_vector_jacobian, &
        rotated_vector_transpose_jacobian, quat_rate_matrix, skew
    use flexmbs_mbs_rotation_dual, only: rotation_matrix_d => rotation_matrix, &
        quat_normalize_d => quat_normalize
    use mbs_random, only: random_state_t, random_vector, random_quaternion
    use flexmbs_mbs_jet, only: jet_t, operator(+), operator(-), operator(*), operator(/), &
        operator(**), sqrt, sin, cos, matmul
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_dual

    ! Forward mode is exact but for rounding: a few ulps of the largest term.
    real(wp), parameter :: tol_ad = 1.0e-13_wp

contains

    function collect_dual() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('scalar_composition', test_scalar_composition), &
                 new_test('comparisons_branches', test_comparisons), &
                 new_test('array_helpers', test_array_helpers), &
                 new_test('rotation_identities_ad', test_rotation_ad), &
                 new_test('jet_second_derivatives', test_jet)]
    end function collect_dual

    !> f(x, y) built from every overloaded scalar operation; df/dx, df/dy by hand.
    subroutine test_scalar_composition(error)
        type(error_t), allocatable, intent(out) :: error
        type(dual_t) :: x, y, f
        real(wp) :: a, b, fx, fy, fv, u
        a = 0.7_wp
        b = 1.3_wp
        x = dual_variable(a, 1)
        y = dual_variable(b, 2)
        f = sin(x * y) + exp(x) / sqrt(y) + log(x) * cos(y) + atan2(y, x) + tanh(x - y) &
            + x**3 + y**2.5_wp + x**y + asin(0.3_wp * x) + acos(0.2_wp * y) &
            + tan(0.1_wp * x * y) + atan(x / y) + sinh(0.5_wp * x) * cosh(0.5_wp * y) &
            + abs(x - y) - (2.0_wp - x) / (1.0_wp + y) + atan2(y, 2.0_wp) &
            + atan2(1.5_wp, x) + (-y) + (+x) - 3.0_wp
        u = 0.1_wp * a * b
        fv = sin(a * b) + exp(a) / sqrt(b) + log(a) * cos(b) + atan2(b, a) + tanh(a - b) &
             + a**3 + b**2.5_wp + a**b + asin(0.3_wp * a) + acos(0.2_wp * b) + tan(u) &
             + atan(a / b) + sinh(0.5_wp * a) * cosh(0.5_wp * b) + abs(a - b) &
             - (2.0_wp - a) / (1.0_wp + b) + atan2(b, 2.0_wp) + atan2(1.5_wp, a) - b + a &
             - 3.0_wp
        fx = b * cos(a * b) + exp(a) / sqrt(b) + cos(b) / a - b / (a**2 + b**2) &
             + (1.0_wp - tanh(a - b)**2) + 3.0_wp * a**2 + b * a**(b - 1.0_wp) &
             + 0.3_wp / sqrt(1.0_wp - (0.3_wp * a)**2) + 0.1_wp * b / cos(u)**2 &
             + (1.0_wp / b) / (1.0_wp + (a / b)**2) &
             + 0.5_wp * cosh(0.5_wp * a) * cosh(0.5_wp * b) - 1.0_wp &
             + 1.0_wp / (1.0_wp + b) - 1.5_wp / (a**2 + 1.5_wp**2) + 1.0_wp
        fy = a * cos(a * b) - 0.5_wp * exp(a) / b**1.5_wp - log(a) * sin(b) &
             + a / (a**2 + b**2) - (1.0_wp - tanh(a - b)**2) + 2.5_wp * b**1.5_wp &
             + a**b * log(a) - 0.2_wp / sqrt(1.0_wp - (0.2_wp * b)**2) &
             + 0.1_wp * a / cos(u)**2 - (a / b**2) / (1.0_wp + (a / b)**2) &
             + 0.5_wp * sinh(0.5_wp * a) * sinh(0.5_wp * b) + 1.0_wp &
             + (2.0_wp - a) / (1.0_wp + b)**2 + 2.0_wp / (b**2 + 4.0_wp) - 1.0_wp
        call check_close(error, f%val, fv, tol_ad, 'value', rel=.true.)
        call check_close(error, f%der(1), fx, tol_ad, 'df/dx', rel=.true.)
        call check_close(error, f%der(2), fy, tol_ad, 'df/dy', rel=.true.)
        call check(error, all(f%der(3:) == 0.0_wp), 'unseeded directions stay zero')
        ! Integer powers, including 0 and negative.
        f = x**0 + x**(-2) + x**1
        call check_close(error, f%der(1), -2.0_wp / a**3 + 1.0_wp, tol_ad, 'd x**n', &
                         rel=.true.)
        f = x**y
        call check_close(error, f%der(2), a**b * log(a), tol_ad, 'd x**y / dy', rel=.true.)
    end subroutine test_scalar_composition

    !> Comparisons act on values; max, min, abs pick the branch's tangent.
    subroutine test_comparisons(error)
        type(error_t), allocatable, intent(out) :: error
        type(dual_t) :: x, y, z
        x = dual_variable(1.0_wp, 1)
        y = dual_variable(2.0_wp, 2)
        call check(error, x < y .and. x <= y .and. y > x .and. y >= x .and. x /= y &
                   .and. .not. (x == y), 'dual-dual comparisons')
        call check(error, x < 1.5_wp .and. 1.5_wp < y .and. x == 1.0_wp .and. &
                   2.0_wp == y .and. x /= 3.0_wp .and. 3.0_wp /= y .and. y >= 2.0_wp &
                   .and. 0.0_wp <= x .and. y > 0.0_wp .and. 5.0_wp > y .and. &
                   x <= 1.0_wp .and. 1.0_wp >= x, 'mixed comparisons')
        z = max(x, y)
        call check(error, z%val == 2.0_wp .and. z%der(2) == 1.0_wp .and. z%der(1) == 0.0_wp, &
                   'max picks y')
        z = min(x, y)
        call check(error, z%der(1) == 1.0_wp .and. z%der(2) == 0.0_wp, 'min picks x')
        z = max(x, 3.0_wp) + min(5.0_wp, y) + max(0.0_wp, x) + min(y, 0.0_wp)
        call check(error, z%val == 6.0_wp .and. z%der(1) == 1.0_wp .and. &
                   z%der(2) == 1.0_wp, 'mixed max/min')
        z = abs(-x)
        call check(error, z%val == 1.0_wp .and. z%der(1) == 1.0_wp, 'abs of negative')
        z = dual_seed(2.0_wp, [0.0_wp, 0.0_wp, 4.0_wp])
        call check(error, z%der(3) == 4.0_wp .and. dual_value(z) == 2.0_wp .and. &
                   size(z%der) == dual_size, 'seed')
    end subroutine test_comparisons

    !> d(x^T B x) = (B + B^T) x, d|x| = x/|x|, d(B(t) x(t)) = B' x + B x', sum.
    subroutine test_array_helpers(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: b(4, 4), xv(4), grad(4), bd(4, 4), xd(4), c(4, 2)
        type(dual_t) :: x(4), f, bt(4, 4), xt(4), y(4), m(4, 2)
        integer :: k
        b = reshape(random_vector(rng, 16, -1.0_wp, 1.0_wp), [4, 4])
        xv = random_vector(rng, 4, -1.0_wp, 1.0_wp)
        do k = 1, 4
            x(k) = dual_variable(xv(k), k)
        end do
        f = dot_product(x, matmul(b, x))
        grad = matmul(b + transpose(b), xv)
        call check_close(error, maxval(abs(f%der(1:4) - grad)), 0.0_wp, tol_ad, &
                         'd(x^T B x)')
        f = dot_product(matmul(transpose(b), x), x) - dot_product(xv, matmul(transpose(b), x))
        call check_close(error, maxval(abs(f%der(1:4) - matmul(transpose(b), xv))), 0.0_wp, &
                         tol_ad, &
                         'd(x^T B x - xv^T B^T x)')
        f = norm2(x)
        call check_close(error, maxval(abs(f%der(1:4) - xv / norm2(xv))), 0.0_wp, tol_ad, &
                         'd|x|')
        f = sum(x) + dot_product(x, xv)
        call check_close(error, maxval(abs(f%der(1:4) - (1.0_wp + xv))), 0.0_wp, tol_ad, &
                         'd sum')
        ! One direction t: B(t) = B + t Bd, x(t) = xv + t xd.
        bd = reshape(random_vector(rng, 16, -1.0_wp, 1.0_wp), [4, 4])
        xd = random_vector(rng, 4, -1.0_wp, 1.0_wp)
        do k = 1, 4
            xt(k) = dual_seed(xv(k), [xd(k)])
        end do
        bt = b
        bt%der(1) = bd
        y = matmul(bt, xt)
        call check_close(error, maxval(abs(y%der(1) - matmul(bd, xv) - matmul(b, xd))), &
                         0.0_wp, tol_ad, "(B x)'")
        c = reshape(random_vector(rng, 8, -1.0_wp, 1.0_wp), [4, 2])
        m = matmul(bt, c) + matmul(b, dual_constant(c)) + matmul(dual_constant(b), &
                                                             dual_constant(c))
        call check_close(error, maxval(abs(m%der(1) - matmul(bd, c))), 0.0_wp, tol_ad, &
                         "(B C)'")
        call check_close(error, maxval(abs(m%val - 3.0_wp * matmul(b, c))), 0.0_wp, &
                         tol_ad, 'B C value')
    end subroutine test_array_helpers

    !> AD of A(p) s and A(p)^T s equals the hand-coded d(A s)/dp; AD of A(p/|p|) s
    !> along T w_b equals -A skew(s) w_b (the normalisation is invisible along T w_b).
    subroutine test_rotation_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p(4), s(3), wb(3), worst, worst_t, worst_v, tw(4)
        type(dual_t) :: pd(4), a(3, 3), r(3)
        integer :: trial, k
        worst = 0.0_wp
        worst_t = 0.0_wp
        worst_v = 0.0_wp
        do trial = 1, 50
            p = random_quaternion(rng)
            s = random_vector(rng, 3, -1.0_wp, 1.0_wp)
            wb = random_vector(rng, 3, -2.0_wp, 2.0_wp)
            tw = matmul(quat_rate_matrix(p), wb)
            do k = 1, 4
                pd(k) = dual_variable(p(k), k)
                pd(k)%der(5) = tw(k)
            end do
            a = rotation_matrix_d(pd)
            r = matmul(a, s)
            worst = max(worst, maxval(abs(reshape([(r%der(k), k = 1, 4)], [3, 4]) - &
                        rotated_vector_jacobian(p, s))))
            worst = max(worst, maxval(abs(r%val - matmul(rotation_matrix(p), s))))
            r = matmul(transpose(a), s)
            worst_t = max(worst_t, maxval(abs(reshape([(r%der(k), k = 1, 4)], [3, 4]) - &
                          rotated_vector_transpose_jacobian(p, s))))
            r = matmul(rotation_matrix_d(quat_normalize_d(pd)), s)
            worst_v = max(worst_v, maxval(abs(r%der(5) + &
                          matmul(rotation_matrix(p), matmul(skew(s), wb)))))
        end do
        call check_close(error, worst, 0.0_wp, tol_ad, 'AD d(A s)/dp')
        call check_close(error, worst_t, 0.0_wp, tol_ad, 'AD d(A^T s)/dp')
        call check_close(error, worst_v, 0.0_wp, tol_ad, 'AD d(A s)/dt along T w_b')
    end subroutine test_rotation_ad

    !> Jets along s: f(s) = sin(x) sqrt(y) / z + x**3 − cos(x y), with x, y, z
    !> quadratics in s, and a 2 × 2 matrix-vector product: value, f' and f''
    !> against the closed forms and central differences of the real formula.
    subroutine test_jet(error)
        type(error_t), allocatable, intent(out) :: error
        type(jet_t) :: x, y, z, f, m(2, 2), u(2), w(2)
        real(wp) :: h, fp, fm, f0, d1, d2
        x = jet_t(0.7_wp, 1.3_wp, -0.4_wp)
        y = jet_t(2.1_wp, -0.6_wp, 0.9_wp)
        z = jet_t(1.5_wp, 0.2_wp, 0.3_wp)
        f = sin(x) * sqrt(y) / z - cos(x * y) + x**3
        h = 1.0e-4_wp
        f0 = real_f(0.0_wp)
        fp = real_f(h)
        fm = real_f(-h)
        d1 = (fp - fm) / (2.0_wp * h)
        d2 = (fp - 2.0_wp * f0 + fm) / h**2
        call check_close(error, f%f0, f0, 1.0e-14_wp, 'jet value')
        if (allocated(error)) return
        call check_close(error, f%f1, d1, 1.0e-7_wp, 'jet first derivative')
        if (allocated(error)) return
        call check_close(error, f%f2, d2, 1.0e-5_wp, 'jet second derivative')
        if (allocated(error)) return
        ! (M u)'' for M(s) = M0 + s M1, u(s) = u0 + s u1 + s² u2 / 2: 2 M1 u1 + M0 u2
        m = reshape([jet_t(1.0_wp, 2.0_wp, 0.0_wp), jet_t(3.0_wp, -1.0_wp, 0.0_wp), &
                     jet_t(0.5_wp, 0.0_wp, 0.0_wp), jet_t(-2.0_wp, 1.0_wp, 0.0_wp)], [2, 2])
        u = [jet_t(1.0_wp, 1.0_wp, 2.0_wp), jet_t(-1.0_wp, 0.5_wp, 1.0_wp)]
        w = matmul(m, u)
        call check(error, abs(w(1)%f2 - (2.0_wp * (2.0_wp * 1.0_wp + 0.0_wp * 0.5_wp) + &
                   (1.0_wp * 2.0_wp + 0.5_wp * 1.0_wp))) <= 1.0e-14_wp .and. &
                   abs(w(2)%f2 - (2.0_wp * (-1.0_wp * 1.0_wp + 1.0_wp * 0.5_wp) + &
                   (3.0_wp * 2.0_wp - 2.0_wp * 1.0_wp))) <= 1.0e-14_wp, 'jet matmul')

    contains

        real(wp) function real_f(s)
            real(wp), intent(in) :: s
            real(wp) :: xr, yr, zr
            xr = 0.7_wp + 1.3_wp * s - 0.2_wp * s**2
            yr = 2.1_wp - 0.6_wp * s + 0.45_wp * s**2
            zr = 1.5_wp + 0.2_wp * s + 0.15_wp * s**2
            real_f = sin(xr) * sqrt(yr) / zr - cos(xr * yr) + xr**3
        end function real_f
    end subroutine test_jet
end module test_dual
