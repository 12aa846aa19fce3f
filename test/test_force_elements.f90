!> Force elements between markers (src/mbs/force_element.f90,
!> src/mbs/system_elements.f90): ∂f/∂q and ∂f/∂v of every kind against
!> central differences, the hand-coded laws (force_element_tangent, the
!> default 'analytic') against the dual-number laws ('ad'), dense against
!> sparse; equal and opposite wrenches;
!> a spring–mass oscillation against its analytic motion; an undamped
!> pendulum on a torsion spring carrying a body on a nonlinear spring
!> conserves energy to tolerance level, damped it dissipates; coinciding
!> spring markers and bad elements are refused with a message.
module test_force_elements
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_mechanical_problem, only: mechanical_patterns_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_joint, only: joint_revolute
    use flexmbs_mbs_driver, only: driver_t
    use flexmbs_mbs_force_element, only: force_element_t, force_spring_damper, &
        force_rotational, force_bushing, force_applied
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        constraint_derivatives_ad
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_joint_revolute, chain_joint_spherical
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2, &
        formulation_ggl
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_mexax, only: mexax_t
    use mbs_random, only: random_state_t, random_vector, random_quaternion
    use test_mbs_system, only: test_body, random_state, integrate, rel_err
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_force_elements, compare_derivatives, compare_with_ad

