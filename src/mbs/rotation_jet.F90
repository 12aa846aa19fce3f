!> The rotation formulas of flexmbs_mbs_rotation on jets (second-order Taylor
!> arithmetic, flexmbs_mbs_jet): rotation.inc compiled with SCALAR = type(jet_t).
module flexmbs_mbs_rotation_jet
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_jet, only: jet_t, operator(+), operator(-), operator(*), &
        operator(/), operator(**), assignment(=), sqrt, sin, cos
    implicit none
    private

#define SCALAR type(jet_t)
#include "rotation.inc"
#undef SCALAR
end module flexmbs_mbs_rotation_jet
