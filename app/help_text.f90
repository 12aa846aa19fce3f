!> The help texts of the flexmbs command line: the overview of `flexmbs
!> --help` and each command's own usage (`flexmbs COMMAND --help`), with
!> every option the command line (app/main) takes for it and an example.
!> They live apart from the parsing so that app/main stays about running
!> the commands; a new option is added to the parsing and to its text here.
module flexmbs_app_help_text
    use flexmbs_core_version, only: version
    implicit none
    private

    !> The commands that have a usage of their own, as typed.
    character(len=*), parameter :: commands(6) = [character(len=15) :: 'run', 'reference', &
        'sweep', 'columns', 'modes', 'scene-reference']
    character, parameter :: nl = achar(10)
    !> The lines of the options several commands share (each usage ends
    !> with its -h, --help line: write_command_usage).
    character(len=*), parameter :: force_text = '  --force           replace any file at an &
        &output''s path, not only' // nl // '                    flexmbs''s own of that kind'
    character(len=*), parameter :: quiet_text = '  -q, --quiet       no progress display on &
        &standard error'
    !> Where a study's records go, for the overview and sweep's usage.
    character(len=*), parameter :: results_folder_text = 'The results folder of a study is &
        &<study name>_points/ beside its table, or' // nl // 'beside the study file when it &
        &names no table (docs/studies_on_a_cluster.md).'

    public :: has_command_usage, write_usage, write_command_usage

