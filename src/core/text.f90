!> Numbers as text for status messages, and small string helpers.
module flexmbs_core_text
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: real_text, int_text, lower, excerpt

contains

    !> x in the es14.6 format, without blanks.
    pure function real_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf
        write (buf, '(es14.6)') x
        text = trim(adjustl(buf))
    end function real_text

    !> i without blanks.
    pure function int_text(i) result(text)
        integer, intent(in) :: i
        character(len=:), allocatable :: text
        character(len=16) :: buf
        write (buf, '(i0)') i
        text = trim(buf)
    end function int_text

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
end module flexmbs_core_text
