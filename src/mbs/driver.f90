!> Prescribed functions of time, s(t) = Σ_k c_k t^k (k ≤ 3) + a sin(ω t + φ)
!> + a ramp-then-hold term, with s' and s'' exact: what the drivers of
!> flexmbs_mbs_system follow and what scales the applied loads of
!> flexmbs_mbs_force_element.
!>
!> Ramp then hold (the spin-up manoeuvre of Kane, Ryan and Banerjee 1987):
!> the rate s' rises from 0 to Ω over T as Ω/T (t − T/(2π) sin(2πt/T)) and
!> then holds, so s'' = Ω/T (1 − cos(2πt/T)) starts and ends at zero and
!> the motion has no jerk at either end:
!>   s = Ω/T (t²/2 + (T/2π)² (cos(2πt/T) − 1))   for 0 ≤ t < T,
!>   s = Ω (t − T/2)                              for t ≥ T   (s = 0 before 0).
module flexmbs_mbs_driver
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> A prescribed function of time, s(t) = Σ_k poly(k) t^k + amplitude
    !> sin(frequency t + phase): constant, constant rate, polynomial, harmonic.
    type, public :: driver_t
        real(wp) :: poly(0:3) = 0.0_wp
        real(wp) :: amplitude = 0.0_wp
        real(wp) :: frequency = 0.0_wp !! ω [rad/s]
        real(wp) :: phase = 0.0_wp     !! φ [rad]
        real(wp) :: ramp_rate = 0.0_wp !! Ω: the rate held after the ramp
        real(wp) :: ramp_time = 0.0_wp !! T [s] (> 0 when Ω /= 0)
    end type driver_t

    public :: driver_values

contains

    !> (s, s', s'') of a driver at t.
    pure function driver_values(driver, t) result(drv)
        type(driver_t), intent(in) :: driver
        real(wp), intent(in) :: t
        real(wp) :: drv(3), arg
        associate (c => driver%poly)
            drv(1) = c(0) + t * (c(1) + t * (c(2) + t * c(3)))
            drv(2) = c(1) + t * (2.0_wp * c(2) + 3.0_wp * t * c(3))
            drv(3) = 2.0_wp * c(2) + 6.0_wp * t * c(3)
        end associate
        arg = driver%frequency * t + driver%phase
        drv = drv + driver%amplitude * [sin(arg), driver%frequency * cos(arg), &
                                        -driver%frequency**2 * sin(arg)]
        if (driver%ramp_rate /= 0.0_wp) drv = drv + ramp_values(driver%ramp_rate, &
                                                                driver%ramp_time, t)
    end function driver_values

    !> (s, s', s'') of the ramp-then-hold term (module header).
    pure function ramp_values(rate, time, t) result(drv)
        real(wp), intent(in) :: rate, time, t
        real(wp) :: drv(3), w, c
        real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)
        if (t <= 0.0_wp) then
            drv = 0.0_wp
        else if (t < time) then
            w = two_pi / time
            c = rate / time
            drv = c * [t**2 / 2 + (cos(w * t) - 1.0_wp) / w**2, t - sin(w * t) / w, &
                       1.0_wp - cos(w * t)]
        else
            drv = [rate * (t - time / 2), rate, 0.0_wp]
        end if
    end function ramp_values
end module flexmbs_mbs_driver
