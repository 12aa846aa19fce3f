!> A sink that keeps the run's checkpoint in its HDF5 result
!> (io/checkpoint): after an accepted step once `interval` wall seconds
!> have passed since the last one (every accepted step for interval 0),
!> and on the step after which the run stops for SIGINT or SIGTERM. The
!> records up to the step are written first, so a resume finds every
!> record the checkpoint counts.
module flexmbs_run_checkpoint_sink
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_signals, only: signal_pending
    use flexmbs_core_timer, only: timer_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_checkpoint, only: checkpoint_t
    implicit none
    private

    public :: new_checkpoint_sink

    !> The checkpoint sink (see the module): the file it writes into, the
    !> solver whose step counts it records, the checkpoint it keeps.
    type, extends(sink_t), public :: checkpoint_sink_t
        private
        type(hdf5_sink_t), pointer :: h5 => null()
        class(dae_solver_t), pointer :: solver => null()
        real(wp) :: interval = 60.0_wp
        integer(i8) :: last = 0           !! system_clock count of the last checkpoint
        type(timer_t) :: timer            !! this piece of the run
        type(checkpoint_t) :: cp
        integer :: written = 0            !! checkpoints written
    contains
        procedure :: output => checkpoint_output
        procedure :: wants_steps => checkpoint_wants_steps
        procedure :: step => checkpoint_step
        procedure :: count => checkpoint_count
    end type checkpoint_sink_t

contains

    !> The sink of a run writing into `h5` (open, of n unknowns) with
    !> `solver`: piece 1 of the run without `prior`, else the piece after
    !> those whose statistics `prior` sums.
    function new_checkpoint_sink(h5, solver, n, interval, piece, prior) result(sink)
        type(hdf5_sink_t), target, intent(in) :: h5
        class(dae_solver_t), target, intent(in) :: solver
        integer, intent(in) :: n
        real(wp), intent(in) :: interval   !! wall seconds; 0: every accepted step
        integer, intent(in) :: piece
        type(dae_stats_t), intent(in) :: prior
        type(checkpoint_sink_t) :: sink
        integer(i8) :: rate
        sink%h5 => h5
        sink%solver => solver
        sink%interval = interval
        allocate (sink%cp%y(n))
        sink%cp%piece = piece
        sink%cp%prior = prior
        call sink%timer%start()
        call system_clock(sink%last, rate)
    end function new_checkpoint_sink

    !> Output times need nothing: checkpoints are of accepted steps.
    subroutine checkpoint_output(self, t, y, status)
        class(checkpoint_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
    end subroutine checkpoint_output

    logical function checkpoint_wants_steps(self)
        class(checkpoint_sink_t), intent(in) :: self
        checkpoint_wants_steps = .true.
    end function checkpoint_wants_steps

    !> The checkpoint of the step [t_old, t] when it is due (the module).
    subroutine checkpoint_step(self, nr, t_old, t, y, dense, stop, status)
        class(checkpoint_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        integer(i8) :: now, rate
        integer :: attempted, accepted
        if (nr == 1 .or. .not. status%ok()) return  ! t0: nothing to continue from
        call system_clock(now, rate)
        if (.not. (stop .or. signal_pending() .or. &
                   real(now - self%last, wp) >= self%interval * real(rate, wp))) return
        self%cp%t = t
        self%cp%h = t - t_old
        self%cp%order = dense%order()
        self%cp%y(:) = y
        ! nr counts the accepted steps of every solver; the attempts, the
        ! solvers that count them as they go (IDA does not: NRJ 0 then)
        call self%solver%step_counts(attempted, accepted)
        self%cp%live%nac = nr - 1
        self%cp%live%nst = max(attempted, nr - 1)
        self%cp%live%nrj = self%cp%live%nst - self%cp%live%nac
        self%cp%live%cpu = self%timer%cpu()
        self%cp%live%wall = self%timer%wall()
        call self%h5%keep_checkpoint(self%cp, status)
        self%written = self%written + 1
        self%last = now
    end subroutine checkpoint_step

    !> Checkpoints written so far.
    integer function checkpoint_count(self)
        class(checkpoint_sink_t), intent(in) :: self
        checkpoint_count = self%written
    end function checkpoint_count
end module flexmbs_run_checkpoint_sink
