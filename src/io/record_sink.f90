!> A sink that keeps the solution at the output times in memory (the
!> studies compare runs with a reference at these times).
module flexmbs_io_record_sink
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t
    implicit none
    private

    !> A sink that keeps every output (t, y) in memory: a study's runs and
    !> their reference compared point by point, and tests.
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
        include '../dae/sink_output_arguments.inc'
        real(wp), allocatable :: tt(:), yy(:, :)
        integer :: capacity, stat
        if (.not. allocated(self%t)) then
            capacity = 128
        else if (self%records == size(self%t)) then
            capacity = 2 * self%records
        else
            capacity = 0
        end if
        if (capacity > 0) then
            allocate (tt(capacity), yy(size(y), capacity), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'recorded trajectory', &
                    (size(y) + 1_i8) * capacity, 8)
                return
            end if
            if (self%records > 0) then
                tt(1:self%records) = self%t(1:self%records)
                yy(:, 1:self%records) = self%y(:, 1:self%records)
            end if
            call move_alloc(tt, self%t)
            call move_alloc(yy, self%y)
        end if
        self%records = self%records + 1
        self%t(self%records) = t
        self%y(:, self%records) = y
    end subroutine record_output
end module flexmbs_io_record_sink
