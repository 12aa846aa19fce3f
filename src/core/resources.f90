!> What the machine has: its physical memory and the free space of a file
!> system, for the size checks of the input (a mesh or an output that
!> cannot fit is bad input, said before anything is allocated or written).
module flexmbs_core_resources
    use, intrinsic :: iso_c_binding, only: c_long_long, c_char, c_null_char
    use flexmbs_core_kinds, only: wp, i8
    implicit none
    private

    public :: physical_memory, free_space, bytes_text

    interface
        function c_physical_memory() bind(C, name='flexmbs_physical_memory') result(bytes)
            import :: c_long_long
            integer(c_long_long) :: bytes
        end function c_physical_memory
        function c_free_space(folder) bind(C, name='flexmbs_free_space') result(bytes)
            import :: c_long_long, c_char
            character(kind=c_char), intent(in) :: folder(*)
            integer(c_long_long) :: bytes
        end function c_free_space
    end interface

contains

    !> Physical memory in bytes; -1 when the system does not say.
    integer(i8) function physical_memory()
        physical_memory = int(c_physical_memory(), i8)
    end function physical_memory

    !> Free bytes in the file system of `folder` ('' = the working
    !> directory); -1 when the system does not say.
    integer(i8) function free_space(folder)
        character(len=*), intent(in) :: folder
        if (len(folder) == 0) then
            free_space = int(c_free_space('.' // c_null_char), i8)
        else
            free_space = int(c_free_space(folder // c_null_char), i8)
        end if
    end function free_space

    !> A byte count for people: '2.4 TB', '24 GB', '512 MB'.
    function bytes_text(bytes) result(text)
        real(wp), intent(in) :: bytes
        character(len=:), allocatable :: text
        character(len=*), parameter :: units(5) = ['B ', 'kB', 'MB', 'GB', 'TB']
        character(len=16) :: buf
        real(wp) :: x
        integer :: u
        x = bytes
        u = 1
        do while (x >= 1000.0_wp .and. u < size(units))
            x = x / 1000.0_wp
            u = u + 1
        end do
        write (buf, '(f0.1)') x
        text = trim(adjustl(buf)) // ' ' // trim(units(u))
    end function bytes_text
end module flexmbs_core_resources
