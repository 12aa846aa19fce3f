!> Scene files: the groups `&simulation`, `&solver`, `&output`, for a
!> flexible body `&flexible_body` with `&material` groups, for mechanisms
!> `&multibody`, `&rigid_body`, `&marker`, `&joint`, `&driver` and
!> `&rigid_chain`; study files hold one `&study`.
!>
!> Reading goes through stages, each collecting its errors so that a file
!> gets all its mistakes reported in one run: the lexer (groups, names,
!> values; scene_lexer), the schema's types and ranges (scene_values),
!> the typed scene (scene_reader), the checks across variables
!> (scene_checks, body_checks, multibody_checks) and the paths. Every
!> message names file, group, variable, value and reason, e.g.
!> `inputs/x.nml: &solver: rtol = -1e-6: must be positive (line 7)`.
module flexmbs_io_namelist
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_files, only: read_text_file
    use flexmbs_core_text, only: lower
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_io_input_errors, only: input_errors_t
    use flexmbs_io_scene_schema, only: group_names, find_group
    use flexmbs_io_scene_lexer, only: entry_t, span_t, tokenise
    use flexmbs_io_scene_values, only: check_types, check_rules
    use flexmbs_io_scene_input, only: scene_input_t
    use flexmbs_io_scene_reader, only: read_entries
    use flexmbs_io_scene_checks, only: check_scene, resolve_paths
    use flexmbs_io_study_file, only: study_input_t, read_study, parse_study
    implicit none
    private

    public :: scene_input_t, study_input_t
    public :: read_scene, parse_scene, scene_dae_options, read_study, &
        parse_study

contains

    !> Read and validate a scene file. A missing file is bad input; a file
    !> that exists but cannot be read is an I/O error.
    subroutine read_scene(path, scene, status)
        character(len=*), intent(in) :: path      !! scene file
        type(scene_input_t), intent(out) :: scene !! defaults plus the file's values
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        call read_text_file(path, text, status)
        if (.not. status%ok()) return
        call parse_scene(text, path, scene, status)
    end subroutine read_scene

    !> Validate and read scene text; `path` is used in messages, for the
    !> default output name and as the folder paths in the scene start from.
    subroutine parse_scene(text, path, scene, status)
        character(len=*), intent(in) :: text      !! the whole file
        character(len=*), intent(in) :: path      !! where it came from
        type(scene_input_t), intent(out) :: scene
        type(status_t), intent(out) :: status
        type(input_errors_t) :: errors
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        integer :: k

        scene%path = path
        scene%text = text
        call errors%start(path)
        call tokenise(text, errors, entries, spans)
        k = findloc(spans%group, find_group('study'), dim=1)
        if (k > 0) call errors%add('&study: belongs in a study file (flexmbs reference, &
            &flexmbs sweep), not in a scene', spans(k)%line)
        call check_types(entries, errors)
        call check_rules(entries, errors)
        call read_entries(entries, spans, scene)
        call check_scene(scene, entries, errors)
        call resolve_paths(scene, entries, errors)
        call errors%to_status(status)
    end subroutine parse_scene

    !> Common options of the scene: tolerances, steps, output times.
    function scene_dae_options(scene) result(options)
        type(scene_input_t), intent(in) :: scene
        type(dae_options_t) :: options
        integer :: i, m
        options%rtol = scene%rtol
        options%atol = scene%atol
        options%h0 = scene%h0
        options%hmax = scene%hmax
        options%max_steps = scene%max_steps
        options%pmax = min(scene%pmax, 12)
        options%linear_solver = trim(scene%linear_solver)
        options%sparse_ordering = trim(scene%sparse_ordering)
        options%newton_system = trim(scene%newton_system)
        options%jacobian = trim(scene%jacobian)
        options%output_steps = scene%every_step
        m = max(scene%n_output, 2)
        allocate (options%output_times(m))
        do i = 1, m
            options%output_times(i) = scene%t_start + (scene%t_end - scene%t_start) * &
                real(i - 1, wp) / real(m - 1, wp)
        end do
        options%output_times(m) = scene%t_end
    end function scene_dae_options
end module flexmbs_io_namelist