contains

    !> Whether `command` is one of flexmbs's commands (with its own usage).
    pure logical function has_command_usage(command)
        character(len=*), intent(in) :: command
        has_command_usage = any(commands == command)
    end function has_command_usage

    !> The overview of `flexmbs --help`, every command in a line or two,
    !> the files, the exit codes; each command's usage has its options.
    subroutine write_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'flexmbs ' // version // &
            ' - flexible multibody dynamics and stiff DAE solvers', &
            '', &
            'usage:', &
            '  flexmbs run FILE.nml [--quiet] [--force] [--verbose]', &
            '                                          run the scene described by FILE.nml', &
            '  flexmbs run FILE.nml --resume [RESULT.h5]', &
            '                                          continue a stopped or killed run from', &
            '                                          the checkpoint in its HDF5 file', &
            '  flexmbs reference STUDY.nml [--quiet] [--force]', &
            '                                          integrate the study''s scene at tight', &
            '                                          tolerance, cross-check, keep in HDF5', &
            '  flexmbs sweep STUDY.nml [-j N] [--quiet] [--force]', &
            '                                          run the study''s grid of solvers and', &
            '                                          tolerances, ERR against the reference;', &
            '                                          -j N: N processes at a time', &
            '  flexmbs sweep STUDY.nml --point K       run grid point K alone, its record', &
            '                                          into the results folder', &
            '  flexmbs sweep STUDY.nml --merge         the table from the records there', &
            '  flexmbs sweep STUDY.nml --slurm [--chunk K] [--partition P] [--time T]', &
            '                                [--mem M] [--submit]', &
            '                                          write a Slurm job array and a merge', &
            '                                          job into the results folder;', &
            '                                          --submit submits both', &
            '  flexmbs columns FILE.h5 COLUMN [COLUMN ...]', &
            '                                          t and the columns of a result, as text', &
            '  flexmbs modes FILE.nml [--time T] [--count K] [--shift S]', &
            '                         [--method auto|dense|arpack] [--output P] [--no-run]', &
            '                         [--force]', &
            '                                          eigenvalues of the scene linearised,', &
            '                                          its modes, and the BDF sectors at the', &
            '                                          step sizes of a BDF run (docs/modes.md)', &
            '  flexmbs scene-reference                 every group and variable of a scene', &
            '                                          file: type, unit, default, range, as', &
            '                                          Markdown (docs/scene_reference.md)', &
            '  flexmbs COMMAND --help                  the usage of COMMAND alone: each of', &
            '                                          its options, and an example', &
            '  flexmbs --help                          show this text', &
            '  flexmbs --version                       show the version', &
            '', &
            'FILE.nml holds the namelist groups &simulation, &solver and &output,', &
            'and for a flexible body &flexible_body with one or more &material;', &
            'for rigid bodies and joints &multibody, &rigid_body, &marker, &joint, &driver,', &
            '&force, and any number of &flexible_body groups (each &material naming its', &
            'body); for chains in relative coordinates &rigid_chain (a tree each)', &
            '(docs/scene_reference.md or flexmbs scene-reference: every variable,', &
            'its type, unit and default; docs/user_guide.md: how to use them).', &
            'STUDY.nml holds one &study group naming a scene file and the grid.', &
            'Paths in a scene or study file are relative to that file''s folder;', &
            'every error of a file is listed, one per line.', &
            '--quiet turns the progress display on standard error off.', &
            'An output never replaces an input, and two outputs of a run are never one', &
            'file. A file already at an output''s path is replaced only when it is', &
            'flexmbs''s own of that kind (an HDF5 result, a ParaView file, a table);', &
            '--force replaces anything else too. A sweep refuses a reference made from', &
            'another version of its study (exit 2); --force uses it, the table says so.', &
            '', &
            results_folder_text, &
            '', &
            'exit codes: 0 success, 2 bad input (no output written),', &
            '            3 solver failure (outputs kept); sweep --merge and -j: a point', &
            '            has no current record (no table written), 4 I/O error,', &
            '            130 / 143 stopped by SIGINT / SIGTERM after the current step', &
            '            (outputs flushed and closed; a second signal ends it at once)'
    end subroutine write_usage

    !> The usage of `command` alone (has_command_usage): what it does, each
    !> option it takes, an example, and where the documentation says more.
    subroutine write_command_usage(command, unit)
        character(len=*), intent(in) :: command
        integer, intent(in) :: unit
        character(len=:), allocatable :: example
        select case (command)
        case ('run')
            call run_usage(unit)
            example = 'flexmbs run inputs/five_body.nml'
        case ('reference')
            call reference_usage(unit)
            example = 'flexmbs reference inputs/paper/four_bar_study.nml'
        case ('sweep')
            call sweep_usage(unit)
            example = 'flexmbs sweep inputs/paper/four_bar_study.nml -j 2'
        case ('columns')
            call columns_usage(unit)
            example = 'flexmbs columns five_body.h5 ''rocker pivot/angle'' ''coupler/node 23/x'''
        case ('modes')
            call modes_usage(unit)
            example = 'flexmbs modes inputs/five_body.nml --count 5 --no-run'
        case default
            call scene_reference_usage(unit)
            example = 'flexmbs scene-reference > scene_reference.md'
        end select
        write (unit, '(a)') '  -h, --help        show this text', '', 'example:', &
            '  ' // example, ''
        if (command == 'columns' .or. command == 'scene-reference') then
            write (unit, '(a)') 'The exit codes: flexmbs --help.'
        else
            write (unit, '(a)') 'The exit codes, and which files an output may replace: ' // &
                'flexmbs --help.'
        end if
    end subroutine write_command_usage

    subroutine run_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs run FILE.nml [--quiet] [--force] [--verbose]', &
            '       flexmbs run FILE.nml --resume [RESULT.h5] [--quiet] [--verbose]', &
            '', &
            'Run the scene described by FILE.nml: read and check the whole file first', &
            '(every error listed, nothing written), integrate it, write the outputs it', &
            'names (the HDF5 trajectory, a statistics table, ParaView files), and print', &
            'the statistics line, the linear solver that factored the Newton matrices', &
            '(what linear_solver = ''auto'' chose) and the end state on standard', &
            'output: the bodies by name, the energy and the constraint drift for a', &
            'scene with bodies, the state y (at most 12 components) for one without', &
            '(docs/user_guide.md).', &
            '', &
            'The HDF5 file keeps a checkpoint, the state of an accepted step, every', &
            'checkpoint_interval seconds (&output, default 60) and when SIGINT or SIGTERM', &
            'stops the run. --resume continues the run from it, in the same file: the', &
            'records up to the checkpoint stay, the statistics sum every piece. The', &
            'scene must be the one that wrote the file (docs/output.md, "Restart").', &
            '', &
            'options:', &
            quiet_text, &
            '  -v, --verbose     every component of the end state y too', &
            '  --resume [RESULT.h5]', &
            '                    continue the run kept in RESULT.h5 (the scene''s own', &
            '                    &output file when not given) from its checkpoint', &
            force_text
    end subroutine run_usage

    subroutine reference_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs reference STUDY.nml [--quiet] [--force]', &
            '', &
            'The reference solution of the study STUDY.nml (one &study group): its scene', &
            'integrated at the study''s reference tolerance, integrated again by the', &
            'check solver, the ERR between the two printed, and the reference written', &
            'to the study''s reference_file (HDF5) when both runs succeed; a sweep', &
            'measures its runs against it (docs/studies.md).', &
            '', &
            'options:', &
            quiet_text, &
            force_text
    end subroutine reference_usage

    subroutine sweep_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs sweep STUDY.nml [-j N] [--quiet] [--force]', &
            '       flexmbs sweep STUDY.nml --point K [--force]', &
            '       flexmbs sweep STUDY.nml --merge [--force]', &
            '       flexmbs sweep STUDY.nml --slurm [--chunk K] [--partition P] [--time T]', &
            '                               [--mem M] [--submit] [--force]', &
            '', &
            'The study''s grid of solvers and tolerances (one &study group), each run', &
            'measured (ERR) against the study''s reference (flexmbs reference first):', &
            'a line per run, then the table, also written to the study''s table file', &
            '(docs/studies.md). -j, --point, --merge and --slurm split the grid into', &
            'records, one per point; only one of them at a time.', &
            results_folder_text, &
            'Each first compares the reference''s fingerprint with what `flexmbs', &
            'reference STUDY.nml` would make of the study now (the scene''s settings', &
            'and mesh, t_start, t_end, the output times, the reference''s solver and', &
            'tolerance) and refuses a stale reference (exit 2, nothing written),', &
            'naming what differs.', &
            '', &
            'options:', &
            quiet_text, &
            '  --force           use a stale reference (or one without a fingerprint)', &
            '                    if its output times are the scene''s: the table says so', &
            '                    (-j and --slurm pass --force on to the points and the', &
            '                    merge); and replace any file at the table''s path, not', &
            '                    only flexmbs''s own', &
            '  -j N              the points in N processes at a time (each', &
            '                    flexmbs sweep STUDY.nml --point K), then the merge', &
            '  --point K         grid point K alone (1 .. the grid''s size, in the', &
            '                    table''s order): its record into the results folder;', &
            '                    a point stopped before (SIGTERM, a time limit) resumes', &
            '                    from its checkpoint (point_K.h5 there)', &
            '  --merge           the table from the records in the results folder; lists', &
            '                    the points missing, stale or failed and the commands', &
            '                    that run only those', &
            '  --slurm           write a Slurm job array (array.sbatch) and a merge job', &
            '                    (merge.sbatch) into the results folder and show the', &
            '                    sbatch commands that submit them', &
            '  --chunk K         (--slurm) K consecutive grid points per array task', &
            '                    (default 1)', &
            '  --partition P     (--slurm) #SBATCH --partition=P', &
            '  --time T          (--slurm) #SBATCH --time=T: M, M:S, H:M:S, D-H, D-H:M,', &
            '                    D-H:M:S or UNLIMITED; 120 s before it a task stops its', &
            '                    point with a checkpoint, requeues and resumes it', &
            '  --mem M           (--slurm) #SBATCH --mem=M: a whole number, unit K, M, G', &
            '                    or T (M when none)', &
            '  --submit          (--slurm) submit both, the merge job to run once the', &
            '                    array has ended, and show their job ids'
    end subroutine sweep_usage

    subroutine columns_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs columns FILE.h5 COLUMN [COLUMN ...]', &
            '', &
            't and the chosen columns of the result FILE.h5 as text, one output time', &
            'per line, for a quick plot or a spreadsheet (docs/output.md). A COLUMN is', &
            '  K                        component K of /y (counted from 1)', &
            '  BODY/QUANTITY/COMPONENT  ''rocker/position/z'', ''motor/reaction_torque/z''', &
            '  JOINT/QUANTITY           ''rocker pivot/angle''', &
            '  BODY/node N/COMPONENT    a node of a flexible body: ''coupler/node 23/x'',', &
            '                           ''coupler/node 23/velocity/x''', &
            'A name with blanks is one argument: quote it in the shell.', &
            '', &
            'options:'
    end subroutine columns_usage

    subroutine modes_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs modes FILE.nml [--time T] [--count K] [--shift S]', &
            '                     [--method auto|dense|arpack] [--output P] [--no-run]', &
            '                     [--force]', &
            '', &
            'The eigenvalues of the scene''s DAE pencil (dF/dy, M) linearised at t_start', &
            '(or T): the K lowest modes with frequency and damping, and per BDF order', &
            'the stiff modes outside its A(alpha) sector at the step sizes a BDF run of', &
            'the scene took at that order; every eigenvalue in P.csv, a plot in P.png', &
            '(when gnuplot is on PATH) (docs/modes.md).', &
            '', &
            'options:', &
            '  --time T          linearise at time T [s], which the BDF run reaches', &
            '                    (default t_start; other times not with --no-run)', &
            '  --count K         the modes listed (default 10); with arpack also the', &
            '                    modes computed', &
            '  --method M        dense: QZ, every eigenvalue; arpack: the eigenvalues', &
            '                    nearest S; auto (default): dense up to 2000 unknowns,', &
            '                    else arpack', &
            '  --shift S         ARPACK''s shift [1/s], not an eigenvalue (default -1)', &
            '  --output P        the files P.csv and P.png (default: the scene''s path', &
            '                    without .nml, then _modes)', &
            '  --no-run          no BDF run, so no sector check', &
            force_text
    end subroutine modes_usage

    subroutine scene_reference_usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs scene-reference', &
            '', &
            'Every group and variable a scene file can hold, with its type, unit,', &
            'default and range, as Markdown on standard output: what', &
            'docs/scene_reference.md holds. Takes no file.', &
            '', &
            'options:'
    end subroutine scene_reference_usage
end module flexmbs_app_help_text
