!> A rigid chain's analytic derivatives (the RNEA differentiated along each
!> coordinate): ∂(M w)/∂q, ∂f/∂q and ∂f/∂v on a branching tree with
!> revolute, prismatic and spherical joints (one quaternion off the unit
!> sphere), against central differences of M(q) w and f(q, v), and against
!> dual-number AD of Kane's equations Σ J_vᵀ m (a_c − g) + J_ωᵀ (Ī α + ω × Ī ω)
!> built from the dual marker states (independent of the RNEA).
module test_chain_derivatives
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle
    use flexmbs_mbs_dual, only: dual_t, dual_size, assignment(=), operator(+), operator(-), &
        operator(*), operator(/), matmul
    use flexmbs_mbs_rotation_dual, only: cross_d => cross
    use flexmbs_mbs_constraint_primitives_dual, only: marker_state_t, chain_marker_state, &
        chain_marker_jacobian
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_joint_revolute, chain_joint_prismatic, chain_joint_spherical
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_chain_derivatives, branching_tree

    real(wp), parameter :: g_earth(3) = [0.0_wp, 0.0_wp, -9.81_wp]
    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])
    ! The tree: nq = 4 + 1 + 1 + 4 + 1 + 1, nv = 3 + 1 + 1 + 3 + 1 + 1.
    integer, parameter :: nq = 12, nv = 10
    ! Central-difference step, about eps^(1/3): truncation and rounding both ~1e-11.
    real(wp), parameter :: central_step = 6.0e-6_wp

