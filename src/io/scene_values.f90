!> Typed values of scene entries: each value checked against its
!> variable's kind and the schema's rule or choices (every error
!> collected), then read, the schema's default standing in for a variable
!> not given or given wrongly.
module flexmbs_io_scene_values
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: lower, int_text
    use flexmbs_io_input_errors, only: input_errors_t, excerpt
    use flexmbs_io_scene_schema, only: schema, find_var, string_length, kind_string, &
        kind_real, kind_integer, kind_logical, split_choices, choice_list, is_choice, &
        did_you_mean
    use flexmbs_core_rules, only: rule_reason
    use flexmbs_io_scene_lexer, only: entry_t, item_t, entry_index, is_digit, unquoted_length
    implicit none
    private

    public :: check_types, check_rules, get, get_list, unquote, value_error, &
        required_error

    !> The value of `group`/`name` (occurrence `instance`): the entry's
    !> when given and valid, else the schema's default.
    interface get
        module procedure get_real, get_real_array, get_integer, get_integer_array, &
            get_logical, get_string, get_string_array
    end interface get

    !> The 1..count values of a list variable as given (none when absent).
    interface get_list
        module procedure list_real, list_integer, list_string
    end interface get_list

contains

    !> Every value against its variable's kind; a wrong entry is marked bad.
    subroutine check_types(entries, errors)
        type(entry_t), intent(inout) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i, j, k
        character(len=:), allocatable :: reason
        do i = 1, size(entries)
            if (entries(i)%bad) cycle
            k = schema(find_var(entries(i)%group, entries(i)%name))%kind
            do j = 1, size(entries(i)%items)
                reason = type_reason(k, entries(i)%name, entries(i)%items(j))
                if (len(reason) == 0) cycle
                ! in a list, say which value is wrong
                if (size(entries(i)%items) > 1) reason = 'value ' // int_text(j) // ' (' // &
                    excerpt(entries(i)%items(j)%text) // ') ' // reason
                call reject(entries(i), reason, errors)
                exit
            end do
        end do
    end subroutine check_types

    ! Report a wrong value of `entry` and mark the entry bad (later checks skip it).
    subroutine reject(entry, reason, errors)
        type(entry_t), intent(inout) :: entry
        character(len=*), intent(in) :: reason
        type(input_errors_t), intent(inout) :: errors
        call errors%add_value(entry%group, entry%name, entry%value, reason, entry%line)
        entry%bad = .true.
    end subroutine reject

    !> Every valid value against its variable's rule and choices.
    subroutine check_rules(entries, errors)
        type(entry_t), intent(inout) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i, j, spec
        real(wp) :: x
        character(len=:), allocatable :: reason, text
        do i = 1, size(entries)
            if (entries(i)%bad) cycle
            spec = find_var(entries(i)%group, entries(i)%name)
            do j = 1, size(entries(i)%items)
                reason = ''
                if (schema(spec)%kind == kind_string .and. len_trim(schema(spec)%choices) > 0) &
                    then
                    text = unquote(entries(i)%items(j)%text)
                    if (.not. is_choice(text, schema(spec)%choices)) reason = 'must be ' // &
                        choice_list(split_choices(schema(spec)%choices)) // &
                        did_you_mean(text, split_choices(schema(spec)%choices))
                else if ((schema(spec)%kind == kind_real .or. schema(spec)%kind == kind_integer) &
                         .and. len_trim(schema(spec)%rule) > 0) then
                    read (entries(i)%items(j)%text, *) x
                    reason = rule_reason(trim(schema(spec)%rule), x, &
                                         schema(spec)%kind == kind_integer)
                end if
                if (len(reason) == 0) cycle
                ! in a list of strings, say which one
                if (size(entries(i)%items) > 1 .and. schema(spec)%kind == kind_string) &
                    reason = '''' // excerpt(text) // ''': ' // reason
                call reject(entries(i), reason, errors)
                exit
            end do
        end do
    end subroutine check_rules

    !> Report `reason` against variable `group`/`name` of occurrence
    !> `instance` (default 1): 'path: &group: name = value: reason (line n)'
    !> when given, 'path: &group 'label': name (default): reason' when not;
    !> nothing when its entry is already reported as wrong.
    subroutine value_error(errors, entries, group, name, reason, instance, label, line)
        type(input_errors_t), intent(inout) :: errors
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name, reason
        integer, intent(in), optional :: instance, line
        character(len=*), intent(in), optional :: label
        integer :: k, where
        k = entry_index(entries, group, name, instance)
        if (k > 0) then
            if (.not. entries(k)%bad) call errors%add_value(group, name, entries(k)%value, &
                reason, entries(k)%line)
            return
        end if
        where = 0
        if (present(line)) where = line
        if (present(label)) then
            call errors%add('&' // group // ' ''' // excerpt(trim(label)) // ''': ' // name // &
                ' (default): ' // reason, where)
        else
            call errors%add('&' // group // ': ' // name // ' (default): ' // reason, where)
        end if
    end subroutine value_error

    !> 'path: &group 'label': name: required (what) (line n)'.
    subroutine required_error(errors, group, name, what, label, line)
        type(input_errors_t), intent(inout) :: errors
        character(len=*), intent(in) :: group, name, what
        character(len=*), intent(in), optional :: label
        integer, intent(in), optional :: line
        integer :: where
        where = 0
        if (present(line)) where = line
        if (present(label)) then
            call errors%add('&' // group // ' ''' // excerpt(trim(label)) // ''': ' // name // &
                ': required (' // what // ')', where)
        else
            call errors%add('&' // group // ': ' // name // ': required (' // what // ')', where)
        end if
    end subroutine required_error

    !> Why one value does not fit the kind of variable `name` ('' if it does).
    function type_reason(kind, name, item) result(reason)
        integer, intent(in) :: kind
        character(len=*), intent(in) :: name
        type(item_t), intent(in) :: item
        character(len=:), allocatable :: reason
        integer :: ios, m
        real(wp) :: x
        type(ieee_status_type) :: fp_status
        reason = ''
        select case (kind)
        case (kind_string)
            if (.not. item%quoted) then
                reason = 'must be a quoted string, e.g. ' // name // ' = ''' // &
                    excerpt(item%text) // ''''
            else if (unquoted_length(item%text) > string_length(name)) then
                reason = 'longer than ' // int_text(string_length(name)) // ' characters'
            end if
        case (kind_real)
            if (item%quoted .or. .not. is_real_text(item%text)) then
                reason = 'must be a real number'
            else
                ! an overflowing value must not leave the overflow flag raised
                call ieee_get_status(fp_status)
                read (item%text, *, iostat=ios) x
                call ieee_set_status(fp_status)
                if (ios /= 0) then
                    reason = 'is out of the range of real numbers'
                else if (.not. ieee_is_finite(x)) then
                    reason = 'is out of the range of real numbers'
                end if
            end if
        case (kind_integer)
            if (item%quoted .or. .not. is_integer_text(item%text)) then
                reason = 'must be an integer'
            else if (len(item%text) > 12) then
                reason = 'is out of the range of integers (at most ' // int_text(huge(1)) // ')'
            else
                read (item%text, *, iostat=ios) m
                if (ios /= 0) reason = 'is out of the range of integers (at most ' // &
                    int_text(huge(1)) // ')'
            end if
        case (kind_logical)
            if (item%quoted .or. .not. is_logical_text(item%text)) then
                reason = 'must be .true. or .false.'
            end if
        end select
    end function type_reason

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
        if (len(s) == 0 .or. len(s) > 64) return
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
        is_logical_text = .false.
        if (len(s) <= 8) is_logical_text = any(forms == lower(s))
    end function is_logical_text

    !> Index of the entry to read, 0 when not given or given wrongly.
    pure integer function valid_index(entries, group, name, instance) result(k)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: instance
        k = entry_index(entries, group, name, instance)
        if (k > 0) then
            if (entries(k)%bad) k = 0
        end if
    end function valid_index

    !> The text of variable `group`/`name` to read: the entry's values
    !> joined by commas, or the schema's default.
    function value_text(entries, group, name, instance) result(text)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: instance
        character(len=:), allocatable :: text
        integer :: k, j
        k = valid_index(entries, group, name, instance)
        if (k == 0) then
            text = trim(schema(find_var(group, name))%default)
            return
        end if
        text = entries(k)%items(1)%text
        do j = 2, size(entries(k)%items)
            text = text // ', ' // entries(k)%items(j)%text
        end do
    end function value_text

    ! A scalar is read as the first value of a list (the same list-directed read).
    subroutine get_real(entries, group, name, x, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        real(wp), intent(out) :: x
        integer, intent(in), optional :: instance
        real(wp) :: first(1)
        call get_real_array(entries, group, name, first, instance)
        x = first(1)
    end subroutine get_real

    subroutine get_real_array(entries, group, name, x, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        real(wp), intent(out) :: x(:)
        integer, intent(in), optional :: instance
        character(len=:), allocatable :: text
        integer :: ios
        text = value_text(entries, group, name, instance)
        x = 0.0_wp
        if (len(text) > 0) read (text, *, iostat=ios) x
    end subroutine get_real_array

    ! As get_real.
    subroutine get_integer(entries, group, name, m, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(out) :: m
        integer, intent(in), optional :: instance
        integer :: first(1)
        call get_integer_array(entries, group, name, first, instance)
        m = first(1)
    end subroutine get_integer

    subroutine get_integer_array(entries, group, name, m, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(out) :: m(:)
        integer, intent(in), optional :: instance
        character(len=:), allocatable :: text
        integer :: ios
        text = value_text(entries, group, name, instance)
        m = 0
        if (len(text) > 0) read (text, *, iostat=ios) m
    end subroutine get_integer_array

    subroutine get_logical(entries, group, name, flag, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        logical, intent(out) :: flag
        integer, intent(in), optional :: instance
        character(len=:), allocatable :: text
        text = lower(value_text(entries, group, name, instance))
        flag = text == '.true.' .or. text == '.t.' .or. text == '.t' .or. text == 't' .or. &
            text == 'true'
    end subroutine get_logical

    !> A string value, unquoted (the schema's default is written bare).
    subroutine get_string(entries, group, name, s, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        character(len=*), intent(out) :: s
        integer, intent(in), optional :: instance
        integer :: k
        k = valid_index(entries, group, name, instance)
        if (k == 0) then
            s = schema(find_var(group, name))%default
        else
            s = unquote(entries(k)%items(1)%text)
        end if
    end subroutine get_string

    !> The strings of an array variable; the rest blank.
    subroutine get_string_array(entries, group, name, s, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        character(len=*), intent(out) :: s(:)
        integer, intent(in), optional :: instance
        integer :: k, j
        s = ''
        k = valid_index(entries, group, name, instance)
        if (k == 0) return
        do j = 1, min(size(s), size(entries(k)%items))
            s(j) = unquote(entries(k)%items(j)%text)
        end do
    end subroutine get_string_array

    subroutine list_real(entries, group, name, x)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        real(wp), allocatable, intent(out) :: x(:)
        integer :: k, j, ios
        k = valid_index(entries, group, name)
        allocate (x(0))
        if (k == 0) return
        deallocate (x)
        allocate (x(size(entries(k)%items)))
        do j = 1, size(x)
            read (entries(k)%items(j)%text, *, iostat=ios) x(j)
        end do
    end subroutine list_real

    subroutine list_integer(entries, group, name, m)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, allocatable, intent(out) :: m(:)
        integer :: k, j, ios
        k = valid_index(entries, group, name)
        allocate (m(0))
        if (k == 0) return
        deallocate (m)
        allocate (m(size(entries(k)%items)))
        do j = 1, size(m)
            read (entries(k)%items(j)%text, *, iostat=ios) m(j)
        end do
    end subroutine list_integer

    subroutine list_string(entries, group, name, s)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        character(len=*), allocatable, intent(out) :: s(:)
        integer :: k, j
        k = valid_index(entries, group, name)
        allocate (s(0))
        if (k == 0) return
        deallocate (s)
        allocate (s(size(entries(k)%items)))
        do j = 1, size(s)
            s(j) = lower(unquote(entries(k)%items(j)%text))
        end do
    end subroutine list_string

    !> Contents of a quoted value, doubled quotes made single (linear time).
    pure function unquote(value) result(text)
        character(len=*), intent(in) :: value
        character(len=:), allocatable :: text
        integer :: i, n
        character :: quote
        allocate (character(len=max(len(value) - 2, 0)) :: text)
        if (len(value) < 2) then
            text = ''
            return
        end if
        quote = value(1:1)
        i = 2
        n = 0
        do while (i < len(value))
            n = n + 1
            text(n:n) = value(i:i)
            if (value(i:i) == quote) i = i + 1
            i = i + 1
        end do
        text = text(1:n)
    end function unquote

end module flexmbs_io_scene_values
