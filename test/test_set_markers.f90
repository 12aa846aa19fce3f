!> Node-set markers without a node frame: a spherical joint between the
!> centroids of node sets (or a centroid and the ground) is linear in the
!> nodes' positions, so the builder gives such markers no massless frame
!> body and the system keeps a constant mass matrix.
!>
!> - The same two hanging bars move alike with set markers and with node
!>   frames (the markers given their centroid as `position`).
!> - The rows' c_q against differences, G = c_q, γ = 0, sparse G = dense G,
!>   and the GGL Jacobian against differences.
!> - Set markers jointed to a rigid hub (rows nonlinear on the hub's side
!>   only): the four formulations' Jacobians against differences and sparse
!>   against dense, for hand-coded and AD constraint derivatives.
!> - A free chain of three soft bars on such joints, undamped, conserves
!>   linear momentum to round-off and angular momentum and energy to
!>   tolerance level for the four solvers.
!> - Set markers in a joint other than spherical, or under a force element,
!>   are refused with a message.
module test_set_markers
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_spherical, joint_revolute, joint_primitive
    use flexmbs_mbs_primitive_kinds, only: primitive_distance
    use flexmbs_mbs_force_element, only: force_element_t, force_spring_damper
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        part_rigid, part_flexible, part_frame
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index1, formulation_index2, formulation_index3
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_run_runner, only: run_scene, run_result_t
    use flexmbs_run_multibody_builder, only: build_multibody
    use test_problems, only: fill_random
    use test_formulation, only: difference_jacobian
    use test_two_flexible, only: check_invariants, solvers
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_set_markers

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_set_markers() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('centroid_against_node_frames', test_against_frames), &
                 new_test('rows_and_jacobians', test_derivatives), &
                 new_test('rigid_hub_jacobians', test_hub_jacobians), &
                 new_test('free_chain_invariants_four_solvers', test_invariants), &
                 new_test('refused_uses', test_refused)]
    end function collect_set_markers

    !> Two soft bars of 4 x 1 x 1 hex8 hanging from the ground, the lower from
    !> the upper, by spherical joints between face node sets; with `framed`
    !> the markers are given their centroids as positions (node frames).
    function hanging_scene(framed) result(text)
        logical, intent(in) :: framed
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.05 /' // nl // &
            '&multibody formulation = ''ggl'', gravity = 0, -9.81, 0 /' // nl // &
            bar('upper', '0') // bar('lower', '0.2') // &
            '&marker name = ''pivot'', body = ''ground'' /' // nl // &
            marker('upper root', 'upper', 'xmin', '0') // &
            marker('upper tip', 'upper', 'xmax', '0.2') // &
            marker('lower root', 'lower', 'xmin', '0.2') // &
            '&joint type = ''spherical'', marker_i = ''pivot'', marker_j = ''upper root'' /' &
            // nl // &
            '&joint type = ''spherical'', marker_i = ''upper tip'', ' // &
            'marker_j = ''lower root'' /' // nl // &
            '&output file = ''none'', n_output = 2 /' // nl
    contains
        function bar(name, x0) result(group)
            character(len=*), intent(in) :: name, x0
            character(len=:), allocatable :: group
            group = '&flexible_body name = ''' // name // ''', divisions = 4, 1, 1, ' // &
                'lengths = 0.2, 0.05, 0.05, origin = ' // x0 // ', -0.025, -0.025, ' // &
                'gravity = 0, -9.81, 0 /' // nl // &
                '&material name = ''' // name // ' soft'', body = ''' // name // ''', ' // &
                'youngs_modulus = 7e5, density = 920, viscosity = 1000 /' // nl
        end function bar
        function marker(name, body, set, x) result(group)
            character(len=*), intent(in) :: name, body, set, x
            character(len=:), allocatable :: group
            group = '&marker name = ''' // name // ''', body = ''' // body // ''', ' // &
                'node_set = ''' // set // ''''
            if (framed) group = group // ', position = ' // x // ', 0, 0'
            group = group // ' /' // nl
        end function marker
    end function hanging_scene

    !> RADAU5 and DDASSL at rtol 1e-8 over 0.05 s (the bars fall about
    !> 1 cm): both bodies' nodes end within 1e-6 m of the framed run's.
    subroutine test_against_frames(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene(2)
        type(mbs_system_t) :: sys(2)
        type(run_result_t) :: result(2)
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:)
        real(wp) :: dev, fall
        integer :: s, k, f, o1, n1, o2, n2
        do k = 1, 2
            call parse_scene(hanging_scene(k == 2), 'hanging.nml', scene(k), status)
            if (status%ok()) call build_multibody(scene(k), sys(k), q0, v0, status)
            call check(error, status%ok(), 'scene: ' // status%text())
            if (allocated(error)) return
        end do
        call check(error, sys(1)%part_count(part_frame) == 0 .and. &
                   sys(2)%part_count(part_frame) == 3, &
                   'set markers need no node frame; given positions, three')
        call check(error, sys(1)%nc == 6 .and. sys(2)%nc == 6 + 3 * 6, 'constraint rows')
        if (allocated(error)) return
        do s = 1, 2
            do k = 1, 2
                scene(k)%solver_name = solvers(s)
                scene(k)%rtol = 1.0e-8_wp
                scene(k)%atol = 1.0e-8_wp
                scene(k)%progress = .false.
                call run_scene(scene(k), .true., result(k), status)
                call check(error, status%ok(), trim(solvers(s)) // ': ' // status%text())
                if (allocated(error)) return
            end do
            dev = 0.0_wp
            fall = 0.0_wp
            do f = 1, 2
                call sys(1)%flexible_coordinates(f, o1, n1)
                call sys(2)%flexible_coordinates(f, o2, n2)
                associate (a => result(1)%y(o1 + 1:o1 + n1), b => result(2)%y(o2 + 1:o2 + n2), &
                           x0 => q0(o2 + 1:o2 + n2))
                    dev = max(dev, maxval(abs(a - b)))
                    fall = max(fall, maxval(abs(b - x0)))
                end associate
            end do
            print '(4x,a8,a,es9.2,a,es9.2,a)', solvers(s), ' set markers against node &
                &frames: ', dev, ' m (nodes moved up to ', fall, ' m)'
            call check(error, fall > 5.0e-3_wp, 'the bars did not fall')
            call check(error, dev <= 1.0e-6_wp, trim(solvers(s)) // &
                       ': set markers and node frames move the bars differently')
            if (allocated(error)) return
        end do
    end subroutine test_against_frames

    !> At a perturbed state of the hanging pair: c_q against central
    !> differences of c, G = c_q (nodal coordinates: T = I), γ = 0 and
    !> ∂(Gᵀλ)/∂q = 0, the sparse G equal to the dense one, and the GGL
    !> Jacobian (constant-mass layout) against differences of F.
    subroutine test_derivatives(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(csc_matrix_t) :: gp
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), q(:), v(:), cq(:, :), cfd(:, :), gm(:, :), &
            cp(:), cm(:), gam(:), gs(:, :), gwq(:, :), gtlq(:, :), lam(:), w(:), y(:), &
            jac(:, :), jfd(:, :), values(:)
        real(wp) :: h, dq, dj
        integer(i8) :: seed
        integer :: k, nc
        call parse_scene(hanging_scene(.false.), 'hanging.nml', scene, status)
        if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), 'scene: ' // status%text())
        if (allocated(error)) return
        nc = sys%nc
        allocate (q(sys%nq), v(sys%nv), cq(nc, sys%nq), cfd(nc, sys%nq), gm(nc, sys%nv), &
                  cp(nc), cm(nc), gam(nc), gwq(nc, sys%nq), gtlq(sys%nv, sys%nq), lam(nc), &
                  gs(nc, sys%nv), &
                  w(sys%nv))
        seed = 21_i8
        call fill_random(q, seed, -0.01_wp, 0.01_wp)
        q = q0 + q
        call fill_random(v, seed, -1.0_wp, 1.0_wp)
        call fill_random(w, seed, -1.0_wp, 1.0_wp)
        call fill_random(lam, seed, -1.0_wp, 1.0_wp)
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
        dq = maxval(abs(cq - cfd))
        call sys%constraint_jacobian(0.0_wp, q, gm, status)
        call sys%constraint_curvature(0.0_wp, q, v, gam, status)
        call sys%constraint_jacobian_derivatives(0.0_wp, q, w, lam, gwq, gtlq, status)
        call sys%constraint_jacobian_pattern(gp, status)
        allocate (values(gp%nnz))
        call sys%constraint_jacobian_sparse(0.0_wp, q, values, status)
        gp%values = values
        call gp%to_dense(gs)
        print '(4x,a,es9.2,a,i0,a)', 'set-marker rows: c_q against differences ', dq, &
            ' (G has ', count(gm /= 0.0_wp), ' entries)'
        call check(error, status%ok(), 'evaluations: ' // status%text())
        call check(error, dq <= 1.0e-9_wp, 'c_q differs from differences')
        call check(error, all(gm == cq), 'G differs from c_q')
        call check(error, count(gm /= 0.0_wp) == 3 * (4 + 4 + 4), &
                   'G: one row per axis, each over the 3 x 4 nodes of a face set ' // &
                   '(two faces for the pair joint)')
        call check(error, all(gam == 0.0_wp), 'gamma is not zero')
        call check(error, all(gwq == 0.0_wp) .and. all(gtlq == 0.0_wp), &
                   'second derivatives are not zero')
        call check(error, all(gs == gm), 'sparse G differs from dense G')
        if (allocated(error)) return
        gen = new_formulation(sys, formulation_ggl, q0, constant_mass=.true., status=status)
        call check(error, status%ok(), 'formulation: ' // status%text())
        if (allocated(error)) return
        allocate (y(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
        call fill_random(y, seed, -0.01_wp, 0.01_wp)
        y(1:sys%nq) = q
        call gen%jacobian_dense(0.0_wp, y, jac, status)
        call difference_jacobian(gen, y, jfd, status)
        dj = maxval(abs(jac - jfd)) / maxval(abs(jac))
        print '(4x,a,es9.2)', 'GGL Jacobian with set markers against differences ', dj
        call check(error, status%ok(), 'jacobian: ' // status%text())
        call check(error, dj <= 1.0e-6_wp, 'GGL Jacobian differs from differences')
    end subroutine test_derivatives

    !> A rigid hub between two soft bars (2 x 1 x 1 hex8, damped), hanging
    !> by spherical joints at the centroids of the bars' inner faces.
    function hub_scene(derivatives) result(text)
        character(len=*), intent(in) :: derivatives
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.05 /' // nl // &
            '&multibody formulation = ''ggl'', gravity = 0, -9.81, 0, ' // &
            'constraint_derivatives = ''' // derivatives // ''' /' // nl // &
            '&rigid_body name = ''hub'', mass = 0.5, inertia = 0.002, 0.01, 0.01, ' // &
            'angular_velocity = 0.5, 1.0, 2.0 /' // nl // &
            bar('right', '0.05') // bar('left', '-0.35') // &
            '&marker name = ''hr'', body = ''hub'', position = 0.05, 0, 0 /' // nl // &
            '&marker name = ''hl'', body = ''hub'', position = -0.05, 0, 0 /' // nl // &
            '&marker name = ''r0'', body = ''right'', node_set = ''xmin'' /' // nl // &
            '&marker name = ''l0'', body = ''left'', node_set = ''xmax'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''hr'', marker_j = ''r0'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''l0'', marker_j = ''hl'' /' // nl // &
            '&output file = ''none'' /' // nl
    contains
        function bar(name, x0) result(group)
            character(len=*), intent(in) :: name, x0
            character(len=:), allocatable :: group
            group = '&flexible_body name = ''' // name // ''', divisions = 2, 1, 1, ' // &
                'lengths = 0.3, 0.04, 0.04, origin = ' // x0 // ', -0.02, -0.02 /' // nl // &
                '&material name = ''' // name // ''', body = ''' // name // ''', ' // &
                'youngs_modulus = 7e5, density = 920, viscosity = 100 /' // nl
        end function bar
    end function hub_scene

    !> The hub scene at a perturbed state (the hub's quaternion turned, the
    !> nodes moved, random velocities and multipliers): each formulation's
    !> dense Jacobian against central differences of F, and the sparse
    !> Jacobian against the dense one, with 'analytic' and 'ad' derivatives.
    subroutine test_hub_jacobians(error)
        character(len=8), parameter :: sources(2) = ['analytic', 'ad      ']
        integer, parameter :: forms(4) = [formulation_index1, formulation_index2, &
            formulation_index3, formulation_ggl]
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dense, sparse
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), y(:), jac(:, :), jfd(:, :), js(:, :)
        real(wp) :: dfd, dsp
        integer(i8) :: seed
        integer :: s, f
        seed = 5_i8
        dfd = 0.0_wp
        dsp = 0.0_wp
        do s = 1, size(sources)
            call parse_scene(hub_scene(trim(sources(s))), 'hub.nml', scene, status)
            if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
            call check(error, status%ok(), 'scene: ' // status%text())
            if (allocated(error)) return
            call check(error, sys%part_count(part_frame) == 0 .and. &
                       sys%part_count(part_rigid) == 1, &
                       'the hub and no node frame')
            if (allocated(error)) return
            do f = 1, size(forms)
                dense = new_formulation(sys, forms(f), q0, constant_mass=.true., status=status)
                if (status%ok()) sparse = new_formulation(sys, forms(f), q0, &
                    constant_mass=.true., status=status, sparse=.true.)
                call check(error, status%ok(), 'formulation: ' // status%text())
                if (allocated(error)) return
                allocate (y(dense%n), jac(dense%n, dense%n), jfd(dense%n, dense%n), &
                          js(dense%n, dense%n))
                call fill_random(y, seed, -0.01_wp, 0.01_wp)
                y(1:sys%nq) = q0 + y(1:sys%nq)
                y(4:7) = [0.9_wp, 0.3_wp, -0.2_wp, 0.1_wp]
                y(4:7) = y(4:7) / norm2(y(4:7))
                y(sys%nq + 1:sys%nq + sys%nv) = 100 * y(sys%nq + 1:sys%nq + sys%nv)
                call dense%jacobian_dense(0.0_wp, y, jac, status)
                call difference_jacobian(dense, y, jfd, status)
                call sparse%jacobian_pattern(pattern, status)
                call sparse%jacobian_sparse(0.0_wp, y, pattern%values, status)
                call check(error, status%ok(), 'jacobians: ' // status%text())
                if (allocated(error)) return
                call pattern%to_dense(js)
                dfd = max(dfd, maxval(abs(jac - jfd)) / maxval(abs(jac)))
                dsp = max(dsp, maxval(abs(jac - js)) / maxval(abs(jac)))
                deallocate (y, jac, jfd, js)
            end do
        end do
        print '(4x,a,es9.2,a,es9.2)', 'set markers on a rigid hub: Jacobians against &
            &differences ', dfd, ', sparse against dense ', dsp
        call check(error, dfd <= 1.0e-6_wp, 'a Jacobian differs from differences')
        call check(error, dsp <= 1.0e-13_wp, 'a sparse Jacobian differs from the dense one')
    end subroutine test_hub_jacobians

    !> Three soft bars along x, jointed end to end at their faces' centroids,
    !> moving with v = (0.2, -0.1, 0.05) and turning with ω = (0.3, 0.5, 4)
    !> about the origin, the middle one 2 rad/s faster about x (the joints
    !> lie on the x axis: consistent velocities). No gravity, no damping.
    function free_scene() result(text)
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.05 /' // nl // &
            '&multibody formulation = ''ggl'', gravity = 0, 0, 0 /' // nl // &
            bar('left', '-0.45', '0.2, -1.3, 0.2', '0.3') // &
            bar('middle', '-0.15', '0.2, -0.1, 0.05', '2.3') // &
            bar('right', '0.15', '0.2, 1.1, -0.1', '0.3') // &
            '&marker name = ''l1'', body = ''left'', node_set = ''xmax'' /' // nl // &
            '&marker name = ''m0'', body = ''middle'', node_set = ''xmin'' /' // nl // &
            '&marker name = ''m1'', body = ''middle'', node_set = ''xmax'' /' // nl // &
            '&marker name = ''r0'', body = ''right'', node_set = ''xmin'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''l1'', marker_j = ''m0'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''m1'', marker_j = ''r0'' /' // nl // &
            '&output file = ''none'', n_output = 2 /' // nl
    contains
        !> A bar from x = x0 on, its centroid c moving at v + ω × c.
        function bar(name, x0, velocity, wx) result(group)
            character(len=*), intent(in) :: name, x0, velocity, wx
            character(len=:), allocatable :: group
            group = '&flexible_body name = ''' // name // ''', divisions = 2, 1, 1, ' // &
                'lengths = 0.3, 0.04, 0.04, origin = ' // x0 // ', -0.02, -0.02, ' // &
                'initial_velocity = ' // velocity // ', ' // &
                'initial_angular_velocity = ' // wx // ', 0.5, 4.0 /' // nl // &
                '&material name = ''' // name // ''', body = ''' // name // ''', ' // &
                'youngs_modulus = 7e5, density = 920 /' // nl
        end function bar
    end function free_scene

    !> Three flexible bodies, no node frame, and the invariants
    !> (test_two_flexible's check_invariants).
    subroutine test_invariants(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:)
        call parse_scene(free_scene(), 'free.nml', scene, status)
        if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), 'scene: ' // status%text())
        if (allocated(error)) return
        call check(error, sys%part_count(part_flexible) == 3 .and. &
                   sys%part_count(part_frame) == 0, &
                   'three flexible bodies and no node frame')
        if (allocated(error)) return
        call check_invariants(error, scene, sys, q0, v0)
    end subroutine test_invariants

    !> The system refuses a set marker in a revolute joint, in a distance and
    !> under a spring-damper, naming why; it takes one jointed to the ground
    !> or to a rigid body.
    subroutine test_refused(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t), target :: sys
        type(mbs_system_t) :: bad
        type(status_t) :: status
        type(flexible_body_t), allocatable :: flex(:)
        integer :: i
        type(rigid_body_t) :: body(1)
        type(marker_t), allocatable :: markers(:)
        type(force_element_t) :: spring(1)
        real(wp), allocatable :: q0(:), v0(:)
        call parse_scene(hanging_scene(.false.), 'hanging.nml', scene, status)
        if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), 'scene: ' // status%text())
        if (allocated(error)) return
        ! component by component (a constructor with nodes leaks under gfortran 12)
        ! the system's flexible bodies, for the systems built from them below
        allocate (flex(sys%part_count(part_flexible)))
        do i = 1, size(flex)
            flex(i) = sys%flexible_of(i)
        end do
        allocate (markers(3))
        markers(1)%flexible = 1
        markers(1)%nodes = [1, 2, 3]
        markers(3)%body = 1
        bad = new_mbs_system(body, markers, [mbs_joint_t(joint_revolute, 1, 2)], &
                             status=status, flexible=flex)
        call check(error, index(status%text(), 'no rotation') > 0, &
                   'revolute joint on a set marker: ' // status%text())
        bad = new_mbs_system(body, markers, [mbs_joint_t(joint_primitive, 1, 3, &
                             primitive_distance)], status=status, flexible=flex)
        call check(error, index(status%text(), 'spherical joints only') > 0, &
                   'distance on a set marker: ' // status%text())
        bad = new_mbs_system(body, markers, [mbs_joint_t(joint_spherical, 1, 3)], &
                             status=status, flexible=flex)
        call check(error, status%ok(), 'set marker to a rigid body: ' // status%text())
        bad = new_mbs_system(body, markers, [mbs_joint_t(joint_spherical, 1, 2)], &
                             status=status, flexible=flex)
        call check(error, status%ok(), 'set marker to the ground: ' // status%text())
        spring(1)%kind = force_spring_damper
        spring(1)%marker_i = 1
        spring(1)%marker_j = 3
        bad = new_mbs_system(body, markers, [mbs_joint_t(joint_spherical, 1, 2)], &
                             status=status, flexible=flex, elements=spring)
        call check(error, index(status%text(), 'node-set centroid') > 0, &
                   'spring on a set marker: ' // status%text())
    end subroutine test_refused
end module test_set_markers
