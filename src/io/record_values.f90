!> Values derived from each record of a trajectory, which an HDF5 sink
!> writes beside /y as a named series (hdf5_sink_t%add_series): a body's
!> position, its rotation matrix, a joint's reaction. The model layer
!> implements them; the sink only knows how many values each record has.
module flexmbs_io_record_values
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    implicit none
    private

    !> Values computed from each record (t, y): `evaluate` fills a fixed number
    !> of rows, which the HDF5 sink stores as a series.
    type, abstract, public :: record_values_t
    contains
        procedure(evaluate_i), deferred :: evaluate
    end type record_values_t

    abstract interface
        !> The values at (t, y); `values` has the series' rows (no allocation).
        subroutine evaluate_i(self, t, y, values, status)
            import :: record_values_t, wp, status_t
            class(record_values_t), intent(inout) :: self
            real(wp), intent(in) :: t, y(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine evaluate_i
    end interface
end module flexmbs_io_record_values
