!> Studies (`flexmbs reference`, `flexmbs sweep`): the study file's checks,
!> a reference with its cross-check, and a sweep against it whose ERR meets
!> the tolerances and whose results repeat to the bit.
module test_study
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_io_namelist, only: study_input_t, parse_study, parse_scene, scene_input_t, &
        read_study
    use flexmbs_run_study, only: make_reference, run_sweep, read_reference, sweep_run_t
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
                 new_test('five_body_quick', test_quick)]
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
        call parse_study('&study scene = ''../../inputs/four_bar.nml'', ' // &
            'reference_tolerance = 1e-7, check_solver = ''ddassl'', ' // &
            'solvers = ''radau5'', ''ddassl'', stabilisations = ''ggl'', ' // &
            'tolerances = 1e-4, pmax = 2, 5 /', dir // 'fb.nml', study, status)
        call check(error, status%ok(), 'study: ' // status%text())
        if (allocated(error)) return
        call make_reference(study, 'test', .true., log, status)
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
    end subroutine test_sweep
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
        call make_reference(study, 'test', .true., log, status)
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
end module test_study
