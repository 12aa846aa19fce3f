!> Input and output: namelist validation, tables, the HDF5 sink, the
!> progress display, and one scene run end to end.
module test_io
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene, scene_dae_options
    use flexmbs_io_table, only: stats_row_t, new_stats_row, table_text, table_format, &
        write_table, table_markdown, table_csv, table_latex, layout_text
    use flexmbs_dae_rejections, only: cause_count
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_hdf5_text, only: read_text_attribute => read_string_attribute
    use flexmbs_io_output_files, only: named_path_t, named_path, check_output_paths, &
        output_hdf5, output_table
    use flexmbs_core_version, only: version
    use flexmbs_io_progress, only: progress_t, new_progress
    use flexmbs_dae_radau5, only: radau5_t, radau5_controller_classical
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_io_scene_input, only: given_setting
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_run_solver_factory, only: build_solver, new_solver
    use flexmbs_run_catalogue, only: solvers
    use flexmbs_io_scene_schema, only: schema
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_io_xdmf_file, only: xdmf_beside
    use flexmbs_run_problem_factory, only: build_problem, block_spec_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_io, scratch, read_series

    character, parameter :: nl = new_line('a')

    !> A constant dense output, enough to drive `step`.
    type, extends(dense_output_t) :: still_t
        real(wp) :: value = 0.0_wp
    contains
        procedure :: evaluate => still_evaluate
    end type still_t

