!> A tiny test harness: a test is a subroutine with an allocatable error
!> argument; suites collect tests; one driver runs them all.
module testing
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    type, public :: error_t
        character(len=:), allocatable :: message
    end type error_t

    abstract interface
        subroutine test_i(error)
            import :: error_t
            type(error_t), allocatable, intent(out) :: error
        end subroutine test_i
    end interface

    !> The name has a fixed length: collect_* functions build their lists as
    !> array constructors of new_test results, and gfortran 12 never frees
    !> the allocatable components of such results.
    type, public :: test_case_t
        character(len=64) :: name = ''
        procedure(test_i), pointer, nopass :: run => null()
    end type test_case_t

    public :: test_i, new_test, check, check_close, run_suite

contains

    function new_test(name, run) result(test)
        character(len=*), intent(in) :: name
        procedure(test_i) :: run
        type(test_case_t) :: test
        if (len(name) > len(test%name)) error stop 'new_test: name too long: ' // name
        test%name = name
        test%run => run
    end function new_test

    !> Record a failure when cond is false (keeps the first failure).
    subroutine check(error, cond, message)
        type(error_t), allocatable, intent(inout) :: error
        logical, intent(in) :: cond
        character(len=*), intent(in) :: message
        if (allocated(error)) return
        if (.not. cond) then
            allocate (error)
            error%message = message
        end if
    end subroutine check

    !> Record a failure unless |actual - expected| <= tol (absolute) or,
    !> with rel=.true., <= tol*|expected|. NaN always fails.
    subroutine check_close(error, actual, expected, tol, message, rel)
        type(error_t), allocatable, intent(inout) :: error
        real(wp), intent(in) :: actual, expected, tol
        character(len=*), intent(in) :: message
        logical, intent(in), optional :: rel
        real(wp) :: bound
        character(len=200) :: buf
        if (allocated(error)) return
        bound = tol
        if (present(rel)) then
            if (rel) bound = tol * abs(expected)
        end if
        if (.not. (abs(actual - expected) <= bound)) then
            write (buf, '(a,es24.16,a,es24.16,a,es10.3)') ': got ', actual, ' expected ', &
                expected, ' tol ', bound
            allocate (error)
            error%message = message // trim(buf)
        end if
    end subroutine check_close

    !> Run every test of a suite whose name matches `filter` (substring of
    !> 'suite/test'; empty runs all); count passes and failures.
    subroutine run_suite(suite, tests, filter, npassed, nfailed)
        character(len=*), intent(in) :: suite
        type(test_case_t), intent(in) :: tests(:)
        character(len=*), intent(in) :: filter
        integer, intent(inout) :: npassed, nfailed
        type(error_t), allocatable :: error
        integer :: i
        character(len=:), allocatable :: full
        do i = 1, size(tests)
            full = suite // '/' // trim(tests(i)%name)
            if (len_trim(filter) > 0) then
                if (index(full, trim(filter)) == 0) cycle
            end if
            call tests(i)%run(error)
            if (allocated(error)) then
                nfailed = nfailed + 1
                write (*, '(a)') 'FAIL ' // full // ': ' // error%message
                deallocate (error)
            else
                npassed = npassed + 1
                write (*, '(a)') 'pass ' // full
            end if
            flush (6)
        end do
    end subroutine run_suite
end module testing
