!> The assembled multibody system (src/mbs/system.f90): analytic against AD
!> constraint derivatives of the whole system, formulation Jacobians against
!> differences, a spherical (heavy) pendulum's invariants, a rigid planar
!> pendulum against the point-mass pendulum of the equivalent length, a double
!> pendulum's energy, the reaction of a body hanging at rest, and the
!> reactions on the ground against those on the body.
module test_mbs_system
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_problems_pendulum, only: pendulum_mechanical_t, new_pendulum_mechanical, &
        pendulum_mechanical_initial, pendulum_angle_exact
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_spherical, joint_revolute, joint_cylindrical, &
        joint_prismatic, joint_universal, joint_fixed, joint_primitive, joint_planar
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t
    use flexmbs_mbs_primitive_kinds, only: primitive_distance, primitive_dot1
    use flexmbs_mbs_formulation, only: block_lambda, block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_ggl
    use test_formulation, only: difference_jacobian
    use mbs_random, only: random_state_t, uniform, random_vector, random_quaternion
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mbs_system, test_body, random_state, integrate, rel_err, random_marker, unit

    !> The issue's bound: AD against hand-coded, relative to the largest entry (floor 1).
    real(wp), parameter :: tol_ad = 1.0e-12_wp
    real(wp), parameter :: g_earth = 9.81_wp

