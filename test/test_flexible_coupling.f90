!> Flexible bodies inside the multibody system: node markers joined to
!> rigid markers (rigid–flexible) and to nodes of another flexible body
!> (flexible–flexible) by spherical joints.
!>
!> The loop: a rigid link on a revolute joint to the ground at the origin,
!> a soft bar (hex8, 2 × 1 × 1, 0.4 m along x) whose xmin face nodes are
!> pinned to the link's end and whose xmax face is fixed: ground – link –
!> bar – ground, a closed loop through the flexible body.
module test_flexible_coupling
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_revolute, joint_spherical
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t
    use flexmbs_mbs_formulation, only: block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index2
    use test_problems, only: fill_random
    use mbs_random, only: ad_deviation
    use test_formulation, only: difference_jacobian
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_flexible_coupling

    real(wp), parameter :: g_earth(3) = [0.0_wp, -9.81_wp, 0.0_wp]

contains

    function collect_flexible_coupling() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('node_joints_ad_vs_analytic', test_ad), &
                 new_test('formulation_jacobian_fd', test_jacobian), &
                 new_test('closed_loop_energy', test_energy), &
                 new_test('free_system_momentum', test_momentum)]
    end function collect_flexible_coupling

    !> The loop (and, with `second`, a small cube whose corner node is
    !> pinned to a node of the bar: flexible–flexible).
    subroutine make_loop(derivatives, sys, q0, status, second, viscosity)
        character(len=*), intent(in) :: derivatives
        type(mbs_system_t), intent(out) :: sys
        real(wp), allocatable, intent(out) :: q0(:)
        type(status_t), intent(out) :: status
        logical, intent(in) :: second
        real(wp), intent(in) :: viscosity
        type(mesh_t) :: mesh, cube_mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t), allocatable :: flex(:)
        type(marker_t), allocatable :: m(:)
        type(mbs_joint_t), allocatable :: j(:)
        integer, allocatable :: face(:), fixed(:)
        integer :: i, nflex, oq, nq
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, viscosity, status)
        if (status%ok()) call box_mesh(mesh, hex8, [2, 1, 1], [0.4_wp, 0.05_wp, 0.05_wp], &
                                       status, origin=[0.3_wp, -0.025_wp, -0.025_wp])
        if (status%ok()) call mesh%node_set('xmin', face, status)
        if (status%ok()) call mesh%node_set('xmax', fixed, status)
        if (.not. status%ok()) return
        nflex = merge(2, 1, second)
        allocate (flex(nflex))
        call new_flexible_body(flex(1), mesh, [mat], fixed, status, gravity=g_earth)
        if (.not. status%ok()) return
        if (second) then
            call box_mesh(cube_mesh, hex8, [1, 1, 1], [0.05_wp, 0.05_wp, 0.05_wp], status, &
                          origin=[0.5_wp, 0.025_wp, -0.025_wp])
            if (status%ok()) call new_flexible_body(flex(2), cube_mesh, [mat], [integer ::], &
                                                    status, gravity=g_earth)
            if (.not. status%ok()) return
        end if
        ! markers: ground pivot, link pivot, 4 link pins, 4 bar nodes [, 2 nodes]
        allocate (m(10 + merge(2, 0, second)), j(5 + merge(1, 0, second)))
        m(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp])
        m(2) = marker_t(1, [-0.15_wp, 0.0_wp, 0.0_wp])
        j(1) = mbs_joint_t(joint_revolute, 1, 2)
        do i = 1, 4
            ! the pin at the node's reference position, in the link's frame
            m(2 + i) = marker_t(1, mesh%x(:, face(i)) - [0.15_wp, 0.0_wp, 0.0_wp])
            m(6 + i) = marker_t(0, flexible=1, node=face(i))
            j(1 + i) = mbs_joint_t(joint_spherical, 2 + i, 6 + i)
        end do
        if (second) then
            ! the cube's node 1 sits at (0.5, 0.025, -0.025): bar node 5 of the
            ! 3 x 2 x 2 grid (x = 0.5, y = +0.025, z = -0.025)
            m(11) = marker_t(0, flexible=1, node=5)
            m(12) = marker_t(0, flexible=2, node=1)
            j(6) = mbs_joint_t(joint_spherical, 11, 12)
        end if
        sys = new_mbs_system([link()], m, j, &
            gravity=g_earth, constraint_derivatives=derivatives, status=status, flexible=flex)
        if (.not. status%ok()) return
        allocate (q0(sys%nq))
        q0(1:7) = [0.15_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        call sys%flexible_coordinates(1, oq, nq)
        q0(oq + 1:oq + nq) = flex(1)%free_positions()
        if (second) then
            call sys%flexible_coordinates(2, oq, nq)
            q0(oq + 1:) = flex(2)%free_positions()
        end if
    end subroutine make_loop

    !> c, G, c_q, c_t and γ of 'ad' equal 'analytic' at perturbed states,
    !> with rigid–flexible and flexible–flexible spherical joints.
    subroutine test_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: hand, ad, full
        type(status_t) :: status
        real(wp), allocatable :: q0(:), q(:), v(:)
        real(wp) :: worst
        integer(i8) :: seed
        integer :: trial
        call make_loop('analytic', hand, q0, status, .true., 0.0_wp)
        if (status%ok()) call make_loop('ad', ad, q0, status, .true., 0.0_wp)
        if (status%ok()) call make_loop('ad_full', full, q0, status, .true., 0.0_wp)
        call check(error, status%ok(), 'systems: ' // status%text())
        if (allocated(error)) return
        associate (nc => hand%nc, nq => hand%nq, nv => hand%nv)
            call check(error, nc == 5 + 12 + 3, 'rows')
            allocate (q(nq), v(nv))
        end associate
        seed = 3_i8
        worst = 0.0_wp
        do trial = 1, 5
            call fill_random(q, seed, -0.01_wp, 0.01_wp)
            q = q0 + q
            q(4:7) = q(4:7) / norm2(q(4:7))
            call fill_random(v, seed, -1.0_wp, 1.0_wp)
            worst = max(worst, ad_deviation(hand, ad, 0.2_wp, q, v, status), &
                        ad_deviation(hand, full, 0.2_wp, q, v, status))
        end do
        print '(4x,a,es9.2)', 'node joints: AD (ad, ad_full) vs analytic ', worst
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, worst <= 1.0e-12_wp, 'AD differs from analytic')
    end subroutine test_ad

    !> The GGL and index-2 Jacobians of the coupled system against central
    !> differences of F (1e-6 relative), both derivative sources.
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: sources(2) = ['analytic', 'ad      ']
        integer, parameter :: forms(2) = [formulation_ggl, formulation_index2]
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), jac(:, :), jfd(:, :), p(:)
        real(wp) :: dev
        integer(i8) :: seed
        integer :: s, f
        seed = 8_i8
        dev = 0.0_wp
        do s = 1, 2
            do f = 1, 2
                call make_loop(trim(sources(s)), sys, q0, status, .false., 100.0_wp)
                gen = new_formulation(sys, forms(f), q0, status=status)
                call check(error, status%ok(), 'formulation: ' // status%text())
                if (allocated(error)) return
                allocate (y(gen%n), p(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
                call fill_random(p, seed, -0.01_wp, 0.01_wp)
                y = p
                y(1:sys%nq) = q0 + p(1:sys%nq)
                y(4:7) = y(4:7) / norm2(y(4:7))
                call gen%jacobian_dense(0.0_wp, y, jac, status)
                call difference_jacobian(gen, y, jfd, status)
                call check(error, status%ok(), 'jacobian: ' // status%text())
                if (allocated(error)) return
                dev = max(dev, maxval(abs(jac - jfd)) / maxval(abs(jac)))
                deallocate (y, p, jac, jfd)
            end do
        end do
        print '(4x,a,es9.2)', 'coupled formulation Jacobians vs differences: ', dev
        call check(error, dev <= 1.0e-6_wp, 'formulation Jacobian differs from differences')
    end subroutine test_jacobian

    !> Undamped, the loop keeps its energy (rigid kinetic and potential, bar
    !> kinetic, strain and gravity potential) to a drift that shrinks with
    !> the tolerance; RADAU5, GGL, 0.2 s from a swing of the link.
    subroutine test_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), yp(:)
        real(wp) :: t, e0, e1, drift(2), tol(2), scale
        integer :: k
        tol = [1.0e-5_wp, 1.0e-7_wp]
        do k = 1, 2
            call make_loop('analytic', sys, q0, status, .false., 0.0_wp)
            gen = new_formulation(sys, formulation_ggl, q0, constant_mass=.true., status=status)
            call check(error, status%ok(), 'formulation: ' // status%text())
            if (allocated(error)) return
            allocate (y(gen%n), yp(gen%n), source=0.0_wp)
            y(1:sys%nq) = q0
            y(gen%offset(block_v) + 6) = 2.0_wp   ! the link's spin about z (body frame)
            call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), 'initial: ' // status%text())
            if (allocated(error)) return
            e0 = sys%energy(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)))
            ! kinetic scale
            scale = 0.5_wp * sum(y(gen%offset(block_v) + 1:gen%offset(block_v) + 6)**2)
            options%rtol = tol(k)
            options%atol = tol(k)
            t = 0.0_wp
            call solver%integrate(gen, t, y, 0.2_wp, options, stats, status)
            call check(error, status%ok(), 'run: ' // status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)))
            drift(k) = abs(e1 - e0)
            deallocate (y, yp)
        end do
        print '(4x,a,2es9.2,a,es9.2)', 'closed loop with a flexible link: energy drift ', &
            drift, ' J at rtol 1e-5, 1e-7; initial energy ', e0
        call check(error, drift(2) < drift(1), 'energy drift does not shrink with the tolerance')
        call check(error, drift(2) <= 1.0e-4_wp * max(abs(e0), scale), 'energy drift too large')
    end subroutine test_energy
    !> A free rigid link with the soft bar pinned to it (no ground, no
    !> gravity), spinning and flying: linear and angular momentum conserved
    !> (RADAU5, GGL, rtol 1e-8).
    subroutine test_momentum(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: bar(1)
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(marker_t) :: m(8)
        type(mbs_joint_t) :: j(4)
        integer, allocatable :: face(:)
        real(wp), allocatable :: y(:), yp(:)
        real(wp) :: l0(3), a0(3), l1(3), a1(3), t
        integer :: i
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        call box_mesh(mesh, hex8, [2, 1, 1], [0.4_wp, 0.05_wp, 0.05_wp], status, &
                      origin=[0.3_wp, -0.025_wp, -0.025_wp])
        call mesh%node_set('xmin', face, status)
        call new_flexible_body(bar(1), mesh, [mat], [integer ::], status)
        do i = 1, 4
            m(i) = marker_t(1, mesh%x(:, face(i)) - [0.15_wp, 0.0_wp, 0.0_wp])
            m(4 + i) = marker_t(0, flexible=1, node=face(i))
            j(i) = mbs_joint_t(joint_spherical, i, 4 + i)
        end do
        sys = new_mbs_system([link()], m, j, status=status, &
            flexible=bar)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        gen = new_formulation(sys, formulation_ggl, [0.15_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, &
            0.0_wp, 0.0_wp, bar(1)%free_positions()], constant_mass=.true., status=status)
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(1:7) = [0.15_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        y(8:sys%nq) = bar(1)%free_positions()
        y(gen%offset(block_v) + 1:gen%offset(block_v) + 6) = [0.3_wp, -0.2_wp, 0.1_wp, 0.5_wp, &
                                                              1.0_wp, 3.0_wp]
        call gen%consistent_initial(0.0_wp, y, yp, status)
        call sys%momenta(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)), l0, a0)
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        t = 0.0_wp
        call solver%integrate(gen, t, y, 0.2_wp, options, stats, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call sys%momenta(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)), l1, a1)
        print '(4x,a,2es9.2)', 'free system: momentum change (linear, angular) ', &
            norm2(l1 - l0) / norm2(l0), norm2(a1 - a0) / norm2(a0)
        call check(error, norm2(l1 - l0) <= 1.0e-6_wp * norm2(l0), 'linear momentum')
        call check(error, norm2(a1 - a0) <= 1.0e-6_wp * norm2(a0), 'angular momentum')
    end subroutine test_momentum
    !> The rigid link: 0.5 kg, isotropic inertia 0.01 kg m².
    pure function link() result(body)
        type(rigid_body_t) :: body
        body = rigid_body_t(0.5_wp, 0.01_wp * reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
                            1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3]))
    end function link
end module test_flexible_coupling
