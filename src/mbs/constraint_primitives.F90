!> Markers on rigid bodies and the constraint primitives (dot-1, dot-2, spherical,
!> distance, angle and translation drivers) with hand-coded c, C, c_t, (C v)_q T v and
!> 2 C_t v + c_tt, in real arithmetic. The formulas are in constraint_primitives.inc,
!> shared with flexmbs_mbs_constraint_primitives_dual.
module flexmbs_mbs_constraint_primitives
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_rotation, only: rotation_matrix, rotated_vector_jacobian, skew, cross, &
        quat_from_axis_angle
    ! every primitive kind and its rows: the formulas select on them all
    use flexmbs_mbs_primitive_kinds
    use flexmbs_mbs_joint, only: joint_t, joint_part_time_derivative, joint_part_convective
    implicit none
    private

#define SCALAR real(wp)
#define SPECIFICATION
#include "constraint_primitives.inc"
#undef SPECIFICATION

contains

#include "constraint_primitives.inc"
#undef SCALAR
end module flexmbs_mbs_constraint_primitives
