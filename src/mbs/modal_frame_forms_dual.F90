!> The rows of flexmbs_mbs_modal_frame_forms on dual numbers
!> (modal_frame.inc with SCALAR = type(dual_t)): AD of the rows gives their
!> Jacobians, AD of the hand-coded G and γ their second derivatives.
module flexmbs_mbs_modal_frame_forms_dual
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, operator(+), operator(-), operator(*), &
        assignment(=), matmul
    use flexmbs_mbs_rotation_dual, only: rotation_matrix, rotated_vector_jacobian, skew, cross
    use flexmbs_mbs_modal_frame_forms, only: modal_interface_t
    implicit none
    private
    public :: modal_frame_rows, modal_frame_velocity_jacobian, modal_frame_position_jacobian, &
        modal_frame_curvature_rows

contains

#define SCALAR type(dual_t)
#include "modal_frame.inc"
#undef SCALAR
end module flexmbs_mbs_modal_frame_forms_dual
