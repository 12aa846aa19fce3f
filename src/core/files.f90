!> Whole files as text, with status messages that name the file.
module flexmbs_core_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_text, only: int_text
    implicit none
    private
    public :: read_text_file, same_file, file_kind, folder_of

    !> What a path names (file_kind), links followed.
    integer, parameter, public :: file_missing = 0, file_regular = 1, file_folder = 2, &
        file_special = 3

    interface
        function c_same_file(a, b) bind(C, name='flexmbs_same_file') result(same)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: a(*), b(*)
            integer(c_int) :: same
        end function c_same_file
        function c_file_kind(path) bind(C, name='flexmbs_file_kind') result(kind)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: kind
        end function c_file_kind
    end interface

contains

    !> The whole file as one string (line ends kept); a missing file, a
    !> folder or anything but a regular file (a FIFO would block the read, a
    !> device never end) is bad input, an unreadable one an I/O error.
    subroutine read_text_file(path, text, status)
        character(len=*), intent(in) :: path
        character(len=:), allocatable, intent(out) :: text
        type(status_t), intent(out) :: status
        integer :: unit, ios, nbytes
        character(len=256) :: msg
        select case (file_kind(path))
        case (file_missing)
            call status%set(status_bad_input, path // ': no such file')
            return
        case (file_folder)
            call status%set(status_bad_input, path // ': is a folder, not a file')
            return
        case (file_special)
            call status%set(status_bad_input, path // ': not a regular file (a FIFO, a &
                &device or a socket): refused, it may block or never end')
            return
        end select
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
        allocate (character(len=nbytes) :: text, stat=ios, errmsg=msg)
        if (ios /= 0) then
            close (unit)
            call status%set(status_io_error, path // ': cannot hold its ' // &
                int_text(nbytes) // ' bytes in memory: ' // trim(msg))
            return
        end if
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

    !> What `path` names: file_missing, file_regular, file_folder or
    !> file_special (FIFO, device, socket); links are followed.
    integer function file_kind(path)
        character(len=*), intent(in) :: path
        file_kind = c_file_kind(path // c_null_char)
    end function file_kind

    !> The folder part of a path ('' for a bare name, '/' for one in the root).
    pure function folder_of(path) result(folder)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: folder
        integer :: slash
        slash = index(path, '/', back=.true.)
        if (slash == 0) then
            folder = ''
        else if (slash == 1) then
            folder = '/'
        else
            folder = path(1:slash - 1)
        end if
    end function folder_of
end module flexmbs_core_files
