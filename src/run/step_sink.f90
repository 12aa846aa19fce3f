!> A sink that keeps the accepted steps of a run: the step size h = t − t_old
!> of every accepted step and the order of the multistep formula it used
!> (the dense output's `order`, 0 for one-step methods); optionally the
!> state at one time t_state from the step's dense output. `flexmbs modes`
!> (run/modes) runs a BDF code with it to see where the step sizes put h·λ
!> relative to the A(α) sectors.
module flexmbs_run_step_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    implicit none
    private

    !> First capacity of the step arrays; they double when full.
    integer, parameter :: first_capacity = 1024

    !> The accepted steps of a run (size, end and order) and optionally the state
    !> at t_state (see the module).
    type, extends(sink_t), public :: step_sink_t
        integer :: steps = 0                 !! accepted steps kept
        real(wp), allocatable :: h(:)        !! step sizes (1:steps)
        real(wp), allocatable :: t_end(:)    !! where each step ended
        integer, allocatable :: order(:)     !! order of each step (0: one-step method)
        !> the time whose state is wanted (none when not set)
        logical :: wants_state = .false.
        real(wp) :: t_state = 0.0_wp
        logical :: has_state = .false.
        real(wp), allocatable :: state(:)
    contains
        procedure :: output => step_output
        procedure :: wants_steps => step_wants_steps
        procedure :: step => step_step
    end type step_sink_t

contains

    subroutine step_output(self, t, y, status)
        class(step_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
    end subroutine step_output

    logical function step_wants_steps(self)
        class(step_sink_t), intent(in) :: self
        step_wants_steps = .true.
    end function step_wants_steps

    subroutine step_step(self, nr, t_old, t, y, dense, stop, status)
        class(step_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        if (self%wants_state .and. .not. self%has_state) then
            if (t == self%t_state) then
                self%state = y
                self%has_state = .true.
            else if (nr > 1 .and. (t_old - self%t_state) * (t - self%t_state) < 0.0_wp) then
                allocate (self%state(size(y)))
                call dense%evaluate(self%t_state, self%state)
                self%has_state = .true.
            end if
        end if
        if (nr == 1) return
        if (.not. allocated(self%h)) allocate (self%h(first_capacity), &
            self%t_end(first_capacity), self%order(first_capacity))
        if (self%steps == size(self%h)) call grow(self)
        self%steps = self%steps + 1
        self%h(self%steps) = abs(t - t_old)
        self%t_end(self%steps) = t
        self%order(self%steps) = dense%order()
    end subroutine step_step

    !> Twice the room, the steps kept.
    subroutine grow(self)
        class(step_sink_t), intent(inout) :: self
        real(wp), allocatable :: h(:), t_end(:)
        integer, allocatable :: order(:)
        integer :: m
        m = size(self%h)
        allocate (h(2 * m), t_end(2 * m), order(2 * m))
        h(1:m) = self%h
        t_end(1:m) = self%t_end
        order(1:m) = self%order
        call move_alloc(h, self%h)
        call move_alloc(t_end, self%t_end)
        call move_alloc(order, self%order)
    end subroutine grow
end module flexmbs_run_step_sink
