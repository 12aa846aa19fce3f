!> Small 3x3 tensor helpers for the solid elements and materials, and the
!> Voigt order of symmetric tensors used by the tangents: (11, 22, 33, 12, 23, 13).
module flexmbs_fe_tensor
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> Row and column of each Voigt component.
    integer, parameter, public :: voigt_i(6) = [1, 2, 3, 1, 2, 1]
    integer, parameter, public :: voigt_j(6) = [1, 2, 3, 2, 3, 3]
    real(wp), parameter, public :: identity3(3, 3) = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1] &
        * 1.0_wp, [3, 3])

    public :: det3, inverse3

contains

    !> Determinant of a 3x3 matrix.
    pure real(wp) function det3(a)
        real(wp), intent(in) :: a(3, 3)
        det3 = a(1, 1) * (a(2, 2) * a(3, 3) - a(2, 3) * a(3, 2)) &
             - a(1, 2) * (a(2, 1) * a(3, 3) - a(2, 3) * a(3, 1)) &
             + a(1, 3) * (a(2, 1) * a(3, 2) - a(2, 2) * a(3, 1))
    end function det3

    !> Inverse by cofactors; ainv is left zero when det = 0.
    pure subroutine inverse3(a, ainv, det)
        real(wp), intent(in) :: a(3, 3)
        real(wp), intent(out) :: ainv(3, 3), det
        ainv(1, 1) = a(2, 2) * a(3, 3) - a(2, 3) * a(3, 2)
        ainv(1, 2) = a(1, 3) * a(3, 2) - a(1, 2) * a(3, 3)
        ainv(1, 3) = a(1, 2) * a(2, 3) - a(1, 3) * a(2, 2)
        ainv(2, 1) = a(2, 3) * a(3, 1) - a(2, 1) * a(3, 3)
        ainv(2, 2) = a(1, 1) * a(3, 3) - a(1, 3) * a(3, 1)
        ainv(2, 3) = a(1, 3) * a(2, 1) - a(1, 1) * a(2, 3)
        ainv(3, 1) = a(2, 1) * a(3, 2) - a(2, 2) * a(3, 1)
        ainv(3, 2) = a(1, 2) * a(3, 1) - a(1, 1) * a(3, 2)
        ainv(3, 3) = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)
        det = a(1, 1) * ainv(1, 1) + a(1, 2) * ainv(2, 1) + a(1, 3) * ainv(3, 1)
        if (det /= 0.0_wp) then
            ainv = ainv / det
        else
            ainv = 0.0_wp
        end if
    end subroutine inverse3
end module flexmbs_fe_tensor