contains

    function collect_force_elements() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('derivatives_vs_differences', test_derivatives), &
                 new_test('sparse_equals_dense', test_sparse_dense), &
                 new_test('chain_markers_derivatives', test_chain_markers), &
                 new_test('node_markers_derivatives', test_node_markers), &
                 new_test('equal_and_opposite', test_equal_opposite), &
                 new_test('spring_mass_frequency', test_spring_mass), &
                 new_test('undamped_energy_conserved', test_energy), &
                 new_test('undamped_energy_other_solvers', test_energy_solvers), &
                 new_test('damping_dissipates', test_dissipation), &
                 new_test('coinciding_spring_markers', test_zero_length), &
                 new_test('bad_elements', test_bad_elements)]
    end function collect_force_elements

    ! ---------------------------------------------------------------- helpers

    !> Two bodies and the ground, eight random markers and an element of
    !> every kind (nonlinear and linear springs, torsion, two bushings with
    !> full K and C, loads in the world and in a marker frame).
    function all_elements_system(rng, status) result(sys)
        type(random_state_t), intent(inout) :: rng
        type(status_t), intent(out) :: status
        type(mbs_system_t) :: sys
        type(marker_t) :: markers(8)
        type(force_element_t) :: el(7)
        integer, parameter :: bodies_of(8) = [0, 1, 1, 2, 1, 2, 0, 2]
        real(wp) :: a(6, 6)
        integer :: k
        do k = 1, 8
            markers(k)%body = bodies_of(k)
            markers(k)%position = random_vector(rng, 3, -0.5_wp, 0.5_wp)
            markers(k)%axes = rotation_matrix(random_quaternion(rng))
        end do
        el(1) = force_element_t(force_spring_damper, 1, 2, reference=0.3_wp, &
            stiffness=[50.0_wp, 20.0_wp, 30.0_wp, 0.0_wp, 5.0_wp], damping=2.0_wp)
        el(2) = force_element_t(force_spring_damper, 3, 4, reference=0.8_wp, &
            stiffness=[40.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=1.5_wp)
        el(3) = force_element_t(force_rotational, 5, 6, reference=0.2_wp, &
            stiffness=[7.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=0.4_wp)
        do k = 1, 6
            a(:, k) = random_vector(rng, 6, -1.0_wp, 1.0_wp)
        end do
        el(4) = force_element_t(force_bushing, 7, 8)
        el(4)%stiffness6 = 100.0_wp * matmul(transpose(a), a)
        el(4)%damping6 = 3.0_wp * a
        el(5) = force_element_t(force_bushing, 3, 6)
        el(5)%stiffness6 = 30.0_wp * a
        el(5)%damping6 = matmul(transpose(a), a)
        el(6) = force_element_t(force_applied, 4, 0, world_frame=.false., &
            force=[1.0_wp, -2.0_wp, 0.5_wp], torque=[0.3_wp, 0.1_wp, -0.2_wp], &
            driver=driver_t([1.0_wp, 0.5_wp, 0.0_wp, 0.0_wp], 2.0_wp, 3.0_wp, 0.1_wp))
        el(7) = force_element_t(force_applied, 2, 0, force=[0.0_wp, 0.0_wp, -3.0_wp], &
            torque=[1.0_wp, 0.0_wp, 0.0_wp], driver=driver_t(amplitude=1.0_wp, &
            frequency=5.0_wp))
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp), test_body(2.0_wp, 0.5_wp)], &
                             markers, [mbs_joint_t ::], gravity=[0.0_wp, 0.0_wp, -9.81_wp], &
                             status=status, elements=el)
    end function all_elements_system

    !> Central differences of f in q (wrt_q) or v, column by column.
    subroutine difference_columns(sys, q, v, wrt_q, d, status)
        type(mbs_system_t), intent(inout) :: sys
        real(wp), intent(in) :: q(:), v(:)
        logical, intent(in) :: wrt_q
        real(wp), intent(out) :: d(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: x(max(size(q), size(v))), fp(size(v)), fm(size(v)), h
        integer :: j, n
        n = merge(size(q), size(v), wrt_q)
        do j = 1, n
            if (wrt_q) then
                x(1:n) = q
            else
                x(1:n) = v
            end if
            h = 1.0e-6_wp * max(1.0_wp, abs(x(j)))
            x(j) = x(j) + h
            call evaluate(fp)
            x(j) = x(j) - 2 * h
            call evaluate(fm)
            d(:, j) = (fp - fm) / (2 * h)
        end do
    contains
        subroutine evaluate(f)
            real(wp), intent(out) :: f(:)
            if (wrt_q) then
                call sys%forces(0.3_wp, x(1:n), v, f, status)
            else
                call sys%forces(0.3_wp, q, x(1:n), f, status)
            end if
        end subroutine evaluate
    end subroutine difference_columns

    !> ∂f/∂q, ∂f/∂v against central differences (1e-7 relative), the sparse
    !> blocks against the dense ones (1e-14); `what` labels the message.
    subroutine compare_derivatives(error, sys, patterns, q, v, what)
        type(error_t), allocatable, intent(inout) :: error
        type(mbs_system_t), intent(inout) :: sys
        type(mechanical_patterns_t), intent(in) :: patterns
        real(wp), intent(in) :: q(:), v(:)
        character(len=*), intent(in) :: what
        type(status_t) :: status
        real(wp) :: fq(size(v), size(q)), fv(size(v), size(v)), dq(size(v), size(q)), &
            dv(size(v), size(v)), sq(size(v), size(q)), sv(size(v), size(v)), eq, ev, es
        character(len=120) :: msg
        call sys%force_derivatives(0.3_wp, q, v, fq, fv, status)
        call difference_columns(sys, q, v, .true., dq, status)
        call difference_columns(sys, q, v, .false., dv, status)
        call sparse_as_dense(sys, patterns, 0.3_wp, q, v, sq, sv, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        eq = rel_err(fq, dq)
        ev = rel_err(fv, dv)
        es = max(rel_err(sq, fq), rel_err(sv, fv))
        write (msg, '(a,3(a,es9.2))') what, ': df/dq ', eq, ', df/dv ', ev, &
            ', sparse - dense ', es
        print '(a)', '    ' // trim(msg)
        call check(error, eq < 1.0e-7_wp .and. ev < 1.0e-7_wp .and. es < 1.0e-14_wp, trim(msg))
    end subroutine compare_derivatives

    !> The hand-coded laws ('analytic', sys's default) against the dual-number
    !> laws ('ad', a copy of sys): f, ∂f/∂q and ∂f/∂v equal to round-off.
    subroutine compare_with_ad(error, sys, q, v, what)
        type(error_t), allocatable, intent(inout) :: error
        type(mbs_system_t), intent(inout) :: sys
        real(wp), intent(in) :: q(:), v(:)
        character(len=*), intent(in) :: what
        type(mbs_system_t) :: ad
        type(status_t) :: status
        real(wp) :: f(size(v)), fa(size(v)), fq(size(v), size(q)), fv(size(v), size(v)), &
            aq(size(v), size(q)), av(size(v), size(v)), e(3)
        character(len=120) :: msg
        ad = sys
        ad%derivatives = constraint_derivatives_ad
        call sys%forces(0.3_wp, q, v, f, status)
        if (status%ok()) call ad%forces(0.3_wp, q, v, fa, status)
        if (status%ok()) call sys%force_derivatives(0.3_wp, q, v, fq, fv, status)
        if (status%ok()) call ad%force_derivatives(0.3_wp, q, v, aq, av, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        e = [maxval(abs(f - fa)) / maxval(abs(fa)), rel_err(fq, aq), rel_err(fv, av)]
        write (msg, '(a,3(a,es9.2))') what, ': analytic - AD: f ', e(1), ', df/dq ', e(2), &
            ', df/dv ', e(3)
        print '(a)', '    ' // trim(msg)
        call check(error, all(e < 1.0e-13_wp), trim(msg))
    end subroutine compare_with_ad

    !> The sparse ∂f/∂q and ∂f/∂v on their patterns, as dense arrays.
    subroutine sparse_as_dense(sys, patterns, t, q, v, sq, sv, status)
        type(mbs_system_t), intent(inout) :: sys
        type(mechanical_patterns_t), intent(in) :: patterns
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: sq(:, :), sv(:, :)
        type(status_t), intent(inout) :: status
        type(csc_matrix_t) :: pq, pv
        pq = patterns%force_q
        pv = patterns%force_v
        call sys%force_derivatives_sparse(t, q, v, pq%values, pv%values, status)
        call pq%to_dense(sq)
        call pv%to_dense(sv)
    end subroutine sparse_as_dense

    ! ------------------------------------------------------------------ tests

    !> ∂f/∂q and ∂f/∂v (dense binding: bodies plus elements) against central
    !> differences of f at three random states (relative to the largest entry).
    subroutine test_derivatives(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp) :: q(14), v(12), fq(12, 14), fv(12, 12), dq(12, 14), dv(12, 12), eq, ev, &
            worst
        integer :: trial
        character(len=120) :: msg
        sys = all_elements_system(rng, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        worst = 0.0_wp
        do trial = 1, 3
            call random_state(rng, 2, q, v)
            call sys%force_derivatives(0.3_wp, q, v, fq, fv, status)
            call difference_columns(sys, q, v, .true., dq, status)
            call difference_columns(sys, q, v, .false., dv, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            eq = rel_err(fq, dq)
            ev = rel_err(fv, dv)
            worst = max(worst, eq, ev)
            write (msg, '(a,i0,2(a,es9.2))') 'state ', trial, ': df/dq ', eq, ', df/dv ', ev
            print '(a)', '    ' // trim(msg)
            call check(error, eq < 1.0e-7_wp .and. ev < 1.0e-7_wp, trim(msg))
            if (allocated(error)) return
            call compare_with_ad(error, sys, q, v, 'state ' // achar(iachar('0') + trial))
            if (allocated(error)) return
        end do
        ! the elements contribute: without them the blocks differ
        call check(error, maxval(abs(fq(1:6, 8:14))) > 1.0_wp, &
                   'the bodies are coupled through df/dq')
    end subroutine test_derivatives

    !> The sparse ∂f/∂q, ∂f/∂v (on the patterns) equal the dense ones.
    subroutine test_sparse_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(mechanical_patterns_t) :: patterns
        real(wp) :: q(14), v(12), fq(12, 14), fv(12, 12), sq(12, 14), sv(12, 12)
        character(len=120) :: msg
        sys = all_elements_system(rng, status)
        if (status%ok()) call sys%derivative_patterns(patterns, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        call random_state(rng, 2, q, v)
        call sys%force_derivatives(1.1_wp, q, v, fq, fv, status)
        call sparse_as_dense(sys, patterns, 1.1_wp, q, v, sq, sv, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        write (msg, '(2(a,es9.2))') 'sparse - dense: df/dq ', rel_err(sq, fq), &
            ', df/dv ', rel_err(sv, fv)
        print '(a)', '    ' // trim(msg)
        call check(error, rel_err(sq, fq) < 1.0e-14_wp .and. rel_err(sv, fv) < 1.0e-14_wp, &
                   trim(msg))
    end subroutine test_sparse_dense

    !> Elements on the links of a chain in relative coordinates (a revolute
    !> link and a spherical one: quaternion coordinates, nq ≠ nv), between
    !> two links of the same chain, and to a rigid body: ∂f/∂q and ∂f/∂v
    !> against central differences, sparse equal to dense.
    subroutine test_chain_markers(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(rigid_chain_t) :: chain
        type(chain_body_t) :: links(2)
        type(marker_t) :: m(6)
        type(force_element_t) :: el(4)
        type(mechanical_patterns_t) :: patterns
        real(wp), parameter :: eye(3, 3) = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1] * 1.0_wp, [3, 3])
        real(wp) :: q(12), v(10)
        integer :: k
        links(1) = chain_body_t(0, chain_joint_revolute, [0.0_wp, 0.0_wp, 0.0_wp], eye, &
            [0.0_wp, 0.0_wp, 1.0_wp], [0.3_wp, 0.0_wp, 0.0_wp], 1.0_wp, 0.02_wp * eye)
        links(2) = chain_body_t(1, chain_joint_spherical, [0.6_wp, 0.0_wp, 0.0_wp], eye, &
            [0.0_wp, 0.0_wp, 1.0_wp], [0.2_wp, 0.1_wp, 0.0_wp], 0.5_wp, 0.01_wp * eye)
        chain = new_rigid_chain(links, status, gravity=[0.0_wp, -9.81_wp, 0.0_wp])
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        do k = 1, 6
            m(k)%position = random_vector(rng, 3, -0.3_wp, 0.3_wp)
            m(k)%axes = rotation_matrix(random_quaternion(rng))
        end do
        m(1)%body = 0
        m(2)%chain = 1
        m(2)%link = 1
        m(3)%chain = 1
        m(3)%link = 2
        m(4)%body = 1
        m(5)%chain = 1
        m(5)%link = 2
        m(6)%chain = 1
        m(6)%link = 1
        el(1) = force_element_t(force_bushing, 1, 2)
        el(1)%stiffness6 = 50.0_wp * eye6()
        el(1)%damping6 = 2.0_wp * eye6()
        el(1)%stiffness6(1, 5) = 7.0_wp
        el(2) = force_element_t(force_spring_damper, 3, 4, reference=0.2_wp, &
            stiffness=[30.0_wp, 0.0_wp, 10.0_wp, 0.0_wp, 0.0_wp], damping=0.7_wp)
        el(3) = force_element_t(force_rotational, 4, 5, reference=-0.1_wp, &
            stiffness=[4.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=0.3_wp)
        el(4) = force_element_t(force_spring_damper, 6, 5, reference=0.1_wp, &
            stiffness=[20.0_wp, 5.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=0.2_wp)
        sys = new_mbs_system([test_body(1.0_wp, 0.1_wp)], m, [mbs_joint_t ::], &
            gravity=[0.0_wp, -9.81_wp, 0.0_wp], status=status, chains=[chain], elements=el)
        if (status%ok()) call sys%derivative_patterns(patterns, status)
        call check(error, status%ok() .and. sys%nq == 12 .and. sys%nv == 10, status%text())
        if (allocated(error)) return
        q(1:3) = random_vector(rng, 3, -1.0_wp, 1.0_wp)
        q(4:7) = random_quaternion(rng)
        q(8) = 0.7_wp
        q(9:12) = random_quaternion(rng)
        v = random_vector(rng, 10, -1.0_wp, 1.0_wp)
        call compare_derivatives(error, sys, patterns, q, v, 'chain')
        if (.not. allocated(error)) call compare_with_ad(error, sys, q, v, 'chain')
    contains
        pure function eye6() result(a)
            real(wp) :: a(6, 6)
            integer :: i
            a = 0.0_wp
            do i = 1, 6
                a(i, i) = 1.0_wp
            end do
        end function eye6
    end subroutine test_chain_markers

    !> Elements on node markers of a soft bar (2 x 1 x 1 hex8, free): a
    !> spring–damper from a rigid body to a node, one between two nodes and a
    !> load on a node: ∂f/∂q, ∂f/∂v (the bar's own tangents included)
    !> against central differences, sparse equal to dense. A rotational
    !> element or a bushing on a node marker is refused.
    subroutine test_node_markers(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(neo_hooke_t) :: mat
        type(mesh_t) :: mesh
        type(flexible_body_t) :: bar(1)
        type(marker_t) :: m(4)
        type(mechanical_patterns_t) :: patterns
        real(wp), allocatable :: q(:), v(:)
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 5.0_wp, status)
        if (status%ok()) call box_mesh(mesh, hex8, [2, 1, 1], [0.4_wp, 0.05_wp, 0.05_wp], &
                                       status, origin=[0.3_wp, -0.025_wp, -0.025_wp])
        if (status%ok()) call new_flexible_body(bar(1), mesh, [mat], [integer ::], status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        m(1) = marker_t(1, [0.1_wp, 0.05_wp, 0.0_wp])
        m(2) = marker_t(0, flexible=1, node=1)
        m(3) = marker_t(0, flexible=1, node=12)
        m(4) = marker_t(0, flexible=1, node=5)
        sys = new_mbs_system([test_body(1.0_wp, 0.1_wp)], m, [mbs_joint_t ::], &
            status=status, flexible=bar, elements=[ &
            force_element_t(force_spring_damper, 1, 2, reference=0.1_wp, stiffness=[300.0_wp, &
                0.0_wp, 1.0e3_wp, 0.0_wp, 0.0_wp], damping=2.0_wp), &
            force_element_t(force_spring_damper, 2, 3, reference=0.3_wp, stiffness=[500.0_wp, &
                50.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=1.0_wp), &
            force_element_t(force_applied, 4, 0, force=[0.0_wp, 3.0_wp, 1.0_wp], &
                driver=driver_t(amplitude=2.0_wp, frequency=7.0_wp))])
        if (status%ok()) call sys%derivative_patterns(patterns, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        allocate (q(sys%nq), v(sys%nv))
        q(1:3) = random_vector(rng, 3, -0.1_wp, 0.1_wp)
        q(4:7) = random_quaternion(rng)
        q(8:) = bar(1)%free_positions() + random_vector(rng, sys%nq - 7, -0.005_wp, 0.005_wp)
        v = random_vector(rng, sys%nv, -0.5_wp, 0.5_wp)
        call compare_derivatives(error, sys, patterns, q, v, 'nodes')
        if (.not. allocated(error)) call compare_with_ad(error, sys, q, v, 'nodes')
        if (allocated(error)) return
        ! a node has no axes: a rotational element or a bushing on one is refused
        sys = new_mbs_system([test_body(1.0_wp, 0.1_wp)], m, [mbs_joint_t ::], &
            status=status, flexible=bar, elements=[force_element_t(force_rotational, 1, 2)])
        call check(error, .not. status%ok() .and. index(status%text(), 'marker 2 is a node &
            &marker (no rotation)') > 0, 'rotational on a node: ' // status%text())
        if (allocated(error)) return
        sys = new_mbs_system([test_body(1.0_wp, 0.1_wp)], m, [mbs_joint_t ::], &
            status=status, flexible=bar, elements=[force_element_t(force_bushing, 3, 1)])
        call check(error, .not. status%ok() .and. index(status%text(), 'marker 3 is a node &
            &marker (no rotation)') > 0, 'bushing on a node: ' // status%text())
    end subroutine test_node_markers

    !> Each two-marker element: F_i + F_j = 0 and the moments about the
    !> origin cancel; the loads are s(t) F.
    subroutine test_equal_opposite(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp) :: q(14), v(12), f(3, 2), n(3, 2), xi(3), xj(3), a(3, 3), s, moment(3)
        type(force_element_t) :: element
        integer :: ie
        character(len=120) :: msg
        sys = all_elements_system(rng, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        call random_state(rng, 2, q, v)
        do ie = 1, 5
            call sys%element_wrench(ie, 0.7_wp, q, v, f, n, status)
            element = sys%element_of(ie)
            call sys%marker_pose(element%marker_i, q, xi, a)
            call sys%marker_pose(element%marker_j, q, xj, a)
            moment = n(:, 1) + n(:, 2) + cross(xi, f(:, 1)) + cross(xj, f(:, 2))
            write (msg, '(a,i0,3(a,es9.2))') 'element ', ie, ': |F_i + F_j| ', &
                norm2(f(:, 1) + f(:, 2)), ', |moment| ', norm2(moment), ', |F| ', &
                norm2(f(:, 1)) + norm2(n(:, 1))
            call check(error, norm2(f(:, 1) + f(:, 2)) < 1.0e-12_wp * norm2(f(:, 1)) + &
                1.0e-14_wp .and. norm2(moment) < 1.0e-12_wp * (1.0_wp + norm2(f(:, 1)) + &
                norm2(n(:, 1))) .and. norm2(f(:, 1)) + norm2(n(:, 1)) > 1.0e-3_wp, trim(msg))
            if (allocated(error)) return
        end do
        ! load 7: s = sin(5 t) in the world frame
        call sys%element_wrench(7, 0.7_wp, q, v, f, n, status)
        s = sin(5.0_wp * 0.7_wp)
        call check(error, maxval(abs(f(:, 1) - s * [0.0_wp, 0.0_wp, -3.0_wp])) < 1.0e-14_wp &
            .and. maxval(abs(n(:, 1) - s * [1.0_wp, 0.0_wp, 0.0_wp])) < 1.0e-14_wp, &
            'applied load in the world frame')
    end subroutine test_equal_opposite

    !> A body (m = 2) on a linear spring (k = 50, ℓ₀ = 1) to the ground
    !> along x, released 0.1 stretched: x = 1 + 0.1 cos(5 t); no gravity.
    subroutine test_spring_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(marker_t) :: markers(2)
        real(wp) :: y(7 + 12), yp(7 + 12), err
        real(wp), parameter :: t_end = 2.0_wp, omega = 5.0_wp
        character(len=120) :: msg
        markers(1)%body = 0
        markers(2)%body = 1
        sys = new_mbs_system([test_body(2.0_wp, 0.1_wp)], markers, [mbs_joint_t ::], &
            gravity=[0.0_wp, 0.0_wp, 0.0_wp], status=status, elements=[force_element_t( &
            force_spring_damper, 1, 2, reference=1.0_wp, stiffness=[50.0_wp, 0.0_wp, &
            0.0_wp, 0.0_wp, 0.0_wp])])
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        y = 0.0_wp
        y(1) = 1.1_wp
        y(4) = 1.0_wp
        gen = new_formulation(sys, formulation_index2, y(1:7), status=status)
        if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
        if (status%ok()) call integrate(gen, y, t_end, 1.0e-9_wp, stats, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        err = abs(y(1) - (1.0_wp + 0.1_wp * cos(omega * t_end)))
        write (msg, '(a,es9.2,a,es9.2)') 'x(2) against 1 + 0.1 cos(5 t): ', err, &
            ', |y, z| ', norm2(y(2:3))
        print '(a)', '    ' // trim(msg)
        call check(error, err < 1.0e-6_wp .and. norm2(y(2:3)) < 1.0e-12_wp, trim(msg))
    end subroutine test_spring_mass

    !> Body 1 on a revolute joint to the ground about z, held by a torsion
    !> spring (φ₀ = 0.3); body 2 hangs from body 1 on a nonlinear spring; gravity −y.
    subroutine torsion_pendulum(sys, y, c)
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: y(:)
        real(wp), intent(in) :: c !! the dampers' coefficient
        type(status_t) :: status
        type(marker_t) :: markers(4)
        markers(1)%body = 0
        markers(2) = marker_t(1, [0.0_wp, 0.5_wp, 0.0_wp])
        markers(3) = marker_t(1, [0.1_wp, -0.5_wp, 0.05_wp])
        markers(4) = marker_t(2, [0.0_wp, 0.2_wp, 0.0_wp])
        sys = new_mbs_system([test_body(1.0_wp, 0.05_wp), test_body(0.7_wp, 0.03_wp)], &
            markers, [mbs_joint_t(joint_revolute, 1, 2)], &
            gravity=[0.0_wp, -9.81_wp, 0.0_wp], status=status, elements=[ &
            force_element_t(force_rotational, 1, 2, reference=0.3_wp, stiffness=[20.0_wp, &
                0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], damping=c), &
            force_element_t(force_spring_damper, 3, 4, reference=0.4_wp, stiffness=[60.0_wp, &
                0.0_wp, 200.0_wp, 0.0_wp, 0.0_wp], damping=c)])
        y = 0.0_wp
        y(4:7) = quat_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 1.0_wp)
        y(1:3) = -matmul(rotation_matrix(y(4:7)), markers(2)%position)
        y(11:14) = quat_from_axis_angle([1.0_wp, 0.0_wp, 0.0_wp], 0.4_wp)
        y(8:10) = y(1:3) + [0.2_wp, -1.1_wp, 0.1_wp]
        y(20) = 1.5_wp
        y(21:23) = [0.3_wp, -0.2_wp, 0.1_wp]
    end subroutine torsion_pendulum

    !> The torsion pendulum undamped: energy drift ≤ 50 rtol (measured 6 to
    !> 31 rtol: RADAU5's global error on the stiff nonlinear spring; the
    !> torsion spring alone drifts 0.02 rtol), at least 10 times smaller for
    !> each 100 times smaller tolerance.
    subroutine test_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(14 + 24 + 5), y0(14 + 24 + 5), yp(14 + 24 + 5), e0, e1, drift(3), scale
        real(wp), parameter :: rtols(3) = [1.0e-6_wp, 1.0e-8_wp, 1.0e-10_wp], t_end = 3.0_wp
        integer :: k
        character(len=120) :: msg
        call torsion_pendulum(sys, y0, 0.0_wp)
        do k = 1, 3
            y = y0
            gen = new_formulation(sys, formulation_index2, y(1:14), projection=.true., &
                                  status=status)
            gen%projection_rtol = rtols(k)
            gen%projection_atol = rtols(k)
            if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e0 = sys%energy(y(1:14), y(15:26))
            scale = abs(e0) + 1.0_wp
            call integrate(gen, y, t_end, rtols(k), stats, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:14), y(15:26))
            drift(k) = abs(e1 - e0) / scale
            write (msg, '(a,es8.1,a,es10.3,a,i0)') 'rtol ', rtols(k), ': energy drift ', &
                drift(k), ', steps ', stats%nst
            print '(a)', '    ' // trim(msg)
            call check(error, drift(k) <= 50.0_wp * rtols(k), trim(msg))
            if (allocated(error)) return
            if (k > 1) call check(error, drift(k) < 0.1_wp * drift(k - 1), &
                                  'the drift shrinks with the tolerance: ' // trim(msg))
            if (allocated(error)) return
        end do
    end subroutine test_energy

    !> The undamped torsion pendulum with DDASSL and IDA (GGL) and MEXAX
    !> (its projection) over 3 s in six legs: the largest energy drift at the
    !> legs' ends shrinks with the tolerance, at least 10 times per 100
    !> times, and stays within 1000 rtol (measured below). The drift at one
    !> time alone changes sign and moved tenfold under valgrind.
    subroutine test_energy_solvers(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(ddassl_t) :: ddassl
        type(ida_t) :: ida
        type(mexax_t) :: mexax
        real(wp), allocatable :: y(:), yp(:), y0(:), yp0(:)
        real(wp) :: ystart(14 + 24 + 5), t, e0, e1, drift(2), scale
        real(wp), parameter :: rtols(2) = [1.0e-6_wp, 1.0e-8_wp], t_end = 3.0_wp
        character(len=*), parameter :: names(3) = [character(len=6) :: 'ddassl', 'ida', 'mexax']
        integer :: k, s, seg
        integer, parameter :: segments = 6
        character(len=120) :: msg
        call torsion_pendulum(sys, ystart, 0.0_wp)
        gen = new_formulation(sys, formulation_ggl, ystart(1:14), status=status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        allocate (y0(gen%n), yp0(gen%n), source=0.0_wp)
        y0(1:26) = ystart(1:26)
        call gen%consistent_initial(0.0_wp, y0, yp0, status)
        call check(error, status%ok(), 'initial: ' // status%text())
        if (allocated(error)) return
        e0 = sys%energy(y0(1:14), y0(15:26))
        scale = abs(e0) + 1.0_wp
        do s = 1, 3
            do k = 1, 2
                y = y0
                yp = yp0
                options%rtol = rtols(k)
                options%atol = rtols(k)
                t = 0.0_wp
                drift(k) = 0.0_wp
                do seg = 1, segments
                    select case (s)
                    case (1)
                        call ddassl%integrate(gen, t, y, seg * t_end / segments, options, &
                                              stats, status, yp=yp)
                    case (2)
                        call ida%integrate(gen, t, y, seg * t_end / segments, options, stats, &
                                           status, yp=yp)
                    case (3)
                        call mexax%integrate_mechanical(sys, t, y(1:14), y(15:26), &
                                                        seg * t_end / segments, options, &
                                                        stats, status)
                    end select
                    call check(error, status%ok(), trim(names(s)) // ': ' // status%text())
                    if (allocated(error)) return
                    e1 = sys%energy(y(1:14), y(15:26))
                    drift(k) = max(drift(k), abs(e1 - e0) / scale)
                end do
                write (msg, '(a,a,es8.1,a,es10.3,a,i0)') trim(names(s)), ' rtol ', rtols(k), &
                    ': energy drift ', drift(k), ', steps ', stats%nst
                print '(a)', '    ' // trim(msg)
                call check(error, drift(k) <= 1000.0_wp * rtols(k), trim(msg))
                if (allocated(error)) return
            end do
            call check(error, drift(2) < 0.1_wp * drift(1), &
                       'the drift shrinks with the tolerance: ' // trim(msg))
            if (allocated(error)) return
        end do
    end subroutine test_energy_solvers

    !> The same with dampers (c = 0.5): the energy falls in every interval.
    subroutine test_dissipation(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(14 + 24 + 5), yp(14 + 24 + 5), e(0:6)
        integer :: k
        character(len=160) :: msg
        call torsion_pendulum(sys, y, 0.5_wp)
        gen = new_formulation(sys, formulation_index2, y(1:14), projection=.true., &
                              status=status)
        if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        e(0) = sys%energy(y(1:14), y(15:26))
        do k = 1, 6
            call integrate(gen, y, 0.5_wp * k, 1.0e-8_wp, stats, status, t0=0.5_wp * (k - 1))
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e(k) = sys%energy(y(1:14), y(15:26))
        end do
        write (msg, '(a,7es11.3)') 'energy every 0.5 s:', e
        print '(a)', '    ' // trim(msg)
        call check(error, all(e(1:6) < e(0:5)) .and. e(0) - e(6) > 0.1_wp * abs(e(0)), &
                   trim(msg))
    end subroutine test_dissipation

    !> A spring whose markers coincide: the forces fail with a message, no NaN.
    subroutine test_zero_length(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(marker_t) :: markers(2)
        real(wp) :: q(7), v(6), f(6)
        markers(1)%body = 0
        markers(2)%body = 1
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], markers, [mbs_joint_t ::], &
            status=status, elements=[force_element_t(force_spring_damper, 1, 2, &
            reference=0.5_wp, stiffness=[10.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])])
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        q = [0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        v = 0.0_wp
        call sys%forces(0.0_wp, q, v, f, status)
        call check(error, .not. status%ok(), 'coinciding markers are refused')
        if (allocated(error)) return
        print '(a)', '    ' // status%text()
        call check(error, index(status%text(), 'force element 1') > 0 .and. &
                   index(status%text(), 'undefined') > 0, status%text())
    end subroutine test_zero_length

    !> Elements with a second marker on a load, the same marker twice, a
    !> marker out of range: refused naming the element and the reason.
    subroutine test_bad_elements(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(marker_t) :: markers(2)
        type(force_element_t) :: bad(3)
        character(len=40), parameter :: expect(3) = [character(len=40) :: &
            'acts on one marker', 'are both marker 2', 'must name markers 1 .. 2']
        integer :: k
        markers(1)%body = 0
        markers(2)%body = 1
        bad = [force_element_t(force_applied, 2, 1), force_element_t(force_bushing, 2, 2), &
               force_element_t(force_rotational, 1, 3)]
        do k = 1, 3
            sys = new_mbs_system([test_body(1.0_wp, 1.0_wp)], markers, [mbs_joint_t ::], &
                                 status=status, elements=[bad(k)])
            call check(error, .not. status%ok() .and. &
                       index(status%text(), trim(expect(k))) > 0 .and. &
                       index(status%text(), 'force element 1') > 0, status%text())
            if (allocated(error)) return
        end do
    end subroutine test_bad_elements
end module test_force_elements
