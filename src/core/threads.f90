!> How many threads the BLAS uses (docs/linear_algebra.md).
!>
!> OpenBLAS starts as many threads as there are cores. flexmbs's dense
!> factorisations are small (the classic faces, small scenes, MUMPS's
!> fronts): on them threads cost more than they gain. Measured on the
!> five-body scene (RADAU5 + GGL, TOL 1e-6, dense LU of order 547, two
!> cores): one thread 4.9-5.2 s wall and as much CPU, two threads 4.1-5.0 s
!> wall at 8.0-10.0 s CPU; on an earlier machine 11.5 s wall with two
!> threads against 7.0 s with one. Studies run two processes at a time.
!> So unless the user says otherwise — OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS
!> or OMP_NUM_THREADS set in the environment, which are then left alone —
!> the solvers put OpenBLAS on one thread when they set up their linear
!> algebra (`default_blas_threads`, idempotent). The finite-element
!> assembly has its own threads (OPENMP=1 builds), independent of this.
module flexmbs_core_threads
    use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
    implicit none
    private

    public :: default_blas_threads, blas_threads

    !> Whether default_blas_threads has run (it acts once per process).
    logical, save :: done = .false.

    interface
        function c_set_threads(n) bind(C, name='flexmbs_blas_set_threads') result(found)
            import :: c_int
            integer(c_int), value :: n
            integer(c_int) :: found
        end function c_set_threads
        function c_get_threads() bind(C, name='flexmbs_blas_get_threads') result(n)
            import :: c_int
            integer(c_int) :: n
        end function c_get_threads
        function c_env_is_set(name) bind(C, name='flexmbs_env_is_set') result(set)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: name(*)
            integer(c_int) :: set
        end function c_env_is_set
    end interface

contains

    !> One BLAS thread unless the environment names a count (module header).
    subroutine default_blas_threads()
        if (done) return
        done = .true.
        if (env_is_set('OPENBLAS_NUM_THREADS') .or. env_is_set('GOTO_NUM_THREADS') .or. &
            env_is_set('OMP_NUM_THREADS')) return
        if (c_set_threads(1_c_int) == 0) return ! not OpenBLAS: nothing to set
    end subroutine default_blas_threads

    !> OpenBLAS's thread count now; 0 when the BLAS is not OpenBLAS.
    integer function blas_threads()
        blas_threads = int(c_get_threads())
    end function blas_threads

    logical function env_is_set(name)
        character(len=*), intent(in) :: name
        env_is_set = c_env_is_set(name // c_null_char) /= 0
    end function env_is_set
end module flexmbs_core_threads
