!> Filling scene_input_t from checked entries: every variable from its
!> entry or, when not given (or given wrongly, already reported), from the
!> schema's default. Names of repeated groups default to 'body N' etc.;
!> choices are lower-cased (they compare case-insensitively).
module flexmbs_io_scene_reader
    use flexmbs_core_text, only: lower, int_text
    use flexmbs_io_scene_schema, only: find_group, schema, kind_real, kind_integer, kind_logical
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_io_scene_lexer, only: entry_t, span_t, has_entry, instance_ranges
    use flexmbs_io_scene_values, only: get
    use flexmbs_io_scene_records, only: read_scene_record, read_flexible_body_record, &
        read_material_record, read_multibody_record, read_rigid_body_record, &
        read_marker_record, read_joint_record, read_driver_record, read_force_record, &
        read_rigid_chain_record
    use flexmbs_io_scene_input, only: scene_input_t
    implicit none
    private

    public :: read_entries

contains

    !> The scene's values; `spans` give the groups present and their lines.
    subroutine read_entries(entries, spans, scene)
        type(entry_t), intent(in) :: entries(:)
        type(span_t), intent(in) :: spans(:)
        type(scene_input_t), intent(inout) :: scene
        integer :: i

        call read_scene_record(entries, scene%scene_record_t)
        call read_solver_settings(entries, scene)
        ! `file` stays as written; resolving it is the checks' business
        scene%output_file = trim(scene%file)
        scene%has_multibody = any(spans%group == find_group('multibody'))
        allocate (scene%bodies(count(spans%group == find_group('flexible_body'))), &
                  scene%materials(count(spans%group == find_group('material'))), &
                  scene%rigid_bodies(count(spans%group == find_group('rigid_body'))), &
                  scene%markers(count(spans%group == find_group('marker'))), &
                  scene%joints(count(spans%group == find_group('joint'))), &
                  scene%drivers(count(spans%group == find_group('driver'))), &
                  scene%forces(count(spans%group == find_group('force'))), &
                  scene%chain(count(spans%group == find_group('rigid_chain'))))
        call read_body(entries, scene)
        call read_multibody(entries, scene)
        call read_forces(entries, scene)
        do i = 1, size(spans)
            call set_line(scene, spans(i))
        end do
        if (scene%has_body() .and. .not. has_entry(entries, 'simulation', 'problem')) &
            scene%problem = 'flexible_body'
        if (size(scene%rigid_bodies) > 0 .and. &
            .not. has_entry(entries, 'simulation', 'problem')) scene%problem = 'multibody'
    end subroutine read_entries

    subroutine set_line(scene, span)
        type(scene_input_t), intent(inout) :: scene
        type(span_t), intent(in) :: span
        if (span%group == find_group('flexible_body')) scene%bodies(span%instance)%line = &
            span%line
        if (span%group == find_group('multibody')) scene%multibody%line = span%line
        if (span%group == find_group('material')) scene%materials(span%instance)%line = span%line
        if (span%group == find_group('rigid_body')) &
            scene%rigid_bodies(span%instance)%line = span%line
        if (span%group == find_group('marker')) scene%markers(span%instance)%line = span%line
        if (span%group == find_group('joint')) scene%joints(span%instance)%line = span%line
        if (span%group == find_group('driver')) scene%drivers(span%instance)%line = span%line
        if (span%group == find_group('force')) scene%forces(span%instance)%line = span%line
        if (span%group == find_group('rigid_chain')) scene%chain(span%instance)%line = span%line
    end subroutine set_line

    !> The solvers' own settings the scene gives: the &solver variables
    !> without a default in the schema (their defaults are the solver
    !> types'), each read as its kind says, a choice in lower case.
    subroutine read_solver_settings(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'solver'
        type(solver_setting_t) :: setting
        integer :: v
        allocate (scene%solver_settings(0))
        do v = 1, size(schema)
            if (schema(v)%group /= g .or. len_trim(schema(v)%default) > 0) cycle
            if (.not. has_entry(e, g, trim(schema(v)%name))) cycle
            setting = solver_setting_t(name=schema(v)%name)
            select case (schema(v)%kind)
            case (kind_real)
                call get(e, g, trim(setting%name), setting%real_value)
            case (kind_integer)
                call get(e, g, trim(setting%name), setting%integer_value)
            case (kind_logical)
                call get(e, g, trim(setting%name), setting%logical_value)
            case default
                call get(e, g, trim(setting%name), setting%string_value)
                if (len_trim(schema(v)%choices) > 0) &
                    setting%string_value = lower(setting%string_value)
            end select
            scene%solver_settings = [scene%solver_settings, setting]
        end do
    end subroutine read_solver_settings

    subroutine read_body(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'flexible_body'
        integer :: i
        integer, allocatable :: ranges(:, :)
        call instance_ranges(e, g, size(scene%bodies), ranges)
        do i = 1, size(scene%bodies)
            associate (b => scene%bodies(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_flexible_body_record(ei, b%flexible_body_record_t, i)
                if (size(scene%bodies) > 1 .and. .not. has_entry(ei, g, 'name', i)) &
                    b%name = 'body ' // int_text(i)
            end associate
        end do
        call instance_ranges(e, 'material', size(scene%materials), ranges)
        do i = 1, size(scene%materials)
            associate (m => scene%materials(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_material_record(ei, m%material_record_t, i)
                if (len_trim(m%name) == 0) m%name = 'material ' // int_text(i)
            end associate
        end do
    end subroutine read_body

    subroutine read_multibody(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        integer :: i
        integer, allocatable :: ranges(:, :)
        call read_multibody_record(e, scene%multibody%multibody_record_t)
        call instance_ranges(e, 'rigid_body', size(scene%rigid_bodies), ranges)
        do i = 1, size(scene%rigid_bodies)
            associate (b => scene%rigid_bodies(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_rigid_body_record(ei, b%rigid_body_record_t, i)
                if (len_trim(b%name) == 0) b%name = 'body ' // int_text(i)
            end associate
        end do
        call instance_ranges(e, 'marker', size(scene%markers), ranges)
        do i = 1, size(scene%markers)
            associate (m => scene%markers(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_marker_record(ei, m%marker_record_t, i)
                if (len_trim(m%name) == 0) m%name = 'marker ' // int_text(i)
                m%position_given = has_entry(ei, 'marker', 'position', i)
            end associate
        end do
        call instance_ranges(e, 'joint', size(scene%joints), ranges)
        do i = 1, size(scene%joints)
            associate (j => scene%joints(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_joint_record(ei, j%joint_record_t, i)
                if (len_trim(j%name) == 0) j%name = 'joint ' // int_text(i)
            end associate
        end do
        call instance_ranges(e, 'driver', size(scene%drivers), ranges)
        do i = 1, size(scene%drivers)
            associate (d => scene%drivers(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_driver_record(ei, d%driver_record_t, i)
                if (len_trim(d%name) == 0) d%name = 'driver ' // int_text(i)
            end associate
        end do
        call instance_ranges(e, 'rigid_chain', size(scene%chain), ranges)
        do i = 1, size(scene%chain)
            associate (c => scene%chain(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_rigid_chain_record(ei, c%rigid_chain_record_t, i)
                if (len_trim(c%name) == 0) c%name = 'link ' // int_text(i)
            end associate
        end do
    end subroutine read_multibody

    subroutine read_forces(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'force'
        integer :: i
        integer, allocatable :: ranges(:, :)
        call instance_ranges(e, g, size(scene%forces), ranges)
        do i = 1, size(scene%forces)
            associate (f => scene%forces(i), ei => e(ranges(1, i):ranges(2, i)))
                call read_force_record(ei, f%force_record_t, i)
                if (len_trim(f%name) == 0) f%name = 'force ' // int_text(i)
                f%has_stiffness_matrix = has_entry(ei, g, 'stiffness_matrix', i)
                f%has_damping_matrix = has_entry(ei, g, 'damping_matrix', i)
            end associate
        end do
    end subroutine read_forces

end module flexmbs_io_scene_reader
