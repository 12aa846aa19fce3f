!> Rigid chains inside the multibody system: the Grashof four-bar with the
!> crank and coupler as a two-link chain in relative coordinates and the
!> rocker as a free rigid body, closed by two dot-2 rows (in-plane
!> coincidence of the coupler end and the rocker end) and driven by an angle
!> driver on the chain's first link: 2 + 6 velocities, 5 + 2 + 1 rows.
module test_chain_coupling
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_joint_revolute, chain_joint_spherical
    use flexmbs_mbs_joint, only: joint_revolute, joint_primitive, joint_spherical
    use flexmbs_mbs_primitive_kinds, only: primitive_dot1, primitive_dot2, primitive_angle_driver
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, driver_t, &
        force_element_t
    use flexmbs_mbs_force_element, only: force_spring_damper, force_bushing
    use flexmbs_dae_mechanical_problem, only: mechanical_patterns_t
    use test_force_elements, only: compare_derivatives, compare_with_ad
    use flexmbs_mbs_formulation, only: block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index1, formulation_index2, formulation_index3
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_problems_mechanisms, only: four_bar_exact, crank_angle, mechanism_theta0, &
        mechanism_omega, bar_a, bar_b, bar_c, bar_d
    use test_problems, only: fill_random
    use mbs_random, only: ad_deviation
    use test_formulation, only: difference_jacobian
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_chain_coupling

    real(wp), parameter :: g_earth(3) = [0.0_wp, -9.81_wp, 0.0_wp]
    real(wp), parameter :: identity(3, 3) = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1] * 1.0_wp, [3, 3])
    ! The long chain (make_long): 14 links, link 7 spherical; two rigid bodies.
    integer, parameter :: long_links = 14, long_spherical = 7
    integer, parameter :: long_nq = 14 + long_links + 3, long_nv = 12 + long_links + 2

