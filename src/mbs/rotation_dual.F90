!> The rotation formulas of flexmbs_mbs_rotation on dual numbers (forward-mode AD):
!> the same text, rotation.inc, compiled with SCALAR = type(dual_t).
module flexmbs_mbs_rotation_dual
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, operator(+), operator(-), operator(*), &
        operator(/), operator(**), assignment(=), sqrt, sin, cos
    implicit none
    private

#define SCALAR type(dual_t)
#include "rotation.inc"
#undef SCALAR
end module flexmbs_mbs_rotation_dual
