!> Prescribed functions of time, s(t) = Σ_k c_k t^k (k ≤ 3) + a sin(ω t + φ),
!> with s' and s'' exact: what the drivers of flexmbs_mbs_system follow and
!> what scales the applied loads of flexmbs_mbs_force_element.
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
    end function driver_values
end module flexmbs_mbs_driver
