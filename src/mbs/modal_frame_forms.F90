!> The rows that hold a frame body on an interface of a modal body, with
!> hand-coded c, G, c_q and γ in real arithmetic (modal_frame.inc, shared
!> with flexmbs_mbs_modal_frame_forms_dual); flexmbs_mbs_modal_frame
!> places them.
module flexmbs_mbs_modal_frame_forms
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_rotation, only: rotation_matrix, rotated_vector_jacobian, skew, cross
    implicit none
    private
    public :: modal_frame_rows, modal_frame_velocity_jacobian, modal_frame_position_jacobian, &
        modal_frame_curvature_rows

    !> Interface j of a modal body as its frame rows see it.
    type, public :: modal_interface_t
        real(wp) :: offset(3) = 0.0_wp           !! d: centroid from the centre of mass
        real(wp), allocatable :: translation(:, :) !! U (3, n): centroid per unit η
        real(wp), allocatable :: rotation(:, :)    !! Θ (3, n): small rotation per unit η
    end type modal_interface_t

contains

#define SCALAR real(wp)
#include "modal_frame.inc"
#undef SCALAR
end module flexmbs_mbs_modal_frame_forms
