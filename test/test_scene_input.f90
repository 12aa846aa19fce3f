!> Scene input as a user meets it: every error of a file in one message,
!> "did you mean" for misspelt names, a unit after a value named as such,
!> messages bounded whatever the input, tolerances with a floor, the
!> schema consistent with the linear solvers, paths relative to the
!> scene's folder, defaults from the schema.
module test_scene_input
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_files, only: read_text_file
    use flexmbs_linalg_linear_solver, only: linear_solver_names
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_core_text, only: nearest, int_text
    use flexmbs_io_scene_schema, only: schema, kind_real, kind_integer, kind_string, &
        kind_logical, find_var
    use flexmbs_core_rules, only: rule_reason
    use flexmbs_io_input_errors, only: max_errors
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_scene_input

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_scene_input() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('every_error_at_once', test_every_error), &
                 new_test('error_limit', test_error_limit), &
                 new_test('did_you_mean', test_did_you_mean), &
                 new_test('unit_after_value', test_unit_after_value), &
                 new_test('bounded_messages', test_bounded_messages), &
                 new_test('tolerance_floor', test_tolerance_floor), &
                 new_test('rules', test_rules), &
                 new_test('schema_defaults', test_schema_defaults), &
                 new_test('paths_relative_to_scene', test_relative_paths), &
                 new_test('schema_documented', test_schema_documented)]
    end function collect_scene_input

    !> Three mistakes in three groups: three lines, each naming its variable.
    subroutine test_every_error(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse('&simulation problem = ''van_der_pol'', t_end = -1 /' // nl // &
                       '&solver rtol = -1e-6, nitt = 3 /' // nl // &
                       '&output n_output = ''many'' /')
        call check(error, status%code == status_bad_input, 'bad input')
        call expect(error, status, 'in.nml: &solver: rtol = -1e-6: must be positive (line 2)')
        call expect(error, status, 'in.nml: &solver: nitt: unknown variable (did you mean ''nit''?)')
        call expect(error, status, 'in.nml: &output: n_output = ''many'': must be an integer')
        call expect(error, status, 'in.nml: &simulation: t_end = -1: must be greater than &
            &t_start = 0 (line 1)')
        call check(error, lines(status%text()) == 4, 'four messages, one per line: ' // &
                   status%text())
    end subroutine test_every_error

    !> Hundreds of errors: the first max_errors listed, the rest counted.
    subroutine test_error_limit(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        character(len=:), allocatable :: text
        integer :: i
        text = '&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // '&solver'
        do i = 1, 300
            text = text // nl // ' x' // int_text(i) // ' = 1'
        end do
        status = parse(text // ' /')
        call check(error, lines(status%text()) == max_errors + 1, 'listed: ' // &
                   int_text(lines(status%text())))
        call expect(error, status, '... and ' // int_text(300 - max_errors) // ' more errors')
    end subroutine test_error_limit

    subroutine test_did_you_mean(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        call check(error, nearest('rtoll', ['rtol', 'atol', 'h0  ']) == 'rtol', 'rtoll')
        call check(error, nearest('mxa_steps', ['max_steps', 'nit      ']) == 'max_steps', &
                   'transposition and deletion')
        call check(error, nearest('zzzz', ['rtol', 'atol']) == '', 'nothing close')
        status = parse(mechanism('Lnik'))
        call expect(error, status, '&joint: marker_j = ''Lnik'': no &marker of that name &
            &(did you mean ''Link''?) (known: Ground, Link)')
        status = parse('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                       '&solver name = ''Radua5'' /')
        call expect(error, status, '(did you mean ''radau5''?)')
        status = parse('&simulation problem = ''pendulm'', t_end = 1 /')
        call expect(error, status, 'problem = ''pendulm'': must be one of')
        call expect(error, status, '(did you mean ''pendulum''?)')
        status = parse('&simulaton problem = ''pendulum'', t_end = 1 /')
        call expect(error, status, '&simulaton: unknown group (did you mean ''simulation''?)')
    end subroutine test_did_you_mean

    subroutine test_unit_after_value(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        status = parse('&simulation problem = ''pendulum'', t_end = 1' // nl // &
                       '  pendulum_length = 1 m' // nl // '/')
        call expect(error, status, '&simulation: pendulum_length = 1: ''m'' after the value &
            &(a unit?): write the number alone, in m (line 2)')
        call check(error, index(status%text(), 'unknown variable') == 0, 'not an unknown variable')
        call check(error, lines(status%text()) == 1, 'one message: ' // status%text())
        status = parse('&simulation problem = ''pendulum'', t_end = 2 s /')
        call expect(error, status, 't_end = 2: ''s'' after the value (a unit?)')
    end subroutine test_unit_after_value

    !> A 4 MB name and a 4 MB string value: messages of one short line each
    !> (read in linear time: a quadratic reader takes hours here).
    subroutine test_bounded_messages(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        character(len=:), allocatable :: huge_word
        huge_word = repeat('a', 4 * 1024 * 1024)
        status = parse('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                       '&solver ' // huge_word // ' = 1 /')
        call expect(error, status, 'unknown variable')
        call check(error, len(status%text()) < 600, 'short message: ' // int_text(len(status%text())))
        call expect(error, status, '(4194304 characters)')
        status = parse('&simulation problem = ''van_der_pol'', t_end = 1, title = ''' // &
                       huge_word // ''' /')
        call expect(error, status, 'title = ''aaaa')
        call expect(error, status, 'longer than 256 characters')
        call check(error, len(status%text()) < 400, 'short message: ' // int_text(len(status%text())))
    end subroutine test_bounded_messages

    subroutine test_tolerance_floor(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        type(scene_input_t) :: scene
        status = parse('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                       '&solver rtol = 1e-30, atol = 1e-15 /')
        call expect(error, status, '&solver: rtol = 1e-30: must be at least 1e-14')
        call expect(error, status, '&solver: atol = 1e-15: must be at least 1e-14')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                         '&solver rtol = 1e-12, atol = 1e-14 /', 'in.nml', scene, status)
        call check(error, status%ok(), 'tight tolerances stay possible: ' // status%text())
        call check_close(error, scene%rtol, 1.0e-12_wp, 0.0_wp, 'rtol read')
        ! a solver's own refusal named in the scene's terms
        status = parse('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                       '&solver name = ''ida'', linear_solver = ''band'' /')
        call expect(error, status, 'in.nml: &solver: linear_solver = ''band'': ''band'' is &
            &offered with radau5 and ddassl only (ida: ''auto'', ''dense'' or ''klu'') (line 2)')
    end subroutine test_tolerance_floor

    subroutine test_rules(error)
        type(error_t), allocatable, intent(out) :: error
        call check(error, rule_reason('positive', 0.0_wp, .false.) == 'must be positive', '> 0')
        call check(error, rule_reason('positive', 1.0e-300_wp, .false.) == '', 'tiny positive')
        call check(error, rule_reason('(-1,0.5)', 0.5_wp, .false.) == 'must lie in (-1, 0.5)', &
                   'open interval: ' // rule_reason('(-1,0.5)', 0.5_wp, .false.))
        call check(error, rule_reason('(-1,0.5)', 0.4999_wp, .false.) == '', 'inside')
        call check(error, rule_reason('[1,12]', 13.0_wp, .true.) == 'must lie in 1..12', &
                   'integer range')
        call check(error, rule_reason('[2,inf)', 1.0_wp, .true.) == 'must be at least 2', &
                   'lower bound')
        call check(error, rule_reason('(-inf,1)', 1.0_wp, .false.) == 'must be less than 1', &
                   'upper bound')
        call check(error, rule_reason('tolerance', 1.0_wp, .false.) == 'must be less than 1', &
                   'relative tolerance below 1')
    end subroutine test_rules

    !> Every default reads as its kind and meets its own rule and choices;
    !> the linear solvers the schema documents are the library's.
    subroutine test_schema_defaults(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        type(scene_input_t) :: scene
        integer :: i, ios, m(4)
        real(wp) :: x(4)
        character(len=:), allocatable :: why
        do i = 1, size(schema)
            associate (s => schema(i))
                if (len_trim(s%default) == 0) cycle
                select case (s%kind)
                case (kind_real)
                    read (s%default, *, iostat=ios) x(1:s%count)
                    call check(error, ios == 0, trim(s%name) // ': default reads')
                    if (len_trim(s%rule) > 0 .and. ios == 0 .and. s%name /= 'lengths') then
                        why = rule_reason(trim(s%rule), x(1), .false.)
                        call check(error, len(why) == 0, trim(s%name) // ': default ' // why)
                    end if
                case (kind_integer)
                    read (s%default, *, iostat=ios) m(1:s%count)
                    call check(error, ios == 0, trim(s%name) // ': default reads')
                case (kind_logical)
                    call check(error, s%default == '.true.' .or. s%default == '.false.', &
                               trim(s%name) // ': default logical')
                case (kind_string)
                    if (len_trim(s%choices) > 0) call check(error, index('|' // &
                        trim(s%choices) // '|', '|' // trim(s%default) // '|') > 0, &
                        trim(s%name) // ': default among the choices')
                end select
            end associate
        end do
        do i = 1, size(linear_solver_names)
            call check(error, index(schema(find_var('solver', 'linear_solver'))%doc, &
                       trim(linear_solver_names(i))) > 0, 'documented: ' // linear_solver_names(i))
        end do
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /', 'in.nml', &
                         scene, status)
        call check(error, status%ok(), status%text())
        call check(error, scene%solver_name == 'radau5' .and. scene%max_steps == 100000 .and. &
                   scene%n_output == 101 .and. scene%progress .and. .not. scene%every_step, &
                   'defaults from the schema')
        call check_close(error, scene%multibody%gravity(2), -9.81_wp, 0.0_wp, 'gravity default')
        call check_close(error, scene%pendulum_angle, 2.0_wp * atan(1.0_wp), 1.0e-15_wp, &
                         'pendulum angle default')
    end subroutine test_schema_defaults

    subroutine test_relative_paths(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        type(scene_input_t) :: scene
        character(len=*), parameter :: dir = 'build/test-scene-input/a/'
        call execute_command_line('mkdir -p ' // dir // 'out')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                         '&output file = ''out/r.h5'', table = ''t.csv'', vtk = ''/tmp/p'' /', &
                         dir // 's.nml', scene, status)
        call check(error, status%ok(), status%text())
        call check(error, scene%output_file == dir // 'out/r.h5', 'file: ' // scene%output_file)
        call check(error, scene%table == dir // 't.csv', 'table: ' // trim(scene%table))
        call check(error, scene%vtk == '/tmp/p', 'absolute kept: ' // trim(scene%vtk))
        ! a folder that does not exist: bad input while reading, not after the run
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /' // nl // &
                         '&output file = ''nowhere/r.h5'' /', dir // 's.nml', scene, status)
        call expect(error, status, '&output: file = ''nowhere/r.h5'': the folder ''' // dir // &
                    'nowhere/'' does not exist')
        call parse_scene('&simulation problem = ''van_der_pol'', t_end = 1 /', &
                         dir // 's.nml', scene, status)
        call check(error, scene%output_file == 's.h5', 'default in the working directory: ' // &
                   scene%output_file)
    end subroutine test_relative_paths

    !> Every variable of the schema is in the scene reference of docs/.
    subroutine test_schema_documented(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        character(len=:), allocatable :: readme
        integer :: i
        call read_text_file('docs/scene_reference.md', readme, status)
        call check(error, status%ok(), 'docs/scene_reference.md: ' // status%text())
        if (allocated(error)) return
        do i = 1, size(schema)
            call check(error, index(readme, '`' // trim(schema(i)%name) // '`') > 0, &
                       'docs/scene_reference.md lacks &' // trim(schema(i)%group) // ' ' // trim(schema(i)%name))
        end do
    end subroutine test_schema_documented

    ! ------------------------------------------------------------------

    function mechanism(target) result(text)
        character(len=*), intent(in) :: target
        character(len=:), allocatable :: text
        text = '&simulation t_end = 1 /' // nl // &
            '&rigid_body name = ''B'', mass = 1, inertia = 1, 1, 1 /' // nl // &
            '&marker name = ''Ground'' /' // nl // &
            '&marker name = ''Link'', body = ''B'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''Ground'', marker_j = ''' // target // &
            ''' /'
    end function mechanism

    function parse(text) result(status)
        character(len=*), intent(in) :: text
        type(status_t) :: status
        type(scene_input_t) :: scene
        call parse_scene(text, 'in.nml', scene, status)
    end function parse

    subroutine expect(error, status, part)
        type(error_t), allocatable, intent(inout) :: error
        type(status_t), intent(in) :: status
        character(len=*), intent(in) :: part
        character(len=:), allocatable :: text
        text = status%text()
        call check(error, .not. status%ok(), 'expected an error containing: ' // part)
        call check(error, index(text, part) > 0, 'message "' // text(1:min(2000, len(text))) &
                   // '" lacks "' // part // '"')
    end subroutine expect

    pure integer function lines(text)
        character(len=*), intent(in) :: text
        integer :: i
        lines = 1
        do i = 1, len(text)
            if (text(i:i) == nl) lines = lines + 1
        end do
    end function lines

end module test_scene_input
