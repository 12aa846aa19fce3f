!> The markers and constraint primitives of flexmbs_mbs_constraint_primitives on dual
!> numbers (constraint_primitives.inc with SCALAR = type(dual_t)): AD of the values
!> gives C and c_t, AD of the hand-coded C v along T v gives (C v)_q T v.
module flexmbs_mbs_constraint_primitives_dual
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, operator(+), operator(-), operator(*), &
        operator(**), assignment(=), sin, cos, matmul
    use flexmbs_mbs_rotation_dual, only: rotation_matrix, rotated_vector_jacobian, skew, &
        cross, quat_from_axis_angle
    use flexmbs_mbs_primitive_kinds, only: primitive_dot1, primitive_dot2, &
        primitive_spherical, primitive_distance, primitive_angle_driver, &
        primitive_translation_driver, primitive_rows
    use flexmbs_mbs_joint, only: joint_t, joint_part_time_derivative, joint_part_convective
    implicit none
    private
    public :: rigid_marker_state, rigid_marker_pose, ground_marker_state, rigid_marker_jacobian, &
        rigid_marker_jacobian_q, primitive_value, primitive_jacobian, &
        primitive_time_derivative, primitive_convective, primitive_time_terms, &
        joint_value, joint_jacobian, joint_rows, chain_marker_state, chain_marker_jacobian

#define SCALAR type(dual_t)
#define SPECIFICATION
#include "constraint_primitives.inc"
#undef SPECIFICATION

contains

#include "constraint_primitives.inc"
#undef SCALAR
end module flexmbs_mbs_constraint_primitives_dual
