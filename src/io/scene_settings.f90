!> A scene's settings as one canonical text: every variable of every group
!> the scene gives, with its value as given or the schema's default, one
!> `&group(instance) name = value` line each, in the schema's order.
!> Comments, blanks, the order of the entries, quotes, the case of
!> choices and the spelling of numbers (1.0, 1., 1e0) leave it unchanged;
!> a changed value, or a changed default, changes it. What a study's
!> reference was made from (run/reference_fingerprint) is this text's
!> SHA-256, and a changed line names what changed.
!>
!> Reals are written with as few digits as read back to their bits
!> (core/text exact_text); a variable without a default in the schema
!> (its solver's own) is `(default)`.
module flexmbs_io_scene_settings
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: exact_text, int_text, lower
    use flexmbs_io_input_errors, only: input_errors_t
    use flexmbs_io_scene_schema, only: schema, group_names, repeatable_groups, kind_real, &
        kind_integer, kind_logical
    use flexmbs_io_scene_lexer, only: entry_t, span_t, tokenise
    use flexmbs_io_scene_values, only: unquote
    implicit none
    private

    public :: scene_settings

    character, parameter :: nl = new_line('a')

    type :: piece_t
        character(len=:), allocatable :: text
    end type piece_t

contains

    !> The settings text of the scene `text` (module header), read as it is
    !> (the scene has been checked: read_scene). `omit` lists what is left
    !> out, each 'group/name' or 'group/*' (a whole group).
    function scene_settings(text, omit) result(settings)
        character(len=*), intent(in) :: text
        character(len=*), intent(in) :: omit(:)
        character(len=:), allocatable :: settings
        type(input_errors_t) :: errors
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        type(piece_t), allocatable :: pieces(:)
        character(len=:), allocatable :: group, label
        integer, allocatable :: own(:)
        integer :: s, v, k, i, at
        call errors%start('')
        call tokenise(text, errors, entries, spans)
        ! a piece per group, joined at the end: linear in the scene's size
        allocate (pieces(size(spans)))
        do s = 1, size(spans)
            pieces(s)%text = ''
            group = trim(group_names(spans(s)%group))
            if (any(omit == group // '/*')) cycle
            label = '&' // group
            if (any(repeatable_groups == group)) label = label // '(' // &
                int_text(spans(s)%instance) // ')'
            own = occurrence(entries, group, spans(s)%instance)
            do v = 1, size(schema)
                if (schema(v)%group /= group) cycle
                if (any(omit == group // '/' // trim(schema(v)%name))) cycle
                k = 0
                do i = 1, size(own)
                    if (entries(own(i))%name == trim(schema(v)%name)) k = own(i)
                end do
                pieces(s)%text = pieces(s)%text // label // ' ' // trim(schema(v)%name) // &
                    ' = ' // setting_value(v, entries, k) // nl
            end do
        end do
        allocate (character(len=sum([(len(pieces(s)%text), s=1, size(pieces))])) :: settings)
        at = 0
        do s = 1, size(pieces)
            settings(at + 1:at + len(pieces(s)%text)) = pieces(s)%text
            at = at + len(pieces(s)%text)
        end do
    end function scene_settings

    !> The indices of the valid entries of `group`'s occurrence `instance`.
    function occurrence(entries, group, instance) result(own)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group
        integer, intent(in) :: instance
        integer, allocatable :: own(:)
        logical :: mine(size(entries))
        integer :: i
        do i = 1, size(entries)
            mine(i) = entries(i)%group == group .and. entries(i)%instance == instance .and. &
                .not. entries(i)%bad
        end do
        own = pack([(i, i=1, size(entries))], mine)
    end function occurrence

    !> The canonical value of variable `v` of the schema: entry k's values
    !> (k > 0) or the schema's default.
    function setting_value(v, entries, k) result(value)
        integer, intent(in) :: v, k
        type(entry_t), intent(in) :: entries(:)
        character(len=:), allocatable :: value
        character(len=:), allocatable :: default
        integer :: j, start, comma
        value = ''
        if (k > 0) then
            do j = 1, size(entries(k)%items)
                if (j > 1) value = value // ', '
                value = value // canonical(entries(k)%items(j)%text, v)
            end do
            return
        end if
        default = trim(schema(v)%default)
        if (len(default) == 0) then
            value = '(default)'
            return
        end if
        ! a default lists its values separated by commas, unquoted
        start = 1
        do
            comma = index(default(start:), ',')
            if (comma == 0) comma = len(default) - start + 2
            if (start > 1) value = value // ', '
            value = value // canonical(trim(adjustl(default(start:start + comma - 2))), v)
            start = start + comma
            if (start > len(default)) exit
        end do
    end function setting_value

    !> One value of variable `v` as text that reads alike however it was
    !> written (numbers and logicals as read, strings without their quotes,
    !> a choice in lower case); a value that does not read is kept as given.
    function canonical(item, v) result(text)
        character(len=*), intent(in) :: item
        integer, intent(in) :: v
        character(len=:), allocatable :: text
        real(wp) :: x
        integer :: m, ios
        text = item
        select case (schema(v)%kind)
        case (kind_real)
            read (item, *, iostat=ios) x
            if (ios == 0) text = exact_text(x)
        case (kind_integer)
            read (item, *, iostat=ios) m
            if (ios == 0) text = int_text(m)
        case (kind_logical)
            text = merge('T', 'F', any(lower(item) == [character(len=6) :: '.true.', '.t.', &
                                                        '.t', 't', 'true']))
        case default
            if (len(item) >= 2) then
                if (scan(item(1:1), '''"') > 0) text = unquote(item)
            end if
            if (len_trim(schema(v)%choices) > 0) text = lower(text)
        end select
    end function canonical
end module flexmbs_io_scene_settings
