!> The flexmbs command line.
!>
!>   flexmbs run FILE.nml [--quiet] [--force] [--verbose]  run a scene
!>   flexmbs reference STUDY.nml [--quiet] [--force]   a study's reference solution
!>   flexmbs sweep STUDY.nml [-j N] [--quiet] [--force]  a study's grid of runs against it
!>   flexmbs sweep STUDY.nml --point K        point K alone, its record into the results folder
!>   flexmbs sweep STUDY.nml --merge          the table from the records there
!>   flexmbs sweep STUDY.nml --slurm [--chunk K] [--partition P] [--time T] [--mem M] [--submit]
!>                                            a Slurm job array and merge job for the study
!>   (every sweep refuses a stale reference, run/reference_fingerprint; --force uses it)
!>   flexmbs columns FILE.h5 COLUMN [COLUMN ...]  t and columns of a result as text
!>                                        (COLUMN: a number of /y, or rocker/position/z ...)
!>   flexmbs modes FILE.nml [--time T] [--count K] [--shift S] [--method M] [--output P]
!>                 [--no-run] [--force]        eigenvalues of the linearised scene and the
!>                                            BDF sectors at the step sizes of a BDF run
!>   flexmbs scene-reference                  every group and variable of a scene, as Markdown
!>   flexmbs COMMAND --help                   the usage of one command (app/help_text)
!>   flexmbs --help | --version
!>
!> Exit codes: 0 success, 2 bad input (nothing written), 3 solver failure
!> (outputs kept; for `sweep --merge` and `-j`: points without a record),
!> 4 I/O error, 130 / 143 stopped by SIGINT / SIGTERM (outputs flushed and
!> closed). Only this program decides exit codes.
program flexmbs_main
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_flag_type, ieee_get_status, &
        ieee_set_status, ieee_get_flag, ieee_set_flag, ieee_invalid, ieee_divide_by_zero, &
        ieee_overflow
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, &
        status_solver_failure, status_io_error, status_interrupted, status_signal, &
        reason_name, reason_none
    use flexmbs_core_signals, only: install_signals, caught_signal
    use flexmbs_core_version, only: version
    use flexmbs_core_processes, only: executable_path
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_io_namelist, only: study_input_t, read_study
    use flexmbs_run_study, only: make_reference, run_sweep, run_sweep_point, sweep_run_t, &
        read_reference, prepare_points
    use flexmbs_io_result_columns, only: read_column
    use flexmbs_io_scene_reference, only: scene_reference_lines
    use flexmbs_run_study_grid, only: array_task_count
    use flexmbs_run_study_merge, only: merged_t, merge_records, merge_report
    use flexmbs_run_study_slurm, only: slurm_options_t, check_slurm_options, &
        write_slurm_scripts, shell_word
    use flexmbs_io_table, only: layout_text, table_markdown, stats_row_t
    use flexmbs_app_parallel_sweep, only: run_points_in_processes
    use flexmbs_app_slurm_submit, only: submit_study
    use flexmbs_app_modes_command, only: modes_command
    use flexmbs_app_help_text, only: has_command_usage, write_usage, write_command_usage
    use flexmbs_run_modes, only: modes_options_t
    use flexmbs_linalg_mumps_service, only: mpi_build, start_processes, stop_processes, &
        mumps_serve
    implicit none

    integer, parameter :: exit_ok = 0, exit_bad_input = 2, exit_solver = 3, exit_io = 4
    !> A run stopped by a signal exits with this plus the signal's number
    !> (the shell's convention: 130 for SIGINT, 143 for SIGTERM).
    integer, parameter :: exit_signal_base = 128
    !> Largest state printed whole; larger ones are summarised.
    integer, parameter :: max_printed = 12

    character(len=:), allocatable :: command, file, arg, value, slurm_only, resume_file
    logical :: quiet, force, merging, slurm, submit, jobs_given, verbose, resuming
    integer :: i, nargs, jobs, point, ios, rank, ranks
    type(slurm_options_t) :: cluster
    !> the IEEE flags at the start, all quiet (finish)
    type(ieee_status_type) :: quiet_flags

    call ieee_get_status(quiet_flags)

    ! An MPI run: rank 0 goes on, the others serve its MUMPS calls until it
    ! finishes (linalg/mumps_service); a signal must not end them first.
    call start_processes(rank, ranks)
    if (rank > 0) then
        if (install_signals(even_if_ignored=.true.)) continue
        call mumps_serve()
        call finish(exit_ok)
    end if
    call check_launch()

    nargs = command_argument_count()
    if (nargs == 0) then
        call write_usage(error_unit)
        call finish(exit_bad_input)
    end if
    command = argument(1)
    ! a command's --help wins over everything else on its line, even over
    ! a missing file: who asks for help may not know what the command needs
    if (has_command_usage(command)) then
        do i = 2, nargs
            if (argument(i) == '--help' .or. argument(i) == '-h') then
                call write_command_usage(command, output_unit)
                call finish(exit_ok)
            end if
        end do
    end if
    select case (command)
    case ('--help', '-h', 'help')
        ! `flexmbs help run` and `flexmbs --help run` as `flexmbs run --help`
        if (nargs >= 2) then
            if (has_command_usage(argument(2))) then
                call write_command_usage(argument(2), output_unit)
                call finish(exit_ok)
            end if
        end if
        call write_usage(output_unit)
        call finish(exit_ok)
    case ('--version', '-V')
        write (output_unit, '(a)') 'flexmbs ' // version
        call finish(exit_ok)
    case ('run', 'reference', 'sweep')
        if (ranks > 1 .and. command /= 'run') call fail_usage(command // ': one process; &
            &only flexmbs run uses several MPI ranks (got ' // int_text(ranks) // ')')
        quiet = .false.
        verbose = .false.
        resuming = .false.
        resume_file = ''
        force = .false.
        file = ''
        jobs = 1
        point = 0
        merging = .false.
        slurm = .false.
        submit = .false.
        jobs_given = .false.
        slurm_only = ''
        i = 1
        do while (i < nargs)
            i = i + 1
            arg = argument(i)
            if (arg == '--quiet' .or. arg == '-q') then
                quiet = .true.
            else if (command == 'run' .and. (arg == '--verbose' .or. arg == '-v')) then
                verbose = .true.
            else if (command == 'run' .and. arg == '--resume') then
                ! its optional value is the result file, told by its .h5
                resuming = .true.
                if (i < nargs) then
                    value = argument(i + 1)
                    if (len(value) > 3 .and. value(max(1, len(value) - 2):) == '.h5') then
                        resume_file = value
                        i = i + 1
                    end if
                end if
            else if (arg == '--force') then
                force = .true.
            else if (command == 'sweep' .and. any(arg == [character(len=11) :: '-j', &
                     '--point', '--chunk', '--partition', '--time', '--mem'])) then
                if (i == nargs) call fail_usage(arg // ' needs a value')
                i = i + 1
                value = argument(i)
                call sweep_option(arg, value)
            else if (command == 'sweep' .and. arg == '--merge') then
                merging = .true.
            else if (command == 'sweep' .and. arg == '--slurm') then
                slurm = .true.
            else if (command == 'sweep' .and. arg == '--submit') then
                submit = .true.
                slurm_only = arg
            else if (arg(1:min(1, len(arg))) == '-') then
                call fail_usage('unknown option ''' // arg // '''')
            else if (len(file) > 0) then
                call fail_usage(command // ' takes one file, got ''' // file // ''' and ''' &
                                // arg // '''')
            else
                file = arg
            end if
        end do
        ! SIGINT and SIGTERM stop a run after its current step (core/signals);
        ! a parallel sweep's point catches them although its shell ignores them
        if (.not. install_signals(even_if_ignored=point > 0)) write (error_unit, '(a)') &
            'flexmbs: warning: SIGINT and SIGTERM cannot be caught: they end the run at once'
        select case (command)
        case ('run')
            if (len(file) == 0) call fail_usage('run needs a scene file')
            call run(file, quiet, force, resuming, resume_file)
        case ('reference')
            if (len(file) == 0) call fail_usage('reference needs a study file')
            call reference(file, quiet, force)
        case ('sweep')
            if (len(file) == 0) call fail_usage('sweep needs a study file')
            call check_sweep_modes()
            if (point > 0) then
                call sweep_point(file, point, force)
            else if (merging) then
                call sweep_merge(file, force)
            else if (slurm) then
                cluster%force = force
                call sweep_slurm(file, cluster, submit, force)
            else if (jobs > 1) then
                call sweep_parallel(file, jobs, force)
            else
                call sweep(file, quiet, force)
            end if
        end select
    case ('modes')
        call modes()
    case ('columns')
        call columns()
    case ('scene-reference')
        if (nargs > 1) call fail_usage('scene-reference takes no arguments')
        call scene_reference()
    case default
        call fail_usage('unknown command ''' // command // '''')
    end select

contains

    subroutine run(path, quiet, force, resuming, resume_file)
        character(len=*), intent(in) :: path
        logical, intent(in) :: quiet, force
        logical, intent(in) :: resuming          !! --resume
        character(len=*), intent(in) :: resume_file  !! its file, '' for the scene's
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status

        call read_scene(path, scene, status)
        if (.not. status%ok()) call stop_on(status)
        if (ranks > 1 .and. scene%linear_solver /= 'mumps') call fail_usage(path // &
            ': &solver: linear_solver = ''' // trim(scene%linear_solver) // ''': ' // &
            int_text(ranks) // ' MPI ranks factor with MUMPS only (linear_solver = ''mumps'')')
        if (resuming) then
            if (len(resume_file) > 0) scene%output_file = resume_file
            if (len(scene%output_file) == 0) call fail_usage('run --resume: ' // path // &
                ' writes no HDF5 file (&output file = ''none''): name the result to &
                &continue, --resume RESULT.h5')
            call run_scene(scene, quiet, result, status, force=force, resume=scene%output_file)
        else
            call run_scene(scene, quiet, result, status, force=force)
        end if
        if (status%ok() .and. result%finished_before) then
            write (error_unit, '(a)') 'flexmbs: ' // scene%output_file // ' holds the finished &
                &run of ' // path // ': nothing to resume'
            call finish(exit_ok)
        end if
        select case (status%code)
        case (status_ok)
            if (allocated(result%stats%warning)) &
                write (error_unit, '(a)') 'flexmbs: warning: ' // result%stats%warning
            if (len_trim(scene%title) > 0) write (output_unit, '(a)') trim(scene%title)
            call report(result, scene, verbose)
            call finish(exit_ok)
        case (status_solver_failure, status_interrupted, status_signal)
            if (status%code == status_signal) then
                write (error_unit, '(a)') 'flexmbs: ' // status%text()
            else
                write (error_unit, '(a)') 'flexmbs: ' // failure_text(status)
            end if
            write (error_unit, '(a,es23.15)') 'flexmbs: time reached t =', result%t
            write (error_unit, '(a)') 'flexmbs: statistics so far: ' // result%stats%summary()
            if (result%hdf5_written) write (error_unit, '(a)') &
                'flexmbs: trajectory up to there kept in ' // scene%output_file
            if (len(result%xdmf_file) > 0) write (error_unit, '(a)') &
                'flexmbs: its records for ParaView (XDMF): ' // result%xdmf_file
            if (status%code == status_signal) call finish(signal_exit(status))
            call finish(exit_solver)
        case default
            call stop_on(status)
        end select
    end subroutine run

    !> The reference solution of a study, cross-checked.
    subroutine reference(path, quiet, force)
        character(len=*), intent(in) :: path
        logical, intent(in) :: quiet, force
        type(study_input_t) :: study
        type(status_t) :: status
        character(len=:), allocatable :: log
        call read_study(path, study, status)
        if (.not. status%ok()) call stop_on(status)
        call make_reference(study, quiet, log, status, force)
        if (.not. status%ok()) call stop_on(status)
        write (output_unit, '(a)', advance='no') log
        call finish(exit_ok)
    end subroutine reference

    !> A value of a sweep's option (`arg value`), checked as a number
    !> where it is one; --chunk's range is the Slurm options' check.
    subroutine sweep_option(arg, value)
        character(len=*), intent(in) :: arg, value
        select case (arg)
        case ('-j')
            read (value, *, iostat=ios) jobs
            if (ios /= 0 .or. jobs < 1) call fail_usage('-j ' // value // &
                ': needs a whole number >= 1')
            jobs_given = .true.
        case ('--point')
            read (value, *, iostat=ios) point
            if (ios /= 0 .or. point < 1) call fail_usage('--point ' // value // &
                ': needs a whole number >= 1')
        case ('--chunk')
            read (value, *, iostat=ios) cluster%chunk
            if (ios /= 0 .or. verify(trim(adjustl(value)), '+-0123456789') /= 0) &
                call fail_usage('--chunk ' // value // ': needs a whole number >= 1')
        case ('--partition')
            cluster%partition = value
        case ('--time')
            cluster%time = value
        case ('--mem')
            cluster%mem = value
        end select
        if (arg /= '-j' .and. arg /= '--point') slurm_only = arg
    end subroutine sweep_option

    !> A sweep does one of: all points here (-j N), one point (--point),
    !> the merge (--merge), the Slurm scripts (--slurm); the Slurm options
    !> only with --slurm.
    subroutine check_sweep_modes()
        character(len=:), allocatable :: modes
        modes = ''
        if (jobs_given) modes = modes // ' -j'
        if (point > 0) modes = modes // ' --point'
        if (merging) modes = modes // ' --merge'
        if (slurm) modes = modes // ' --slurm'
        if (count([jobs_given, point > 0, merging, slurm]) > 1) call fail_usage('sweep:' // &
            modes // ': only one of -j, --point, --merge and --slurm at a time')
        if (len(slurm_only) > 0 .and. .not. slurm) call fail_usage(slurm_only // &
            ': only with --slurm')
    end subroutine check_sweep_modes

    !> A study's grid of runs against its reference, here one after the
    !> other: a line per run, then the table (also written to the study's
    !> table file, if named).
    subroutine sweep(path, quiet, force)
        character(len=*), intent(in) :: path
        logical, intent(in) :: quiet, force
        type(study_input_t) :: study
        type(status_t) :: status
        type(sweep_run_t), allocatable :: runs(:)
        character(len=:), allocatable :: stale
        call read_study(path, study, status)
        if (.not. status%ok()) call stop_on(status)
        call run_sweep(study, quiet, runs, status, force, stale)
        if (allocated(runs)) then
            call print_runs(runs, study, stale)
            if (len(study%table) > 0 .and. status%ok()) &
                write (output_unit, '(a)') 'table: ' // study%table
        end if
        if (.not. status%ok()) call stop_on(status)
        call finish(exit_ok)
    end subroutine sweep

    !> A line per run, the table in the study's layout, its note (a stale
    !> reference used with --force), the count.
    subroutine print_runs(runs, study, note)
        type(sweep_run_t), intent(in) :: runs(:)
        type(study_input_t), intent(in) :: study
        character(len=*), intent(in) :: note
        type(stats_row_t), allocatable :: rows(:)
        integer :: k
        do k = 1, size(runs)
            write (output_unit, '(a)') runs(k)%summary
        end do
        rows = runs%row
        write (output_unit, '(a)', advance='no') layout_text(rows, table_markdown, &
            trim(study%layout))
        if (len(note) > 0) write (output_unit, '(a)') note
        write (output_unit, '(i0,a,i0,a)') count(runs%ok), ' runs finished, ', &
            count(.not. runs%ok), ' failed'
    end subroutine print_runs

    !> `sweep -j N`: the points in N processes at a time
    !> (app/parallel_sweep), then the table from their records.
    subroutine sweep_parallel(path, jobs, force)
        character(len=*), intent(in) :: path
        integer, intent(in) :: jobs
        logical, intent(in) :: force
        type(study_input_t) :: study
        type(status_t) :: status
        character(len=:), allocatable :: folder, problems
        integer :: npoints
        call read_study(path, study, status)
        if (.not. status%ok()) call stop_on(status)
        call prepare_points(study, npoints, folder, status, force)
        if (.not. status%ok()) call stop_on(status)
        call run_points_in_processes(this_program(), path, npoints, folder, jobs, force, &
                                     problems, status)
        if (len(problems) > 0) call say(problems(1:len(problems) - 1))
        if (.not. status%ok()) call stop_on(status)
        call merge_and_report(study, force)
    end subroutine sweep_parallel

    !> `sweep --merge`: the table from the records of the results folder.
    subroutine sweep_merge(path, force)
        character(len=*), intent(in) :: path
        logical, intent(in) :: force
        type(study_input_t) :: study
        type(status_t) :: status
        call read_study(path, study, status)
        if (.not. status%ok()) call stop_on(status)
        call merge_and_report(study, force)
    end subroutine sweep_merge

    !> The merged table as a sweep prints it, then what is missing or
    !> failed and how to run those points again; exit 0 when every point
    !> has its record (failed runs are rows, as in a serial sweep), 3 when
    !> some have none (the table file is then not written).
    subroutine merge_and_report(study, force)
        type(study_input_t), intent(in) :: study
        logical, intent(in) :: force
        type(status_t) :: status
        type(merged_t) :: merged
        character(len=:), allocatable :: report
        call merge_records(study, merged, status, force)
        if (.not. status%ok()) call stop_on(status)
        call print_runs(merged%runs, study, merged%stale_reference)
        if (merged%table_written) write (output_unit, '(a)') 'table: ' // study%table
        write (output_unit, '(a)') 'records: ' // merged%folder
        report = merge_report(merged, study, this_program())
        write (output_unit, '(a)', advance='no') report
        if (merged%complete()) call finish(exit_ok)
        call say(study%path // ': ' // int_text(size(merged%missing)) // ' of ' // &
            int_text(merged%npoints) // ' points have no current record (listed above); ' // &
            'no table written')
        call finish(exit_solver)
    end subroutine merge_and_report

    !> `sweep --slurm`: the job array and merge job scripts into the
    !> results folder; submitted with --submit, else the commands shown.
    subroutine sweep_slurm(path, options, submit, force)
        character(len=*), intent(in) :: path
        type(slurm_options_t), intent(in) :: options
        logical, intent(in) :: submit, force
        type(study_input_t) :: study
        type(status_t) :: status
        character(len=:), allocatable :: folder, array, merge, array_id, merge_id, stale
        integer :: npoints
        stale = ''
        call check_slurm_options(options, status)
        if (status%ok()) call read_study(path, study, status)
        if (status%ok()) call prepare_points(study, npoints, folder, status, force, stale)
        if (status%ok()) call write_slurm_scripts(study, this_program(), folder, npoints, &
                                                  options, array, merge, status)
        if (.not. status%ok()) call stop_on(status)
        write (output_unit, '(a)') 'job array: ' // array // ' (' // int_text(npoints) // &
            ' points in ' // int_text(array_task_count(npoints, options%chunk)) // ' tasks)', &
            'merge job: ' // merge
        ! the tasks and the merge job use the stale reference too (--force)
        if (len(stale) > 0) write (output_unit, '(a)') stale
        if (.not. submit) then
            write (output_unit, '(a)') 'submit with:', &
                '  jobid=$(sbatch --parsable ' // shell_word(array) // ')', &
                '  sbatch --dependency=afterany:$jobid ' // shell_word(merge)
            call finish(exit_ok)
        end if
        call submit_study(array, merge, folder, array_id, merge_id, status)
        if (.not. status%ok()) call stop_on(status)
        write (output_unit, '(a)') 'submitted: array job ' // array_id // ', merge job ' // &
            merge_id // ' (runs once the array has ended)'
        call finish(exit_ok)
    end subroutine sweep_slurm

    !> This program's executable, absolute when the system says it.
    function this_program() result(path)
        character(len=:), allocatable :: path
        path = executable_path()
        if (len(path) == 0) path = argument(0)
    end function this_program


    !> `modes FILE.nml [options]`: the eigen-analysis (app/modes_command).
    subroutine modes()
        type(modes_options_t) :: options
        type(status_t) :: status
        character(len=:), allocatable :: prefix
        logical :: run_failed
        file = ''
        prefix = ''
        force = .false.
        i = 1
        do while (i < nargs)
            i = i + 1
            arg = argument(i)
            select case (arg)
            case ('--force')
                force = .true.
            case ('--no-run')
                options%run_bdf = .false.
            case ('--time', '--count', '--shift', '--method', '--output')
                if (i == nargs) call fail_usage(arg // ' needs a value')
                i = i + 1
                value = argument(i)
                call modes_option(options, arg, value, prefix)
            case default
                if (arg(1:min(1, len(arg))) == '-') call fail_usage('unknown option ''' // &
                    arg // '''')
                if (len(file) > 0) call fail_usage('modes takes one file, got ''' // file // &
                    ''' and ''' // arg // '''')
                file = arg
            end select
        end do
        if (len(file) == 0) call fail_usage('modes needs a scene file')
        call modes_command(file, options, prefix, force, status, run_failed)
        if (.not. status%ok()) call stop_on(status)
        if (run_failed) call finish(exit_solver)
        call finish(exit_ok)
    end subroutine modes

    !> A value of a `modes` option, checked as a number where it is one.
    subroutine modes_option(options, arg, value, prefix)
        type(modes_options_t), intent(inout) :: options
        character(len=*), intent(in) :: arg, value
        character(len=:), allocatable, intent(inout) :: prefix
        select case (arg)
        case ('--time')
            read (value, *, iostat=ios) options%time
            if (ios /= 0) call fail_usage('--time ' // value // ': needs a number (s)')
            options%at_time = .true.
        case ('--count')
            read (value, *, iostat=ios) options%count
            if (ios /= 0 .or. verify(trim(adjustl(value)), '+0123456789') /= 0 .or. &
                options%count < 1) call fail_usage('--count ' // value // &
                ': needs a whole number >= 1')
        case ('--shift')
            read (value, *, iostat=ios) options%shift
            if (ios /= 0) call fail_usage('--shift ' // value // ': needs a number (1/s)')
        case ('--method')
            if (all(value /= [character(len=6) :: 'auto', 'dense', 'arpack'])) call &
                fail_usage('--method ' // value // ': use auto, dense or arpack')
            options%method = value
        case ('--output')
            if (len(value) == 0) call fail_usage('--output needs a path prefix')
            prefix = value
        end select
    end subroutine modes_option

    !> `columns FILE.h5 COLUMN...`: t and each column at every record of a
    !> result, as text (for plots). A column is a component number of /y or
    !> a name: rocker/position/z, motor/reaction_torque/z, coupler/node 23/x
    !> (io/result_columns).
    subroutine columns()
        type(status_t) :: status
        real(wp), allocatable :: t(:), values(:, :), column(:)
        real(wp), allocatable :: y(:, :)
        integer :: i, j
        if (nargs < 3) call fail_usage('columns needs a result file and columns (numbers of &
            &/y or names such as ''rocker/position/z'')')
        call read_reference(argument(2), t, y, status)
        if (.not. status%ok()) call stop_on(status)
        deallocate (y)
        allocate (values(size(t), nargs - 2))
        do i = 3, nargs
            call read_column(argument(2), argument(i), column, status)
            if (.not. status%ok()) call stop_on(status)
            if (size(column) < size(t)) then
                call status%set(status_io_error, argument(2) // ': column ''' // argument(i) &
                    // ''' has ' // int_text(size(column)) // ' records, /time ' // &
                    int_text(size(t)))
                call stop_on(status)
            end if
            values(:, i - 2) = column(1:size(t))
        end do
        do j = 1, size(t)
            write (output_unit, '(*(es24.15e3))') t(j), values(j, :)
        end do
        call finish(exit_ok)
    end subroutine columns

    !> One point of a study's grid (a parallel sweep's process, a Slurm
    !> task): its record into the results folder, its line here.
    subroutine sweep_point(path, k, force)
        character(len=*), intent(in) :: path
        integer, intent(in) :: k
        logical, intent(in) :: force
        type(study_input_t) :: study
        type(status_t) :: status
        type(sweep_run_t) :: run
        character(len=:), allocatable :: record
        call read_study(path, study, status)
        if (.not. status%ok()) call stop_on(status)
        call run_sweep_point(study, k, run, record, status, force)
        if (.not. status%ok()) call stop_on(status)
        write (output_unit, '(a)') run%summary, 'record: ' // record
        call finish(exit_ok)
    end subroutine sweep_point

    !> The run on standard output: the statistics line (with CPU and wall
    !> seconds), the last time, then for a scene with bodies its bodies,
    !> joints and flexible bodies there (run/summary), the energy and the
    !> drift; the state itself for a problem without bodies, or with
    !> --verbose.
    subroutine report(result, scene, verbose)
        type(run_result_t), intent(in) :: result
        type(scene_input_t), intent(in) :: scene
        logical, intent(in) :: verbose
        integer :: k, n
        logical :: bodies
        write (output_unit, '(a)') result%solver_name // ': ' // result%stats%summary()
        if (result%resumed) write (output_unit, '(a,es23.15,a)') 'resumed at t =', &
            result%resumed_from, ' (the statistics sum every piece of the run)'
        if (allocated(result%stats%linear_solver)) &
            write (output_unit, '(a)') 'linear solver: ' // result%stats%linear_solver
        if (verbose .and. allocated(result%stats%linear_solver_report)) then
            if (len(result%stats%linear_solver_report) > 0) write (output_unit, '(a)') &
                'factorisations: ' // result%stats%linear_solver_report
        end if
        n = size(result%y)
        write (output_unit, '(a,es23.15)') 't =', result%t
        bodies = .false.
        if (allocated(result%summary)) bodies = len(result%summary) > 0
        if (bodies) write (output_unit, '(a)', advance='no') result%summary
        if (verbose .or. .not. bodies) then
            do k = 1, merge(n, min(n, max_printed), verbose)
                write (output_unit, '(a,i0,a,es23.15)') 'y(', k, ') =', result%y(k)
            end do
            if (n > max_printed .and. .not. verbose) write (output_unit, '(a,i0,a)') '... (', &
                n, ' components; all of them are in the HDF5 file; --verbose prints them)'
        end if
        if (allocated(result%assembly)) write (output_unit, '(a)') &
            'initial assembly moved: ' // result%assembly
        ! (a flexible body alone says more below: strain, kinetic, total)
        if (result%has_monitor_energy .and. .not. result%has_energy) &
            write (output_unit, '(a,es14.6,a,es14.6,a,es10.2,a)') &
            'energy [J]: at t_start', result%monitor_energy(1), ', at t_end', &
            result%monitor_energy(2), ' (change', result%monitor_energy(2) - &
            result%monitor_energy(1), ')'
        if (result%has_drift .and. result%constraints > 0) then
            write (output_unit, '(a,2es11.3)') 'constraint drift at t_end: |g|, |G v + g_I|', &
                result%drift_end
        end if
        if (result%has_energy) then
            write (output_unit, '(a,3es14.6)') 'energy at t_start [J]: strain, kinetic, total', &
                result%energy_start
            write (output_unit, '(a,3es14.6)') 'energy at t_end   [J]: strain, kinetic, total', &
                result%energy_end
        end if
        if (len(scene%output_file) > 0) write (output_unit, '(a)') &
            'trajectory: ' // scene%output_file
        if (len(result%xdmf_file) > 0) write (output_unit, '(a)') &
            'for ParaView (XDMF): ' // result%xdmf_file
        if (len_trim(scene%table) > 0) write (output_unit, '(a)') 'table: ' // trim(scene%table)
    end subroutine report

    pure function failure_text(status) result(text)
        type(status_t), intent(in) :: status
        character(len=:), allocatable :: text
        text = 'solver failure'
        if (status%reason /= reason_none) text = text // ' (' // reason_name(status%reason) // ')'
        text = text // ': ' // status%text()
    end function failure_text

    !> Message on standard error and the exit code of the status.
    subroutine stop_on(status)
        type(status_t), intent(in) :: status
        call say(status%text())
        select case (status%code)
        case (status_bad_input)
            call finish(exit_bad_input)
        case (status_io_error)
            call finish(exit_io)
        case (status_signal)
            call finish(signal_exit(status))
        case default
            call finish(exit_solver)
        end select
    end subroutine stop_on

    !> A message on standard error, each line headed 'flexmbs: '; control
    !> characters a file may carry (escape sequences) shown as '?'.
    subroutine say(text)
        character(len=*), intent(in) :: text
        character(len=len(text)) :: clean
        integer :: i, start
        clean = text
        do i = 1, len(clean)
            if (clean(i:i) == new_line('a')) cycle
            if (iachar(clean(i:i)) < 32 .or. iachar(clean(i:i)) == 127) clean(i:i) = '?'
        end do
        start = 1
        do i = 1, len(clean) + 1
            if (i <= len(clean)) then
                if (clean(i:i) /= new_line('a')) cycle
            end if
            write (error_unit, '(a)') 'flexmbs: ' // clean(start:i - 1)
            start = i + 1
        end do
    end subroutine say

    !> 128 + the number of the signal that stopped the run (the status's
    !> reason; a sweep's processes may have caught it instead of this one).
    integer function signal_exit(status)
        type(status_t), intent(in) :: status
        signal_exit = exit_solver
        if (status%reason > 0) then
            signal_exit = exit_signal_base + status%reason
        else if (caught_signal() > 0) then
            signal_exit = exit_signal_base + caught_signal()
        end if
    end function signal_exit

    !> A bad command line: the message, and where the usage is (the
    !> command's own when the command is known).
    subroutine fail_usage(message)
        character(len=*), intent(in) :: message
        write (error_unit, '(a)') 'flexmbs: ' // message
        if (has_command_usage(command)) then
            write (error_unit, '(a)') 'try ''flexmbs ' // command // ' --help'''
        else
            write (error_unit, '(a)') 'try ''flexmbs --help'''
        end if
        call finish(exit_bad_input)
    end subroutine fail_usage

    !> The scene reference on standard output.
    subroutine scene_reference()
        character(len=:), allocatable :: lines(:)
        integer :: k
        call scene_reference_lines(lines)
        do k = 1, size(lines)
            write (output_unit, '(a)') trim(lines(k))
        end do
        call finish(exit_ok)
    end subroutine scene_reference

    function argument(i) result(value)
        integer, intent(in) :: i
        character(len=:), allocatable :: value
        integer :: length
        call get_command_argument(i, length=length)
        allocate (character(len=length) :: value)
        if (length > 0) call get_command_argument(i, value)
    end function argument

    !> Stop with `code`. A success ends with gfortran's note on the
    !> floating-point exceptions still signalling, but only the real ones:
    !> invalid, divide-by-zero and overflow (library calls that raise them
    !> on purpose keep the flags as they were: linalg/lapack). Underflow to
    !> subnormal numbers is IEEE arithmetic working as designed, not an
    !> error, and is not reported. A failure has said why on its own.
    !> A sequential flexmbs started as several MPI ranks (mpirun, srun -n)
    !> would run the scene once per rank, each writing the same files: bad
    !> use, said before anything runs. The launchers' variables tell.
    subroutine check_launch()
        character(len=*), parameter :: names(3) = [character(len=21) :: &
            'OMPI_COMM_WORLD_SIZE', 'PMI_SIZE', 'SLURM_STEP_NUM_TASKS']
        character(len=32) :: value
        integer :: k, count, length, stat
        if (mpi_build) return
        do k = 1, size(names)
            call get_environment_variable(trim(names(k)), value, length, stat)
            if (stat /= 0) cycle
            read (value, *, iostat=stat) count
            if (stat == 0 .and. count > 1) call fail_usage('this flexmbs is a sequential &
                &build, started as ' // trim(value) // ' processes (' // trim(names(k)) // &
                '): each would run the whole scene; build with make MPI=1 &
                &(docs/large_scenes.md) or start one process')
        end do
    end subroutine check_launch

    subroutine finish(code)
        integer, intent(in) :: code
        type(ieee_flag_type), parameter :: real_ones(3) = [ieee_invalid, &
            ieee_divide_by_zero, ieee_overflow]
        logical :: raised(3)
        flush (output_unit)
        flush (error_unit)
        call stop_processes()
        if (code /= exit_ok) stop code, quiet = .true.
        call ieee_get_flag(real_ones, raised)
        call ieee_set_status(quiet_flags)   ! underflow and denormal too
        call ieee_set_flag(real_ones, raised)
        stop
    end subroutine finish
end program flexmbs_main
