!> The table of joint types (src/mbs/joint_types.f90): every type is found
!> by its name, the schema's choices are the table's, a joint built from an
!> entry has the entry's rows (the constraint count of its mechanism: 6
!> minus its degrees of freedom), and a scene's unknown joint type is bad
!> input at the builder, never a default.
module test_joint_types
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_mbs_joint, only: joint_t, new_joint
    use flexmbs_mbs_joint_types, only: joint_types, joint_choices, joint_kind, joint_name, &
        joint_type_rows, joint_primitive
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_run_multibody_builder, only: build_multibody
    use flexmbs_core_kinds, only: wp
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_joint_types

    character(len=*), parameter :: nl = new_line('a')

contains

    !> The suite.
    function collect_joint_types() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('table_names_and_choices', test_names), &
                 new_test('rows_are_six_minus_freedoms', test_rows), &
                 new_test('builder_refuses_unknown_type', test_unknown)]
    end function collect_joint_types

    !> joint_kind(joint_name(k)) = k for every type a scene may name, and
    !> joint_choices lists exactly those, in table order.
    subroutine test_names(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=:), allocatable :: listed
        integer :: k
        listed = ''
        do k = 1, size(joint_types)
            if (k == joint_primitive) then
                call check(error, joint_kind(joint_name(k)) == 0, &
                           'joint_primitive must be no &joint choice')
                cycle
            end if
            call check(error, joint_kind(joint_name(k)) == k, 'kind of ' // joint_name(k))
            if (len(listed) > 0) listed = listed // '|'
            listed = listed // joint_name(k)
        end do
        call check(error, listed == joint_choices, 'joint_choices ' // joint_choices // &
                   ' differs from the table: ' // listed)
        call check(error, joint_kind('hinge') == 0 .and. joint_name(0) == 'unknown' .and. &
                   joint_name(size(joint_types) + 1) == 'unknown', 'unknown names and kinds')
    end subroutine test_names

    !> A joint removes 6 minus its freedoms of relative motion (spherical:
    !> 3 rotations; revolute 1; cylindrical 2; prismatic 1; universal 2;
    !> fixed 0; planar: 2 translations and the rotation about the normal).
    subroutine test_rows(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: names(7) = [character(len=12) :: 'spherical', &
            'revolute', 'cylindrical', 'prismatic', 'universal', 'fixed', 'planar']
        integer, parameter :: freedoms(7) = [3, 1, 2, 1, 2, 0, 3]
        type(joint_t) :: joint
        type(status_t) :: status
        integer :: k, kind
        do k = 1, size(names)
            kind = joint_kind(trim(names(k)))
            call check(error, kind > 0, trim(names(k)) // ' is not in the table')
            if (allocated(error)) return
            call new_joint(joint, kind, status)
            call check(error, status%ok() .and. joint%kind == kind .and. &
                       joint%nrows == 6 - freedoms(k) .and. &
                       joint_type_rows(kind) == 6 - freedoms(k), trim(names(k)) // ': rows')
        end do
        call new_joint(joint, joint_primitive, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), joint_choices) > 0, 'joint_primitive without ' // &
                   'a primitive: ' // status%text())
    end subroutine test_rows

    !> A scene whose &joint type the schema would refuse, given to the
    !> builder directly: bad input naming the file, joint, value and choices.
    subroutine test_unknown(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:)
        call parse_scene('&simulation problem = ''multibody'', t_end = 0.1 /' // nl // &
            '&rigid_body name = ''bar'', mass = 1, inertia = 0.1, 0.1, 0.1 /' // nl // &
            '&marker name = ''O'', body = ''ground'' /' // nl // &
            '&marker name = ''P'', body = ''bar'' /' // nl // &
            '&joint name = ''pin'', type = ''revolute'', marker_i = ''O'', marker_j = ''P'' /' &
            // nl // '&output file = ''none'' /', 'mb.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        if (allocated(error)) return
        call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), 'the revolute scene builds: ' // status%text())
        scene%joints(1)%type = 'hinge'
        call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%code == status_bad_input .and. index(status%text(), &
                   "mb.nml: &joint 'pin': type = 'hinge': no joint type of that name; " // &
                   'use one of ' // joint_choices // '|attach') > 0, status%text())
    end subroutine test_unknown
end module test_joint_types
