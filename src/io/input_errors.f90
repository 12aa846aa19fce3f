!> The errors of one input file, collected so that a user sees all of them
!> in one run: each 'path: &group: name = value: reason (line n)', the
!> user's text quoted in at most 80 characters (core/text excerpt).
module flexmbs_io_input_errors
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: excerpt
    implicit none
    private

    !> Errors kept per file; more are counted, not listed.
    integer, parameter, public :: max_errors = 25
    type :: message_t
        character(len=:), allocatable :: text
    end type message_t

    !> The messages of one input file (at most max_errors kept) and the file's
    !> path that prefixes them; `to_status` turns them into one status.
    type, public :: input_errors_t
        private
        character(len=:), allocatable :: path
        type(message_t) :: messages(max_errors)
        integer :: count = 0
    contains
        procedure :: start => errors_start
        procedure :: add => errors_add
        procedure :: add_value => errors_add_value
        procedure :: n => errors_count
        procedure :: to_status => errors_to_status
    end type input_errors_t

    public :: excerpt, at_line, at_other

contains

    !> Start collecting the errors of file `path`.
    subroutine errors_start(self, path)
        class(input_errors_t), intent(inout) :: self
        character(len=*), intent(in) :: path
        self%path = excerpt(path)
        self%count = 0
    end subroutine errors_start

    !> 'path: what (line n)'; `what` is already bounded by the caller
    !> (quote the user's words through `excerpt`). line 0: no line.
    subroutine errors_add(self, what, line)
        class(input_errors_t), intent(inout) :: self
        character(len=*), intent(in) :: what
        integer, intent(in) :: line
        self%count = self%count + 1
        if (self%count <= max_errors) &
            self%messages(self%count)%text = self%path // ': ' // what // at_line(line)
    end subroutine errors_add

    !> 'path: &group: name = value: reason (line n)', value quoted in at
    !> most 80 characters.
    subroutine errors_add_value(self, group, name, value, reason, line)
        class(input_errors_t), intent(inout) :: self
        character(len=*), intent(in) :: group, name, value, reason
        integer, intent(in) :: line
        call self%add('&' // excerpt(group) // ': ' // excerpt(name) // ' = ' // &
                      excerpt(value) // ': ' // reason, line)
    end subroutine errors_add_value

    pure integer function errors_count(self)
        class(input_errors_t), intent(in) :: self
        errors_count = self%count
    end function errors_count

    !> Bad input with every message, one per line (the first ones when
    !> there are more than max_errors); status untouched when none.
    subroutine errors_to_status(self, status)
        class(input_errors_t), intent(in) :: self
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: text
        integer :: i
        character(len=16) :: buf
        if (self%count == 0) return
        text = self%messages(1)%text
        do i = 2, min(self%count, max_errors)
            text = text // new_line('a') // self%messages(i)%text
        end do
        if (self%count > max_errors) then
            write (buf, '(i0)') self%count - max_errors
            text = text // new_line('a') // self%path // ': ... and ' // trim(buf) // &
                ' more errors'
        end if
        call status%set(status_bad_input, text)
    end subroutine errors_to_status


    !> ' (line n)', or '' for line 0.
    pure function at_line(line) result(text)
        integer, intent(in) :: line
        character(len=:), allocatable :: text
        character(len=24) :: buf
        text = ''
        if (line <= 0) return
        write (buf, '(i0)') line
        text = ' (line ' // trim(buf) // ')'
    end function at_line

    !> ' at line n': where the other group of a clash starts (a message's
    !> own '(line m)' is its value's).
    pure function at_other(line) result(text)
        integer, intent(in) :: line
        character(len=:), allocatable :: text
        character(len=24) :: buf
        write (buf, '(i0)') line
        text = ' at line ' // trim(buf)
    end function at_other
end module flexmbs_io_input_errors
