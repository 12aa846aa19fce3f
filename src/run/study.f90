!> Studies over a scene (`flexmbs reference`, `flexmbs sweep`).
!>
!> A reference is the scene integrated by `reference_solver` at rtol = atol
!> = `reference_tolerance`, kept at the scene's output times in an HDF5
!> trajectory file (/time, /y, /q) with its provenance: the study and scene
!> files, the solver and tolerance, the cross-check (a second solver at
!> `check_tolerance` and the ERR between the two), and, as every result file,
!> the flexmbs version and the date (attributes); and the fingerprint of
!> what made it (run/reference_fingerprint), which every sweep compares with
!> what `flexmbs reference` would make of the study now before it runs: a
!> stale reference is bad input unless forced, and then the table says so.
!>
!> A sweep runs the grid solvers × stabilisations × tolerances × p_max
!> (DDASSL only) × derivative sources (multibody scenes only), each at
!> rtol = atol = TOL, and measures ERR of eq. (13) against the reference over
!> the positions (block q; all of y for problems without one) at every
!> output time. Stabilisations of multibody scenes: 'none' is the index-2
!> formulation, 'ggl' GGL (eq. 10), 'projection' index 2 with coordinate
!> projection (eqs. 11-12); MEXAX always projects internally and runs once
!> per tolerance ('projection'). A run that fails is a row with ERR '-' and
!> the reason on its summary line; a run whose output times or size are not
!> the reference's stops the sweep as bad input (ERR cannot be measured).
!> CPU in the table is normalised to the row `cpu_reference` (the paper's
!> Tables 2 and 3 normalise to one run).
!>
!> A point of the grid can also run alone (`sweep --point K`, the process
!> of a parallel sweep or a Slurm array task): its record goes into the
!> study's results folder (run/study_results, run/study_record), and
!> run/study_merge assembles the table from the records there.
module flexmbs_run_study
    use hdf5
    use flexmbs_io_result_columns, only: open_result
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error, &
        status_solver_failure, status_signal
    use flexmbs_core_signals, only: signal_pending, caught_signal, signal_name
    use flexmbs_core_text, only: int_text, real_text
    use flexmbs_core_files, only: delete_file
    use flexmbs_io_xdmf_file, only: xdmf_beside
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_run_catalogue, only: solver_projects, solver_pmax_grid, problem_stabilisations
    use flexmbs_io_namelist, only: study_input_t, scene_input_t, read_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_io_record_sink, only: record_sink_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_table, only: stats_row_t, new_stats_row, write_table
    use flexmbs_io_output_files, only: named_path_t, named_path, check_output_paths, &
        output_hdf5, output_table
    use flexmbs_run_study_grid, only: sweep_point_t, sweep_points
    use flexmbs_run_study_results, only: make_results_folder, record_path, point_result_path
    use flexmbs_run_study_record, only: sweep_run_t, fingerprint_t, study_fingerprint, &
        write_record
    use flexmbs_run_reference_fingerprint, only: reference_print_t, reference_print, &
        write_reference_print, check_reference_print, check_reference_times, remake_command, &
        same_times
    implicit none
    private

    public :: sweep_run_t
    public :: make_reference, run_sweep, run_sweep_point, prepare_points, read_reference, &
        read_study_scene, check_study_output

