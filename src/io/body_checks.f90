!> Checks of `&flexible_body` and `&material` beyond the schema's ranges:
!> presence, combinations, the size of a box mesh, unique names and
!> element sets. Node- and element-set names are checked against the mesh
!> when the body is built.
module flexmbs_io_body_checks
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: int_text, real_text
    use flexmbs_core_resources, only: physical_memory, bytes_text
    use flexmbs_io_input_errors, only: input_errors_t, at_other
    use flexmbs_io_scene_lexer, only: entry_t, has_entry, entry_index
    use flexmbs_io_scene_values, only: value_error, required_error
    use flexmbs_io_scene_input, only: scene_input_t, flexible_index, material_of
    use flexmbs_io_scene_schema, only: did_you_mean
    implicit none
    private

    public :: check_body, box_size_problem

contains

    !> Add to `errors` what is wrong with the scene's &flexible_body and &material
    !> groups (the checks of the module), also a body given to a problem without one.
    subroutine check_body(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=*), parameter :: fb = 'flexible_body', mat = 'material'
        character(len=len(scene%bodies%name)), allocatable :: body_names(:)
        integer :: i

        if (scene%problem /= 'flexible_body' .and. &
            .not. (scene%problem == 'multibody' .and. scene%has_body())) then
            if (scene%has_body()) then
                call errors%add('&flexible_body: given, but problem = ''' // &
                    trim(scene%problem) // ''' (a scene builds only what it declares)', &
                    scene%bodies(1)%line)
            else if (size(scene%materials) > 0) then
                call errors%add('&material: given without &flexible_body', &
                                scene%materials(1)%line)
            end if
            return
        end if
        if (.not. scene%has_body()) then
            call errors%add('&simulation: problem = ''flexible_body'': needs a &flexible_body &
                &group', 0)
            return
        end if
        if (scene%problem == 'flexible_body' .and. size(scene%bodies) > 1) then
            call errors%add('&flexible_body: given ' // int_text(size(scene%bodies)) // &
                ' times, but problem = ''flexible_body'' simulates one body (several are &
                &joined in problem = ''multibody'')', scene%bodies(2)%line)
            return
        end if
        do i = 1, size(scene%bodies)
            call check_one_body(i)
        end do
        body_names = scene%bodies%name   ! contiguous, for did_you_mean
        do i = 1, size(scene%materials)
            associate (m => scene%materials(i))
                if (.not. has_entry(entries, mat, 'youngs_modulus', i)) call required_error( &
                    errors, mat, 'youngs_modulus', 'Young''s modulus E in Pa', m%name, m%line)
                if (.not. has_entry(entries, mat, 'density', i)) call required_error(errors, &
                    mat, 'density', 'the mass density in kg/m^3', m%name, m%line)
                if (has_entry(entries, mat, 'elements', i) .and. len_trim(m%elements) == 0) &
                    call value_error(errors, entries, mat, 'elements', 'must name an element &
                    &set (leave it out for the elements no other material names)', i)
                if (len_trim(m%body) == 0 .and. size(scene%bodies) > 1) then
                    call required_error(errors, mat, 'body', 'the &flexible_body it belongs &
                        &to: the scene has ' // int_text(size(scene%bodies)), m%name, m%line)
                else if (len_trim(m%body) > 0 .and. flexible_index(scene, m%body) == 0) then
                    call value_error(errors, entries, mat, 'body', 'no &flexible_body of that &
                        &name' // did_you_mean(trim(m%body), body_names), i)
                end if
                call check_unique(i)
            end associate
        end do

    contains

        !> &flexible_body i: its mesh, supports and load, a unique name and a material.
        subroutine check_one_body(i)
            integer, intent(in) :: i
            character(len=:), allocatable :: why
            integer :: k, j
            associate (b => scene%bodies(i))
                if (len_trim(b%mesh_file) > 0) then
                    if (has_entry(entries, fb, 'divisions', i)) call value_error(errors, &
                        entries, fb, 'divisions', 'not used with mesh_file (the file gives &
                        &the mesh)', i)
                    if (has_entry(entries, fb, 'lengths', i)) call value_error(errors, entries, &
                        fb, 'lengths', 'not used with mesh_file (the file gives the mesh)', i)
                    if (has_entry(entries, fb, 'origin', i)) call value_error(errors, entries, &
                        fb, 'origin', 'not used with mesh_file (the file gives the mesh)', i)
                else
                    if (.not. has_entry(entries, fb, 'lengths', i)) call errors%add( &
                        label(i) // ': lengths: required (the box edge lengths in m), or &
                        &mesh_file', b%line)
                    k = entry_index(entries, fb, 'divisions', i)
                    why = ''
                    if (k > 0) then
                        if (.not. entries(k)%bad) why = box_size_problem(b%divisions, b%element)
                    end if
                    if (len(why) > 0) call value_error(errors, entries, fb, 'divisions', why, i)
                end if
                k = entry_index(entries, fb, 'fixed', i)
                if (k > 0) then
                    if (.not. entries(k)%bad .and. any(b%fixed(1:min(size(b%fixed), &
                        size(entries(k)%items))) == '')) call value_error(errors, entries, fb, &
                        'fixed', 'node-set names must not be empty', i)
                end if
                call check_model(scene, entries, errors, i)
                if (has_entry(entries, fb, 'load', i) .and. len_trim(b%load_set) == 0) &
                    call value_error(errors, entries, fb, 'load', 'needs load_set (the node &
                    &set that carries it)', i)
                if (has_entry(entries, fb, 'load_set', i) .and. &
                    .not. has_entry(entries, fb, 'load', i)) call value_error(errors, entries, &
                    fb, 'load_set', 'needs load = fx, fy, fz (the total force in N)', i)
                if (.not. any([(material_of(scene, j, i), j = 1, size(scene%materials))])) then
                    if (size(scene%bodies) > 1) then
                        call errors%add(label(i) // ': needs a &material group naming it in &
                            &body (youngs_modulus, density, ...)', b%line)
                    else
                        call errors%add(label(i) // ': needs a &material group &
                            &(youngs_modulus, density, ...)', b%line)
                    end if
                end if
                do j = 1, i - 1
                    if (scene%bodies(j)%name == b%name) call value_error(errors, entries, fb, &
                        'name', 'also the name of the &flexible_body' // &
                        at_other(scene%bodies(j)%line), i, b%name, b%line)
                end do
                if (any(scene%rigid_bodies%name == b%name) .or. any(scene%chain%name == b%name)) &
                    call value_error(errors, entries, fb, 'name', 'also the name of a &
                    &&rigid_body or &rigid_chain body (markers name bodies)', i, b%name, b%line)
            end associate
        end subroutine check_one_body

        !> '&flexible_body', or with several '&flexible_body ''NAME'''.
        function label(i) result(text)
            integer, intent(in) :: i
            character(len=:), allocatable :: text
            text = '&flexible_body'
            if (size(scene%bodies) > 1) text = text // ' ''' // trim(scene%bodies(i)%name) // ''''
        end function label

        !> Material i's name differs from the earlier ones', and its element
        !> set from those of the earlier materials of its body.
        subroutine check_unique(i)
            integer, intent(in) :: i
            integer :: j
            associate (m => scene%materials(i))
                do j = 1, i - 1
                    if (scene%materials(j)%name == m%name) then
                        call value_error(errors, entries, mat, 'name', 'also the name of the &
                            &&material' // at_other(scene%materials(j)%line), i)
                    else if (scene%materials(j)%body /= m%body) then
                        cycle
                    else if (scene%materials(j)%elements == m%elements .and. &
                             len_trim(m%elements) > 0) then
                        call value_error(errors, entries, mat, 'elements', 'the same set as &
                            &&material ''' // trim(scene%materials(j)%name) // '''' // &
                            at_other(scene%materials(j)%line), i)
                    else if (scene%materials(j)%elements == m%elements) then
                        call errors%add('&material ''' // trim(m%name) // ''': elements: not &
                            &given here nor in &material ''' // trim(scene%materials(j)%name) &
                            // ''': only one material may cover the elements no other names', &
                            m%line)
                    end if
                end do
            end associate
        end subroutine check_unique
    end subroutine check_body

    !> model = 'modal' in a multibody scene, without supports or nodal
    !> loads (joints hold it, force elements load it); the modal
    !> settings only with it.
    subroutine check_model(scene, entries, errors, i)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer, intent(in) :: i !! the &flexible_body
        character(len=*), parameter :: fb = 'flexible_body'
        character(len=*), parameter :: modal_vars(4) = [character(len=12) :: 'modes', &
            'interfaces', 'modes_method', 'modes_cache']
        integer :: k
        associate (b => scene%bodies(i))
            if (b%model /= 'modal') then
                do k = 1, size(modal_vars)
                    if (has_entry(entries, fb, trim(modal_vars(k)), i)) call value_error( &
                        errors, entries, fb, trim(modal_vars(k)), 'only with model = &
                        &''modal''', i)
                end do
                return
            end if
            if (scene%problem /= 'multibody') call value_error(errors, entries, fb, &
                'model', 'a modal body needs problem = ''multibody'' (joints hold it on &
                &its interfaces)', i)
            if (has_entry(entries, fb, 'fixed', i)) call value_error(errors, entries, fb, &
                'fixed', 'not with model = ''modal'': hold a modal body by a joint on an &
                &interface', i)
            if (has_entry(entries, fb, 'load_set', i)) call value_error(errors, entries, &
                fb, 'load_set', 'not with model = ''modal'': load it by a &force on a &
                &marker', i)
            k = entry_index(entries, fb, 'interfaces', i)
            if (k > 0) then
                if (.not. entries(k)%bad .and. any(b%interfaces(1:min(size(b%interfaces), &
                    size(entries(k)%items))) == '')) call value_error(errors, entries, fb, &
                    'interfaces', 'node-set names must not be empty', i)
            end if
        end associate
    end subroutine check_model


    !> Why a box mesh of `divisions` elements of type `element` cannot be
    !> made here, or '': its node and element counts must fit the default
    !> integers that number them, and a lower estimate of the memory the run
    !> needs (the tangent pattern: per node 3 rows of 81 (hex8) or 375
    !> (hex27) entries of about 40 bytes each, values, damping, index and
    !> maps) must fit the machine. Counted in 64 bits: 2000³ elements
    !> overflow a default integer.
    function box_size_problem(divisions, element) result(why)
        integer, intent(in) :: divisions(3)
        character(len=*), intent(in) :: element
        character(len=:), allocatable :: why
        integer(i8) :: nodes, elements, p, machine
        real(wp) :: bytes, per_node
        why = ''
        if (any(divisions < 1)) return
        p = merge(1_i8, 2_i8, element == 'hex8')
        per_node = merge(3.0_wp * 81.0_wp, 3.0_wp * 375.0_wp, element == 'hex8') * 40.0_wp
        nodes = product(p * int(divisions, i8) + 1_i8)
        elements = product(int(divisions, i8))
        bytes = real(nodes, wp) * per_node
        if (3_i8 * nodes > int(huge(1), i8) .or. elements > int(huge(1), i8)) then
            why = real_text(real(nodes, wp)) // ' nodes (' // real_text(3.0_wp * real(nodes, &
                wp)) // ' coordinates) and ' // real_text(real(elements, wp)) // &
                ' elements: more than the ' // int_text(huge(1)) // ' a mesh can number'
            return
        end if
        machine = physical_memory()
        if (machine > 0 .and. bytes > real(machine, wp)) why = real_text(real(nodes, wp)) // &
            ' nodes, needs at least ~' // bytes_text(bytes) // '; this machine has ' // &
            bytes_text(real(machine, wp))
    end function box_size_problem
end module flexmbs_io_body_checks
