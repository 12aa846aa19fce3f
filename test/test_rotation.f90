!> Rotations: orthogonality, composition, the G/L identities, q' = T(q) w along
!> exact rotations, and the derivative identities against central differences.
module test_rotation
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_rotation, only: skew, cross, quat_g, quat_l, rotation_matrix, &
        quat_rate_matrix, quat_product, quat_conjugate, quat_from_axis_angle, &
        quat_normalize, rotated_vector_jacobian, rotated_vector_transpose_jacobian
    use mbs_random, only: random_state_t, random_vector, random_quaternion
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_rotation

    integer, parameter :: ntrials = 50
    ! Identities hold to rounding of O(1) entries.
    real(wp), parameter :: tol_exact = 1.0e-14_wp
    ! Central differences of quadratics are exact but for the rounding of the
    ! quotient (~eps/h); of smooth paths, O(h^2).
    real(wp), parameter :: fd_step = 1.0e-5_wp
    real(wp), parameter :: tol_fd = 1.0e-9_wp

contains

    function collect_rotation() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('orthogonal_det_one', test_orthogonal), &
                 new_test('composition', test_composition), &
                 new_test('g_l_identities', test_gl_identities), &
                 new_test('rate_matrix_exact_rotation', test_rate_matrix), &
                 new_test('rotated_vector_jacobian_fd', test_rotated_vector_fd), &
                 new_test('rotated_vector_velocity', test_rotated_vector_velocity)]
    end function collect_rotation

    pure function det3(a) result(d)
        real(wp), intent(in) :: a(3, 3)
        real(wp) :: d
        d = dot_product(a(:, 1), cross(a(:, 2), a(:, 3)))
    end function det3

    pure function identity3() result(e)
        real(wp) :: e(3, 3)
        integer :: i
        e = 0.0_wp
        do i = 1, 3
            e(i, i) = 1.0_wp
        end do
    end function identity3

    !> The rotation of the body-frame angular velocity w_b held for time t:
    !> p(t) = p0 o exp(w_b t / 2).
    function rotated_by(p0, wb, t) result(p)
        real(wp), intent(in) :: p0(4), wb(3), t
        real(wp) :: p(4)
        p = quat_product(p0, quat_from_axis_angle(wb / norm2(wb), norm2(wb) * t))
    end function rotated_by

    subroutine test_orthogonal(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p(4), a(3, 3), worst_orth, worst_det, axis(3)
        integer :: k
        worst_orth = 0.0_wp
        worst_det = 0.0_wp
        do k = 1, ntrials
            p = random_quaternion(rng)
            a = rotation_matrix(p)
            worst_orth = max(worst_orth, maxval(abs(matmul(transpose(a), a) - identity3())))
            worst_det = max(worst_det, abs(det3(a) - 1.0_wp))
        end do
        call check_close(error, worst_orth, 0.0_wp, tol_exact, 'A^T A - I')
        call check_close(error, worst_det, 0.0_wp, tol_exact, 'det A - 1')
        ! A rotation about z by 90 degrees takes x to y.
        axis = [0.0_wp, 0.0_wp, 1.0_wp]
        a = rotation_matrix(quat_from_axis_angle(axis, 2.0_wp * atan(1.0_wp)))
        call check_close(error, maxval(abs(matmul(a, [1.0_wp, 0.0_wp, 0.0_wp]) - &
                         [0.0_wp, 1.0_wp, 0.0_wp])), 0.0_wp, tol_exact, 'A_z(90) x = y')
    end subroutine test_orthogonal

    subroutine test_composition(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p(4), r(4), worst, worst_conj
        integer :: k
        worst = 0.0_wp
        worst_conj = 0.0_wp
        do k = 1, ntrials
            p = random_quaternion(rng)
            r = random_quaternion(rng)
            worst = max(worst, maxval(abs(rotation_matrix(quat_product(p, r)) - &
                        matmul(rotation_matrix(p), rotation_matrix(r)))))
            worst_conj = max(worst_conj, maxval(abs(rotation_matrix(quat_conjugate(p)) - &
                             transpose(rotation_matrix(p)))))
        end do
        call check_close(error, worst, 0.0_wp, tol_exact, 'A(p o r) - A(p) A(r)')
        call check_close(error, worst_conj, 0.0_wp, tol_exact, 'A(conj p) - A(p)^T')
    end subroutine test_composition

    !> A = G L^T, G p = L p = 0, G G^T = L L^T = I, A = L-consistent: A L = G.
    subroutine test_gl_identities(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p(4), g(3, 4), l(3, 4), worst
        integer :: k
        worst = 0.0_wp
        do k = 1, ntrials
            p = random_quaternion(rng)
            g = quat_g(p)
            l = quat_l(p)
            worst = max(worst, maxval(abs(matmul(g, transpose(l)) - rotation_matrix(p))))
            worst = max(worst, maxval(abs(matmul(g, p))), maxval(abs(matmul(l, p))))
            worst = max(worst, maxval(abs(matmul(g, transpose(g)) - identity3())))
            worst = max(worst, maxval(abs(matmul(l, transpose(l)) - identity3())))
            worst = max(worst, maxval(abs(matmul(rotation_matrix(p), l) - g)))
            worst = max(worst, maxval(abs(2.0_wp * matmul(l, quat_rate_matrix(p)) - &
                        identity3())))
        end do
        call check_close(error, worst, 0.0_wp, tol_exact, 'G/L identities')
    end subroutine test_gl_identities

    !> p' = T(p) w_b and w_b = 2 L p', w = 2 G p' = A w_b along an exact rotation.
    subroutine test_rate_matrix(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p0(4), wb(3), pdot(4), worst_t, worst_w
        integer :: k
        worst_t = 0.0_wp
        worst_w = 0.0_wp
        do k = 1, ntrials
            p0 = random_quaternion(rng)
            wb = random_vector(rng, 3, -2.0_wp, 2.0_wp)
            pdot = (rotated_by(p0, wb, fd_step) - rotated_by(p0, wb, -fd_step)) / &
                   (2.0_wp * fd_step)
            worst_t = max(worst_t, maxval(abs(pdot - matmul(quat_rate_matrix(p0), wb))))
            worst_w = max(worst_w, maxval(abs(2.0_wp * matmul(quat_g(p0), pdot) - &
                          matmul(rotation_matrix(p0), wb))))
        end do
        call check_close(error, worst_t, 0.0_wp, tol_fd, "p' - T(p) w_b (central FD)")
        call check_close(error, worst_w, 0.0_wp, tol_fd, "2 G p' - A w_b (central FD)")
    end subroutine test_rate_matrix

    !> d(A s_b)/dp and d(A^T s)/dp against central differences in each component of p
    !> (not normalised: the identities are those of the homogeneous extension).
    subroutine test_rotated_vector_fd(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p(4), s(3), dp(4), fd(3), worst, worst_t, d(3, 4), dt(3, 4)
        integer :: k, j
        worst = 0.0_wp
        worst_t = 0.0_wp
        do k = 1, ntrials
            p = random_quaternion(rng)
            s = random_vector(rng, 3, -1.0_wp, 1.0_wp)
            d = rotated_vector_jacobian(p, s)
            dt = rotated_vector_transpose_jacobian(p, s)
            do j = 1, 4
                dp = 0.0_wp
                dp(j) = fd_step
                fd = (matmul(rotation_matrix(p + dp), s) - matmul(rotation_matrix(p - dp), s)) &
                     / (2.0_wp * fd_step)
                worst = max(worst, maxval(abs(fd - d(:, j))))
                fd = (matmul(transpose(rotation_matrix(p + dp)), s) - &
                      matmul(transpose(rotation_matrix(p - dp)), s)) / (2.0_wp * fd_step)
                worst_t = max(worst_t, maxval(abs(fd - dt(:, j))))
            end do
            ! Homogeneity: (A s)_p p = 2 A s.
            worst = max(worst, maxval(abs(matmul(d, p) - 2.0_wp * matmul(rotation_matrix(p), s))))
        end do
        call check_close(error, worst, 0.0_wp, tol_fd, 'd(A s)/dp (central FD)')
        call check_close(error, worst_t, 0.0_wp, tol_fd, 'd(A^T s)/dp (central FD)')
    end subroutine test_rotated_vector_fd

    !> d(A s_b)/dt = -A skew(s_b) w_b = (A s_b)_p T w_b along an exact rotation.
    subroutine test_rotated_vector_velocity(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        real(wp) :: p0(4), wb(3), s(3), fd(3), hand(3), chain(3), worst, worst_chain
        integer :: k
        worst = 0.0_wp
        worst_chain = 0.0_wp
        do k = 1, ntrials
            p0 = random_quaternion(rng)
            wb = random_vector(rng, 3, -2.0_wp, 2.0_wp)
            s = random_vector(rng, 3, -1.0_wp, 1.0_wp)
            fd = (matmul(rotation_matrix(rotated_by(p0, wb, fd_step)), s) - &
                  matmul(rotation_matrix(rotated_by(p0, wb, -fd_step)), s)) / (2.0_wp * fd_step)
            hand = -matmul(rotation_matrix(p0), matmul(skew(s), wb))
            chain = matmul(rotated_vector_jacobian(p0, s), matmul(quat_rate_matrix(p0), wb))
            worst = max(worst, maxval(abs(fd - hand)))
            worst_chain = max(worst_chain, maxval(abs(chain - hand)))
        end do
        call check_close(error, worst, 0.0_wp, tol_fd, 'd(A s)/dt (central FD)')
        call check_close(error, worst_chain, 0.0_wp, tol_exact, '(A s)_p T w - (-A s~ w)')
    end subroutine test_rotated_vector_velocity
end module test_rotation
