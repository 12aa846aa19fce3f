!> Several sinks behind one: a solver feeds one sink, the application
!> wants the HDF5 file and the progress display at once.
module flexmbs_io_multi_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    implicit none
    private

    type :: sink_ref_t
        class(sink_t), pointer :: sink => null()
    end type sink_ref_t

    !> Forwards every call to each attached sink, in the order attached.
    type, extends(sink_t), public :: multi_sink_t
        type(sink_ref_t), allocatable :: sinks(:)
    contains
        procedure :: attach => multi_attach
        procedure :: output => multi_output
        procedure :: wants_steps => multi_wants_steps
        procedure :: step => multi_step
        procedure :: finish => multi_finish
    end type multi_sink_t

contains

    !> Add a sink; it must outlive this one (it is referenced, not copied).
    subroutine multi_attach(self, sink)
        class(multi_sink_t), intent(inout) :: self
        class(sink_t), intent(inout), target :: sink
        if (.not. allocated(self%sinks)) allocate (self%sinks(0))
        self%sinks = [self%sinks, sink_ref_t(sink)]
    end subroutine multi_attach

    subroutine multi_output(self, t, y, status)
        class(multi_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
        integer :: i
        if (.not. allocated(self%sinks)) return
        do i = 1, size(self%sinks)
            call self%sinks(i)%sink%output(t, y, status)
            if (.not. status%ok()) return
        end do
    end subroutine multi_output

    logical function multi_wants_steps(self)
        class(multi_sink_t), intent(in) :: self
        integer :: i
        multi_wants_steps = .false.
        if (.not. allocated(self%sinks)) return
        do i = 1, size(self%sinks)
            if (self%sinks(i)%sink%wants_steps()) multi_wants_steps = .true.
        end do
    end function multi_wants_steps

    subroutine multi_step(self, nr, t_old, t, y, dense, stop, status)
        class(multi_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        integer :: i
        if (.not. allocated(self%sinks)) return
        do i = 1, size(self%sinks)
            if (.not. self%sinks(i)%sink%wants_steps()) cycle
            call self%sinks(i)%sink%step(nr, t_old, t, y, dense, stop, status)
            if (.not. status%ok()) return
        end do
    end subroutine multi_step

    !> Every sink is finished, even after one of them failed; the first
    !> error is kept.
    subroutine multi_finish(self, status)
        class(multi_sink_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        type(status_t) :: each
        integer :: i
        if (.not. allocated(self%sinks)) return
        do i = 1, size(self%sinks)
            call each%clear()
            call self%sinks(i)%sink%finish(each)
            if (status%ok() .and. .not. each%ok()) status = each
        end do
    end subroutine multi_finish
end module flexmbs_io_multi_sink
