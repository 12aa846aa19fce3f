!> Whole files as text, with status messages that name the file.
module flexmbs_core_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_long_long, c_null_char
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_resources, only: physical_memory, bytes_text
    implicit none
    private
    public :: read_text_file, same_file, file_kind
    public :: file_missing, file_regular, file_folder, file_fifo, file_device, file_other

    integer, parameter :: file_missing = 0, file_regular = 1, file_folder = 2, file_fifo = 3, &
        file_device = 4, file_other = 5

    interface
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
end module flexmbs_core_files
