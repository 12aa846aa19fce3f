!> Whole files as text, with status messages that name the file.
module flexmbs_core_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    implicit none
    private
    public :: read_text_file, same_file

    interface
        function c_same_file(a, b) bind(C, name='flexmbs_same_file') result(same)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: a(*), b(*)
            integer(c_int) :: same
        end function c_same_file
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
end module flexmbs_core_files
