!> Studies (`flexmbs reference`, `flexmbs sweep`): the study file's checks,
!> a reference with its cross-check, and a sweep against it whose ERR meets
!> the tolerances and whose results repeat to the bit; its points run
!> alone into records that merge into the same table; records read back,
!> stale, damaged, missing and failed ones in a merge; SHA-256 against
!> FIPS 180 test vectors; how a job array's tasks share the points; the
!> Slurm options and scripts; a reference's fingerprint, and every kind of
!> sweep refusing a stale reference.
module test_study
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_core_files, only: delete_file, read_text_file, make_folder
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_io_namelist, only: study_input_t, parse_study, parse_scene, scene_input_t, &
        read_study
    use flexmbs_run_study, only: make_reference, run_sweep, read_reference, sweep_run_t, &
        run_sweep_point, read_study_scene, prepare_points
    use flexmbs_io_scene_settings, only: scene_settings
    use flexmbs_run_reference_fingerprint, only: reference_print_t, reference_print
    use flexmbs_run_study_grid, only: sweep_point_t, sweep_points, array_spec, &
        array_task_count, task_first_points, task_last_point, point_list_text
    use flexmbs_run_study_results, only: results_folder, make_results_folder, record_path
    use flexmbs_run_study_record, only: fingerprint_t, study_fingerprint, write_record, &
        read_record, record_missing, record_current, record_stale, record_damaged
    use flexmbs_run_study_merge, only: merged_t, merge_records, merge_report
    use flexmbs_run_study_slurm, only: slurm_options_t, check_slurm_options, &
        slurm_time_valid, write_slurm_scripts, shell_word
    use flexmbs_io_table, only: table_text, table2_text, table_markdown, stats_row_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_study

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_study() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('bad_studies', test_bad), &
                 new_test('reference_and_sweep', test_sweep), &
                 new_test('five_body_quick', test_quick), &
                 new_test('sha256_vectors', test_sha256), &
                 new_test('record_round_trip', test_record), &
                 new_test('merge_missing_failed_stale', test_merge), &
                 new_test('array_chunks', test_chunks), &
                 new_test('scene_settings', test_settings), &
                 new_test('reference_fingerprint', test_fingerprint), &
                 new_test('shared_references', test_shared_references), &
                 new_test('slurm_options_and_scripts', test_slurm)]
    end function collect_study

    subroutine expect(error, text, message)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: text, message
        type(study_input_t) :: study
        type(status_t) :: status
        if (allocated(error)) return
        call parse_study(text, 'dir/s.nml', study, status)
        call check(error, index(status%text(), message) > 0, 'expected "' // message // &
                   '", got "' // status%text() // '"')
    end subroutine expect

    subroutine test_bad(error)
        type(error_t), allocatable, intent(out) :: error
        type(study_input_t) :: study
        type(scene_input_t) :: scene
        type(status_t) :: status
        call expect(error, '&study solvers = ''radau5'' /', 'scene: required')
        call expect(error, '&study scene = ''a.nml'', solvers = ''rk4'' /', &
                    "dir/s.nml: &study: solvers = 'rk4': must be one of")
        call expect(error, '&study scene = ''a.nml'', table = ''t.txt'' /', &
                    'the name must end in .md, .csv or .tex')
        call expect(error, '&study scene = ''a.nml'', tolerances = 1e-4, 2.0 /', &
                    'tolerances = 1e-4, 2.0: must be less than 1')
        call expect(error, '&study scene = ''a.nml'', pmax = 2, 7 /', 'pmax = 2, 7: must lie in 1..5')
        call expect(error, '&study scene = ''a.nml'', stabilisations = ''baumgarte'' /', &
                    "stabilisations = 'baumgarte': must be 'none', 'ggl' or 'projection'")
        call expect(error, '&simulation t_end = 1 /' // nl // '&study scene = ''a.nml'' /', &
                    '&simulation: a study file holds only &study')
        call expect(error, '&study scene = ''a.nml'', tolerance = 1e-4 /', 'tolerance')
        call expect(error, '&study scene = ''a.nml'', layout = ''table4'' /', &
                    "layout = 'table4': must be 'table3' or 'table2'")
        ! defaults and paths relative to the study's folder
        call parse_study('&study scene = ''a.nml'', table = ''t.csv'' /', 'dir/s.nml', study, &
                         status)
        call check(error, status%ok() .and. study%scene == 'dir/a.nml' .and. &
                   study%reference_file == 'dir/s_reference.h5' .and. &
                   study%table == 'dir/t.csv' .and. size(study%solvers) == 4 .and. &
                   all(study%tolerances == [1.0e-6_wp]), 'defaults: ' // status%text())
        ! a scene refuses &study
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                         '&study scene = ''a.nml'' /', 'sc.nml', scene, status)
        call check(error, index(status%text(), '&study: belongs in a study file') > 0, &
                   'scene with &study: ' // status%text())
    end subroutine test_bad

    !> The four-bar: a RADAU5 reference at 1e-7, cross-checked by DDASSL (the
    !> BDF codes stop at t0 below 1e-7 on this scene: see the notes); a sweep
    !> of RADAU5 and DDASSL (p_max 2 and 5) with GGL at 1e-4: every ERR ≤ 10
    !> TOL, CPU normalised to the first row, and a second sweep repeats every
    !> ERR and counter exactly.
    subroutine test_sweep(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: dir = 'build/test-study/'
        type(study_input_t) :: study
        type(status_t) :: status
        type(sweep_run_t), allocatable :: runs(:), again(:)
        type(stats_row_t), allocatable :: rows(:)
        character(len=:), allocatable :: log, text
        real(wp), allocatable :: t(:), y(:, :)
        integer :: k
        call execute_command_line('mkdir -p ' // dir)
        ! on disk too: a point's record carries the study file's hash
        call write_text(dir // 'fb.nml', '&study scene = ''../../inputs/four_bar.nml'', ' // &
            'reference_tolerance = 1e-7, check_solver = ''ddassl'', ' // &
            'solvers = ''radau5'', ''ddassl'', stabilisations = ''ggl'', ' // &
            'tolerances = 1e-4, pmax = 2, 5 /' // nl)
        call read_study(dir // 'fb.nml', study, status)
        call check(error, status%ok(), 'study: ' // status%text())
        if (allocated(error)) return
        call make_reference(study, .true., log, status)
        call check(error, status%ok(), 'reference: ' // status%text())
        if (allocated(error)) return
        print '(a)', '    ' // log(1:index(log, nl) - 1)
        call read_reference(study%reference_file, t, y, status)
        call check(error, status%ok() .and. size(t) == 101 .and. abs(t(101) - 1.0_wp) < &
                   1.0e-14_wp, 'reference file: ' // status%text())
        call run_sweep(study, .true., runs, status)
        call check(error, status%ok() .and. size(runs) == 3, 'sweep: ' // status%text())
        if (allocated(error)) return
        do k = 1, size(runs)
            print '(a)', '    ' // runs(k)%summary
            call check(error, runs(k)%ok .and. runs(k)%row%err > 0.0_wp .and. &
                       runs(k)%row%err <= 10.0_wp * 1.0e-4_wp, 'ERR: ' // runs(k)%summary)
        end do
        rows = runs%row
        text = table_text(rows, table_markdown)
        call check(error, index(text, '| 1.00 |') > 0, 'CPU not normalised to the first row')
        ! the Table 2 layout: a column per run, rows ERR … CPU
        text = table2_text(rows, table_markdown)
        call check(error, index(text, '| ddassl p_max=2 | ddassl p_max=5 |') > 0 .and. &
                   index(text, '| rejected/NST |') > 0 .and. index(text, '| CPU ') > 0, &
                   'Table 2 layout: ' // text)
        call run_sweep(study, .true., again, status)
        do k = 1, size(runs)
            call check(error, again(k)%row%err == runs(k)%row%err .and. &
                       again(k)%row%stats%nst == runs(k)%row%stats%nst .and. &
                       again(k)%row%stats%nfe == runs(k)%row%stats%nfe, &
                       'the sweep does not repeat: ' // again(k)%summary)
        end do
        call points_merge_as_serial(error, study, runs)
    end subroutine test_sweep

    !> Every point of the study run alone (`sweep --point K`) writes its
    !> record; merged, they make the serial sweep's rows, CPU apart.
    subroutine points_merge_as_serial(error, study, runs)
        type(error_t), allocatable, intent(inout) :: error
        type(study_input_t), intent(in) :: study
        type(sweep_run_t), intent(in) :: runs(:)
        type(sweep_run_t) :: one
        type(merged_t) :: merged
        type(status_t) :: status
        character(len=:), allocatable :: record
        integer :: k
        if (allocated(error)) return
        do k = 1, size(runs)
            call run_sweep_point(study, k, one, record, status)
            call check(error, status%ok() .and. record == record_path(results_folder(study), k), &
                       'point ' // int_text(k) // ': ' // status%text())
        end do
        call run_sweep_point(study, size(runs) + 1, one, record, status)
        call check(error, index(status%text(), '--point 4: the grid has points 1 .. 3') > 0, &
                   'a point beyond the grid: ' // status%text())
        call merge_records(study, merged, status)
        call check(error, status%ok() .and. merged%complete() .and. size(merged%runs) == &
                   size(runs), 'merge: ' // status%text())
        if (allocated(error)) return
        do k = 1, size(runs)
            call check(error, same_row(merged%runs(k)%row, runs(k)%row) .and. &
                       merged%runs(k)%summary(1:index(merged%runs(k)%summary, ' CPU=')) == &
                       runs(k)%summary(1:index(runs(k)%summary, ' CPU=')), &
                       'merged row ' // int_text(k) // ' differs: ' // merged%runs(k)%summary)
        end do
    end subroutine points_merge_as_serial

    !> Two rows alike in every column but CPU and wall.
    logical function same_row(a, b)
        type(stats_row_t), intent(in) :: a, b
        same_row = a%solver == b%solver .and. a%stab == b%stab .and. a%tol == b%tol .and. &
            a%err == b%err .and. a%stats%nst == b%stats%nst .and. a%stats%nac == b%stats%nac &
            .and. a%stats%nrj == b%stats%nrj .and. a%stats%nfe == b%stats%nfe .and. &
            a%stats%nfe_jac == b%stats%nfe_jac .and. a%stats%nje == b%stats%nje .and. &
            a%stats%ndec == b%stats%ndec .and. a%stats%nsol == b%stats%nsol .and. &
            a%stats%nprj == b%stats%nprj .and. a%stats%t_reached == b%stats%t_reached .and. &
            a%stats%h_last == b%stats%h_last .and. &
            all(a%stats%rejections%counts_by_cause() == b%stats%rejections%counts_by_cause()) &
            .and. a%stats%rejections%refusal_reason() == b%stats%rejections%refusal_reason()
    end function same_row
    !> The quick variant of the paper's studies (inputs/paper/five_body_quick.nml:
    !> the five-body mechanism over 0.05 s): the reference's cross-check
    !> agrees, and every run finishes with ERR ≤ 10 TOL.
    subroutine test_quick(error)
        type(error_t), allocatable, intent(out) :: error
        type(study_input_t) :: study
        type(status_t) :: status
        type(sweep_run_t), allocatable :: runs(:)
        character(len=:), allocatable :: log
        integer :: k
        call read_study('inputs/paper/five_body_quick.nml', study, status)
        call check(error, status%ok(), 'study: ' // status%text())
        if (allocated(error)) return
        call make_reference(study, .true., log, status)
        call check(error, status%ok(), 'reference: ' // status%text())
        if (allocated(error)) return
        call run_sweep(study, .true., runs, status)
        call check(error, status%ok() .and. size(runs) == 6, 'sweep: ' // status%text())
        if (allocated(error)) return
        do k = 1, size(runs)
            print '(a)', '    ' // runs(k)%summary(1:index(runs(k)%summary, ', NST') - 1)
            call check(error, runs(k)%ok .and. runs(k)%row%err <= 10.0_wp * runs(k)%row%tol, &
                       'ERR: ' // runs(k)%summary)
        end do
    end subroutine test_quick

    !> SHA-256 of the FIPS 180 examples: one block, two blocks of padding
    !> (56 bytes), a two-block message, and a million 'a' (whole blocks).
    subroutine test_sha256(error)
        type(error_t), allocatable, intent(out) :: error
        call vector('', 'e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855')
        call vector('abc', 'ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad')
        call vector('abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq', &
                    '248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1')
        call vector('abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmno' // &
                    'ijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu', &
                    'cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1')
        call vector(repeat('a', 1000000), &
                    'cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0')
    contains
        subroutine vector(text, digest)
            character(len=*), intent(in) :: text, digest
            call check(error, sha256_hex(text) == digest, 'SHA-256 of ' // &
                       int_text(len(text)) // ' bytes: ' // sha256_hex(text) // ', not ' // digest)
        end subroutine vector
    end subroutine test_sha256

    !> A record reads back to the bit (a failed run with a reason of two
    !> lines); another study, scene or mesh text or another grid point
    !> make it stale, a wrong point number or a lost number damaged.
    subroutine test_record(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: dir = 'build/test-study/records'
        type(sweep_point_t) :: point, other
        type(fingerprint_t) :: print, changed
        type(sweep_run_t) :: run, back
        type(status_t) :: status
        character(len=:), allocatable :: note, path, text
        integer :: state
        call execute_command_line('mkdir -p ' // dir)
        path = record_path(dir, 2)
        point = sweep_point_t('ddassl', 'ggl', 1.0e-4_wp / 3.0_wp, 2, 'ad')
        print = fingerprint_t(repeat('a', 64), repeat('b', 64), '-')
        run%ok = .false.
        run%reason = 'step size too small' // nl // 'at t = 0.5'
        run%summary = 'ddassl p_max=2 (ad) ggl: failed'
        run%row%solver = 'ddassl p_max=2 (ad)'
        run%row%stab = 'ggl'
        run%row%tol = point%tol
        run%row%err = -1.0_wp
        run%row%stats%nst = 123; run%row%stats%nac = 100; run%row%stats%nrj = 23
        run%row%stats%nfe = 456; run%row%stats%nfe_jac = 7; run%row%stats%nje = 8
        run%row%stats%ndec = 9; run%row%stats%nsol = 10; run%row%stats%nprj = 11
        run%row%stats%cpu = 2.0_wp / 3.0_wp; run%row%stats%wall = 1.0_wp / 7.0_wp
        run%row%stats%t_reached = 0.1_wp; run%row%stats%h_last = 1.0e-3_wp / 9.0_wp
        ! NRJ = 23 by cause, with a refusal whose reason holds ' = '
        call run%row%stats%rejections%restore([12, 1, 2, 0, 8, 0, 0], &
                                              'flexible body: element 17: det F = -1.0E-02')
        call write_record(path, 2, point, print, run, status)
        call check(error, status%ok(), 'write: ' // status%text())
        call read_record(path, 2, point, print, back, state, note)
        call check(error, state == record_current .and. .not. back%ok .and. &
                   back%reason == 'step size too small / at t = 0.5' .and. &
                   back%summary == run%summary .and. same_row(back%row, run%row) .and. &
                   back%row%stats%cpu == run%row%stats%cpu .and. &
                   back%row%stats%wall == run%row%stats%wall, 'read back: ' // note)
        changed = print
        changed%study(1:1) = 'c'
        call read_record(path, 2, point, changed, back, state, note)
        call check(error, state == record_stale .and. note == 'computed from another text &
                   &of the study file', 'another study: ' // note)
        changed = print
        changed%scene(64:64) = 'c'
        changed%mesh = repeat('d', 64)
        call read_record(path, 2, point, changed, back, state, note)
        call check(error, state == record_stale .and. index(note, 'the scene file, the mesh &
                   &file') > 0, 'another scene and mesh: ' // note)
        other = point
        other%tol = 1.0e-4_wp
        call read_record(path, 2, other, print, back, state, note)
        call check(error, state == record_stale .and. index(note, 'another grid point') > 0, &
                   'another point: ' // note)
        call read_record(path, 3, point, print, back, state, note)
        call check(error, state == record_damaged, 'read as point 3: ' // note)
        call read_text_file(path, text, status)
        call write_text(path, text(1:index(text, 'nje = ') - 1) // &
                        text(index(text, 'ndec = '):))
        call read_record(path, 2, point, print, back, state, note)
        call check(error, state == record_damaged .and. index(note, 'unreadable') > 0, &
                   'a number lost: ' // note)
        call check(error, delete_file(path), 'cannot remove ' // path)
        call read_record(path, 2, point, print, back, state, note)
        call check(error, state == record_missing, 'no file')
    end subroutine test_record

    !> A merge of a four-point study (no run: records written here): point
    !> 1 ok, 2 failed, 3 missing, 4 stale. Then every point is there: the
    !> table is written, CPU normalised to cpu_reference.
    subroutine test_merge(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: dir = 'build/test-study/merge/'
        type(study_input_t) :: study
        type(scene_input_t) :: base
        type(sweep_point_t), allocatable :: points(:)
        type(fingerprint_t) :: print, old
        type(sweep_run_t) :: runs(4)
        type(merged_t) :: merged
        type(slurm_options_t) :: options
        type(status_t) :: status
        character(len=:), allocatable :: folder, report, array, script, table
        logical :: exists
        integer :: k
        call execute_command_line('mkdir -p ' // dir)
        call write_text(dir // 'm.nml', '&study scene = ''../../../inputs/four_bar.nml'', ' // &
            'solvers = ''radau5'', ''ddassl'', stabilisations = ''ggl'', tolerances = 1e-3, ' // &
            '1e-4, pmax = 2, table = ''m.md'', reference_tolerance = 1e-5, ' // &
            'check_solver = ''none'' /' // nl)
        call read_study(dir // 'm.nml', study, status)
        ! a merge checks the reference first (run/reference_fingerprint)
        if (status%ok()) call make_reference(study, .true., report, status)
        if (status%ok()) call read_study_scene(study, base, status)
        if (status%ok()) call study_fingerprint(study, base, print, status)
        if (status%ok()) call make_results_folder(study, folder, status)
        call check(error, status%ok() .and. folder == dir // 'm_points', 'study: ' // &
                   status%text())
        if (allocated(error)) return
        call sweep_points(study, base, points)
        call check(error, size(points) == 4, 'grid of ' // int_text(size(points)))
        if (allocated(error)) return
        do k = 1, 4
            call check(error, delete_file(record_path(folder, k)), 'old record ' // int_text(k))
            runs(k)%ok = k /= 2
            runs(k)%reason = merge('                   ', 'step size too small', k /= 2)
            runs(k)%summary = 'run ' // int_text(k)
            runs(k)%row%solver = trim(points(k)%solver)
            runs(k)%row%stab = 'ggl'
            runs(k)%row%err = merge(-1.0_wp, 1.0e-5_wp * k, k == 2)
            runs(k)%row%stats%nst = 10 * k
            runs(k)%row%stats%cpu = 0.5_wp * k
        end do
        call check(error, delete_file(study%table) .and. delete_file(folder // &
                   '/array.sbatch'), 'old table or script')
        old = print
        old%study(1:1) = merge('0', '1', print%study(1:1) /= '0')
        call write_record(record_path(folder, 1), 1, points(1), print, runs(1), status)
        call write_record(record_path(folder, 2), 2, points(2), print, runs(2), status)
        call write_record(record_path(folder, 4), 4, points(4), old, runs(4), status)
        call merge_records(study, merged, status)
        call check(error, status%ok() .and. .not. merged%complete() .and. &
                   size(merged%missing) == 2 .and. size(merged%present) == 2 .and. &
                   size(merged%failed) == 1, 'merge: ' // status%text())
        if (allocated(error)) return
        call check(error, all(merged%missing == [3, 4]) .and. all(merged%present == [1, 2]) &
                   .and. merged%failed(1) == 2 .and. .not. merged%table_written .and. &
                   merged%runs(2)%row%stats%nst == 20 .and. merged%runs(1)%row%err == 1.0e-5_wp, &
                   'merged rows')
        inquire (file=study%table, exist=exists)
        call check(error, .not. exists, 'a table was written with points missing')
        report = merge_report(merged, study, 'flexmbs')
        call check(error, index(report, 'stale: point 4: computed from another text of the &
                   &study file') > 0 .and. index(report, 'failed: point 2: step size too &
                   &small') > 0 .and. index(report, 'missing: 2 of 4 points') > 0 .and. &
                   index(report, ' --point 3' // nl) > 0 .and. index(report, ' --point 4' // &
                   nl) > 0 .and. index(report, 'resubmit: flexmbs sweep /') > 0 .and. &
                   index(report, '(Slurm)') == 0, 'report: ' // report)
        ! with the Slurm scripts there, the sbatch commands for those points
        call write_slurm_scripts(study, '/opt/flexmbs', folder, 4, options, array, script, &
                                 status)
        report = merge_report(merged, study, 'flexmbs')
        call check(error, index(report, 'resubmit (Slurm): sbatch --array=3-4 /') > 0 .and. &
                   index(report, '/m_points/array.sbatch 1' // nl) > 0 .and. &
                   index(report, 'rerun failed (Slurm): sbatch --array=2 /') > 0, &
                   'report with Slurm: ' // report)
        call write_record(record_path(folder, 3), 3, points(3), print, runs(3), status)
        call write_record(record_path(folder, 4), 4, points(4), print, runs(4), status)
        call merge_records(study, merged, status)
        call check(error, status%ok() .and. merged%complete() .and. merged%table_written .and. &
                   size(merged%runs) == 4, 'complete merge: ' // status%text())
        if (allocated(error)) return
        call check(error, all(merged%runs%row%cpu_unit == 0.5_wp), 'CPU not normalised')
        call read_text_file(study%table, table, status)
        call check(error, status%ok() .and. index(table, '| ddassl | 1.0e-04 | ggl   | 4.0e-05 &
                   &|  40 |') > 0 .and. index(table, '| 4.00 |') > 0, &
                   'table: ' // table)
    end subroutine test_merge

    !> Every array of n points in tasks of k covers each point once, and
    !> its --array value lists exactly the tasks' numbers.
    subroutine test_chunks(error)
        type(error_t), allocatable, intent(out) :: error
        integer, allocatable :: first(:)
        integer :: n, k, t, hits(20)
        call check(error, array_spec(6, 4) == '1-6:4' .and. array_task_count(6, 4) == 2 .and. &
                   array_spec(6, 1) == '1-6' .and. array_spec(1, 3) == '1', 'array specs')
        call check(error, point_list_text([2, 3, 4, 7]) == '2-4,7' .and. &
                   point_list_text([5]) == '5' .and. point_list_text([1, 3, 5]) == '1,3,5', &
                   'point lists')
        do n = 1, 20
            do k = 1, 22
                first = task_first_points(n, k)
                call check(error, size(first) == array_task_count(n, k) .and. &
                           size(first) == (n + k - 1) / k, 'tasks of ' // int_text(n) // &
                           ' points by ' // int_text(k))
                if (allocated(error)) return
                call check(error, all(first == expanded(array_spec(n, k))), 'the array ' // &
                           array_spec(n, k) // ' is not the tasks')
                hits = 0
                do t = 1, size(first)
                    hits(first(t):task_last_point(first(t), k, n)) = &
                        hits(first(t):task_last_point(first(t), k, n)) + 1
                end do
                call check(error, all(hits(1:n) == 1) .and. all(hits(n + 1:) == 0), &
                           'coverage of ' // int_text(n) // ' points by ' // int_text(k))
            end do
        end do
    contains
        !> The task numbers of Slurm's 'a', 'a-b' or 'a-b:s'.
        function expanded(spec) result(ids)
            character(len=*), intent(in) :: spec
            integer, allocatable :: ids(:)
            integer :: a, b, step, dash, colon, i
            dash = index(spec, '-')
            colon = index(spec, ':')
            step = 1
            if (colon > 0) read (spec(colon + 1:), *) step
            if (colon == 0) colon = len(spec) + 1
            if (dash == 0) then
                read (spec, *) a
                b = a
            else
                read (spec(1:dash - 1), *) a
                read (spec(dash + 1:colon - 1), *) b
            end if
            ids = [(i, i=a, b, step)]
        end function expanded
    end subroutine test_chunks

    !> The Slurm options' checks, and the words of a command line.
    subroutine test_slurm(error)
        type(error_t), allocatable, intent(out) :: error
        type(slurm_options_t) :: options
        type(status_t) :: status
        character(len=12), parameter :: good(8) = [character(len=12) :: '', '30', '30:00', &
            '1:00:00', '2-0', '2-12:30', '2-12:30:15', 'UNLIMITED']
        character(len=12), parameter :: bad(9) = [character(len=12) :: '1:60', '1:2:3:4', &
            '2-24', 'abc', '-5', '1h', '2-', ':30', '1:00:60']
        integer :: i
        do i = 1, size(good)
            call check(error, slurm_time_valid(trim(good(i))), 'refused --time ' // good(i))
        end do
        do i = 1, size(bad)
            call check(error, .not. slurm_time_valid(trim(bad(i))), 'took --time ' // bad(i))
        end do
        options%chunk = 0
        call check_slurm_options(options, status)
        call check(error, index(status%text(), '--chunk 0: needs a whole number >= 1') > 0, &
                   'chunk 0: ' // status%text())
        options%chunk = 2
        options%mem = '4GB'
        call check_slurm_options(options, status)
        call check(error, index(status%text(), '--mem ''4GB''') > 0, 'mem: ' // status%text())
        options%mem = '4G'
        options%partition = 'gpu x'
        call check_slurm_options(options, status)
        call check(error, index(status%text(), '--partition ''gpu x''') > 0, 'partition: ' // &
                   status%text())
        options%partition = 'short,long'
        options%time = '0:30:00'
        call check_slurm_options(options, status)
        call check(error, status%ok(), 'good options: ' // status%text())
        call check(error, shell_word('/a/b_c-1.nml') == '/a/b_c-1.nml' .and. &
                   shell_word('a b') == '''a b''' .and. &
                   shell_word('it''s') == '''it''\''''s''', 'shell words')
    end subroutine test_slurm

    !> The scene's settings (io/scene_settings) read alike however written
    !> (comments, order, spelling of numbers, quotes, the case of a choice),
    !> with the defaults of what is left out, and differ in a changed value.
    subroutine test_settings(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=24), parameter :: omit(1) = [character(len=24) :: 'output/*']
        character(len=:), allocatable :: a, b, c
        a = scene_settings('&simulation problem = ''van_der_pol'', t_end = 1.0, vdp_eps = 1e-3 /' &
                           // nl // '&output n_output = 11 /', omit)
        b = scene_settings('! the same' // nl // '&simulation vdp_eps=0.001, t_end=1.,' // nl // &
                           '  problem = "VAN_DER_POL" /', omit)
        c = scene_settings('&simulation problem = ''van_der_pol'', t_end = 1.0, vdp_eps = 2e-3 /', &
                           omit)
        call check(error, a == b, 'the same scene, written otherwise: ' // nl // a // nl // b)
        call check(error, a /= c .and. index(c, '&simulation vdp_eps = 0.002' // nl) > 0 .and. &
                   index(a, '&simulation vdp_eps = 0.001' // nl) > 0, 'a changed value: ' // c)
        call check(error, index(a, '&simulation vdp_y1 = 2' // nl) > 0 .and. &
                   index(a, '&simulation t_end = 1' // nl) > 0 .and. index(a, '&output') == 0, &
                   'defaults, and &output left out: ' // a)
    end subroutine test_settings

    !> A reference of the four-bar over 0.1 s, then its scene changed (the
    !> motor twice as fast): a sweep, a point, a merge and the points of a
    !> parallel or Slurm sweep refuse it as bad input, naming the variable
    !> and the command that remakes it, and write nothing; with force the
    !> sweep runs and says the reference is stale. Another t_end is named too.
    subroutine test_fingerprint(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: dir = 'build/test-study/fingerprint/'
        character(len=*), parameter :: speed = '6.283185307179586'
        type(study_input_t) :: study
        type(status_t) :: status
        type(sweep_run_t), allocatable :: runs(:)
        type(sweep_run_t) :: one
        type(merged_t) :: merged
        character(len=:), allocatable :: scene, log, stale, record, folder, why
        logical :: exists
        integer :: at, npoints
        call execute_command_line('mkdir -p ' // dir)
        call read_text_file('inputs/four_bar.nml', scene, status)
        call check(error, status%ok() .and. index(scene, speed) > 0, 'four_bar.nml: ' // &
                   status%text())
        if (allocated(error)) return
        call write_text(dir // 'scene.nml', scene)
        call write_text(dir // 'f.nml', '&study scene = ''scene.nml'', t_end = 0.1, ' // &
            'reference_tolerance = 1e-5, check_solver = ''none'', solvers = ''radau5'', ' // &
            'stabilisations = ''ggl'', tolerances = 1e-3 /' // nl)
        call read_study(dir // 'f.nml', study, status)
        if (status%ok()) call make_reference(study, .true., log, status)
        if (status%ok()) call run_sweep(study, .true., runs, status, stale=stale)
        call check(error, status%ok() .and. stale == '', 'unchanged: ' // status%text())
        if (allocated(error)) return
        at = index(scene, speed)
        call write_text(dir // 'scene.nml', scene(1:at - 1) // '12.566370614359172' // &
                        scene(at + len(speed):))
        why = 'what differs: the scene text (after defaults): &driver(1) coefficients = 0.3, ' &
            // speed // ', 0, 0 in the reference, 0.3, 12.566370614359172, 0, 0 now' // nl // &
            'remake it: flexmbs reference ' // dir // 'f.nml (or use it as it is: --force)'
        call run_sweep(study, .true., runs, status)
        call refused('sweep', .not. allocated(runs))
        folder = dir // 'f_points'
        exists = delete_file(record_path(folder, 1))
        call run_sweep_point(study, 1, one, record, status)
        inquire (file=record_path(folder, 1), exist=exists)
        call refused('--point', .not. exists)
        call merge_records(study, merged, status)
        call refused('--merge', .true.)
        call prepare_points(study, npoints, record, status)
        call refused('-j and --slurm', npoints == 0)
        call run_sweep(study, .true., runs, status, force=.true., stale=stale)
        call check(error, status%ok() .and. stale == 'note: the reference ' // dir // &
                   'f_reference.h5 is stale (it differs in the scene text), used as it is &
                   &(--force)', 'forced: ' // status%text() // ' / ' // stale)
        call write_text(dir // 'scene.nml', scene)
        call write_text(dir // 'f.nml', '&study scene = ''scene.nml'', t_end = 0.05, ' // &
            'reference_tolerance = 1e-5, check_solver = ''none'', solvers = ''radau5'', ' // &
            'stabilisations = ''ggl'', tolerances = 1e-3 /' // nl)
        call read_study(dir // 'f.nml', study, status)
        call run_sweep(study, .true., runs, status)
        call check(error, status%code == status_bad_input .and. index(status%text(), &
                   'what differs: t_end (0.1 in the reference, 0.05 now); the output times &
                   &(101 from 0 to 0.1 s in the reference, 101 from 0 to 0.05 s now)') > 0, &
                   'another t_end: ' // status%text())

    contains

        !> The last status refused the stale reference (and `nothing`: wrote nothing).
        subroutine refused(what, nothing)
            character(len=*), intent(in) :: what
            logical, intent(in) :: nothing
            call check(error, status%code == status_bad_input .and. &
                       index(status%text(), why) > 0 .and. nothing, what // ': ' // &
                       status%text())
        end subroutine refused
    end subroutine test_fingerprint

    !> The paper's studies that share a reference file (make paper makes it
    !> by the first, sweeps all) have the same fingerprint: their sweeps
    !> take it.
    subroutine test_shared_references(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: groups(2, 3) = reshape([character(len=24) :: &
            'five_body_table3', 'five_body_fine_table3', 'five_body_table2', &
            'five_body_fine_table2', 'five_body_figure6', 'five_body_fine_figure6'], [2, 3])
        type(study_input_t) :: study
        type(scene_input_t) :: base
        type(reference_print_t) :: first, print
        type(status_t) :: status
        integer :: g, k
        do g = 1, size(groups, 1)
            do k = 1, size(groups, 2)
                call read_study('inputs/paper/' // trim(groups(g, k)) // '.nml', study, status)
                if (status%ok()) call read_study_scene(study, base, status)
                if (status%ok()) call reference_print(study, base, print, status)
                call check(error, status%ok(), trim(groups(g, k)) // ': ' // status%text())
                if (allocated(error)) return
                if (k == 1) first = print
                call check(error, print%digest == first%digest, trim(groups(g, k)) // &
                           ' has another fingerprint than ' // trim(groups(g, 1)) // ': ' // &
                           print%parts // ' / ' // first%parts)
            end do
        end do
    end subroutine test_shared_references

    !> A file of `text` (replaced).
    subroutine write_text(path, text)
        character(len=*), intent(in) :: path, text
        integer :: unit
        open (newunit=unit, file=path, status='replace', access='stream', form='unformatted')
        write (unit) text
        close (unit)
    end subroutine write_text
end module test_study
