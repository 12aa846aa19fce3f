!> The rotation formulas of flexmbs_mbs_rotation on jets (second-order Taylor
!> arithmetic, flexmbs_mbs_jet): rotation.inc compiled with SCALAR = type(jet_t).
module flexmbs_mbs_rotation_jet
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_jet, only: jet_t, operator(+), operator(-), operator(*), &
        operator(/), operator(**), assignment(=), sqrt, sin, cos
    implicit none
    private
    public :: skew, cross, quat_g, quat_l, rotation_matrix, quat_rate_matrix, &
        quat_product, quat_conjugate, quat_from_axis_angle, quat_normalize, &
        rotated_vector_jacobian, rotated_vector_transpose_jacobian

contains

#define SCALAR type(jet_t)
#include "rotation.inc"
#undef SCALAR
end module flexmbs_mbs_rotation_jet
