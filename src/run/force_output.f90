!> The force elements of a multibody scene in its HDF5 file, beside the
!> joints' reactions (flexmbs_run_named_output):
!>
!>   /forces/<name>/force_i   (3)  N     exerted by the element on marker i's
!>   /forces/<name>/torque_i  (3)  N m   body, world frame, torque about the marker
!>   /forces/<name>/force_j, torque_j:   the same on marker j's body (not for loads)
module flexmbs_run_force_output
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_io_record_values, only: record_values_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    implicit none
    private

    !> The force (`torque` false) or the torque on the body of one marker of
    !> a two-marker item, a force element or a joint (its reaction), at
    !> each record; an extension's evaluate finds the item's two wrenches
    !> and gives `part` of them.
    type, abstract, extends(record_values_t), public :: wrench_values_t
        integer :: side = 1 !! marker i (1) or marker j (2)
        logical :: torque = .false.
    contains
        procedure :: part => wrench_part
    end type wrench_values_t

    !> One element's force or torque on one marker at each record.
    type, extends(wrench_values_t) :: element_values_t
        type(mbs_system_t), pointer :: system => null()
        integer :: element = 0
        integer :: oq = 0, ov = 0 !! q and v in y
    contains
        procedure :: evaluate => element_evaluate
    end type element_values_t

    public :: add_force_output

contains

    !> The series of every element of sys under `groups` ('forces/NAME/',
    !> in the elements' order); q and v at oq, ov in y.
    subroutine add_force_output(h5, sys, groups, oq, ov, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(mbs_system_t), intent(in), target :: sys
        character(len=*), intent(in) :: groups(:)
        integer, intent(in) :: oq, ov
        type(status_t), intent(inout) :: status
        type(element_values_t) :: values
        character(len=:), allocatable :: base
        integer :: k, side
        values%system => sys
        values%oq = oq
        values%ov = ov
        do k = 1, min(size(groups), sys%element_count())
            values%element = k
            base = trim(groups(k))
            do side = 1, sys%element_bodies(k)
                values%side = side
                values%torque = .false.
                call h5%add_series(base // merge('force_i', 'force_j', side == 1), 3, 'N', &
                    values, status, 'exerted by the element on the body of marker ' // &
                    merge('i', 'j', side == 1) // ', world frame')
                if (.not. status%ok()) return
                values%torque = .true.
                call h5%add_series(base // merge('torque_i', 'torque_j', side == 1), 3, &
                    'N m', values, status, 'exerted by the element on the body of marker ' &
                    // merge('i', 'j', side == 1) // ', world frame, about the marker')
                if (.not. status%ok()) return
            end do
        end do
    end subroutine add_force_output

    subroutine element_evaluate(self, t, y, values, status)
        class(element_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: force(3, 2), torque(3, 2)
        associate (sys => self%system)
            call sys%element_wrench(self%element, t, y(self%oq + 1:self%oq + sys%nq), &
                                    y(self%ov + 1:self%ov + sys%nv), force, torque, status)
        end associate
        call self%part(force, torque, values)
    end subroutine element_evaluate

    !> The series' values of the item's forces and torques on the bodies of
    !> its markers i and j (columns 1, 2).
    pure subroutine wrench_part(self, force, torque, values)
        class(wrench_values_t), intent(in) :: self
        real(wp), intent(in) :: force(3, 2), torque(3, 2)
        real(wp), intent(out) :: values(:)
        if (self%torque) then
            values = torque(:, self%side)
        else
            values = force(:, self%side)
        end if
    end subroutine wrench_part
end module flexmbs_run_force_output
