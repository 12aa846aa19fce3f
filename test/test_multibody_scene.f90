!> Multibody scenes (`&multibody`, `&rigid_body`, `&marker`, `&joint`,
!> `&driver`): the four-bar of inputs/four_bar.nml against its closed form
!> with every solver, and the messages for bad scenes (no output file).
module test_multibody_scene
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_mbs_rotation, only: rotation_matrix
    use flexmbs_problems_mechanisms, only: four_bar_exact, four_bar_torque, crank_angle, bar_b
    use flexmbs_run_chain_builder, only: build_rigid_chain, chain_link
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_multibody_scene, read_matrix, expect, run_file

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_multibody_scene() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('four_bar_file_closed_form', test_four_bar), &
                 new_test('bad_scenes', test_bad_scenes), &
                 new_test('rigid_chain_file', test_chain_file), &
                 new_test('rigid_chain_bad_scenes', test_chain_bad), &
                 new_test('rigid_flexible_file', test_rigid_flexible), &
                 new_test('rigid_flexible_bad_scenes', test_rigid_flexible_bad), &
                 new_test('monitor_drift_energy', test_monitor), &
                 new_test('four_bar_chain_file', test_four_bar_chain), &
                 new_test('four_bar_two_chains_file', test_four_bar_chains), &
                 new_test('face_hinge_file', test_face_hinge), &
                 new_test('five_body_file', test_five_body), &
                 new_test('bdf_ggl_tight_tolerance', test_bdf_tight), &
                 new_test('four_bar_torque_tight_tolerance', test_torque_tight)]
    end function collect_multibody_scene

    !> inputs/four_bar.nml with each solver: the coupler end at t = 1
    !> (rtol 1e-7) on the closed form (RADAU5, DDASSL, IDA within 1e-5;
    !> MEXAX at its index-2 state within 1e-5).
    subroutine test_four_bar(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp) :: b(3), c(3), r(3, 3), dev
        integer :: k
        do k = 1, size(solvers)
            call run_file(error, 'inputs/four_bar.nml', solvers(k), scene, result)
            if (allocated(error)) return
            call four_bar_exact(crank_angle(1.0_wp), b, c)
            r = rotation_matrix(result%y(11:14))
            dev = norm2(result%y(8:10) + 0.5_wp * bar_b * r(:, 1) - c)
            print '(4x,a,a,es9.2)', solvers(k), ': coupler end off the closed form by ', dev
            call check(error, dev <= 1.0e-5_wp, trim(solvers(k)) // ': four-bar off the closed form')
        end do
    end subroutine test_four_bar

    !> A revolute pendulum scene, varied into each defect.
    function pendulum(bar, markers, joints, extra) result(text)
        character(len=*), intent(in) :: bar, markers, joints, extra
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.1 /' // nl // &
               '&rigid_body name = ''bar'', mass = 1, inertia = 0.1, 0.1, 0.1, ' // bar // &
               ' /' // nl // markers // nl // joints // nl // extra // nl // &
               '&output file = ''none'' /'
    end function pendulum

    subroutine expect(error, text, part)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: text, part
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        call parse_scene(text, 'mb.nml', scene, status)
        if (status%ok()) then
            scene%progress = .false.
            call run_scene(scene, .true., result, status)
        end if
        call check(error, status%code == status_bad_input .and. index(status%text(), part) > 0, &
                   'expected "' // part // '", got: ' // status%text())
    end subroutine expect

    subroutine test_bad_scenes(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: bar = 'position = 0.25, 0.4330127018922193, 0, ' // &
            'rotation_angle = 1.0471975511965976'
        character(len=*), parameter :: markers = '&marker name = ''O'', body = ''ground'' /' &
            // nl // '&marker name = ''P'', body = ''bar'', position = -0.5, 0, 0 /'
        character(len=*), parameter :: hinge = '&joint type = ''revolute'', marker_i = ''O'', ' &
            // 'marker_j = ''P'' /'
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        ! the valid scene runs
        call parse_scene(pendulum(bar, markers, hinge, ''), 'mb.nml', scene, status)
        if (status%ok()) call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'valid pendulum: ' // status%text())
        call expect(error, pendulum(bar, markers, '&joint type = ''revolute'', marker_i = ''O'', &
            &marker_j = ''Q'' /', ''), "mb.nml: &joint: marker_j = 'Q': no &marker of that name")
        call expect(error, pendulum(bar, markers // nl // '&marker name = ''R'', body = ''rod'' /', &
            hinge, ''), "mb.nml: &marker: body = 'rod': no &rigid_body or &rigid_chain body of that name")
        call expect(error, pendulum(bar, markers, '&joint type = ''hinge'', marker_i = ''O'', &
            &marker_j = ''P'' /', ''), "mb.nml: &joint: type = 'hinge': must be one of")
        call expect(error, pendulum(bar, markers // nl // '&marker name = ''P2'', body = ''bar'' /', &
            '&joint type = ''spherical'', marker_i = ''P'', marker_j = ''P2'' /', ''), &
            "marker_j = 'P2': on the same body as marker_i ('bar')")
        call expect(error, pendulum(bar, markers, '&joint name = ''a'', type = ''spherical'', &
            &marker_i = ''O'', marker_j = ''P'' /' // nl // '&joint name = ''b'', type = &
            &''spherical'', marker_i = ''O'', marker_j = ''P'' /', ''), &
            "the constraint set is redundant or singular at t_start: 6 rows of rank 3")
        call expect(error, pendulum(bar, markers // nl // '&marker name = ''E'', body = ''bar'', &
            &position = 0.5, 0, 0 /' // nl // '&marker name = ''Q'', body = ''ground'', &
            &position = 3, 0, 0 /', hinge // nl // '&driver type = ''distance'', marker_i = ''Q'', &
            &marker_j = ''E'', coefficients = 5, 0, 0, 0 /', ''), 'no consistent initial state')
        call expect(error, pendulum('inertia_products = 0.2, 0, 0', markers, hinge, ''), &
            'the inertia tensor is not positive definite')
        call expect(error, '&simulation problem = ''pendulum'', t_end = 1 /' // nl // &
            '&rigid_body mass = 1 /', "&rigid_body: given, but problem = 'pendulum'")
        call expect(error, pendulum(bar, markers, hinge, '&multibody constraint_derivatives = &
            &''fd'' /'), "constraint_derivatives = 'fd': must be 'analytic', 'ad' or 'ad_full'")
        ! the full AD path runs from a scene too
        call parse_scene(pendulum(bar, markers, hinge, '&multibody constraint_derivatives = &
            &''ad_full'' /'), 'mb.nml', scene, status)
        if (status%ok()) call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'ad_full pendulum: ' // status%text())
        call expect(error, pendulum(bar, markers, hinge, '&multibody formulation = ''idx2'' /'), &
            "&multibody: formulation = 'idx2': must be one of")
    end subroutine test_bad_scenes
    !> inputs/double_pendulum_chain.nml: every solver reaches the same state
    !> (1e-6), and RADAU5 keeps the energy (undamped) to 1e-6 relative.
    subroutine test_chain_file(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        type(rigid_chain_t) :: chain
        real(wp), allocatable :: q0(:), v0(:)
        real(wp) :: y_ref(4), ek0, ep0, ek, ep
        integer :: k
        do k = 1, size(solvers)
            call run_file(error, 'inputs/double_pendulum_chain.nml', solvers(k), scene, result)
            if (allocated(error)) return
            if (k == 1) then
                y_ref = result%y(1:4)
                call build_rigid_chain(scene, chain, q0, v0, status)
                call chain%energy(q0, v0, ek0, ep0)
                call chain%energy(result%y(1:2), result%y(3:4), ek, ep)
                print '(4x,a,es9.2)', 'chain scene, RADAU5: relative energy drift ', &
                    abs(ek + ep - ek0 - ep0) / ek0
                call check(error, abs(ek + ep - ek0 - ep0) <= 1.0e-6_wp * ek0, 'energy drift')
            else
                call check(error, maxval(abs(result%y(1:4) - y_ref)) <= 1.0e-6_wp, &
                           trim(solvers(k)) // ': differs from RADAU5')
            end if
        end do
    end subroutine test_chain_file

    subroutine test_chain_bad(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: sim = '&simulation problem = ''rigid_chain'', ' // &
            't_end = 0.1 /' // nl
        character(len=*), parameter :: link = '&rigid_chain name = ''a'', mass = 1, ' // &
            'inertia = 1, 1, 1 /' // nl
        call expect(error, sim // link // '&rigid_chain name = ''b'', parent = ''c'', mass = 1, &
            &inertia = 1, 1, 1 /', "mb.nml: &rigid_chain: parent = 'c': must be 'ground' or a &
            &body of an earlier &rigid_chain group")
        call expect(error, sim // '&rigid_chain joint = ''ball'', mass = 1, inertia = 1, 1, 1 /', &
            "mb.nml: &rigid_chain: joint = 'ball': must be 'revolute', 'prismatic' or 'spherical'")
        call expect(error, sim // '&rigid_chain inertia = 1, 1, 1 /', &
            "&rigid_chain 'link 1': mass (default): must be positive (required)")
        call expect(error, '&simulation problem = ''pendulum'', t_end = 1 /' // nl // link, &
            "&rigid_chain: given, but problem = 'pendulum'")
    end subroutine test_chain_bad
    !> inputs/rigid_flexible_pendulum.nml: RADAU5 and DDASSL agree (1e-5);
    !> the attached face stays on the link (GGL: to the tolerance).
    subroutine test_rigid_flexible(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(2) = ['radau5', 'ddassl']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: y_ref(:)
        real(wp) :: r(3, 3), pin(3), worst
        integer :: k, j
        do k = 1, size(solvers)
            call run_file(error, 'inputs/rigid_flexible_pendulum.nml', solvers(k), scene, result)
            if (allocated(error)) return
            if (k == 1) then
                y_ref = result%y
                ! bar nodes 1, 6, 11, 16 (the xmin face of the 5 x 2 x 2 grid)
                ! sit at the link's tip corners (0.15, ±0.025, ±0.025)
                r = rotation_matrix(result%y(4:7))
                worst = 0.0_wp
                do j = 1, 4
                    pin = result%y(1:3) + matmul(r, [0.15_wp, merge(-0.025_wp, 0.025_wp, &
                        mod(j - 1, 2) == 0), merge(-0.025_wp, 0.025_wp, j <= 2)])
                    worst = max(worst, norm2(result%y(7 + 15 * (j - 1) + 1:7 + 15 * (j - 1) &
                                                      + 3) - pin))
                end do
                print '(4x,a,es9.2)', 'attached face off the link tip by ', worst
                call check(error, worst <= 1.0e-5_wp, 'the attached face left the link')
            else
                call check(error, maxval(abs(result%y(1:7) - y_ref(1:7))) <= 1.0e-5_wp, &
                           trim(solvers(k)) // ': link differs from RADAU5')
            end if
        end do
    end subroutine test_rigid_flexible

    subroutine test_rigid_flexible_bad(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: base = '&simulation problem = ''multibody'', ' // &
            't_end = 0.1 /' // nl // '&rigid_body name = ''link'', mass = 1, inertia = 1, 1, 1 /' &
            // nl // '&flexible_body name = ''bar'', lengths = 0.4, 0.05, 0.05 /' // nl // &
            '&material youngs_modulus = 7e5, density = 920 /' // nl // &
            '&marker name = ''tip'', body = ''link'' /' // nl // '&output file = ''none'' /' // nl
        call expect(error, base // '&marker name = ''root'', body = ''bar'' /', &
            "&marker: body = 'bar': a marker on a flexible body needs node_set")
        call expect(error, base // '&marker name = ''root'', body = ''bar'', node_set = &
            &''xmn'' /' // nl // '&joint type = ''attach'', marker_i = ''tip'', marker_j = &
            &''root'' /', "marker_j 'root': mesh: no node set named 'xmn'")
        call expect(error, base // '&marker name = ''root'', body = ''bar'', node_set = &
            &''xmin'' /' // nl // '&joint type = ''attach'', marker_i = ''root'', marker_j = &
            &''tip'' /', "'attach' joins a marker of a rigid body, a chain link or the ground")
        call expect(error, base // '&marker name = ''root'', body = ''bar'', node_set = &
            &''xmn'' /' // nl // '&joint type = ''revolute'', marker_i = ''tip'', marker_j = &
            &''root'' /', "&marker 'root': mesh: no node set named 'xmn'")
        call expect(error, base // '&marker name = ''m2'', body = ''link'', node_set = &
            &''xmin'' /', "&marker: node_set = 'xmin': only for markers on a &flexible_body")
        ! several flexible bodies: each material names its body, names are unique
        call expect(error, base // '&flexible_body name = ''pad'', lengths = 1, 1, 1 /', &
            "&material 'material 1': body: required (the &flexible_body it belongs to: the &
            &scene has 2)")
        call expect(error, base // '&flexible_body name = ''pad'', lengths = 1, 1, 1 /' // nl &
            // '&material youngs_modulus = 1e6, density = 1, body = ''pda'' /', &
            "&material: body = 'pda': no &flexible_body of that name (did you mean 'pad'?)")
        call expect(error, base // '&flexible_body name = ''pad'', lengths = 1, 1, 1 /', &
            "&flexible_body 'pad': needs a &material group naming it in body")
        call expect(error, base // '&flexible_body name = ''bar'', lengths = 1, 1, 1 /', &
            "&flexible_body: name = 'bar': also the name of the &flexible_body at line 3")
        call expect(error, base // '&flexible_body name = ''link'', lengths = 1, 1, 1 /', &
            "&flexible_body: name = 'link': also the name of a &rigid_body or &rigid_chain")
    end subroutine test_rigid_flexible_bad
    !> inputs/face_hinge.nml, a revolute joint on a node-set marker: the
    !> frame sits on the Kabsch fit of the bar's xmax face, the link's hub on
    !> the frame's origin with parallel hinge axes; RADAU5, DDASSL and IDA
    !> agree (1e-5).
    subroutine test_face_hinge(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(3) = ['radau5', 'ddassl', 'ida   ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        type(flexible_marker_t) :: fit
        real(wp), allocatable :: y_ref(:)
        real(wp) :: x_ref(3, 4), x(3, 4), origin(3), axes(3, 3), rl(3, 3), rf(3, 3), &
            dfit, djoint
        integer :: k, a
        do k = 1, size(solvers)
            call run_file(error, 'inputs/face_hinge.nml', solvers(k), scene, result)
            if (allocated(error)) return
            if (k > 1) then
                call check(error, maxval(abs(result%y(1:14) - y_ref(1:14))) <= 1.0e-5_wp, &
                           trim(solvers(k)) // ': link and frame differ from RADAU5')
                cycle
            end if
            y_ref = result%y
            ! xmax face: nodes 5, 10, 15, 20 of the 5 x 2 x 2 grid, free nodes
            ! 4, 8, 12, 16 (xmin is clamped), after the link's and frame's q
            do a = 1, 4
                x_ref(:, a) = [0.4_wp, merge(-0.025_wp, 0.025_wp, mod(a - 1, 2) == 0), &
                               merge(-0.025_wp, 0.025_wp, a <= 2)]
                x(:, a) = result%y(14 + 12 * a - 2:14 + 12 * a)
            end do
            call new_flexible_marker(fit, x_ref, [1, 2, 3, 4], status)
            call fit%pose(x, origin, axes, status)
            rf = rotation_matrix(result%y(11:14))
            dfit = max(norm2(origin - result%y(8:10)), maxval(abs(axes - rf)))
            rl = rotation_matrix(result%y(4:7))
            djoint = max(norm2(result%y(1:3) + matmul(rl, [-0.1_wp, 0.0_wp, 0.0_wp]) - &
                               result%y(8:10)), norm2(rl(:, 3) - rf(:, 3)))
            print '(4x,a,es9.2,a,es9.2,a,f7.4)', 'face hinge: frame off the fit ', dfit, &
                ', hinge off the frame ', djoint, ', tip deflection ', 0.0_wp - origin(2)
            call check(error, status%ok(), 'fit: ' // status%text())
            call check(error, dfit <= 1.0e-6_wp, 'the frame left the fit of the face')
            call check(error, djoint <= 1.0e-6_wp, 'the hinge opened')
            call check(error, -origin(2) > 0.01_wp, 'the bar did not bend')
        end do
    end subroutine test_face_hinge

    !> inputs/five_body.nml over its first 0.1 s: RADAU5, DDASSL and IDA
    !> reach the same state (1e-6), the constraints hold (GGL) and the rocker
    !> has begun to fall (its quaternion's x component grows).
    subroutine test_five_body(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(3) = ['radau5', 'ddassl', 'ida   ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        real(wp), allocatable :: y_ref(:)
        integer :: k, nq
        ! q: rocker, slider, two node frames (4 x 7), chain (2), coupler (135)
        nq = 4 * 7 + 2 + 135
        do k = 1, size(solvers)
            call run_file(error, 'inputs/five_body.nml', solvers(k), scene, result, &
                          t_end=0.1_wp)
            if (allocated(error)) return
            call check(error, result%has_drift .and. result%drift_end(1) <= 1.0e-8_wp .and. &
                       result%drift_end(2) <= 1.0e-6_wp, trim(solvers(k)) // ': drift')
            if (k == 1) then
                y_ref = result%y
                print '(4x,a,i0,a,es9.2,a,f8.5)', 'five-body: ', size(result%y), &
                    ' unknowns, RADAU5 drift ', result%drift_end(1), ', rocker e1 ', result%y(5)
                call check(error, result%y(5) > 1.0e-3_wp, 'the rocker did not start to fall')
            else
                print '(4x,a,es9.2)', trim(solvers(k)) // ': positions off RADAU5 by ', &
                    maxval(abs(result%y(1:nq) - y_ref(1:nq)))
                call check(error, maxval(abs(result%y(1:nq) - y_ref(1:nq))) <= 1.0e-5_wp, &
                           trim(solvers(k)) // ': positions differ from RADAU5')
            end if
        end do
    end subroutine test_five_body

    !> DDASSL and IDA on the four-bar with GGL at rtol = atol = 1e-8: they
    !> measure the multipliers λ and μ in the Newton test as h δ, without
    !> which they stopped at t0 (μ = 0 has only atol for its weight, and the
    !> round-off of δ grows like 1/h); they reach RADAU5's state (1e-6).
    subroutine test_bdf_tight(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(3) = ['radau5', 'ddassl', 'ida   ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        real(wp), allocatable :: y_ref(:)
        integer :: k
        do k = 1, size(solvers)
            call run_file(error, 'inputs/four_bar.nml', solvers(k), scene, result, &
                          tol=1.0e-8_wp)
            if (allocated(error)) return
            if (k == 1) then
                y_ref = result%y(1:21)
            else
                print '(4x,a,es9.2,a,a)', trim(solvers(k)) // ' at 1e-8, off RADAU5 by ', &
                    maxval(abs(result%y(1:21) - y_ref)), ': ', result%stats%summary()
                call check(error, maxval(abs(result%y(1:21) - y_ref)) <= 1.0e-6_wp, &
                           trim(solvers(k)) // ' differs from RADAU5')
            end if
        end do
    end subroutine test_bdf_tight

    !> inputs/four_bar.nml (RADAU5, GGL) at rtol = atol = 1e-8, 1e-10, 1e-12:
    !> the motor's torque on the crank at the 101 output times, in the HDF5
    !> file's /drivers/motor and /reactions, against the closed form's power
    !> balance. The reactions come from the multipliers consistent with the
    !> output's q and v, so they converge with the positions (measured max
    !> errors 3.1e-8, 1.1e-9, 5.9e-11); from the integrator's λ (index 2,
    !> its dense output) they were 6.3e-6, 9.0e-7, 1.7e-7.
    subroutine test_torque_tight(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: h5 = 'build/test-torque.h5'
        real(wp), parameter :: tols(3) = [1.0e-8_wp, 1.0e-10_wp, 1.0e-12_wp]
        real(wp), parameter :: bounds(3) = [1.0e-7_wp, 5.0e-9_wp, 3.0e-10_wp]
        real(wp), parameter :: mass(3) = [1.0_wp, 0.5_wp, 0.333_wp], inertia(3) = 0.01_wp
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: named(:, :), table(:, :)
        real(wp) :: dev(3), exact
        integer :: k, i, err, unit
        call h5open_f(err)
        do k = 1, size(tols)
            call read_scene('inputs/four_bar.nml', scene, status)
            call check(error, status%ok(), 'read: ' // status%text())
            if (allocated(error)) return
            scene%output_file = h5
            scene%progress = .false.
            scene%rtol = tols(k)
            scene%atol = tols(k)
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), 'run: ' // status%text())
            if (allocated(error)) return
            call read_matrix(h5, 'drivers/motor/reaction_torque_j', named, error)
            if (allocated(error)) return
            call read_matrix(h5, 'reactions', table, error)
            if (allocated(error)) return
            call check(error, size(named, 2) == 101 .and. size(table, 2) == 101, 'records')
            if (allocated(error)) return
            ! the driver is the fifth system joint: n_j in rows 58:60 of /reactions
            call check(error, all(named == table(58:60, :)), '/reactions and /drivers differ')
            if (allocated(error)) return
            dev(k) = 0.0_wp
            do i = 1, 101
                exact = four_bar_torque(real(i - 1, wp) / 100.0_wp, mass, inertia, 9.81_wp)
                dev(k) = max(dev(k), abs(named(3, i) - exact))
            end do
            print '(4x,a,es8.1,a,es9.2)', 'rtol ', tols(k), &
                ': motor torque off the closed form by ', dev(k)
            call check(error, dev(k) <= bounds(k), 'motor torque off the closed form')
            if (allocated(error)) return
        end do
        call check(error, dev(2) <= 0.1_wp * dev(1) .and. dev(3) <= 0.1_wp * dev(2), &
                   'the torque error does not fall with the tolerance')
        open (newunit=unit, file=h5)
        close (unit, status='delete')
    end subroutine test_torque_tight

    !> Read the scene file, run it with `solver` (no output file), at
    !> rtol = atol = tol and to t_end when given.
    subroutine run_file(error, path, solver, scene, result, tol, t_end)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: path, solver
        type(scene_input_t), intent(out) :: scene
        type(run_result_t), intent(out) :: result
        real(wp), intent(in), optional :: tol, t_end
        type(status_t) :: status
        call read_scene(path, scene, status)
        call check(error, status%ok(), 'read: ' // status%text())
        if (allocated(error)) return
        scene%output_file = ''
        scene%progress = .false.
        scene%solver_name = solver
        if (present(tol)) then
            scene%rtol = tol
            scene%atol = tol
        end if
        if (present(t_end)) scene%t_end = t_end
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), trim(solver) // ': ' // status%text())
    end subroutine run_file
    !> The four-bar with an HDF5 file: /monitor holds (t, ‖g‖, ‖Gv + g_I‖,
    !> energy) at the 101 output times (dense output between steps: GGL keeps
    !> the drifts at the tolerance level there, rtol 1e-7); the summary
    !> reports the last; after one crank revolution the energy returns.
    subroutine test_monitor(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: h5 = 'build/test-monitor.h5'
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        integer(hsize_t) :: dims(2)
        real(wp), allocatable :: table(:, :)
        integer :: err, unit
        call read_scene('inputs/four_bar.nml', scene, status)
        scene%output_file = h5
        scene%progress = .false.
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call check(error, result%has_drift .and. result%constraints == 18 .and. &
                   maxval(result%drift_end) <= 1.0e-8_wp, 'summary drift')
        call h5open_f(err)
        call read_matrix(h5, 'monitor', table, error)
        if (allocated(error)) return
        dims = shape(table, kind=hsize_t)
        call check(error, all(dims == [4_hsize_t, 101_hsize_t]), '/monitor shape')
        if (allocated(error)) return
        print '(4x,a,2es9.2,a,2es10.2)', 'four-bar monitor: max drift ', &
            maxval(table(2, :)), maxval(table(3, :)), ', energy from/to ', table(4, 1), &
            table(4, 101)
        call check(error, table(1, 101) == 1.0_wp .and. maxval(table(2:3, :)) <= 1.0e-6_wp, &
                   '/monitor values')
        call check(error, abs(table(4, 101) - table(4, 1)) <= 1.0e-5_wp * abs(table(4, 1)), &
                   'energy after one revolution')
        call check(error, all(table(4, :) == table(4, :)), 'energy not finite')
        ! /reactions: 12 numbers per system joint (4 joints and the driver)
        call read_matrix(h5, 'reactions', table, error)
        if (allocated(error)) return
        dims = shape(table, kind=hsize_t)
        call check(error, all(dims == [60_hsize_t, 101_hsize_t]), '/reactions shape')
        ! the motor drives the crank: its torque on the crank is not zero
        call check(error, maxval(abs(table(58:60, :))) > 0.0_wp .and. &
                   all(table == table), '/reactions values')
        open (newunit=unit, file=h5)
        close (unit, status='delete')
    end subroutine test_monitor
    !> A 2-D real dataset of an HDF5 file.
    subroutine read_matrix(path, name, table, error)
        character(len=*), intent(in) :: path, name
        real(wp), allocatable, intent(out) :: table(:, :)
        type(error_t), allocatable, intent(inout) :: error
        integer(hid_t) :: file, dset, space
        integer(hsize_t) :: dims(2), maxdims(2)
        integer :: err
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        call h5dopen_f(file, name, dset, err)
        call check(error, err >= 0, '/' // name // ' missing')
        if (allocated(error)) return
        call h5dget_space_f(dset, space, err)
        call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
        allocate (table(dims(1), dims(2)))
        call h5dread_f(dset, H5T_NATIVE_DOUBLE, table, dims, err)
        call h5sclose_f(space, err)
        call h5dclose_f(dset, err)
        call h5fclose_f(file, err)
    end subroutine read_matrix
    !> inputs/four_bar_chain.nml (the crank as a one-link chain inside the
    !> multibody system) with each solver: the coupler end on the closed form.
    subroutine test_four_bar_chain(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        real(wp) :: b(3), c(3), r(3, 3), dev
        integer :: k
        do k = 1, size(solvers)
            call run_file(error, 'inputs/four_bar_chain.nml', solvers(k), scene, result)
            if (allocated(error)) return
            call four_bar_exact(crank_angle(1.0_wp), b, c)
            ! q = (coupler r, p; rocker r, p; crank angle)
            r = rotation_matrix(result%y(4:7))
            dev = max(norm2(result%y(1:3) + 0.5_wp * bar_b * r(:, 1) - c), &
                      abs(atan2(sin(result%y(15) - crank_angle(1.0_wp)), &
                                cos(result%y(15) - crank_angle(1.0_wp)))))
            print '(4x,a,a,es9.2)', solvers(k), ': four-bar with a chain crank off by ', dev
            call check(error, dev <= 1.0e-5_wp, trim(solvers(k)) // ': off the closed form')
        end do
    end subroutine test_four_bar_chain

    !> inputs/four_bar_chains.nml: crank and rocker as two chains, a rope of
    !> 8 links (11 coordinates) as a third between them in the file. Links
    !> map to (chain, link) tree by tree; the coupler and crank follow the
    !> closed form (RADAU5, 1e-5 at rtol 1e-7); the rope swings freely.
    subroutine test_four_bar_chains(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: links(4) = ['crank ', 'rope 1', 'rocker', 'rope 8']
        integer, parameter :: chain_of(4) = [1, 2, 3, 2], link_of(4) = [1, 1, 1, 8]
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        real(wp) :: b(3), c(3), r(3, 3), dev
        integer :: k, chain, link
        call run_file(error, 'inputs/four_bar_chains.nml', 'radau5', scene, result)
        if (allocated(error)) return
        do k = 1, size(links)
            call chain_link(scene, trim(links(k)), chain, link)
            call check(error, chain == chain_of(k) .and. link == link_of(k), &
                       trim(links(k)) // ': wrong chain or link')
            if (allocated(error)) return
        end do
        call four_bar_exact(crank_angle(1.0_wp), b, c)
        ! q = (coupler r, p; crank; rope; rocker)
        r = rotation_matrix(result%y(4:7))
        dev = max(norm2(result%y(1:3) + 0.5_wp * bar_b * r(:, 1) - c), &
                  abs(atan2(sin(result%y(8) - crank_angle(1.0_wp)), &
                            cos(result%y(8) - crank_angle(1.0_wp)))))
        print '(4x,a,es9.2)', 'four-bar with crank and rocker as two chains off by ', dev
        call check(error, dev <= 1.0e-5_wp, 'two chains: off the closed form')
        call check(error, abs(result%y(9) + 0.5_wp) > 0.1_wp, 'the rope did not swing')
    end subroutine test_four_bar_chains
end module test_multibody_scene
