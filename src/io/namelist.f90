!> Scene input: the namelist groups `&simulation`, `&solver`, `&output`,
!> and for a flexible body `&flexible_body` and `&material` (repeatable).
!>
!> The text is checked before Fortran namelist I/O reads it, because the
!> compiler's own namelist errors name neither the variable nor the value.
!> A small tokeniser walks every group, rejects unknown groups and
!> variables and values of the wrong type; the validated text of each group
!> is then read with `read(..., nml=...)`, and ranges are checked on the
!> typed values. Every problem yields one `status_t` whose message names
!> file, group, variable, value and reason, e.g.
!> `inputs/x.nml: &solver: rtol = -1e-6: must be positive (line 7)`.
module flexmbs_io_namelist
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_files, only: read_text_file
    use flexmbs_core_text, only: lower
    use flexmbs_dae_options, only: dae_options_t
    implicit none
    private

    integer, parameter :: kind_string = 1, kind_real = 2, kind_integer = 3, kind_logical = 4
    integer, parameter :: len_title = 256, len_name = 32, len_path = 512

    !> One variable of the schema.
    type :: var_spec_t
        character(len=16) :: group
        character(len=24) :: name
        integer :: kind
        integer :: count = 1 !! values: 1, or the fixed size of an array
    end type var_spec_t

    type(var_spec_t), parameter :: schema(*) = [ &
        var_spec_t('simulation', 'title', kind_string), &
        var_spec_t('simulation', 'problem', kind_string), &
        var_spec_t('simulation', 't_start', kind_real), &
        var_spec_t('simulation', 't_end', kind_real), &
        var_spec_t('simulation', 'vdp_eps', kind_real), &
        var_spec_t('simulation', 'vdp_y1', kind_real), &
        var_spec_t('simulation', 'vdp_y2', kind_real), &
        var_spec_t('simulation', 'pendulum_formulation', kind_string), &
        var_spec_t('simulation', 'pendulum_length', kind_real), &
        var_spec_t('simulation', 'pendulum_mass', kind_real), &
        var_spec_t('simulation', 'pendulum_angle', kind_real), &
        var_spec_t('simulation', 'pendulum_projection', kind_logical), &
        var_spec_t('simulation', 'gravity', kind_real), &
        var_spec_t('simulation', 'npoints', kind_integer), &
        var_spec_t('solver', 'name', kind_string), &
        var_spec_t('solver', 'rtol', kind_real), &
        var_spec_t('solver', 'atol', kind_real), &
        var_spec_t('solver', 'h0', kind_real), &
        var_spec_t('solver', 'hmax', kind_real), &
        var_spec_t('solver', 'max_steps', kind_integer), &
        var_spec_t('solver', 'linear_solver', kind_string), &
        var_spec_t('solver', 'sparse_ordering', kind_string), &
        var_spec_t('solver', 'jacobian', kind_string), &
        var_spec_t('solver', 'nit', kind_integer), &
        var_spec_t('solver', 'thet', kind_real), &
        var_spec_t('solver', 'fnewt', kind_real), &
        var_spec_t('solver', 'quot1', kind_real), &
        var_spec_t('solver', 'quot2', kind_real), &
        var_spec_t('solver', 'safe', kind_real), &
        var_spec_t('solver', 'fac_min', kind_real), &
        var_spec_t('solver', 'fac_max', kind_real), &
        var_spec_t('solver', 'controller', kind_string), &
        var_spec_t('solver', 'zero_start', kind_logical), &
        var_spec_t('solver', 'pmax', kind_integer), &
        var_spec_t('solver', 'initial_derivative', kind_logical), &
        var_spec_t('solver', 'exclude_index23', kind_logical), &
        var_spec_t('solver', 'netlib', kind_logical), &
        var_spec_t('solver', 'max_extrapolation', kind_integer), &
        var_spec_t('solver', 'mexax_base', kind_string), &
        var_spec_t('output', 'file', kind_string), &
        var_spec_t('output', 'n_output', kind_integer), &
        var_spec_t('output', 'every_step', kind_logical), &
        var_spec_t('output', 'table', kind_string), &
        var_spec_t('output', 'progress', kind_logical), &
        var_spec_t('flexible_body', 'name', kind_string), &
        var_spec_t('flexible_body', 'element', kind_string), &
        var_spec_t('flexible_body', 'mesh_file', kind_string), &
        var_spec_t('flexible_body', 'divisions', kind_integer, 3), &
        var_spec_t('flexible_body', 'lengths', kind_real, 3), &
        var_spec_t('flexible_body', 'origin', kind_real, 3), &
        var_spec_t('flexible_body', 'fixed', kind_string), &
        var_spec_t('flexible_body', 'load_set', kind_string), &
        var_spec_t('flexible_body', 'load', kind_real, 3), &
        var_spec_t('flexible_body', 'gravity', kind_real, 3), &
        var_spec_t('flexible_body', 'velocity', kind_real, 3), &
        var_spec_t('flexible_body', 'angular_velocity', kind_real, 3), &
        var_spec_t('material', 'name', kind_string), &
        var_spec_t('material', 'young', kind_real), &
        var_spec_t('material', 'poisson', kind_real), &
        var_spec_t('material', 'density', kind_real), &
        var_spec_t('material', 'viscosity', kind_real), &
        var_spec_t('material', 'elements', kind_string)]

    character(len=16), parameter :: group_names(*) = [character(len=16) :: &
        'simulation', 'solver', 'output', 'flexible_body', 'material']
    !> Groups that may be given more than once (one entry each).
    character(len=16), parameter :: repeatable_groups(*) = [character(len=16) :: 'material']

    !> Problem names the schema accepts (the scene builder says which exist).
    character(len=16), parameter, public :: problem_names(*) = [character(len=16) :: &
        'van_der_pol', 'pendulum', 'robertson', 'brusselator_1d', 'brusselator_2d', &
        'flexible_body']
    character(len=8), parameter, public :: formulation_names(*) = [character(len=8) :: &
        'index3', 'index2', 'index1', 'ggl']

    !> π/2: the pendulum starts horizontal by default.
    real(wp), parameter :: half_pi = 1.5707963267948966_wp

    !> One `&material` group: the paper's neo-Hookean law with damping.
    type, public :: material_input_t
        character(len=len_name) :: name = ''
        real(wp) :: young = 0.0_wp      !! E [Pa], required
        real(wp) :: poisson = 0.3_wp    !! ν
        real(wp) :: density = 0.0_wp    !! ρ [kg/m³], required
        real(wp) :: viscosity = 0.0_wp  !! η [Pa·s]
        character(len=len_name) :: elements = 'all' !! element set it applies to
        integer :: line = 0             !! where the group starts (messages)
    end type material_input_t

    !> The `&flexible_body` group: a box mesh or a mesh file, supports,
    !> loads and a rigid initial velocity field.
    type, public :: body_input_t
        logical :: given = .false.
        character(len=len_name) :: name = 'body'
        character(len=len_name) :: element = 'hex8'
        character(len=len_path) :: mesh_file = ''       !! '' = box mesh
        integer :: divisions(3) = [4, 1, 1]
        real(wp) :: lengths(3) = [1.0_wp, 0.1_wp, 0.1_wp] !! m
        real(wp) :: origin(3) = 0.0_wp                    !! m
        character(len=len_name) :: fixed = ''             !! node set held at X
        character(len=len_name) :: load_set = ''          !! node set carrying `load`
        real(wp) :: load(3) = 0.0_wp                      !! N, total, equal per node
        real(wp) :: gravity(3) = 0.0_wp                   !! m/s²
        real(wp) :: velocity(3) = 0.0_wp                  !! m/s, of the centroid
        real(wp) :: angular_velocity(3) = 0.0_wp          !! rad/s, about the centroid
    end type body_input_t

    !> Everything a scene file says, with defaults for what it leaves out.
    type, public :: scene_input_t
        character(len=:), allocatable :: path !! the file read
        character(len=:), allocatable :: text !! its full text (stored in the HDF5 file)
        ! &simulation
        character(len=len_title) :: title = ''
        character(len=len_name) :: problem = ''
        real(wp) :: t_start = 0.0_wp          !! s
        real(wp) :: t_end = 0.0_wp            !! s, required, > t_start
        real(wp) :: vdp_eps = 1.0e-6_wp
        real(wp) :: vdp_y1 = 2.0_wp
        real(wp) :: vdp_y2 = -0.66_wp
        character(len=len_name) :: pendulum_formulation = 'index2'
        real(wp) :: pendulum_length = 1.0_wp  !! m
        real(wp) :: pendulum_mass = 1.0_wp    !! kg
        real(wp) :: pendulum_angle = half_pi  !! rad from the downward vertical, at rest
        logical :: pendulum_projection = .false. !! project onto both constraints
        real(wp) :: gravity = 9.81_wp         !! m/s²
        integer :: npoints = 100              !! grid points per direction (Brusselator)
        ! &solver
        character(len=len_name) :: solver_name = 'radau5'
        real(wp) :: rtol = 1.0e-6_wp
        real(wp) :: atol = 1.0e-6_wp
        real(wp) :: h0 = 0.0_wp               !! s, 0 = automatic
        real(wp) :: hmax = 0.0_wp             !! s, 0 = |t_end - t_start|
        integer :: max_steps = 100000
        character(len=len_name) :: linear_solver = 'auto'
        character(len=len_name) :: sparse_ordering = 'auto' !! KLU: 'auto' | 'amd' | 'nd'
        character(len=len_name) :: jacobian = 'analytic'
        integer :: nit = 7
        real(wp) :: thet = 0.001_wp
        real(wp) :: fnewt = 0.0_wp            !! 0 = the solver's default
        real(wp) :: quot1 = 1.0_wp
        real(wp) :: quot2 = 1.2_wp
        real(wp) :: safe = 0.9_wp
        real(wp) :: fac_min = 0.2_wp
        real(wp) :: fac_max = 8.0_wp
        character(len=len_name) :: controller = 'predictive'
        logical :: zero_start = .false.
        integer :: pmax = 5
        logical :: initial_derivative = .false. !! DDASSL: y' by DDAINI
        logical :: exclude_index23 = .true.     !! DDASSL: index-2/3 out of the error test
        logical :: netlib = .false.             !! DDASSL: later netlib revision
        integer :: max_extrapolation = 12       !! MEXAX: extrapolation columns (KDMAX), 2..12
        character(len=len_name) :: mexax_base = 'midpoint' !! MEXAX: 'midpoint' | 'euler'
        ! &output
        !> HDF5 file; '' = none. Derived from the input name when not given.
        character(len=:), allocatable :: output_file
        integer :: n_output = 101
        logical :: every_step = .false.
        character(len=len_path) :: table = ''
        logical :: progress = .true.
        ! &flexible_body, &material
        type(body_input_t) :: body
        type(material_input_t), allocatable :: materials(:)
    end type scene_input_t

    !> One `name = value` of the text.
    type :: entry_t
        character(len=:), allocatable :: group, name, value
        integer :: line = 0
        logical :: quoted = .false.  !! (of every value, for arrays)
        integer :: occurrence = 1    !! which instance of a repeatable group
    end type entry_t

    !> Text span [first, last] of a group, from '&name' to its closing '/'.
    type :: span_t
        integer :: group = 0, first = 0, last = 0, line = 0
        integer :: occurrence = 1
    end type span_t

    public :: read_scene, parse_scene, scene_dae_options, controller_code

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

    !> Validate and read scene text; `path` is used in messages and for the
    !> default output name.
    subroutine parse_scene(text, path, scene, status)
        character(len=*), intent(in) :: text      !! the whole file
        character(len=*), intent(in) :: path      !! where it came from
        type(scene_input_t), intent(out) :: scene
        type(status_t), intent(out) :: status
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        character(len=:), allocatable :: clean
        integer :: k

        scene%path = path
        scene%text = text
        allocate (scene%materials(0))
        call tokenise(text, path, entries, spans, clean, status)
        if (.not. status%ok()) return
        call check_types(entries, path, status)
        if (.not. status%ok()) return
        do k = 1, size(spans)
            select case (group_names(spans(k)%group))
            case ('flexible_body')
                call read_body_group(clean(spans(k)%first:spans(k)%last), path, scene, status)
            case ('material')
                call read_material_group(clean(spans(k)%first:spans(k)%last), path, &
                                         spans(k)%line, scene, status)
            case default
                call read_group(clean(spans(k)%first:spans(k)%last), &
                                trim(group_names(spans(k)%group)), path, scene, status)
            end select
            if (.not. status%ok()) return
        end do
        call normalise(scene)
        call check_ranges(scene, entries, path, status)
        if (.not. status%ok()) return
        call check_body_ranges(scene, entries, path, status)
        if (.not. status%ok()) return
        call resolve_output(scene, entries, path, status)
    end subroutine parse_scene

    ! ------------------------------------------------------------------
    ! Tokenising: find groups, names and raw values, with line numbers.
    ! ------------------------------------------------------------------

    !> Walk the text; return the `name = value` entries, each group's span
    !> in `clean` (the text with comments blanked, same length).
    subroutine tokenise(text, path, entries, spans, clean, status)
        character(len=*), intent(in) :: text, path
        type(entry_t), allocatable, intent(out) :: entries(:)
        type(span_t), allocatable, intent(out) :: spans(:)
        character(len=:), allocatable, intent(out) :: clean
        type(status_t), intent(inout) :: status
        integer :: pos, line, g, n, first, vline, occurrence, glines, k, nvalues
        character(len=:), allocatable :: word, group, name, value, previous, more
        logical :: quoted, more_quoted

        allocate (entries(0), spans(0))
        clean = blank_comments(text)
        n = len(clean)
        pos = 1
        line = 1
        do
            ! outside any group
            call skip_blank(clean, pos, line)
            if (pos > n) exit
            if (clean(pos:pos) /= '&') then
                word = bare_word(clean, pos)
                call status%set(status_bad_input, path // ': unexpected text ''' // word // &
                    ''' outside a group (groups start with &name and end with /)' // at(line))
                return
            end if
            first = pos
            pos = pos + 1
            group = lower(name_word(clean, pos))
            g = find_group(group)
            if (g == 0) then
                call status%set(status_bad_input, path // ': &' // group // &
                    ': unknown group (expected ' // group_list() // ')' // at(line))
                return
            end if
            occurrence = count(spans%group == g) + 1
            if (occurrence > 1 .and. all(repeatable_groups /= group)) then
                call status%set(status_bad_input, path // ': &' // group // &
                    ': group given more than once' // at(line))
                return
            end if
            glines = line
            previous = ''
            do
                ! inside group `group`
                call skip_blank(clean, pos, line)
                if (pos > n) then
                    call status%set(status_bad_input, path // ': &' // group // &
                        ': not closed by ''/''' // at(line))
                    return
                end if
                if (clean(pos:pos) == '/') then
                    pos = pos + 1
                    exit
                end if
                if (clean(pos:pos) == '&') then
                    pos = pos + 1
                    word = lower(name_word(clean, pos))
                    if (word == 'end') exit
                    call status%set(status_bad_input, path // ': &' // group // &
                        ': not closed by ''/'' before &' // word // at(line))
                    return
                end if
                if (clean(pos:pos) == ',' .and. len(previous) > 0) then
                    pos = pos + 1
                    cycle
                end if
                if (.not. is_letter(clean(pos:pos))) then
                    word = bare_word(clean, pos)
                    if (len(previous) > 0) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            previous // ': unexpected ''' // word // &
                            ''' after its value (one value per variable)' // at(line))
                    else
                        call status%set(status_bad_input, path // ': &' // group // &
                            ': unexpected ''' // word // ''' (expected name = value)' // at(line))
                    end if
                    return
                end if
                name = lower(variable_word(clean, pos))
                if (find_var(group, name) == 0) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': unknown variable (known: ' // known_vars(group) // ')' // at(line))
                    return
                end if
                if (has_entry(entries, group, name, occurrence)) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': given more than once' // at(line))
                    return
                end if
                call skip_blank(clean, pos, line)
                if (pos > n) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': expected ''='' after the name' // at(line))
                    return
                end if
                if (clean(pos:pos) /= '=') then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': expected ''='' after the name' // at(line))
                    return
                end if
                pos = pos + 1
                call skip_blank(clean, pos, line)
                vline = line
                if (pos > n) then
                    value = ''
                else if (scan(clean(pos:pos), ',/&') > 0) then
                    value = ''
                else
                    call value_word(clean, pos, value, quoted, status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ' = ' // value // ': unterminated string' // at(vline))
                        return
                    end if
                end if
                if (len(value) == 0) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': has no value' // at(vline))
                    return
                end if
                ! An array variable takes exactly its count of values.
                nvalues = schema(find_var(group, name))%count
                do k = 2, nvalues
                    call skip_blank(clean, pos, line)
                    more = ''
                    if (pos <= n) then
                        if (clean(pos:pos) == ',') then
                            pos = pos + 1
                            call skip_blank(clean, pos, line)
                            if (pos <= n) then
                                if (scan(clean(pos:pos), ',/&') == 0) &
                                    call value_word(clean, pos, more, more_quoted, status)
                            end if
                        end if
                    end if
                    if (.not. status%ok() .or. len(more) == 0) then
                        call status%clear()
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ': needs ' // itoa(nvalues) // ' values separated by ' // &
                            'commas' // at(vline))
                        return
                    end if
                    value = value // ', ' // more
                    quoted = quoted .and. more_quoted
                end do
                entries = [entries, entry_t(group, name, value, vline, quoted, occurrence)]
                previous = name
            end do
            spans = [spans, span_t(g, first, pos - 1, glines, occurrence)]
        end do
    end subroutine tokenise

    !> The text with every comment ('!' outside a string, to the end of
    !> its line) replaced by blanks; positions and newlines are kept.
    pure function blank_comments(text) result(clean)
        character(len=*), intent(in) :: text
        character(len=len(text)) :: clean
        integer :: i
        character :: quote
        logical :: comment
        clean = text
        quote = ' '
        comment = .false.
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                comment = .false.
                quote = ' '
            else if (comment) then
                clean(i:i) = ' '
            else if (quote /= ' ') then
                if (text(i:i) == quote) quote = ' '
            else if (text(i:i) == '''' .or. text(i:i) == '"') then
                quote = text(i:i)
            else if (text(i:i) == '!') then
                comment = .true.
                clean(i:i) = ' '
            end if
        end do
    end function blank_comments

    !> Skip blanks, tabs, carriage returns and newlines, counting lines.
    pure subroutine skip_blank(text, pos, line)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line
        do while (pos <= len(text))
            if (text(pos:pos) == new_line('a')) then
                line = line + 1
            else if (.not. is_space(text(pos:pos))) then
                exit
            end if
            pos = pos + 1
        end do
    end subroutine skip_blank

    !> A Fortran name (letters, digits, '_') starting at pos.
    function name_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable :: word
        integer :: start
        start = pos
        do while (pos <= len(text))
            if (.not. (is_letter(text(pos:pos)) .or. is_digit(text(pos:pos)) &
                       .or. text(pos:pos) == '_')) exit
            pos = pos + 1
        end do
        word = text(start:pos - 1)
    end function name_word

    !> A variable designator: a name, possibly with a subscript or
    !> component, so that `y0(1)` is reported whole as unknown.
    function variable_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable :: word
        integer :: start
        start = pos
        do while (pos <= len(text))
            if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
            if (scan(text(pos:pos), '=,/&''"') > 0) exit
            pos = pos + 1
        end do
        word = text(start:pos - 1)
    end function variable_word

    !> Anything up to the next separator (for messages about stray text).
    function bare_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(in) :: pos
        character(len=:), allocatable :: word
        integer :: last
        last = pos
        do while (last < len(text))
            if (is_space(text(last + 1:last + 1)) .or. text(last + 1:last + 1) == new_line('a') &
                .or. scan(text(last + 1:last + 1), ',/=') > 0) exit
            last = last + 1
        end do
        word = text(pos:last)
    end function bare_word

    !> One value: a quoted string (quotes doubled inside) or a bare token
    !> ending at a blank, ',', '/' or end of line. Sets status (message
    !> filled by the caller) when a string is not closed on its line.
    subroutine value_word(text, pos, value, quoted, status)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable, intent(out) :: value
        logical, intent(out) :: quoted
        type(status_t), intent(inout) :: status
        integer :: start
        character :: quote
        start = pos
        quoted = text(pos:pos) == '''' .or. text(pos:pos) == '"'
        if (quoted) then
            quote = text(pos:pos)
            pos = pos + 1
            do
                if (pos > len(text)) exit
                if (text(pos:pos) == new_line('a')) exit
                if (text(pos:pos) == quote) then
                    if (pos < len(text)) then
                        if (text(pos + 1:pos + 1) == quote) then
                            pos = pos + 2
                            cycle
                        end if
                    end if
                    pos = pos + 1
                    value = text(start:pos - 1)
                    return
                end if
                pos = pos + 1
            end do
            value = text(start:pos - 1)
            call status%set(status_bad_input, 'unterminated string')
            return
        end if
        do while (pos <= len(text))
            if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
            if (scan(text(pos:pos), ',/') > 0) exit
            pos = pos + 1
        end do
        value = text(start:pos - 1)
    end subroutine value_word

    ! ------------------------------------------------------------------
    ! Types: check each raw value against its variable's kind.
    ! ------------------------------------------------------------------

    subroutine check_types(entries, path, status)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: i, first, comma, k
        character(len=:), allocatable :: reason

        do i = 1, size(entries)
            associate (e => entries(i))
                k = schema(find_var(e%group, e%name))%kind
                ! Array values were joined as 'a, b, c' (numbers only).
                first = 1
                do
                    comma = 0
                    if (schema(find_var(e%group, e%name))%count > 1) &
                        comma = index(e%value(first:), ',')
                    if (comma == 0) then
                        reason = value_reason(k, e%name, trim(adjustl(e%value(first:))), &
                                              e%quoted)
                    else
                        reason = value_reason(k, e%name, &
                            trim(adjustl(e%value(first:first + comma - 2))), e%quoted)
                    end if
                    if (len(reason) > 0 .or. comma == 0) exit
                    first = first + comma
                end do
                if (len(reason) > 0) then
                    call fail(status, path, e, reason)
                    return
                end if
            end associate
        end do
    end subroutine check_types

    !> Why one raw value does not fit its variable's kind ('' if it does).
    function value_reason(k, name, value, quoted) result(reason)
        integer, intent(in) :: k
        character(len=*), intent(in) :: name, value
        logical, intent(in) :: quoted
        character(len=:), allocatable :: reason
        integer :: ios, m
        real(wp) :: x
        type(ieee_status_type) :: fp_status
        reason = ''
        select case (k)
        case (kind_string)
            if (.not. quoted) then
                reason = 'must be a quoted string, e.g. ' // name // ' = ''' // value // ''''
            else if (len(unquote(value)) > string_length(name)) then
                reason = 'longer than ' // itoa(string_length(name)) // ' characters'
            end if
        case (kind_real)
            if (quoted .or. .not. is_real_text(value)) then
                reason = 'must be a real number'
            else
                ! an overflowing value must not leave the overflow flag raised
                call ieee_get_status(fp_status)
                read (value, *, iostat=ios) x
                call ieee_set_status(fp_status)
                if (ios /= 0) then
                    reason = 'is out of the range of real numbers'
                else if (.not. ieee_is_finite(x)) then
                    reason = 'is out of the range of real numbers'
                end if
            end if
        case (kind_integer)
            if (quoted .or. .not. is_integer_text(value)) then
                reason = 'must be an integer'
            else
                read (value, *, iostat=ios) m
                if (ios /= 0) reason = 'is out of the range of integers'
            end if
        case (kind_logical)
            if (quoted .or. .not. is_logical_text(value)) then
                reason = 'must be .true. or .false.'
            end if
        end select
    end function value_reason

    pure logical function is_integer_text(s)
        character(len=*), intent(in) :: s
        integer :: i, start
        is_integer_text = .false.
        start = 1
        if (len(s) == 0) return
        if (s(1:1) == '+' .or. s(1:1) == '-') start = 2
        if (start > len(s)) return
        do i = start, len(s)
            if (.not. is_digit(s(i:i))) return
        end do
        is_integer_text = .true.
    end function is_integer_text

    !> [sign] digits [. digits] [e|d [sign] digits], at least one mantissa digit.
    pure logical function is_real_text(s)
        character(len=*), intent(in) :: s
        integer :: i, ndig
        is_real_text = .false.
        i = 1
        ndig = 0
        if (len(s) == 0) return
        if (s(1:1) == '+' .or. s(1:1) == '-') i = 2
        do while (i <= len(s))
            if (.not. is_digit(s(i:i))) exit
            ndig = ndig + 1
            i = i + 1
        end do
        if (i <= len(s)) then
            if (s(i:i) == '.') then
                i = i + 1
                do while (i <= len(s))
                    if (.not. is_digit(s(i:i))) exit
                    ndig = ndig + 1
                    i = i + 1
                end do
            end if
        end if
        if (ndig == 0) return
        if (i <= len(s)) then
            if (index('eEdD', s(i:i)) == 0) return
            i = i + 1
            if (i <= len(s)) then
                if (s(i:i) == '+' .or. s(i:i) == '-') i = i + 1
            end if
            if (i > len(s)) return
            do while (i <= len(s))
                if (.not. is_digit(s(i:i))) return
                i = i + 1
            end do
        end if
        is_real_text = .true.
    end function is_real_text

    pure logical function is_logical_text(s)
        character(len=*), intent(in) :: s
        character(len=8), parameter :: forms(*) = [character(len=8) :: '.true.', '.false.', &
            '.t.', '.f.', '.t', '.f', 't', 'f', 'true', 'false']
        is_logical_text = any(forms == lower(s))
    end function is_logical_text

    !> Declared length of a string variable.
    pure integer function string_length(name)
        character(len=*), intent(in) :: name
        select case (name)
        case ('title'); string_length = len_title
        case ('file', 'table', 'mesh_file'); string_length = len_path
        case default; string_length = len_name
        end select
    end function string_length

    ! ------------------------------------------------------------------
    ! Reading: the validated text of one group through namelist I/O.
    ! ------------------------------------------------------------------

    subroutine read_group(text, group, path, scene, status)
        character(len=*), intent(in) :: text  !! '&group ... /', comments blanked
        character(len=*), intent(in) :: group, path
        type(scene_input_t), intent(inout) :: scene
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        ! Namelist variables carry the schema's names, so they are local.
        character(len=len_title) :: title
        character(len=len_name) :: problem, pendulum_formulation, name, linear_solver, &
            jacobian, controller, mexax_base, sparse_ordering
        character(len=len_path) :: file, table
        real(wp) :: t_start, t_end, vdp_eps, vdp_y1, vdp_y2, pendulum_length, pendulum_mass, &
            pendulum_angle, gravity, rtol, atol, h0, hmax, thet, fnewt, &
            quot1, quot2, safe, fac_min, fac_max
        integer :: npoints, max_steps, nit, pmax, n_output, max_extrapolation
        logical :: pendulum_projection, zero_start, every_step, progress
        logical :: initial_derivative, exclude_index23, netlib
        namelist /simulation/ title, problem, t_start, t_end, vdp_eps, vdp_y1, vdp_y2, &
            pendulum_formulation, pendulum_length, pendulum_mass, pendulum_angle, &
            pendulum_projection, gravity, npoints
        namelist /solver/ name, rtol, atol, h0, hmax, max_steps, linear_solver, &
            sparse_ordering, jacobian, &
            nit, thet, fnewt, quot1, quot2, safe, fac_min, fac_max, controller, zero_start, pmax, &
            initial_derivative, exclude_index23, netlib, max_extrapolation, mexax_base
        namelist /output/ file, n_output, every_step, table, progress

        lines = split_lines(text)
        ios = 0
        msg = ''
        select case (group)
        case ('simulation')
            title = scene%title
            problem = scene%problem
            t_start = scene%t_start
            t_end = scene%t_end
            vdp_eps = scene%vdp_eps
            vdp_y1 = scene%vdp_y1
            vdp_y2 = scene%vdp_y2
            pendulum_formulation = scene%pendulum_formulation
            pendulum_length = scene%pendulum_length
            pendulum_mass = scene%pendulum_mass
            pendulum_angle = scene%pendulum_angle
            pendulum_projection = scene%pendulum_projection
            gravity = scene%gravity
            npoints = scene%npoints
            read (lines, nml=simulation, iostat=ios, iomsg=msg)
            scene%title = title
            scene%problem = problem
            scene%t_start = t_start
            scene%t_end = t_end
            scene%vdp_eps = vdp_eps
            scene%vdp_y1 = vdp_y1
            scene%vdp_y2 = vdp_y2
            scene%pendulum_formulation = pendulum_formulation
            scene%pendulum_length = pendulum_length
            scene%pendulum_mass = pendulum_mass
            scene%pendulum_angle = pendulum_angle
            scene%pendulum_projection = pendulum_projection
            scene%gravity = gravity
            scene%npoints = npoints
        case ('solver')
            name = scene%solver_name
            rtol = scene%rtol
            atol = scene%atol
            h0 = scene%h0
            hmax = scene%hmax
            max_steps = scene%max_steps
            linear_solver = scene%linear_solver
            sparse_ordering = scene%sparse_ordering
            jacobian = scene%jacobian
            nit = scene%nit
            thet = scene%thet
            fnewt = scene%fnewt
            quot1 = scene%quot1
            quot2 = scene%quot2
            safe = scene%safe
            fac_min = scene%fac_min
            fac_max = scene%fac_max
            controller = scene%controller
            zero_start = scene%zero_start
            pmax = scene%pmax
            initial_derivative = scene%initial_derivative
            exclude_index23 = scene%exclude_index23
            netlib = scene%netlib
            max_extrapolation = scene%max_extrapolation
            mexax_base = scene%mexax_base
            read (lines, nml=solver, iostat=ios, iomsg=msg)
            scene%solver_name = name
            scene%rtol = rtol
            scene%atol = atol
            scene%h0 = h0
            scene%hmax = hmax
            scene%max_steps = max_steps
            scene%linear_solver = linear_solver
            scene%sparse_ordering = sparse_ordering
            scene%jacobian = jacobian
            scene%nit = nit
            scene%thet = thet
            scene%fnewt = fnewt
            scene%quot1 = quot1
            scene%quot2 = quot2
            scene%safe = safe
            scene%fac_min = fac_min
            scene%fac_max = fac_max
            scene%controller = controller
            scene%zero_start = zero_start
            scene%pmax = pmax
            scene%initial_derivative = initial_derivative
            scene%exclude_index23 = exclude_index23
            scene%netlib = netlib
            scene%max_extrapolation = max_extrapolation
            scene%mexax_base = mexax_base
        case ('output')
            file = ''
            n_output = scene%n_output
            every_step = scene%every_step
            table = scene%table
            progress = scene%progress
            read (lines, nml=output, iostat=ios, iomsg=msg)
            scene%output_file = trim(file)
            scene%n_output = n_output
            scene%every_step = every_step
            scene%table = table
            scene%progress = progress
        end select
        if (ios /= 0) then
            ! Not expected after validation; report what the compiler says.
            call status%set(status_bad_input, path // ': &' // group // ': ' // trim(msg))
        end if
    end subroutine read_group

    !> `&flexible_body` through namelist I/O (its own locals: `gravity` is a
    !> vector here, a scalar in &simulation).
    subroutine read_body_group(text, path, scene, status)
        character(len=*), intent(in) :: text, path
        type(scene_input_t), intent(inout) :: scene
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, element, fixed, load_set
        character(len=len_path) :: mesh_file
        integer :: divisions(3)
        real(wp) :: lengths(3), origin(3), load(3), gravity(3), velocity(3), &
            angular_velocity(3)
        namelist /flexible_body/ name, element, mesh_file, divisions, lengths, origin, fixed, &
            load_set, load, gravity, velocity, angular_velocity
        associate (b => scene%body)
            name = b%name
            element = b%element
            mesh_file = b%mesh_file
            divisions = b%divisions
            lengths = b%lengths
            origin = b%origin
            fixed = b%fixed
            load_set = b%load_set
            load = b%load
            gravity = b%gravity
            velocity = b%velocity
            angular_velocity = b%angular_velocity
            lines = split_lines(text)
            read (lines, nml=flexible_body, iostat=ios, iomsg=msg)
            b%given = .true.
            b%name = name
            b%element = lower(element)
            b%mesh_file = mesh_file
            b%divisions = divisions
            b%lengths = lengths
            b%origin = origin
            b%fixed = fixed
            b%load_set = load_set
            b%load = load
            b%gravity = gravity
            b%velocity = velocity
            b%angular_velocity = angular_velocity
        end associate
        if (ios /= 0) call status%set(status_bad_input, path // ': &flexible_body: ' // trim(msg))
    end subroutine read_body_group

    !> One `&material` group, appended to scene%materials.
    subroutine read_material_group(text, path, line, scene, status)
        character(len=*), intent(in) :: text, path
        integer, intent(in) :: line  !! where the group starts
        type(scene_input_t), intent(inout) :: scene
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        type(material_input_t) :: m
        character(len=len_name) :: name, elements
        real(wp) :: young, poisson, density, viscosity
        namelist /material/ name, young, poisson, density, viscosity, elements
        name = m%name
        young = m%young
        poisson = m%poisson
        density = m%density
        viscosity = m%viscosity
        elements = m%elements
        lines = split_lines(text)
        read (lines, nml=material, iostat=ios, iomsg=msg)
        m%name = name
        m%young = young
        m%poisson = poisson
        m%density = density
        m%viscosity = viscosity
        m%elements = elements
        m%line = line
        if (len_trim(m%name) == 0) m%name = 'material ' // itoa(size(scene%materials) + 1)
        scene%materials = [scene%materials, m]
        if (ios /= 0) call status%set(status_bad_input, path // ': &material: ' // trim(msg))
    end subroutine read_material_group

    !> &flexible_body and &material: present exactly when the problem is a
    !> flexible body; values in range. Set names are checked against the
    !> mesh when the body is built (before any output file exists).
    subroutine check_body_ranges(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=*), parameter :: fb = 'flexible_body', mat = 'material'
        integer :: k
        if (scene%problem /= 'flexible_body') then
            if (scene%body%given .or. size(scene%materials) > 0) &
                call status%set(status_bad_input, path // ': &' // &
                    trim(merge(fb // '   ', mat // '        ', scene%body%given)) // &
                    ': given, but &simulation problem = ''' // trim(scene%problem) // &
                    ''' (a flexible body needs problem = ''flexible_body'')')
            return
        end if
        if (.not. scene%body%given) then
            call status%set(status_bad_input, path // ': &flexible_body: required by ' // &
                            'problem = ''flexible_body''')
        else if (size(scene%materials) == 0) then
            call status%set(status_bad_input, path // ': &material: at least one required ' // &
                            'by problem = ''flexible_body'' (young, density, ...)')
        else if (all([character(len=8) :: 'hex8', 'hex27'] /= scene%body%element)) then
            call bad(fb, 'element', 'must be ''hex8'' or ''hex27''', 1)
        else if (len_trim(scene%body%mesh_file) == 0 .and. any(scene%body%divisions < 1)) then
            call bad(fb, 'divisions', 'must be positive (elements along x, y, z)', 1)
        else if (len_trim(scene%body%mesh_file) == 0 .and. &
                 any(.not. scene%body%lengths > 0.0_wp)) then
            call bad(fb, 'lengths', 'must be positive (box edges along x, y, z in m)', 1)
        else if (len_trim(scene%body%load_set) == 0 .and. any(scene%body%load /= 0.0_wp)) then
            call bad(fb, 'load', 'needs load_set, the node set that carries it', 1)
        end if
        if (.not. status%ok()) return
        do k = 1, size(scene%materials)
            associate (m => scene%materials(k))
                if (.not. has_entry(entries, mat, 'young', k)) then
                    call status%set(status_bad_input, path // ': &material #' // itoa(k) // &
                        ': young: required (Young''s modulus in Pa)' // at(m%line))
                else if (.not. has_entry(entries, mat, 'density', k)) then
                    call status%set(status_bad_input, path // ': &material #' // itoa(k) // &
                        ': density: required (in kg/m³)' // at(m%line))
                else if (.not. m%young > 0.0_wp) then
                    call bad(mat, 'young', 'must be positive', k)
                else if (.not. (m%poisson > -1.0_wp .and. m%poisson < 0.5_wp)) then
                    call bad(mat, 'poisson', 'must lie in (-1, 0.5)', k)
                else if (.not. m%density > 0.0_wp) then
                    call bad(mat, 'density', 'must be positive', k)
                else if (m%viscosity < 0.0_wp) then
                    call bad(mat, 'viscosity', 'must not be negative (Pa s; 0 = undamped)', k)
                end if
            end associate
            if (.not. status%ok()) return
        end do

    contains

        subroutine bad(group, name, reason, occurrence)
            character(len=*), intent(in) :: group, name, reason
            integer, intent(in) :: occurrence
            integer :: i
            do i = 1, size(entries)
                if (entries(i)%group == group .and. entries(i)%name == name .and. &
                    entries(i)%occurrence == occurrence) then
                    call fail(status, path, entries(i), reason)
                    return
                end if
            end do
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ' (default): ' // reason)
        end subroutine bad
    end subroutine check_body_ranges

    !> Split text at newlines into records of equal length.
    pure function split_lines(text) result(lines)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: lines(:)
        integer :: i, k, nl, width, start
        nl = 1
        width = 1
        start = 1
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                nl = nl + 1
                width = max(width, i - start)
                start = i + 1
            end if
        end do
        width = max(width, len(text) - start + 1)
        allocate (character(len=width) :: lines(nl))
        k = 1
        start = 1
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                lines(k) = text(start:i - 1)
                k = k + 1
                start = i + 1
            end if
        end do
        lines(k) = text(start:)
    end function split_lines

    ! ------------------------------------------------------------------
    ! Ranges: check the typed values, quoting the text they came from.
    ! ------------------------------------------------------------------

    !> Lower-case the choice variables (names compare case-insensitively).
    subroutine normalise(scene)
        type(scene_input_t), intent(inout) :: scene
        scene%problem = lower(scene%problem)
        scene%pendulum_formulation = lower(scene%pendulum_formulation)
        scene%solver_name = lower(scene%solver_name)
        scene%linear_solver = lower(scene%linear_solver)
        scene%sparse_ordering = lower(scene%sparse_ordering)
        scene%jacobian = lower(scene%jacobian)
        scene%controller = lower(scene%controller)
        scene%mexax_base = lower(scene%mexax_base)
    end subroutine normalise

    subroutine check_ranges(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=*), parameter :: sim = 'simulation', sol = 'solver', out = 'output'
        character(len=:), allocatable :: ext

        ! &simulation
        if (.not. has_entry(entries, sim, 'problem')) then
            call missing(sim, 'problem', 'one of ' // choices(problem_names))
        else if (all(problem_names /= scene%problem)) then
            call bad(sim, 'problem', 'must be one of ' // choices(problem_names))
        else if (.not. has_entry(entries, sim, 't_end')) then
            call missing(sim, 't_end', 'the end time in s, greater than t_start')
        else if (.not. scene%t_end > scene%t_start) then
            call bad(sim, 't_end', 'must be greater than t_start = ' // &
                     raw_value(entries, sim, 't_start', '0'))
        else if (.not. scene%vdp_eps > 0.0_wp) then
            call bad(sim, 'vdp_eps', 'must be positive')
        else if (all(formulation_names /= scene%pendulum_formulation)) then
            call bad(sim, 'pendulum_formulation', 'must be one of ' // choices(formulation_names))
        else if (.not. scene%pendulum_length > 0.0_wp) then
            call bad(sim, 'pendulum_length', 'must be positive')
        else if (.not. scene%pendulum_mass > 0.0_wp) then
            call bad(sim, 'pendulum_mass', 'must be positive')
        else if (scene%gravity < 0.0_wp) then
            call bad(sim, 'gravity', 'must not be negative (it acts downwards)')
        else if (scene%npoints < 1) then
            call bad(sim, 'npoints', 'must be positive')
        ! &solver
        else if (all([character(len=8) :: 'radau5', 'ddassl', 'ida', 'mexax'] &
                     /= scene%solver_name)) then
            call bad(sol, 'name', 'must be ''radau5'', ''ddassl'', ''ida'' or ''mexax''')
        else if (scene%solver_name == 'mexax' .and. scene%problem /= 'pendulum' .and. &
                 scene%problem /= 'flexible_body') then
            ! ALGORITHMS.md §6: MEXAX integrates the mechanical form only.
            call bad(sol, 'name', '''mexax'' integrates mechanical problems only: &
                &problem must be ''pendulum'' or ''flexible_body''')
        else if (.not. scene%rtol > 0.0_wp) then
            call bad(sol, 'rtol', 'must be positive')
        else if (.not. scene%rtol < 1.0_wp) then
            call bad(sol, 'rtol', 'must be less than 1')
        else if (.not. scene%atol > 0.0_wp) then
            call bad(sol, 'atol', 'must be positive')
        else if (scene%h0 < 0.0_wp) then
            call bad(sol, 'h0', 'must not be negative (0 = automatic)')
        else if (scene%hmax < 0.0_wp) then
            call bad(sol, 'hmax', 'must not be negative (0 = the whole interval)')
        else if (scene%max_steps < 1) then
            call bad(sol, 'max_steps', 'must be positive')
        else if (all([character(len=8) :: 'auto', 'dense', 'klu', 'band'] &
                     /= scene%linear_solver)) then
            call bad(sol, 'linear_solver', 'must be ''auto'', ''dense'', ''klu'' or ''band''')
        else if (all([character(len=8) :: 'auto', 'amd', 'nd'] /= scene%sparse_ordering)) then
            call bad(sol, 'sparse_ordering', 'must be ''auto'', ''amd'' or ''nd''')
        else if (all([character(len=8) :: 'analytic', 'fd'] /= scene%jacobian)) then
            call bad(sol, 'jacobian', 'must be ''analytic'' or ''fd''')
        else if (scene%nit < 1) then
            call bad(sol, 'nit', 'must be positive')
        else if (.not. scene%thet < 1.0_wp) then
            call bad(sol, 'thet', 'must be less than 1')
        else if (scene%fnewt < 0.0_wp) then
            call bad(sol, 'fnewt', 'must not be negative (0 = the solver''s default)')
        else if (.not. (scene%quot1 > 0.0_wp .and. scene%quot1 <= 1.0_wp)) then
            call bad(sol, 'quot1', 'must lie in (0, 1]')
        else if (scene%quot2 < 1.0_wp) then
            call bad(sol, 'quot2', 'must be at least 1')
        else if (.not. (scene%safe > 0.001_wp .and. scene%safe < 1.0_wp)) then
            call bad(sol, 'safe', 'must lie in (0.001, 1)')
        else if (.not. (scene%fac_min > 0.0_wp .and. scene%fac_min <= 1.0_wp)) then
            call bad(sol, 'fac_min', 'must lie in (0, 1]')
        else if (scene%fac_max < 1.0_wp) then
            call bad(sol, 'fac_max', 'must be at least 1')
        else if (controller_code(scene%controller) == 0) then
            call bad(sol, 'controller', 'must be ''predictive'' or ''classical''')
        else if (scene%pmax < 1 .or. scene%pmax > 12) then
            call bad(sol, 'pmax', 'must lie in 1..12')
        else if (scene%solver_name == 'ddassl' .and. scene%pmax > 5) then
            ! ALGORITHMS.md §2.2: MAXORD ≤ 5.
            call bad(sol, 'pmax', 'must lie in 1..5 for ddassl (its maximal BDF order)')
        else if (scene%max_extrapolation < 2 .or. scene%max_extrapolation > 12) then
            call bad(sol, 'max_extrapolation', 'must lie in 2..12')
        else if (all([character(len=8) :: 'midpoint', 'euler'] /= scene%mexax_base)) then
            call bad(sol, 'mexax_base', 'must be ''midpoint'' or ''euler''')
        ! &output
        else if (scene%n_output < 2) then
            call bad(out, 'n_output', 'must be at least 2 (t_start and t_end)')
        else if (len_trim(scene%table) > 0) then
            ext = lower(extension(trim(scene%table)))
            if (all([character(len=4) :: 'md', 'csv', 'tex'] /= ext)) then
                call bad(out, 'table', 'must end in .md, .csv or .tex')
            end if
        end if

    contains

        subroutine bad(group, name, reason)
            character(len=*), intent(in) :: group, name, reason
            integer :: i
            do i = 1, size(entries)
                if (entries(i)%group == group .and. entries(i)%name == name) then
                    call fail(status, path, entries(i), reason)
                    return
                end if
            end do
            ! a default out of range relative to a value that was given
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ' (default): ' // reason)
        end subroutine bad

        subroutine missing(group, name, what)
            character(len=*), intent(in) :: group, name, what
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ': required (' // what // ')')
        end subroutine missing
    end subroutine check_ranges

    !> RADAU5's controller switch: 1 predictive (Gustafsson), 2 classical; 0 unknown.
    pure integer function controller_code(name)
        character(len=*), intent(in) :: name
        select case (lower(trim(name)))
        case ('predictive'); controller_code = 1
        case ('classical'); controller_code = 2
        case default; controller_code = 0
        end select
    end function controller_code

    !> The HDF5 file: as given ('' or 'none' = no file), or the input's
    !> base name with `.h5` in the working directory.
    subroutine resolve_output(scene, entries, path, status)
        type(scene_input_t), intent(inout) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: i
        if (.not. has_entry(entries, 'output', 'file')) then
            scene%output_file = stem(basename(path)) // '.h5'
        else if (lower(scene%output_file) == 'none') then
            scene%output_file = ''
        end if
        if (len(scene%output_file) == 0 .or. scene%output_file /= path) return
        do i = 1, size(entries)
            if (entries(i)%group == 'output' .and. entries(i)%name == 'file') then
                call fail(status, path, entries(i), 'would overwrite the input file')
                return
            end if
        end do
        call status%set(status_bad_input, path // ': &output: file (default ''' // &
            scene%output_file // '''): would overwrite the input file')
    end subroutine resolve_output

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

    ! ------------------------------------------------------------------
    ! Small helpers.
    ! ------------------------------------------------------------------

    !> Record a bad value: 'path: &group: name = value: reason (line n)'.
    subroutine fail(status, path, e, reason)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: path
        type(entry_t), intent(in) :: e
        character(len=*), intent(in) :: reason
        character(len=:), allocatable :: label
        label = e%group
        if (any(repeatable_groups == e%group)) label = label // ' #' // itoa(e%occurrence)
        call status%set(status_bad_input, path // ': &' // label // ': ' // e%name // &
            ' = ' // e%value // ': ' // reason // at(e%line))
    end subroutine fail

    pure function at(line) result(text)
        integer, intent(in) :: line
        character(len=:), allocatable :: text
        text = ' (line ' // itoa(line) // ')'
    end function at

    pure integer function find_group(name)
        character(len=*), intent(in) :: name
        integer :: g
        find_group = 0
        do g = 1, size(group_names)
            if (group_names(g) == name) find_group = g
        end do
    end function find_group

    pure integer function find_var(group, name)
        character(len=*), intent(in) :: group, name
        integer :: i
        find_var = 0
        do i = 1, size(schema)
            if (schema(i)%group == group .and. schema(i)%name == name) find_var = i
        end do
    end function find_var

    pure function known_vars(group) result(list)
        character(len=*), intent(in) :: group
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        do i = 1, size(schema)
            if (schema(i)%group /= group) cycle
            if (len(list) > 0) list = list // ', '
            list = list // trim(schema(i)%name)
        end do
    end function known_vars

    !> An entry group/name exists (in the given occurrence of the group, if any).
    pure logical function has_entry(entries, group, name, occurrence)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: occurrence
        integer :: i
        has_entry = .false.
        do i = 1, size(entries)
            if (entries(i)%group == group .and. entries(i)%name == name) then
                if (present(occurrence)) then
                    if (entries(i)%occurrence /= occurrence) cycle
                end if
                has_entry = .true.
            end if
        end do
    end function has_entry

    !> '&simulation, &solver, … or &material'.
    pure function group_list() result(list)
        character(len=:), allocatable :: list
        integer :: g
        list = ''
        do g = 1, size(group_names)
            if (g > 1) list = list // trim(merge(' or', ',  ', g == size(group_names))) // ' '
            list = list // '&' // trim(group_names(g))
        end do
    end function group_list

    pure function choices(names) result(list)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        do i = 1, size(names)
            if (i == size(names) .and. i > 1) then
                list = list // ' or '
            else if (i > 1) then
                list = list // ', '
            end if
            list = list // '''' // trim(names(i)) // ''''
        end do
    end function choices

    !> Contents of a quoted value, doubled quotes made single.
    pure function unquote(value) result(text)
        character(len=*), intent(in) :: value
        character(len=:), allocatable :: text
        integer :: i
        character :: quote
        text = ''
        if (len(value) < 2) return
        quote = value(1:1)
        i = 2
        do while (i < len(value))
            text = text // value(i:i)
            if (value(i:i) == quote) i = i + 1
            i = i + 1
        end do
    end function unquote

    pure logical function is_letter(c)
        character, intent(in) :: c
        is_letter = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z')
    end function is_letter

    pure logical function is_digit(c)
        character, intent(in) :: c
        is_digit = c >= '0' .and. c <= '9'
    end function is_digit

    pure logical function is_space(c)
        character, intent(in) :: c
        is_space = c == ' ' .or. c == achar(9) .or. c == achar(13)
    end function is_space

    pure function itoa(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write (buf, '(i0)') i
        s = trim(buf)
    end function itoa

    !> The value as written in the file, or `default` when not given.
    pure function raw_value(entries, group, name, default) result(text)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name, default
        character(len=:), allocatable :: text
        integer :: i
        text = default
        do i = 1, size(entries)
            if (entries(i)%group == group .and. entries(i)%name == name) text = entries(i)%value
        end do
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
end module flexmbs_io_namelist
