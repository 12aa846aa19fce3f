!> The paper's Table 1: A(α) angles of BDF-k from the boundary locus.
module test_bdf_stability
    use flexmbs_core_kinds, only: wp
    use flexmbs_dae_bdf_stability, only: bdf_stability_angle
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_bdf_stability

contains

    function collect_bdf_stability() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('table1_angles', test_angles), &
                 new_test('root_condition_confirms_angles', test_locus)]
    end function collect_bdf_stability

    !> Within 1e-3 degrees of docs/theory.md §10 (the paper truncates to
    !> 90, 90, 86, 73, 51); minimising θ as tabulated.
    subroutine test_angles(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: expected(6) = [90.0_wp, 90.0_wp, 86.0324_wp, 73.3517_wp, &
            51.8398_wp, 17.8398_wp]
        real(wp), parameter :: theta_expected(3:6) = [0.93861_wp, 1.36944_wp, 1.57526_wp, &
            1.64229_wp]
        integer, parameter :: paper(5) = [90, 90, 86, 73, 51]
        real(wp) :: alpha, theta
        integer :: k
        character(len=40) :: label
        do k = 1, 6
            alpha = bdf_stability_angle(k, theta)
            write (label, '(a,i0)') 'alpha of BDF-', k
            call check_close(error, alpha, expected(k), 1.0e-3_wp, trim(label))
            if (k <= 5) call check(error, int(alpha) == paper(k), trim(label) // ' vs paper')
            if (k >= 3) call check_close(error, theta, theta_expected(k), 1.0e-4_wp, &
                'minimising theta of ' // trim(label))
        end do
    end subroutine test_angles

    !> Independent check of α by the root condition: on the ray at angle
    !> α − 0.01° from the negative real axis every z = r e^{i(π − α + δ)} is
    !> stable (all roots of the characteristic polynomial in |ζ| ≤ 1); on the
    !> ray at α + 0.01° some r is unstable.
    subroutine test_locus(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: pi = acos(-1.0_wp), delta = 0.01_wp * pi / 180.0_wp
        real(wp) :: alpha, r, worst_inside, worst_outside
        integer :: k, i
        character(len=60) :: label
        do k = 3, 5
            alpha = bdf_stability_angle(k) * pi / 180.0_wp
            worst_inside = 0.0_wp
            worst_outside = 0.0_wp
            do i = 1, 4000
                r = 10.0_wp**(-3.0_wp + 6.0_wp * real(i, wp) / 4000.0_wp)
                worst_inside = max(worst_inside, &
                    largest_root(k, r * exp(cmplx(0.0_wp, pi - (alpha - delta), kind=wp))))
                worst_outside = max(worst_outside, &
                    largest_root(k, r * exp(cmplx(0.0_wp, pi - (alpha + delta), kind=wp))))
            end do
            write (label, '(a,i0)') 'BDF-', k
            call check(error, worst_inside <= 1.0_wp + 1.0e-9_wp, &
                trim(label) // ': unstable inside the sector')
            call check(error, worst_outside > 1.0_wp, trim(label) // ': stable beyond alpha')
        end do
    end subroutine test_locus

    !> Largest |ζ| among the roots of Σ_{j=1}^{k} (ζ − 1)^j ζ^{k−j} / j − z ζ^k,
    !> the characteristic polynomial of BDF-k for y' = λy, z = hλ
    !> (Durand–Kerner iteration).
    real(wp) function largest_root(k, z) result(rmax)
        integer, intent(in) :: k
        complex(wp), intent(in) :: z
        complex(wp) :: c(0:k), term(0:k), roots(k), p, q
        integer :: j, m, it, i
        c = (0.0_wp, 0.0_wp)
        do j = 1, k
            ! term = (ζ − 1)^j ζ^{k−j}, coefficients in ascending powers
            term = (0.0_wp, 0.0_wp)
            term(k - j) = (1.0_wp, 0.0_wp)
            do m = 1, j
                term(1:k) = term(0:k - 1) - term(1:k)
                term(0) = -term(0)
            end do
            c = c + term / real(j, wp)
        end do
        c(k) = c(k) - z
        c = c / c(k)
        do i = 1, k
            roots(i) = (0.4_wp, 0.9_wp)**(i - 1)
        end do
        do it = 1, 500
            do i = 1, k
                p = c(k)
                do m = k - 1, 0, -1
                    p = p * roots(i) + c(m)
                end do
                q = (1.0_wp, 0.0_wp)
                do m = 1, k
                    if (m /= i) q = q * (roots(i) - roots(m))
                end do
                roots(i) = roots(i) - p / q
            end do
        end do
        rmax = maxval(abs(roots))
    end function largest_root
end module test_bdf_stability
