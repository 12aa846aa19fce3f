!> The markers and constraint primitives of flexmbs_mbs_constraint_primitives on dual
!> numbers (constraint_primitives.inc with SCALAR = type(dual_t)): AD of the values
!> gives C and c_t, AD of the hand-coded C v along T v gives (C v)_q T v.
module flexmbs_mbs_constraint_primitives_dual
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, operator(+), operator(-), operator(*), &
        operator(**), assignment(=), sin, cos, matmul
    use flexmbs_mbs_rotation_dual, only: rotation_matrix, rotated_vector_jacobian, skew, &
        cross, quat_from_axis_angle
    ! every primitive kind and its rows: the formulas select on them all
    use flexmbs_mbs_primitive_kinds
    use flexmbs_mbs_joint, only: joint_t, joint_part_time_derivative, joint_part_convective
    implicit none
    private

#define SCALAR type(dual_t)
#define SPECIFICATION
#include "constraint_primitives.inc"
#undef SPECIFICATION

contains

#include "constraint_primitives.inc"
#undef SCALAR
end module flexmbs_mbs_constraint_primitives_dual
