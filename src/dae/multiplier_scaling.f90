!> How DDASSL and IDA weigh the multipliers in their Newton test
!> (docs/theory.md §6.4). The multipliers of index k (out of the error
!> test) count as h^(k-1) δ / κ: h^(k-1) δ is their effect on the components
!> of index 1, and κ keeps them as accurate as the rest although no error
!> test watches them. κ may not fall below the level at which the round-off
!> of δ (amplified like 1/h by the iteration matrix) fills the whole Newton
!> tolerance: at rtol = 1e-12 that is κ = 0.1 (the fine five-body mesh's
!> multiplier corrections stay at h δ ≈ 1e-14 whatever h).
module flexmbs_dae_multiplier_scaling
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: multiplier_kappa

    real(wp), parameter :: kappa_accuracy = 0.01_wp  !! κ for accuracy (calibrated, docs/theory.md §6.4)
    real(wp), parameter :: roundoff_factor = 450.0_wp !! κ ≥ 450 ε / rtol (calibrated)

contains

    !> κ for the smallest relative tolerance of a run.
    pure real(wp) function multiplier_kappa(rtol_min) result(kappa)
        real(wp), intent(in) :: rtol_min
        if (rtol_min <= 0.0_wp) then
            kappa = 1.0_wp
            return
        end if
        kappa = min(1.0_wp, max(kappa_accuracy, roundoff_factor * epsilon(1.0_wp) / rtol_min))
    end function multiplier_kappa
end module flexmbs_dae_multiplier_scaling
