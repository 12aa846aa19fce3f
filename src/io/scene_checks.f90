!> Checks of a scene across variables, after the schema's type and range
!> checks: what is required, what depends on another value (t_end after
!> t_start, MEXAX only for mechanical problems, BDF orders), and the
!> paths: mesh file and outputs relative to the scene file's folder, no
!> output on an input. Every error goes to the list.
module flexmbs_io_scene_checks
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: lower, real_text, int_text
    use flexmbs_core_files, only: same_file, file_kind, file_folder
    use flexmbs_core_resources, only: physical_memory, bytes_text
    use flexmbs_linalg_linear_solver, only: linear_solver_names, linear_solver_names_text
    use flexmbs_run_catalogue, only: solver_info_t, solver_info, problem_info_t, problem_info, &
        mechanical_problem_names, band_solver_names
    use flexmbs_io_input_errors, only: input_errors_t
    use flexmbs_io_scene_schema, only: schema, find_var, split_choices, choice_list
    use flexmbs_io_scene_lexer, only: entry_t, has_entry, entry_index
    use flexmbs_io_scene_values, only: value_error, required_error
    use flexmbs_io_scene_input, only: scene_input_t
    use flexmbs_io_body_checks, only: check_body
    use flexmbs_io_multibody_checks, only: check_multibody, check_chain
    use flexmbs_io_force_checks, only: check_forces
    implicit none
    private

    public :: check_scene, resolve_paths, relative_to, folder_of

