!> Numbers as text for status messages, and small string helpers.
module flexmbs_core_text
    use flexmbs_core_kinds, only: wp, i8
    implicit none
    private
    public :: real_text, exact_text, int_text, lower, excerpt, nearest

    !> An integer (default or 64-bit) without blanks.
    interface int_text
        module procedure int_text_default, int_text_i8
    end interface int_text

contains

    !> x in the es14.6 format, without blanks.
    pure function real_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf
        write (buf, '(es14.6)') x
        text = trim(adjustl(buf))
    end function real_text

    !> x with as few significant digits (15, 16 or 17) as read back to its
    !> very bits, trailing zeros dropped, positional from 1e-4 to 1e16:
    !> 0.3 is '0.3', 2*pi '6.283185307179586', 1e-8 '1E-8'. For texts that
    !> are compared (fingerprints) and still read well.
    pure function exact_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=40) :: buf
        character(len=16) :: form
        character(len=:), allocatable :: sign, digits
        real(wp) :: back
        integer :: n, ios, e, exponent
        do n = 15, 17
            write (form, '(a,i0,a)') '(es40.', n - 1, 'e3)'
            write (buf, form) x
            read (buf, *, iostat=ios) back
            if (ios == 0 .and. back == x) exit
        end do
        text = trim(adjustl(buf))
        e = index(text, 'E')
        if (e == 0) return              ! not a number: as written
        read (text(e + 1:), *) exponent
        sign = ''
        if (text(1:1) == '-') sign = '-'
        ! the significant digits, trailing zeros dropped (at least one kept)
        digits = text(len(sign) + 1:len(sign) + 1) // text(len(sign) + 3:e - 1)
        digits = digits(1:max(1, verify(digits, '0', back=.true.)))
        if (exponent < -4 .or. exponent >= 16) then
            text = sign // digits(1:1)
            if (len(digits) > 1) text = text // '.' // digits(2:)
            text = text // 'E' // int_text(exponent)
        else if (exponent < 0) then
            text = sign // '0.' // repeat('0', -exponent - 1) // digits
        else if (len(digits) <= exponent + 1) then
            text = sign // digits // repeat('0', exponent + 1 - len(digits))
        else
            text = sign // digits(1:exponent + 1) // '.' // digits(exponent + 2:)
        end if
    end function exact_text

    !> i without blanks.
    pure function int_text_default(i) result(text)
        integer, intent(in) :: i
        character(len=:), allocatable :: text
        character(len=16) :: buf
        write (buf, '(i0)') i
        text = trim(buf)
    end function int_text_default

    !> i without blanks (64-bit: counts of entries, bytes, offsets).
    pure function int_text_i8(i) result(text)
        integer(i8), intent(in) :: i
        character(len=:), allocatable :: text
        character(len=24) :: buf
        write (buf, '(i0)') i
        text = trim(buf)
    end function int_text_i8

    !> s in lower case (ASCII).
    pure function lower(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: i, c
        t = s
        do i = 1, len(s)
            c = iachar(s(i:i))
            if (c >= iachar('A') .and. c <= iachar('Z')) t(i:i) = achar(c + 32)
        end do
    end function lower

    !> The text itself when short; else its start, '...' and its length:
    !> a message quotes at most ~80 characters of what a user wrote.
    pure function excerpt(text) result(short)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: short
        integer, parameter :: max_quote = 80
        character(len=24) :: buf
        if (len(text) <= max_quote) then
            short = text
        else
            write (buf, '(i0)') len(text)
            short = text(1:max_quote - 20) // '... (' // trim(buf) // ' characters)'
        end if
    end function excerpt

    !> The candidate closest to `word` by edit distance (insertions,
    !> deletions, substitutions, transpositions), '' when none is close:
    !> at most a third of the word's length, and at least 1, may differ.
    pure function nearest(word, candidates) result(best)
        character(len=*), intent(in) :: word, candidates(:)
        character(len=:), allocatable :: best
        integer :: i, d, dbest
        best = ''
        if (len(word) > 64) return
        dbest = max(1, len(word) / 3) + 1
        do i = 1, size(candidates)
            if (len_trim(candidates(i)) == 0) cycle
            d = edit_distance(lower(word), lower(trim(candidates(i))))
            if (d < dbest) then
                dbest = d
                best = trim(candidates(i))
            end if
        end do
    end function nearest

    !> Optimal string alignment distance (Damerau–Levenshtein without
    !> repeated edits of one substring).
    pure integer function edit_distance(a, b) result(d)
        character(len=*), intent(in) :: a, b
        integer :: prev2(0:len(b)), prev(0:len(b)), row(0:len(b))
        integer :: i, j, cost
        prev2 = 0
        prev = [(j, j = 0, len(b))]
        row = 0
        do i = 1, len(a)
            row(0) = i
            do j = 1, len(b)
                cost = merge(0, 1, a(i:i) == b(j:j))
                row(j) = min(prev(j) + 1, row(j - 1) + 1, prev(j - 1) + cost)
                if (i > 1 .and. j > 1) then
                    if (a(i:i) == b(j - 1:j - 1) .and. a(i - 1:i - 1) == b(j:j)) &
                        row(j) = min(row(j), prev2(j - 2) + 1)
                end if
            end do
            prev2 = prev
            prev = row
        end do
        d = prev(len(b))
    end function edit_distance
end module flexmbs_core_text
