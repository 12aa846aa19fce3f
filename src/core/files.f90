!> Whole files as text, with status messages that name the file; what a
!> path names (nothing, a file, a folder; the same file as another).
module flexmbs_core_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    implicit none
    private
    public :: read_text_file, read_first_lines, same_file, same_path, path_kind, &
        make_scratch_folder

    !> What a path names (path_kind).
    integer, parameter, public :: path_missing = 0, path_file = 1, path_folder = 2, &
        path_other = 3
    !> Longest resolved path handled (Linux's PATH_MAX).
    integer, parameter :: max_path = 4096

    interface
        function c_same_file(a, b) bind(C, name='flexmbs_same_file') result(same)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: a(*), b(*)
            integer(c_int) :: same
        end function c_same_file
        function c_path_kind(path) bind(C, name='flexmbs_path_kind') result(kind)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: kind
        end function c_path_kind
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

    !> The whole file as one string (line ends kept); a missing file is bad
    !> input, an unreadable one an I/O error.
    subroutine read_text_file(path, text, status)
        character(len=*), intent(in) :: path
        character(len=:), allocatable, intent(out) :: text
        type(status_t), intent(out) :: status
        logical :: exists
        integer :: unit, ios, nbytes
        character(len=256) :: msg
        inquire (file=path, exist=exists)
        if (.not. exists) then
            call status%set(status_bad_input, path // ': no such file')
            return
        end if
        open (newunit=unit, file=path, access='stream', form='unformatted', &
              action='read', status='old', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot open: ' // trim(msg))
            return
        end if
        inquire (unit=unit, size=nbytes)
        if (nbytes < 0) then
            close (unit)
            call status%set(status_io_error, path // ': cannot determine its size')
            return
        end if
        allocate (character(len=nbytes) :: text)
        if (nbytes > 0) read (unit, iostat=ios, iomsg=msg) text
        close (unit)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot read: ' // trim(msg))
    end subroutine read_text_file

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

    !> path_missing, path_file, path_folder or path_other.
    integer function path_kind(path)
        character(len=*), intent(in) :: path
        path_kind = int(c_path_kind(path // c_null_char))
    end function path_kind

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
