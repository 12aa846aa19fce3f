!> Whole files as text, with status messages that name the file; what a
!> path names (nothing, a file, a folder; the same file as another).
module flexmbs_core_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_long_long, c_null_char
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_resources, only: physical_memory, bytes_text
    implicit none
    private
    public :: read_text_file, read_first_lines, same_file, same_path, file_kind, &
        make_scratch_folder, write_file_atomically, make_folder, absolute_path, delete_file, &
        error_text

    !> What a path names (file_kind).
    integer, parameter, public :: file_missing = 0, file_regular = 1, file_folder = 2, &
        file_fifo = 3, file_device = 4, file_other = 5
    !> Longest resolved path handled (Linux's PATH_MAX).
    integer, parameter :: max_path = 4096

    interface
        function c_write_atomically(path, text, n) bind(C, name='flexmbs_write_atomically') &
            result(rc)
            import :: c_char, c_int, c_long_long
            character(kind=c_char), intent(in) :: path(*), text(*)
            integer(c_long_long), value :: n
            integer(c_int) :: rc
        end function c_write_atomically
        function c_make_folder(path) bind(C, name='flexmbs_make_folder') result(rc)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: rc
        end function c_make_folder
        subroutine c_error_text(code, out, n) bind(C, name='flexmbs_error_text')
            import :: c_char, c_int
            integer(c_int), value :: code, n
            character(kind=c_char), intent(out) :: out(*)
        end subroutine c_error_text
        function c_same_file(a, b) bind(C, name='flexmbs_same_file') result(same)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: a(*), b(*)
            integer(c_int) :: same
        end function c_same_file
        function c_file_kind(path, size) bind(C, name='flexmbs_file_kind') result(kind)
            import :: c_char, c_int, c_long_long
            character(kind=c_char), intent(in) :: path(*)
            integer(c_long_long), intent(out) :: size
            integer(c_int) :: kind
        end function c_file_kind
        function c_resolved_path(path, out, n) bind(C, name='flexmbs_resolved_path') &
            result(length)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            character(kind=c_char), intent(out) :: out(*)
            integer(c_int), value :: n
            integer(c_int) :: length
        end function c_resolved_path
        function c_make_scratch_folder(path) bind(C, name='flexmbs_make_scratch_folder') &
            result(rc)
            import :: c_char, c_int
            character(kind=c_char), intent(inout) :: path(*)
            integer(c_int) :: rc
        end function c_make_scratch_folder
    end interface

contains

    !> The whole file as one string (line ends kept). A missing file, a
    !> folder, FIFO or device (reading one could block for ever) and a file
    !> beyond what a string holds (2 GiB) or the machine's memory are bad
    !> input; an unreadable one an I/O error. Sizes are counted in 64 bits.
    subroutine read_text_file(path, text, status)
        character(len=*), intent(in) :: path
        character(len=:), allocatable, intent(out) :: text
        type(status_t), intent(out) :: status
        integer :: unit, ios, nbytes
        integer(i8) :: size, machine
        character(len=256) :: msg
        select case (file_kind(path, size))
        case (file_missing)
            call status%set(status_bad_input, path // ': no such file')
            return
        case (file_folder)
            call status%set(status_bad_input, path // ': is a folder, not a file')
            return
        case (file_fifo, file_device, file_other)
            call status%set(status_bad_input, path // ': not a regular file (a FIFO, device &
                &or socket); give a file')
            return
        end select
        machine = physical_memory()
        if (size > int(huge(1), i8)) then
            call status%set(status_bad_input, path // ': ' // bytes_text(real(size, wp)) // &
                ', larger than an input can be (2 GiB)')
            return
        else if (machine > 0 .and. 3 * size > machine) then
            call status%set(status_bad_input, path // ': ' // bytes_text(real(size, wp)) // &
                ', too large to read on this machine (' // bytes_text(real(machine, wp)) // ')')
            return
        end if
        nbytes = int(size)
        open (newunit=unit, file=path, access='stream', form='unformatted', &
              action='read', status='old', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot open: ' // trim(msg))
            return
        end if
        allocate (character(len=nbytes) :: text, stat=ios)
        if (ios /= 0) then
            close (unit)
            call status%set(status_bad_input, path // ': ' // bytes_text(real(size, wp)) // &
                ': not enough memory to read it')
            return
        end if
        if (nbytes > 0) read (unit, iostat=ios, iomsg=msg) text
        close (unit)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot read: ' // trim(msg))
    end subroutine read_text_file

    !> What `path` names (file_missing, file_regular, ...) and, for a
    !> regular file, its size in bytes.
    integer function file_kind(path, size)
        character(len=*), intent(in) :: path
        integer(i8), intent(out) :: size
        integer(c_long_long) :: bytes
        file_kind = c_file_kind(path // c_null_char, bytes)
        size = int(bytes, i8)
    end function file_kind

    !> Whether two paths name one existing file (same device and inode),
    !> however they are spelled.
    logical function same_file(a, b)
        character(len=*), intent(in) :: a, b
        same_file = c_same_file(a // c_null_char, b // c_null_char) /= 0
    end function same_file

    !> Whether two paths name one file, existing or not yet written: the same
    !> device and inode, or the same absolute path once links, '.' and '..'
    !> of their folders are resolved.
    logical function same_path(a, b)
        character(len=*), intent(in) :: a, b
        character(len=:), allocatable :: ra, rb
        same_path = same_file(a, b)
        if (same_path) return
        ra = resolved(a)
        rb = resolved(b)
        same_path = len(ra) > 0 .and. ra == rb
    end function same_path

    !> A new folder `prefix` // six characters, which no one else has
    !> (mkdtemp(3)): scratch space that may be removed whole afterwards.
    subroutine make_scratch_folder(prefix, path, status)
        character(len=*), intent(in) :: prefix
        character(len=:), allocatable, intent(out) :: path
        type(status_t), intent(out) :: status
        character(kind=c_char, len=len(prefix) + 7) :: buf
        buf = prefix // 'XXXXXX' // c_null_char
        if (c_make_scratch_folder(buf) /= 0) then
            call status%set(status_io_error, prefix // 'XXXXXX: cannot create the folder')
            return
        end if
        path = buf(1:len(buf) - 1)
    end subroutine make_scratch_folder

    !> `text` as the whole of the file `path`, or nothing: written to a new
    !> file beside it, flushed, then renamed over it (flexmbs_write_atomically),
    !> so that no reader and no process killed meanwhile sees a part of it.
    subroutine write_file_atomically(path, text, status)
        character(len=*), intent(in) :: path, text
        type(status_t), intent(out) :: status
        integer(c_int) :: rc
        rc = c_write_atomically(path // c_null_char, text, int(len(text), c_long_long))
        if (rc /= 0) call status%set(status_io_error, path // ': cannot write: ' // &
            error_text(rc))
    end subroutine write_file_atomically

    !> The folder `path` (its parent must exist); nothing when it is one.
    subroutine make_folder(path, status)
        character(len=*), intent(in) :: path
        type(status_t), intent(out) :: status
        integer(c_int) :: rc
        rc = c_make_folder(path // c_null_char)
        if (rc /= 0) call status%set(status_io_error, path // ': cannot create the folder: ' &
            // error_text(rc))
    end subroutine make_folder

    !> Remove the file `path` if there is one; false when it stays.
    logical function delete_file(path)
        character(len=*), intent(in) :: path
        integer :: unit, ios
        logical :: exists
        inquire (file=path, exist=exists)
        delete_file = .true.
        if (.not. exists) return
        open (newunit=unit, file=path, status='old', iostat=ios)
        if (ios == 0) close (unit, status='delete', iostat=ios)
        inquire (file=path, exist=exists)
        delete_file = .not. exists
    end function delete_file

    !> The absolute path of `path`, links, '.' and '..' resolved (the
    !> file's own when it exists, else its folder's and its name); '' when
    !> its folder does not exist.
    function absolute_path(path) result(absolute)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: absolute
        absolute = resolved(path)
    end function absolute_path

    !> strerror(3) of an errno value.
    function error_text(code) result(text)
        integer(c_int), intent(in) :: code
        character(len=:), allocatable :: text
        character(kind=c_char, len=256) :: buf
        buf = ''
        call c_error_text(code, buf, int(len(buf), c_int))
        text = buf(1:max(index(buf, c_null_char) - 1, 0))
    end function error_text

    !> The first lines of a text file, as many as `lines` holds: `count` of
    !> them were read (fewer when the file is shorter or unreadable).
    subroutine read_first_lines(path, lines, count)
        character(len=*), intent(in) :: path
        character(len=*), intent(out) :: lines(:)
        integer, intent(out) :: count
        integer :: unit, ios
        lines = ''
        count = 0
        open (newunit=unit, file=path, action='read', status='old', iostat=ios)
        if (ios /= 0) return
        do while (count < size(lines))
            read (unit, '(a)', iostat=ios) lines(count + 1)
            if (ios /= 0) exit
            count = count + 1
        end do
        close (unit)
    end subroutine read_first_lines

    !> The absolute path of `path` (flexmbs_resolved_path), '' when its
    !> folder does not exist.
    function resolved(path) result(absolute)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: absolute
        character(kind=c_char, len=max_path) :: buf
        integer :: length
        length = int(c_resolved_path(path // c_null_char, buf, int(max_path, c_int)))
        absolute = ''
        if (length > 0) absolute = buf(1:length)
    end function resolved
end module flexmbs_core_files
