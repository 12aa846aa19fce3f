!> Node frames: massless rigid frames held on the best rigid fit of a node
!> set, so that joints of every type attach to flexible bodies.
!>
!> The loop: a rigid link on a revolute joint to the ground at the origin,
!> joined by a second revolute joint (rotation rows: dot-1 on the marker
!> axes) to a frame on the xmin face of a soft bar (hex8, 2 × 1 × 1, 0.4 m
!> along x) whose xmax face is fixed. For the derivative checks the bar is
!> free and a cube is welded (fixed joint, frame to frame) to its xmax face:
!> rigid–flexible and flexible–flexible joints with rotations.
module test_node_frame
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, quat_product
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_revolute, joint_fixed
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        node_frame_t
    use flexmbs_mbs_formulation, only: block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index2
    use test_problems, only: fill_random
    use mbs_random, only: ad_deviation
    use test_formulation, only: difference_jacobian
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_node_frame

    real(wp), parameter :: g_earth(3) = [0.0_wp, -9.81_wp, 0.0_wp]

contains

    function collect_node_frame() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('rigid_motion_satisfies', test_rigid), &
                 new_test('hand_vs_differences', test_differences), &
                 new_test('ad_vs_analytic', test_ad), &
                 new_test('formulation_jacobian_fd', test_jacobian), &
                 new_test('closed_loop_energy_and_fit', test_energy), &
                 new_test('bad_frames_refused', test_bad)]
    end function collect_node_frame

    !> The link: 0.5 kg, isotropic inertia 0.01 kg m²; a frame body.
    pure function link() result(body)
        type(rigid_body_t) :: body
        body = rigid_body_t(0.5_wp, 0.01_wp * reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
                            1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3]))
    end function link

    pure function frame_body() result(body)
        type(rigid_body_t) :: body
        body%frame = .true.
    end function frame_body

    !> The loop (fixed xmax face), or with `weld` the free bar with a cube
    !> welded to its xmax face.
    subroutine make(derivatives, weld, viscosity, sys, q0, status)
        character(len=*), intent(in) :: derivatives
        logical, intent(in) :: weld
        real(wp), intent(in) :: viscosity
        type(mbs_system_t), intent(out) :: sys
        real(wp), allocatable, intent(out) :: q0(:)
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh, cube_mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t), allocatable :: flex(:)
        type(node_frame_t), allocatable :: frames(:)
        type(marker_t), allocatable :: m(:)
        type(mbs_joint_t), allocatable :: j(:)
        integer, allocatable :: xmin(:), xmax(:), cube_face(:)
        integer :: oq, nq
        real(wp) :: id(4)
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, viscosity, status)
        if (status%ok()) call box_mesh(mesh, hex8, [2, 1, 1], [0.4_wp, 0.05_wp, 0.05_wp], &
                                       status, origin=[0.3_wp, -0.025_wp, -0.025_wp])
        if (status%ok()) call mesh%node_set('xmin', xmin, status)
        if (status%ok()) call mesh%node_set('xmax', xmax, status)
        if (.not. status%ok()) return
        allocate (flex(merge(2, 1, weld)))
        if (weld) then
            call new_flexible_body(flex(1), mesh, [mat], [integer ::], status, gravity=g_earth)
            if (status%ok()) call box_mesh(cube_mesh, hex8, [1, 1, 1], &
                [0.05_wp, 0.05_wp, 0.05_wp], status, origin=[0.7_wp, -0.025_wp, -0.025_wp])
            if (status%ok()) call cube_mesh%node_set('xmin', cube_face, status)
            if (status%ok()) call new_flexible_body(flex(2), cube_mesh, [mat], [integer ::], &
                                                    status, gravity=g_earth)
        else
            call new_flexible_body(flex(1), mesh, [mat], xmax, status, gravity=g_earth)
        end if
        if (.not. status%ok()) return
        ! bodies: link, frame on the bar's xmin face [, frames on the bar's
        ! xmax face and on the cube's xmin face]
        allocate (frames(merge(3, 1, weld)))
        frames(1) = node_frame_t(flexible=1, body=2, nodes=xmin)
        if (weld) then
            frames(2) = node_frame_t(flexible=1, body=3, nodes=xmax)
            frames(3) = node_frame_t(flexible=2, body=4, nodes=cube_face)
        end if
        allocate (m(merge(6, 4, weld)), j(merge(3, 2, weld)))
        m(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp])
        m(2) = marker_t(1, [-0.15_wp, 0.0_wp, 0.0_wp])
        m(3) = marker_t(1, [0.15_wp, 0.0_wp, 0.0_wp])
        m(4) = marker_t(2, [0.0_wp, 0.0_wp, 0.0_wp])   ! at the face's centroid
        j(1) = mbs_joint_t(joint_revolute, 1, 2)
        j(2) = mbs_joint_t(joint_revolute, 3, 4)
        if (weld) then
            m(5) = marker_t(3, [0.0_wp, 0.0_wp, 0.0_wp])
            m(6) = marker_t(4, [0.0_wp, 0.0_wp, 0.0_wp])
            j(3) = mbs_joint_t(joint_fixed, 5, 6)
        end if
        if (weld) then
            sys = new_mbs_system([link(), frame_body(), frame_body(), frame_body()], m, j, &
                gravity=g_earth, constraint_derivatives=derivatives, status=status, &
                flexible=flex, frames=frames)
        else
            sys = new_mbs_system([link(), frame_body()], m, j, gravity=g_earth, &
                constraint_derivatives=derivatives, status=status, flexible=flex, &
                frames=frames)
        end if
        if (.not. status%ok()) return
        allocate (q0(sys%nq))
        id = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        q0(1:7) = [0.15_wp, 0.0_wp, 0.0_wp, id]
        q0(8:14) = [0.3_wp, 0.0_wp, 0.0_wp, id]
        if (weld) then
            q0(15:21) = [0.7_wp, 0.0_wp, 0.0_wp, id]
            q0(22:28) = [0.7_wp, 0.0_wp, 0.0_wp, id]
        end if
        call sys%flexible_coordinates(1, oq, nq)
        q0(oq + 1:oq + nq) = flex(1)%free_positions()
        if (weld) then
            call sys%flexible_coordinates(2, oq, nq)
            q0(oq + 1:) = flex(2)%free_positions()
        end if
    end subroutine make

    !> Rigidly moved (x = c + Q X), the bar and the cube keep every frame
    !> constraint satisfied with the frames at (c + Q X̄, Q); a frame turned
    !> away from the fit violates its rotation rows.
    subroutine test_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), q(:), g(:)
        real(wp) :: qrot(4), rq(3, 3), c(3), worst, off
        integer :: a, b, row, oq, nq
        call make('analytic', .true., 0.0_wp, sys, q0, status)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        qrot = quat_from_axis_angle([1.0_wp, 2.0_wp, -0.5_wp] / norm2([1.0_wp, 2.0_wp, &
                                    -0.5_wp]), 0.9_wp)
        rq = rotation_matrix(qrot)
        c = [0.2_wp, -0.4_wp, 1.1_wp]
        q = q0
        ! every body's point X goes to c + Q X; frames at (c + Q r, Q)
        do b = 1, 4
            q(7 * b - 6:7 * b - 4) = c + matmul(rq, q0(7 * b - 6:7 * b - 4))
            q(7 * b - 3:7 * b) = qrot
        end do
        call sys%flexible_coordinates(1, oq, nq)
        do a = oq + 1, sys%nq, 3
            q(a:a + 2) = c + matmul(rq, q0(a:a + 2))
        end do
        allocate (g(sys%nc))
        call sys%constraint(0.0_wp, q, g, status)
        ! the frames' rows come last: 3 × 6
        worst = maxval(abs(g(sys%nc - 17:sys%nc)))
        print '(4x,a,es9.2)', 'rigid motion: frame rows ', worst
        call check(error, worst <= 1.0e-14_wp, 'frame rows not satisfied under rigid motion')
        ! turn frame 1 by 0.1 rad about z: its rotation rows no longer vanish
        q(11:14) = quat_product(qrot, quat_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 0.1_wp))
        call sys%constraint(0.0_wp, q, g, status)
        row = sys%joint_first_row(sys%joint_count() + 1)
        off = norm2(g(row + 3:row + 5))
        ! about c sin(0.1) = 6e-5 (c = 0.025², the face's second moment)
        call check(error, off > 1.0e-5_wp, 'a turned frame still satisfies its rows')
    end subroutine test_rigid

    !> The hand-coded c_q and G = c_q T of the frame rows against central
    !> differences of c, and γ = (G v)_q T v against differences of G v
    !> along q' = T v, at a perturbed state of the welded system.
    subroutine test_differences(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), q(:), v(:), cq(:, :), cfd(:, :), gm(:, :), &
            tmat(:, :), cp(:), cm(:), qd(:), gam(:), gp(:, :), gmm(:, :)
        real(wp) :: h, dq, dg, dgam
        integer(i8) :: seed
        integer :: k, r0, nc, i
        call make('analytic', .true., 0.0_wp, sys, q0, status)
        call check(error, status%ok(), 'system: ' // status%text())
        if (allocated(error)) return
        nc = sys%nc
        r0 = sys%joint_first_row(sys%joint_count() + 1) - 1
        allocate (q(sys%nq), v(sys%nv), cq(nc, sys%nq), cfd(nc, sys%nq), gm(nc, sys%nv), &
                  tmat(sys%nq, sys%nv), cp(nc), cm(nc), qd(sys%nq), gam(nc), gp(nc, sys%nv), &
                  gmm(nc, sys%nv))
        seed = 12_i8
        call fill_random(q, seed, -0.02_wp, 0.02_wp)
        q = q0 + q
        do i = 1, 4
            q(7 * i - 3:7 * i) = q(7 * i - 3:7 * i) / norm2(q(7 * i - 3:7 * i))
        end do
        call fill_random(v, seed, -1.0_wp, 1.0_wp)
        call sys%constraint_position_jacobian(0.0_wp, q, cq, status)
        h = 1.0e-6_wp
        do k = 1, sys%nq
            q(k) = q(k) + h
            call sys%constraint(0.0_wp, q, cp, status)
            q(k) = q(k) - 2.0_wp * h
            call sys%constraint(0.0_wp, q, cm, status)
            q(k) = q(k) + h
            cfd(:, k) = (cp - cm) / (2.0_wp * h)
        end do
        dq = maxval(abs(cq(r0 + 1:, :) - cfd(r0 + 1:, :))) / maxval(abs(cq(r0 + 1:, :)))
        ! G = c_q T, T column by column from the kinematics
        do k = 1, sys%nv
            cp(1:1) = 0.0_wp
            call sys%kinematics(0.0_wp, q, unit(sys%nv, k), tmat(:, k), status)
        end do
        call sys%constraint_jacobian(0.0_wp, q, gm, status)
        dg = maxval(abs(gm(r0 + 1:, :) - matmul(cq(r0 + 1:, :), tmat))) / &
             maxval(abs(gm(r0 + 1:, :)))
        ! γ: d/ds (G(q + s T v) v) at s = 0
        call sys%constraint_curvature(0.0_wp, q, v, gam, status)
        call sys%kinematics(0.0_wp, q, v, qd, status)
        call sys%constraint_jacobian(0.0_wp, q + h * qd, gp, status)
        call sys%constraint_jacobian(0.0_wp, q - h * qd, gmm, status)
        cp = matmul(gp - gmm, v) / (2.0_wp * h)
        dgam = maxval(abs(gam(r0 + 1:) - cp(r0 + 1:))) / maxval(abs(gam(r0 + 1:)))
        print '(4x,a,3es9.2)', 'frame rows: c_q, G = c_q T, gamma vs differences ', dq, dg, dgam
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, dq <= 1.0e-8_wp, 'c_q differs from differences')
        call check(error, dg <= 1.0e-13_wp, 'G differs from c_q T')
        call check(error, dgam <= 1.0e-7_wp, 'gamma differs from differences')
    end subroutine test_differences

    pure function unit(n, k) result(e)
        integer, intent(in) :: n, k
        real(wp) :: e(n)
        e = 0.0_wp
        e(k) = 1.0_wp
    end function unit

    !> c, G, c_q, c_t and γ of 'ad' equal 'analytic' at perturbed states:
    !> revolute (rigid–flexible) and fixed (flexible–flexible) joints.
    subroutine test_ad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t) :: hand, ad, full
        type(status_t) :: status
        real(wp), allocatable :: q0(:), q(:), v(:)
        real(wp) :: worst
        integer(i8) :: seed
        integer :: trial, i
        call make('analytic', .true., 0.0_wp, hand, q0, status)
        if (status%ok()) call make('ad', .true., 0.0_wp, ad, q0, status)
        if (status%ok()) call make('ad_full', .true., 0.0_wp, full, q0, status)
        call check(error, status%ok(), 'systems: ' // status%text())
        if (allocated(error)) return
        call check(error, hand%nc == 5 + 5 + 6 + 3 * 6, 'rows')
        allocate (q(hand%nq), v(hand%nv))
        seed = 3_i8
        worst = 0.0_wp
        do trial = 1, 5
            call fill_random(q, seed, -0.02_wp, 0.02_wp)
            q = q0 + q
            do i = 1, 4
                q(7 * i - 3:7 * i) = q(7 * i - 3:7 * i) / norm2(q(7 * i - 3:7 * i))
            end do
            call fill_random(v, seed, -1.0_wp, 1.0_wp)
            worst = max(worst, ad_deviation(hand, ad, 0.2_wp, q, v, status), &
                        ad_deviation(hand, full, 0.2_wp, q, v, status))
        end do
        print '(4x,a,es9.2)', 'joints on node frames: AD (ad, ad_full) vs analytic ', worst
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, worst <= 1.0e-12_wp, 'AD differs from analytic')
    end subroutine test_ad

    !> The GGL and index-2 Jacobians (acceleration layout: the frames are
    !> massless) against central differences of F, both derivative sources:
    !> checks the AD second derivatives of the frame rows.
    subroutine test_jacobian(error)
        character(len=8), parameter :: sources(2) = ['analytic', 'ad      ']
        integer, parameter :: forms(2) = [formulation_ggl, formulation_index2]
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: q0(:), y(:), jac(:, :), jfd(:, :), p(:)
        real(wp) :: dev
        integer(i8) :: seed
        integer :: s, f, i
        seed = 8_i8
        dev = 0.0_wp
        do s = 1, 2
            do f = 1, 2
                call make(trim(sources(s)), .true., 100.0_wp, sys, q0, status)
                gen = new_formulation(sys, forms(f), q0, status=status)
                call check(error, status%ok(), 'formulation: ' // status%text())
                if (allocated(error)) return
                allocate (y(gen%n), p(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
                call fill_random(p, seed, -0.01_wp, 0.01_wp)
                y = p
                y(1:sys%nq) = q0 + p(1:sys%nq)
                do i = 1, 4
                    y(7 * i - 3:7 * i) = y(7 * i - 3:7 * i) / norm2(y(7 * i - 3:7 * i))
                end do
                call gen%jacobian_dense(0.0_wp, y, jac, status)
                call difference_jacobian(gen, y, jfd, status)
                call check(error, status%ok(), 'jacobian: ' // status%text())
                if (allocated(error)) return
                dev = max(dev, maxval(abs(jac - jfd)) / maxval(abs(jac)))
                deallocate (y, p, jac, jfd)
            end do
        end do
        print '(4x,a,es9.2)', 'formulation Jacobians with node frames vs differences: ', dev
        call check(error, dev <= 1.0e-6_wp, 'formulation Jacobian differs from differences')
    end subroutine test_jacobian

    !> Undamped, the loop (revolute joint on the bar's face frame) keeps its
    !> energy to a drift that shrinks with the tolerance (RADAU5, GGL, 0.2 s
    !> from a swing of the link); the frame stays on the Kabsch fit of its
    !> nodes (flexmbs_mbs_flexible_marker); MEXAX agrees with RADAU5.
    subroutine test_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(mexax_t) :: mexax
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(flexible_marker_t) :: fit
        real(wp), allocatable :: q0(:), y(:), yp(:), x(:, :), yr(:)
        real(wp) :: t, e0, e1, drift(2), tol(2), origin(3), axes(3, 3), dfit, dmex
        type(flexible_body_t), pointer :: body
        type(node_frame_t) :: frame
        integer :: k, n
        tol = [1.0e-5_wp, 1.0e-7_wp]
        do k = 1, 2
            call make('analytic', .false., 0.0_wp, sys, q0, status)
            gen = new_formulation(sys, formulation_ggl, q0, status=status)
            call check(error, status%ok(), 'formulation: ' // status%text())
            if (allocated(error)) return
            allocate (y(gen%n), yp(gen%n), source=0.0_wp)
            y(1:sys%nq) = q0
            y(gen%offset(block_v) + 6) = 2.0_wp   ! the link's spin about z (body frame)
            call gen%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), 'initial: ' // status%text())
            if (allocated(error)) return
            e0 = sys%energy(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)))
            options%rtol = tol(k)
            options%atol = tol(k)
            t = 0.0_wp
            call solver%integrate(gen, t, y, 0.2_wp, options, stats, status)
            call check(error, status%ok(), 'run: ' // status%text())
            if (allocated(error)) return
            e1 = sys%energy(y(1:sys%nq), y(gen%offset(block_v) + 1:gen%last(block_v)))
            drift(k) = abs(e1 - e0)
            if (k < 2) deallocate (y, yp)
        end do
        ! the frame against the fit of the face's nodes
        body => sys%flexible_of(1)
        frame = sys%frame_of(1)
        n = body%mesh%node_count()
        allocate (x(3, n))
        x = body%mesh%x
        associate (fr => frame)
            do k = 1, size(fr%nodes)
                x(:, fr%nodes(k)) = y(fr%nq(k) + 1:fr%nq(k) + 3)
            end do
            call new_flexible_marker(fit, body%mesh%x, fr%nodes, status)
            call fit%pose(x, origin, axes, status)
            dfit = max(norm2(origin - y(8:10)), maxval(abs(axes - rotation_matrix(y(11:14)))))
        end associate
        ! MEXAX on the same loop, from the same consistent start
        yr = y(1:sys%nq)
        deallocate (y, yp)
        gen = new_formulation(sys, formulation_index2, q0, status=status)
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(1:sys%nq) = q0
        y(gen%offset(block_v) + 6) = 2.0_wp
        call gen%consistent_initial(0.0_wp, y, yp, status)
        options%rtol = 1.0e-7_wp
        options%atol = 1.0e-7_wp
        t = 0.0_wp
        call mexax%integrate_mechanical(sys, t, y(1:sys%nq), &
                                        y(gen%offset(block_v) + 1:gen%last(block_v)), &
                                        0.2_wp, options, stats, status)
        call check(error, status%ok(), 'mexax: ' // status%text())
        if (allocated(error)) return
        dmex = maxval(abs(y(1:sys%nq) - yr))
        print '(4x,a,2es9.2,a,es9.2)', 'loop through a face frame: energy drift ', drift, &
            ' J at rtol 1e-5, 1e-7; initial energy ', e0
        print '(4x,a,es9.2,a,es9.2)', 'frame vs Kabsch fit ', dfit, '; MEXAX vs RADAU5 ', dmex
        call check(error, drift(2) < drift(1), 'energy drift does not shrink with the tolerance')
        call check(error, drift(2) <= 1.0e-5_wp * abs(e0), 'energy drift too large')
        call check(error, dfit <= 1.0e-6_wp, 'the frame left the fit of its nodes')
        call check(error, dmex <= 1.0e-5_wp, 'MEXAX differs from RADAU5')
    end subroutine test_energy

    !> A frame on a non-frame body, a frame body without a frame, a fixed
    !> node and a collinear set are refused with messages.
    subroutine test_bad(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: bar(1)
        type(mbs_system_t) :: sys
        type(status_t) :: status
        type(marker_t) :: m(0)
        type(mbs_joint_t) :: j(0)
        integer, allocatable :: xmin(:), xmax(:)
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        call box_mesh(mesh, hex8, [2, 1, 1], [0.4_wp, 0.05_wp, 0.05_wp], status)
        call mesh%node_set('xmin', xmin, status)
        call mesh%node_set('xmax', xmax, status)
        call new_flexible_body(bar(1), mesh, [mat], xmax, status)
        sys = new_mbs_system([link()], m, j, status=status, flexible=bar, &
                             frames=[node_frame_t(flexible=1, body=1, nodes=xmin)])
        call check(error, index(status%text(), 'not a frame') > 0, 'non-frame body: ' // &
                   status%text())
        sys = new_mbs_system([link(), frame_body()], m, j, status=status, flexible=bar)
        call check(error, index(status%text(), 'exactly one node frame') > 0, &
                   'frame body without frame: ' // status%text())
        sys = new_mbs_system([frame_body()], m, j, status=status, flexible=bar, &
                             frames=[node_frame_t(flexible=1, body=1, nodes=xmax)])
        call check(error, index(status%text(), 'is fixed') > 0, 'fixed node: ' // &
                   status%text())
        sys = new_mbs_system([frame_body()], m, j, status=status, flexible=bar, &
                             frames=[node_frame_t(flexible=1, body=1, nodes=xmin(1:2))])
        call check(error, index(status%text(), 'at least 3 nodes') > 0, 'two nodes: ' // &
                   status%text())
    end subroutine test_bad
end module test_node_frame
