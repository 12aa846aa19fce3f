!> Rigid chains in relative coordinates: the composite-rigid-body mass
!> matrix against the kinetic energy of the bodies, recursive Newton–Euler
!> against Lagrange's equations, energy conservation, the same bodies in
!> absolute coordinates with revolute and spherical joints (up to a 12-link
!> chain and a branching tree), and MEXAX on the chain.
module test_rigid_chain
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, quat_product, cross
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_marker_t, chain_joint_revolute, chain_joint_prismatic, chain_joint_spherical
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_revolute, joint_spherical
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2, &
        formulation_ggl
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_rigid_chain

    real(wp), parameter :: g_earth(3) = [0.0_wp, 0.0_wp, -9.81_wp]
    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])

contains

    function collect_rigid_chain() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('mass_matrix_vs_kinetic_energy', test_mass_matrix), &
                 new_test('newton_euler_vs_lagrange', test_lagrange), &
                 new_test('energy_conserved', test_energy), &
                 new_test('same_motion_as_absolute_coordinates', test_absolute), &
                 new_test('mexax_runs_the_chain', test_mexax), &
                 new_test('spherical_joint_mass_and_energy', test_spherical), &
                 new_test('spherical_joint_same_motion_as_absolute', test_spherical_absolute), &
                 new_test('twelve_links_same_motion_as_absolute', test_twelve_links), &
                 new_test('branching_tree_same_motion_as_absolute', test_branching_tree)]
    end function collect_rigid_chain

    !> A tree of four bodies: 1 on the ground (revolute z), 2 on 1 (revolute
    !> about a skew axis), 3 on 2 (prismatic along x), 4 on 1 (revolute x);
    !> full inertia tensors and offset centres of mass; a marker at every
    !> centre of mass.
    function tree(status) result(chain)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(4)
        type(chain_marker_t) :: m(4)
        integer :: i
        b(1) = chain_body_t(0, chain_joint_revolute, [0.0_wp, 0.0_wp, 0.1_wp], &
                            body_rotation(0.0_wp), [0.0_wp, 0.0_wp, 1.0_wp], &
                            [0.25_wp, 0.02_wp, 0.0_wp], 1.5_wp, inertia(1))
        b(2) = chain_body_t(1, chain_joint_revolute, [0.5_wp, 0.0_wp, 0.0_wp], &
                            body_rotation(0.3_wp), [0.0_wp, 0.6_wp, 0.8_wp], &
                            [0.2_wp, 0.0_wp, -0.05_wp], 0.8_wp, inertia(2))
        b(3) = chain_body_t(2, chain_joint_prismatic, [0.4_wp, 0.0_wp, 0.0_wp], &
                            body_rotation(0.0_wp), [1.0_wp, 0.0_wp, 0.0_wp], &
                            [0.05_wp, 0.03_wp, 0.0_wp], 0.5_wp, inertia(3))
        b(4) = chain_body_t(1, chain_joint_revolute, [0.0_wp, 0.2_wp, 0.0_wp], &
                            body_rotation(-0.2_wp), [1.0_wp, 0.0_wp, 0.0_wp], &
                            [0.0_wp, 0.15_wp, 0.02_wp], 0.6_wp, inertia(4))
        do i = 1, 4
            m(i) = chain_marker_t(i, b(i)%centre)
        end do
        chain = new_rigid_chain(b, status, m, g_earth)
    end function tree

    !> A joint rotation about y by angle a.
    pure function body_rotation(a) result(r)
        real(wp), intent(in) :: a
        real(wp) :: r(3, 3)
        r = rotation_matrix(quat_from_axis_angle([0.0_wp, 1.0_wp, 0.0_wp], a))
    end function body_rotation

    !> A full, positive definite inertia tensor, different per body.
    pure function inertia(k) result(j)
        integer, intent(in) :: k
        real(wp) :: j(3, 3)
        j = reshape([0.02_wp, 0.003_wp, -0.001_wp, 0.003_wp, 0.03_wp, 0.002_wp, &
                     -0.001_wp, 0.002_wp, 0.025_wp], [3, 3]) * (1.0_wp + 0.3_wp * k)
    end function inertia

    !> M against Σ m J_cᵀ J_c + J_ωᵀ Ī J_ω from the centre-of-mass markers'
    !> Jacobians (1e-12 relative), symmetric, vᵀ M v > 0.
    subroutine test_mass_matrix(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t) :: chain
        type(status_t) :: status
        real(wp) :: q(4), m(4, 4), mk(4, 4), jx(3, 4), jr(3, 4), o(3), r(3, 3), v(4)
        integer :: trial, i
        chain = tree(status)
        call check(error, status%ok(), 'chain: ' // status%text())
        if (allocated(error)) return
        do trial = 1, 5
            q = [0.3_wp, -0.7_wp, 0.15_wp, 1.1_wp] * trial
            call chain%mass(0.0_wp, q, m, status)
            mk = 0.0_wp
            do i = 1, 4
                call chain%marker_jacobian(q, i, jx, jr)
                call chain%body_frame(q, i, o, r)
                mk = mk + chain%bodies(i)%mass * matmul(transpose(jx), jx) &
                     + matmul(transpose(jr), matmul(matmul(r, matmul(chain%bodies(i)%inertia, &
                                                                     transpose(r))), jr))
            end do
            call check(error, maxval(abs(m - mk)) <= 1.0e-12_wp * maxval(abs(m)), &
                       'CRBA M differs from the kinetic energy')
            call check(error, maxval(abs(m - transpose(m))) == 0.0_wp, 'M not symmetric')
            v = [1.0_wp, -2.0_wp, 0.5_wp, 3.0_wp] / trial
            call check(error, dot_product(v, matmul(m, v)) > 0.0_wp, 'M not positive')
        end do
    end subroutine test_mass_matrix

    !> b(q, v) = −f from RNEA against Lagrange: Σ_k ∂M/∂q_k v_k v −
    !> ½ [vᵀ ∂M/∂q_i v]_i + ∂V/∂q_i by central differences (1e-7 relative);
    !> and RNEA(q, v, a) = M a + b (round-off).
    subroutine test_lagrange(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t) :: chain
        type(status_t) :: status
        real(wp) :: q(4), v(4), a(4), f(4), b(4), tau(4), m(4, 4), mp(4, 4), mm(4, 4), &
            dm(4, 4, 4), qp(4), ek, vp, vm, dv(4), lag(4)
        real(wp), parameter :: h = 1.0e-6_wp
        integer :: k, i
        chain = tree(status)
        q = [0.4_wp, -0.9_wp, 0.2_wp, 0.7_wp]
        v = [1.3_wp, -0.8_wp, 0.6_wp, 2.1_wp]
        a = [0.5_wp, 1.5_wp, -2.0_wp, 0.3_wp]
        call chain%forces(0.0_wp, q, v, f, status)
        b = -f
        do k = 1, 4
            qp = q
            qp(k) = q(k) + h
            call chain%mass(0.0_wp, qp, mp, status)
            call chain%energy(qp, v, ek, vp)
            qp(k) = q(k) - h
            call chain%mass(0.0_wp, qp, mm, status)
            call chain%energy(qp, v, ek, vm)
            dm(:, :, k) = (mp - mm) / (2 * h)
            dv(k) = (vp - vm) / (2 * h)
        end do
        do i = 1, 4
            lag(i) = dv(i) - 0.5_wp * dot_product(v, matmul(dm(:, :, i), v))
            do k = 1, 4
                lag(i) = lag(i) + dot_product(dm(i, :, k), v) * v(k)
            end do
        end do
        print '(4x,a,es9.2)', 'RNEA vs Lagrange (differences): ', &
            maxval(abs(b - lag)) / maxval(abs(lag))
        call check(error, maxval(abs(b - lag)) <= 1.0e-7_wp * maxval(abs(lag)), &
                   'RNEA bias differs from Lagrange''s equations')
        call chain%inverse_dynamics(q, v, a, tau)
        call chain%mass(0.0_wp, q, m, status)
        call check(error, maxval(abs(tau - matmul(m, a) - b)) <= 1.0e-12_wp * maxval(abs(tau)), &
                   'RNEA(q, v, a) differs from M a + b')
    end subroutine test_lagrange

    !> RADAU5 through the index-2 formulation (acceleration layout, nc = 0):
    !> total energy drift at rtol 1e-6 and 1e-8 proportional to the tolerance.
    subroutine test_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t), target :: chain
        type(formulation_t) :: dae
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q0(4), v0(4), t, e0, ek, ep, drift(2), tol(2)
        real(wp), allocatable :: y(:)
        integer :: k
        chain = tree(status)
        q0 = [0.4_wp, -0.9_wp, 0.2_wp, 0.7_wp]
        v0 = [1.3_wp, -0.8_wp, 0.6_wp, 2.1_wp]
        call chain%energy(q0, v0, ek, ep)
        e0 = ek + ep
        tol = [1.0e-6_wp, 1.0e-8_wp]
        do k = 1, 2
            dae = new_formulation(chain, formulation_index2, q0, status=status)
            allocate (y(dae%n), source=0.0_wp)
            y(1:4) = q0
            y(5:8) = v0
            options%rtol = tol(k)
            options%atol = tol(k)
            t = 0.0_wp
            call solver%integrate(dae, t, y, 2.0_wp, options, stats, status)
            call check(error, status%ok(), 'energy: ' // status%text())
            if (allocated(error)) return
            call chain%energy(y(1:4), y(5:8), ek, ep)
            drift(k) = abs(ek + ep - e0) / abs(ek)
            deallocate (y)
        end do
        print '(4x,a,2es9.2)', 'relative energy drift at rtol 1e-6, 1e-8: ', drift
        call check(error, drift(1) <= 100 * tol(1) .and. drift(2) <= 100 * tol(2), &
                   'energy drift beyond 100 tol')
        call check(error, drift(2) < drift(1), 'energy drift does not shrink with tol')
    end subroutine test_energy

    !> Orthonormal axes with z = a.
    pure function axes_with_z(a) result(u)
        real(wp), intent(in) :: a(3)
        real(wp) :: u(3, 3), h(3)
        h = [1.0_wp, 0.0_wp, 0.0_wp]
        if (abs(a(1)) > 0.9_wp) h = [0.0_wp, 1.0_wp, 0.0_wp]
        u(:, 1) = h - dot_product(h, a) * a
        u(:, 1) = u(:, 1) / norm2(u(:, 1))
        u(:, 2) = cross(a, u(:, 1))
        u(:, 3) = a
    end function axes_with_z

    !> A double pendulum with non-parallel revolute axes as a chain and as
    !> two free bodies with revolute joints.
    subroutine test_absolute(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t), target :: chain
        type(status_t) :: status
        type(chain_body_t) :: b(2)
        type(marker_t) :: m(4)
        real(wp) :: q0(2), v0(2), p(4, 2)
        b(1) = chain_body_t(0, chain_joint_revolute, [0.0_wp, 0.0_wp, 0.0_wp], &
                            body_rotation(0.0_wp), [0.0_wp, 1.0_wp, 0.0_wp], &
                            [0.3_wp, 0.0_wp, -0.1_wp], 1.0_wp, inertia(1))
        b(2) = chain_body_t(1, chain_joint_revolute, [0.6_wp, 0.0_wp, -0.2_wp], &
                            body_rotation(0.0_wp), [0.6_wp, 0.0_wp, 0.8_wp], &
                            [0.0_wp, 0.25_wp, -0.1_wp], 0.7_wp, inertia(2))
        chain = new_rigid_chain(b, status, gravity=g_earth)
        q0 = [0.5_wp, -0.4_wp]
        v0 = [0.8_wp, 1.5_wp]
        p(:, 1) = quat_from_axis_angle(b(1)%axis, q0(1))
        p(:, 2) = quat_product(p(:, 1), quat_from_axis_angle(b(2)%axis, q0(2)))
        m(1) = marker_t(0, b(1)%joint_position, axes_with_z(b(1)%axis))
        m(2) = marker_t(1, -b(1)%centre, axes_with_z(b(1)%axis))
        m(3) = marker_t(1, b(2)%joint_position - b(1)%centre, axes_with_z(b(2)%axis))
        m(4) = marker_t(2, -b(2)%centre, axes_with_z(b(2)%axis))
        call compare_absolute(error, chain, q0, v0, p, m, [mbs_joint_t(joint_revolute, 1, 2), &
                              mbs_joint_t(joint_revolute, 3, 4)], 'revolute chain')
    end subroutine test_absolute

    !> Two bodies of `chain` (frames' quaternions p at q0) also as free bodies
    !> joined by `joints` between `markers` (GGL); both integrated to t = 1 at
    !> rtol 1e-8; the centres of mass and rotations must agree to 1e-6.
    subroutine compare_absolute(error, chain, q0, v0, p, markers, joints, label)
        type(error_t), allocatable, intent(inout) :: error
        type(rigid_chain_t), target, intent(inout) :: chain
        real(wp), intent(in) :: q0(:), v0(:), p(:, :)
        type(marker_t), intent(in) :: markers(:)
        type(mbs_joint_t), intent(in) :: joints(:)
        character(len=*), intent(in) :: label
        real(wp) :: worst
        call absolute_difference(error, chain, q0, v0, p, markers, joints, label, 1.0e-8_wp, &
                                 1.0_wp, worst)
        if (allocated(error)) return
        print '(4x,a,a,es9.2)', label, ' vs absolute coordinates at t = 1: ', worst
        call check(error, worst <= 1.0e-6_wp, label // ': chain and absolute coordinates differ')
    end subroutine compare_absolute

    !> The bodies of `chain` (frames' quaternions p at q0) also as free bodies
    !> joined by `joints` between `markers` (GGL), both integrated by RADAU5
    !> to t_end at rtol = atol = tol; worst: the largest difference of a
    !> centre of mass or a rotation matrix entry at t_end.
    subroutine absolute_difference(error, chain, q0, v0, p, markers, joints, label, tol, t_end, &
                                   worst)
        type(error_t), allocatable, intent(inout) :: error
        type(rigid_chain_t), target, intent(inout) :: chain
        real(wp), intent(in) :: q0(:), v0(:), p(:, :), tol, t_end
        type(marker_t), intent(in) :: markers(:)
        type(mbs_joint_t), intent(in) :: joints(:)
        character(len=*), intent(in) :: label
        real(wp), intent(out) :: worst
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dae_chain, dae_abs
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(rigid_body_t) :: bodies(size(p, 2))
        real(wp) :: qa(7 * size(p, 2)), o(3), r(3, 3), vc(3), w(3), t
        real(wp), allocatable :: y(:), ya(:), yp(:), qn(:)
        integer :: i, nq, nv, nb
        nq = chain%nq
        nv = chain%nv
        nb = size(p, 2)
        worst = huge(1.0_wp)
        do i = 1, nb
            call chain%body_frame(q0, i, o, r)
            call check(error, maxval(abs(rotation_matrix(p(:, i)) - r)) < 1.0e-14_wp, &
                       label // ': quaternion of the chain frame')
            qa(7 * i - 6:7 * i - 4) = o + matmul(r, chain%bodies(i)%centre)
            qa(7 * i - 3:7 * i) = p(:, i)
            bodies(i) = rigid_body_t(chain%bodies(i)%mass, chain%bodies(i)%inertia)
        end do
        if (allocated(error)) return
        sys = new_mbs_system(bodies, markers, joints, gravity=g_earth, status=status)
        call check(error, status%ok(), label // ': absolute system: ' // status%text())
        if (allocated(error)) return
        dae_abs = new_formulation(sys, formulation_ggl, qa, status=status)
        allocate (ya(dae_abs%n), yp(dae_abs%n), source=0.0_wp)
        ya(1:7 * nb) = qa
        do i = 1, nb
            call chain%body_velocity(q0, v0, i, vc, w)
            call chain%body_frame(q0, i, o, r)
            ya(7 * nb + 6 * i - 5:7 * nb + 6 * i - 3) = vc
            ya(7 * nb + 6 * i - 2:7 * nb + 6 * i) = matmul(transpose(r), w)
        end do
        call dae_abs%consistent_initial(0.0_wp, ya, yp, status)
        options%rtol = tol
        options%atol = tol
        t = 0.0_wp
        call solver%integrate(dae_abs, t, ya, t_end, options, stats, status)
        call check(error, status%ok(), label // ': absolute run: ' // status%text())
        dae_chain = new_formulation(chain, formulation_index2, q0, status=status)
        allocate (y(dae_chain%n), source=0.0_wp)
        y(1:nq) = q0
        y(nq + 1:nq + nv) = v0
        t = 0.0_wp
        call solver%integrate(dae_chain, t, y, t_end, options, stats, status)
        call check(error, status%ok(), label // ': chain run: ' // status%text())
        if (allocated(error)) return
        qn = y(1:nq)
        call chain%normalize(qn)
        worst = 0.0_wp
        do i = 1, nb
            call chain%body_frame(qn, i, o, r)
            worst = max(worst, norm2(o + matmul(r, chain%bodies(i)%centre) - &
                                     ya(7 * i - 6:7 * i - 4)), &
                        maxval(abs(rotation_matrix(ya(7 * i - 3:7 * i) / &
                                                   norm2(ya(7 * i - 3:7 * i))) - r)))
        end do
    end subroutine absolute_difference

    !> MEXAX integrates the chain's mechanical form (nc = 0) to the RADAU5
    !> state within the tolerance.
    subroutine test_mexax(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t), target :: chain
        type(formulation_t) :: dae
        type(radau5_t) :: radau5
        type(mexax_t) :: mexax
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q(4), v(4), t
        real(wp), allocatable :: y(:)
        chain = tree(status)
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        q = [0.4_wp, -0.9_wp, 0.2_wp, 0.7_wp]
        v = [1.3_wp, -0.8_wp, 0.6_wp, 2.1_wp]
        t = 0.0_wp
        call mexax%integrate_mechanical(chain, t, q, v, 1.0_wp, options, stats, status)
        call check(error, status%ok(), 'mexax: ' // status%text())
        dae = new_formulation(chain, formulation_index2, q, status=status)
        allocate (y(dae%n), source=0.0_wp)
        y(1:4) = [0.4_wp, -0.9_wp, 0.2_wp, 0.7_wp]
        y(5:8) = [1.3_wp, -0.8_wp, 0.6_wp, 2.1_wp]
        t = 0.0_wp
        call radau5%integrate(dae, t, y, 1.0_wp, options, stats, status)
        call check(error, status%ok(), 'radau5: ' // status%text())
        print '(4x,a,es9.2)', 'MEXAX vs RADAU5 on the chain at t = 1: ', &
            max(maxval(abs(q - y(1:4))), maxval(abs(v - y(5:8))))
        call check(error, max(maxval(abs(q - y(1:4))), maxval(abs(v - y(5:8)))) <= 1.0e-5_wp, &
                   'MEXAX and RADAU5 disagree on the chain')
    end subroutine test_mexax
    !> A spherical root (quaternion coordinates, body-fixed rates) under a
    !> revolute link: two bodies, nq = 5, nv = 4.
    function spherical_pair(status) result(chain)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(2)
        type(chain_marker_t) :: m(2)
        b(1) = chain_body_t(0, chain_joint_spherical, [0.0_wp, 0.0_wp, 0.0_wp], &
                            body_rotation(0.0_wp), [0.0_wp, 0.0_wp, 1.0_wp], &
                            [0.3_wp, 0.05_wp, -0.1_wp], 1.2_wp, inertia(1))
        b(2) = chain_body_t(1, chain_joint_revolute, [0.6_wp, 0.0_wp, -0.2_wp], &
                            body_rotation(0.0_wp), [0.6_wp, 0.0_wp, 0.8_wp], &
                            [0.0_wp, 0.25_wp, -0.1_wp], 0.7_wp, inertia(2))
        m(1) = chain_marker_t(1, b(1)%centre)
        m(2) = chain_marker_t(2, b(2)%centre)
        chain = new_rigid_chain(b, status, m, g_earth)
    end function spherical_pair

    !> With a spherical joint: M against the kinetic energy (1e-12), and
    !> RADAU5 keeps the energy (rtol 1e-8, 1e-6 relative over 2 s).
    subroutine test_spherical(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t), target :: chain
        type(formulation_t) :: dae
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q0(5), v0(4), m(4, 4), mk(4, 4), jx(3, 4), jr(3, 4), o(3), r(3, 3), &
            t, ek0, ep0, ek, ep
        real(wp), allocatable :: y(:)
        integer :: i
        chain = spherical_pair(status)
        call check(error, status%ok() .and. chain%nq == 5 .and. chain%nv == 4, &
                   'spherical chain: ' // status%text())
        if (allocated(error)) return
        q0(1:4) = quat_from_axis_angle([0.48_wp, 0.6_wp, 0.64_wp], 0.7_wp)
        q0(5) = -0.4_wp
        v0 = [0.5_wp, -1.0_wp, 0.8_wp, 1.5_wp]
        call chain%mass(0.0_wp, q0, m, status)
        mk = 0.0_wp
        do i = 1, 2
            call chain%marker_jacobian(q0, i, jx, jr)
            call chain%body_frame(q0, i, o, r)
            mk = mk + chain%bodies(i)%mass * matmul(transpose(jx), jx) &
                 + matmul(transpose(jr), matmul(matmul(r, matmul(chain%bodies(i)%inertia, &
                                                                 transpose(r))), jr))
        end do
        call check(error, maxval(abs(m - mk)) <= 1.0e-12_wp * maxval(abs(m)), &
                   'spherical: CRBA M differs from the kinetic energy')
        call chain%energy(q0, v0, ek0, ep0)
        dae = new_formulation(chain, formulation_index2, q0, status=status)
        allocate (y(dae%n), source=0.0_wp)
        y(1:5) = q0
        y(6:9) = v0
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        t = 0.0_wp
        call solver%integrate(dae, t, y, 2.0_wp, options, stats, status)
        call check(error, status%ok(), 'spherical run: ' // status%text())
        if (allocated(error)) return
        call chain%energy(y(1:5), y(6:9), ek, ep)
        print '(4x,a,es9.2,a,es9.2)', 'spherical chain: energy drift ', &
            abs(ek + ep - ek0 - ep0) / ek0, ', |p| - 1 = ', norm2(y(1:4)) - 1.0_wp
        call check(error, abs(ek + ep - ek0 - ep0) <= 1.0e-6_wp * ek0, 'spherical: energy drift')
    end subroutine test_spherical

    !> The spherical–revolute pair as a chain and as two free bodies with a
    !> spherical and a revolute joint.
    subroutine test_spherical_absolute(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_chain_t), target :: chain
        type(status_t) :: status
        type(marker_t) :: m(4)
        real(wp) :: q0(5), v0(4), p(4, 2)
        chain = spherical_pair(status)
        q0(1:4) = quat_from_axis_angle([0.48_wp, 0.6_wp, 0.64_wp], 0.7_wp)
        q0(5) = -0.4_wp
        v0 = [0.5_wp, -1.0_wp, 0.8_wp, 1.5_wp]
        p(:, 1) = q0(1:4)
        p(:, 2) = quat_product(p(:, 1), quat_from_axis_angle(chain%bodies(2)%axis, q0(5)))
        m(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp])
        m(2) = marker_t(1, -chain%bodies(1)%centre)
        m(3) = marker_t(1, chain%bodies(2)%joint_position - chain%bodies(1)%centre, &
                        axes_with_z(chain%bodies(2)%axis))
        m(4) = marker_t(2, -chain%bodies(2)%centre, axes_with_z(chain%bodies(2)%axis))
        call compare_absolute(error, chain, q0, v0, p, m, [mbs_joint_t(joint_spherical, 1, 2), &
                              mbs_joint_t(joint_revolute, 3, 4)], 'spherical chain')
    end subroutine test_spherical_absolute

    !> A chain of 12 revolute links, each on the one before, axes turning
    !> from link to link, under gravity.
    subroutine test_twelve_links(error)
        type(error_t), allocatable, intent(out) :: error
        integer :: i
        call tree_against_absolute(error, [(i - 1, i = 1, 12)], &
                                   [(chain_joint_revolute, i = 1, 12)], '12-link chain')
    end subroutine test_twelve_links

    !> A revolute root carrying two 3-link branches, one starting with a
    !> spherical joint.
    subroutine test_branching_tree(error)
        type(error_t), allocatable, intent(out) :: error
        call tree_against_absolute(error, [0, 1, 2, 3, 1, 5, 6], [chain_joint_revolute, &
            chain_joint_spherical, chain_joint_revolute, chain_joint_revolute, &
            chain_joint_revolute, chain_joint_revolute, chain_joint_revolute], 'branching tree')
    end subroutine test_branching_tree

    !> The tree of `parent`s and joint `kinds` (revolute or spherical; joint
    !> frames parallel to the parent's, axes varying) as a chain and as free
    !> bodies with revolute and spherical joints, to t = 1 at tolerances
    !> 1e-6 and 1e-8: the bodies' difference at most 100 tol, and at least
    !> ten times smaller at the hundred times tighter tolerance.
    subroutine tree_against_absolute(error, parent, kinds, label)
        type(error_t), allocatable, intent(out) :: error
        integer, intent(in) :: parent(:), kinds(:)
        character(len=*), intent(in) :: label
        real(wp), parameter :: tols(2) = [1.0e-6_wp, 1.0e-8_wp]
        type(rigid_chain_t), target :: chain
        type(status_t) :: status
        type(chain_body_t) :: b(size(parent))
        type(marker_t) :: m(2 * size(parent))
        type(mbs_joint_t) :: joints(size(parent))
        real(wp) :: p(4, size(parent)), pj(4), axis(3), q0(4 * size(parent)), &
            v0(3 * size(parent)), worst(2), centre(3)
        integer :: i, nq, nv, k
        nq = 0
        nv = 0
        do i = 1, size(parent)
            axis = [sin(1.7_wp * i), cos(1.7_wp * i), 0.6_wp]
            axis = axis / norm2(axis)
            b(i) = chain_body_t(parent(i), kinds(i), &
                merge([0.0_wp, 0.0_wp, 0.0_wp], [0.3_wp, 0.04_wp * (-1)**i, 0.0_wp], &
                      parent(i) == 0), identity3, axis, [0.15_wp, 0.02_wp, -0.01_wp * i], &
                0.4_wp + 0.05_wp * i, inertia(i))
            if (kinds(i) == chain_joint_spherical) then
                pj = quat_from_axis_angle(axis, 0.3_wp)
                q0(nq + 1:nq + 4) = pj
                v0(nv + 1:nv + 3) = [0.4_wp, -0.3_wp, 0.2_wp]
                nq = nq + 4
                nv = nv + 3
            else
                q0(nq + 1) = 0.25_wp * sin(0.9_wp * i)
                pj = quat_from_axis_angle(axis, q0(nq + 1))
                v0(nv + 1) = 0.5_wp * cos(1.3_wp * i)
                nq = nq + 1
                nv = nv + 1
            end if
            if (parent(i) == 0) then
                p(:, i) = pj
                m(2 * i - 1) = marker_t(0, b(i)%joint_position, axes_with_z(axis))
            else
                p(:, i) = quat_product(p(:, parent(i)), pj)
                centre = b(parent(i))%centre
                m(2 * i - 1) = marker_t(parent(i), b(i)%joint_position - centre, &
                                        axes_with_z(axis))
            end if
            m(2 * i) = marker_t(i, -b(i)%centre, axes_with_z(axis))
            joints(i) = mbs_joint_t(merge(joint_spherical, joint_revolute, &
                                          kinds(i) == chain_joint_spherical), 2 * i - 1, 2 * i)
        end do
        chain = new_rigid_chain(b, status, gravity=g_earth)
        call check(error, status%ok(), label // ': ' // status%text())
        if (allocated(error)) return
        do k = 1, 2
            call absolute_difference(error, chain, q0(1:nq), v0(1:nv), p, m, joints, label, &
                                     tols(k), 1.0_wp, worst(k))
            if (allocated(error)) return
        end do
        print '(4x,a,a,2es9.2)', label, ' vs absolute coordinates at t = 1, tol 1e-6, 1e-8: ', &
            worst
        call check(error, all(worst <= 100 * tols) .and. worst(2) <= 0.1_wp * worst(1), &
                   label // ': chain and absolute coordinates differ')
    end subroutine tree_against_absolute
end module test_rigid_chain
