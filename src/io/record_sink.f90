!> A sink that keeps the solution at the output times in memory (the
!> studies compare runs with a reference at these times).
module flexmbs_io_record_sink
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t
    implicit none
    private

    type, extends(sink_t), public :: record_sink_t
        integer :: records = 0
        real(wp), allocatable :: t(:)    !! (records)
        real(wp), allocatable :: y(:, :) !! (n, records)
    contains
        procedure :: output => record_output
    end type record_sink_t

contains

    !> Append (t, y), doubling the storage when full.
    subroutine record_output(self, t, y, status)
        class(record_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: tt(:), yy(:, :)
        if (.not. allocated(self%t)) allocate (self%t(128), self%y(size(y), 128))
        if (self%records == size(self%t)) then
            allocate (tt(2 * self%records), yy(size(y), 2 * self%records))
            tt(1:self%records) = self%t
            yy(:, 1:self%records) = self%y
            call move_alloc(tt, self%t)
            call move_alloc(yy, self%y)
        end if
        self%records = self%records + 1
        self%t(self%records) = t
        self%y(:, self%records) = y
    end subroutine record_output
end module flexmbs_io_record_sink