contains

    function collect_chain_derivatives() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('derivatives_vs_differences', test_differences), &
                 new_test('derivatives_vs_ad', test_ad)]
    end function collect_chain_derivatives

    !> Six bodies: 1 spherical on the ground; 2 revolute (skew axis) and 4
    !> spherical on 1; 3 prismatic and 6 revolute on 2; 5 revolute on 4.
    function branching_tree(status) result(chain)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(6)
        integer, parameter :: parent(6) = [0, 1, 2, 1, 4, 2], kinds(6) = [chain_joint_spherical, &
            chain_joint_revolute, chain_joint_prismatic, chain_joint_spherical, &
            chain_joint_revolute, chain_joint_revolute]
        real(wp) :: axis(3)
        integer :: i
        do i = 1, 6
            axis = [0.2_wp * i, 1.0_wp - 0.1_wp * i, 0.5_wp]
            b(i) = chain_body_t(parent(i), kinds(i), [0.3_wp + 0.05_wp * i, 0.1_wp, -0.02_wp * i], &
                rotation_matrix(quat_from_axis_angle([0.0_wp, 1.0_wp, 0.0_wp], 0.1_wp * i)), &
                axis / norm2(axis), [0.15_wp, 0.03_wp * i, -0.04_wp], 0.5_wp + 0.2_wp * i, &
                reshape([0.02_wp, 0.003_wp, -0.001_wp, 0.003_wp, 0.03_wp, 0.002_wp, &
                         -0.001_wp, 0.002_wp, 0.025_wp], [3, 3]) * (1.0_wp + 0.3_wp * i))
        end do
        chain = new_rigid_chain(b, status, gravity=g_earth)
    end function branching_tree

    !> A state of the tree: body 4's quaternion 1 % off the unit sphere.
    subroutine tree_state(q, v, w)
        real(wp), intent(out) :: q(nq), v(nv), w(nv)
        integer :: k
        q(1:4) = quat_from_axis_angle([0.48_wp, 0.6_wp, 0.64_wp], 0.7_wp)
        q(5:6) = [0.4_wp, 0.12_wp]
        q(7:10) = 1.01_wp * quat_from_axis_angle([0.0_wp, 0.6_wp, 0.8_wp], -0.5_wp)
        q(11:12) = [-0.8_wp, 1.1_wp]
        v = [(0.7_wp * sin(1.3_wp * k) + 0.2_wp, k = 1, nv)]
        w = [(cos(0.9_wp * k), k = 1, nv)]
    end subroutine tree_state

    !> Analytic against central differences of f and M w: 1e-7 relative.
    subroutine test_differences(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t) :: chain
        type(status_t) :: status
        real(wp) :: q(nq), v(nv), w(nv), fq(nv, nq), fv(nv, nv), mq(nv, nq), &
            dfq(nv, nq), dfv(nv, nv), dmq(nv, nq), fp(nv), fm(nv), mp(nv, nv), mm(nv, nv), &
            qp(nq), vp(nv), h, err(3)
        integer :: j
        chain = branching_tree(status)
        call check(error, status%ok() .and. chain%nq == nq .and. chain%nv == nv, status%text())
        if (allocated(error)) return
        call tree_state(q, v, w)
        call chain%force_derivatives(0.0_wp, q, v, fq, fv, status)
        call chain%mass_derivative(0.0_wp, q, w, mq, status)
        do j = 1, nq
            qp = q
            h = central_step * max(1.0_wp, abs(q(j)))
            qp(j) = q(j) + h
            call chain%forces(0.0_wp, qp, v, fp, status)
            call chain%mass(0.0_wp, qp, mp, status)
            qp(j) = q(j) - h
            call chain%forces(0.0_wp, qp, v, fm, status)
            call chain%mass(0.0_wp, qp, mm, status)
            dfq(:, j) = (fp - fm) / (2 * h)
            dmq(:, j) = matmul(mp - mm, w) / (2 * h)
        end do
        do j = 1, nv
            vp = v
            h = central_step * max(1.0_wp, abs(v(j)))
            vp(j) = v(j) + h
            call chain%forces(0.0_wp, q, vp, fp, status)
            vp(j) = v(j) - h
            call chain%forces(0.0_wp, q, vp, fm, status)
            dfv(:, j) = (fp - fm) / (2 * h)
        end do
        err = [maxval(abs(fq - dfq)) / maxval(abs(fq)), maxval(abs(fv - dfv)) / maxval(abs(fv)), &
               maxval(abs(mq - dmq)) / maxval(abs(mq))]
        print '(4x,a,3es9.2)', 'tree: df/dq, df/dv, d(Mw)/dq vs central differences: ', err
        call check(error, all(err <= 1.0e-7_wp), 'analytic chain derivatives differ from ' // &
                   'central differences')
    end subroutine test_differences

    !> Analytic against AD of Kane's equations (1e-12 relative), in chunks of
    !> dual_size directions; Kane's τ itself against the RNEA's (1e-12).
    subroutine test_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t) :: chain
        type(status_t) :: status
        real(wp) :: q(nq), v(nv), w(nv), fq(nv, nq), fv(nv, nv), mq(nv, nq), &
            afq(nv, nq), afv(nv, nv), amq(nv, nq), tau(nv), zero(nv), err(4)
        type(dual_t) :: qd(nq), vd(nv), wd(nv), td(nv), zd(nv)
        integer :: j0, j, n
        chain = branching_tree(status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        call tree_state(q, v, w)
        zero = 0.0_wp
        zd = zero
        call chain%force_derivatives(0.0_wp, q, v, fq, fv, status)
        call chain%mass_derivative(0.0_wp, q, w, mq, status)
        call chain%inverse_dynamics(q, v, w, tau)
        ! position directions in chunks
        do j0 = 0, nq - 1, dual_size
            n = min(dual_size, nq - j0)
            qd = q
            do j = 1, n
                qd(j0 + j)%der(j) = 1.0_wp
            end do
            vd = v
            call kane(chain, qd, vd, zd, .true., td)
            do j = 1, n
                afq(:, j0 + j) = -td%der(j)
            end do
            wd = w
            call kane(chain, qd, zd, wd, .false., td)
            do j = 1, n
                amq(:, j0 + j) = td%der(j)
            end do
        end do
        qd = q
        vd = v
        do j = 1, nv
            vd(j)%der(j) = 1.0_wp
        end do
        call kane(chain, qd, vd, zd, .true., td)
        do j = 1, nv
            afv(:, j) = -td%der(j)
        end do
        vd = v
        wd = w
        call kane(chain, qd, vd, wd, .true., td)
        err = [maxval(abs(fq - afq)) / maxval(abs(fq)), maxval(abs(fv - afv)) / maxval(abs(fv)), &
               maxval(abs(mq - amq)) / maxval(abs(mq)), maxval(abs(tau - td%val)) / maxval(abs(tau))]
        print '(4x,a,4es9.2)', 'tree: df/dq, df/dv, d(Mw)/dq, tau vs AD of Kane''s equations: ', err
        call check(error, all(err <= 1.0e-12_wp), 'analytic chain derivatives differ from AD')
    end subroutine test_ad

    !> τ(q, v, v') of Kane's equations on dual numbers: per body, the centre's
    !> acceleration and Jacobian from the dual marker state at the centre of
    !> mass; ω, α and J_ω from the axes A = R (identity marker axes):
    !> [ω]× = Ȧ A⁻¹, [α]× = (Ä − [ω]× Ȧ) A⁻¹ (A need not be orthonormal).
    subroutine kane(chain, q, v, vdot, gravity, tau)
        type(rigid_chain_t), intent(in) :: chain
        type(dual_t), intent(in) :: q(nq), v(nv), vdot(nv)
        logical, intent(in) :: gravity
        type(dual_t), intent(out) :: tau(nv)
        type(marker_state_t) :: m
        type(dual_t) :: ainv(3, 3), om(3), al(3), jx(3, nv), ja(3, nv, 3), jw(3, nv), &
            ibar(3, 3), ac(3), n(3), blk(3, 3)
        real(wp) :: g(3), jpos(3, size(chain%bodies)), jrot(3, 3, size(chain%bodies)), &
            axis(3, size(chain%bodies))
        integer :: i, c, nb, parent(size(chain%bodies)), kinds(size(chain%bodies))
        nb = size(chain%bodies)
        call chain_geometry(chain, jpos, jrot, axis)
        parent = chain%bodies%parent
        kinds = chain%bodies%joint
        g = 0.0_wp
        if (gravity) g = chain%gravity
        tau = 0.0_wp
        do i = 1, nb
            associate (b => chain%bodies(i))
                call chain_marker_state(parent, kinds, chain%iq(1:nb), &
                    chain%iv(1:nb), jpos, jrot, axis, i, b%centre, identity3, &
                    q, v, m)
                call chain_marker_jacobian(parent, kinds, chain%iq(1:nb), &
                    chain%iv(1:nb), jpos, jrot, axis, i, b%centre, identity3, &
                    q, jx, ja)
                ainv = inverse3(m%a)
                om = axial(matmul(m%ad, ainv))
                al = axial(matmul(m%ga - matmul(skew_d(om), m%ad), ainv))
                do c = 1, nv
                    blk = ja(:, c, :)
                    jw(:, c) = axial(matmul(blk, ainv))
                end do
                ibar = matmul(m%a, matmul(b%inertia, transpose_d(m%a)))
                ac = m%gx + matmul(jx, vdot) - g
                al = al + matmul(jw, vdot)
                n = matmul(ibar, al) + cross_d(om, matmul(ibar, om))
                do c = 1, nv
                    tau(c) = tau(c) + b%mass * dot3(jx(:, c), ac) + dot3(jw(:, c), n)
                end do
            end associate
        end do
    end subroutine kane

    !> The joints' positions, rotations and axes as arrays (the marker formulas' form).
    pure subroutine chain_geometry(chain, jpos, jrot, axis)
        type(rigid_chain_t), intent(in) :: chain
        real(wp), intent(out) :: jpos(:, :), jrot(:, :, :), axis(:, :)
        integer :: i
        do i = 1, size(chain%bodies)
            jpos(:, i) = chain%bodies(i)%joint_position
            jrot(:, :, i) = chain%bodies(i)%joint_rotation
            axis(:, i) = chain%bodies(i)%axis
        end do
    end subroutine chain_geometry

    !> The inverse of a 3 x 3 dual matrix: rows' cross products over det.
    pure function inverse3(a) result(b)
        type(dual_t), intent(in) :: a(3, 3)
        type(dual_t) :: b(3, 3), at(3, 3), det
        at = transpose_d(a)
        b(:, 1) = cross_d(at(:, 2), at(:, 3))
        b(:, 2) = cross_d(at(:, 3), at(:, 1))
        b(:, 3) = cross_d(at(:, 1), at(:, 2))
        det = dot3(at(:, 1), b(:, 1))
        b = b / det
    end function inverse3

    !> The vector of a skew matrix (its antisymmetric part).
    pure function axial(s) result(x)
        type(dual_t), intent(in) :: s(3, 3)
        type(dual_t) :: x(3)
        x(1) = 0.5_wp * (s(3, 2) - s(2, 3))
        x(2) = 0.5_wp * (s(1, 3) - s(3, 1))
        x(3) = 0.5_wp * (s(2, 1) - s(1, 2))
    end function axial

    pure function skew_d(x) result(s)
        type(dual_t), intent(in) :: x(3)
        type(dual_t) :: s(3, 3)
        s = 0.0_wp
        s(1, 2) = -1.0_wp * x(3)
        s(1, 3) = x(2)
        s(2, 1) = x(3)
        s(2, 3) = -1.0_wp * x(1)
        s(3, 1) = -1.0_wp * x(2)
        s(3, 2) = x(1)
    end function skew_d

    pure function transpose_d(a) result(b)
        type(dual_t), intent(in) :: a(3, 3)
        type(dual_t) :: b(3, 3)
        integer :: i, j
        do j = 1, 3
            do i = 1, 3
                b(i, j) = a(j, i)
            end do
        end do
    end function transpose_d

    pure function dot3(x, y) result(s)
        type(dual_t), intent(in) :: x(3), y(3)
        type(dual_t) :: s
        s = x(1) * y(1) + x(2) * y(2) + x(3) * y(3)
    end function dot3
end module test_chain_derivatives
