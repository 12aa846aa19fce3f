!> A lowered address-space limit (RLIMIT_AS) for the tests of allocation
!> failures: Linux overcommits, so an allocation that the machine could not
!> hold may still succeed; under the limit it fails at once, whatever the
!> machine. Linux only (the resource number and rlim_t of glibc).
module memory_limit
    use, intrinsic :: iso_c_binding, only: c_int, c_long
    implicit none
    private
    public :: limit_address_space, restore_address_space

    !> struct rlimit: rlim_t is an unsigned long; RLIM_INFINITY reads as -1.
    type, bind(C) :: rlimit_t
        integer(c_long) :: cur
        integer(c_long) :: max
    end type rlimit_t

    integer(c_int), parameter :: rlimit_as = 9 !! RLIMIT_AS, <sys/resource.h>

    interface
        integer(c_int) function getrlimit(resource, rlim) bind(C, name='getrlimit')
            import :: c_int, rlimit_t
            integer(c_int), value :: resource
            type(rlimit_t), intent(out) :: rlim
        end function getrlimit
        integer(c_int) function setrlimit(resource, rlim) bind(C, name='setrlimit')
            import :: c_int, rlimit_t
            integer(c_int), value :: resource
            type(rlimit_t), intent(in) :: rlim
        end function setrlimit
        integer(c_int) function getpagesize() bind(C, name='getpagesize')
            import :: c_int
        end function getpagesize
    end interface

    type(rlimit_t), save :: saved
    logical, save :: active = .false.

contains

    !> Allow the process `margin` bytes of address space beyond what it uses
    !> now (soft limit only, so that it can be raised back). False when the
    !> system would not say or not allow it.
    logical function limit_address_space(margin) result(ok)
        integer(c_long), intent(in) :: margin
        type(rlimit_t) :: lowered
        integer(c_long) :: pages
        integer :: unit, ios
        ok = .false.
        if (active) return
        open (newunit=unit, file='/proc/self/statm', action='read', iostat=ios)
        if (ios /= 0) return
        read (unit, *, iostat=ios) pages
        close (unit)
        if (ios /= 0) return
        if (getrlimit(rlimit_as, saved) /= 0) return
        lowered = saved
        lowered%cur = pages * getpagesize() + margin
        if (saved%cur >= 0 .and. saved%cur < lowered%cur) lowered%cur = saved%cur
        if (setrlimit(rlimit_as, lowered) /= 0) return
        active = .true.
        ok = .true.
    end function limit_address_space

    !> The limit as it was before limit_address_space.
    subroutine restore_address_space()
        if (.not. active) return
        if (setrlimit(rlimit_as, saved) /= 0) error stop 'memory_limit: cannot restore RLIMIT_AS'
        active = .false.
    end subroutine restore_address_space
end module memory_limit