contains

    !> The scene of a study with one run's settings: solver, rtol = atol =
    !> tol, and (multibody) the formulation and projection of `stab`, the
    !> derivative source; no HDF5 file, no table, no ParaView files.
    subroutine configure(base, solver, tol, stab, pmax, derivatives, scene)
        type(scene_input_t), intent(in) :: base
        character(len=*), intent(in) :: solver, stab, derivatives
        real(wp), intent(in) :: tol
        integer, intent(in) :: pmax
        type(scene_input_t), intent(out) :: scene
        scene = base
        scene%solver_name = solver
        scene%rtol = tol
        scene%atol = tol
        scene%pmax = pmax
        scene%output_file = ''
        scene%table = ''
        scene%vtk = ''
        if (.not. problem_stabilisations(scene%problem)) return
        select case (stab)
        case ('none')
            scene%multibody%formulation = 'index2'
            scene%multibody%projection = .false.
        case ('ggl')
            scene%multibody%formulation = 'ggl'
            scene%multibody%projection = .false.
        case ('projection')
            scene%multibody%formulation = 'index2'
            scene%multibody%projection = .true.
        end select
        if (len_trim(derivatives) > 0) scene%multibody%constraint_derivatives = derivatives
    end subroutine configure

    !> The study's scene, with the study's t_end when it sets one.
    subroutine read_study_scene(study, scene, status)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(out) :: scene
        type(status_t), intent(out) :: status
        call read_scene(study%scene, scene, status)
        if (.not. status%ok()) return
        if (study%t_end > 0.0_wp) then
            if (.not. study%t_end > scene%t_start) then
                call status%set(status_bad_input, study%path // ': &study: t_end: must be ' // &
                    'after the scene''s t_start')
                return
            end if
            scene%t_end = study%t_end
        end if
    end subroutine read_study_scene

    !> An output of a study (`name` = `output`: its reference file or its
    !> table, of `kind` output_hdf5 or output_table): its folder must exist,
    !> it must not be one of the study's inputs — the study file, the scene
    !> file, the scene's mesh file, and for the table the reference, which
    !> the sweep reads — however spelled, and a file there must be flexmbs's
    !> own of that kind unless `force` (io/output_files). Checked before any
    !> run, so that no reference is computed only to be refused when it is
    !> written, and no input is overwritten.
    subroutine check_study_output(study, base, name, output, kind, force, status)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(in) :: base
        character(len=*), intent(in) :: name, output
        integer, intent(in) :: kind
        logical, intent(in) :: force
        type(status_t), intent(inout) :: status
        type(named_path_t) :: inputs(3 + size(base%bodies)), outputs(1)
        character(len=:), allocatable :: folder
        logical :: exists
        integer :: slash, n, b
        slash = index(output, '/', back=.true.)
        if (slash > 1) then
            folder = output(1:slash - 1)
            inquire (file=folder // '/.', exist=exists)
            if (.not. exists) then
                call status%set(status_bad_input, study%path // ': &study: ' // name // &
                    ' = ''' // output // ''': the folder ''' // folder // ''' does not exist')
                return
            end if
        end if
        inputs(1) = named_path(study%path, 'an input of the study (the study file)')
        inputs(2) = named_path(study%scene, 'an input of the study (its scene file)')
        n = 2
        do b = 1, size(base%bodies)
            if (len_trim(base%bodies(b)%mesh_file) == 0) cycle
            n = n + 1
            inputs(n) = named_path(trim(base%bodies(b)%mesh_file), 'an input of the study &
                &(the scene''s mesh file)')
        end do
        if (kind == output_table) then
            n = n + 1
            inputs(n) = named_path(study%reference_file, 'an input of the sweep (the &
                &reference file)')
        end if
        outputs(1) = named_path(output, '&study: ' // name, kind)
        call check_output_paths(study%path // ': ', outputs, inputs(1:n), force, status)
    end subroutine check_study_output

    !> The reference of a study (module header); `log` gets one line per
    !> run. Nothing is written unless both runs succeed.
    subroutine make_reference(study, quiet, log, status, force)
        type(study_input_t), intent(in) :: study
        logical, intent(in) :: quiet
        character(len=:), allocatable, intent(out) :: log
        type(status_t), intent(out) :: status
        !> replace a file at reference_file that is not flexmbs's own
        logical, intent(in), optional :: force
        type(scene_input_t) :: base, scene
        type(run_result_t) :: ref, chk
        type(record_sink_t) :: rec, rec_check
        type(hdf5_sink_t) :: h5
        type(status_t) :: close_status
        type(reference_print_t) :: print
        character(len=:), allocatable :: check_text
        real(wp) :: err
        integer :: k
        character, parameter :: nl = new_line('a')

        call read_study_scene(study, base, status)
        if (.not. status%ok()) return
        call check_study_output(study, base, 'reference_file', study%reference_file, &
                                output_hdf5, given(force), status)
        ! what it is made from, before the runs: a sweep compares it with its own
        if (status%ok()) call reference_print(study, base, print, status)
        if (.not. status%ok()) return
        call one_run('reference', trim(study%reference_solver), study%reference_tolerance, &
                     ref, rec)
        if (.not. status%ok()) return
        log = 'reference: ' // ref%solver_name // ' at ' // real_text(study%reference_tolerance) &
            // ': ' // ref%stats%summary() // nl
        check_text = 'none'
        if (len_trim(study%check_solver) > 0) then
            call one_run('check', trim(study%check_solver), study%check_tolerance, chk, &
                         rec_check)
            if (.not. status%ok()) return
            if (rec_check%records /= rec%records) then
                call status%set(status_solver_failure, study%path // ': the check run has ' &
                    // int_text(rec_check%records) // ' output records, the reference ' // &
                    int_text(rec%records))
                return
            end if
            err = series_error(rec_check%y(ref%q_first:ref%q_last, 1:rec%records), &
                               rec%y(ref%q_first:ref%q_last, 1:rec%records), &
                               study%check_tolerance)
            check_text = trim(study%check_solver) // ' at ' // real_text(study%check_tolerance) &
                // ': ERR = ' // real_text(err) // ' (' // &
                real_text(err / study%check_tolerance) // ' of its TOL)'
            log = log // 'check: ' // chk%solver_name // ': ' // chk%stats%summary() // nl // &
                'check: ERR of ' // check_text // nl
        end if

        call h5%create(study%reference_file, size(rec%y, 1), status, input_text=base%text)
        if (status%ok()) call h5%add_block('q', ref%q_first, ref%q_last, status)
        do k = 1, rec%records
            if (.not. status%ok()) exit
            call h5%output(rec%t(k), rec%y(:, k), status)
        end do
        if (status%ok()) call h5%write_text('study_file', study%path, status)
        if (status%ok()) call h5%write_text('scene_file', study%scene, status)
        if (status%ok()) call h5%write_text('reference_solver', ref%solver_name, status)
        if (status%ok()) call h5%write_text('reference_tolerance', &
                                            real_text(study%reference_tolerance), status)
        if (status%ok()) call h5%write_text('check', check_text, status)
        if (status%ok()) call write_reference_print(h5, print, status)
        if (status%ok()) call h5%write_statistics(ref%stats, status, ref%solver_name, 'ok')
        call h5%close(close_status)
        if (status%ok()) status = close_status
        if (.not. status%ok()) then
            call status%set(status_io_error, study%reference_file // ': ' // status%text())
            return
        end if
        log = log // 'written: ' // study%reference_file // ' (' // int_text(rec%records) // &
            ' output times)' // nl

    contains

        !> The scene with `solver` at rtol = atol = tol, recorded; a failure
        !> says which run (`what`) failed.
        subroutine one_run(what, solver, tol, result, rec)
            character(len=*), intent(in) :: what, solver
            real(wp), intent(in) :: tol
            type(run_result_t), intent(out) :: result
            type(record_sink_t), intent(inout) :: rec
            call configure(base, solver, tol, '', base%pmax, '', scene)
            call run_scene(scene, quiet, result, status, rec)
            if (.not. status%ok()) call status%set(status%code, study%path // ': ' // what // &
                ' run (' // solver // ') failed: ' // status%text(), status%reason)
        end subroutine one_run
    end subroutine make_reference

    !> /time and /y of a trajectory file.
    subroutine read_reference(path, t, y, status)
        character(len=*), intent(in) :: path
        real(wp), allocatable, intent(out) :: t(:), y(:, :)
        type(status_t), intent(out) :: status
        integer(hid_t) :: file, dset, space
        integer(hsize_t) :: dims(2), maxdims(2)
        integer :: err, stat
        logical :: exists
        inquire (file=path, exist=exists)
        if (.not. exists) then
            call status%set(status_bad_input, path // ': no reference file (make it with ' // &
                '''flexmbs reference'' first)')
            return
        end if
        call open_result(path, file, status)
        if (.not. status%ok()) return
        call h5dopen_f(file, 'time', dset, err)
        if (err >= 0) then
            call h5dget_space_f(dset, space, err)
            call h5sget_simple_extent_dims_f(space, dims(1:1), maxdims(1:1), err)
            allocate (t(dims(1)), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, path // ': /time', int(dims(1), i8), 8)
                err = -1
            end if
            if (err >= 0) call h5dread_f(dset, H5T_NATIVE_DOUBLE, t, dims(1:1), err)
            call h5sclose_f(space, err)
            call h5dclose_f(dset, err)
        end if
        if (err >= 0) call h5dopen_f(file, 'y', dset, err)
        if (err >= 0) then
            call h5dget_space_f(dset, space, err)
            call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
            allocate (y(dims(1), dims(2)), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, path // ': /y', int(dims(1) * dims(2), i8), 8)
                err = -1
            end if
            if (err >= 0) call h5dread_f(dset, H5T_NATIVE_DOUBLE, y, dims, err)
            call h5sclose_f(space, err)
            call h5dclose_f(dset, err)
        end if
        if (err < 0 .and. status%ok()) &
            call status%set(status_io_error, path // ': cannot read /time and /y')
        call h5fclose_f(file, err)
    end subroutine read_reference

    !> Every run of the study's grid against its reference (module header),
    !> one after the other in this process; the table written when the
    !> study names one. A parallel sweep runs the points in processes of
    !> their own (app/) and merges their records (run/study_merge).
    subroutine run_sweep(study, quiet, runs, status, force, stale)
        type(study_input_t), intent(in) :: study
        logical, intent(in) :: quiet
        type(sweep_run_t), allocatable, intent(out) :: runs(:)
        type(status_t), intent(out) :: status
        !> use a stale reference (run/reference_fingerprint), replace a file
        !> at the table's path that is not flexmbs's own
        logical, intent(in), optional :: force
        !> '', or with force what is stale about the reference (the table's note)
        character(len=:), allocatable, intent(out), optional :: stale
        type(scene_input_t) :: base
        type(sweep_point_t), allocatable :: points(:)
        type(stats_row_t), allocatable :: rows(:)
        real(wp), allocatable :: t_ref(:), y_ref(:, :)
        character(len=:), allocatable :: note, refused
        integer :: k

        call prepare_sweep(study, base, t_ref, y_ref, points, note, status, force, &
                           table=.true.)
        if (present(stale)) stale = note
        if (.not. status%ok()) return
        allocate (runs(size(points)))
        do k = 1, size(points)
            runs(k) = point_run(base, points(k), t_ref, y_ref, quiet, refused)
            if (len(refused) > 0) then
                ! bad input, as a stale reference: no rows, no table
                deallocate (runs)
                call status%set(status_bad_input, refusal_text(study, k, refused))
                return
            end if
            if (signal_pending()) then
                ! the runs so far, the interrupted one last; no table
                runs = runs(1:k)
                call status%set(status_signal, study%path // ': stopped by ' // &
                    signal_name(caught_signal()) // ' after ' // int_text(k) // ' of ' // &
                    int_text(size(points)) // ' runs; no table written', caught_signal())
                return
            end if
        end do
        if (study%cpu_reference <= size(runs)) then
            if (runs(study%cpu_reference)%ok) runs%row%cpu_unit = &
                runs(study%cpu_reference)%row%stats%cpu
        end if
        rows = runs%row
        if (len(study%table) > 0) call write_table(study%table, rows, status, &
                                                   trim(study%layout), study%reasons, note)
    end subroutine run_sweep

    !> What every sweep starts from: the study's scene with the sweep's step
    !> limit (not the reference's), the reference, checked to be the one
    !> `flexmbs reference` would make of the study now (`stale` says why
    !> not, with `force`), at the scene's output times, and the grid's points.
    !> With `table`, the path of the study's table (if it names one) is
    !> checked too, as before a sweep's first run.
    subroutine prepare_sweep(study, base, t_ref, y_ref, points, stale, status, force, table)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(out) :: base
        real(wp), allocatable, intent(out) :: t_ref(:), y_ref(:, :)
        type(sweep_point_t), allocatable, intent(out) :: points(:)
        character(len=:), allocatable, intent(out) :: stale
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: force, table
        type(reference_print_t) :: now
        stale = ''
        call read_study_scene(study, base, status)
        if (status%ok()) call reference_print(study, base, now, status)
        if (status%ok()) call check_reference_print(study, now, given(force), stale, status)
        if (status%ok()) call read_reference(study%reference_file, t_ref, y_ref, status)
        if (status%ok()) call check_reference_times(study, base, t_ref, status)
        if (.not. status%ok()) return
        if (study%max_steps > 0) base%max_steps = study%max_steps
        call sweep_points(study, base, points)
        if (given(table) .and. len(study%table) > 0) call check_study_output(study, base, &
            'table', study%table, output_table, given(force), status)
    end subroutine prepare_sweep

    !> What a sweep whose points run elsewhere checks first, as a serial
    !> sweep does before its first run (the scene, the reference, the
    !> table's path), and the results folder, created when missing:
    !> `npoints` points, their records to go into `folder`; `stale` as
    !> run_sweep's.
    subroutine prepare_points(study, npoints, folder, status, force, stale)
        type(study_input_t), intent(in) :: study
        integer, intent(out) :: npoints
        character(len=:), allocatable, intent(out) :: folder
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: force
        character(len=:), allocatable, intent(out), optional :: stale
        type(scene_input_t) :: base
        type(sweep_point_t), allocatable :: points(:)
        real(wp), allocatable :: t_ref(:), y_ref(:, :)
        character(len=:), allocatable :: note
        npoints = 0
        call prepare_sweep(study, base, t_ref, y_ref, points, note, status, force, &
                           table=.true.)
        if (present(stale)) stale = note
        if (.not. status%ok()) return
        npoints = size(points)
        call make_results_folder(study, folder, status)
    end subroutine prepare_points

    !> Point k of the study's grid alone (`sweep --point K`): its record
    !> into the results folder (`record`, its path), written whole or not
    !> at all; none when a signal stopped the run (status_signal), nor when
    !> the reference is stale (bad input; `force` uses it all the same).
    subroutine run_sweep_point(study, k, run, record, status, force)
        type(study_input_t), intent(in) :: study
        integer, intent(in) :: k
        type(sweep_run_t), intent(out) :: run
        character(len=:), allocatable, intent(out) :: record
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: force
        type(scene_input_t) :: base
        type(sweep_point_t), allocatable :: points(:)
        type(fingerprint_t) :: print
        real(wp), allocatable :: t_ref(:), y_ref(:, :)
        character(len=:), allocatable :: folder, stale, refused, result_file
        call prepare_sweep(study, base, t_ref, y_ref, points, stale, status, force)
        if (.not. status%ok()) return
        if (k < 1 .or. k > size(points)) then
            call status%set(status_bad_input, study%path // ': --point ' // int_text(k) // &
                ': the grid has points 1 .. ' // int_text(size(points)))
            return
        end if
        ! the fingerprint of the files as they are before the run
        call study_fingerprint(study, base, print, status)
        if (status%ok()) call make_results_folder(study, folder, status)
        if (.not. status%ok()) return
        record = record_path(folder, k)
        ! the run keeps its checkpoints there: stopped, it resumes next time
        result_file = point_result_path(folder, k)
        run = point_run(base, points(k), t_ref, y_ref, .true., refused, result_file)
        if (len(refused) > 0) then
            call status%set(status_bad_input, refusal_text(study, k, refused) // &
                '; no record written')
            return
        end if
        if (signal_pending()) then
            call status%set(status_signal, study%path // ': point ' // int_text(k) // &
                ': stopped by ' // signal_name(caught_signal()) // '; no record written', &
                caught_signal())
            return
        end if
        call write_record(record, k, points(k), print, run, status)
        if (status%ok()) call remove_result(result_file)
    end subroutine run_sweep_point

    !> A point's result file and the XDMF file beside it, once its record
    !> holds what the sweep needs.
    subroutine remove_result(path)
        character(len=*), intent(in) :: path
        if (delete_file(path)) continue
        if (delete_file(xdmf_beside(path))) continue
    end subroutine remove_result

    !> Why a sweep stops at grid point k whose run cannot be measured
    !> against the reference (`why`, point_run's), and how to go on.
    function refusal_text(study, k, why) result(text)
        type(study_input_t), intent(in) :: study
        integer, intent(in) :: k
        character(len=*), intent(in) :: why
        character(len=:), allocatable :: text
        text = study%path // ': grid point ' // int_text(k) // ': ' // why // ' (' // &
            study%reference_file // '): ERR cannot be measured' // new_line('a') // &
            'remake it: ' // remake_command(study)
    end function refusal_text

    !> One point of the grid against the reference; `refused` says why a
    !> run's outputs cannot be compared with the reference's, '' when they
    !> can (a failed run is a row that says why).
    function point_run(base, point, t_ref, y_ref, quiet, refused, result_file) result(run)
        type(scene_input_t), intent(in) :: base
        type(sweep_point_t), intent(in) :: point
        real(wp), intent(in) :: t_ref(:), y_ref(:, :)
        logical, intent(in) :: quiet
        character(len=:), allocatable, intent(out) :: refused
        !> the run's HDF5 file with its checkpoints (`sweep --point`): a run
        !> stopped before resumes from it; none without
        character(len=*), intent(in), optional :: result_file
        type(sweep_run_t) :: run
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(record_sink_t) :: rec
        type(status_t) :: run_status
        character(len=:), allocatable :: label, stab_label, solver, source
        real(wp) :: err, tol
        solver = trim(point%solver)
        source = trim(point%source)
        tol = point%tol
        label = solver
        if (solver_pmax_grid(solver)) label = label // ' p_max=' // int_text(point%pmax)
        if (len(source) > 0 .and. source /= 'analytic') label = label // ' (' // source // ')'
        stab_label = trim(point%stab)
        if (solver_projects(solver) .and. problem_stabilisations(base%problem)) &
            stab_label = 'projection'
        call configure(base, solver, tol, trim(point%stab), point%pmax, source, scene)
        if (present(result_file)) then
            scene%output_file = result_file
            call resume_or_run(scene, quiet, result, run_status, rec)
        else
            call run_scene(scene, quiet, result, run_status, rec)
        end if
        run%ok = run_status%ok()
        err = -1.0_wp
        refused = ''
        if (run%ok) then
            refused = outputs_refused(rec, result%q_last, t_ref, y_ref)
            if (len(refused) == 0) err = series_error(rec%y(result%q_first:result%q_last, &
                1:rec%records), y_ref(result%q_first:result%q_last, :), tol)
        end if
        run%row = new_stats_row(label, tol, stab_label, result%stats)
        run%row%err = err
        run%reason = ''
        if (.not. run%ok) run%reason = run_status%text()
        if (run%ok) then
            run%summary = label // ' ' // stab_label // ' TOL ' // real_text(tol) // ': ERR ' &
                // real_text(err) // ' = ' // real_text(err / tol) // ' TOL, ' // &
                result%stats%summary()
            if (result%has_drift) run%summary = run%summary // ' drift |g| ' // &
                real_text(result%drift_end(1)) // ' |Gv+gI| ' // real_text(result%drift_end(2))
            if (result%resumed) run%summary = run%summary // '; resumed at t = ' // &
                real_text(result%resumed_from) // ' from ' // scene%output_file
        else
            run%summary = label // ' ' // stab_label // ' TOL ' // real_text(tol) // &
                ': failed at t = ' // real_text(result%stats%t_reached) // ': ' // &
                run_status%text() // '; ' // result%stats%summary()
        end if
    end function point_run

    !> A grid point's run into its result file: resumed from the file's
    !> checkpoint when it has one of this run, else from the start (a file
    !> of another run, without a checkpoint, or holding a finished run
    !> whose record was never written is replaced).
    subroutine resume_or_run(scene, quiet, result, status, rec)
        type(scene_input_t), intent(in) :: scene
        logical, intent(in) :: quiet
        type(run_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        type(record_sink_t), intent(inout) :: rec
        logical :: exists
        inquire (file=scene%output_file, exist=exists)
        if (exists) then
            call run_scene(scene, quiet, result, status, rec, resume=scene%output_file)
            if (result%resumed) return
            rec = record_sink_t()
        end if
        call run_scene(scene, quiet, result, status, rec, force=.true.)
    end subroutine resume_or_run

    !> Why a run's outputs (`rec`, positions up to q_last) cannot be
    !> compared with the reference's at its times: '' when they can.
    function outputs_refused(rec, q_last, t_ref, y_ref) result(why)
        type(record_sink_t), intent(in) :: rec
        integer, intent(in) :: q_last
        real(wp), intent(in) :: t_ref(:), y_ref(:, :)
        character(len=:), allocatable :: why
        why = ''
        if (rec%records /= size(t_ref)) then
            why = 'the run has ' // int_text(rec%records) // ' output records, the reference ' &
                // int_text(size(t_ref))
        else if (size(y_ref, 1) < q_last) then
            why = 'the run has ' // int_text(q_last) // ' positions, the reference ' // &
                int_text(size(y_ref, 1)) // ' components'
        else if (.not. same_times(rec%t(1:rec%records), t_ref)) then
            why = 'the output times of the run are not the reference''s'
        end if
    end function outputs_refused

    !> An optional flag's value, false when absent.
    pure logical function given(flag)
        logical, intent(in), optional :: flag
        given = .false.
        if (present(flag)) given = flag
    end function given

    !> ERR of eq. (13) over all components and output times, rtol = atol = tol.
    pure real(wp) function series_error(y, y_ref, tol) result(err)
        real(wp), intent(in) :: y(:, :), y_ref(:, :), tol
        err = paper_error(reshape(y, [size(y)]), reshape(y_ref, [size(y_ref)]), tol, tol)
    end function series_error
end module flexmbs_run_study
