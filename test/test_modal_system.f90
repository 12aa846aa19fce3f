!> Modal bodies in the multibody system, joined through interface frames:
!> a modal bar hanging from the ground by a spherical joint at its xmin
!> interface (a revolute joint for the second bar of the chain test). The
!> formulations' Jacobians against differences with hand-coded and AD
!> frame rows, sparse against dense, the rigid limit (k = 0 on one
!> interface) against a rigid-body pendulum, and the energy of the
!> undamped pendulum under every solver.
module test_modal_system
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: real_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_spherical, joint_revolute, joint_fixed
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_linalg_lapack, only: dsygv_quiet
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        node_frame_t, part_rigid, part_modal
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index2, formulation_index3
    use test_modal_body, only: new_test_modal_body, allocate_solver
    use test_problems, only: fill_random
    use test_formulation, only: difference_jacobian
    use mbs_random, only: ad_deviation
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_modal_system

    real(wp), parameter :: g_earth(3) = [0.0_wp, -9.81_wp, 0.0_wp]
    real(wp), parameter :: bar(3) = [0.6_wp, 0.08_wp, 0.05_wp], density = 920.0_wp

contains

    function collect_modal_system() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('jacobians_vs_differences', test_jacobian), &
                 new_test('ad_equals_analytic', test_ad), &
                 new_test('sparse_equals_dense', test_sparse), &
                 new_test('no_modes_is_a_rigid_pendulum', test_rigid_limit), &
                 new_test('pendulum_energy_every_solver', test_energy), &
                 new_test('all_modes_equal_linear_fe', test_linear_fe), &
                 new_test('bad_frames_refused', test_bad)]
    end function collect_modal_system

    pure function frame_body() result(body)
        type(rigid_body_t) :: body
        body%frame = .true.
    end function frame_body

    !> The modal bar (k modes on `faces`) hanging at its xmin interface's
    !> centroid from the ground at the origin, horizontal along x at rest;
    !> with `second`, a second bar hinged (revolute about z) to the first
    !> one's xmax interface. q0 is consistent.
    subroutine make(k, faces, derivatives, viscosity, sys, q0, status, second)
        integer, intent(in) :: k
        character(len=*), intent(in) :: faces(:), derivatives
        real(wp), intent(in) :: viscosity
        type(mbs_system_t), intent(out) :: sys
        real(wp), allocatable, intent(out) :: q0(:)
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: second
        type(modal_body_t), allocatable :: bodies(:)
        type(node_frame_t), allocatable :: frames(:)
        type(marker_t), allocatable :: m(:)
        type(mbs_joint_t), allocatable :: j(:)
        type(rigid_body_t), allocatable :: rigid(:)
        logical :: two
        integer :: nb, b, iq, iv
        two = .false.
        if (present(second)) two = second
        nb = merge(2, 1, two)
        allocate (bodies(nb))
        do b = 1, nb
            call new_test_modal_body([4, 1, 1], faces, k, viscosity, bodies(b), status, &
                                     gravity=g_earth)
            if (.not. status%ok()) return
        end do
        if (two) then
            rigid = [frame_body(), frame_body(), frame_body()]
            frames = [node_frame_t(body=1, modal=1, modal_interface=1), &
                      node_frame_t(body=2, modal=1, modal_interface=2), &
                      node_frame_t(body=3, modal=2, modal_interface=1)]
            m = [marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp]), marker_t(1, [0.0_wp, 0.0_wp, 0.0_wp]), &
                 marker_t(2, [0.0_wp, 0.0_wp, 0.0_wp]), marker_t(3, [0.0_wp, 0.0_wp, 0.0_wp])]
            j = [mbs_joint_t(joint_spherical, 1, 2), mbs_joint_t(joint_revolute, 3, 4)]
        else
            rigid = [frame_body()]
            frames = [node_frame_t(body=1, modal=1, modal_interface=1)]
            m = [marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp]), marker_t(1, [0.0_wp, 0.0_wp, 0.0_wp])]
            j = [mbs_joint_t(joint_spherical, 1, 2)]
        end if
        sys = new_mbs_system(rigid, m, j, gravity=g_earth, constraint_derivatives=derivatives, &
                             status=status, frames=frames, modal=bodies)
        if (.not. status%ok()) return
        allocate (q0(sys%nq), source=0.0_wp)
        ! frame bodies at the interfaces' centroids, unrotated; the bars
        ! along x, the first one's xmin centroid at the origin
        do b = 1, size(rigid)
            q0(7 * b - 3) = 1.0_wp
        end do
        if (two) then
            q0(7 * 2 - 6) = bar(1)
            q0(7 * 3 - 6) = bar(1)
        end if
        do b = 1, nb
            call sys%part_offsets(part_modal, b, iq, iv)
            q0(iq + 1) = bar(1) / 2 + (b - 1) * bar(1)
            q0(iq + 4) = 1.0_wp
        end do
    end subroutine make

    !> GGL and index-2 Jacobians (acceleration layout) against central
    !> differences of F, hand-coded and AD frame rows, two bars.
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: sources(2) = ['analytic', 'ad      ']
        integer, parameter :: forms(2) = [formulation_ggl, formulation_index2]
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), p(:), jac(:, :), jfd(:, :)
        real(wp) :: dev
        integer(i8) :: seed
        integer :: s, f, i
        seed = 21_i8
        dev = 0.0_wp
        do s = 1, 2
            do f = 1, 2
                call make(2, [character(len=4) :: 'xmin', 'xmax'], trim(sources(s)), 500.0_wp, &
                          sys, q0, status, second=.true.)
                if (status%ok()) gen = new_formulation(sys, forms(f), q0, status=status)
                call check(error, status%ok(), 'system: ' // status%text())
                if (allocated(error)) return
                allocate (y(gen%n), p(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
                call fill_random(p, seed, -0.01_wp, 0.01_wp)
                y = p
                y(1:sys%nq) = q0 + p(1:sys%nq)
                call normalise_quaternions(sys, y)
                call gen%jacobian_dense(0.0_wp, y, jac, status)
                call difference_jacobian(gen, y, jfd, status)
                call check(error, status%ok(), 'jacobian: ' // status%text())
                if (allocated(error)) return
                dev = max(dev, maxval(abs(jac - jfd)) / maxval(abs(jac)))
                deallocate (y, p, jac, jfd)
            end do
        end do
        print '(4x,a,es9.2)', 'Jacobians with modal bodies vs differences: ', dev
        call check(error, dev <= 1.0e-6_wp, 'formulation Jacobian differs from differences')
    end subroutine test_jacobian

    !> Every quaternion of the system's q (rigid bodies, modal bodies) unit.
    subroutine normalise_quaternions(sys, y)
        type(mbs_system_t), intent(in) :: sys
        real(wp), intent(inout) :: y(:)
        integer :: b, i0, iv
        do b = 1, sys%part_count(part_rigid)
            y(7 * b - 3:7 * b) = y(7 * b - 3:7 * b) / norm2(y(7 * b - 3:7 * b))
        end do
        do b = 1, sys%part_count(part_modal)
            call sys%part_offsets(part_modal, b, i0, iv)
            y(i0 + 4:i0 + 7) = y(i0 + 4:i0 + 7) / norm2(y(i0 + 4:i0 + 7))
        end do
    end subroutine normalise_quaternions

    !> c, G, c_q, c_t and γ of the system: 'ad' against 'analytic'.
    subroutine test_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: hand, ad
        type(status_t) :: status
        real(wp), allocatable :: q0(:), q(:), v(:)
        integer(i8) :: seed
        real(wp) :: worst
        call make(3, [character(len=4) :: 'xmin', 'xmax'], 'analytic', 500.0_wp, hand, q0, &
                  status, second=.true.)
        if (status%ok()) call make(3, [character(len=4) :: 'xmin', 'xmax'], 'ad', 500.0_wp, &
                                   ad, q0, status, second=.true.)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        allocate (q(hand%nq), v(hand%nv))
        seed = 5_i8
        call fill_random(q, seed, -0.05_wp, 0.05_wp)
        call fill_random(v, seed, -1.0_wp, 1.0_wp)
        q = q + q0
        call normalise_quaternions(hand, q)
        worst = ad_deviation(hand, ad, 0.0_wp, q, v, status)
        call check(error, status%ok() .and. worst <= 1.0e-12_wp, 'AD differs from analytic: ' &
                   // real_text(worst))
    end subroutine test_ad

    !> The sparse formulation's Jacobian and mass equal the dense ones.
    subroutine test_sparse(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dense, sparse
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), p(:), jd(:, :), js(:, :)
        integer(i8) :: seed
        call make(2, [character(len=4) :: 'xmin', 'xmax'], 'analytic', 500.0_wp, sys, q0, &
                  status, second=.true.)
        if (status%ok()) dense = new_formulation(sys, formulation_ggl, q0, status=status)
        if (status%ok()) sparse = new_formulation(sys, formulation_ggl, q0, status=status, &
                                                  sparse=.true.)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        allocate (y(dense%n), p(dense%n), jd(dense%n, dense%n), js(dense%n, dense%n))
        seed = 9_i8
        call fill_random(p, seed, -0.01_wp, 0.01_wp)
        y = p
        y(1:sys%nq) = q0 + p(1:sys%nq)
        call normalise_quaternions(sys, y)
        call dense%jacobian_dense(0.0_wp, y, jd, status)
        call sparse%jacobian_pattern(pattern, status)
        call sparse%jacobian_sparse(0.0_wp, y, pattern%values, status)
        call pattern%to_dense(js)
        call check(error, status%ok(), 'sparse: ' // status%text())
        call check(error, maxval(abs(jd - js)) <= 1.0e-12_wp * maxval(abs(jd)), &
                   'sparse Jacobian differs: ' // real_text(maxval(abs(jd - js))))
    end subroutine test_sparse

    !> k = 0 on one interface: the modal bar swings like a rigid bar of the
    !> box's mass and inertia hung at its xmin face centre (RADAU5, GGL,
    !> 0.5 s): centre of mass and orientation to the tolerance.
    subroutine test_rigid_limit(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: modal, rigid
        type(formulation_t) :: gm, gr
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(rigid_body_t) :: box
        real(wp), allocatable :: q0(:), ym(:), yr(:), yp(:)
        type(modal_body_t), pointer :: body
        real(wp) :: t, dev, mass
        call make(0, [character(len=4) :: 'xmin'], 'analytic', 0.0_wp, modal, q0, status)
        if (status%ok()) body => modal%modal_of(1)
        call check(error, status%ok(), 'modal: ' // status%text())
        if (allocated(error)) return
        call check(error, body%mode_count() == 0, 'modal: ' // &
                   status%text())
        if (allocated(error)) return
        mass = density * product(bar)
        box%mass = mass
        box%inertia = 0.0_wp
        box%inertia(1, 1) = mass * (bar(2)**2 + bar(3)**2) / 12
        box%inertia(2, 2) = mass * (bar(1)**2 + bar(3)**2) / 12
        box%inertia(3, 3) = mass * (bar(1)**2 + bar(2)**2) / 12
        rigid = new_mbs_system([box], [marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp]), &
                               marker_t(1, [-bar(1) / 2, 0.0_wp, 0.0_wp])], &
                               [mbs_joint_t(joint_spherical, 1, 2)], gravity=g_earth, &
                               status=status)
        call check(error, status%ok(), 'rigid: ' // status%text())
        if (allocated(error)) return
        options%rtol = 1.0e-9_wp
        options%atol = 1.0e-9_wp
        gm = new_formulation(modal, formulation_ggl, q0, status=status)
        allocate (ym(gm%n), yp(gm%n), source=0.0_wp)
        ym(1:modal%nq) = q0
        if (status%ok()) call gm%consistent_initial(0.0_wp, ym, yp, status)
        t = 0.0_wp
        if (status%ok()) call solver%integrate(gm, t, ym, 0.5_wp, options, stats, status)
        call check(error, status%ok(), 'modal run: ' // status%text())
        if (allocated(error)) return
        gr = new_formulation(rigid, formulation_ggl, q0(8:14), status=status)
        deallocate (yp)
        allocate (yr(gr%n), yp(gr%n), source=0.0_wp)
        yr(1:7) = q0(8:14)
        if (status%ok()) call gr%consistent_initial(0.0_wp, yr, yp, status)
        t = 0.0_wp
        if (status%ok()) call solver%integrate(gr, t, yr, 0.5_wp, options, stats, status)
        call check(error, status%ok(), 'rigid run: ' // status%text())
        if (allocated(error)) return
        dev = maxval(abs(ym(8:14) - yr(1:7)))
        print '(4x,a,es9.2,a,3f9.5)', 'modal (k = 0) vs rigid pendulum at 0.5 s: ', dev, &
            ', centre ', yr(1:3)
        call check(error, dev <= 1.0e-7_wp, 'rigid limit: ' // real_text(dev))
    end subroutine test_rigid_limit

    !> The undamped modal pendulum (two interfaces, k = 2), 0.3 s: energy
    !> within 10 rtol under RADAU5, DDASSL and IDA (GGL, index 2) and
    !> MEXAX; the joint held.
    subroutine test_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), yp(:), c(:)
        real(wp) :: e0, e1, t, de, scale
        real(wp), parameter :: rtol = 1.0e-8_wp
        character(len=6), parameter :: names(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        integer :: s, form
        call make(2, [character(len=4) :: 'xmin', 'xmax'], 'analytic', 0.0_wp, sys, q0, status)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        options%rtol = rtol
        options%atol = rtol
        allocate (c(sys%nc))
        do s = 1, 4
            call allocate_solver(s, solver)
            form = merge(formulation_index2, formulation_ggl, s == 4)
            gen = new_formulation(sys, form, q0, constant_mass=.false., status=status)
            allocate (y(gen%n), yp(gen%n), source=0.0_wp)
            y(1:sys%nq) = q0
            if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
            e0 = sys%energy(y(1:sys%nq), y(sys%nq + 1:sys%nq + sys%nv))
            t = 0.0_wp
            if (s < 4) then
                if (status%ok()) call solver%integrate(gen, t, y, 0.3_wp, options, stats, status)
            else
                select type (solver)
                type is (mexax_t)
                    if (status%ok()) call solver%integrate_mechanical(sys, t, y(1:sys%nq), &
                        y(sys%nq + 1:sys%nq + sys%nv), 0.3_wp, options, stats, status)
                end select
            end if
            call check(error, status%ok(), names(s) // ': ' // status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:sys%nq), y(sys%nq + 1:sys%nq + sys%nv))
            ! the scale: the potential energy the swing has turned over
            scale = density * product(bar) * norm2(g_earth) * bar(1) / 2
            de = abs(e1 - e0) / scale
            call sys%constraint(0.3_wp, y(1:sys%nq), c, status)
            print '(4x,a)', names(s) // ': energy ' // real_text(de) // ', |c| ' // &
                real_text(maxval(abs(c)))
            call check(error, de <= 10 * rtol, names(s) // ': energy ' // real_text(de))
            call check(error, maxval(abs(c)) <= 1.0e-6_wp, names(s) // ': constraint')
            deallocate (solver, y, yp)
        end do
    end subroutine test_energy

    !> With every fixed-interface mode, the modal cantilever (clamped at
    !> its xmin interface by a fixed joint, undamped, stepped by gravity ε
    !> from rest) moves as the linear FE cantilever of the same mesh clamped
    !> there, solved here by modal superposition of the dense pencil
    !> (K_ff, M_ff): u(t) = Σ_i φ_i φ_iᵀ f (1 − cos ω_i t)/ω_i². The
    !> difference is the linearisation's, O(ε²): relative to the motion it
    !> falls tenfold with ε.
    subroutine test_linear_fe(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: eps(2), rel(2)
        integer :: l
        eps = [0.5_wp, 0.05_wp]
        do l = 1, 2
            call linear_fe_deviation(eps(l), rel(l), error)
            if (allocated(error)) return
        end do
        print '(4x,a,2es10.2)', 'all modes vs linear FE, relative deviation at g = 0.5, 0.05: ', &
            rel
        call check(error, rel(1) <= 1.0e-2_wp .and. rel(2) <= 0.15_wp * rel(1), &
                   'deviation does not shrink with the load')
    end subroutine test_linear_fe

    !> max |u_modal − u_FE| / max |u_FE| over the nodes at t = 0.06 s.
    subroutine linear_fe_deviation(eps, rel, error)
        real(wp), intent(in) :: eps
        real(wp), intent(out) :: rel
        type(error_t), allocatable, intent(inout) :: error
        real(wp), parameter :: t_end = 0.06_wp
        type(modal_body_t) :: bar1(1)
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        type(flexible_body_t) :: clamped
        type(modal_body_t), pointer :: body
        integer, allocatable :: xmin(:)
        real(wp), allocatable :: y(:), yp(:), q0(:), k(:, :), m(:, :), w(:), work(:), &
            u_fe(:), x(:), u_modal(:)
        real(wp) :: g(3), t, c
        integer :: nf, i, info, node, d, iq, iv
        g = [0.0_wp, -eps, 0.0_wp]
        ! the FE cantilever, xmin clamped
        call box_mesh(mesh, hex8, [4, 1, 1], bar, status)
        if (status%ok()) call new_neo_hooke(material, 7.0e5_wp, 0.3_wp, density, 0.0_wp, status)
        if (status%ok()) call mesh%node_set('xmin', xmin, status)
        if (status%ok()) call new_flexible_body(clamped, mesh, [material], xmin, status, &
                                                gravity=g)
        if (status%ok()) call clamped%assemble_tangents(clamped%free_positions(), &
            spread(0.0_wp, 1, clamped%nv), status)
        call check(error, status%ok(), 'FE body: ' // status%text())
        if (allocated(error)) return
        nf = clamped%nv
        allocate (k(nf, nf), m(nf, nf), w(nf), work(10 * nf), u_fe(nf))
        call clamped%stiffness%to_dense(k)
        call clamped%mass_matrix%to_dense(m)
        call dsygv_quiet(1, 'V', 'U', nf, k, nf, m, nf, w, work, size(work), info)
        call check(error, info == 0, 'dsygv')
        if (allocated(error)) return
        u_fe = 0.0_wp
        do i = 1, nf
            c = dot_product(k(:, i), clamped%applied_force) / w(i) * (1.0_wp - cos(sqrt(w(i)) &
                                                                       * t_end))
            u_fe = u_fe + c * k(:, i)
        end do
        ! the modal cantilever with every mode, the same load
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin'], nf, 0.0_wp, &
                                 bar1(1), status, gravity=g)
        call check(error, status%ok() .and. bar1(1)%modes == nf, 'modal: ' // status%text())
        if (allocated(error)) return
        ! the body where its mesh is (frame at the centre of mass), its xmin
        ! interface's frame body at the face's centroid, welded to the ground
        sys = new_mbs_system([frame_body()], [marker_t(0, [0.0_wp, bar(2:3) / 2]), &
                             marker_t(1, [0.0_wp, 0.0_wp, 0.0_wp])], &
                             [mbs_joint_t(joint_fixed, 1, 2)], status=status, &
                             frames=[node_frame_t(body=1, modal=1, modal_interface=1)], &
                             modal=bar1)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        allocate (q0(sys%nq), source=0.0_wp)
        q0(1:7) = [0.0_wp, bar(2:3) / 2, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        q0(8:14) = [bar / 2, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        options%rtol = 1.0e-9_wp
        options%atol = 1.0e-12_wp
        gen = new_formulation(sys, formulation_ggl, q0, status=status)
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(1:sys%nq) = q0
        if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
        t = 0.0_wp
        if (status%ok()) call solver%integrate(gen, t, y, t_end, options, stats, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        allocate (x(3 * mesh%node_count()), u_modal(nf))
        body => sys%modal_of(1)
        call sys%part_offsets(part_modal, 1, iq, iv)
        call body%node_positions(y(iq + 1:iq + body%nq), x)
        do node = 1, mesh%node_count()
            do d = 1, 3
                if (clamped%dof(d, node) == 0) cycle
                u_modal(clamped%dof(d, node)) = x(3 * node - 3 + d) - mesh%x(d, node)
            end do
        end do
        rel = maxval(abs(u_modal - u_fe)) / maxval(abs(u_fe))
    end subroutine linear_fe_deviation

    !> A frame on a modal body that does not exist, or on an interface it
    !> does not have: refused by name.
    subroutine test_bad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(modal_body_t) :: bar1(1)
        type(status_t) :: status
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin'], 1, 0.0_wp, bar1(1), &
                                 status)
        sys = new_mbs_system([frame_body()], [marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp]), &
                             marker_t(1, [0.0_wp, 0.0_wp, 0.0_wp])], &
                             [mbs_joint_t(joint_spherical, 1, 2)], status=status, &
                             frames=[node_frame_t(body=1, modal=1, modal_interface=2)], &
                             modal=bar1)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'interface 2') > 0, 'interface: ' // status%text())
        sys = new_mbs_system([frame_body()], [marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp]), &
                             marker_t(1, [0.0_wp, 0.0_wp, 0.0_wp])], &
                             [mbs_joint_t(joint_spherical, 1, 2)], status=status, &
                             frames=[node_frame_t(body=1, modal=2, modal_interface=1)], &
                             modal=bar1)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'modal = 2') > 0, 'body: ' // status%text())
    end subroutine test_bad
end module test_modal_system