contains

    function collect_chain_coupling() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('chain_markers_ad_vs_analytic', test_ad), &
                 new_test('formulation_jacobian_fd', test_jacobian), &
                 new_test('four_bar_with_chain_closed_form', test_closed_form), &
                 new_test('spherical_chain_in_system', test_spherical), &
                 new_test('chain_joint_reactions_balance', test_reactions), &
                 new_test('large_chains_in_system', test_large), &
                 new_test('long_chain_markers_derivatives', test_long_derivatives), &
                 new_test('long_chain_markers_formulations', test_long_formulations), &
                 new_test('long_chain_force_elements', test_long_elements), &
                 new_test('long_chain_closed_loop_energy', test_long_loop)]
    end function collect_chain_coupling

    subroutine make(derivatives, sys, q0, status)
        character(len=*), intent(in) :: derivatives
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: q0(9)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(2)
        type(marker_t) :: m(6)
        type(driver_t) :: drive
        real(wp) :: pb(3), pc(3), phi, psi
        call four_bar_exact(mechanism_theta0, pb, pc)
        phi = atan2(pc(2) - pb(2), pc(1) - pb(1))
        psi = atan2(pc(2), pc(1) - bar_d)
        b(1) = chain_body_t(0, chain_joint_revolute, [0.0_wp, 0.0_wp, 0.0_wp], identity, &
                            [0.0_wp, 0.0_wp, 1.0_wp], [0.5_wp * bar_a, 0.0_wp, 0.0_wp], 1.0_wp, &
                            0.01_wp * identity)
        b(2) = chain_body_t(1, chain_joint_revolute, [bar_a, 0.0_wp, 0.0_wp], identity, &
                            [0.0_wp, 0.0_wp, 1.0_wp], [0.5_wp * bar_b, 0.0_wp, 0.0_wp], 0.5_wp, &
                            0.01_wp * identity)
        chain = new_rigid_chain(b, status, gravity=g_earth)
        if (.not. status%ok()) return
        m(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp])
        m(2) = marker_t(0, chain=1, link=1)
        m(3) = marker_t(0, [bar_b, 0.0_wp, 0.0_wp], chain=1, link=2)
        m(4) = marker_t(1, [0.5_wp * bar_c, 0.0_wp, 0.0_wp])
        m(5) = marker_t(1, [-0.5_wp * bar_c, 0.0_wp, 0.0_wp])
        m(6) = marker_t(0, [bar_d, 0.0_wp, 0.0_wp])
        drive%poly(0:1) = [mechanism_theta0, mechanism_omega]
        sys = new_mbs_system([rigid_body_t(0.333_wp, 0.01_wp * identity)], m, &
            [mbs_joint_t(joint_revolute, 6, 5), &
             mbs_joint_t(joint_primitive, 3, 4, primitive_dot2, 1, 1), &
             mbs_joint_t(joint_primitive, 3, 4, primitive_dot2, 2, 1), &
             mbs_joint_t(joint_primitive, 1, 2, primitive_angle_driver, 1, 1, drive)], &
            gravity=g_earth, constraint_derivatives=derivatives, status=status, chains=[chain])
        if (.not. status%ok()) return
        ! q = (rocker r, p; chain θ1, θ2)
        q0(1:3) = 0.5_wp * (pc + [bar_d, 0.0_wp, 0.0_wp])
        q0(4:7) = quat_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], psi)
        q0(8:9) = [mechanism_theta0, phi - mechanism_theta0]
    end subroutine make

    !> G, c_q, c_t and γ with chain markers: 'ad' equals 'analytic' (1e-12).
    subroutine test_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: hand, ad, full
        type(status_t) :: status
        real(wp) :: q0(9), q(9), v(8), worst
        integer(i8) :: seed
        integer :: trial
        call make('analytic', hand, q0, status)
        if (status%ok()) call make('ad', ad, q0, status)
        if (status%ok()) call make('ad_full', full, q0, status)
        call check(error, status%ok() .and. hand%nc == 8 .and. hand%nv == 8, &
                   'systems: ' // status%text())
        if (allocated(error)) return
        seed = 12_i8
        worst = 0.0_wp
        do trial = 1, 5
            call fill_random(q, seed, -0.1_wp, 0.1_wp)
            q = q0 + q
            q(4:7) = q(4:7) / norm2(q(4:7))
            call fill_random(v, seed, -1.0_wp, 1.0_wp)
            worst = max(worst, ad_deviation(hand, ad, 0.2_wp, q, v, status), &
                        ad_deviation(hand, full, 0.2_wp, q, v, status))
        end do
        print '(4x,a,es9.2)', 'chain markers: AD (ad, ad_full) vs analytic ', worst
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, worst <= 1.0e-12_wp, 'AD differs from analytic')
    end subroutine test_ad

    !> The GGL Jacobian (acceleration layout: M depends on the chain's q)
    !> against central differences of F (1e-6 relative).
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp) :: q0(9)
        real(wp), allocatable :: y(:), jac(:, :), jfd(:, :)
        integer(i8) :: seed
        call make('analytic', sys, q0, status)
        gen = new_formulation(sys, formulation_ggl, q0, status=status)
        allocate (y(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
        seed = 4_i8
        call fill_random(y, seed, -0.1_wp, 0.1_wp)
        y(1:9) = y(1:9) + q0
        y(4:7) = y(4:7) / norm2(y(4:7))
        call gen%jacobian_dense(0.0_wp, y, jac, status)
        call difference_jacobian(gen, y, jfd, status)
        call check(error, status%ok(), 'jacobian: ' // status%text())
        print '(4x,a,es9.2)', 'chain coupling: Jacobian vs differences ', &
            maxval(abs(jac - jfd)) / maxval(abs(jac))
        call check(error, maxval(abs(jac - jfd)) <= 1.0e-6_wp * maxval(abs(jac)), &
                   'Jacobian differs from differences')
    end subroutine test_jacobian

    !> One crank revolution (RADAU5, GGL, rtol 1e-7): the rocker angle and
    !> the chain's coupler angle follow the closed form.
    subroutine test_closed_form(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q0(9), t, pb(3), pc(3), r(3, 3), dev
        real(wp), allocatable :: y(:), yp(:)
        call make('analytic', sys, q0, status)
        gen = new_formulation(sys, formulation_ggl, q0, status=status)
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(1:9) = q0
        call gen%consistent_initial(0.0_wp, y, yp, status)
        call check(error, status%ok(), 'initial: ' // status%text())
        if (allocated(error)) return
        options%rtol = 1.0e-7_wp
        options%atol = 1.0e-7_wp
        t = 0.0_wp
        call solver%integrate(gen, t, y, 1.0_wp, options, stats, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call four_bar_exact(crank_angle(t), pb, pc)
        r = rotation_matrix(y(4:7) / norm2(y(4:7)))
        dev = max(abs(angle_difference(atan2(r(2, 1), r(1, 1)), atan2(pc(2), pc(1) - bar_d))), &
                  abs(angle_difference(y(8) + y(9), atan2(pc(2) - pb(2), pc(1) - pb(1)))), &
                  abs(angle_difference(y(8), crank_angle(t))))
        print '(4x,a,i0,a,es9.2)', 'four-bar with a chain: NST=', stats%nst, &
            ', closed-form deviation ', dev
        call check(error, dev <= 1.0e-5_wp, 'off the closed form')
    end subroutine test_closed_form

    pure real(wp) function angle_difference(a, b)
        real(wp), intent(in) :: a, b
        angle_difference = atan2(sin(a - b), cos(a - b))
    end function angle_difference
    !> A chain with a spherical root (quaternion coordinates) and a revolute
    !> link, and a rigid body hanging from the link's end by a spherical
    !> joint: AD against hand-coded (1e-12), the GGL Jacobian against
    !> differences (1e-6), and the energy over 0.5 s (RADAU5, rtol 1e-8).
    subroutine test_spherical(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: hand, ad, full
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q0(12), q(12), v(10), worst, t, e0, e1
        real(wp), allocatable :: y(:), yp(:), jac(:, :), jfd(:, :)
        integer(i8) :: seed
        integer :: trial
        call make_pair('analytic', hand, q0, status)
        if (status%ok()) call make_pair('ad', ad, q0, status)
        if (status%ok()) call make_pair('ad_full', full, q0, status)
        call check(error, status%ok() .and. hand%nq == 12 .and. hand%nv == 10 .and. &
                   hand%nc == 3, 'systems: ' // status%text())
        if (allocated(error)) return
        seed = 21_i8
        worst = 0.0_wp
        do trial = 1, 5
            call fill_random(q, seed, -0.05_wp, 0.05_wp)
            q = q0 + q
            q(4:7) = q(4:7) / norm2(q(4:7))
            q(8:11) = q(8:11) / norm2(q(8:11))
            call fill_random(v, seed, -1.0_wp, 1.0_wp)
            worst = max(worst, ad_deviation(hand, ad, 0.2_wp, q, v, status), &
                        ad_deviation(hand, full, 0.2_wp, q, v, status))
        end do
        print '(4x,a,es9.2)', 'spherical chain markers: AD (ad, ad_full) vs analytic ', worst
        call check(error, worst <= 1.0e-12_wp, 'AD differs from analytic')
        gen = new_formulation(hand, formulation_ggl, q0, status=status)
        allocate (y(gen%n), yp(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
        call fill_random(y, seed, -0.05_wp, 0.05_wp)
        y(1:12) = q0 + y(1:12)
        y(4:7) = y(4:7) / norm2(y(4:7))
        y(8:11) = y(8:11) / norm2(y(8:11))
        call gen%jacobian_dense(0.0_wp, y, jac, status)
        call difference_jacobian(gen, y, jfd, status)
        print '(4x,a,es9.2)', 'spherical chain coupling: Jacobian vs differences ', &
            maxval(abs(jac - jfd)) / maxval(abs(jac))
        call check(error, maxval(abs(jac - jfd)) <= 1.0e-6_wp * maxval(abs(jac)), &
                   'Jacobian differs from differences')
        y = 0.0_wp
        y(1:12) = q0
        ! the ball joint's spin
        y(gen%offset(block_v) + 8:gen%offset(block_v) + 10) = [1.0_wp, -0.5_wp, 0.8_wp]
        call gen%consistent_initial(0.0_wp, y, yp, status)
        e0 = hand%energy(y(1:12), y(gen%offset(block_v) + 1:gen%offset(block_v) + 10))
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        t = 0.0_wp
        call solver%integrate(gen, t, y, 0.5_wp, options, stats, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        e1 = hand%energy(y(1:12), y(gen%offset(block_v) + 1:gen%offset(block_v) + 10))
        print '(4x,a,es9.2)', 'spherical chain coupling: relative energy drift ', &
            abs(e1 - e0) / abs(e0)
        call check(error, abs(e1 - e0) <= 1.0e-5_wp * abs(e0), 'energy drift')
    end subroutine test_spherical

    !> A joint's rows do not change when both its markers move as one rigid
    !> body, so what it exerts on its two sides balances: F_i + F_j = 0 and
    !> n_i + n_j + (x_i − x_j) × F_i = 0 (torques about each marker). Checked
    !> for joints between a chain link and a rigid body (the pair's spherical
    !> joint, assembled, whose rows turn with the bodies; the four-bar's two
    !> dot-2 rows, scalars) at perturbed positions and
    !> random multipliers: a chain side's force is a force, not the chain's
    !> generalised forces.
    subroutine test_reactions(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: pair, four
        type(status_t) :: status
        real(wp) :: q0(12), q4(9), worst
        integer(i8) :: seed
        integer :: trial
        call make_pair('analytic', pair, q0, status)
        if (status%ok()) call make('analytic', four, q4, status)
        call check(error, status%ok(), 'systems: ' // status%text())
        if (allocated(error)) return
        seed = 33_i8
        worst = 0.0_wp
        do trial = 1, 4
            worst = max(worst, imbalance(pair, q0, 1), imbalance(four, q4, 2), &
                        imbalance(four, q4, 3))
        end do
        print '(4x,a,es9.2)', 'chain joint reactions: largest imbalance ', worst
        call check(error, worst <= 1.0e-12_wp, 'reactions on a chain link and a body do &
                   &not balance')
    contains
        real(wp) function imbalance(sys, q0, k) result(d)
            type(mbs_system_t), intent(inout) :: sys
            real(wp), intent(in) :: q0(:)
            integer, intent(in) :: k
            real(wp) :: q(size(q0)), lambda(sys%nc), force(3, 2), torque(3, 2), &
                xi(3), xj(3), a(3, 3)
            type(marker_t) :: marker
            integer :: ends(2)
            call fill_random(q, seed, -0.1_wp, 0.1_wp)
            q = q0 + q
            q(4:7) = q(4:7) / norm2(q(4:7))
            if (size(q) == 12) then
                ! the ball joint's rows are a vector: assembled, the body put
                ! where its marker meets the chain's
                q(8:11) = q(8:11) / norm2(q(8:11))
                ends = sys%joint_markers(k)
                marker = sys%marker_of(2)
                call sys%marker_pose(ends(1), q, xi, a)
                q(1:3) = xi - matmul(rotation_matrix(q(4:7)), marker%position)
            end if
            call fill_random(lambda, seed, -2.0_wp, 2.0_wp)
            call sys%joint_reaction(k, 0.3_wp, q, lambda, force, torque)
            ends = sys%joint_markers(k)
            call sys%marker_pose(ends(1), q, xi, a)
            call sys%marker_pose(ends(2), q, xj, a)
            d = max(maxval(abs(force(:, 1) + force(:, 2))), &
                    maxval(abs(torque(:, 1) + torque(:, 2) + cross(xi - xj, force(:, 1)))))
            ! a side that takes nothing balances trivially
            if (norm2(force(:, 1)) + norm2(torque(:, 1)) < 1.0e-3_wp) d = huge(1.0_wp)
        end function imbalance
    end subroutine test_reactions

    !> The pair: rigid body (q 1:7), chain (ball quaternion 8:11, hinge 12).
    subroutine make_pair(derivatives, sys, q0, status)
        character(len=*), intent(in) :: derivatives
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: q0(12)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(2)
        type(marker_t) :: m(2)
        b(1) = chain_body_t(0, chain_joint_spherical, [0.0_wp, 0.0_wp, 0.0_wp], identity, &
                            [0.0_wp, 0.0_wp, 1.0_wp], [0.3_wp, 0.0_wp, 0.0_wp], 1.0_wp, &
                            0.02_wp * identity)
        b(2) = chain_body_t(1, chain_joint_revolute, [0.6_wp, 0.0_wp, 0.0_wp], identity, &
                            [0.6_wp, 0.0_wp, 0.8_wp], [0.2_wp, 0.0_wp, 0.0_wp], 0.5_wp, &
                            0.01_wp * identity)
        chain = new_rigid_chain(b, status, gravity=g_earth)
        if (.not. status%ok()) return
        m(1) = marker_t(0, [0.4_wp, 0.0_wp, 0.0_wp], chain=1, link=2)
        m(2) = marker_t(1, [-0.1_wp, 0.0_wp, 0.0_wp])
        sys = new_mbs_system([rigid_body_t(0.4_wp, 0.005_wp * identity)], m, &
            [mbs_joint_t(joint_spherical, 1, 2)], gravity=g_earth, &
            constraint_derivatives=derivatives, status=status, chains=[chain])
        if (.not. status%ok()) return
        ! link 2's end at (1.0, 0, 0) with the chain at rest (q = identity, 0)
        q0(1:7) = [1.1_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        q0(8:12) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
    end subroutine make_pair

    !> Two chains of 9 revolute links (9 coordinates each, more than a rigid
    !> body's 7) in one system with a rigid body on a spherical joint: built,
    !> M block diagonal with each chain's own M; a marker on one of them is
    !> jointed (its rows: the marker's position minus the ground point), and
    !> a force element takes it.
    subroutine test_large(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: n = 9
        type(rigid_chain_t) :: chains(2)
        type(chain_body_t) :: b(n)
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(marker_t) :: m(3)
        type(force_element_t) :: spring
        real(wp) :: q(7 + 2 * n), mass(6 + 2 * n, 6 + 2 * n), mc(n, n), xm(3), a(3, 3), c3(3)
        integer :: i, c
        do i = 1, n
            b(i) = chain_body_t(i - 1, chain_joint_revolute, [merge(0.0_wp, 0.3_wp, i == 1), &
                0.0_wp, 0.0_wp], identity, [0.0_wp, sin(0.4_wp * i), cos(0.4_wp * i)], &
                [0.15_wp, 0.0_wp, 0.0_wp], 0.5_wp, 0.01_wp * identity)
        end do
        do c = 1, 2
            chains(c) = new_rigid_chain(b, status, gravity=g_earth)
        end do
        m(1) = marker_t(0, [0.0_wp, 1.0_wp, 0.0_wp])
        m(2) = marker_t(1, [0.0_wp, 0.2_wp, 0.0_wp])
        sys = new_mbs_system([rigid_body_t(1.0_wp, 0.02_wp * identity)], m(1:2), &
            [mbs_joint_t(joint_spherical, 1, 2)], gravity=g_earth, chains=chains, status=status)
        call check(error, status%ok() .and. sys%nq == 7 + 2 * n .and. sys%nv == 6 + 2 * n, &
                   'two 9-link chains: ' // status%text())
        if (allocated(error)) return
        q = 0.0_wp
        q(4) = 1.0_wp
        q(8:) = [(0.1_wp * i, i = 1, 2 * n)]
        call sys%mass(0.0_wp, q, mass, status)
        call chains(2)%mass(0.0_wp, q(8 + n:), mc, status)
        call check(error, maxval(abs(mass(7 + n:, 7 + n:) - mc)) == 0.0_wp .and. &
                   maxval(abs(mass(7:6 + n, 7 + n:))) == 0.0_wp, 'M of the second chain')
        if (allocated(error)) return
        m(3) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp], chain=2, link=n)
        spring%kind = force_spring_damper
        spring%marker_i = 2
        spring%marker_j = 3
        spring%stiffness(1) = 10.0_wp
        sys = new_mbs_system([rigid_body_t(1.0_wp, 0.02_wp * identity)], m, &
            [mbs_joint_t(joint_spherical, 1, 3)], gravity=g_earth, chains=chains, status=status)
        call check(error, status%ok() .and. sys%nc == 3, 'marker on a 9-coordinate chain: ' // &
                   status%text())
        if (allocated(error)) return
        call sys%marker_pose(3, q, xm, a)
        call sys%constraint(0.0_wp, q, c3, status)
        call check(error, maxval(abs(c3 - (xm - [0.0_wp, 1.0_wp, 0.0_wp]))) <= 1.0e-14_wp, &
                   'spherical rows on a 9-coordinate chain: marker minus ground point')
        if (allocated(error)) return
        sys = new_mbs_system([rigid_body_t(1.0_wp, 0.02_wp * identity)], m, &
            [mbs_joint_t(joint_spherical, 1, 3)], gravity=g_earth, chains=chains, &
            status=status, elements=[spring])
        call check(error, status%ok() .and. sys%element_count() == 1, 'force element on a &
                   &9-coordinate chain: ' // status%text())
    end subroutine test_large
    !> A chain of 14 links (13 revolute with turning axes, link 7 spherical:
    !> 17 coordinates and 16 rates, three dual windows) and two rigid bodies:
    !> the tip hinged to body 1 (revolute), link 5 held on the ground
    !> (spherical), link 9 turned from the ground by an angle driver, links 3
    !> and 12 tied by a dot-1 row (both markers on the chain), link 10 holding
    !> body 2 (spherical): 13 rows. Force elements: a spring–damper from link
    !> 13 to body 2, bushings from link 6 to the ground and between links 3
    !> and 12. q = (bodies 1:14, chain 15:31).
    subroutine make_long(derivatives, sys, q0, status)
        character(len=*), intent(in) :: derivatives
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: q0(long_nq)
        type(status_t), intent(out) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(long_links)
        type(marker_t) :: m(12)
        type(driver_t) :: drive
        type(force_element_t) :: el(3)
        real(wp) :: u(3, 3), axis(3)
        integer :: i
        do i = 1, long_links
            axis = [sin(0.7_wp * i), 0.3_wp, cos(0.7_wp * i)]
            b(i)%parent = i - 1
            if (i == long_spherical) b(i)%joint = chain_joint_spherical
            if (i > 1) b(i)%joint_position = [0.25_wp, 0.0_wp, 0.0_wp]
            b(i)%axis = axis / norm2(axis)
            b(i)%centre = [0.12_wp, 0.01_wp * i, 0.0_wp]
            b(i)%mass = 0.4_wp + 0.05_wp * i
            b(i)%inertia = 0.01_wp * identity
        end do
        chain = new_rigid_chain(b, status, gravity=g_earth)
        if (.not. status%ok()) return
        u = rotation_matrix(quat_from_axis_angle([0.6_wp, 0.0_wp, 0.8_wp], 0.4_wp))
        m(1) = marker_t(0, [0.25_wp, 0.02_wp, 0.0_wp], u, chain=1, link=long_links)
        m(2) = marker_t(1, [-0.1_wp, 0.05_wp, 0.0_wp], transpose(u))
        m(3) = marker_t(0, [0.1_wp, 0.0_wp, 0.03_wp], chain=1, link=5)
        m(4) = marker_t(0, [0.5_wp, 0.2_wp, 0.1_wp])
        m(5) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp], u)
        m(6) = marker_t(0, [0.1_wp, 0.0_wp, 0.0_wp], transpose(u), chain=1, link=9)
        m(7) = marker_t(0, [0.05_wp, 0.02_wp, 0.0_wp], chain=1, link=3)
        m(8) = marker_t(0, [0.1_wp, -0.03_wp, 0.02_wp], u, chain=1, link=12)
        m(9) = marker_t(0, [0.2_wp, 0.0_wp, -0.02_wp], chain=1, link=10)
        m(10) = marker_t(2, [0.0_wp, 0.1_wp, 0.0_wp])
        m(11) = marker_t(0, [0.15_wp, -0.02_wp, 0.04_wp], transpose(u), chain=1, link=13)
        m(12) = marker_t(0, [0.05_wp, 0.03_wp, -0.01_wp], u, chain=1, link=6)
        el(1) = force_element_t(force_spring_damper, 11, 10, reference=0.3_wp, &
            stiffness=[40.0_wp, 0.0_wp, 8.0_wp, 0.0_wp, 0.0_wp], damping=0.5_wp)
        el(2) = force_element_t(force_bushing, 12, 4)
        el(3) = force_element_t(force_bushing, 7, 8)
        do i = 1, 6
            el(2)%stiffness6(i, i) = 30.0_wp
            el(2)%damping6(i, i) = 1.5_wp
            el(3)%stiffness6(i, i) = 20.0_wp
            el(3)%damping6(i, i) = 0.8_wp
        end do
        el(2)%stiffness6(1, 5) = 6.0_wp
        el(3)%stiffness6(4, 2) = -3.0_wp
        drive%poly(0:2) = [0.3_wp, 0.8_wp, -0.2_wp]
        drive%amplitude = 0.1_wp
        drive%frequency = 3.0_wp
        sys = new_mbs_system([rigid_body_t(0.7_wp, 0.02_wp * identity), &
                              rigid_body_t(0.3_wp, 0.01_wp * identity)], m, &
            [mbs_joint_t(joint_revolute, 1, 2), mbs_joint_t(joint_spherical, 3, 4), &
             mbs_joint_t(joint_primitive, 5, 6, primitive_angle_driver, 1, 1, drive), &
             mbs_joint_t(joint_primitive, 7, 8, primitive_dot1, 1, 2), &
             mbs_joint_t(joint_spherical, 9, 10)], &
            gravity=g_earth, constraint_derivatives=derivatives, status=status, chains=[chain], &
            elements=el)
        if (.not. status%ok()) return
        q0(1:7) = [3.2_wp, 0.4_wp, -0.2_wp, 0.9_wp, 0.1_wp, -0.3_wp, 0.2_wp]
        q0(8:14) = [2.4_wp, -0.3_wp, 0.5_wp, 0.8_wp, -0.2_wp, 0.1_wp, 0.5_wp]
        q0(15:) = [(0.3_wp * sin(1.3_wp * i), i = 1, long_links + 3)]
        call unit_quaternions(q0)
    end subroutine make_long

    !> The long system's quaternions (bodies 1, 2; the chain's link 7) at unit length.
    pure subroutine unit_quaternions(q)
        real(wp), intent(inout) :: q(:)
        integer, parameter :: first(3) = [4, 11, 14 + long_spherical]
        integer :: k
        do k = 1, size(first)
            q(first(k):first(k) + 3) = q(first(k):first(k) + 3) / norm2(q(first(k):first(k) + 3))
        end do
    end subroutine unit_quaternions

    !> A random state of the long system near q0 (unit quaternions).
    subroutine random_long_state(q0, seed, q, v)
        real(wp), intent(in) :: q0(long_nq)
        integer(i8), intent(inout) :: seed
        real(wp), intent(out) :: q(long_nq), v(long_nv)
        call fill_random(q, seed, -0.2_wp, 0.2_wp)
        q = q0 + q
        call unit_quaternions(q)
        call fill_random(v, seed, -1.0_wp, 1.0_wp)
    end subroutine random_long_state

    !> Markers on a chain of 17 coordinates (make_long): 'ad' and 'ad_full'
    !> equal 'analytic' (1e-12); c_q, c_t, γ against central differences, G
    !> against c_q T; the second derivatives ∂(G w)/∂q, ∂(Gᵀλ)/∂q, ∂c_t/∂q,
    !> ∂γ/∂q, ∂γ/∂v against central differences of the first (1e-6 relative).
    subroutine test_long_derivatives(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: hand, ad, full
        type(status_t) :: status
        real(wp) :: q0(long_nq), q(long_nq), v(long_nv), worst, first, second
        integer(i8) :: seed
        integer :: trial
        call make_long('analytic', hand, q0, status)
        if (status%ok()) call make_long('ad', ad, q0, status)
        if (status%ok()) call make_long('ad_full', full, q0, status)
        call check(error, status%ok() .and. hand%nq == long_nq .and. hand%nv == long_nv .and. &
                   hand%nc == 13, 'long systems: ' // status%text())
        if (allocated(error)) return
        seed = 57_i8
        worst = 0.0_wp
        first = 0.0_wp
        second = 0.0_wp
        do trial = 1, 3
            call random_long_state(q0, seed, q, v)
            worst = max(worst, ad_deviation(hand, ad, 0.2_wp, q, v, status), &
                        ad_deviation(hand, full, 0.2_wp, q, v, status))
            first = max(first, first_deviation(hand, 0.2_wp, q, v, status))
            second = max(second, second_deviation(hand, 0.2_wp, q, v, seed, status))
        end do
        print '(4x,a,es9.2)', 'long chain markers: AD (ad, ad_full) vs analytic ', worst
        print '(4x,a,es9.2)', 'long chain markers: c_q, G, c_t, gamma vs differences ', first
        print '(4x,a,es9.2)', 'long chain markers: second derivatives vs differences ', second
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, worst <= 1.0e-12_wp, 'AD differs from analytic')
        call check(error, first <= 1.0e-6_wp, 'first derivatives differ from differences')
        call check(error, second <= 1.0e-6_wp, 'second derivatives differ from differences')
    end subroutine test_long_derivatives

    !> c_q, c_t and γ against central differences, G against c_q T (largest
    !> deviation relative to the largest entry).
    real(wp) function first_deviation(sys, t, q, v, status) result(worst)
        type(mbs_system_t), intent(inout) :: sys
        real(wp), intent(in) :: t, q(:), v(:)
        type(status_t), intent(inout) :: status
        real(wp), parameter :: h = 1.0e-6_wp
        real(wp) :: cq(sys%nc, sys%nq), fd(sys%nc, sys%nq), g(sys%nc, sys%nv), &
            tm(sys%nq, sys%nv), cp(sys%nc), cm(sys%nc), ct(sys%nc), gam(sys%nc), &
            qp(sys%nq), unit(sys%nv), qdot(sys%nq)
        integer :: j
        call sys%constraint_position_jacobian(t, q, cq, status)
        do j = 1, sys%nq
            qp = q
            qp(j) = q(j) + h
            call sys%constraint(t, qp, cp, status)
            qp(j) = q(j) - h
            call sys%constraint(t, qp, cm, status)
            fd(:, j) = (cp - cm) / (2 * h)
        end do
        worst = maxval(abs(cq - fd)) / maxval(abs(cq))
        do j = 1, sys%nv
            unit = 0.0_wp
            unit(j) = 1.0_wp
            call sys%kinematics(t, q, unit, tm(:, j), status)
        end do
        call sys%constraint_jacobian(t, q, g, status)
        worst = max(worst, maxval(abs(g - matmul(cq, tm))) / maxval(abs(g)))
        call sys%constraint_time_derivative(t, q, ct, status)
        call sys%constraint(t + h, q, cp, status)
        call sys%constraint(t - h, q, cm, status)
        worst = max(worst, maxval(abs(ct - (cp - cm) / (2 * h))) / maxval(abs(ct)))
        ! γ = d/ds (G v + c_t) along q + s T v, t + s (c'' = G v' + γ)
        call sys%constraint_curvature(t, q, v, gam, status)
        call sys%kinematics(t, q, v, qdot, status)
        cp = rate(q + h * qdot, t + h)
        cm = rate(q - h * qdot, t - h)
        worst = max(worst, maxval(abs(gam - (cp - cm) / (2 * h))) / maxval(abs(gam)))
    contains
        function rate(qs, ts) result(r)
            real(wp), intent(in) :: qs(:), ts
            real(wp) :: r(sys%nc)
            call sys%constraint_jacobian(ts, qs, g, status)
            call sys%constraint_time_derivative(ts, qs, r, status)
            r = r + matmul(g, v)
        end function rate
    end function first_deviation

    !> The system's second derivatives (AD through the windows) against
    !> central differences of its first derivatives, at random w and λ.
    real(wp) function second_deviation(sys, t, q, v, seed, status) result(worst)
        type(mbs_system_t), intent(inout) :: sys
        real(wp), intent(in) :: t, q(:), v(:)
        integer(i8), intent(inout) :: seed
        type(status_t), intent(inout) :: status
        real(wp), parameter :: h = 1.0e-6_wp
        real(wp) :: w(sys%nv), lambda(sys%nc), gwq(sys%nc, sys%nq), gtlq(sys%nv, sys%nq), &
            ctq(sys%nc, sys%nq), yq(sys%nc, sys%nq), yv(sys%nc, sys%nv), &
            f1(sys%nc, sys%nq), f2(sys%nv, sys%nq), f3(sys%nc, sys%nq), f4(sys%nc, sys%nq), &
            f5(sys%nc, sys%nv), gp(sys%nc, sys%nv), gm(sys%nc, sys%nv), cp(sys%nc), &
            cm(sys%nc), yp(sys%nc), ym(sys%nc), qp(sys%nq), qm(sys%nq), vp(sys%nv)
        integer :: j
        call fill_random(w, seed, -1.0_wp, 1.0_wp)
        call fill_random(lambda, seed, -1.0_wp, 1.0_wp)
        call sys%constraint_jacobian_derivatives(t, q, w, lambda, gwq, gtlq, status)
        call sys%constraint_time_derivative_jacobian(t, q, ctq, status)
        call sys%constraint_curvature_derivatives(t, q, v, yq, yv, status)
        do j = 1, sys%nq
            qp = q
            qp(j) = q(j) + h
            qm = q
            qm(j) = q(j) - h
            call sys%constraint_jacobian(t, qp, gp, status)
            call sys%constraint_jacobian(t, qm, gm, status)
            f1(:, j) = matmul(gp - gm, w) / (2 * h)
            f2(:, j) = matmul(lambda, gp - gm) / (2 * h)
            call sys%constraint_time_derivative(t, qp, cp, status)
            call sys%constraint_time_derivative(t, qm, cm, status)
            f3(:, j) = (cp - cm) / (2 * h)
            call sys%constraint_curvature(t, qp, v, yp, status)
            call sys%constraint_curvature(t, qm, v, ym, status)
            f4(:, j) = (yp - ym) / (2 * h)
        end do
        do j = 1, sys%nv
            vp = v
            vp(j) = v(j) + h
            call sys%constraint_curvature(t, q, vp, yp, status)
            vp(j) = v(j) - h
            call sys%constraint_curvature(t, q, vp, ym, status)
            f5(:, j) = (yp - ym) / (2 * h)
        end do
        worst = max(maxval(abs(gwq - f1)) / maxval(abs(f1)), &
                    maxval(abs(gtlq - f2)) / maxval(abs(f2)), &
                    maxval(abs(ctq - f3)) / maxval(abs(f3)), &
                    maxval(abs(yq - f4)) / maxval(abs(f4)), &
                    maxval(abs(yv - f5)) / maxval(abs(f5)))
    end function second_deviation

    !> The long system's formulations (index 1, 2, 3 and GGL; accelerations
    !> unknown): ∂F/∂y against central differences of F (1e-6 relative),
    !> and the sparse path's ∂F/∂y equal to the dense one's (1e-13).
    subroutine test_long_formulations(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: forms(4) = [formulation_index1, formulation_index2, &
                                          formulation_index3, formulation_ggl]
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dense, sparse
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp) :: q0(long_nq), fd_dev, sparse_dev
        real(wp), allocatable :: y(:), jac(:, :), jfd(:, :), js(:, :)
        integer(i8) :: seed
        integer :: k
        call make_long('analytic', sys, q0, status)
        call check(error, status%ok(), 'long system: ' // status%text())
        if (allocated(error)) return
        seed = 71_i8
        fd_dev = 0.0_wp
        sparse_dev = 0.0_wp
        do k = 1, size(forms)
            dense = new_formulation(sys, forms(k), q0, status=status)
            if (status%ok()) sparse = new_formulation(sys, forms(k), q0, status=status, &
                                                      sparse=.true.)
            call check(error, status%ok() .and. sparse%is_sparse(), 'formulations: ' // &
                       status%text())
            if (allocated(error)) return
            allocate (y(dense%n), jac(dense%n, dense%n), jfd(dense%n, dense%n), &
                      js(dense%n, dense%n))
            call fill_random(y, seed, -0.1_wp, 0.1_wp)
            y(1:long_nq) = y(1:long_nq) + q0
            call unit_quaternions(y(1:long_nq))
            call dense%jacobian_dense(0.0_wp, y, jac, status)
            call difference_jacobian(dense, y, jfd, status)
            call sparse%jacobian_pattern(pattern, status)
            call sparse%jacobian_sparse(0.0_wp, y, pattern%values, status)
            call pattern%to_dense(js)
            call check(error, status%ok(), 'jacobians: ' // status%text())
            if (allocated(error)) return
            fd_dev = max(fd_dev, maxval(abs(jac - jfd)) / maxval(abs(jac)))
            sparse_dev = max(sparse_dev, maxval(abs(jac - js)) / maxval(abs(jac)))
            deallocate (y, jac, jfd, js)
        end do
        print '(4x,a,es9.2)', 'long chain formulations: Jacobian vs differences ', fd_dev
        print '(4x,a,es9.2)', 'long chain formulations: sparse vs dense Jacobian ', sparse_dev
        call check(error, fd_dev <= 1.0e-6_wp, 'Jacobian differs from differences')
        call check(error, sparse_dev <= 1.0e-13_wp, 'sparse Jacobian differs from dense')
    end subroutine test_long_formulations

    !> The force elements on markers of the long chain (make_long; 'analytic'
    !> laws): ∂f/∂q, ∂f/∂v against central differences (1e-7 relative), the
    !> sparse blocks equal to the dense (1e-14), 'ad' equal to 'analytic'
    !> (1e-13), at two random states.
    subroutine test_long_elements(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(mechanical_patterns_t) :: patterns
        type(status_t) :: status
        real(wp) :: q0(long_nq), q(long_nq), v(long_nv)
        integer(i8) :: seed
        integer :: trial
        call make_long('analytic', sys, q0, status)
        if (status%ok()) call sys%derivative_patterns(patterns, status)
        call check(error, status%ok() .and. sys%element_count() == 3, 'long system: ' // &
                   status%text())
        if (allocated(error)) return
        seed = 93_i8
        do trial = 1, 2
            call random_long_state(q0, seed, q, v)
            call compare_derivatives(error, sys, patterns, q, v, 'long chain elements')
            if (allocated(error)) return
            call compare_with_ad(error, sys, q, v, 'long chain elements')
            if (allocated(error)) return
        end do
    end subroutine test_long_elements

    !> A closed loop through a long chain: 10 revolute links with turning
    !> axes (10 coordinates) from the ground, the tip held on the ground by a
    !> spherical joint, under gravity, undamped (7 degrees of freedom).
    !> RADAU5 (GGL) over 1 s at rtol = atol = 1e-5 and 1e-8: the energy
    !> drift (relative to m g L) shrinks with the tolerance and is below 1e-6
    !> at 1e-8; the constraint drift stays below 1e-9.
    subroutine test_long_loop(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: n = 10
        real(wp), parameter :: tolerances(2) = [1.0e-5_wp, 1.0e-8_wp]
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: b(n)
        type(marker_t) :: m(2)
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q0(n), t, e0, e1, scale, drift(2), c(3), a(3, 3)
        real(wp), allocatable :: y(:), yp(:)
        integer :: i, k
        do i = 1, n
            b(i)%parent = i - 1
            if (i > 1) b(i)%joint_position = [0.3_wp, 0.0_wp, 0.0_wp]
            b(i)%axis = [0.0_wp, sin(0.6_wp * i), cos(0.6_wp * i)]
            b(i)%centre = [0.15_wp, 0.0_wp, 0.0_wp]
            b(i)%mass = 1.0_wp
            b(i)%inertia = 0.01_wp * identity
        end do
        chain = new_rigid_chain(b, status, gravity=g_earth)
        m(1) = marker_t(0, [0.3_wp, 0.0_wp, 0.0_wp], chain=1, link=n)
        m(2) = marker_t(0)
        q0 = [(0.4_wp * cos(0.9_wp * i), i = 1, n)]
        ! the ground point where the tip is at q0
        if (status%ok()) sys = new_mbs_system([rigid_body_t ::], m, [mbs_joint_t ::], &
            gravity=g_earth, status=status, chains=[chain])
        if (status%ok()) call sys%marker_pose(1, q0, m(2)%position, a)
        if (status%ok()) sys = new_mbs_system([rigid_body_t ::], m, &
            [mbs_joint_t(joint_spherical, 1, 2)], gravity=g_earth, status=status, chains=[chain])
        call check(error, status%ok() .and. sys%nq == n .and. sys%nc == 3, 'loop: ' // &
                   status%text())
        if (allocated(error)) return
        scale = n * 1.0_wp * norm2(g_earth) * 0.3_wp * n
        do k = 1, size(tolerances)
            gen = new_formulation(sys, formulation_ggl, q0, status=status)
            allocate (y(gen%n), yp(gen%n), source=0.0_wp)
            y(1:n) = q0
            call gen%consistent_initial(0.0_wp, y, yp, status)
            e0 = sys%energy(y(1:n), y(gen%offset(block_v) + 1:gen%offset(block_v) + n))
            options%rtol = tolerances(k)
            options%atol = tolerances(k)
            t = 0.0_wp
            call solver%integrate(gen, t, y, 1.0_wp, options, stats, status)
            call check(error, status%ok(), 'run: ' // status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:n), y(gen%offset(block_v) + 1:gen%offset(block_v) + n))
            drift(k) = abs(e1 - e0) / scale
            call sys%constraint(t, y(1:n), c, status)
            print '(4x,a,es8.1,a,i0,a,es9.2,a,es9.2)', 'long chain loop: rtol ', &
                tolerances(k), ' NST=', stats%nst, ', energy drift / mgL ', drift(k), &
                ', |c| ', maxval(abs(c))
            call check(error, maxval(abs(c)) <= 1.0e-9_wp, 'constraint drift')
            deallocate (y, yp)
            if (allocated(error)) return
        end do
        call check(error, drift(2) < drift(1) .and. drift(2) <= 1.0e-6_wp, 'energy drift')
    end subroutine test_long_loop
end module test_chain_coupling
