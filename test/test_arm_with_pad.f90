!> inputs/arm_with_pad.nml: a branching rigid arm in relative coordinates
!> (one &rigid_chain tree) holding a soft pad by 'attach' joints on two of
!> its links, against the same arm of rigid bodies in absolute coordinates
!> with revolute joints holding the same pad: the pad moves alike.
module test_arm_with_pad
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_io_namelist, only: scene_input_t, parse_scene, read_scene
    use flexmbs_run_runner, only: run_scene, run_result_t
    use flexmbs_run_multibody_builder, only: build_multibody
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_arm_with_pad

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_arm_with_pad() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('relative_vs_absolute', test_relative_absolute)]
    end function collect_arm_with_pad

    !> The arm of inputs/arm_with_pad.nml as four rigid bodies (centres of
    !> mass in the world at t = 0, every body turning with the base about y
    !> at 1 rad/s: velocity ω × c) on revolute joints at the chain's joint
    !> positions, and the same pad, materials and attach joints.
    function absolute_scene() result(text)
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.3 /' // nl // &
            '&multibody formulation = ''ggl'', gravity = 0, -9.81, 0 /' // nl // &
            '&rigid_body name = ''base'', mass = 2, inertia = 0.01, 0.005, 0.01, ' // &
            'position = 0, 0.1, 0, angular_velocity = 0, 1, 0 /' // nl // &
            '&rigid_body name = ''arm'', mass = 1, inertia = 0.0005, 0.014, 0.014, ' // &
            'position = 0.2, 0.2, 0, velocity = 0, 0, -0.2, angular_velocity = 0, 1, 0 /' // nl &
            // finger('upper finger', '0.23') // finger('lower finger', '0.17') // &
            '&flexible_body name = ''pad'', divisions = 2, 1, 1, lengths = 0.1, 0.06, 0.05, ' // &
            'origin = 0.45, 0.17, -0.025, gravity = 0, -9.81, 0, ' // &
            'initial_velocity = 0, 0, -0.5, initial_angular_velocity = 0, 1, 0 /' // nl // &
            '&material name = ''soft'', youngs_modulus = 7e5, density = 920, ' // &
            'viscosity = 1000 /' // nl // &
            hinge('base', 'ground', '0, 0, 0', 'base', '0, -0.1, 0', '0, 1, 0') // &
            hinge('arm', 'base', '0, 0.1, 0', 'arm', '-0.2, 0, 0', '0, 0, 1') // &
            hinge('upper', 'arm', '0.2, 0.03, 0', 'upper finger', '-0.075, 0, 0', '0, 0, 1') // &
            hinge('lower', 'arm', '0.2, -0.03, 0', 'lower finger', '-0.075, 0, 0', '0, 0, 1') // &
            '&marker name = ''upper grip'', body = ''upper finger'' /' // nl // &
            '&marker name = ''lower grip'', body = ''lower finger'' /' // nl // &
            '&marker name = ''pad top'', body = ''pad'', node_set = ''ymax'' /' // nl // &
            '&marker name = ''pad bottom'', body = ''pad'', node_set = ''ymin'' /' // nl // &
            '&joint type = ''attach'', marker_i = ''upper grip'', marker_j = ''pad top'' /' // &
            nl // '&joint type = ''attach'', marker_i = ''lower grip'', marker_j = ' // &
            '''pad bottom'' /' // nl // '&output file = ''none'' /' // nl
    contains
        function finger(name, y) result(group)
            character(len=*), intent(in) :: name, y
            character(len=:), allocatable :: group
            group = '&rigid_body name = ''' // name // ''', mass = 0.1, ' // &
                'inertia = 2e-5, 2e-4, 2e-4, position = 0.475, ' // y // ', 0, ' // &
                'velocity = 0, 0, -0.475, angular_velocity = 0, 1, 0 /' // nl
        end function finger

        !> A revolute joint about `axis` (world, at t = 0) between a marker
        !> of `parent` at `at_parent` and one of `child` at `at_child`.
        function hinge(name, parent, at_parent, child, at_child, axis) result(group)
            character(len=*), intent(in) :: name, parent, at_parent, child, at_child, axis
            character(len=:), allocatable :: group
            group = '&marker name = ''' // name // ' i'', body = ''' // parent // &
                ''', position = ' // at_parent // ', z_axis = ' // axis // ' /' // nl // &
                '&marker name = ''' // name // ' j'', body = ''' // child // &
                ''', position = ' // at_child // ', z_axis = ' // axis // ' /' // nl // &
                '&joint type = ''revolute'', marker_i = ''' // name // ' i'', marker_j = ''' &
                // name // ' j'' /' // nl
        end function hinge
    end function absolute_scene

    !> RADAU5 at rtol 1e-6 and 1e-8 over 0.3 s: the pad's free nodal
    !> positions of both models differ by at most 1e-6 m and 1e-8 m
    !> (measured 1.1e-8, 3.0e-10), and the difference shrinks with the
    !> tolerance (the pad swings by 0.5 m).
    subroutine test_relative_absolute(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: tols(2) = [1.0e-6_wp, 1.0e-8_wp], bounds(2) = [1.0e-6_wp, &
            1.0e-8_wp]
        type(scene_input_t) :: relative, absolute
        type(run_result_t) :: r_rel, r_abs
        type(mbs_system_t), target :: sys_rel, sys_abs
        type(flexible_body_t), pointer :: body
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:)
        real(wp) :: diff(2), swing
        integer :: i, fr, fa, n
        call read_scene('inputs/arm_with_pad.nml', relative, status)
        if (status%ok()) call parse_scene(absolute_scene(), 'absolute.nml', absolute, status)
        if (status%ok()) call build_multibody(relative, sys_rel, q0, v0, status)
        if (status%ok()) call build_multibody(absolute, sys_abs, q0, v0, status)
        call check(error, status%ok(), 'scenes: ' // status%text())
        if (allocated(error)) return
        call sys_rel%flexible_coordinates(1, fr, n)
        call sys_abs%flexible_coordinates(1, fa, n)
        body => sys_rel%flexible_of(1)
        do i = 1, size(tols)
            call run(relative, r_rel)
            if (.not. allocated(error)) call run(absolute, r_abs)
            if (allocated(error)) return
            diff(i) = maxval(abs(r_rel%y(fr + 1:fr + n) - r_abs%y(fa + 1:fa + n)))
            swing = maxval(abs(r_rel%y(fr + 1:fr + n) - body%free_positions()))
        end do
        print '(4x,a,2es9.2,a,es9.2,a)', 'arm with pad, relative against absolute: ', diff, &
            ' m at rtol 1e-6, 1e-8 (the pad moved ', swing, ' m)'
        call check(error, swing > 0.1_wp, 'the pad did not swing')
        call check(error, all(diff <= bounds), 'the two models differ beyond the bounds')
        call check(error, diff(2) < diff(1), 'the difference does not shrink with the tolerance')

    contains

        subroutine run(scene, result)
            type(scene_input_t), intent(inout) :: scene
            type(run_result_t), intent(out) :: result
            scene%solver_name = 'radau5'
            scene%rtol = tols(i)
            scene%atol = tols(i)
            scene%output_file = ''
            scene%progress = .false.
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), trim(scene%path) // ': ' // status%text())
        end subroutine run
    end subroutine test_relative_absolute
end module test_arm_with_pad
