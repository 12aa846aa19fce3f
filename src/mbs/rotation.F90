!> Unit quaternions, rotation matrices, the G and L matrices, q' = T(q) w and the
!> derivative identities of rotated vectors, in real arithmetic. The formulas are in
!> rotation.inc, shared with flexmbs_mbs_rotation_dual.
module flexmbs_mbs_rotation
    use flexmbs_core_kinds, only: wp
    implicit none
    private

#define SCALAR real(wp)
#include "rotation.inc"
#undef SCALAR
end module flexmbs_mbs_rotation
