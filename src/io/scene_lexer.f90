!> Tokenising scene and study files: groups `&name ... /`, entries
!> `name = value[, value ...]` with their lines, checked against the
!> schema's groups and variables. Errors are collected, not fatal: after
!> one the lexer resynchronises (at the next name, or the group's end) so
!> that a file's mistakes are all reported in one run. Linear in the
!> length of the text.
module flexmbs_io_scene_lexer
    use flexmbs_core_text, only: lower, int_text
    use flexmbs_io_input_errors, only: input_errors_t, excerpt
    use flexmbs_io_scene_schema, only: schema, group_names, repeatable_groups, find_group, &
        find_var, known_vars, group_vars, did_you_mean, kind_string
    implicit none
    private

    !> One value of a variable's list.
    type, public :: item_t
        character(len=:), allocatable :: text
        logical :: quoted = .false.
    end type item_t

    !> One `name = value[, value ...]`; `value` is the list as written
    !> (for messages), `items` its values. `bad`: reported, not to be read.
    type, public :: entry_t
        character(len=:), allocatable :: group, name, value
        integer :: line = 0
        integer :: instance = 1  !! which occurrence of a repeatable group
        logical :: bad = .false.
        type(item_t), allocatable :: items(:)
    end type entry_t

    !> One group of the text: which, its occurrence, and where it starts.
    type, public :: span_t
        integer :: group = 0     !! index in group_names
        integer :: instance = 1  !! occurrence of that group
        integer :: line = 0      !! line of '&name'
    end type span_t

    public :: tokenise, has_entry, entry_index, instance_ranges, is_letter, is_digit, &
        unquoted_length

contains

    !> Walk the text; return the entries and each group's span. Every
    !> structural error goes to `errors`.
    subroutine tokenise(text, errors, entries, spans)
        character(len=*), intent(in) :: text
        type(input_errors_t), intent(inout) :: errors
        type(entry_t), allocatable, intent(out) :: entries(:)
        type(span_t), allocatable, intent(out) :: spans(:)
        character(len=:), allocatable :: clean, group, word
        integer :: pos, line, g, n, first_line, instance, nentries, nspans
        logical :: skip

        allocate (entries(16), spans(8))
        nentries = 0
        nspans = 0
        clean = blank_comments(text)
        n = len(clean)
        pos = 1
        line = 1
        do
            call skip_blank(clean, pos, line)
            if (pos > n) exit
            if (clean(pos:pos) /= '&') then
                word = bare_word(clean, pos)
                call errors%add('unexpected text ''' // excerpt(word) // ''' outside a group &
                    &(groups start with &name and end with /)', line)
                ! resynchronise at the next group
                do while (pos <= n)
                    if (clean(pos:pos) == '&') exit
                    if (clean(pos:pos) == new_line('a')) line = line + 1
                    pos = pos + 1
                end do
                cycle
            end if
            first_line = line
            pos = pos + 1
            group = lower(name_word(clean, pos))
            g = find_group(group)
            skip = .false.
            if (g == 0) then
                call errors%add('&' // excerpt(group) // ': unknown group' // &
                    did_you_mean(group, group_names) // ' (known: ' // known_groups() // &
                    '; &study in study files)', line)
                skip = .true.
                instance = 1
            else
                instance = count(spans(1:nspans)%group == g) + 1
                if (instance > 1 .and. all(repeatable_groups /= group)) then
                    call errors%add('&' // group // ': group given more than once', line)
                    skip = .true.
                end if
            end if
            call read_group_body(clean, pos, line, group, instance, skip, errors, entries, &
                                 nentries)
            if (.not. skip) then
                if (nspans == size(spans)) spans = [spans, spans]
                nspans = nspans + 1
                spans(nspans) = span_t(g, instance, first_line)
            end if
        end do
        entries = entries(1:nentries)
        spans = spans(1:nspans)
    end subroutine tokenise

    !> The entries of one group up to its closing '/' (or '&end'). With
    !> `skip` the group is walked the same way but nothing is kept.
    subroutine read_group_body(clean, pos, line, group, instance, skip, errors, entries, &
                               nentries)
        character(len=*), intent(in) :: clean, group
        integer, intent(inout) :: pos, line, nentries
        integer, intent(in) :: instance
        logical, intent(in) :: skip
        type(input_errors_t), intent(inout) :: errors
        type(entry_t), allocatable, intent(inout) :: entries(:)
        character(len=:), allocatable :: word, name, previous, value
        type(item_t), allocatable :: items(:)
        integer :: n, vline, spec, nitems, p, first_entry, previous_line
        logical :: quoted, closed, bad, duplicate, previous_quoted

        n = len(clean)
        first_entry = nentries + 1
        previous = ''
        previous_quoted = .false.
        previous_line = 0
        do
            call skip_blank(clean, pos, line)
            if (group_ended(clean, pos, line, group, skip, errors)) return
            if (clean(pos:pos) == ',' .and. len(previous) > 0) then
                pos = pos + 1
                cycle
            end if
            if (.not. is_letter(clean(pos:pos))) then
                word = bare_word(clean, pos)
                pos = pos + max(len(word), 1)
                if (skip) cycle
                if (len(previous) > 0) then
                    call errors%add('&' // group // ': ' // previous // ': unexpected ''' // &
                        excerpt(word) // ''' after its value (one value per variable)', line)
                else
                    call errors%add('&' // group // ': unexpected ''' // excerpt(word) // &
                        ''' (expected name = value)', line)
                end if
                cycle
            end if
            p = line
            name = lower(variable_word(clean, pos))
            call skip_blank(clean, pos, line)
            ! a word without '=' on the line of the value before it: a unit?
            if (len(previous) > 0 .and. p == previous_line .and. .not. equals_at(clean, pos)) then
                if (skip) then
                    continue
                else if (previous_quoted) then
                    call errors%add('&' // group // ': ' // previous // ': unexpected ''' // &
                        excerpt(name) // ''' after its value', p)
                else
                    call errors%add('&' // group // ': ' // previous // ' = ' // &
                        excerpt(value) // ': ''' // excerpt(name) // ''' after the value &
                        &(a unit?): write the number alone' // unit_hint(group, previous), p)
                end if
                cycle
            end if
            spec = 0
            bad = .false.
            duplicate = .false.
            if (.not. skip) then
                spec = find_var(group, name)
                if (spec == 0) then
                    call errors%add('&' // group // ': ' // excerpt(name) // ': unknown variable' &
                        // did_you_mean(name, group_vars(group)) // ' (known: ' // &
                        known_vars(group) // ')', p)
                    bad = .true.
                else if (has_entry(entries(first_entry:nentries), group, name, instance)) then
                    call errors%add('&' // group // ': ' // name // ': given more than once', p)
                    bad = .true.
                    duplicate = .true.
                end if
            end if
            if (pos > n) then
                closed = .false.
            else
                closed = clean(pos:pos) == '='
            end if
            if (.not. closed) then
                if (.not. skip .and. .not. bad) call errors%add('&' // group // ': ' // name // &
                    ': expected ''='' after the name', p)
                previous = ''
                cycle
            end if
            pos = pos + 1
            call skip_blank(clean, pos, line)
            vline = line
            allocate (items(8))
            nitems = 0
            value = ''
            if (pos <= n) then
                if (scan(clean(pos:pos), ',/&') == 0) then
                    call value_word(clean, pos, value, quoted, closed)
                    nitems = 1
                    items(1) = item_t(value, quoted)
                    if (.not. closed .and. .not. (skip .or. bad)) then
                        call errors%add('&' // group // ': ' // name // ' = ' // excerpt(value) &
                            // ': unterminated string', vline)
                        bad = .true.
                    end if
                end if
            end if
            if (nitems == 0) then
                if (.not. (skip .or. bad)) call errors%add('&' // group // ': ' // name // &
                    ': has no value', vline)
                deallocate (items)
                previous = ''
                cycle
            end if
            ! a scalar's value ends at its first token (what follows is reported)
            if (spec == 0) then
                call more_values(clean, pos, line, items, nitems, closed)
            else if (schema(spec)%count > 1) then
                call more_values(clean, pos, line, items, nitems, closed)
            end if
            if (.not. closed .and. .not. (skip .or. bad)) then
                call errors%add('&' // group // ': ' // name // ' = ' // &
                    excerpt(joined(items(1:nitems))) // ': unterminated string', vline)
                bad = .true.
            end if
            value = joined(items(1:nitems))
            if (.not. (skip .or. bad) .and. spec > 0) &
                call check_count(spec, nitems, '&' // group // ': ' // name // ' = ' // &
                                 excerpt(value), vline, errors, bad)
            if (.not. skip .and. spec > 0 .and. .not. duplicate) then
                if (nentries == size(entries)) entries = [entries, entries]
                nentries = nentries + 1
                entries(nentries) = entry_t(group, name, value, vline, instance, bad, &
                                            items(1:nitems))
            end if
            previous_quoted = all(items(1:nitems)%quoted)
            previous_line = line
            deallocate (items)
            previous = name
        end do
    end subroutine read_group_body

    !> At pos (blanks skipped): the group's end, '/' or '&end' (pos moves
    !> past it), or what ends it too early: the text's end or another
    !> group's '&' (an error unless `skip`).
    logical function group_ended(clean, pos, line, group, skip, errors) result(ended)
        character(len=*), intent(in) :: clean, group
        integer, intent(inout) :: pos
        integer, intent(in) :: line
        logical, intent(in) :: skip
        type(input_errors_t), intent(inout) :: errors
        character(len=:), allocatable :: word
        integer :: p
        ended = .true.
        if (pos > len(clean)) then
            if (.not. skip) call errors%add('&' // group // ': not closed by ''/''', line)
            return
        end if
        if (clean(pos:pos) == '/') then
            pos = pos + 1
            return
        end if
        if (clean(pos:pos) == '&') then
            p = pos + 1
            word = lower(name_word(clean, p))
            if (word == 'end') then
                pos = p
                return
            end if
            if (.not. skip) call errors%add('&' // group // ': not closed by ''/'' before &' &
                // excerpt(word), line)
            return
        end if
        ended = .false.
    end function group_ended

    !> The number of values of variable `spec` against the schema: one for a
    !> scalar, exactly `count` for a fixed-size vector, at most `count` for a
    !> list or string vector. `what` is '&group: name = value'.
    subroutine check_count(spec, nitems, what, vline, errors, bad)
        integer, intent(in) :: spec, nitems, vline
        character(len=*), intent(in) :: what
        type(input_errors_t), intent(inout) :: errors
        logical, intent(inout) :: bad
        if (schema(spec)%count == 1 .and. nitems > 1) then
            call errors%add(what // ': one value only', vline)
            bad = .true.
        else if (schema(spec)%kind /= kind_string .and. .not. schema(spec)%list .and. &
                 nitems /= schema(spec)%count) then
            call errors%add(what // ': needs ' // int_text(schema(spec)%count) // ' values', &
                            vline)
            bad = .true.
        else if (nitems > schema(spec)%count) then
            call errors%add(what // ': at most ' // int_text(schema(spec)%count) // ' values', &
                            vline)
            bad = .true.
        end if
    end subroutine check_count

    !> text(pos:pos) is '=' (false past the end).
    pure logical function equals_at(text, pos)
        character(len=*), intent(in) :: text
        integer, intent(in) :: pos
        equals_at = .false.
        if (pos <= len(text)) equals_at = text(pos:pos) == '='
    end function equals_at

    !> ' (in SI units: m)' from the schema, or ''.
    pure function unit_hint(group, name) result(hint)
        character(len=*), intent(in) :: group, name
        character(len=:), allocatable :: hint
        integer :: spec
        hint = ', in SI units'
        spec = find_var(group, name)
        if (spec == 0) return
        if (len_trim(schema(spec)%unit) > 0) hint = ', in ' // trim(schema(spec)%unit)
    end function unit_hint

    !> Further values after the first: each after a comma or blanks, a
    !> quoted string or a token starting like a number. Stops (pos at the
    !> comma) before anything else, e.g. the next `name =`.
    subroutine more_values(text, pos, line, items, nitems, closed)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line, nitems
        type(item_t), allocatable, intent(inout) :: items(:)
        logical, intent(inout) :: closed
        integer :: p, l
        character(len=:), allocatable :: value
        logical :: quoted, ok
        do while (closed)
            p = pos
            l = line
            call skip_blank(text, p, l)
            if (p <= len(text)) then
                if (text(p:p) == ',') then
                    p = p + 1
                    call skip_blank(text, p, l)
                end if
            end if
            if (p > len(text)) return
            if (scan(text(p:p), '0123456789+-.''"') == 0) return
            pos = p
            line = l
            call value_word(text, pos, value, quoted, ok)
            if (nitems == size(items)) items = [items, items]
            nitems = nitems + 1
            items(nitems) = item_t(value, quoted)
            closed = ok
        end do
    end subroutine more_values

    !> The values of a list as one text, for messages.
    pure function joined(items) result(text)
        type(item_t), intent(in) :: items(:)
        character(len=:), allocatable :: text
        integer :: i, n, k
        n = sum([(len(items(i)%text), i = 1, size(items))]) + 2 * (size(items) - 1)
        allocate (character(len=n) :: text)
        k = 0
        do i = 1, size(items)
            if (i > 1) then
                text(k + 1:k + 2) = ', '
                k = k + 2
            end if
            text(k + 1:k + len(items(i)%text)) = items(i)%text
            k = k + len(items(i)%text)
        end do
    end function joined

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
        word = word_at(text, pos, designator=.false.)
    end function name_word

    !> A variable designator: a name, possibly with a subscript or
    !> component, so that `y0(1)` is reported whole as unknown.
    function variable_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable :: word
        word = word_at(text, pos, designator=.true.)
    end function variable_word

    !> The word starting at pos, pos moved past it: a name's characters, or
    !> with `designator` anything up to a blank, a newline or one of =,/&'".
    function word_at(text, pos, designator) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        logical, intent(in) :: designator
        character(len=:), allocatable :: word
        integer :: start
        start = pos
        do while (pos <= len(text))
            if (designator) then
                if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
                if (scan(text(pos:pos), '=,/&''"') > 0) exit
            else if (.not. (is_letter(text(pos:pos)) .or. is_digit(text(pos:pos)) &
                            .or. text(pos:pos) == '_')) then
                exit
            end if
            pos = pos + 1
        end do
        word = text(start:pos - 1)
    end function word_at

    !> Anything up to the next separator (for messages about stray text).
    function bare_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(in) :: pos
        character(len=:), allocatable :: word
        integer :: last
        last = pos
        do while (last < len(text))
            if (is_space(text(last + 1:last + 1)) .or. text(last + 1:last + 1) == new_line('a') &
                .or. scan(text(last + 1:last + 1), ',/=&') > 0) exit
            last = last + 1
        end do
        word = text(pos:last)
    end function bare_word

    !> One value: a quoted string (quotes doubled inside) or a bare token
    !> ending at a blank, ',', '/' or end of line. `closed` is false when
    !> a string is not closed on its line.
    subroutine value_word(text, pos, value, quoted, closed)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable, intent(out) :: value
        logical, intent(out) :: quoted, closed
        integer :: start
        character :: quote
        start = pos
        closed = .true.
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
            closed = .false.
            return
        end if
        do while (pos <= len(text))
            if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
            if (scan(text(pos:pos), ',/') > 0) exit
            pos = pos + 1
        end do
        value = text(start:pos - 1)
    end subroutine value_word

    !> Length of a quoted value's contents, doubled quotes counted once.
    pure integer function unquoted_length(value) result(n)
        character(len=*), intent(in) :: value
        integer :: i
        n = 0
        if (len(value) < 2) return
        i = 2
        do while (i < len(value))
            n = n + 1
            if (value(i:i) == value(1:1)) i = i + 1
            i = i + 1
        end do
    end function unquoted_length

    !> Index of the entry `name` of `group` (occurrence `instance`), 0 if none.
    pure integer function entry_index(entries, group, name, instance) result(k)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: instance
        integer :: i
        k = 0
        do i = 1, size(entries)
            if (entries(i)%group /= group .or. entries(i)%name /= name) cycle
            if (present(instance)) then
                if (entries(i)%instance /= instance) cycle
            end if
            k = i
        end do
    end function entry_index

    !> For each occurrence 1..n of `group`, the first and last index of its
    !> entries in `entries` (1 and 0 for an occurrence without entries), in
    !> one pass: readers and checks look a variable up in its occurrence's
    !> slice, so that a scene of n groups is read in time linear in n.
    pure subroutine instance_ranges(entries, group, n, ranges)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group
        integer, intent(in) :: n
        integer, allocatable, intent(out) :: ranges(:, :)
        integer :: i, k
        allocate (ranges(2, n))
        ranges(1, :) = huge(1)
        ranges(2, :) = 0
        do i = 1, size(entries)
            if (entries(i)%group /= group) cycle
            k = entries(i)%instance
            if (k < 1 .or. k > n) cycle
            ranges(1, k) = min(ranges(1, k), i)
            ranges(2, k) = max(ranges(2, k), i)
        end do
        where (ranges(2, :) == 0) ranges(1, :) = 1
    end subroutine instance_ranges

    !> Whether `name` is given in `group` (in occurrence `instance` if present).
    pure logical function has_entry(entries, group, name, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: instance
        has_entry = entry_index(entries, group, name, instance) > 0
    end function has_entry

    !> True for an ASCII letter a-z, A-Z (names start with one).
    pure logical function is_letter(c)
        character, intent(in) :: c
        is_letter = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z')
    end function is_letter

    !> True for an ASCII digit 0-9.
    pure logical function is_digit(c)
        character, intent(in) :: c
        is_digit = c >= '0' .and. c <= '9'
    end function is_digit

    pure logical function is_space(c)
        character, intent(in) :: c
        is_space = c == ' ' .or. c == achar(9) .or. c == achar(13)
    end function is_space


    !> The scene groups of the schema, '&simulation, &solver, ...' (the
    !> study's own group left out): the list cannot fall behind the schema.
    function known_groups() result(text)
        character(len=:), allocatable :: text
        integer :: g
        text = ''
        do g = 1, size(group_names)
            if (group_names(g) == 'study') cycle
            if (len(text) > 0) text = text // ', '
            text = text // '&' // trim(group_names(g))
        end do
    end function known_groups
end module flexmbs_io_scene_lexer
