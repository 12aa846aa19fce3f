!> Checks of `&multibody`, `&rigid_body`, `&marker`, `&joint`, `&driver`
!> and `&rigid_chain` beyond the schema's ranges: the groups present
!> exactly for their problem, required values, unique names, references
!> to bodies and markers that exist (with the nearest known name when
!> one is misspelt). Constraint rank, inertia tensors and the initial
!> assembly are checked when the system is built.
module flexmbs_io_multibody_checks
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_io_input_errors, only: input_errors_t, excerpt, at_other
    use flexmbs_io_scene_schema, only: did_you_mean, len_name
    use flexmbs_io_scene_lexer, only: entry_t, has_entry, instance_ranges
    use flexmbs_io_scene_values, only: value_error, required_error
    use flexmbs_io_scene_input, only: scene_input_t, marker_index, flexible_index
    implicit none
    private

    public :: check_multibody, check_chain

contains

    !> &rigid_chain groups: present exactly for problem = 'rigid_chain' (or
    !> a multibody scene), each parent the ground or an earlier link.
    subroutine check_chain(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i, j
        logical :: found
        if (scene%problem /= 'rigid_chain' .and. &
            .not. (scene%problem == 'multibody' .and. size(scene%chain) > 0)) then
            if (size(scene%chain) > 0) call errors%add('&rigid_chain: given, but problem = ''' &
                // trim(scene%problem) // ''' (a scene builds only what it declares)', &
                scene%chain(1)%line)
            return
        end if
        if (size(scene%chain) == 0) then
            call errors%add('&simulation: problem = ''rigid_chain'': needs at least one &
                &&rigid_chain group (one per body)', 0)
            return
        end if
        do i = 1, size(scene%chain)
            associate (b => scene%chain(i))
                found = b%parent == 'ground'
                do j = 1, i - 1
                    if (scene%chain(j)%name == b%parent) found = .true.
                    if (scene%chain(j)%name == b%name) call bad('name', i, &
                        'also the name of the &rigid_chain' // at_other(scene%chain(j)%line))
                end do
                if (.not. found) call bad('parent', i, 'must be ''ground'' or a body of an &
                    &earlier &rigid_chain group' // did_you_mean(trim(b%parent), &
                    [character(len=len_name) :: scene%chain(1:i - 1)%name, 'ground']))
                if (b%joint == 'spherical' .and. .not. norm2(b%rotation_axis) > 0.0_wp) &
                    call bad('rotation_axis', i, 'must not be zero')
                if (.not. norm2(b%joint_axis) > 0.0_wp) call bad('joint_axis', i, &
                    'must not be zero')
                if (.not. b%mass > 0.0_wp) call bad('mass', i, 'must be positive (required)')
                if (any(.not. b%inertia > 0.0_wp)) call bad('inertia', i, &
                    'must be positive (required: Jxx, Jyy, Jzz)')
            end associate
        end do

    contains

        subroutine bad(name, instance, reason)
            character(len=*), intent(in) :: name, reason
            integer, intent(in) :: instance
            call value_error(errors, entries, 'rigid_chain', name, reason, instance, &
                             scene%chain(instance)%name, scene%chain(instance)%line)
        end subroutine bad
    end subroutine check_chain

    !> &multibody, &rigid_body, &marker, &joint and &driver: present exactly
    !> for problem = 'multibody'; required values; names unique and known.
    subroutine check_multibody(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=16), parameter :: mb_groups(6) = [character(len=16) :: 'multibody', &
            'rigid_body', 'marker', 'joint', 'driver', 'force']
        integer :: i, g
        integer, allocatable :: ranges(:, :)
        if (scene%problem /= 'multibody') then
            do g = 1, size(mb_groups)
                ! a chain takes gravity and formulation from &multibody
                if (g == 1 .and. scene%problem == 'rigid_chain') cycle
                if (given(scene, entries, mb_groups(g)) .or. &
                    (g == 1 .and. scene%has_multibody)) then
                    call errors%add('&' // trim(mb_groups(g)) // ': given, but problem = ''' // &
                        trim(scene%problem) // ''' (a scene builds only what it declares)', 0)
                    return
                end if
            end do
            return
        end if
        if (size(scene%rigid_bodies) + size(scene%chain) + size(scene%bodies) == 0) &
            call errors%add('&simulation: problem = ''multibody'': needs at least one &
            &&rigid_body, &rigid_chain or &flexible_body group', 0)
        call check_rigid_bodies(scene, entries, errors)
        ! each occurrence's own entries: linear in the number of groups
        call instance_ranges(entries, 'marker', size(scene%markers), ranges)
        do i = 1, size(scene%markers)
            call check_marker(scene, entries, errors, i, entries(ranges(1, i):ranges(2, i)))
        end do
        call check_joints(scene, entries, errors)
        call check_drivers(scene, entries, errors)
    end subroutine check_multibody

    !> Whether some entry of `group` was given (empty groups count via the scene).
    logical function given(scene, entries, group)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group
        integer :: e
        given = .false.
        do e = 1, size(entries)
            if (entries(e)%group == group) given = .true.
        end do
        select case (group)
        case ('rigid_body'); given = given .or. size(scene%rigid_bodies) > 0
        case ('marker'); given = given .or. size(scene%markers) > 0
        case ('joint'); given = given .or. size(scene%joints) > 0
        case ('driver'); given = given .or. size(scene%drivers) > 0
        case ('force'); given = given .or. size(scene%forces) > 0
        end select
    end function given

    !> Each &rigid_body: mass and inertia given, a rotation axis, a unique
    !> name that is not 'ground'.
    subroutine check_rigid_bodies(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i, j
        integer, allocatable :: ranges(:, :)
        call instance_ranges(entries, 'rigid_body', size(scene%rigid_bodies), ranges)
        do i = 1, size(scene%rigid_bodies)
            associate (b => scene%rigid_bodies(i), own => entries(ranges(1, i):ranges(2, i)))
                if (.not. has_entry(own, 'rigid_body', 'mass', i)) call required_error( &
                    errors, 'rigid_body', 'mass', 'in kg', b%name, b%line)
                if (.not. has_entry(own, 'rigid_body', 'inertia', i)) call required_error( &
                    errors, 'rigid_body', 'inertia', 'Jxx, Jyy, Jzz in kg m^2 about the centre &
                    &of mass', b%name, b%line)
                if (.not. norm2(b%rotation_axis) > 0.0_wp) call value_error(errors, entries, &
                    'rigid_body', 'rotation_axis', 'must not be zero', i)
                do j = 1, i - 1
                    if (scene%rigid_bodies(j)%name == b%name) call value_error(errors, entries, &
                        'rigid_body', 'name', 'also the name of the &rigid_body' // &
                        at_other(scene%rigid_bodies(j)%line), i)
                end do
                if (b%name == 'ground') call value_error(errors, entries, 'rigid_body', 'name', &
                    '''ground'' is reserved', i)
            end associate
        end do
    end subroutine check_rigid_bodies

    !> Each &joint: a type, two markers on different bodies; 'attach' from a
    !> rigid side to a node-set marker of a flexible body.
    subroutine check_joints(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i
        integer, allocatable :: ranges(:, :)
        call instance_ranges(entries, 'joint', size(scene%joints), ranges)
        do i = 1, size(scene%joints)
            associate (jt => scene%joints(i), own => entries(ranges(1, i):ranges(2, i)))
                if (.not. has_entry(own, 'joint', 'type', i)) then
                    call required_error(errors, 'joint', 'type', 'spherical, revolute, ...', &
                                        jt%name, jt%line)
                else
                    call check_markers(scene, entries, errors, 'joint', i, jt%marker_i, &
                                       jt%marker_j, jt%name, jt%line)
                end if
                if (jt%type == 'attach') then
                    if (.not. (on_flexible(scene, jt%marker_j) .and. &
                               .not. on_flexible(scene, jt%marker_i))) &
                        call value_error(errors, entries, 'joint', 'type', '''attach'' joins a &
                        &marker of a rigid body, a chain link or the ground (marker_i) to a &
                        &node-set marker of a flexible body (marker_j)', i)
                end if
            end associate
        end do
    end subroutine check_joints

    !> Each &driver: a type, two markers on different bodies, a ramp with
    !> its duration.
    subroutine check_drivers(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i
        integer, allocatable :: ranges(:, :)
        call instance_ranges(entries, 'driver', size(scene%drivers), ranges)
        do i = 1, size(scene%drivers)
            associate (d => scene%drivers(i), own => entries(ranges(1, i):ranges(2, i)))
                if (.not. has_entry(own, 'driver', 'type', i)) then
                    call required_error(errors, 'driver', 'type', 'angle, translation or &
                        &distance', d%name, d%line)
                else
                    call check_markers(scene, entries, errors, 'driver', i, d%marker_i, &
                                       d%marker_j, d%name, d%line)
                end if
                if (d%ramp_rate /= 0.0_wp .and. .not. d%ramp_time > 0.0_wp) call value_error( &
                    errors, entries, 'driver', 'ramp_time', 'must be positive with ramp_rate &
                    &(the ramp''s duration in s)', i, d%name, d%line)
            end associate
        end do
    end subroutine check_drivers

    !> Marker i (its entries `own`): on a known body, with a node set exactly
    !> on a flexible body, axes neither zero nor parallel, a unique name.
    subroutine check_marker(scene, entries, errors, i, own)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer, intent(in) :: i
        type(entry_t), intent(in) :: own(:) !! the marker's entries
        integer :: j
        real(wp) :: c(3)
        associate (m => scene%markers(i))
            if (flexible_index(scene, m%body) > 0) then
                if (len_trim(m%node_set) == 0) call value_error(errors, entries, 'marker', &
                    'body', 'a marker on a flexible body needs node_set (the nodes a &
                    &joint attaches)', i, m%name, m%line)
            else if (len_trim(m%node_set) > 0) then
                call value_error(errors, entries, 'marker', 'node_set', 'only for markers on &
                    &a &flexible_body', i)
            else if (m%body /= 'ground' .and. .not. any(scene%rigid_bodies%name == m%body) &
                     .and. .not. any(scene%chain%name == m%body)) then
                call value_error(errors, entries, 'marker', 'body', 'no &rigid_body or &
                    &&rigid_chain body of that name (nor ''ground'')' // &
                    did_you_mean(trim(m%body), body_names(scene)), i, m%name, m%line)
            end if
            if (.not. norm2(m%z_axis) > 0.0_wp) then
                call value_error(errors, entries, 'marker', 'z_axis', 'must not be zero', i)
            else if (has_entry(own, 'marker', 'x_axis', i)) then
                c = [m%x_axis(2) * m%z_axis(3) - m%x_axis(3) * m%z_axis(2), &
                     m%x_axis(3) * m%z_axis(1) - m%x_axis(1) * m%z_axis(3), &
                     m%x_axis(1) * m%z_axis(2) - m%x_axis(2) * m%z_axis(1)]
                if (norm2(c) <= 1.0e-12_wp * norm2(m%z_axis) * norm2(m%x_axis)) &
                    call value_error(errors, entries, 'marker', 'x_axis', 'must not be &
                    &parallel to z_axis (nor zero)', i)
            end if
            do j = 1, i - 1
                if (scene%markers(j)%name == m%name) call value_error(errors, entries, &
                    'marker', 'name', 'also the name of the &marker' // &
                    at_other(scene%markers(j)%line), i)
            end do
        end associate
    end subroutine check_marker

    !> The names a marker's body may have: the ground, the rigid bodies, the
    !> links and the flexible bodies.
    function body_names(scene) result(names)
        type(scene_input_t), intent(in) :: scene
        character(len=len_name), allocatable :: names(:)
        names = [character(len=len_name) :: 'ground', &
                 scene%rigid_bodies%name, scene%chain%name]
        if (scene%has_body()) names = [names, scene%bodies%name]
    end function body_names

    !> The marker of that name sits on a flexible body.
    logical function on_flexible(scene, name)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        integer :: k
        on_flexible = .false.
        k = marker_index(scene, name)
        if (k > 0) on_flexible = flexible_index(scene, scene%markers(k)%body) > 0
    end function on_flexible

    !> Both markers exist and sit on different bodies.
    subroutine check_markers(scene, entries, errors, group, instance, mi, mj, label, line)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=*), intent(in) :: group, mi, mj, label
        integer, intent(in) :: instance, line
        integer :: ki, kj, k
        character(len=len_name), allocatable :: names(:)
        names = scene%markers%name
        ki = 0
        kj = 0
        do k = size(scene%markers), 1, -1
            if (scene%markers(k)%name == mi) ki = k
            if (scene%markers(k)%name == mj) kj = k
        end do
        if (ki == 0) call value_error(errors, entries, group, 'marker_i', 'no &marker of &
            &that name' // did_you_mean(trim(mi), names) // known(scene), &
            instance, label, line)
        if (kj == 0) call value_error(errors, entries, group, 'marker_j', 'no &marker of &
            &that name' // did_you_mean(trim(mj), names) // known(scene), &
            instance, label, line)
        if (ki > 0 .and. kj > 0) then
            if (scene%markers(ki)%body == scene%markers(kj)%body) call value_error(errors, &
                entries, group, 'marker_j', 'on the same body as marker_i (''' // &
                trim(scene%markers(ki)%body) // ''')', instance, label, line)
        end if
    end subroutine check_markers

    !> ' (known: a, b, ...)', at most ~80 characters of the markers' names.
    function known(scene) result(text)
        type(scene_input_t), intent(in) :: scene
        character(len=:), allocatable :: text
        integer :: k
        text = ''
        do k = 1, size(scene%markers)
            if (len(text) > 60) then
                text = text // ', ...'
                exit
            end if
            if (k > 1) text = text // ', '
            text = text // trim(scene%markers(k)%name)
        end do
        text = ' (known: ' // excerpt(text) // ')'
        if (size(scene%markers) == 0) text = ' (no &marker given)'
    end function known

end module flexmbs_io_multibody_checks
