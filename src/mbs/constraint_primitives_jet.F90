!> The markers and constraint primitives of flexmbs_mbs_constraint_primitives on jets
!> (constraint_primitives.inc with SCALAR = type(jet_t)): the value of a joint along
!> the markers' motion, c(s), gives γ = c''(0) (flexmbs_mbs_system, 'ad').
module flexmbs_mbs_constraint_primitives_jet
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_jet, only: jet_t, operator(+), operator(-), operator(*), &
        operator(**), assignment(=), sin, cos, matmul
    use flexmbs_mbs_rotation_jet, only: rotation_matrix, rotated_vector_jacobian, skew, &
        cross, quat_from_axis_angle
    ! every primitive kind and its rows: the formulas select on them all
    use flexmbs_mbs_primitive_kinds
    use flexmbs_mbs_joint, only: joint_t, joint_part_time_derivative, joint_part_convective
    implicit none
    private

#define SCALAR type(jet_t)
#define SPECIFICATION
#include "constraint_primitives.inc"
#undef SPECIFICATION

contains

#include "constraint_primitives.inc"
#undef SCALAR
end module flexmbs_mbs_constraint_primitives_jet
