!> A free flexible body integrated by RADAU5 through the generic formulation
!> layer (nc = 0: the index-2 form with constant mass is the ODE
!> q' = v, M v' = f − k): momentum conservation, tolerance-proportional
!> energy drift without damping, monotone energy decay with damping.
module test_fe_dynamics
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_radau5, only: radau5_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_fe_dynamics

    integer, parameter :: n_out = 41          !! output times on [0, t_end]
    real(wp), parameter :: t_end = 1.0_wp     !! about 2.5 periods of the lowest mode
    real(wp), parameter :: spin(3) = [0.3_wp, -0.2_wp, 1.0_wp] !! initial ω [rad/s]
    real(wp), parameter :: drift(3) = [0.1_wp, 0.0_wp, -0.05_wp] !! initial translation [m/s]
    real(wp), parameter :: stretch = 0.05_wp  !! initial deformation: 5 % along x

    !> Keeps y at the output times.
    type, extends(sink_t) :: keep_sink_t
        integer :: count = 0
        real(wp), allocatable :: y(:, :)
    contains
        procedure :: output => keep_output
    end type keep_sink_t

contains

    function collect_fe_dynamics() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('free_body_momentum_and_energy', test_free_body), &
                 new_test('damped_body_energy_decreases', test_damped_body)]
    end function collect_fe_dynamics

    subroutine keep_output(self, t, y, status)
        class(keep_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        if (.not. allocated(self%y)) allocate (self%y(size(y), n_out))
        self%count = self%count + 1
        if (self%count <= n_out) self%y(:, self%count) = y
    end subroutine keep_output

    !> Integrate a free 2 x 1 x 1 box of 8-node elements, stretched and spinning,
    !> to t_end; energy E = strain + kinetic, momenta at the output times.
    subroutine run_free_body(tol, viscosity, energy, linear, angular, ok, message)
        real(wp), intent(in) :: tol, viscosity
        real(wp), intent(out) :: energy(n_out), linear(3, n_out), angular(3, n_out)
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: message
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        type(flexible_body_t), target :: body
        type(formulation_t) :: dae
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(keep_sink_t) :: sink
        real(wp), allocatable :: q0(:), v0(:), y(:), x(:, :), w(:, :)
        real(wp) :: t, centre(3)
        integer :: i, nq, k
        ok = .false.
        call box_mesh(mesh, hex8, [2, 1, 1], [2.0_wp, 1.0_wp, 1.0_wp], status)
        if (status%ok()) call new_neo_hooke(material, 1.0e4_wp, 0.3_wp, 100.0_wp, viscosity, &
            status)
        if (status%ok()) call new_flexible_body(body, mesh, [material], [integer ::], status)
        if (.not. status%ok()) then
            message = 'set-up: ' // status%text()
            return
        end if
        nq = body%nq
        ! Free body: dof(:, a) = 3a−2..3a, so nodal arrays map onto q, v.
        x = mesh%x
        centre = sum(x, dim=2) / size(x, 2)
        x(1, :) = centre(1) + (1.0_wp + stretch) * (x(1, :) - centre(1))
        allocate (w, mold=x)
        do i = 1, size(x, 2)
            w(:, i) = drift + cross(spin, x(:, i) - centre)
        end do
        q0 = reshape(x, [nq])
        v0 = reshape(w, [nq])
        dae = new_formulation(body, formulation_index2, q0, constant_mass=.true., status=status)
        if (.not. status%ok()) then
            message = 'formulation: ' // status%text()
            return
        end if
        allocate (y(dae%n), source=0.0_wp)
        y(1:nq) = q0
        y(nq + 1:2 * nq) = v0
        options%rtol = tol
        options%atol = tol
        options%output_times = [(t_end * real(k, wp) / real(n_out - 1, wp), k=0, n_out - 1)]
        t = 0.0_wp
        call solver%integrate(dae, t, y, t_end, options, stats, status, sink)
        if (.not. status%ok() .or. sink%count /= n_out) then
            message = 'radau5: ' // status%text()
            return
        end if
        do k = 1, n_out
            energy(k) = body%strain_energy(sink%y(1:nq, k), status) + &
                body%kinetic_energy(sink%y(nq + 1:2 * nq, k))
            call body%momenta(sink%y(1:nq, k), sink%y(nq + 1:2 * nq, k), linear(:, k), &
                angular(:, k))
        end do
        ok = status%ok()
        message = 'strain energy: ' // status%text()
    end subroutine run_free_body

    pure function cross(a, b) result(c)
        real(wp), intent(in) :: a(3), b(3)
        real(wp) :: c(3)
        c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
    end function cross

    !> Undamped: linear and angular momentum conserved to tolerance, the energy
    !> drift shrinks with the tolerance (1e-5 → 1e-7: at least 10×; measured
    !> 4.2e-5 and 2.2e-6 relative).
    subroutine test_free_body(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: e5(n_out), l5(3, n_out), a5(3, n_out), e7(n_out), l7(3, n_out), a7(3, n_out)
        real(wp) :: drift5, drift7, dl, da
        logical :: ok
        character(len=:), allocatable :: msg
        character(len=200) :: line
        call run_free_body(1.0e-5_wp, 0.0_wp, e5, l5, a5, ok, msg)
        call check(error, ok, msg)
        if (allocated(error)) return
        call run_free_body(1.0e-7_wp, 0.0_wp, e7, l7, a7, ok, msg)
        call check(error, ok, msg)
        if (allocated(error)) return
        drift5 = maxval(abs(e5 - e5(1))) / e5(1)
        drift7 = maxval(abs(e7 - e7(1))) / e7(1)
        dl = maxval(abs(l7 - spread(l7(:, 1), 2, n_out))) / norm2(l7(:, 1))
        da = maxval(abs(a7 - spread(a7(:, 1), 2, n_out))) / norm2(a7(:, 1))
        write (line, '(4(a,es9.2))') 'energy drift 1e-5: ', drift5, ', 1e-7: ', drift7, &
            '; momentum 1e-7: linear ', dl, ', angular ', da
        ! Runge–Kutta methods keep linear invariants: linear momentum to round-off
        ! (measured 3e-15); angular momentum, quadratic, to the tolerance (1.5e-7).
        call check(error, dl <= 1.0e-12_wp .and. da <= 10.0_wp * 1.0e-7_wp, &
            'momenta: ' // trim(line))
        call check(error, drift5 <= 1.0e-3_wp .and. drift7 <= drift5 / 10.0_wp, &
            'energy drift not tolerance-proportional: ' // trim(line))
    end subroutine test_free_body

    !> Damped (η = 10 Pa·s): the energy decreases monotonically at the outputs
    !> (to the tolerance of the integration) while the momenta stay.
    subroutine test_damped_body(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: e(n_out), l(3, n_out), a(3, n_out), rise, loss
        logical :: ok
        character(len=:), allocatable :: msg
        character(len=200) :: line
        call run_free_body(1.0e-7_wp, 10.0_wp, e, l, a, ok, msg)
        call check(error, ok, msg)
        if (allocated(error)) return
        rise = maxval(e(2:) - e(:n_out - 1)) / e(1)
        loss = (e(1) - e(n_out)) / e(1)
        write (line, '(2(a,es9.2))') 'largest rise ', rise, ', total loss ', loss
        call check(error, rise <= 1.0e-7_wp, 'energy rose: ' // trim(line))
        call check(error, loss > 1.0e-3_wp, 'damping removed no energy: ' // trim(line))
        call check(error, maxval(abs(l - spread(l(:, 1), 2, n_out))) <= &
            1.0e-7_wp * norm2(l(:, 1)), 'linear momentum not conserved with damping')
    end subroutine test_damped_body
end module test_fe_dynamics
