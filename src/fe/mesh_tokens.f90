!> The text of a mesh file as tokens, and a cursor that reads them one by
!> one: words, keywords, integers and reals, each failure bad input naming
!> the file, the token's line and the reason (flexmbs_fe_mesh_file's grammar
!> reads through it).
module flexmbs_fe_mesh_tokens
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text, lower, excerpt
    use flexmbs_core_files, only: read_text_file
    implicit none
    private

    public :: open_tokens

    !> The file as tokens: start and end offsets and the line of each.
    type :: tokens_t
        integer, allocatable :: first(:), last(:), line(:)
        integer :: n = 0
    end type tokens_t

    !> A file's tokens and the position of the last one read (0: none yet).
    type, public :: token_cursor_t
        private
        character(len=:), allocatable :: path, text
        type(tokens_t) :: tok
        integer :: pos = 0
    contains
        procedure :: at_end => cursor_at_end
        procedure :: fits => cursor_fits
        procedure :: fail => cursor_fail
        procedure :: next_word => cursor_next_word
        procedure :: expect_word => cursor_expect_word
        procedure :: next_int => cursor_next_int
        procedure :: next_real => cursor_next_real
    end type token_cursor_t

contains

    !> The tokens of the file at `path`, the cursor before the first.
    subroutine open_tokens(path, cursor, status)
        character(len=*), intent(in) :: path
        type(token_cursor_t), intent(out) :: cursor
        type(status_t), intent(out) :: status
        cursor%path = path
        call read_text_file(path, cursor%text, status)
        if (.not. status%ok()) return
        call tokenise(cursor%text, cursor%tok, status)
    end subroutine open_tokens

    !> Whether every token has been read.
    pure logical function cursor_at_end(self)
        class(token_cursor_t), intent(in) :: self
        cursor_at_end = self%pos >= self%tok%n
    end function cursor_at_end

    !> Whether `count` items of `per_item` values each fit in the values
    !> the file has left; bad input (before any allocation) if not, so
    !> that a declared count of 2e9 cannot exhaust the memory.
    logical function cursor_fits(self, count, per_item, what, status) result(fits)
        class(token_cursor_t), intent(in) :: self
        integer, intent(in) :: count, per_item
        character(len=*), intent(in) :: what
        type(status_t), intent(inout) :: status
        fits = count <= (self%tok%n - self%pos) / per_item
        if (.not. fits) call self%fail(int_text(count) // ' ' // what // ' declared, but the &
            &file holds only ' // int_text(self%tok%n - self%pos) // ' more values (' // &
            int_text(per_item) // ' per item)', status)
    end function cursor_fits

    !> Bad input at the current token's line (the last line at the end).
    subroutine cursor_fail(self, reason, status)
        class(token_cursor_t), intent(in) :: self
        character(len=*), intent(in) :: reason
        type(status_t), intent(inout) :: status
        integer :: line
        line = 1
        if (self%tok%n > 0) line = self%tok%line(max(1, min(self%pos, self%tok%n)))
        call status%set(status_bad_input, self%path // ':' // int_text(line) // ': ' // reason)
    end subroutine cursor_fail

    !> The next token; bad input (what was expected) at the end of the file.
    subroutine cursor_next_word(self, word, what, status)
        class(token_cursor_t), intent(inout) :: self
        character(len=:), allocatable, intent(out) :: word
        character(len=*), intent(in) :: what
        type(status_t), intent(inout) :: status
        if (self%pos >= self%tok%n) then
            self%pos = self%tok%n
            word = ''
            call self%fail('file ends where a ' // what // ' is expected', status)
            return
        end if
        self%pos = self%pos + 1
        word = self%text(self%tok%first(self%pos):self%tok%last(self%pos))
    end subroutine cursor_next_word

    !> The next token, which must be `keyword` (any case).
    subroutine cursor_expect_word(self, keyword, status)
        class(token_cursor_t), intent(inout) :: self
        character(len=*), intent(in) :: keyword
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: word
        call self%next_word(word, '''' // keyword // '''', status)
        if (.not. status%ok()) return
        if (lower(word) /= keyword) call self%fail('''' // excerpt(word) // ''' where ''' // &
                                                   keyword // ''' is expected', status)
    end subroutine cursor_expect_word

    !> The next token as an integer (`what` names it in a message).
    subroutine cursor_next_int(self, value, what, status)
        class(token_cursor_t), intent(inout) :: self
        integer, intent(out) :: value
        character(len=*), intent(in) :: what
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: word
        integer :: ios
        value = 0
        call self%next_word(word, what, status)
        if (.not. status%ok()) return
        if (verify(word, '+-0123456789') /= 0) then
            ios = 1
        else
            read (word, *, iostat=ios) value
        end if
        if (ios /= 0) call self%fail('''' // excerpt(word) // ''' is not an integer (' // what &
                                     // ')', status)
    end subroutine cursor_next_int

    !> The next token as a real (`what` names it in a message).
    subroutine cursor_next_real(self, value, what, status)
        class(token_cursor_t), intent(inout) :: self
        real(wp), intent(out) :: value
        character(len=*), intent(in) :: what
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: word
        integer :: ios
        value = 0.0_wp
        call self%next_word(word, what, status)
        if (.not. status%ok()) return
        if (verify(word, '+-.0123456789eEdD') /= 0) then
            ios = 1
        else
            read (word, *, iostat=ios) value
        end if
        if (ios /= 0) call self%fail('''' // excerpt(word) // ''' is not a number (' // what &
                                     // ')', status)
    end subroutine cursor_next_real

    !> Split text into whitespace-separated tokens, dropping # comments.
    subroutine tokenise(text, tok, status)
        character(len=*), intent(in) :: text
        type(tokens_t), intent(out) :: tok
        type(status_t), intent(inout) :: status
        integer :: i, line, start, capacity
        logical :: comment
        character :: c
        capacity = 1024
        allocate (tok%first(capacity), tok%last(capacity), tok%line(capacity))
        line = 1
        start = 0
        comment = .false.
        do i = 1, len(text) + 1
            if (i <= len(text)) then
                c = text(i:i)
            else
                c = new_line('a')
            end if
            if (c == new_line('a') .or. c == char(13) .or. c == ' ' .or. c == char(9) &
                .or. (c == '#' .and. .not. comment)) then
                if (start > 0) call push(start, i - 1)
                if (.not. status%ok()) return
                start = 0
                if (c == '#') comment = .true.
                if (c == new_line('a')) then
                    line = line + 1
                    comment = .false.
                end if
            else if (.not. comment .and. start == 0) then
                start = i
            end if
        end do

    contains

        subroutine push(first, last)
            integer, intent(in) :: first, last
            integer, allocatable :: tmp_first(:), tmp_last(:), tmp_line(:)
            integer :: stat
            if (tok%n == capacity) then
                ! a token takes at least 2 characters: len(text) bounds the count
                capacity = int(min(2_i8 * capacity, len(text, i8) / 2 + 1, int(huge(1), i8)))
                allocate (tmp_first(capacity), tmp_last(capacity), tmp_line(capacity), &
                    stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'mesh file tokens', 3_i8 * capacity, 4)
                    return
                end if
                tmp_first(1:tok%n) = tok%first(1:tok%n)
                call move_alloc(tmp_first, tok%first)
                tmp_last(1:tok%n) = tok%last(1:tok%n)
                call move_alloc(tmp_last, tok%last)
                tmp_line(1:tok%n) = tok%line(1:tok%n)
                call move_alloc(tmp_line, tok%line)
            end if
            tok%n = tok%n + 1
            tok%first(tok%n) = first
            tok%last(tok%n) = last
            tok%line(tok%n) = line
        end subroutine push
    end subroutine tokenise
end module flexmbs_fe_mesh_tokens
