!> A program of a project that depends on flexmbs through fpm: the planar
!> pendulum's mechanical form, its index-2 formulation and RADAU5, all from
!> `use flexmbs`, from 1 rad at rest to t = 1 s against the exact angle.
program uses_flexmbs
    use flexmbs
    implicit none
    real(wp), parameter :: phi0 = 1.0_wp, t_end = 1.0_wp
    type(pendulum_mechanical_t), target :: mech
    type(formulation_t) :: formulation
    type(radau5_t) :: solver
    type(dae_options_t) :: options
    type(dae_stats_t) :: stats
    type(status_t) :: status
    real(wp) :: y(5), t, phi, dphi, error

    call pendulum_angle_exact(phi0, sqrt(9.81_wp), t_end, phi, dphi, status)
    mech = new_pendulum_mechanical(status=status)
    if (status%ok()) then
        ! y = (x, y, u, v, λ): the layout of the index-2 formulation
        call pendulum_mechanical_initial(mech, phi0, y(1:2), y(3:4), y(5:5))
        formulation = new_formulation(mech, formulation_index2, y(1:2), &
                                      constant_mass=.true., status=status)
    end if
    if (status%ok()) then
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        t = 0.0_wp
        call solver%integrate(formulation, t, y, t_end, options, stats, status)
    end if
    if (.not. status%ok()) then
        write (*, '(a)') status%text()
        error stop 3
    end if
    error = abs(atan2(y(1), -y(2)) - phi)
    write (*, '(a,f12.9,a,es9.2)') 'flexmbs as an fpm dependency: pendulum angle ', &
        atan2(y(1), -y(2)), ' rad at t = 1 s, error ', error
    if (error > 1.0e-5_wp) error stop 'the angle is off'
end program uses_flexmbs
