!> Study files (`flexmbs reference`, `flexmbs sweep`): one `&study` group
!> naming a scene and the grid of runs over it. Paths in it are relative
!> to the study file's folder. Read with the scene files' lexer and
!> schema; every error of the file reported at once.
module flexmbs_io_study_file
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_files, only: read_text_file
    use flexmbs_core_text, only: lower
    use flexmbs_run_catalogue, only: solvers
    use flexmbs_io_input_errors, only: input_errors_t
    use flexmbs_io_scene_schema, only: group_names, len_name, len_path
    use flexmbs_io_scene_lexer, only: entry_t, span_t, tokenise
    use flexmbs_io_scene_values, only: check_types, check_rules, get, get_list, value_error, &
        required_error
    use flexmbs_io_scene_checks, only: relative_to, folder_of
    implicit none
    private

    !> A study: the scene, the reference, and the grid of runs.
    type, public :: study_input_t
        character(len=:), allocatable :: path            !! the study file
        character(len=:), allocatable :: scene           !! scene file, resolved
        character(len=:), allocatable :: reference_file  !! HDF5 reference, resolved
        character(len=len_name) :: reference_solver
        real(wp) :: reference_tolerance
        character(len=len_name) :: check_solver !! '': no check
        real(wp) :: check_tolerance
        character(len=len_name), allocatable :: solvers(:)
        character(len=len_name), allocatable :: stabilisations(:)
        real(wp), allocatable :: tolerances(:)
        integer, allocatable :: pmax(:)
        character(len=len_name), allocatable :: derivatives(:)
        character(len=:), allocatable :: table            !! '' = no file, resolved
        integer :: cpu_reference !! the row whose CPU is 1 in the table
        real(wp) :: t_end !! > 0: the scene's t_end for every run
        integer :: max_steps !! > 0: every run's step limit
        character(len=len_name) :: layout !! 'table3' or 'table2' (the table's)
        logical :: reasons !! the table also counts the rejected steps by cause
    end type study_input_t

    public :: read_study, parse_study

contains

    !> Read a study file (see study_input_t).
    subroutine read_study(path, study, status)
        character(len=*), intent(in) :: path
        type(study_input_t), intent(out) :: study
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        call read_text_file(path, text, status)
        if (.not. status%ok()) return
        call parse_study(text, path, study, status)
    end subroutine read_study

    !> Validate and read a study's text.
    subroutine parse_study(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(study_input_t), intent(out) :: input
        type(status_t), intent(out) :: status
        character(len=*), parameter :: g = 'study'
        type(input_errors_t) :: errors
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        character(len=len_path) :: scene, reference_file, table
        character(len=:), allocatable :: dir, ext
        integer :: i

        input%path = path
        call errors%start(path)
        call tokenise(text, errors, entries, spans)
        do i = 1, size(spans)
            if (group_names(spans(i)%group) /= g) call errors%add('&' // &
                trim(group_names(spans(i)%group)) // ': a study file holds only &study (its &
                &scene = names the scene file)', spans(i)%line)
        end do
        if (count(group_names(spans%group) == g) /= 1 .and. errors%n() == 0) &
            call errors%add('needs one &study group', 0)
        call check_types(entries, errors)
        call check_rules(entries, errors)
        call get(entries, g, 'scene', scene)
        call get(entries, g, 'reference_file', reference_file)
        call get(entries, g, 'table', table)
        call get(entries, g, 'reference_solver', input%reference_solver)
        input%reference_solver = lower(input%reference_solver)
        call get(entries, g, 'reference_tolerance', input%reference_tolerance)
        call get(entries, g, 'check_solver', input%check_solver)
        input%check_solver = lower(input%check_solver)
        if (input%check_solver == 'none') input%check_solver = ''
        call get(entries, g, 'check_tolerance', input%check_tolerance)
        call get(entries, g, 't_end', input%t_end)
        call get(entries, g, 'max_steps', input%max_steps)
        call get(entries, g, 'layout', input%layout)
        call get(entries, g, 'reasons', input%reasons)
        input%layout = lower(input%layout)
        call get(entries, g, 'cpu_reference', input%cpu_reference)
        call get_list(entries, g, 'solvers', input%solvers)
        if (size(input%solvers) == 0) input%solvers = [character(len=len_name) :: &
            solvers%name]
        call get_list(entries, g, 'stabilisations', input%stabilisations)
        if (size(input%stabilisations) == 0) input%stabilisations = &
            [character(len=len_name) :: 'none', 'ggl']
        call get_list(entries, g, 'derivatives', input%derivatives)
        if (size(input%derivatives) == 0) input%derivatives = [character(len=len_name) :: &
            'analytic']
        call get_list(entries, g, 'tolerances', input%tolerances)
        if (size(input%tolerances) == 0) input%tolerances = [1.0e-6_wp]
        call get_list(entries, g, 'pmax', input%pmax)
        if (size(input%pmax) == 0) input%pmax = [5]

        if (len_trim(scene) == 0 .and. count(group_names(spans%group) == g) == 1) &
            call required_error(errors, g, 'scene', 'the scene file')
        if (input%check_tolerance == 0.0_wp) then
            input%check_tolerance = input%reference_tolerance
        else if (.not. (input%check_tolerance > 0.0_wp .and. input%check_tolerance < 1.0_wp)) &
            then
            call value_error(errors, entries, g, 'check_tolerance', 'must lie in (0, 1) (0: &
                &the reference tolerance)')
        end if
        dir = folder_of(path)
        input%scene = relative_to(dir, trim(scene))
        if (len_trim(reference_file) > 0) then
            input%reference_file = relative_to(dir, trim(reference_file))
        else
            i = index(path, '.', back=.true.)
            if (i <= index(path, '/', back=.true.)) i = len(path) + 1
            input%reference_file = path(1:i - 1) // '_reference.h5'
        end if
        input%table = ''
        if (len_trim(table) > 0) then
            input%table = relative_to(dir, trim(table))
            i = index(input%table, '.', back=.true.)
            ext = ''
            if (i > 0) ext = lower(input%table(i + 1:))
            if (all([character(len=4) :: 'md', 'csv', 'tex'] /= ext)) &
                call value_error(errors, entries, g, 'table', 'the name must end in .md, .csv &
                &or .tex (the format)')
        end if
        call errors%to_status(status)
    end subroutine parse_study
end module flexmbs_io_study_file