contains

    !> Every check of a read scene.
    subroutine check_scene(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        call check_simulation(scene, entries, errors)
        call check_solver(scene, entries, errors)
        call check_output(scene, entries, errors)
        call check_body(scene, entries, errors)
        call check_multibody(scene, entries, errors)
        call check_chain(scene, entries, errors)
        call check_forces(scene, entries, errors)
    end subroutine check_scene

    subroutine check_simulation(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=*), parameter :: sim = 'simulation'
        if (.not. has_entry(entries, sim, 'problem') .and. .not. scene%has_body() .and. &
            size(scene%rigid_bodies) == 0) call required_error(errors, sim, 'problem', &
            choice_list(split_choices(schema(find_var(sim, 'problem'))%choices)))
        if (.not. has_entry(entries, sim, 't_end')) then
            call required_error(errors, sim, 't_end', 'the end time in s, greater than t_start')
        else if (.not. scene%t_end > scene%t_start .and. valid(entries, sim, 't_start')) then
            call value_error(errors, entries, sim, 't_end', 'must be greater than t_start = ' // &
                             raw_value(entries, sim, 't_start', '0'))
        end if
    end subroutine check_simulation

    subroutine check_solver(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=*), parameter :: sol = 'solver'
        type(solver_info_t) :: solver
        type(problem_info_t) :: problem
        solver = solver_info(scene%solver_name)
        problem = problem_info(scene%problem)
        if (solver%mechanical_only .and. valid(entries, 'simulation', 'problem') .and. &
            .not. problem%mechanical) then
            call value_error(errors, entries, sol, 'name', '''' // trim(solver%name) // &
                ''' integrates mechanical problems only: problem must be ' // &
                mechanical_problem_names())
        end if
        if (all(linear_solver_names /= scene%linear_solver)) call value_error(errors, entries, &
            sol, 'linear_solver', 'must be ' // linear_solver_names_text)
        if (scene%linear_solver == 'band' .and. .not. solver%band) call value_error(errors, &
            entries, sol, 'linear_solver', '''band'' is offered with ' // band_solver_names() // &
            ' only (' // trim(solver%name) // ': ''auto'', ''dense'' or ''klu'')')
        if (solver%max_order > 0 .and. scene%pmax > solver%max_order) call value_error(errors, &
            entries, sol, 'pmax', 'must lie in 1..' // int_text(solver%max_order) // ' for ' // &
            trim(solver%name) // ' (its maximal BDF order)')
    end subroutine check_solver

    !> The output grid must fit in memory (its times are held as reals).
    subroutine check_output(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=:), allocatable :: ext
        integer(i8) :: machine
        real(wp) :: bytes
        if (len_trim(scene%table) > 0) then
            ext = lower(extension(trim(scene%table)))
            if (all([character(len=4) :: 'md', 'csv', 'tex'] /= ext)) call value_error(errors, &
                entries, 'output', 'table', 'must end in .md, .csv or .tex')
        end if
        machine = physical_memory()
        bytes = 8.0_wp * real(scene%n_output, wp)
        if (machine > 0 .and. bytes > 0.5_wp * real(machine, wp)) call value_error(errors, &
            entries, 'output', 'n_output', real_text(real(scene%n_output, wp)) // ' output &
            &times need ~' // bytes_text(bytes) // ' for the times alone; this machine has ' // &
            bytes_text(real(machine, wp)))
    end subroutine check_output

    !> Mesh file and outputs relative to the scene's folder; the HDF5 file
    !> as given ('' or 'none' = no file), or the scene's base name with .h5
    !> in the working directory; no output may be the scene itself.
    subroutine resolve_paths(scene, entries, errors)
        type(scene_input_t), intent(inout) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        character(len=:), allocatable :: dir
        integer :: b
        dir = folder_of(scene%path)
        do b = 1, size(scene%bodies)
            if (len_trim(scene%bodies(b)%mesh_file) > 0) scene%bodies(b)%mesh_file = &
                relative_to(dir, trim(scene%bodies(b)%mesh_file))
            if (len_trim(scene%bodies(b)%modes_cache) > 0) scene%bodies(b)%modes_cache = &
                relative_to(dir, trim(scene%bodies(b)%modes_cache))
        end do
        if (len_trim(scene%table) > 0) scene%table = relative_to(dir, trim(scene%table))
        if (len_trim(scene%vtk) > 0) scene%vtk = relative_to(dir, trim(scene%vtk))
        if (.not. has_entry(entries, 'output', 'file')) then
            scene%output_file = stem(basename(scene%path)) // '.h5'
        else if (lower(scene%output_file) == 'none') then
            scene%output_file = ''
        else if (len(scene%output_file) > 0) then
            scene%output_file = relative_to(dir, scene%output_file)
        end if
        if (len_trim(scene%table) > 0) call check_folder('table', trim(scene%table))
        if (len_trim(scene%vtk) > 0) call check_folder('vtk', trim(scene%vtk))
        if (len(scene%output_file) == 0) return
        if (has_entry(entries, 'output', 'file')) call check_folder('file', scene%output_file)
        ! the same file by any spelling (./s.nml, ../in/s.nml, a link)
        if (scene%output_file /= scene%path .and. .not. same_file(scene%output_file, &
                                                                  scene%path)) return
        if (has_entry(entries, 'output', 'file')) then
            call value_error(errors, entries, 'output', 'file', 'would overwrite the input file')
        else
            call errors%add('&output: file (default ''' // scene%output_file // '''): would &
                &overwrite the input file', 0)
        end if

    contains

        !> An output's folder must exist (found now, not after the run).
        subroutine check_folder(name, path)
            character(len=*), intent(in) :: name, path
            integer(i8) :: size
            character(len=:), allocatable :: folder
            folder = folder_of(path)
            if (len(folder) == 0) return
            if (file_kind(folder, size) /= file_folder) call value_error(errors, entries, &
                'output', name, 'the folder ''' // folder // ''' does not exist (paths are &
                &relative to the scene''s folder)')
        end subroutine check_folder
    end subroutine resolve_paths

    !> `name` relative to folder `dir` ('' or ending in '/'), unless absolute.
    pure function relative_to(dir, name) result(full)
        character(len=*), intent(in) :: dir, name
        character(len=:), allocatable :: full
        full = name
        if (len(name) == 0) return
        if (name(1:1) /= '/') full = dir // name
    end function relative_to

    !> The folder of a file's path, with its trailing '/' ('' for none).
    pure function folder_of(path) result(dir)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: dir
        dir = path(1:index(path, '/', back=.true.))
    end function folder_of

    !> The variable was not given wrongly (given valid, or not given).
    pure logical function valid(entries, group, name)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer :: k
        k = entry_index(entries, group, name)
        valid = .true.
        if (k > 0) valid = .not. entries(k)%bad
    end function valid

    !> The value as written in the file, or `default` when not given.
    pure function raw_value(entries, group, name, default) result(text)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name, default
        character(len=:), allocatable :: text
        integer :: k
        text = default
        k = entry_index(entries, group, name)
        if (k > 0) text = entries(k)%value
    end function raw_value

    pure function basename(path) result(name)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: name
        name = path(index(path, '/', back=.true.) + 1:)
    end function basename

    !> File name without its last extension.
    pure function stem(name) result(s)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: s
        integer :: dot
        dot = index(name, '.', back=.true.)
        if (dot > 1) then
            s = name(1:dot - 1)
        else
            s = name
        end if
    end function stem

    pure function extension(name) result(ext)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: ext
        integer :: dot
        dot = index(name, '.', back=.true.)
        if (dot > index(name, '/', back=.true.) .and. dot > 0) then
            ext = name(dot + 1:)
        else
            ext = ''
        end if
    end function extension
end module flexmbs_io_scene_checks
