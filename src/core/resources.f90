!> What the machine has: its physical memory and the free space of a file
!> system, for the size checks of the input (a mesh or an output that
!> cannot fit is bad input, said before anything is allocated or written).
module flexmbs_core_resources
    use, intrinsic :: iso_c_binding, only: c_long_long, c_char, c_null_char
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_solver_failure
    implicit none
    private

    public :: physical_memory, free_space, bytes_text, out_of_memory

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
    pure function bytes_text(bytes) result(text)
        real(wp), intent(in) :: bytes
        character(len=:), allocatable :: text
        character(len=*), parameter :: units(5) = ['B ', 'kB', 'MB', 'GB', 'TB']
        character(len=40) :: buf
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

    !> Record in `status` that allocating `what`, `count` entries of
    !> `entry_bytes` bytes each, failed (`stat=` non-zero). A solver failure,
    !> not bad input: the input was checked against the memory before
    !> anything was built, so what is left is a machine, or a limit, with less
    !> free memory than the check saw. The compiler's `errmsg=` is not quoted:
    !> gfortran 12 says 'Attempt to allocate an allocated object' for every
    !> failed allocation, out of memory included.
    pure subroutine out_of_memory(status, what, count, entry_bytes)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: what !! e.g. 'KLU matrix values'
        integer(i8), intent(in) :: count     !! entries asked for
        integer, intent(in) :: entry_bytes   !! bytes of one entry
        character(len=24) :: buf
        write (buf, '(i0)') count
        call status%set(status_solver_failure, 'out of memory: ' // what // ' (' // &
            trim(buf) // ' entries, ' // bytes_text(real(count, wp) * entry_bytes) // ')')
    end subroutine out_of_memory
end module flexmbs_core_resources
