!> The planar pendulum through the modern API: its mechanical form
!> (q' = v, M v' = f - Gᵀλ, 0 = G v) and the index-2 formulation of it,
!> integrated by each solver through the one `integrate` — MEXAX takes the
!> mechanical form itself, the others the formulation — from 1 rad at rest
!> to t = 1 s, against the exact angle.
!>
!>   gfortran pendulum.f90 $(pkg-config --cflags --libs flexmbs)
program pendulum
    use flexmbs
    implicit none
    character(len=*), parameter :: names(4) = [character(len=6) :: 'radau5', 'ddassl', &
        'ida', 'mexax']
    real(wp), parameter :: phi0 = 1.0_wp, t_end = 1.0_wp, tol = 1.0e-8_wp
    type(pendulum_mechanical_t), target :: mech
    type(formulation_t) :: formulation
    class(dae_solver_t), allocatable :: solver
    type(dae_options_t) :: options
    type(dae_stats_t) :: stats
    type(status_t) :: status
    real(wp) :: y(5), t, phi, dphi, error
    integer :: k

    options%rtol = tol
    options%atol = tol
    call pendulum_angle_exact(phi0, sqrt(9.81_wp), t_end, phi, dphi, status)
    write (*, '(a,f12.9,a)') 'exact angle at t = 1 s: ', phi, ' rad'
    do k = 1, size(names)
        ! y = (x, y, u, v, λ): the layout of the index-2 formulation
        mech = new_pendulum_mechanical(status=status)
        call pendulum_mechanical_initial(mech, phi0, y(1:2), y(3:4), y(5:5))
        formulation = new_formulation(mech, formulation_index2, y(1:2), &
                                      constant_mass=.true., status=status)
        call new_solver(trim(names(k)), solver, status)
        if (.not. status%ok()) error stop 'no such solver'
        t = 0.0_wp
        call solver%integrate(mech, formulation, t, y, t_end, options, stats, status)
        if (.not. status%ok()) then
            write (*, '(a)') trim(names(k)) // ': ' // status%text()
            error stop 3
        end if
        error = abs(atan2(y(1), -y(2)) - phi)
        write (*, '(a8,a,f12.9,a,es9.2,a)') trim(names(k)), ': angle ', atan2(y(1), -y(2)), &
            ' rad, error ', error, '; ' // stats%summary()
        if (error > 1.0e-5_wp) error stop 'the angle is off'
    end do
end program pendulum
