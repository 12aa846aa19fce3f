!> Inertia tensors of rigid bodies and chain links: the tensor from its
!> moments and products, and the test that it can belong to a body.
!>
!> A body's inertia tensor about its centre of mass is symmetric positive
!> definite, and its principal moments J1, J2, J3 satisfy the triangle
!> inequalities J1 + J2 >= J3 (and permutations), since J1 + J2 - J3 =
!> 2 ∫ ρ x3² dV >= 0 in principal axes. The principal moments come from
!> LAPACK's symmetric eigensolver. The smallest must exceed ε times the
!> largest: below it the tensor is singular to working precision.
module flexmbs_mbs_inertia
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text
    use flexmbs_linalg_lapack, only: dsyev_quiet
    implicit none
    private

    public :: inertia_tensor, inertia_defect

    ! Relative slack of the triangle inequalities (round-off of the moments
    ! as written in an input file: a thin rod has J1 + J2 = J3 exactly).
    real(wp), parameter :: triangle_slack = 1.0e-9_wp

contains

    !> The tensor of moments (Jxx, Jyy, Jzz) and products (Jxy, Jyz, Jxz).
    pure function inertia_tensor(moments, products) result(j)
        real(wp), intent(in) :: moments(3), products(3)
        real(wp) :: j(3, 3)
        j = reshape([moments(1), products(1), products(3), products(1), moments(2), &
                     products(2), products(3), products(2), moments(3)], [3, 3])
    end function inertia_tensor

    !> Why `j` cannot be a body's inertia tensor, or '' when it can.
    function inertia_defect(j) result(why)
        real(wp), intent(in) :: j(3, 3)
        character(len=:), allocatable :: why
        real(wp) :: a(3, 3), w(3), work(16)
        integer :: info
        why = ''
        a = j
        call dsyev_quiet('N', 'U', 3, a, 3, w, work, size(work), info)
        if (info /= 0 .or. .not. all(abs(w) <= huge(1.0_wp))) then
            why = 'the inertia tensor has no principal moments (not finite)'
            return
        end if
        if (w(1) <= 0.0_wp) then
            why = 'the inertia tensor is not positive definite (principal moments ' // &
                moments_text(w) // ')'
            return
        end if
        ! a moment below ε times the largest is zero to working precision:
        ! the body's mass matrix would be singular in all but name (1e-310
        ! beside 0.01 overflowed its rotational accelerations)
        if (w(1) <= epsilon(1.0_wp) * w(3)) then
            why = 'the inertia tensor is singular to working precision (principal moments ' &
                // moments_text(w) // '): the smallest must exceed 2.2e-16 times the largest'
            return
        end if
        ! w ascends: the largest must not exceed the sum of the other two
        if (w(3) > w(1) + w(2) + triangle_slack * w(3)) why = 'the principal moments ' // &
            moments_text(w) // ' violate the triangle inequality J1 + J2 >= J3: no body &
            &has them'
    contains
        function moments_text(w) result(t)
            real(wp), intent(in) :: w(3)
            character(len=:), allocatable :: t
            t = real_text(w(1)) // ', ' // real_text(w(2)) // ', ' // real_text(w(3))
        end function moments_text
    end function inertia_defect
end module flexmbs_mbs_inertia
