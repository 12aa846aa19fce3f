!> Rigid bodies in absolute coordinates through the formulation layer:
!> the torque-free symmetric top against its analytic precession, energy
!> and angular momentum of an asymmetric body, exact free fall, the unit
!> quaternion kept by the projection, Jacobians against differences.
module test_rigid_body
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_rigid_body, only: rigid_body_t, rigid_bodies_t, new_rigid_bodies, &
        rigid_body_energy, rigid_body_momenta
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use test_formulation, only: difference_jacobian
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_rigid_body

    real(wp), parameter :: rtol = 1.0e-8_wp

contains

    function collect_rigid_body() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('symmetric_top_precession', test_symmetric_top), &
                 new_test('energy_momentum_free_fall', test_conservation), &
                 new_test('jacobian_vs_differences', test_jacobian)]
    end function collect_rigid_body

    !> Integrate one body from (q, v) to t_end with RADAU5 in the index-2
    !> acceleration layout; y = (q, v, a).
    subroutine run_body(bodies, q, v, t_end, projection, y, stats, status)
        type(rigid_bodies_t), target, intent(inout) :: bodies
        real(wp), intent(in) :: q(7), v(6), t_end
        logical, intent(in) :: projection
        real(wp), intent(out) :: y(19)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        real(wp) :: t, yp(19)
        gen = new_formulation(bodies, formulation_index2, q, projection=projection, &
            status=status)
        if (.not. status%ok()) return
        y = 0.0_wp
        y(1:7) = q
        y(8:13) = v
        call gen%consistent_initial(0.0_wp, y, yp, status)
        if (.not. status%ok()) return
        options%rtol = rtol
        options%atol = rtol
        t = 0.0_wp
        call solver%integrate(gen, t, y, t_end, options, stats, status)
    end subroutine run_body

    !> Torque-free symmetric top, J = diag(A, A, C): in the body ω' = (ω⊥ cos Ωt,
    !> ω⊥ sin Ωt, ω3) with Ω = (C - A) ω3 / A; in space the symmetry axis
    !> A(p) e3 rotates about the constant H at the rate |H| / A.
    subroutine test_symmetric_top(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_bodies_t) :: bodies
        type(rigid_body_t) :: body
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q(7), v(6), y(19), h(3), hhat(3), k0(3), k(3), kexp(3), omega(3), big_omega
        real(wp) :: phi, lin(3), err_omega, err_axis
        real(wp), parameter :: a = 2.0_wp, c = 1.0_wp, t_end = 5.0_wp
        character(len=200) :: msg
        body%mass = 3.0_wp
        body%inertia = 0.0_wp
        body%inertia(1, 1) = a
        body%inertia(2, 2) = a
        body%inertia(3, 3) = c
        bodies = new_rigid_bodies([body], status=status)
        q(1:3) = [0.1_wp, 0.2_wp, 0.3_wp]
        q(4:7) = quat_from_axis_angle([0.0_wp, 0.6_wp, 0.8_wp], 0.7_wp)
        v = [0.0_wp, 0.0_wp, 0.0_wp, 0.5_wp, 0.0_wp, 3.0_wp]
        call rigid_body_momenta(bodies, q, v, lin, h)
        k0 = matmul(rotation_matrix(q(4:7)), [0.0_wp, 0.0_wp, 1.0_wp])
        call run_body(bodies, q, v, t_end, .true., y, stats, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        big_omega = (c - a) * v(6) / a
        omega = [0.5_wp * cos(big_omega * t_end), 0.5_wp * sin(big_omega * t_end), 3.0_wp]
        err_omega = maxval(abs(y(11:13) - omega))
        ! Rodrigues: k0 rotated about Ĥ by φ = |H| t / A
        hhat = h / norm2(h)
        phi = norm2(h) * t_end / a
        kexp = k0 * cos(phi) + cross(hhat, k0) * sin(phi) &
            + hhat * dot_product(hhat, k0) * (1.0_wp - cos(phi))
        k = matmul(rotation_matrix(y(4:7)), [0.0_wp, 0.0_wp, 1.0_wp])
        err_axis = maxval(abs(k - kexp))
        write (msg, '(a,es10.3,a,es10.3,a,i0)') 'top: |ω - exact| = ', err_omega, &
            ', |axis - exact| = ', err_axis, ', steps ', stats%nst
        print '(a)', '    ' // trim(msg)
        call check(error, err_omega <= 1.0e-6_wp .and. err_axis <= 1.0e-6_wp, trim(msg))
    end subroutine test_symmetric_top

    !> An asymmetric body (full inertia) under gravity: energy conserved,
    !> spin angular momentum A(p) J ω' conserved, the centre falls exactly;
    !> without projection |p| drifts at tolerance level, with it |p| = 1.
    subroutine test_conservation(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_bodies_t) :: bodies
        type(rigid_body_t) :: body
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q(7), v(6), y(19), e0, e1, h0(3), h1(3), r(3), g(3), drift_p
        integer :: k
        real(wp), parameter :: t_end = 10.0_wp
        character(len=200) :: msg
        body%mass = 2.0_wp
        body%inertia = reshape([2.0_wp, 0.1_wp, 0.0_wp, 0.1_wp, 3.0_wp, 0.2_wp, &
                                0.0_wp, 0.2_wp, 4.0_wp], [3, 3])
        g = [0.0_wp, 0.0_wp, -9.81_wp]
        bodies = new_rigid_bodies([body], gravity=g, status=status)
        q(1:3) = [1.0_wp, 0.0_wp, 2.0_wp]
        q(4:7) = quat_from_axis_angle([1.0_wp, 0.0_wp, 0.0_wp], 0.3_wp)
        v = [0.5_wp, -0.2_wp, 4.0_wp, 1.0_wp, 2.0_wp, 0.5_wp]
        e0 = rigid_body_energy(bodies, q, v)
        h0 = matmul(rotation_matrix(q(4:7)), matmul(body%inertia, v(4:6)))
        do k = 0, 1
            call run_body(bodies, q, v, t_end, k == 1, y, stats, status)
            call check(error, status%ok(), status%text())
            if (allocated(error)) return
            e1 = rigid_body_energy(bodies, y(1:7), y(8:13))
            h1 = matmul(rotation_matrix(y(4:7)), matmul(body%inertia, y(11:13)))
            r = q(1:3) + v(1:3) * t_end + 0.5_wp * g * t_end**2
            drift_p = abs(norm2(y(4:7)) - 1.0_wp)
            write (msg, '(a,l1,4(a,es10.3))') 'projection ', k == 1, ': energy ', &
                abs(e1 - e0) / abs(e0), ', spin momentum ', norm2(h1 - h0) / norm2(h0), &
                ', centre ', maxval(abs(y(1:3) - r)), ', ||p| - 1| ', drift_p
            print '(a)', '    ' // trim(msg)
            call check(error, abs(e1 - e0) <= 1.0e-6_wp * abs(e0) .and. &
                norm2(h1 - h0) <= 1.0e-6_wp * norm2(h0) .and. &
                maxval(abs(y(1:3) - r)) <= 1.0e-8_wp * maxval(abs(r)), trim(msg))
            if (k == 0) call check(error, drift_p <= 1.0e-5_wp, trim(msg))
            if (k == 1) call check(error, drift_p <= 4 * epsilon(1.0_wp), trim(msg))
        end do
    end subroutine test_conservation

    !> Analytic (kinematics and gyroscopic) Jacobian of the formulation of two
    !> bodies against central differences of F.
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(rigid_bodies_t), target :: bodies
        type(rigid_body_t) :: body(2)
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp) :: y(38), jac(38, 38), jfd(38, 38)
        integer :: j
        character(len=120) :: msg
        body(1)%inertia = reshape([2.0_wp, 0.1_wp, 0.0_wp, 0.1_wp, 3.0_wp, 0.2_wp, &
                                   0.0_wp, 0.2_wp, 4.0_wp], [3, 3])
        body(2)%mass = 0.5_wp
        body(2)%torque = [0.1_wp, 0.2_wp, 0.3_wp]
        bodies = new_rigid_bodies(body, gravity=[0.0_wp, -9.81_wp, 0.0_wp], status=status)
        do j = 1, 38
            y(j) = sin(1.3_wp * j)
        end do
        gen = new_formulation(bodies, formulation_index2, y(1:14), status=status)
        call gen%jacobian_dense(0.0_wp, y, jac, status)
        call difference_jacobian(gen, y, jfd, status)
        write (msg, '(a,es10.3)') 'Jacobian vs central differences: ', maxval(abs(jac - jfd))
        call check(error, status%ok() .and. maxval(abs(jac - jfd)) <= 1.0e-8_wp, trim(msg))
    end subroutine test_jacobian
end module test_rigid_body
