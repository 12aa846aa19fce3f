!> Stability angles of the BDF methods (docs/theory.md §10, the paper's Table 1).
!>
!> BDF-k applied to y' = λy with μ = hλ is stable outside the bounded region
!> enclosed by the boundary locus μ(θ) = Σ_{j=1}^{k} (1 − e^{−iθ})^j / j,
!> θ ∈ (0, π]. The method is A(α)-stable with α = min over θ of
!> (π − |arg μ(θ)|): the widest sector around the negative real axis that
!> misses the locus. For k = 1, 2 the locus lies in Re μ ≥ 0 and the infimum
!> π/2 is approached as θ → 0.
module flexmbs_dae_bdf_stability
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: bdf_boundary_locus, bdf_stability_angle, sector_angle

    real(wp), parameter :: pi = acos(-1.0_wp)
    !> Samples of (0, π] for the coarse search; the minimiser is then refined.
    integer, parameter :: n_samples = 20000
    !> Golden-section iterations: the bracket shrinks by 0.618 each.
    integer, parameter :: n_refine = 80

contains

    !> μ(θ) of BDF-k.
    pure complex(wp) function bdf_boundary_locus(k, theta) result(mu)
        integer, intent(in) :: k         !! order, 1..6
        real(wp), intent(in) :: theta    !! in (0, π]
        complex(wp) :: w, p
        integer :: j
        w = 1.0_wp - exp(cmplx(0.0_wp, -theta, kind=wp))
        p = (1.0_wp, 0.0_wp)
        mu = (0.0_wp, 0.0_wp)
        do j = 1, k
            p = p * w
            mu = mu + p / real(j, wp)
        end do
    end function bdf_boundary_locus

    !> α_k in degrees; theta_min (optional) returns the minimising θ (0 when
    !> the infimum is only approached as θ → 0).
    real(wp) function bdf_stability_angle(k, theta_min) result(alpha_deg)
        integer, intent(in) :: k
        real(wp), intent(out), optional :: theta_min
        real(wp) :: theta, best, value, lo, hi, a, b, fa, fb
        integer :: i, ibest
        real(wp), parameter :: golden = 0.6180339887498949_wp
        best = huge(1.0_wp)
        ibest = 1
        do i = 1, n_samples
            theta = pi * real(i, wp) / real(n_samples, wp)
            value = sector_gap(k, theta)
            if (value < best) then
                best = value
                ibest = i
            end if
        end do
        ! Refine inside the neighbouring samples by golden-section search.
        lo = pi * real(max(ibest - 1, 0), wp) / real(n_samples, wp)
        hi = pi * real(min(ibest + 1, n_samples), wp) / real(n_samples, wp)
        lo = max(lo, tiny(1.0_wp))
        a = hi - golden * (hi - lo)
        b = lo + golden * (hi - lo)
        fa = sector_gap(k, a)
        fb = sector_gap(k, b)
        do i = 1, n_refine
            if (fa < fb) then
                hi = b
                b = a
                fb = fa
                a = hi - golden * (hi - lo)
                fa = sector_gap(k, a)
            else
                lo = a
                a = b
                fa = fb
                b = lo + golden * (hi - lo)
                fb = sector_gap(k, b)
            end if
        end do
        theta = 0.5_wp * (lo + hi)
        best = min(best, sector_gap(k, theta))
        ! The gap tends to π/2 as θ → 0 (μ ≈ iθ); it never goes below that
        ! from the right half-plane.
        if (best >= 0.5_wp * pi) then
            best = 0.5_wp * pi
            theta = 0.0_wp
        end if
        if (present(theta_min)) theta_min = theta
        alpha_deg = best * 180.0_wp / pi
    end function bdf_stability_angle

    !> |arg(−z)| in degrees, the angle of z from the negative real axis: 0
    !> there, 90 on the imaginary axis, above 90 in the right half-plane.
    !> h·λ (h > 0) lies in BDF-k's sector when sector_angle(λ) ≤ α_k.
    elemental real(wp) function sector_angle(z)
        complex(wp), intent(in) :: z
        sector_angle = abs(atan2(-aimag(z), -real(z, wp))) * 180.0_wp / pi
    end function sector_angle

    !> π − |arg μ(θ)|: angle between the locus point and the negative axis.
    pure real(wp) function sector_gap(k, theta)
        integer, intent(in) :: k
        real(wp), intent(in) :: theta
        complex(wp) :: mu
        mu = bdf_boundary_locus(k, theta)
        sector_gap = pi - abs(atan2(aimag(mu), real(mu, wp)))
    end function sector_gap
end module flexmbs_dae_bdf_stability
