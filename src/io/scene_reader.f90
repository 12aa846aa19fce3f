!> Filling scene_input_t from checked entries: every variable from its
!> entry or, when not given (or given wrongly, already reported), from the
!> schema's default. Names of repeated groups default to 'body N' etc.;
!> choices are lower-cased (they compare case-insensitively).
module flexmbs_io_scene_reader
    use flexmbs_core_text, only: lower, int_text
    use flexmbs_io_scene_schema, only: find_group, schema, kind_real, kind_integer, kind_logical
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_io_scene_lexer, only: entry_t, span_t, has_entry, instance_ranges
    use flexmbs_io_scene_values, only: get, get_list
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

        call read_simulation(entries, scene)
        call read_solver(entries, scene)
        call read_output(entries, scene)
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

    subroutine read_simulation(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'simulation'
        call get(e, g, 'title', scene%title)
        call get(e, g, 'problem', scene%problem)
        scene%problem = lower(scene%problem)
        call get(e, g, 't_start', scene%t_start)
        call get(e, g, 't_end', scene%t_end)
        call get(e, g, 'vdp_eps', scene%vdp_eps)
        call get(e, g, 'vdp_y1', scene%vdp_y1)
        call get(e, g, 'vdp_y2', scene%vdp_y2)
        call get(e, g, 'pendulum_formulation', scene%pendulum_formulation)
        scene%pendulum_formulation = lower(scene%pendulum_formulation)
        call get(e, g, 'pendulum_length', scene%pendulum_length)
        call get(e, g, 'pendulum_mass', scene%pendulum_mass)
        call get(e, g, 'pendulum_angle', scene%pendulum_angle)
        call get(e, g, 'pendulum_projection', scene%pendulum_projection)
        call get(e, g, 'gravity', scene%gravity)
        call get(e, g, 'npoints', scene%npoints)
    end subroutine read_simulation

    subroutine read_solver(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'solver'
        call get(e, g, 'name', scene%solver_name)
        scene%solver_name = lower(scene%solver_name)
        call get(e, g, 'rtol', scene%rtol)
        call get(e, g, 'atol', scene%atol)
        call get(e, g, 'h0', scene%h0)
        call get(e, g, 'hmax', scene%hmax)
        call get(e, g, 'max_steps', scene%max_steps)
        call get(e, g, 'linear_solver', scene%linear_solver)
        scene%linear_solver = lower(scene%linear_solver)
        call get(e, g, 'sparse_ordering', scene%sparse_ordering)
        scene%sparse_ordering = lower(scene%sparse_ordering)
        call get(e, g, 'newton_system', scene%newton_system)
        scene%newton_system = lower(scene%newton_system)
        call get(e, g, 'jacobian', scene%jacobian)
        scene%jacobian = lower(scene%jacobian)
        call get(e, g, 'pmax', scene%pmax)
        call read_solver_settings(e, scene)
    end subroutine read_solver

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

    !> `file` stays as written; resolving it is the checks' business.
    subroutine read_output(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'output'
        character(len=512) :: file
        call get(e, g, 'file', file)
        scene%output_file = trim(file)
        call get(e, g, 'n_output', scene%n_output)
        call get(e, g, 'every_step', scene%every_step)
        call get(e, g, 'table', scene%table)
        call get(e, g, 'progress', scene%progress)
        call get(e, g, 'reasons', scene%reasons)
        call get(e, g, 'vtk', scene%vtk)
        call get(e, g, 'vtk_format', scene%vtk_format)
        scene%vtk_format = lower(scene%vtk_format)
    end subroutine read_output

    subroutine read_body(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        character(len=*), parameter :: g = 'flexible_body'
        integer :: i
        integer, allocatable :: ranges(:, :)
        call instance_ranges(e, g, size(scene%bodies), ranges)
        do i = 1, size(scene%bodies)
            associate (b => scene%bodies(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, g, 'name', b%name, i)
                if (size(scene%bodies) > 1 .and. .not. has_entry(ei, g, 'name', i)) &
                    b%name = 'body ' // int_text(i)
                call get(ei, g, 'element', b%element, i)
                b%element = lower(b%element)
                call get(ei, g, 'mesh_file', b%mesh_file, i)
                call get(ei, g, 'divisions', b%divisions, i)
                call get(ei, g, 'lengths', b%lengths, i)
                call get(ei, g, 'origin', b%origin, i)
                call get(ei, g, 'fixed', b%fixed, i)
                call get(ei, g, 'load_set', b%load_set, i)
                call get(ei, g, 'load', b%load, i)
                call get(ei, g, 'gravity', b%gravity, i)
                call get(ei, g, 'initial_velocity', b%initial_velocity, i)
                call get(ei, g, 'initial_angular_velocity', b%initial_angular_velocity, i)
                call get(ei, g, 'formulation', b%formulation, i)
                b%formulation = lower(b%formulation)
                call get(ei, g, 'model', b%model, i)
                b%model = lower(b%model)
                call get(ei, g, 'modes', b%modes, i)
                call get(ei, g, 'interfaces', b%interfaces, i)
                call get(ei, g, 'modes_method', b%modes_method, i)
                b%modes_method = lower(b%modes_method)
                call get(ei, g, 'modes_cache', b%modes_cache, i)
            end associate
        end do
        call instance_ranges(e, 'material', size(scene%materials), ranges)
        do i = 1, size(scene%materials)
            associate (m => scene%materials(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'material', 'name', m%name, i)
                if (len_trim(m%name) == 0) m%name = 'material ' // int_text(i)
                call get(ei, 'material', 'youngs_modulus', m%youngs_modulus, i)
                call get(ei, 'material', 'poisson_ratio', m%poisson_ratio, i)
                call get(ei, 'material', 'density', m%density, i)
                call get(ei, 'material', 'viscosity', m%viscosity, i)
                call get(ei, 'material', 'elements', m%elements, i)
                call get(ei, 'material', 'body', m%body, i)
            end associate
        end do
    end subroutine read_body

    subroutine read_multibody(e, scene)
        type(entry_t), intent(in) :: e(:)
        type(scene_input_t), intent(inout) :: scene
        integer :: i
        integer, allocatable :: ranges(:, :)
        associate (mb => scene%multibody)
            call get(e, 'multibody', 'formulation', mb%formulation)
            mb%formulation = lower(mb%formulation)
            call get(e, 'multibody', 'gravity', mb%gravity)
            call get(e, 'multibody', 'constraint_derivatives', mb%constraint_derivatives)
            mb%constraint_derivatives = lower(mb%constraint_derivatives)
            call get(e, 'multibody', 'projection', mb%projection)
            call get(e, 'multibody', 'assembly_tolerance', mb%assembly_tolerance)
        end associate
        call instance_ranges(e, 'rigid_body', size(scene%rigid_bodies), ranges)
        do i = 1, size(scene%rigid_bodies)
            associate (b => scene%rigid_bodies(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'rigid_body', 'name', b%name, i)
                if (len_trim(b%name) == 0) b%name = 'body ' // int_text(i)
                call get(ei, 'rigid_body', 'mass', b%mass, i)
                call get(ei, 'rigid_body', 'inertia', b%inertia, i)
                call get(ei, 'rigid_body', 'inertia_products', b%inertia_products, i)
                call get(ei, 'rigid_body', 'position', b%position, i)
                call get(ei, 'rigid_body', 'rotation_axis', b%rotation_axis, i)
                call get(ei, 'rigid_body', 'rotation_angle', b%rotation_angle, i)
                call get(ei, 'rigid_body', 'velocity', b%velocity, i)
                call get(ei, 'rigid_body', 'angular_velocity', b%angular_velocity, i)
            end associate
        end do
        call instance_ranges(e, 'marker', size(scene%markers), ranges)
        do i = 1, size(scene%markers)
            associate (m => scene%markers(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'marker', 'name', m%name, i)
                if (len_trim(m%name) == 0) m%name = 'marker ' // int_text(i)
                call get(ei, 'marker', 'body', m%body, i)
                call get(ei, 'marker', 'position', m%position, i)
                m%position_given = has_entry(ei, 'marker', 'position', i)
                call get(ei, 'marker', 'z_axis', m%z_axis, i)
                call get(ei, 'marker', 'x_axis', m%x_axis, i)
                call get(ei, 'marker', 'node_set', m%node_set, i)
            end associate
        end do
        call instance_ranges(e, 'joint', size(scene%joints), ranges)
        do i = 1, size(scene%joints)
            associate (j => scene%joints(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'joint', 'name', j%name, i)
                if (len_trim(j%name) == 0) j%name = 'joint ' // int_text(i)
                call get(ei, 'joint', 'type', j%type, i)
                j%type = lower(j%type)
                call get(ei, 'joint', 'marker_i', j%marker_i, i)
                call get(ei, 'joint', 'marker_j', j%marker_j, i)
            end associate
        end do
        call instance_ranges(e, 'driver', size(scene%drivers), ranges)
        do i = 1, size(scene%drivers)
            associate (d => scene%drivers(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'driver', 'name', d%name, i)
                if (len_trim(d%name) == 0) d%name = 'driver ' // int_text(i)
                call get(ei, 'driver', 'type', d%type, i)
                d%type = lower(d%type)
                call get(ei, 'driver', 'marker_i', d%marker_i, i)
                call get(ei, 'driver', 'marker_j', d%marker_j, i)
                call get(ei, 'driver', 'axis_i', d%axis_i, i)
                call get(ei, 'driver', 'axis_j', d%axis_j, i)
                call get(ei, 'driver', 'coefficients', d%coefficients, i)
                call get(ei, 'driver', 'amplitude', d%amplitude, i)
                call get(ei, 'driver', 'frequency', d%frequency, i)
                call get(ei, 'driver', 'phase', d%phase, i)
                call get(ei, 'driver', 'ramp_rate', d%ramp_rate, i)
                call get(ei, 'driver', 'ramp_time', d%ramp_time, i)
            end associate
        end do
        call instance_ranges(e, 'rigid_chain', size(scene%chain), ranges)
        do i = 1, size(scene%chain)
            associate (c => scene%chain(i), ei => e(ranges(1, i):ranges(2, i)))
                call get(ei, 'rigid_chain', 'name', c%name, i)
                if (len_trim(c%name) == 0) c%name = 'link ' // int_text(i)
                call get(ei, 'rigid_chain', 'parent', c%parent, i)
                call get(ei, 'rigid_chain', 'joint', c%joint, i)
                c%joint = lower(c%joint)
                call get(ei, 'rigid_chain', 'joint_position', c%joint_position, i)
                call get(ei, 'rigid_chain', 'joint_axis', c%joint_axis, i)
                call get(ei, 'rigid_chain', 'centre', c%centre, i)
                call get(ei, 'rigid_chain', 'mass', c%mass, i)
                call get(ei, 'rigid_chain', 'inertia', c%inertia, i)
                call get(ei, 'rigid_chain', 'inertia_products', c%inertia_products, i)
                call get(ei, 'rigid_chain', 'coordinate', c%coordinate, i)
                call get(ei, 'rigid_chain', 'rate', c%rate, i)
                call get(ei, 'rigid_chain', 'rotation_axis', c%rotation_axis, i)
                call get(ei, 'rigid_chain', 'rotation_angle', c%rotation_angle, i)
                call get(ei, 'rigid_chain', 'angular_rate', c%angular_rate, i)
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
                call get(ei, g, 'name', f%name, i)
                if (len_trim(f%name) == 0) f%name = 'force ' // int_text(i)
                call get(ei, g, 'type', f%type, i)
                f%type = lower(f%type)
                call get(ei, g, 'marker_i', f%marker_i, i)
                call get(ei, g, 'marker_j', f%marker_j, i)
                call get(ei, g, 'free_length', f%free_length, i)
                call get(ei, g, 'free_angle', f%free_angle, i)
                call get_list(ei, g, 'stiffness', f%stiffness)
                call get_list(ei, g, 'damping', f%damping)
                call get(ei, g, 'stiffness_matrix', f%stiffness_matrix, i)
                f%has_stiffness_matrix = has_entry(ei, g, 'stiffness_matrix', i)
                call get(ei, g, 'damping_matrix', f%damping_matrix, i)
                f%has_damping_matrix = has_entry(ei, g, 'damping_matrix', i)
                call get(ei, g, 'force', f%force, i)
                call get(ei, g, 'torque', f%torque, i)
                call get(ei, g, 'frame', f%frame, i)
                f%frame = lower(f%frame)
                call get(ei, g, 'coefficients', f%coefficients, i)
                call get(ei, g, 'amplitude', f%amplitude, i)
                call get(ei, g, 'frequency', f%frequency, i)
                call get(ei, g, 'phase', f%phase, i)
            end associate
        end do
    end subroutine read_forces

end module flexmbs_io_scene_reader