contains

    function collect_io() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('valid_file_parses', test_valid_file), &
                 new_test('defaults_and_derived_output', test_defaults), &
                 new_test('options_from_scene', test_options), &
                 new_test('unknown_variable', test_unknown_variable), &
                 new_test('wrong_type', test_wrong_type), &
                 new_test('negative_tolerance', test_negative_tolerance), &
                 new_test('own_settings_reach_one_solver', test_own_settings), &
                 new_test('missing_file', test_missing_file), &
                 new_test('unknown_group', test_unknown_group), &
                 new_test('other_bad_text', test_other_bad_text), &
                 new_test('table_formats', test_table_formats), &
                 new_test('table_rejection_causes', test_table_reasons), &
                 new_test('hdf5_round_trip', test_hdf5_round_trip), &
                 new_test('hdf5_every_step', test_hdf5_every_step), &
                 new_test('hdf5_batches_and_record_times', test_hdf5_batches), &
                 new_test('hdf5_unwritable_path', test_hdf5_unwritable), &
                 new_test('progress_line', test_progress), &
                 new_test('output_files_replace', test_output_files), &
                 new_test('run_scene_van_der_pol', test_run_scene), &
                 new_test('run_scene_pendulum_blocks', test_run_pendulum), &
                 new_test('run_scene_bad_linear_solver_no_file', test_run_bad_solver), &
                 new_test('flexible_body_parses', test_body_parses), &
                 new_test('flexible_body_bad_input', test_body_bad_input), &
                 new_test('flexible_body_bad_sets_no_file', test_body_bad_sets), &
                 new_test('flexible_body_built', test_body_built), &
                 new_test('flexible_body_free_fall_all_solvers', test_body_free_fall), &
                 new_test('flexible_body_cantilever_dissipates', test_body_cantilever)]
    end function collect_io

    ! ------------------------------------------------------------------
    ! Namelist input
    ! ------------------------------------------------------------------

    subroutine test_valid_file(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        class(dae_solver_t), allocatable :: solver
        type(solver_setting_t) :: setting
        character(len=:), allocatable :: path
        path = scratch('valid.nml')
        ! its output folder, beside it
        call execute_command_line('mkdir -p ' // path(1:index(path, '/', back=.true.)) // 'out')
        ! groups out of order, comments, mixed case, '&end', commas
        call write_text(path, &
            '! a scene' // nl // &
            '&output file = ''out/run.h5'', n_output = 5, every_step = .true. /' // nl // &
            '&SOLVER' // nl // &
            '  rtol = 1d-8, atol=1.0e-9 ! tight' // nl // &
            '  max_steps = 5000' // nl // &
            '  controller = ''Classical''' // nl // &
            '  thet = -1, zero_start = T' // nl // &
            '&end' // nl // &
            '&simulation title = ''it''''s a test ! not a comment'', problem = ''pendulum''' // &
            nl // '  t_start = 1, t_end = 3.5, pendulum_formulation = ''ggl''' // nl // &
            '  pendulum_length = 2.0 gravity = 1.62 npoints = 40' // nl // '/' // nl)
        call read_scene(path, scene, status)
        call check(error, status%ok(), 'status: ' // status%text())
        if (allocated(error)) return
        call check(error, scene%title == 'it''s a test ! not a comment', 'title: ' // &
                   trim(scene%title))
        call check(error, scene%problem == 'pendulum', 'problem')
        call check_close(error, scene%t_start, 1.0_wp, 0.0_wp, 't_start')
        call check_close(error, scene%t_end, 3.5_wp, 0.0_wp, 't_end')
        call check(error, scene%pendulum_formulation == 'ggl', 'formulation')
        call check_close(error, scene%pendulum_length, 2.0_wp, 0.0_wp, 'length')
        call check_close(error, scene%gravity, 1.62_wp, 0.0_wp, 'gravity')
        call check(error, scene%npoints == 40, 'npoints')
        call check_close(error, scene%rtol, 1.0e-8_wp, 0.0_wp, 'rtol')
        call check_close(error, scene%atol, 1.0e-9_wp, 0.0_wp, 'atol')
        call check(error, scene%max_steps == 5000, 'max_steps')
        setting = given_setting(scene, 'controller')
        call check(error, setting%string_value == 'classical', 'controller lower-cased')
        setting = given_setting(scene, 'thet')
        call check_close(error, setting%real_value, -1.0_wp, 0.0_wp, 'thet')
        setting = given_setting(scene, 'zero_start')
        call check(error, setting%logical_value, 'zero_start')
        ! relative to the scene's folder
        call check(error, scene%output_file == path(1:index(path, '/', back=.true.)) // &
                   'out/run.h5', 'file: ' // scene%output_file)
        call check(error, scene%n_output == 5, 'n_output')
        call check(error, scene%every_step, 'every_step')
        call check(error, index(scene%text, '&SOLVER') > 0, 'text kept')
        if (allocated(error)) return
        ! given settings reach the solver; the others keep its type's defaults
        setting = given_setting(scene, 'nit')
        call check(error, len_trim(setting%name) == 0, 'nit not given')
        setting = given_setting(scene, 'thet')
        call check(error, setting%name == 'thet', &
                   'settings given')
        call build_solver(scene, solver, status)
        call check(error, status%ok(), 'build_solver: ' // status%text())
        if (allocated(error)) return
        select type (solver)
        type is (radau5_t)
            call check(error, solver%nit == 7 .and. solver%thet == -1.0_wp .and. &
                solver%zero_start .and. solver%controller == radau5_controller_classical .and. &
                solver%quot2 == 1.2_wp, 'RADAU5: the given settings, NIT 7 and QUOT2 1.2 &
                &of radau5_t')
        class default
            call check(error, .false., 'not a radau5_t: ' // solver%name())
        end select
        call delete(path)
    end subroutine test_valid_file

    subroutine test_defaults(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 2 /', &
                         'inputs/vdp.nml', scene, status)
        call check(error, status%ok(), 'status: ' // status%text())
        call check(error, scene%solver_name == 'radau5', 'solver default')
        call check_close(error, scene%rtol, 1.0e-6_wp, 0.0_wp, 'rtol default')
        call check_close(error, scene%vdp_eps, 1.0e-6_wp, 0.0_wp, 'eps default')
        call check(error, scene%linear_solver == 'auto', 'linear_solver default')
        call check(error, scene%output_file == 'vdp.h5', 'derived file: ' // scene%output_file)
        call check(error, scene%n_output == 101 .and. .not. scene%every_step, 'output defaults')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 2 /' // nl // &
                         '&output file = ''none'' /', 'x.nml', scene, status)
        call check(error, status%ok() .and. len(scene%output_file) == 0, 'file = none')
    end subroutine test_defaults

    subroutine test_options(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(dae_options_t) :: options
        call parse_scene('&simulation problem = ''van_der_pol'', t_start = 1, t_end = 2 /' // &
            nl // '&solver rtol = 1e-5, atol = 1e-7, hmax = 0.1, max_steps = 77, ' // &
            'linear_solver = ''klu'' /' // nl // '&output n_output = 5 /', 'x.nml', scene, status)
        call check(error, status%ok(), 'status: ' // status%text())
        if (allocated(error)) return
        options = scene_dae_options(scene)
        call check_close(error, options%rtol, 1.0e-5_wp, 0.0_wp, 'rtol')
        call check_close(error, options%atol, 1.0e-7_wp, 0.0_wp, 'atol')
        call check_close(error, options%hmax, 0.1_wp, 0.0_wp, 'hmax')
        call check(error, options%max_steps == 77, 'max_steps')
        call check(error, options%linear_solver == 'klu', 'linear_solver')
        call check(error, size(options%output_times) == 5, 'output count')
        call check_close(error, options%output_times(1), 1.0_wp, 0.0_wp, 'first output')
        call check_close(error, options%output_times(3), 1.5_wp, 1e-15_wp, 'middle output')
        call check_close(error, options%output_times(5), 2.0_wp, 0.0_wp, 'last output')
        call options%validate(2, status)
        call check(error, status%ok(), 'options validate')
    end subroutine test_options

    subroutine test_unknown_variable(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse_status('&simulation problem = ''van_der_pol'', t_end = 2 /' // nl // &
                              '&solver rtol = 1e-4' // nl // '  atoll = 1e-4 /')
        call check(error, status%code == status_bad_input, 'code')
        call expect(error, status, 'in.nml: &solver: atoll: unknown variable')
        call expect(error, status, '(line 3)')
        call expect(error, status, 'atol')
    end subroutine test_unknown_variable

    subroutine test_wrong_type(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse_status(vdp_sim() // '&solver max_steps = 1.5 /')
        call check(error, status%code == status_bad_input, 'code (integer)')
        call expect(error, status, 'in.nml: &solver: max_steps = 1.5: must be an integer')
        status = parse_status(vdp_sim() // '&solver rtol = ''small'' /')
        call expect(error, status, 'in.nml: &solver: rtol = ''small'': must be a real number')
        status = parse_status(vdp_sim() // '&solver rtol = 1e-4x /')
        call expect(error, status, 'in.nml: &solver: rtol = 1e-4x: must be a real number')
        status = parse_status(vdp_sim() // '&output every_step = yes /')
        call expect(error, status, 'every_step = yes: must be .true. or .false.')
        status = parse_status(vdp_sim() // '&solver name = radau5 /')
        call expect(error, status, 'name = radau5: must be a quoted string')
        status = parse_status(vdp_sim() // '&solver rtol = 1e999 /')
        call expect(error, status, 'rtol = 1e999: is out of the range of real numbers')
    end subroutine test_wrong_type

    subroutine test_negative_tolerance(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse_status(vdp_sim() // '&solver' // nl // '  rtol = -1e-6' // nl // '/')
        call check(error, status%code == status_bad_input, 'code')
        call check(error, status%text() == 'in.nml: &solver: rtol = -1e-6: must be positive' // &
                   ' (line 3)', 'message: ' // status%text())
        status = parse_status(vdp_sim() // '&solver atol = 0 /')
        call expect(error, status, 'in.nml: &solver: atol = 0: must be positive')
        status = parse_status('&simulation problem = ''van_der_pol'', t_start = 3, ' // &
                              't_end = 2 /')
        call expect(error, status, '&simulation: t_end = 2: must be greater than t_start = 3')
        status = parse_status('&simulation problem = ''van_der_pol'' /')
        call expect(error, status, '&simulation: t_end: required')
        status = parse_status(vdp_sim() // '&solver linear_solver = ''lu'' /')
        call expect(error, status, &
            'linear_solver = ''lu'': must be ''auto'', ''dense'', ''klu'', ''band'' or ''mumps''')
        status = parse_status(vdp_sim() // '&output table = ''x.txt'' /')
        call expect(error, status, 'table = ''x.txt'': must end in .md, .csv or .tex')
        ! the range RADAU5 checks itself (core/rules' safety_factor_rule)
        status = parse_status(vdp_sim() // '&solver safe = 1 /')
        call expect(error, status, 'in.nml: &solver: safe = 1: must lie in (0.001, 1)')
    end subroutine test_negative_tolerance

    !> Every solver's own setting in the schema (a &solver variable without
    !> a default) is taken by a solver of the catalogue, and by one only
    !> unless it is a shared name; no solver takes a name the schema lacks.
    subroutine test_own_settings(error)
        type(error_t), allocatable, intent(out) :: error
        class(dae_solver_t), allocatable :: solver
        type(status_t) :: status
        logical :: applied
        integer :: v, k, takers
        do v = 1, size(schema)
            if (schema(v)%group /= 'solver' .or. len_trim(schema(v)%default) > 0) cycle
            takers = 0
            do k = 1, size(solvers)
                call new_solver(trim(solvers(k)%name), solver, status)
                call check(error, status%ok(), status%text())
                if (allocated(error)) return
                call solver%apply_setting(solver_setting_t(name=schema(v)%name), applied)
                if (applied) takers = takers + 1
            end do
            call check(error, takers == 1, trim(schema(v)%name) // ': taken by ' // &
                       int_text(takers) // ' solvers')
        end do
        do k = 1, size(solvers)
            call new_solver(trim(solvers(k)%name), solver, status)
            call solver%apply_setting(solver_setting_t(name='rtol'), applied)
            call check(error, .not. applied, trim(solvers(k)%name) // ' takes rtol')
        end do
    end subroutine test_own_settings

    subroutine test_missing_file(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        character(len=:), allocatable :: path
        path = scratch('does_not_exist.nml')
        call read_scene(path, scene, status)
        call check(error, status%code == status_bad_input, 'code')
        call expect(error, status, path // ': no such file')
    end subroutine test_missing_file

    subroutine test_unknown_group(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse_status(vdp_sim() // '! the solver' // nl // '&solvers rtol = 1e-4 /')
        call check(error, status%code == status_bad_input, 'code')
        call expect(error, status, 'in.nml: &solvers: unknown group (did you mean ''solver''?) ' &
                    // '(known: &simulation, &solver, &output, &flexible_body, &material, ' // &
                    '&multibody, &rigid_body, &marker, &joint, &driver, &force, &rigid_chain; ' &
                    // '&study in ' &
                    // 'study files) (line 3)')
    end subroutine test_unknown_group

    subroutine test_other_bad_text(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse_status(vdp_sim() // '&solver rtol = 1e-4')
        call expect(error, status, '&solver: not closed by ''/''')
        status = parse_status(vdp_sim() // '&solver rtol = 1e-4 2e-4 /')
        call expect(error, status, '&solver: rtol: unexpected ''2e-4'' after its value')
        status = parse_status(vdp_sim() // '&solver rtol = 1e-4, rtol = 1e-5 /')
        call expect(error, status, '&solver: rtol: given more than once')
        status = parse_status(vdp_sim() // vdp_sim())
        call expect(error, status, '&simulation: group given more than once')
        status = parse_status(vdp_sim() // 'rtol = 1 /')
        call expect(error, status, 'unexpected text ''rtol'' outside a group')
        status = parse_status(vdp_sim() // '&solver rtol = /')
        call expect(error, status, '&solver: rtol: has no value')
        status = parse_status(vdp_sim() // '&solver name = ''radau5 /')
        call expect(error, status, 'unterminated string')
        status = parse_status(vdp_sim() // '&solver name = ''dassl'' /')
        call expect(error, status, 'name = ''dassl'': must be one of ''radau5'', ''ddassl'', ' // &
                    '''ida'' or ''mexax'' (did you mean ''ddassl''?)')
        status = parse_status('&simulation problem = ''duffing'', t_end = 1 /')
        call expect(error, status, 'problem = ''duffing'': must be one of ''van_der_pol''')
        status = parse_status(vdp_sim() // '&solver sparse_ordering = ''metis'' /')
        call expect(error, status, &
            '&solver: sparse_ordering = ''metis'': must be ''auto'', ''amd'' or ''nd''')
    end subroutine test_other_bad_text

    ! ------------------------------------------------------------------
    ! Tables
    ! ------------------------------------------------------------------

    subroutine test_table_formats(error)
        type(error_t), allocatable, intent(out) :: error
        type(stats_row_t) :: rows(2)
        type(dae_stats_t) :: stats
        character(len=:), allocatable :: text, path
        type(status_t) :: status
        stats%nst = 275
        stats%nac = 238
        stats%nrj = 37
        stats%nfe = 2218
        stats%nje = 161
        stats%ndec = 248
        stats%nsol = 906
        stats%cpu = 0.0123_wp
        rows(1) = new_stats_row('radau5', 1.0e-4_wp, 'index2', stats, err=2.5e-5_wp)
        rows(2) = new_stats_row('my_solver', 1.0e-6_wp, '', stats)

        text = table_text(rows, table_markdown)
        call check(error, count_char(text, nl) == 4, 'markdown: 4 lines')
        call check(error, index(text, '| solver    |     TOL | stab.  |     ERR | NST |') == 1, &
                   'markdown header: ' // text)
        call check(error, index(text, '| NRJ | NDEC | NSOL |') > 0, 'markdown extra columns')
        call check(error, index(text, '| radau5    | 1.0e-04 | index2 | 2.5e-05 | 275 | 238 |' &
                   // ' 2218 | 161 | 0.012 |  37 |  248 |  906 |') > 0, 'markdown row: ' // text)
        call check(error, index(text, '| my_solver | 1.0e-06 | -      |       - |') > 0, &
                   'markdown missing ERR and stab')

        text = table_text(rows, table_csv)
        call check(error, index(text, 'solver,TOL,stab.,ERR,NST,NAC,NFE,NJE,CPU,NRJ,NDEC,NSOL' &
                   // nl) == 1, 'csv header')
        call check(error, index(text, 'radau5,1.0e-04,index2,2.5e-05,275,238,2218,161,0.012,' &
                   // '37,248,906' // nl) > 0, 'csv row: ' // text)

        text = table_text(rows, table_latex)
        call check(error, index(text, '\begin{tabular}{lrlrrrrrrrrr}') == 1, 'latex begin')
        call check(error, index(text, 'radau5 & $10^{-4}$ & index2 & $2.5\cdot 10^{-5}$ & ' // &
                   '275 & 238 & 2218 & 161 & 0.012 & 37 & 248 & 906 \\') > 0, 'latex row: ' // text)
        call check(error, index(text, 'my\_solver') > 0, 'latex escapes _')
        call check(error, index(text, '\end{tabular}') > 0, 'latex end')

        call check(error, table_format('a/b.md') == table_markdown, 'format md')
        call check(error, table_format('b.csv') == table_csv, 'format csv')
        call check(error, table_format('b.tex') == table_latex, 'format tex')
        call check(error, table_format('b.txt') == 0, 'format unknown')

        path = scratch('table.csv')
        call write_table(path, rows, status)
        call check(error, status%ok(), 'write_table: ' // status%text())
        ! the comment that marks flexmbs's tables, then the table
        call check(error, read_text(path) == '# written by flexmbs ' // version // nl // &
                   table_text(rows, table_csv), 'file content: ' // read_text(path))
        call delete(path)
        call write_table(scratch('table.txt'), rows, status)
        call check(error, status%code == status_bad_input, 'write_table unknown format')
    end subroutine test_table_formats

    !> `reasons`: NRJ by cause after the paper's columns (Table 3) or below
    !> its rows (Table 2); without it the paper's layouts are unchanged.
    subroutine test_table_reasons(error)
        type(error_t), allocatable, intent(out) :: error
        type(stats_row_t) :: rows(1)
        type(dae_stats_t) :: stats
        character(len=:), allocatable :: text
        integer :: counts(cause_count)
        stats%nst = 275
        stats%nac = 238
        stats%nrj = 37
        counts = 0
        counts(1) = 8
        counts(3) = 29
        call stats%rejections%restore(counts, '')
        rows(1) = new_stats_row('radau5', 1.0e-4_wp, '-', stats)
        call check(error, table_text(rows, table_csv) == table_text(rows, table_csv, &
                   reasons=.false.), 'reasons = .false. changed the table')
        call check(error, index(table_text(rows, table_csv), 'Newton') == 0, &
                   'causes without reasons')
        text = table_text(rows, table_csv, reasons=.true.)
        call check(error, index(text, 'solver,TOL,stab.,ERR,NST,NAC,NFE,NJE,CPU,NRJ,NDEC,' // &
                   'NSOL,error test,Newton diverged,Newton slow,singular,refused,' // &
                   'projection,unstable' // nl) == 1, 'csv header with causes: ' // text)
        call check(error, index(text, ',37,0,0,8,0,29,0,0,0,0' // nl) > 0, &
                   'csv row with causes: ' // text)
        text = layout_text(rows, table_markdown, 'table2')
        call check(error, index(text, 'rejected/NST') > 0 .and. index(text, 'Newton') == 0, &
                   'table2 without causes: ' // text)
        text = layout_text(rows, table_markdown, 'table2', reasons=.true.)
        call check(error, index(text, '| Newton slow     |     29 |') > 0 .and. &
                   index(text, '| error test      |      8 |') > 0, 'table2 rows of causes: ' &
                   // text)
    end subroutine test_table_reasons

    !> Which files a run may replace: flexmbs's own HDF5 result and table,
    !> not a file of anyone else unless forced; never an input; never two
    !> outputs in one file, however spelled.
    subroutine test_output_files(error)
        type(error_t), allocatable, intent(out) :: error
        type(named_path_t) :: outputs(2), inputs(1)
        type(hdf5_sink_t) :: sink
        type(status_t) :: status
        character(len=:), allocatable :: h5, md, input
        h5 = scratch('replace.h5')
        md = scratch('replace.md')
        input = scratch('replace.nml')
        call write_text(input, '&simulation /')
        call write_text(h5, 'notes')
        call write_text(md, '| a | b |')
        inputs(1) = named_path(input, 'the scene file itself')
        outputs(1) = named_path(h5, '&output: file', output_hdf5)
        outputs(2) = named_path(md, '&output: table', output_table)
        call check_output_paths('s.nml: ', outputs, inputs, .false., status)
        call check(error, status%code == status_bad_input .and. index(status%text(), &
            'exists and is not an HDF5 file: refused; --force replaces it') > 0, &
            'foreign file: ' // status%text())
        call status%clear()
        call check_output_paths('s.nml: ', outputs, inputs, .true., status)
        call check(error, status%ok(), 'forced: ' // status%text())
        ! flexmbs's own: replaced without force
        call sink%create(h5, 1, status)
        call sink%close(status)
        call write_table(md, [new_stats_row('radau5', 1.0e-4_wp, '-', dae_stats_t())], status)
        call check_output_paths('s.nml: ', outputs, inputs, .false., status)
        call check(error, status%ok(), 'own files: ' // status%text())
        ! never an input, even forced
        outputs(2) = named_path(input, '&output: table', output_table)
        call check_output_paths('s.nml: ', outputs, inputs, .true., status)
        call check(error, index(status%text(), 'is the scene file itself: refused') > 0, &
            'input: ' // status%text())
        ! one file under two names, existing or not
        call status%clear()
        outputs(2) = named_path(h5(1:index(h5, '/', back=.true.)) // '.' // &
            h5(index(h5, '/', back=.true.):), '&output: table', output_table)
        call check_output_paths('s.nml: ', outputs, inputs(1:0), .true., status)
        call check(error, index(status%text(), 'are the same file') > 0, &
            'same file: ' // status%text())
        call delete(h5)
        call status%clear()
        call check_output_paths('s.nml: ', outputs, inputs(1:0), .true., status)
        call check(error, index(status%text(), 'are the same file') > 0, &
            'same file not yet written: ' // status%text())
        call delete(md)
        call delete(input)
    end subroutine test_output_files

    ! ------------------------------------------------------------------
    ! HDF5
    ! ------------------------------------------------------------------

    subroutine test_hdf5_round_trip(error)
        type(error_t), allocatable, intent(out) :: error
        type(hdf5_sink_t) :: sink
        type(status_t) :: status
        type(dae_stats_t) :: stats
        character(len=:), allocatable :: path, big
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        real(wp) :: rec(4)
        integer :: k, i, nst
        path = scratch('round_trip.h5')
        big = repeat('x', 40000)
        call sink%create(path, 4, status, input_text='&simulation t_end = 1 /')
        call check(error, status%ok(), 'create: ' // status%text())
        if (allocated(error)) return
        call sink%add_block('q', 2, 3, status)
        call check(error, status%ok(), 'add_block: ' // status%text())
        do k = 1, 3
            rec = [(real(10 * k + i, wp), i = 1, 4)]
            call sink%output(0.5_wp * k, rec, status)
        end do
        call check(error, status%ok(), 'output: ' // status%text())
        call sink%finish(status)
        stats%nst = 42
        stats%cpu = 1.5_wp
        call sink%write_statistics(stats, status, 'radau5', 'ok')
        call check(error, status%ok(), 'statistics: ' // status%text())
        call sink%write_text('big_text', big, status)
        call check(error, status%ok(), 'big text: ' // status%text())
        call sink%close(status)
        call check(error, status%ok(), 'close: ' // status%text())
        if (allocated(error)) return

        call read_series(path, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 3, 'time length')
        call check(error, all(shape(y) == [4, 3]), 'y shape')
        call check(error, all(shape(q) == [2, 3]), 'q shape')
        if (allocated(error)) return
        call check(error, all(time == [0.5_wp, 1.0_wp, 1.5_wp]), 'time values')
        call check(error, all(y(:, 2) == [21.0_wp, 22.0_wp, 23.0_wp, 24.0_wp]), 'y values')
        call check(error, all(y(4, :) == [14.0_wp, 24.0_wp, 34.0_wp]), 'y row')
        call check(error, all(q(:, 3) == [32.0_wp, 33.0_wp]), 'q block values')
        call check(error, nst == 42, 'NST attribute')
        call check(error, read_string_attribute(path, 'input_text') == &
                   '&simulation t_end = 1 /', 'input_text attribute')
        call check(error, read_string_attribute(path, 'solver') == 'radau5', 'solver attr')
        call check(error, read_string_attribute(path, 'big_text') == &
                   'stored in dataset /big_text', 'large text moved to a dataset')
        call delete(path)
    end subroutine test_hdf5_round_trip

    !> Records held in memory reach the file by `finish` (and at the latest a
    !> second after the last write, not tested: it would wait); the times an
    !> index lists, read back: all up to `most`, else one in k and the last.
    subroutine test_hdf5_batches(error)
        type(error_t), allocatable, intent(out) :: error
        type(hdf5_sink_t) :: sink
        type(status_t) :: status
        character(len=:), allocatable :: path
        real(wp), allocatable :: time(:), y(:, :), q(:, :), times(:)
        integer, allocatable :: rows(:)
        integer :: k, nst, total
        path = scratch('batches.h5')
        call sink%create(path, 2, status)
        do k = 0, 24
            call sink%output(0.1_wp * k, [real(k, wp), -real(k, wp)], status)
        end do
        call check(error, status%ok(), 'output: ' // status%text())
        call sink%record_times(10, rows, times, total, status)
        call check(error, status%ok(), 'record_times: ' // status%text())
        if (allocated(error)) return
        ! 25 records, at most 10 listed: one in 3 (0, 3, ..., 24), 24 being the last
        call check(error, total == 25, 'total')
        call check(error, all(rows == [(3 * k, k = 0, 8)]), 'rows: one in 3 and the last')
        call check(error, all(abs(times - 0.1_wp * rows) <= 1e-15_wp), 'times read back')
        call sink%record_times(100, rows, times, total, status)
        call check(error, size(rows) == 25 .and. rows(25) == 24, 'every record when few')
        call sink%output(2.6_wp, [26.0_wp, -26.0_wp], status)
        call sink%record_times(12, rows, times, total, status)
        ! 26 records, at most 12: one in 3 (0 .. 24) and the last, 25
        call check(error, total == 26 .and. rows(size(rows)) == 25 .and. rows(size(rows) - 1) &
            == 24, 'the last added')
        call sink%finish(status)
        call sink%close(status)
        call check(error, status%ok(), 'close: ' // status%text())
        call read_series(path, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 26 .and. all(y(1, :) == -y(2, :)) .and. &
            y(1, 26) == 26.0_wp, 'every record in the file')
        call delete(path)
    end subroutine test_hdf5_batches

    subroutine test_hdf5_every_step(error)
        type(error_t), allocatable, intent(out) :: error
        type(hdf5_sink_t) :: sink
        type(status_t) :: status
        type(still_t) :: dense
        character(len=:), allocatable :: path
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        logical :: stop
        integer :: nst
        path = scratch('every_step.h5')
        stop = .false.
        call sink%create(path, 2, status, every_step=.true.)
        call check(error, sink%wants_steps(), 'wants steps')
        call sink%step(1, 0.0_wp, 0.0_wp, [1.0_wp, 2.0_wp], dense, stop, status)
        call sink%output(0.05_wp, [9.0_wp, 9.0_wp], status)   ! ignored in this mode
        call sink%step(2, 0.0_wp, 0.1_wp, [3.0_wp, 4.0_wp], dense, stop, status)
        call check(error, status%ok(), 'steps: ' // status%text())
        call sink%close(status)
        call read_series(path, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 2, 'two records')
        call check(error, all(time == [0.0_wp, 0.1_wp]), 'step times')
        call check(error, all(y(:, 2) == [3.0_wp, 4.0_wp]), 'step values')
        call delete(path)
    end subroutine test_hdf5_every_step

    subroutine test_hdf5_unwritable(error)
        type(error_t), allocatable, intent(out) :: error
        type(hdf5_sink_t) :: sink
        type(status_t) :: status
        call sink%create(scratch('no_such_dir/x.h5'), 2, status)
        call check(error, status%code == status_io_error, 'code')
        call expect(error, status, 'no_such_dir/x.h5: HDF5 cannot create the file')
        call sink%close(status)
    end subroutine test_hdf5_unwritable

    !> /time, /y and (if present) /q of a file, and its NST attribute.
    subroutine read_series(path, time, y, q, nst, error)
        character(len=*), intent(in) :: path
        real(wp), allocatable, intent(out) :: time(:), y(:, :), q(:, :)
        integer, intent(out) :: nst
        type(error_t), allocatable, intent(inout) :: error
        integer(hid_t) :: file, dset, space, attr
        integer(hsize_t) :: dims(2), maxdims(2)
        integer :: err
        logical :: exists
        nst = -1
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        call check(error, err >= 0, 'reopen ' // path)
        if (allocated(error)) return
        call h5dopen_f(file, 'time', dset, err)
        call h5dget_space_f(dset, space, err)
        call h5sget_simple_extent_dims_f(space, dims(1:1), maxdims(1:1), err)
        allocate (time(dims(1)))
        call h5dread_f(dset, H5T_NATIVE_DOUBLE, time, dims(1:1), err)
        call check(error, err >= 0, 'read /time')
        call h5sclose_f(space, err)
        call h5dclose_f(dset, err)
        call h5dopen_f(file, 'y', dset, err)
        call h5dget_space_f(dset, space, err)
        call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
        call check(error, maxdims(2) == H5S_UNLIMITED_F, '/y extendible')
        allocate (y(dims(1), dims(2)))
        call h5dread_f(dset, H5T_NATIVE_DOUBLE, y, dims, err)
        call check(error, err >= 0, 'read /y')
        call h5sclose_f(space, err)
        call h5dclose_f(dset, err)
        call h5lexists_f(file, 'q', exists, err)
        if (exists) then
            call h5dopen_f(file, 'q', dset, err)
            call h5dget_space_f(dset, space, err)
            call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
            allocate (q(dims(1), dims(2)))
            call h5dread_f(dset, H5T_NATIVE_DOUBLE, q, dims, err)
            call check(error, err >= 0, 'read /q')
            call h5sclose_f(space, err)
            call h5dclose_f(dset, err)
        else
            allocate (q(0, 0))
        end if
        call h5aexists_f(file, 'NST', exists, err)
        if (exists) then
            call h5aopen_f(file, 'NST', attr, err)
            call h5aread_f(attr, H5T_NATIVE_INTEGER, nst, [1_hsize_t], err)
            call h5aclose_f(attr, err)
        end if
        call h5fclose_f(file, err)
    end subroutine read_series

    !> A string attribute of the file's root, as flexmbs writes them
    !> (variable-length UTF-8; io/hdf5_text reads both kinds).
    function read_string_attribute(path, name) result(text)
        character(len=*), intent(in) :: path, name
        character(len=:), allocatable :: text
        integer(hid_t) :: file
        integer :: err, close_err
        text = '<unreadable>'
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0) return
        call read_text_attribute(file, name, text, err)
        if (err < 0) text = '<unreadable>'
        call h5fclose_f(file, close_err)
    end function read_string_attribute

    ! ------------------------------------------------------------------
    ! Progress display and a whole run
    ! ------------------------------------------------------------------

    subroutine test_progress(error)
        type(error_t), allocatable, intent(out) :: error
        type(progress_t) :: progress
        type(status_t) :: status
        type(still_t) :: dense
        type(radau5_t), target :: radau5
        type(ida_t), target :: ida
        character(len=:), allocatable :: path, text
        integer :: unit
        logical :: stop
        path = scratch('progress.txt')
        open (newunit=unit, file=path, status='replace', action='write')
        progress = new_progress(0.0_wp, 2.0_wp, quiet=.false., unit=unit)
        ! the solver's live counts through dae_solver_t%step_counts
        radau5%native%nstep = 12
        radau5%native%naccpt = 10
        call progress%watch(radau5)
        stop = .false.
        call check(error, progress%wants_steps(), 'wants steps')
        call progress%step(11, 0.9_wp, 1.0_wp, [0.0_wp], dense, stop, status)
        call check(error, index(progress%line(), '50.0 %') > 0, 'percent: ' // progress%line())
        call check(error, index(progress%line(), 'steps 10') > 0, 'steps')
        call check(error, index(progress%line(), 'rejected 2') > 0, 'rejected')
        ! half the simulated time in 75 s: as long again to go
        call check(error, index(progress%line(75.0_wp), 'elapsed 1:15  left ~1:15') > 0, &
            'elapsed and left: ' // progress%line(75.0_wp))
        call check(error, index(progress%line(3725.0_wp), 'elapsed 1:02:05  left ~1:02:05') &
            > 0, 'hours: ' // progress%line(3725.0_wp))
        call progress%watch(ida)
        call check(error, index(progress%line(), 'rejected') == 0, 'no counts, no rejections')
        call progress%watch(radau5)
        call progress%finish(status)
        close (unit)
        text = read_text(path)
        call check(error, text(1:1) == achar(13), 'redrawn with a carriage return')
        call check(error, index(text, 't =  1.00000E+00 s') > 0, 'time shown: ' // text)
        call check(error, index(text, 'elapsed ') > 0, 'elapsed shown: ' // text)
        call delete(path)
        progress = new_progress(0.0_wp, 2.0_wp, quiet=.true., unit=unit)
        call check(error, .not. progress%wants_steps(), 'quiet display wants nothing')
    end subroutine test_progress

    subroutine test_run_scene(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(run_result_t) :: result
        character(len=:), allocatable :: h5, table
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        integer :: nst
        h5 = scratch('vdp_run.h5')
        table = scratch('vdp_run.md')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 2 /' // nl // &
            '&solver rtol = 1e-4, atol = 1e-4, h0 = 1e-6 /' // nl // &
            '&output file = ''' // h5 // ''', n_output = 11, table = ''' // table // ''' /', &
            'vdp.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        if (allocated(error)) return
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        ! the RADAU5 anchor of docs/solvers.md
        call check_close(error, result%y(1), 1.706161101_wp, 1e-6_wp, 'y1(2)')
        call check_close(error, result%y(2), -0.8928074777_wp, 1e-6_wp, 'y2(2)')
        call check(error, result%stats%nst == 275, 'NST')
        call read_series(h5, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 11, 'eleven output records')
        call check_close(error, time(11), 2.0_wp, 0.0_wp, 'last output time')
        call check(error, all(y(:, 1) == [2.0_wp, -0.66_wp]), 'first record is y0')
        call check_close(error, y(1, 11), result%y(1), 1e-12_wp, 'last record is the end state')
        call check(error, nst == 275, 'NST attribute')
        call check(error, index(read_string_attribute(h5, 'input_text'), 'van_der_pol') > 0, &
                   'input text stored')
        call check(error, index(read_text(table), '| radau5 | 1.0e-04 |') > 0, 'table row')
        call delete(h5)
        call delete(table)
    end subroutine test_run_scene

    subroutine test_run_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(run_result_t) :: result
        character(len=:), allocatable :: h5
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        integer :: nst, k
        h5 = scratch('pendulum_run.h5')
        call parse_scene('&simulation problem = ''pendulum'', t_end = 1, ' // &
            'pendulum_length = 2, pendulum_formulation = ''index2'' /' // nl // &
            '&solver rtol = 1e-6, atol = 1e-6 /' // nl // &
            '&output file = ''' // h5 // ''', n_output = 6 /', 'pendulum.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        if (allocated(error)) return
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        call check(error, size(result%y) == 5, 'n = 5 in index 2')
        call read_series(h5, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, all(shape(q) == [2, 6]), '/q block shape')
        if (allocated(error)) return
        call check(error, all(q == y(1:2, :)), '/q equals y(1:2)')
        do k = 1, 6
            ! the rod keeps its length: x² + y² = L² (index 2 drifts slowly)
            call check_close(error, sqrt(q(1, k)**2 + q(2, k)**2), 2.0_wp, 1e-4_wp, 'length')
        end do
        call delete(h5)
    end subroutine test_run_pendulum

    !> A linear solver that does not exist is bad input: no file is left.
    subroutine test_run_bad_solver(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(run_result_t) :: result
        character(len=:), allocatable :: h5
        logical :: exists
        h5 = scratch('bad_solver.h5')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
            '&output file = ''' // h5 // ''' /', 'x.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        scene%linear_solver = 'nonsense'
        call run_scene(scene, .true., result, status)
        call check(error, status%code == status_bad_input, 'bad input expected')
        call expect(error, status, 'x.nml: &solver: ')
        inquire (file=h5, exist=exists)
        call check(error, .not. exists, 'no HDF5 file on bad input')
    end subroutine test_run_bad_solver

    ! ------------------------------------------------------------------
    ! Flexible bodies: &flexible_body and &material
    ! ------------------------------------------------------------------

    !> A box of 3 x 1 x 1 hex8 elements (3 m x 1 m x 1 m) with the variables
    !> `body_vars` added, followed by the groups `rest`.
    function body_scene(body_vars, rest) result(text)
        character(len=*), intent(in) :: body_vars, rest
        character(len=:), allocatable :: text
        text = '&simulation t_end = 0.1 /' // nl // &
            '&flexible_body lengths = 3, 1, 1, divisions = 3, 1, 1' // body_vars // ' /' // nl &
            // rest
    end function body_scene

    !> One soft material on every element.
    function soft() result(text)
        character(len=:), allocatable :: text
        text = '&material name = ''soft'', youngs_modulus = 1e4, density = 100 /' // nl
    end function soft

    !> Arrays, repeated &material groups, defaults; &flexible_body selects
    !> the problem when &simulation does not name one.
    subroutine test_body_parses(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        call parse_scene('&simulation t_end = 0.5 /' // nl // &
            '&flexible_body element = ''HEX27'', divisions = 4 2 1, lengths = 0.4, 0.05, 0.05,' &
            // nl // '  origin = -1, 0, 0, fixed = ''xmin'', ''ymin'', gravity = 0, 0, -9.81 /' &
            // nl // '&material youngs_modulus = 7e5, density = 920, viscosity = 1000 /' // nl &
            // '&material name = ''tip'', elements = ''xmax_layer'', youngs_modulus = 1e7,' // &
            ' poisson_ratio = 0.25, density = 1000 /', 'in.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        if (allocated(error)) return
        call check(error, scene%problem == 'flexible_body' .and. scene%has_body(), 'problem')
        call check(error, scene%bodies(1)%element == 'hex27', 'element lower-cased')
        call check(error, all(scene%bodies(1)%divisions == [4, 2, 1]), 'divisions')
        call check(error, all(scene%bodies(1)%lengths == [0.4_wp, 0.05_wp, 0.05_wp]), 'lengths')
        call check(error, all(scene%bodies(1)%origin == [-1.0_wp, 0.0_wp, 0.0_wp]), 'origin')
        call check(error, scene%bodies(1)%fixed(1) == 'xmin' .and. scene%bodies(1)%fixed(2) == 'ymin' &
                   .and. all(scene%bodies(1)%fixed(3:) == ''), 'fixed')
        call check(error, all(scene%bodies(1)%gravity == [0.0_wp, 0.0_wp, -9.81_wp]), 'gravity')
        call check(error, scene%bodies(1)%formulation == 'index2', 'formulation default')
        call check(error, size(scene%materials) == 2, 'two materials')
        if (allocated(error)) return
        call check(error, scene%materials(1)%name == 'material 1' .and. &
                   scene%materials(1)%elements == '' .and. &
                   scene%materials(1)%poisson_ratio == 0.3_wp .and. &
                   scene%materials(1)%viscosity == 1000.0_wp, 'first material and defaults')
        call check(error, scene%materials(2)%name == 'tip' .and. &
                   scene%materials(2)%youngs_modulus == 1.0e7_wp .and. &
                   scene%materials(2)%poisson_ratio == 0.25_wp .and. &
                   scene%materials(2)%line == 5, 'second material')
    end subroutine test_body_parses

    !> Each bad &flexible_body or &material names file, group, variable,
    !> value and reason.
    subroutine test_body_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: tip = '&material name = ''tip'', youngs_modulus = 1e7, ' &
            // 'density = 1000, elements = '
        call expect(error, parse_status(body_scene('', &
            '&material youngs_modulus = -7e5, density = 920 /')), &
            'in.nml: &material: youngs_modulus = -7e5: must be positive (line 3)')
        call expect(error, parse_status(body_scene('', &
            '&material youngs_modulus = 7e5, density = 0 /')), &
            'in.nml: &material: density = 0: must be positive (line 3)')
        call expect(error, parse_status(body_scene('', soft() // &
            '&material youngs_modulus = 7e5, density = 1, poisson_ratio = 0.5, ' // &
            'elements = ''xmax_layer'' /')), &
            'in.nml: &material: poisson_ratio = 0.5: must lie in (-1, 0.5) (line 4)')
        call expect(error, parse_status(body_scene('', &
            '&material youngs_modulus = 7e5, density = 1, viscosity = -1 /')), &
            '&material: viscosity = -1: must lie in [0, 1e20]')
        ! beyond, the viscous stresses overflow (the fuzzer's 1e300 gave Inf)
        call expect(error, parse_status(body_scene('', &
            '&material youngs_modulus = 7e5, density = 1, viscosity = 1e300 /')), &
            '&material: viscosity = 1e300: must lie in [0, 1e20]')
        call expect(error, parse_status(body_scene('', '&material name = ''soft'', ' // &
            'density = 920 /')), 'in.nml: &material ''soft'': youngs_modulus: required ' // &
            '(Young''s modulus E in Pa) (line 3)')
        call expect(error, parse_status(body_scene('', '')), &
            'in.nml: &flexible_body: needs a &material group')
        call expect(error, parse_status(body_scene('', soft() // &
            '&flexible_body lengths = 1, 1, 1 /')), 'in.nml: &flexible_body: given 2 times, ' // &
            'but problem = ''flexible_body'' simulates one body (several are joined in ' // &
            'problem = ''multibody'') (line 4)')
        call expect(error, parse_status(body_scene(', origin = 2, 1', soft())), &
            'in.nml: &flexible_body: origin = 2, 1: needs 3 values (line 2)')
        call expect(error, parse_status(body_scene(', gravity = 0, 0, -9.81, 1', soft())), &
            'gravity = 0, 0, -9.81, 1: needs 3 values')
        call expect(error, parse_status('&simulation t_end = 1 /' // nl // &
            '&flexible_body lengths = 3, 1, 1, divisions = 3, 1.5, 1 /' // nl // soft()), &
            'in.nml: &flexible_body: divisions = 3, 1.5, 1: value 2 (1.5) must be an integer')
        call expect(error, parse_status(body_scene(', element = ''hex20''', soft())), &
            '&flexible_body: element = ''hex20'': must be ''hex8'' or ''hex27''')
        call expect(error, parse_status(body_scene(', formulation = ''index4''', soft())), &
            '&flexible_body: formulation = ''index4'': must be one of ''index3''')
        call expect(error, parse_status(vdp_sim() // soft()), &
            'in.nml: &material: given without &flexible_body (line 2)')
        call expect(error, parse_status('&simulation problem = ''pendulum'', t_end = 1 /' // &
            nl // '&flexible_body lengths = 1, 1, 1 /' // nl // soft()), &
            'in.nml: &flexible_body: given, but problem = ''pendulum'' (a scene builds only ' // &
            'what it declares) (line 2)')
        call expect(error, parse_status('&simulation problem = ''flexible_body'', t_end = 1 /'), &
            'in.nml: &simulation: problem = ''flexible_body'': needs a &flexible_body group')
        call expect(error, parse_status(body_scene('', soft() // &
            '&material name = ''hard'', youngs_modulus = 1e7, density = 1000 /')), &
            'in.nml: &material ''hard'': elements: not given here nor in &material ''soft'': ' // &
            'only one material may cover the elements no other names (line 4)')
        call expect(error, parse_status(body_scene('', tip // '''xmax_layer'' /' // nl // &
            '&material name = ''b'', youngs_modulus = 1, density = 1, elements = ' // &
            '''xmax_layer'' /')), '&material: elements = ''xmax_layer'': the same set as ' // &
            '&material ''tip'' at line 3 (line 4)')
        call expect(error, parse_status(body_scene('', soft() // soft())), &
            '&material: name = ''soft'': also the name of the &material at line 3 (line 4)')
        call expect(error, parse_status(body_scene(', load = 0, 0, 1', soft())), &
            '&flexible_body: load = 0, 0, 1: needs load_set (the node set that carries it)')
        call expect(error, parse_status(body_scene(', load_set = ''xmax''', soft())), &
            '&flexible_body: load_set = ''xmax'': needs load = fx, fy, fz')
        call expect(error, parse_status(body_scene(', fixed = ''a'' ''b'' ''c'' ''d'' ' // &
            '''e'' ''f'' ''g''', soft())), 'fixed = ''a'', ''b'', ''c'', ''d'', ''e'', ''f'', ' &
            // '''g'': at most 6 values')
        call expect(error, parse_status(body_scene(', lengths = 3, -1, 1', soft())), &
            'lengths: given more than once')
        call expect(error, parse_status('&simulation t_end = 1 /' // nl // &
            '&flexible_body lengths = 3, -1, 1 /' // nl // soft()), &
            '&flexible_body: lengths = 3, -1, 1: must be positive (line 2)')
        call expect(error, parse_status('&simulation t_end = 1 /' // nl // &
            '&flexible_body divisions = 3, 1, 1 /' // nl // soft()), &
            '&flexible_body: lengths: required (the box edge lengths in m), or mesh_file (line 2)')
        call expect(error, parse_status(body_scene(', mesh_file = ''bar.mesh''', soft())), &
            '&flexible_body: divisions = 3, 1, 1: not used with mesh_file')
        call expect(error, parse_status(body_scene('', soft() // '&solver name = ''mexax'', ' &
            // 'rtol = -1 /')), '&solver: rtol = -1: must be positive')
    end subroutine test_body_bad_input

    !> Set names are checked against the mesh before any file exists.
    subroutine test_body_bad_sets(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=:), allocatable :: h5, out
        h5 = scratch('bad_body.h5')
        out = '&output file = ''' // h5 // ''' /' // nl
        call refused(body_scene(', fixed = ''xmin'', ''xmim''', soft() // out), &
            'in.nml: &flexible_body: fixed = ''xmim'': mesh: no node set named ''xmim'' ' // &
            '(did you mean ''xmin''?) (known: xmin, xmax, ymin, ymax, zmin, zmax, xmin_ymin,')
        call refused(body_scene('', soft() // '&material name = ''tip'', youngs_modulus = 1e7,' &
            // ' density = 1000, elements = ''xmax_layr'' /' // nl // out), &
            'in.nml: &material ''tip'': elements = ''xmax_layr'': mesh: no element set named ' &
            // '''xmax_layr'' (did you mean ''xmax_layer''?) (known: all, xmin_layer, ' // &
            'xmax_layer, ymin_layer, ymax_layer, zmin_layer, zmax_layer) (line 4)')
        call refused(body_scene('', '&material name = ''a'', youngs_modulus = 1, density = 1,' &
            // ' elements = ''all'' /' // nl // '&material name = ''b'', youngs_modulus = 1, ' &
            // 'density = 1, elements = ''xmax_layer'' /' // nl // out), &
            'in.nml: &material ''b'': elements = ''xmax_layer'': element 3 is also in ''all''' &
            // ' of &material ''a'' (each element takes one material) (line 4)')
        call refused(body_scene('', '&material name = ''a'', youngs_modulus = 1, density = 1,' &
            // ' elements = ''xmax_layer'' /' // nl // out), &
            'in.nml: &material: elements: element 1 has no material (name a set containing ' // &
            'it, or leave elements out of one &material to cover the rest)')
        call refused(body_scene(', fixed = ''xmin'', load_set = ''xmin'', load = 1, 0, 0', &
            soft() // out), &
            'in.nml: &flexible_body: load_set = ''xmin'': every node of the set is fixed')
        call refused(body_scene(', load_set = ''tip'', load = 1, 0, 0', soft() // out), &
            'in.nml: &flexible_body: load_set = ''tip'': mesh: no node set named ''tip''')
        call refused('&simulation t_end = 1 /' // nl // '&flexible_body mesh_file = ''' // &
            'no/such.mesh'' /' // nl // soft() // out, &
            'in.nml: &flexible_body: mesh_file = ''no/such.mesh'': no/such.mesh: no such file')
        call refused('&simulation t_end = 1 /' // nl // '&flexible_body mesh_file = ''' // &
            'inputs/meshes/bar_hex8.mesh'', element = ''hex27'' /' // nl // soft() // out, &
            'in.nml: &flexible_body: element = ''hex27'': the mesh file ' // &
            '''inputs/meshes/bar_hex8.mesh'' has 8-node elements')
    contains
        subroutine refused(text, part)
            character(len=*), intent(in) :: text, part
            type(scene_input_t) :: scene
            type(status_t) :: status
            type(run_result_t) :: result
            logical :: exists
            call parse_scene(text, 'in.nml', scene, status)
            call check(error, status%ok(), 'parse: ' // status%text())
            if (allocated(error)) return
            call run_scene(scene, .true., result, status)
            call check(error, status%code == status_bad_input, 'bad input expected for ' // part)
            call expect(error, status, part)
            inquire (file=h5, exist=exists)
            call check(error, .not. exists, 'no HDF5 file on bad input: ' // part)
            call delete(h5)
        end subroutine refused
    end subroutine test_body_bad_sets

    !> The body as built: materials by element set (box and mesh file), the
    !> load shared by the set's nodes, gravity, the rigid initial velocity.
    subroutine test_body_built(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        class(dae_problem_t), allocatable :: problem
        class(mechanical_problem_t), allocatable, target :: mechanical
        real(wp), allocatable :: y0(:)
        type(block_spec_t), allocatable :: blocks(:)
        real(wp), parameter :: g(3) = [1.0_wp, -2.0_wp, -9.81_wp], load(3) = [3.0_wp, 0.0_wp, &
            -4.0_wp], omega(3) = [0.0_wp, 0.0_wp, 2.0_wp], v0(3) = [1.0_wp, 0.5_wp, 0.0_wp]
        real(wp) :: mass, total(3), w(3)
        integer :: nq, i, k
        call parse_scene(body_scene(', gravity = 1, -2, -9.81, load_set = ''xmax'', ' // &
            'load = 3, 0, -4, initial_velocity = 1, 0.5, 0, initial_angular_velocity = 0, 0, 2', &
            soft() // '&material name = ''tip'', youngs_modulus = 1e5, density = 300, ' // &
            'elements = ''xmax_layer'' /'), 'in.nml', scene, status)
        call check(error, status%ok(), 'parse: ' // status%text())
        if (allocated(error)) return
        call build_problem(scene, problem, y0, blocks, status, mechanical)
        call check(error, status%ok(), 'build: ' // status%text())
        if (allocated(error)) return
        select type (body => mechanical)
        type is (flexible_body_t)
            nq = body%nq
            call check(error, nq == 3 * 16 .and. problem%n == 2 * nq .and. size(y0) == 2 * nq, &
                       'free body: 16 nodes, y = (q, v)')
            call check(error, size(blocks) == 2, 'blocks q and v')
            if (allocated(error)) return
            call check(error, blocks(1)%name == 'q' .and. blocks(1)%first == 1 .and. &
                blocks(1)%last == nq .and. blocks(2)%name == 'v' .and. &
                blocks(2)%first == nq + 1 .and. blocks(2)%last == 2 * nq, 'block ranges')
            call check(error, all(body%element_material == [1, 1, 2]), 'tip layer material')
            call check_close(error, body%materials(2)%density, 300.0_wp, 0.0_wp, 'tip density')
            ! Σ applied = load + m g, m = ρ V (consistent mass rows sum to ∫ ρ N dV)
            mass = 2.0_wp * 100.0_wp + 300.0_wp
            do k = 1, 3
                total(k) = sum(body%applied_force(k:nq:3))
                call check_close(error, total(k), load(k) + mass * g(k), 1.0e-10_wp, &
                                 'total applied force')
            end do
            ! free body: dof(:, i) = 3i−2..3i; v = v0 + ω × (X − centre), centre (1.5, .5, .5)
            do i = 1, 16
                w = v0 + [-omega(3) * (body%mesh%x(2, i) - 0.5_wp), &
                          omega(3) * (body%mesh%x(1, i) - 1.5_wp), 0.0_wp]
                call check(error, all(abs(y0(nq + 3 * i - 2:nq + 3 * i) - w) <= 1.0e-14_wp), &
                           'rigid initial velocity')
                call check(error, all(y0(3 * i - 2:3 * i) == body%mesh%x(:, i)), 'q0 = X')
            end do
        class default
            call check(error, .false., 'mechanical is not a flexible body')
        end select
        if (allocated(error)) return

        ! A mesh file, its own sets: 'body' soft, 'tip_layer' stiff, 'clamp' fixed.
        call parse_scene('&simulation t_end = 1 /' // nl // '&flexible_body mesh_file = ' // &
            '''inputs/meshes/bar_hex8.mesh'', fixed = ''clamp'' /' // nl // &
            '&material youngs_modulus = 7e5, density = 920, elements = ''body'' /' // nl // &
            '&material youngs_modulus = 1e7, density = 1000, elements = ''tip_layer'' /', &
            'in.nml', scene, status)
        call check(error, status%ok(), 'parse mesh-file scene: ' // status%text())
        if (allocated(error)) return
        call build_problem(scene, problem, y0, blocks, status, mechanical)
        call check(error, status%ok(), 'build from mesh file: ' // status%text())
        if (allocated(error)) return
        select type (body => mechanical)
        type is (flexible_body_t)
            call check(error, body%nq == 3 * 16, '4 clamped nodes of 20')
            call check(error, all(body%element_material == [1, 1, 1, 2]), 'mesh-file sets')
        end select
    end subroutine test_body_built

    !> A free, undeformed body with a translational initial velocity under
    !> gravity falls rigidly: every node follows X + v0 t + g t²/2 (no
    !> internal force), which every solver reproduces far below its tolerance
    !> (degree-2 polynomials are exact for its method; measured: RADAU5 9e-16,
    !> MEXAX 8e-13, DDASSL and IDA 2.4e-11); the total energy is conserved.
    subroutine test_body_free_fall(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: solvers(4) = [character(len=6) :: 'radau5', 'ddassl', &
            'ida', 'mexax']
        real(wp), parameter :: g(3) = [0.0_wp, 0.0_wp, -9.81_wp], v0(3) = [1.0_wp, 0.5_wp, &
            2.0_wp]
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(run_result_t) :: result
        type(mesh_t) :: mesh
        character(len=:), allocatable :: h5
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        real(wp) :: err, x(3)
        integer :: s, k, i, nst, nq
        character(len=80) :: line
        call box_mesh(mesh, 8, [3, 1, 1], [3.0_wp, 1.0_wp, 1.0_wp], status)
        nq = 3 * mesh%node_count()
        do s = 1, size(solvers)
            h5 = scratch('free_fall_' // trim(solvers(s)) // '.h5')
            call parse_scene(body_scene(', gravity = 0, 0, -9.81, initial_velocity = 1, 0.5, 2', &
                '&material youngs_modulus = 1e5, density = 100, viscosity = 10 /' // nl // &
                '&solver name = ''' // trim(solvers(s)) // ''', rtol = 1e-6, atol = 1e-6 /' // &
                nl // '&output file = ''' // h5 // ''', n_output = 5 /'), 'in.nml', scene, status)
            call check(error, status%ok(), 'parse: ' // status%text())
            if (allocated(error)) return
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), trim(solvers(s)) // ': ' // status%text())
            if (allocated(error)) return
            call read_series(h5, time, y, q, nst, error)
            call delete(h5)
            ! the XDMF file beside the result (a flexible body), said and removed
            call check(error, result%xdmf_file == xdmf_beside(h5), trim(solvers(s)) // &
                       ': XDMF file ''' // result%xdmf_file // '''')
            call delete(xdmf_beside(h5))
            if (allocated(error)) return
            call check(error, all(shape(q) == [nq, 5]) .and. all(q == y(1:nq, :)), &
                       trim(solvers(s)) // ': /q is y(1:nq) at 5 times')
            if (allocated(error)) return
            err = 0.0_wp
            do k = 1, 5
                do i = 1, mesh%node_count()
                    x = mesh%x(:, i) + v0 * time(k) + 0.5_wp * g * time(k)**2
                    err = max(err, maxval(abs(q(3 * i - 2:3 * i, k) - x)))
                end do
            end do
            write (line, '(a,es9.2,a,es9.2)') trim(solvers(s)) // ': max |q - exact| =', err, &
                ', energy change', result%energy_end(3) - result%energy_start(3)
            print '(4x,a)', trim(line)
            call check(error, err <= 1.0e-9_wp, trim(line))
            call check(error, result%has_energy, 'energies recorded')
            ! (BDF codes: velocities exact to the tolerance only, 1e-10 relative measured)
            call check_close(error, result%energy_end(3), result%energy_start(3), 1.0e-8_wp, &
                             trim(line), rel=.true.)
            call check_close(error, result%energy_start(2), 0.5_wp * 300.0_wp * &
                             sum(v0**2), 1.0e-10_wp, 'initial kinetic energy m |v0|²/2')
        end do
    end subroutine test_body_free_fall

    !> The example input with damping dissipates: the total energy (strain,
    !> kinetic and the potential of gravity) decreases from its start.
    subroutine test_body_cantilever(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(status_t) :: status
        type(run_result_t) :: result
        call read_scene('inputs/flexible_cantilever.nml', scene, status)
        call check(error, status%ok(), 'read: ' // status%text())
        if (allocated(error)) return
        scene%output_file = ''
        scene%t_end = 0.05_wp
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call check(error, result%has_energy, 'energies recorded')
        call check(error, abs(result%energy_start(3)) <= 1.0e-12_wp, 'starts undeformed, at rest')
        call check(error, result%energy_end(1) > 0.0_wp .and. result%energy_end(2) > 0.0_wp, &
                   'it bends and moves')
        call check(error, result%energy_end(3) < result%energy_start(3), 'damping dissipates')
    end subroutine test_body_cantilever

    ! ------------------------------------------------------------------
    ! Helpers
    ! ------------------------------------------------------------------

    subroutine still_evaluate(self, s, y)
        class(still_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        y = self%value
    end subroutine still_evaluate

    function vdp_sim() result(text)
        character(len=:), allocatable :: text
        text = '&simulation problem = ''van_der_pol'', t_end = 2 /' // nl
    end function vdp_sim

    function parse_status(text) result(status)
        character(len=*), intent(in) :: text
        type(status_t) :: status
        type(scene_input_t) :: scene
        call parse_scene(text, 'in.nml', scene, status)
    end function parse_status

    !> Fail unless the status message contains `part`.
    subroutine expect(error, status, part)
        type(error_t), allocatable, intent(inout) :: error
        type(status_t), intent(in) :: status
        character(len=*), intent(in) :: part
        call check(error, .not. status%ok(), 'expected an error containing: ' // part)
        call check(error, index(status%text(), part) > 0, 'message "' // status%text() // &
                   '" lacks "' // part // '"')
    end subroutine expect

    !> A path in the temporary directory, unique to this test process.
    function scratch(name) result(path)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: path
        character(len=:), allocatable, save :: prefix
        character(len=512) :: dir
        integer :: length, stat
        integer(8) :: count
        if (.not. allocated(prefix)) then
            call get_environment_variable('TMPDIR', dir, length, stat)
            if (stat /= 0 .or. length == 0) dir = '/tmp'
            call system_clock(count)
            write (dir, '(a,a,i0,a)') trim(dir), '/flexmbs_test_io_', count, '_'
            prefix = trim(dir)
        end if
        path = prefix // name
    end function scratch

    subroutine write_text(path, text)
        character(len=*), intent(in) :: path, text
        integer :: unit
        open (newunit=unit, file=path, access='stream', form='unformatted', status='replace')
        write (unit) text
        close (unit)
    end subroutine write_text

    function read_text(path) result(text)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: text
        integer :: unit, n, ios
        open (newunit=unit, file=path, access='stream', form='unformatted', status='old', &
              iostat=ios)
        if (ios /= 0) then
            text = ''
            return
        end if
        inquire (unit=unit, size=n)
        allocate (character(len=n) :: text)
        read (unit) text
        close (unit)
    end function read_text

    subroutine delete(path)
        character(len=*), intent(in) :: path
        integer :: unit, ios
        open (newunit=unit, file=path, status='old', iostat=ios)
        if (ios == 0) close (unit, status='delete')
    end subroutine delete

    pure integer function count_char(text, c)
        character(len=*), intent(in) :: text
        character, intent(in) :: c
        integer :: i
        count_char = 0
        do i = 1, len(text)
            if (text(i:i) == c) count_char = count_char + 1
        end do
    end function count_char
end module test_io
