!> Interface frames of modal bodies (mbs/modal_frame): the hand-coded c_q,
!> G and γ against AD and against central differences of c along the
!> motion, and the rows zero on the interface's own frame.
module test_modal_frame
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text
    use flexmbs_mbs_rotation, only: quat_from_axis_angle, quat_product, quat_rate_matrix
    use flexmbs_mbs_modal_frame, only: modal_interface_t, modal_frame_columns, &
        modal_frame_value, modal_frame_jacobian, modal_frame_curvature, &
        modal_frame_jacobian_ad, modal_frame_curvature_ad, modal_frame_rate_q, &
        modal_frame_gtl_q, modal_frame_curvature_qv
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_modal_frame

    integer, parameter :: n = 20   ! modes: two AD passes over η

contains

    function collect_modal_frame() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('analytic_vs_ad', test_analytic_ad), &
                 new_test('analytic_vs_differences', test_differences), &
                 new_test('zero_on_the_interface', test_zero)]
    end function collect_modal_frame

    !> An interface with every coefficient awake, a state z = (r_f, p_f, r,
    !> p, η) and velocities w.
    subroutine example(m, z, w)
        type(modal_interface_t), intent(out) :: m
        real(wp), intent(out) :: z(14 + n), w(12 + n)
        integer :: i, k
        m%offset = [0.3_wp, -0.05_wp, 0.02_wp]
        allocate (m%translation(3, n), m%rotation(3, n))
        do k = 1, n
            do i = 1, 3
                m%translation(i, k) = 0.1_wp * sin(1.1_wp * i + 0.7_wp * k)
                m%rotation(i, k) = 0.5_wp * cos(0.9_wp * i + 1.3_wp * k)
            end do
        end do
        z(1:3) = [0.2_wp, 0.1_wp, -0.3_wp]
        z(4:7) = quat_from_axis_angle([0.0_wp, 0.6_wp, 0.8_wp], 0.4_wp)
        z(8:10) = [-0.1_wp, 0.2_wp, 0.05_wp]
        z(11:14) = quat_from_axis_angle([0.48_wp, 0.6_wp, 0.64_wp], -0.9_wp)
        do k = 1, n
            z(14 + k) = 0.02_wp * sin(2.1_wp * k)
        end do
        do k = 1, 12 + n
            w(k) = cos(0.8_wp * k)
        end do
    end subroutine example

    !> c_q, G, γ, ∂(G w)/∂q and ∂γ/∂q, ∂γ/∂v: hand-coded against AD.
    subroutine test_analytic_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_interface_t) :: m
        real(wp) :: z(14 + n), w(12 + n), a(6, 14 + n), b(6, 14 + n), gv(6, 12 + n), &
            gva(6, 12 + n), gam(6), gama(6)
        call example(m, z, w)
        ! off the unit sphere too: G = c_q T for the quadratic extension
        z(4:7) = 1.1_wp * z(4:7)
        z(11:14) = 0.9_wp * z(11:14)
        call check(error, modal_frame_columns(m, .true.) == 14 + n .and. &
                   modal_frame_columns(m, .false.) == 12 + n, 'columns')
        call modal_frame_jacobian(m, z, .true., a)
        call modal_frame_jacobian_ad(m, z, .true., b)
        call check(error, maxval(abs(a - b)) <= 1.0e-14_wp * maxval(abs(b)), 'c_q vs AD: ' // &
                   real_text(maxval(abs(a - b))))
        call modal_frame_jacobian(m, z, .false., gv)
        call modal_frame_jacobian_ad(m, z, .false., gva)
        call check(error, maxval(abs(gv - gva)) <= 1.0e-14_wp * maxval(abs(gva)), &
                   'G vs AD: ' // real_text(maxval(abs(gv - gva))))
        call modal_frame_curvature(m, z, w, gam)
        call modal_frame_curvature_ad(m, z, w, gama)
        call check(error, maxval(abs(gam - gama)) <= 1.0e-13_wp * maxval(abs(gama)), &
                   'gamma vs AD: ' // real_text(maxval(abs(gam - gama))))
    end subroutine test_analytic_ad

    !> G w = dc/dt along q' = T w, γ = d(G w)/dt along it, and the AD
    !> second derivatives against central differences of the hand-coded G
    !> and γ.
    subroutine test_differences(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_interface_t) :: m
        real(wp) :: z(14 + n), w(12 + n), zdot(14 + n), cp(6), cm(6), g(6, 12 + n), &
            gp(6, 12 + n), gm(6, 12 + n), gam(6), rq(6, 14 + n), lq(12 + n, 14 + n), &
            gq(6, 14 + n), gvv(6, 12 + n), lam(6), zs(14 + n), ws(12 + n), hp(6), hm(6), &
            d6(6), dl(12 + n), worst
        real(wp), parameter :: h = 1.0e-6_wp
        integer :: j
        call example(m, z, w)
        zdot(1:3) = w(1:3)
        zdot(4:7) = matmul(quat_rate_matrix(z(4:7)), w(4:6))
        zdot(8:10) = w(7:9)
        zdot(11:14) = matmul(quat_rate_matrix(z(11:14)), w(10:12))
        zdot(15:) = w(13:)
        call modal_frame_value(m, z + h * zdot, cp)
        call modal_frame_value(m, z - h * zdot, cm)
        call modal_frame_jacobian(m, z, .false., g)
        d6 = (cp - cm) / (2 * h) - matmul(g, w)
        call check(error, maxval(abs(d6)) <= 1.0e-8_wp * maxval(abs(cp - cm) / (2 * h)), &
                   'G w vs dc/dt: ' // real_text(maxval(abs(d6))))
        call modal_frame_jacobian(m, z + h * zdot, .false., gp)
        call modal_frame_jacobian(m, z - h * zdot, .false., gm)
        call modal_frame_curvature(m, z, w, gam)
        d6 = matmul(gp - gm, w) / (2 * h) - gam
        call check(error, maxval(abs(d6)) <= 1.0e-7_wp * maxval(abs(gam)), &
                   'gamma vs d(G w)/dt: ' // real_text(maxval(abs(d6))))
        lam = [0.3_wp, -1.0_wp, 0.5_wp, 2.0_wp, -0.7_wp, 1.1_wp]
        call modal_frame_rate_q(m, z, w, rq)
        call modal_frame_gtl_q(m, z, lam, lq)
        call modal_frame_curvature_qv(m, z, w, gq, gvv)
        worst = 0.0_wp
        do j = 1, 14 + n
            zs = z
            zs(j) = z(j) + h
            call modal_frame_jacobian(m, zs, .false., gp)
            call modal_frame_curvature(m, zs, w, hp)
            zs(j) = z(j) - h
            call modal_frame_jacobian(m, zs, .false., gm)
            call modal_frame_curvature(m, zs, w, hm)
            d6 = matmul(gp - gm, w) / (2 * h) - rq(:, j)
            dl = matmul(transpose(gp - gm), lam) / (2 * h) - lq(:, j)
            worst = max(worst, maxval(abs(d6)), maxval(abs(dl)), &
                        maxval(abs((hp - hm) / (2 * h) - gq(:, j))))
        end do
        do j = 1, 12 + n
            ws = w
            ws(j) = w(j) + h
            call modal_frame_curvature(m, z, ws, hp)
            ws(j) = w(j) - h
            call modal_frame_curvature(m, z, ws, hm)
            worst = max(worst, maxval(abs((hp - hm) / (2 * h) - gvv(:, j))))
        end do
        call check(error, worst <= 1.0e-6_wp, 'second derivatives vs differences: ' // &
                   real_text(worst))
    end subroutine test_differences

    !> On the interface's own frame (r_f = r + A u, p_f = p at η = 0; the
    !> small rotation's quaternion (1, θ/2) normalised otherwise) the rows
    !> vanish: exactly at η = 0, to O(|θ|³) else.
    subroutine test_zero(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_interface_t) :: m
        real(wp) :: z(14 + n), w(12 + n), c(6), th(3), e(4)
        real(wp) :: scale
        integer :: k
        call example(m, z, w)
        z(15:) = 0.0_wp
        z(4:7) = z(11:14)
        z(1:3) = z(8:10) + rotate(z(11:14), m%offset)
        call modal_frame_value(m, z, c)
        call check(error, maxval(abs(c)) <= 1.0e-15_wp, 'eta = 0: ' // real_text(maxval(abs(c))))
        do k = 1, 3
            scale = 10.0_wp**(-k)
            z(15:) = 0.0_wp
            z(15) = scale
            th = m%rotation(:, 1) * scale
            e = [1.0_wp, th / 2] / norm2([1.0_wp, th / 2])
            z(4:7) = quat_product(z(11:14), e)
            z(1:3) = z(8:10) + rotate(z(11:14), m%offset + m%translation(:, 1) * scale)
            call modal_frame_value(m, z, c)
            call check(error, maxval(abs(c(1:3))) <= 1.0e-15_wp, 'origin on the centroid')
            call check(error, maxval(abs(c(4:6))) <= 2.0_wp * norm2(th)**3, &
                       'rotation rows O(theta^3): ' // real_text(maxval(abs(c(4:6)))))
        end do
    contains
        function rotate(p, x) result(y)
            real(wp), intent(in) :: p(4), x(3)
            real(wp) :: y(3)
            real(wp) :: pv(4)
            pv = quat_product(quat_product(p, [0.0_wp, x]), [p(1), -p(2:4)])
            y = pv(2:4)
        end function rotate
    end subroutine test_zero
end module test_modal_frame