contains

    function collect_mbs_system() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('ad_vs_analytic', test_ad_vs_analytic), &
                 new_test('formulation_jacobians', test_formulation_jacobians), &
                 new_test('bad_input', test_bad_input), &
                 new_test('hanging_reaction', test_hanging_reaction), &
                 new_test('ground_reactions_balance', test_ground_reactions), &
                 new_test('spherical_pendulum_invariants', test_spherical_pendulum), &
                 new_test('planar_pendulum_matches_point_mass', test_planar_pendulum), &
                 new_test('double_pendulum_energy', test_double_pendulum), &
                 new_test('reactions_balance_newton_euler', test_reactions_balance)]
    end function collect_mbs_system

    ! ---------------------------------------------------------------- helpers

    pure real(wp) function rel_err(a, b)
        real(wp), intent(in) :: a(:, :), b(:, :)
        rel_err = 0.0_wp
        if (size(a) == 0) return
        rel_err = maxval(abs(a - b)) / max(1.0_wp, maxval(abs(b)))
    end function rel_err

    !> A body with a full, well-conditioned inertia.
    function test_body(mass, scale) result(b)
        real(wp), intent(in) :: mass, scale
        type(rigid_body_t) :: b
        b%mass = mass
        b%inertia = scale * reshape([2.0_wp, 0.1_wp, 0.0_wp, 0.1_wp, 3.0_wp, 0.2_wp, &
                                     0.0_wp, 0.2_wp, 4.0_wp], [3, 3])
    end function test_body

    !> A marker on `body` at a random position with random axes.
    function random_marker(rng, body) result(m)
        type(random_state_t), intent(inout) :: rng
        integer, intent(in) :: body
        type(marker_t) :: m
        m%body = body
        m%position = random_vector(rng, 3, -0.5_wp, 0.5_wp)
        m%axes = rotation_matrix(random_quaternion(rng))
    end function random_marker

    !> Three bodies and the ground with a joint of every kind (redundant as a
    !> set; the derivatives do not care), markers random.
    function all_joints_system(rng, derivatives, status) result(sys)
        type(random_state_t), intent(inout) :: rng
        character(len=*), intent(in) :: derivatives
        type(status_t), intent(out) :: status
        type(mbs_system_t) :: sys
        type(marker_t) :: markers(14)
        type(mbs_joint_t) :: joints(7)
        integer, parameter :: bodies_of(14) = [0, 1, 1, 2, 2, 3, 3, 0, 1, 3, 2, 0, 3, 1]
        integer :: k
        do k = 1, 14
            markers(k) = random_marker(rng, bodies_of(k))
        end do
        joints = [mbs_joint_t(joint_spherical, 1, 2), mbs_joint_t(joint_revolute, 3, 4), &
                  mbs_joint_t(joint_cylindrical, 5, 6), mbs_joint_t(joint_prismatic, 7, 8), &
                  mbs_joint_t(joint_universal, 9, 10), mbs_joint_t(joint_fixed, 11, 12), &
                  mbs_joint_t(joint_planar, 13, 14)]
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp), test_body(2.0_wp, 0.5_wp), &
                              test_body(0.5_wp, 2.0_wp)], markers, joints, &
                             gravity=[0.0_wp, 0.0_wp, -g_earth], &
                             constraint_derivatives=derivatives, status=status)
    end function all_joints_system

    subroutine random_state(rng, nbodies, q, v)
        type(random_state_t), intent(inout) :: rng
        integer, intent(in) :: nbodies
        real(wp), intent(out) :: q(:), v(:)
        integer :: i
        do i = 1, nbodies
            q(7 * i - 6:7 * i - 4) = random_vector(rng, 3, -1.0_wp, 1.0_wp)
            q(7 * i - 3:7 * i) = random_quaternion(rng)
            v(6 * i - 5:6 * i) = random_vector(rng, 6, -2.0_wp, 2.0_wp)
        end do
    end subroutine random_state

    !> RADAU5 from t = t0 (default 0) to t_end at rtol = atol (y consistent).
    subroutine integrate(gen, y, t_end, rtol, stats, status, t0)
        type(formulation_t), intent(inout) :: gen
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end, rtol
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: t0
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        real(wp) :: t
        options%rtol = rtol
        options%atol = rtol
        t = 0.0_wp
        if (present(t0)) t = t0
        call solver%integrate(gen, t, y, t_end, options, stats, status)
    end subroutine integrate

    ! ------------------------------------------------------------------ tests

    !> The assembled G, c_q, c_t and γ of the analytic and the AD systems
    !> ('ad': AD of the vector relations on the marker frames; 'ad_full':
    !> through the quaternions too) agree on random configurations; G = c_q T;
    !> c equal.
    subroutine test_ad_vs_analytic(error)
        type(error_t), allocatable, intent(out) :: error
        call ad_vs_analytic(error, 'ad')
        if (.not. allocated(error)) call ad_vs_analytic(error, 'ad_full')
    end subroutine test_ad_vs_analytic

    subroutine ad_vs_analytic(error, source)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), intent(in) :: source
        type(random_state_t) :: rng, rng_a, rng_d
        type(mbs_system_t) :: hand, ad
        type(status_t) :: status
        real(wp) :: q(21), v(18), tcol(21)
        real(wp), allocatable :: ch(:), cd(:), gh(:, :), gd(:, :), qh(:, :), qd(:, :), &
            th(:), td(:), yh(:), yd(:), gt(:, :)
        real(wp) :: e_g, e_q, e_t, e_y, e_c, e_gt
        integer :: trial, nc, j
        character(len=200) :: msg
        rng_a = rng
        rng_d = rng
        hand = all_joints_system(rng_a, 'analytic', status)
        call check(error, status%ok(), status%text())
        ad = all_joints_system(rng_d, source, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        rng = rng_a
        nc = hand%nc
        call check(error, nc == 3 + 5 + 4 + 5 + 4 + 6 + 3, 'row count')
        allocate (ch(nc), cd(nc), gh(nc, 18), gd(nc, 18), qh(nc, 21), qd(nc, 21), th(nc), &
                  td(nc), yh(nc), yd(nc), gt(nc, 18))
        e_g = 0
        e_q = 0
        e_t = 0
        e_y = 0
        e_c = 0
        e_gt = 0
        do trial = 1, 20
            call random_state(rng, 3, q, v)
            call hand%constraint(0.3_wp, q, ch, status)
            call ad%constraint(0.3_wp, q, cd, status)
            call hand%constraint_jacobian(0.3_wp, q, gh, status)
            call ad%constraint_jacobian(0.3_wp, q, gd, status)
            call hand%constraint_position_jacobian(0.3_wp, q, qh, status)
            call ad%constraint_position_jacobian(0.3_wp, q, qd, status)
            call hand%constraint_time_derivative(0.3_wp, q, th, status)
            call ad%constraint_time_derivative(0.3_wp, q, td, status)
            call hand%constraint_curvature(0.3_wp, q, v, yh, status)
            call ad%constraint_curvature(0.3_wp, q, v, yd, status)
            do j = 1, 18
                tcol = 0.0_wp
                call hand%kinematics(0.3_wp, q, unit(18, j), tcol, status)
                gt(:, j) = matmul(qh, tcol)
            end do
            e_c = max(e_c, maxval(abs(ch - cd)))
            e_g = max(e_g, rel_err(gd, gh))
            e_q = max(e_q, rel_err(qd, qh))
            e_t = max(e_t, maxval(abs(td - th)))
            e_y = max(e_y, rel_err(reshape(yd, [nc, 1]), reshape(yh, [nc, 1])))
            e_gt = max(e_gt, rel_err(gt, gh))
        end do
        write (msg, '(a,6es10.2)') source // ' vs analytic: c, G, c_q, c_t, γ; c_q T vs G:', &
            e_c, e_g, e_q, e_t, e_y, e_gt
        print '(a)', '    ' // trim(msg)
        call check(error, status%ok(), status%text())
        call check(error, max(e_c, e_g, e_q, e_t, e_y, e_gt) <= tol_ad, trim(msg))
    end subroutine ad_vs_analytic

    !> The unit vector e_j of length n.
    pure function unit(n, j) result(e)
        integer, intent(in) :: n, j
        real(wp) :: e(n)
        e = 0.0_wp
        e(j) = 1.0_wp
    end function unit

    !> The analytic Jacobians of the formulations (index 1 and GGL, acceleration
    !> layout), which use the system's AD second derivatives, against central
    !> differences of F, for both constraint_derivatives, off the manifold.
    subroutine test_formulation_jacobians(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng, rng0
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        type(marker_t) :: markers(6)
        real(wp), allocatable :: y(:), jac(:, :), jfd(:, :)
        integer :: mode, form, j
        character(len=8), parameter :: modes(2) = ['analytic', 'ad      ']
        integer, parameter :: forms(2) = [formulation_index1, formulation_ggl]
        character(len=200) :: msg
        rng0 = rng
        do mode = 1, 2
            rng = rng0
            markers = [random_marker(rng, 0), random_marker(rng, 1), random_marker(rng, 1), &
                       random_marker(rng, 2), random_marker(rng, 0), random_marker(rng, 2)]
            sys = new_mbs_system([test_body(1.0_wp, 1.0_wp), test_body(2.0_wp, 0.5_wp)], &
                                 markers, [mbs_joint_t(joint_revolute, 1, 2), &
                                           mbs_joint_t(joint_universal, 3, 4), &
                                           mbs_joint_t(joint_planar, 5, 6)], &
                                 gravity=[0.0_wp, -g_earth, 0.0_wp], &
                                 constraint_derivatives=trim(modes(mode)), status=status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            do form = 1, 2
                gen = new_formulation(sys, forms(form), [(0.0_wp, j = 1, 14)], status=status)
                allocate (y(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
                do j = 1, gen%n
                    y(j) = 0.8_wp * sin(1.3_wp * j + mode)
                end do
                call gen%jacobian_dense(0.0_wp, y, jac, status)
                call difference_jacobian(gen, y, jfd, status)
                write (msg, '(a,a,i0,a,es10.3)') trim(modes(mode)), ', form ', forms(form), &
                    ': Jacobian vs central differences ', maxval(abs(jac - jfd))
                print '(a)', '    ' // trim(msg)
                call check(error, status%ok() .and. maxval(abs(jac - jfd)) <= 1.0e-7_wp * &
                           max(1.0_wp, maxval(abs(jac))), trim(msg))
                deallocate (y, jac, jfd)
            end do
        end do
    end subroutine test_formulation_jacobians

    !> Unknown markers, two markers on one body, bad option: clear errors.
    subroutine test_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(marker_t) :: m(2)
        m(2)%body = 1
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], m, &
                             [mbs_joint_t(joint_spherical, 1, 3)], status=status)
        call check(error, .not. status%ok(), 'unknown marker accepted')
        print '(a)', '    ' // status%text()
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], [m(2), m(2)], &
                             [mbs_joint_t(joint_spherical, 1, 2)], status=status)
        call check(error, .not. status%ok(), 'joint within one body accepted')
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], m, &
                             [mbs_joint_t(joint_spherical, 1, 2)], &
                             constraint_derivatives='fd', status=status)
        call check(error, .not. status%ok(), 'constraint_derivatives = fd accepted')
        print '(a)', '    ' // status%text()
        m(1)%axes(1, 1) = 2.0_wp
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], m, &
                             [mbs_joint_t(joint_spherical, 1, 2)], status=status)
        call check(error, .not. status%ok(), 'non-orthonormal axes accepted')
    end subroutine test_bad_input

    !> One body (mass m, full inertia) on a spherical joint to the ground at
    !> the global origin, the joint's body marker at s_b = (0, 0, L).
    function heavy_pendulum(mass, length, ground_first, derivatives, status) result(sys)
        real(wp), intent(in) :: mass, length
        logical, intent(in) :: ground_first
        character(len=*), intent(in) :: derivatives
        type(status_t), intent(out) :: status
        type(mbs_system_t) :: sys
        type(marker_t) :: ground, tip
        tip%body = 1
        tip%position = [0.0_wp, 0.0_wp, length]
        if (ground_first) then
            sys = new_mbs_system([test_body(mass, 0.05_wp)], [ground, tip], &
                                 [mbs_joint_t(joint_spherical, 1, 2)], &
                                 gravity=[0.0_wp, 0.0_wp, -g_earth], &
                                 constraint_derivatives=derivatives, status=status)
        else
            sys = new_mbs_system([test_body(mass, 0.05_wp)], [tip, ground], &
                                 [mbs_joint_t(joint_spherical, 1, 2)], &
                                 gravity=[0.0_wp, 0.0_wp, -g_earth], &
                                 constraint_derivatives=derivatives, status=status)
        end if
    end function heavy_pendulum

    !> Hanging at rest: λ from the consistent initial values; the joint holds
    !> the body up with m g (our sign: the force on the body is −C_bᵀλ), no
    !> torque about the pivot; the ground carries m g downwards, no torque
    !> either; for either order of the markers.
    subroutine test_hanging_reaction(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp) :: y(22), yp(22), force(3, 2), torque(3, 2), expected(3)
        real(wp), parameter :: mass = 2.5_wp, length = 0.8_wp
        integer :: order, side
        character(len=200) :: msg
        expected = [0.0_wp, 0.0_wp, mass * g_earth]
        do order = 1, 2
            sys = heavy_pendulum(mass, length, order == 1, 'analytic', status)
            y = 0.0_wp
            y(1:3) = [0.0_wp, 0.0_wp, -length]
            y(4:7) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
            gen = new_formulation(sys, formulation_index2, y(1:7), status=status)
            call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            call sys%joint_reaction(1, 0.0_wp, y(1:7), &
                y(gen%offset(block_lambda) + 1:gen%offset(block_lambda) + 3), force, torque)
            side = merge(2, 1, order == 1)
            write (msg, '(a,i0,a,3es11.3,a,es10.3,a,3es11.3,a,es10.3)') 'order ', order, &
                ': force on body ', force(:, side), ', |torque| ', norm2(torque(:, side)), &
                '; on the ground ', force(:, 3 - side), ', |torque| ', norm2(torque(:, 3 - side))
            print '(a)', '    ' // trim(msg)
            call check(error, maxval(abs(force(:, side) - expected)) <= 1.0e-12_wp * &
                       mass * g_earth .and. norm2(torque(:, side)) <= 1.0e-12_wp .and. &
                       maxval(abs(force(:, 3 - side) + expected)) <= 1.0e-12_wp * &
                       mass * g_earth .and. norm2(torque(:, 3 - side)) <= 1.0e-12_wp, trim(msg))
        end do
    end subroutine test_hanging_reaction

    !> Every joint kind and two primitives between the ground and a body,
    !> the ground's marker first and second, at random orientations and
    !> multipliers: the joint's rows depend only on the relative pose of its
    !> markers, so what it exerts on the two sides balances, F_i + F_j = 0
    !> and n_i + n_j + (x_j − x_i) × F_j = 0 about marker i (scalar rows
    !> anywhere; the spherical part's vector rows where it is closed). The
    !> ground's side must carry its share, not zeros.
    subroutine test_ground_reactions(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: kinds(8) = [joint_spherical, joint_revolute, joint_cylindrical, &
            joint_prismatic, joint_universal, joint_fixed, joint_primitive, joint_primitive]
        integer, parameter :: primitives(8) = [0, 0, 0, 0, 0, 0, primitive_distance, &
            primitive_dot1]
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(random_state_t) :: rng
        type(marker_t) :: m(2)
        type(mbs_joint_t) :: joint
        real(wp) :: q(7), force(3, 2), torque(3, 2), lambda(6), xi(3), xj(3), axes(3, 3)
        real(wp) :: worst, scale, d
        integer :: k, ground_side, trial, body_side
        character(len=200) :: msg
        rng%s = 71_i8
        worst = 0.0_wp
        do k = 1, size(kinds)
            do ground_side = 1, 2
                body_side = 3 - ground_side
                m(ground_side) = random_marker(rng, 0)
                m(body_side) = random_marker(rng, 1)
                joint = mbs_joint_t(kinds(k), 1, 2)
                if (kinds(k) == joint_primitive) then
                    joint%primitive = primitives(k)
                    joint%axis_i = 3
                    joint%axis_j = 1
                end if
                sys = new_mbs_system([test_body(1.5_wp, 0.05_wp)], m, [joint], &
                                     gravity=[0.0_wp, 0.0_wp, -g_earth], status=status)
                call check(error, status%ok(), 'joint kind ' // int_text(k) // ': ' // &
                           status%text())
                if (allocated(error)) return
                do trial = 1, 3
                    q(1:3) = random_vector(rng, 3, -0.5_wp, 0.5_wp)
                    q(4:7) = random_quaternion(rng)
                    ! a spherical part's rows are a vector, x_j − x_i: its
                    ! moments balance where it is closed, so the body is put
                    ! where its marker meets the ground's
                    if (any(kinds(k) == [joint_spherical, joint_revolute, joint_universal, &
                                         joint_fixed])) q(1:3) = m(ground_side)%position &
                        - matmul(rotation_matrix(q(4:7)), m(body_side)%position)
                    lambda = random_vector(rng, 6, -2.0_wp, 2.0_wp)
                    call sys%joint_reaction(1, 0.1_wp, q, lambda(1:sys%nc), force, torque)
                    call sys%marker_pose(1, q, xi, axes)
                    call sys%marker_pose(2, q, xj, axes)
                    scale = max(norm2(force(:, body_side)), norm2(torque(:, body_side)))
                    d = max(maxval(abs(force(:, 1) + force(:, 2))), &
                            maxval(abs(torque(:, 1) + torque(:, 2) + cross(xj - xi, force(:, 2)))))
                    write (msg, '(a,i0,a,i0,a,es10.3,a,es10.3,a,2es10.3)') 'joint kind ', k, &
                        ', ground side ', ground_side, ': imbalance ', d, ' of ', scale, &
                        ', |F|, |n| on the ground ', norm2(force(:, ground_side)), &
                        norm2(torque(:, ground_side))
                    ! a ground side that took nothing would balance only a body
                    ! side that takes nothing: both sides must carry the load
                    call check(error, scale > 1.0e-3_wp .and. d <= 1.0e-12_wp * scale .and. &
                               norm2(force(:, ground_side)) + norm2(torque(:, ground_side)) &
                               > 1.0e-3_wp, trim(msg))
                    if (allocated(error)) return
                    worst = max(worst, d / scale)
                end do
            end do
        end do
        print '(4x,a,es9.2)', 'ground and body reactions: largest relative imbalance ', worst
    end subroutine test_ground_reactions

    !> The heavy spherical pendulum with RADAU5 in GGL form: energy and the
    !> vertical angular momentum about the pivot are conserved, ‖c‖ stays at
    !> tolerance level; analytic and AD runs agree.
    subroutine test_spherical_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(25), yp(25), y_end(25, 2), e0, e1, lin(3), h0(3), h1(3), a(3, 3)
        real(wp) :: dc, dv, scale
        real(wp), parameter :: mass = 1.5_wp, length = 0.7_wp, t_end = 4.0_wp, rtol = 1.0e-8_wp
        integer :: mode
        character(len=8), parameter :: modes(2) = ['analytic', 'ad      ']
        character(len=220) :: msg
        do mode = 1, 2
            sys = heavy_pendulum(mass, length, .true., trim(modes(mode)), status)
            y = 0.0_wp
            y(4:7) = quat_from_axis_angle([1.0_wp, 0.0_wp, 0.0_wp], 0.9_wp)
            a = rotation_matrix(y(4:7))
            y(1:3) = -matmul(a, [0.0_wp, 0.0_wp, length])
            y(11:13) = [0.4_wp, -0.3_wp, 2.5_wp]
            y(8:10) = -matmul(a, cross(y(11:13), [0.0_wp, 0.0_wp, length]))
            gen = new_formulation(sys, formulation_ggl, y(1:7), status=status)
            call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e0 = sys%energy(y(1:7), y(8:13))
            call sys%momenta(y(1:7), y(8:13), lin, h0)
            call integrate(gen, y, t_end, rtol, stats, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:7), y(8:13))
            call sys%momenta(y(1:7), y(8:13), lin, h1)
            call gen%drift(t_end, y, dc, dv, status)
            scale = mass * g_earth * length
            write (msg, '(2a,es10.3,3(a,es10.3),a,i0)') trim(modes(mode)), ': energy ', &
                abs(e1 - e0) / scale, ', H_z ', abs(h1(3) - h0(3)) / norm2(h0), ', |c| ', dc, &
                ', |Gv| ', dv, ', steps ', stats%nst
            print '(a)', '    ' // trim(msg)
            call check(error, abs(e1 - e0) <= 1.0e-6_wp * scale .and. &
                       abs(h1(3) - h0(3)) <= 1.0e-6_wp * norm2(h0) .and. dc <= 1.0e-8_wp &
                       .and. dv <= 1.0e-7_wp, trim(msg))
            y_end(:, mode) = y
        end do
        write (msg, '(a,es10.3)') 'analytic vs AD runs: |Δq| = ', &
            maxval(abs(y_end(1:7, 1) - y_end(1:7, 2)))
        print '(a)', '    ' // trim(msg)
        call check(error, maxval(abs(y_end(1:7, 1) - y_end(1:7, 2))) <= 1.0e-7_wp, trim(msg))
    end subroutine test_spherical_pendulum

    !> A rigid body (mass m, inertia J_zz about the centre) on a revolute joint
    !> about z, its centre at distance L below the pivot, is the physical
    !> pendulum (m L² + J_zz) φ'' = −m g L sin φ: the point-mass pendulum of
    !> length L_eq = (m L² + J_zz)/(m L). Its angle matches
    !> pendulum_mechanical_t of that length (RADAU5, index 2) and the exact one.
    subroutine test_planar_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(pendulum_mechanical_t), target :: point
        type(formulation_t) :: gen, gen_point
        type(dae_stats_t) :: stats, stats_point
        type(status_t) :: status
        type(rigid_body_t) :: body
        type(marker_t) :: ground, pivot
        real(wp) :: y(24), yp(24), yq(5), yqp(5), q2(2), v2(2), lam(1), a(3, 3)
        real(wp) :: phi_body, phi_point, phi_exact, dphi, l_eq
        real(wp), parameter :: mass = 1.2_wp, length = 0.9_wp, jzz = 0.15_wp, phi0 = 1.0_wp
        real(wp), parameter :: t_end = 3.0_wp, rtol = 1.0e-9_wp
        character(len=220) :: msg
        body%mass = mass
        body%inertia = 0.0_wp
        body%inertia(1, 1) = 0.1_wp
        body%inertia(2, 2) = 0.12_wp
        body%inertia(3, 3) = jzz
        pivot%body = 1
        pivot%position = [0.0_wp, length, 0.0_wp]
        sys = new_mbs_system([body], [ground, pivot], [mbs_joint_t(joint_revolute, 1, 2)], &
                             gravity=[0.0_wp, -g_earth, 0.0_wp], status=status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        y = 0.0_wp
        y(4:7) = quat_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], phi0)
        a = rotation_matrix(y(4:7))
        y(1:3) = -matmul(a, pivot%position)
        gen = new_formulation(sys, formulation_index2, y(1:7), projection=.true., &
                              status=status)
        call gen%consistent_initial(0.0_wp, y, yp, status)
        call integrate(gen, y, t_end, rtol, stats, status)
        call check(error, status%ok(), 'rigid: ' // status%text())
        if (allocated(error)) return
        phi_body = atan2(y(1), -y(2))

        l_eq = (mass * length**2 + jzz) / (mass * length)
        point = new_pendulum_mechanical(mass=mass, length=l_eq, gravity=g_earth)
        call pendulum_mechanical_initial(point, phi0, q2, v2, lam)
        yq = [q2, v2, lam]
        gen_point = new_formulation(point, formulation_index2, q2, constant_mass=.true., &
                                    status=status)
        call gen_point%consistent_initial(0.0_wp, yq, yqp, status)
        call integrate(gen_point, yq, t_end, rtol, stats_point, status)
        call check(error, status%ok(), 'point mass: ' // status%text())
        if (allocated(error)) return
        phi_point = atan2(yq(1), -yq(2))
        call pendulum_angle_exact(phi0, sqrt(g_earth / l_eq), t_end, phi_exact, dphi, status)
        write (msg, '(3(a,es10.3),a,2(i0,1x))') 'rigid vs point-mass angle ', &
            abs(phi_body - phi_point), ', rigid vs exact ', abs(phi_body - phi_exact), &
            ', |z| + |tilt| ', abs(y(3)) + norm2(y(5:6)), ', steps ', stats%nst, stats_point%nst
        print '(a)', '    ' // trim(msg)
        call check(error, abs(phi_body - phi_point) <= 1.0e-6_wp .and. &
                   abs(phi_body - phi_exact) <= 1.0e-6_wp .and. &
                   abs(y(3)) + norm2(y(5:6)) <= 1.0e-9_wp, trim(msg))
    end subroutine test_planar_pendulum

    !> Two bodies, revolute joints ground-1 and 1-2 (axes z, offset markers,
    !> full inertias), undamped: the energy drift is proportional to the
    !> tolerance (index 2 with projection, RADAU5, two tolerances).
    !> Two bodies on revolute joints about z: ground-1 (body 1's upper end,
    !> 0.5 above its centre) and 1-2 (body 1's lower end, body 2 at (0.1, 0.4,
    !> 0)); gravity -y. y is a start near consistency (body 1 turned by 1.2,
    !> spinning at 1.5, body 2 unturned), fixed up by the projection.
    subroutine double_pendulum(sys, y, status)
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: y(48)
        type(status_t), intent(out) :: status
        type(marker_t) :: markers(4)
        markers(1)%body = 0
        markers(2) = marker_t(1, [0.0_wp, 0.5_wp, 0.0_wp])
        markers(3) = marker_t(1, [0.0_wp, -0.5_wp, 0.0_wp])
        markers(4) = marker_t(2, [0.1_wp, 0.4_wp, 0.0_wp])
        sys = new_mbs_system([test_body(1.0_wp, 0.05_wp), test_body(0.7_wp, 0.03_wp)], &
                             markers, [mbs_joint_t(joint_revolute, 1, 2), &
                                       mbs_joint_t(joint_revolute, 3, 4)], &
                             gravity=[0.0_wp, -g_earth, 0.0_wp], status=status)
        y = 0.0_wp
        y(4:7) = quat_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 1.2_wp)
        y(1:3) = -matmul(rotation_matrix(y(4:7)), markers(2)%position)
        y(11:14) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        y(8:10) = y(1:3) + matmul(rotation_matrix(y(4:7)), markers(3)%position) &
            - markers(4)%position
        y(20) = 1.5_wp
    end subroutine double_pendulum

    subroutine test_double_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(48), yp(48), y0(48), e0, e1, drift(2), dc, dv, scale
        real(wp), parameter :: t_end = 3.0_wp
        real(wp), parameter :: rtols(2) = [1.0e-6_wp, 1.0e-8_wp]
        integer :: k
        character(len=220) :: msg
        call double_pendulum(sys, y0, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        scale = (1.0_wp + 0.7_wp) * g_earth
        do k = 1, 2
            y = y0
            gen = new_formulation(sys, formulation_index2, y(1:14), projection=.true., &
                                  status=status)
            gen%projection_rtol = rtols(k)
            gen%projection_atol = rtols(k)
            call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e0 = sys%energy(y(1:14), y(15:26))
            call integrate(gen, y, t_end, rtols(k), stats, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:14), y(15:26))
            call gen%drift(t_end, y, dc, dv, status)
            drift(k) = abs(e1 - e0) / scale
            write (msg, '(a,es8.1,3(a,es10.3),a,i0)') 'rtol ', rtols(k), ': energy ', &
                drift(k), ', |c| ', dc, ', |Gv| ', dv, ', steps ', stats%nst
            print '(a)', '    ' // trim(msg)
            call check(error, drift(k) <= 10.0_wp * rtols(k), trim(msg))
        end do
    end subroutine test_double_pendulum

    !> Newton-Euler per body at a consistent moving state of the double
    !> pendulum, from the reported reactions: m a = m g + Σ F and
    !> J ω̇′ + ω′ × J ω′ = Σ Aᵀ(n + A s_m × F) (s_m the marker's body position).
    !> The revolute joints must supply the x and y torques of the gyroscopic
    !> terms (full inertias).
    subroutine test_reactions_balance(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp) :: y(48), yp(48), force(3, 2), torque(3, 2), a(3, 3), fsum(3, 2), nsum(3, 2)
        real(wp) :: res_f, res_n
        integer :: k, side, b, mk, iq, iv
        type(marker_t) :: marker
        type(rigid_body_t) :: body
        character(len=200) :: msg
        call double_pendulum(sys, y, status)
        y(26) = -0.8_wp
        gen = new_formulation(sys, formulation_index2, y(1:14), status=status)
        call gen%consistent_initial(0.0_wp, y, yp, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        fsum = 0.0_wp
        nsum = 0.0_wp
        do k = 1, 2
            call sys%joint_reaction(k, 0.0_wp, y(1:14), &
                y(gen%offset(block_lambda) + 1:gen%offset(block_lambda) + 10), force, torque)
            do side = 1, 2
                mk = merge(2 * k - 1, 2 * k, side == 1)
                marker = sys%marker_of(mk)
                b = marker%body
                if (b == 0) cycle
                a = rotation_matrix(y(7 * b - 3:7 * b))
                fsum(:, b) = fsum(:, b) + force(:, side)
                nsum(:, b) = nsum(:, b) + matmul(transpose(a), torque(:, side)) &
                    + cross(marker%position, matmul(transpose(a), force(:, side)))
            end do
        end do
        res_f = 0.0_wp
        res_n = 0.0_wp
        do b = 1, 2
            iq = 7 * (b - 1)
            iv = gen%offset(block_v) + 6 * (b - 1)
            body = sys%rigid_body_of(b)
            associate (w => y(iv + 4:iv + 6))
                res_f = max(res_f, maxval(abs(body%mass * yp(iv + 1:iv + 3) - body%mass * &
                            [0.0_wp, -g_earth, 0.0_wp] - fsum(:, b))))
                res_n = max(res_n, maxval(abs(matmul(body%inertia, yp(iv + 4:iv + 6)) + &
                            cross(w, matmul(body%inertia, w)) - nsum(:, b))))
            end associate
        end do
        write (msg, '(2(a,es10.3))') 'Newton residual ', res_f, ', Euler residual ', res_n
        print '(a)', '    ' // trim(msg)
        call check(error, res_f <= 1.0e-12_wp * g_earth .and. res_n <= 1.0e-12_wp * g_earth &
                   .and. maxval(abs(nsum(1:2, :))) > 1.0e-3_wp, trim(msg))
    end subroutine test_reactions_balance
end module test_mbs_system
