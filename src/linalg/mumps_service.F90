!> The processes of an MPI run (`make MPI=1`, `mpirun -n N flexmbs run`):
!> rank 0 does everything; the other ranks only take part in MUMPS's
!> factorisations and solves, which MUMPS distributes over the
!> communicator. Every call of MUMPS on rank 0 (linalg/mumps) is first
!> announced to the others (`mumps_announce`: which instance, real or
!> complex, JOB, ICNTL, CNTL), which make the same call on their copy of
!> that instance in `mumps_serve`; the matrix, the right-hand sides and the
!> solutions stay on rank 0 (centralised, ICNTL(18) = 0, ICNTL(20) = 0,
!> ICNTL(21) = 0).
!>
!> The sequential build links MUMPS's sequential library, whose MPI stubs
!> answer one process: the same code then announces nothing. `mpi_build`
!> tells the builds apart (the preprocessor's FLEXMBS_MPI).
module flexmbs_linalg_mumps_service
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure
    implicit none
    private

    include 'mpif.h'
    include 'dmumps_struc.h'
    include 'zmumps_struc.h'

#ifdef FLEXMBS_MPI
    logical, parameter, public :: mpi_build = .true.
#else
    !> Whether this flexmbs links MUMPS's MPI build (`make MPI=1`).
    logical, parameter, public :: mpi_build = .false.
#endif
    !> MUMPS instances alive at once (a run holds a few).
    integer, parameter :: max_instances = 64
    !> What a message asks: stop serving, or a call of a real or a complex
    !> instance.
    integer, parameter, public :: call_stop = 0, call_real = 1, call_complex = 2
    integer, parameter :: job_init = -1, job_end = -2
    !> The message: what, instance, JOB, ICNTL(1:60), then CNTL(1:15) as
    !> integers (one MPI type for every broadcast: gfortran refuses one
    !> external called with two types).
    integer, parameter :: head_size = 63
    integer, parameter :: message_size = head_size + 15 * storage_size(1.0_wp) / storage_size(1)

    integer, save :: rank = 0, processes = 1
    logical, save :: started = .false.
    logical, save :: taken(max_instances) = .false.

    public :: start_processes, stop_processes, process_rank, process_count, &
        mumps_serve, mumps_announce, take_instance, free_instance

contains

    !> Initialise MPI (once); rank and number of the processes.
    subroutine start_processes(my_rank, count)
        integer, intent(out) :: my_rank, count
        integer :: ierr
        logical :: ready
        if (.not. started) then
            call MPI_INITIALIZED(ready, ierr)
            if (.not. ready) call MPI_INIT(ierr)
            call MPI_COMM_RANK(MPI_COMM_WORLD, rank, ierr)
            call MPI_COMM_SIZE(MPI_COMM_WORLD, processes, ierr)
            started = .true.
        end if
        my_rank = rank
        count = processes
    end subroutine start_processes

    !> Rank 0: tell the other ranks to stop serving; every rank: finalise MPI.
    subroutine stop_processes()
        integer :: message(message_size), ierr
        if (.not. started) return
        if (rank == 0 .and. processes > 1) then
            message = 0
            message(1) = call_stop
            call MPI_BCAST(message, message_size, MPI_INTEGER, 0, MPI_COMM_WORLD, ierr)
        end if
        call MPI_FINALIZE(ierr)
        started = .false.
    end subroutine stop_processes

    !> This process's rank (0 before start_processes).
    integer function process_rank()
        process_rank = rank
    end function process_rank

    !> The number of processes (1 before start_processes and in the
    !> sequential build).
    integer function process_count()
        process_count = processes
    end function process_count

    !> A free instance number for a new MUMPS instance of rank 0; failure
    !> when max_instances are alive.
    subroutine take_instance(instance, status)
        integer, intent(out) :: instance
        type(status_t), intent(inout) :: status
        integer :: k
        instance = 0
        do k = 1, max_instances
            if (taken(k)) cycle
            taken(k) = .true.
            instance = k
            return
        end do
        call status%set(status_solver_failure, 'mumps: more than 64 instances alive at once')
    end subroutine take_instance

    !> The instance number is free again (after its JOB = -2).
    subroutine free_instance(instance)
        integer, intent(in) :: instance
        if (instance >= 1 .and. instance <= max_instances) taken(instance) = .false.
    end subroutine free_instance

    !> Rank 0, before each call of MUMPS with JOB = `job` on `instance`
    !> (`what`: call_real or call_complex): the other ranks make the same
    !> call. Nothing with one process.
    subroutine mumps_announce(what, instance, job, icntl, cntl)
        integer, intent(in) :: what, instance, job, icntl(60)
        real(wp), intent(in) :: cntl(15)
        integer :: message(message_size), ierr
        if (processes <= 1 .or. rank /= 0) return
        message(1:head_size) = [what, instance, job, icntl]
        message(head_size + 1:) = transfer(cntl, message, message_size - head_size)
        call MPI_BCAST(message, message_size, MPI_INTEGER, 0, MPI_COMM_WORLD, ierr)
    end subroutine mumps_announce

    !> The other ranks: make the calls rank 0 announces, on their own copy
    !> of each instance, until it says stop.
    subroutine mumps_serve()
        type(dmumps_struc), allocatable, target :: reals(:)
        type(zmumps_struc), allocatable, target :: complexes(:)
        integer :: message(message_size), ierr, what, k, job
        real(wp) :: values(15)
        allocate (reals(max_instances), complexes(max_instances))
        do
            call MPI_BCAST(message, message_size, MPI_INTEGER, 0, MPI_COMM_WORLD, ierr)
            what = message(1)
            if (what == call_stop) exit
            values = transfer(message(head_size + 1:), values)
            k = message(2)
            job = message(3)
            select case (what)
            case (call_real)
#define SERVED reals(k)
#define SERVE_DRIVER dmumps
#include "mumps_serve_call.inc"
            case (call_complex)
#undef SERVED
#undef SERVE_DRIVER
#define SERVED complexes(k)
#define SERVE_DRIVER zmumps
#include "mumps_serve_call.inc"
            end select
        end do
    contains
        !> A new instance (JOB = -1) as rank 0 makes it.
        subroutine prepare(comm, sym, par, previous)
            integer, intent(inout) :: comm, sym, par, previous
            if (job /= job_init) return
            comm = MPI_COMM_WORLD
            sym = 0
            par = 1
            previous = 0
        end subroutine prepare
    end subroutine mumps_serve
end module flexmbs_linalg_mumps_service
