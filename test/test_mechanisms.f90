!> Driven mechanisms (flexmbs_problems_mechanisms) against closed-form
!> kinematics, and the driver rows (angle, translation and distance drivers
!> with s(t)) AD against hand-coded.
module test_mechanisms
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_mbs_rotation, only: rotation_matrix
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_primitive
    use flexmbs_mbs_primitive_kinds, only: primitive_angle_driver, &
        primitive_translation_driver, primitive_distance
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        driver_t, driver_values
    use flexmbs_mbs_formulation, only: block_lambda
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index1, formulation_index2, formulation_index3
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_problems_mechanisms, only: new_mechanism, slider_crank_exact, four_bar_exact, &
        four_bar_torque, crank_angle, bar_b, bar_d
    use mbs_random, only: random_state_t, random_vector, random_quaternion, ad_deviation
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mechanisms

    real(wp), parameter :: rtol = 1.0e-7_wp

    !> Records the largest deviation from the closed form at output times.
    type, extends(sink_t) :: closed_form_sink_t
        integer :: mechanism = 0   !! 1 slider-crank, 2 four-bar
        integer :: samples = 0
        real(wp) :: worst = 0.0_wp
    contains
        procedure :: output => closed_form_output
    end type closed_form_sink_t

contains

    function collect_mechanisms() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('driver_values_exact', test_driver_values), &
                 new_test('ramp_then_hold', test_ramp), &
                 new_test('driver_rows_ad_vs_analytic', test_driver_rows), &
                 new_test('slider_crank_closed_form', test_slider_crank), &
                 new_test('four_bar_closed_form', test_four_bar), &
                 new_test('four_bar_closed_form_ad', test_four_bar_ad), &
                 new_test('sparse_forms_and_mexax_klu', test_sparse), &
                 new_test('every_formulation_every_solver', test_all_forms), &
                 new_test('consistent_multipliers_four_bar', test_consistent_multipliers)]
    end function collect_mechanisms

    !> s' and s'' of a polynomial + harmonic driver against central differences.
    subroutine test_driver_values(error)
        type(error_t), allocatable, intent(out) :: error
        type(driver_t) :: d
        real(wp) :: t, h, s(3), sp(3), sm(3)
        d%poly = [0.3_wp, -1.2_wp, 0.7_wp, 0.25_wp]
        d%amplitude = 0.4_wp
        d%frequency = 3.0_wp
        d%phase = 0.2_wp
        t = 0.9_wp
        h = 1.0e-5_wp
        s = driver_values(d, t)
        sp = driver_values(d, t + h)
        sm = driver_values(d, t - h)
        call check(error, abs((sp(1) - sm(1)) / (2 * h) - s(2)) < 1.0e-8_wp, "s'")
        call check(error, abs((sp(2) - sm(2)) / (2 * h) - s(3)) < 1.0e-8_wp, "s''")
        call check(error, abs(s(1) - (0.3_wp - 1.2_wp * t + 0.7_wp * t**2 + 0.25_wp * t**3 + &
                   0.4_wp * sin(3.0_wp * t + 0.2_wp))) < 1.0e-15_wp, 's')
    end subroutine test_driver_values

    !> The ramp-then-hold term: s' and s'' against central differences
    !> inside the ramp and after it, s, s', s'' continuous at T (the C²
    !> joint: s'' and its slope vanish there), s' = Ω/2 at T/2 by symmetry
    !> (∫ of the rising rate), s = Ω (t − T/2) after, 0 before 0.
    subroutine test_ramp(error)
        type(error_t), allocatable, intent(out) :: error
        type(driver_t) :: d
        real(wp) :: s(3), sp(3), sm(3), t
        real(wp), parameter :: h = 1.0e-6_wp, rate = 4.0_wp, ramp = 1.5_wp, &
            times(3) = [0.4_wp, 1.1_wp, 2.3_wp]
        integer :: k
        d%ramp_rate = rate
        d%ramp_time = ramp
        do k = 1, 3
            t = times(k)
            s = driver_values(d, t)
            sp = driver_values(d, t + h)
            sm = driver_values(d, t - h)
            call check(error, abs((sp(1) - sm(1)) / (2 * h) - s(2)) < 1.0e-8_wp, "ramp s'")
            call check(error, abs((sp(2) - sm(2)) / (2 * h) - s(3)) < 1.0e-8_wp, "ramp s''")
        end do
        sm = driver_values(d, ramp * (1.0_wp - 1.0e-9_wp))
        sp = driver_values(d, ramp * (1.0_wp + 1.0e-9_wp))
        call check(error, maxval(abs(sp - sm)) < 1.0e-7_wp, 'continuous at T')
        s = driver_values(d, ramp / 2)
        call check(error, abs(s(2) - rate / 2) < 1.0e-14_wp, "s'(T/2) = rate/2")
        s = driver_values(d, 3.0_wp)
        call check(error, maxval(abs(s - [rate * (3.0_wp - ramp / 2), rate, 0.0_wp])) < &
                   1.0e-13_wp, 'held')
        s = driver_values(d, -0.5_wp)
        call check(error, all(s == 0.0_wp), 'zero before t = 0')
    end subroutine test_ramp

    !> Two free bodies with an angle, a translation and a distance driver on
    !> random markers: c, G, c_q, c_t and γ of 'ad' equal 'analytic'
    !> (≤ 1e-12), and c_t equals the central difference of c in t.
    subroutine test_driver_rows(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: hand, ad, full
        type(status_t) :: status
        type(marker_t) :: markers(4)
        type(mbs_joint_t) :: joints(3)
        type(driver_t) :: drv
        real(wp) :: q(14), v(12), cp(3), cm(3), th(3), t, worst, fd
        integer :: trial, k
        drv%poly = [0.5_wp, 0.8_wp, -0.3_wp, 0.1_wp]
        drv%amplitude = 0.2_wp
        drv%frequency = 5.0_wp
        do k = 1, 4
            markers(k)%body = merge(1, 2, k <= 2)
            if (k == 4) markers(k)%body = 0
            markers(k)%position = random_vector(rng, 3, -0.5_wp, 0.5_wp)
            markers(k)%axes = rotation_matrix(random_quaternion(rng))
        end do
        joints(1) = mbs_joint_t(joint_primitive, 1, 3, primitive_angle_driver, 1, 1, drv)
        joints(2) = mbs_joint_t(joint_primitive, 2, 4, primitive_translation_driver, 2, 1, drv)
        joints(3) = mbs_joint_t(joint_primitive, 1, 4, primitive_distance, 1, 1, drv)
        hand = new_mbs_system([rigid_body_t(), rigid_body_t()], markers, joints, &
                              constraint_derivatives='analytic', status=status)
        if (status%ok()) ad = new_mbs_system([rigid_body_t(), rigid_body_t()], markers, &
            joints, constraint_derivatives='ad', status=status)
        if (status%ok()) full = new_mbs_system([rigid_body_t(), rigid_body_t()], markers, &
            joints, constraint_derivatives='ad_full', status=status)
        call check(error, status%ok() .and. hand%nc == 3, 'systems: ' // status%text())
        if (allocated(error)) return
        worst = 0.0_wp
        fd = 0.0_wp
        do trial = 1, 10
            t = 0.1_wp * trial
            do k = 1, 2
                q(7 * k - 6:7 * k - 4) = random_vector(rng, 3, -1.0_wp, 1.0_wp)
                q(7 * k - 3:7 * k) = random_quaternion(rng)
                v(6 * k - 5:6 * k) = random_vector(rng, 6, -2.0_wp, 2.0_wp)
            end do
            worst = max(worst, ad_deviation(hand, ad, t, q, v, status), &
                        ad_deviation(hand, full, t, q, v, status))
            call hand%constraint_time_derivative(t, q, th, status)
            call hand%constraint(t + 1.0e-6_wp, q, cp, status)
            call hand%constraint(t - 1.0e-6_wp, q, cm, status)
            fd = max(fd, maxval(abs((cp - cm) / 2.0e-6_wp - th)) / maxval(abs(th)))
        end do
        print '(4x,a,es9.2,a,es9.2)', 'driver rows: AD vs analytic ', worst, &
            ', c_t vs difference ', fd
        call check(error, status%ok(), 'driver rows: ' // status%text())
        call check(error, worst <= 1.0e-12_wp, 'driver rows: AD differs from analytic')
        call check(error, fd <= 1.0e-7_wp, 'driver rows: c_t differs from dc/dt')
        call check(error, all(abs(th) > 0.0_wp), 'driver rows: c_t vanishes')
    end subroutine test_driver_rows

    !> Integrate one crank revolution with RADAU5 on the GGL form from the
    !> closed-form positions (velocities by the consistent-initial
    !> projection), comparing every output with the closed form.
    subroutine run_mechanism(error, mechanism, name, derivatives)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: mechanism
        character(len=*), intent(in) :: name
        character(len=*), intent(in), optional :: derivatives
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dae
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(closed_form_sink_t) :: sink
        real(wp) :: q0(21), t
        real(wp), allocatable :: y(:), yp(:)
        integer :: i
        call new_mechanism(mechanism, sys, q0, status, derivatives)
        call check(error, status%ok() .and. sys%nc == 18, name // ': build: ' // status%text())
        if (allocated(error)) return
        dae = new_formulation(sys, formulation_ggl, q0, status=status)
        call check(error, status%ok(), name // ': formulation: ' // status%text())
        if (allocated(error)) return
        allocate (y(dae%n), yp(dae%n), source=0.0_wp)
        y(1:21) = q0
        call dae%consistent_initial(0.0_wp, y, yp, status)
        call check(error, status%ok(), name // ': initial: ' // status%text())
        if (allocated(error)) return
        options%rtol = rtol
        options%atol = rtol
        options%output_times = [(0.05_wp * i, i = 0, 20)]
        sink%mechanism = mechanism
        t = 0.0_wp
        call solver%integrate(dae, t, y, 1.0_wp, options, stats, status, sink)
        print '(4x,a,a,i0,a,i0,a,es9.2)', name, ': NST=', stats%nst, ', outputs ', &
            sink%samples, ', largest deviation from the closed form ', sink%worst
        call check(error, status%ok(), name // ': ' // status%text())
        call check(error, sink%samples == 21, name // ': outputs missing')
        call check(error, sink%worst <= 10.0_wp * rtol, name // ': off the closed form')
    end subroutine run_mechanism

    !> consistent_multipliers on the driven four-bar, whose consistent states
    !> are its exact motion (one degree of freedom, driven): states at
    !> t = 0.5 (k/25)² s, k = 0..25, by consistent_initial, each from the
    !> last; then, with K factored at t = 0, λ at each of them in turn (the
    !> first ones, close together, by refining with the factorization held,
    !> the later ones, up to 0.04 s apart, by a new one) equals
    !> consistent_initial's λ, and the motor's torque on the crank the closed
    !> form's power balance, on the ground its opposite, to round-off (dense
    !> and sparse K).
    subroutine test_consistent_multipliers(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: states = 26
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dae
        type(status_t) :: status
        real(wp) :: q0(21), t, force(3, 2), torque(3, 2), lambda(18), dev_lambda, dev_torque, &
            drive
        real(wp), allocatable :: y(:, :), yp(:)
        integer :: k, i, path
        call new_mechanism(2, sys, q0, status)
        do path = 1, 2
            dae = new_formulation(sys, formulation_ggl, q0, status=status, sparse=path == 2)
            call check(error, status%ok(), 'formulation: ' // status%text())
            if (allocated(error)) return
            allocate (y(dae%n, 0:states - 1), yp(dae%n), source=0.0_wp)
            y(1:21, 0) = q0
            do k = 0, states - 1
                if (k > 0) y(:, k) = y(:, k - 1)
                ! again: each call first renormalises the quaternions the
                ! last one's projection moved off the unit sphere
                do i = 1, 3
                    call dae%consistent_initial(time(k), y(:, k), yp, status)
                end do
            end do
            call dae%consistent_initial(0.0_wp, y(:, 0), yp, status)
            call check(error, status%ok(), 'states: ' // status%text())
            if (allocated(error)) return
            dev_lambda = 0.0_wp
            dev_torque = 0.0_wp
            do k = 0, states - 1
                t = time(k)
                call dae%consistent_multipliers(t, y(:, k), lambda, status)
                call sys%joint_reaction(2, t, y(1:21, k), lambda, force, torque)
                dev_lambda = max(dev_lambda, maxval(abs(lambda - &
                    y(dae%offset(block_lambda) + 1:dae%offset(block_lambda) + 18, k))) &
                                 / maxval(abs(lambda)))
                ! on the crank (marker j) and, the opposite, on the ground
                drive = four_bar_torque(t, [1.0_wp, 0.5_wp, 1.0_wp / 3.0_wp], &
                                        [0.01_wp, 0.01_wp, 0.01_wp], 9.81_wp)
                dev_torque = max(dev_torque, abs(torque(3, 2) - drive), abs(torque(3, 1) + drive))
            end do
            print '(4x,a,l1,a,es9.2,a,es9.2)', 'sparse ', path == 2, &
                ': consistent multipliers off the direct solve by ', dev_lambda, &
                ' (relative), motor torque off the closed form by ', dev_torque
            call check(error, status%ok(), 'multipliers: ' // status%text())
            call check(error, dev_lambda <= 1.0e-12_wp .and. dev_torque <= 1.0e-12_wp, &
                       'consistent multipliers inexact')
            if (allocated(error)) return
            deallocate (y, yp)
        end do
    contains
        pure real(wp) function time(k)
            integer, intent(in) :: k
            time = 0.5_wp * (real(k, wp) / (states - 1))**2
        end function time
    end subroutine test_consistent_multipliers

    !> Slider position and rod angle (slider-crank) or coupler-end position
    !> and rocker angle (four-bar) against the closed form at time t.
    subroutine closed_form_output(self, t, y, status)
        class(closed_form_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp) :: theta, b(3), c(3), phi, r2(3, 3), r3(3, 3), dev
        theta = crank_angle(t)
        r2 = rotation_matrix(y(11:14))
        r3 = rotation_matrix(y(18:21))
        if (self%mechanism == 1) then
            call slider_crank_exact(theta, b, c, phi)
            dev = max(norm2(y(15:17) - c), abs(angle_difference(atan2(r2(2, 1), r2(1, 1)), phi)))
        else
            call four_bar_exact(theta, b, c)
            dev = max(norm2(y(8:10) + 0.5_wp * bar_b * r2(:, 1) - c), &
                      abs(angle_difference(atan2(r3(2, 1), r3(1, 1)), &
                                           atan2(c(2), c(1) - bar_d))))
        end if
        self%samples = self%samples + 1
        self%worst = max(self%worst, dev)
    end subroutine closed_form_output

    pure real(wp) function angle_difference(a, b)
        real(wp), intent(in) :: a, b
        angle_difference = atan2(sin(a - b), cos(a - b))
    end function angle_difference

    subroutine test_slider_crank(error)
        type(error_t), allocatable, intent(out) :: error
        call run_mechanism(error, 1, 'slider-crank')
    end subroutine test_slider_crank

    subroutine test_four_bar(error)
        type(error_t), allocatable, intent(out) :: error
        call run_mechanism(error, 2, 'four-bar')
    end subroutine test_four_bar

    !> The same with constraint_derivatives = 'ad'.
    subroutine test_four_bar_ad(error)
        type(error_t), allocatable, intent(out) :: error
        call run_mechanism(error, 2, 'four-bar (ad)', 'ad')
    end subroutine test_four_bar_ad
    !> The system's CSC M and G equal the dense ones; MEXAX with KLU on
    !> [M Gᵀ; G 0] follows MEXAX dense on the slider-crank.
    subroutine test_sparse(error)
        type(error_t), allocatable, intent(out) :: error
        type(mbs_system_t), target :: sys
        type(csc_matrix_t) :: mp, gp
        type(status_t) :: status
        type(mexax_t) :: mexax
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        real(wp) :: q0(21), md(18, 18), ms(18, 18), gd(18, 18), gs(18, 18), t, dev
        real(wp) :: q(21, 2), v(18, 2), lam(18, 2)
        real(wp), allocatable :: values(:)
        integer :: k
        call new_mechanism(1, sys, q0, status)
        call sys%mass_pattern(mp, status)
        allocate (values(mp%nnz))
        call sys%mass_sparse(0.0_wp, q0, values, status)
        mp%values = values
        call mp%to_dense(ms)
        call sys%mass(0.0_wp, q0, md, status)
        call sys%constraint_jacobian_pattern(gp, status)
        deallocate (values)
        allocate (values(gp%nnz))
        call sys%constraint_jacobian_sparse(0.1_wp, q0, values, status)
        gp%values = values
        call gp%to_dense(gs)
        call sys%constraint_jacobian(0.1_wp, q0, gd, status)
        call check(error, status%ok(), 'sparse forms: ' // status%text())
        call check(error, all(ms == md), 'sparse M differs from dense M')
        call check(error, all(gs == gd), 'sparse G differs from dense G')
        if (allocated(error)) return
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        do k = 1, 2
            options%linear_solver = trim(merge('dense', 'klu  ', k == 1))
            q(:, k) = q0
            v(:, k) = 0.0_wp
            lam(:, k) = 0.0_wp
            call consistent_velocity(sys, q(:, k), v(:, k))
            t = 0.0_wp
            call mexax%integrate_mechanical(sys, t, q(:, k), v(:, k), 0.5_wp, options, stats, &
                                            status, lambda=lam(:, k))
            call check(error, status%ok(), 'mexax ' // trim(options%linear_solver) // ': ' // &
                       status%text())
            if (allocated(error)) return
        end do
        dev = maxval(abs(q(:, 1) - q(:, 2)))
        print '(4x,a,es9.2)', 'MEXAX dense vs KLU on the slider-crank: ', dev
        call check(error, dev <= 1.0e-8_wp, 'MEXAX KLU differs from dense')
    end subroutine test_sparse

    !> Velocities of the driven mechanism at t = 0 by the formulation's
    !> consistent-initial projection.
    subroutine consistent_velocity(sys, q, v)
        type(mbs_system_t), target, intent(inout) :: sys
        real(wp), intent(inout) :: q(:), v(:)
        type(formulation_t) :: dae
        type(status_t) :: status
        real(wp), allocatable :: y(:), yp(:)
        dae = new_formulation(sys, formulation_ggl, q, status=status)
        allocate (y(dae%n), yp(dae%n), source=0.0_wp)
        y(1:21) = q
        call dae%consistent_initial(0.0_wp, y, yp, status)
        q = y(1:21)
        v = y(22:39)
    end subroutine consistent_velocity
    !> The four-bar in every formulation with RADAU5, DDASSL and IDA (and
    !> MEXAX on the mechanical form) for half a revolution at rtol 1e-6: each
    !> finishes and follows the closed form within 1e-4 m (measured 8e-9 …
    !> 6e-6; index 1 without stabilisation and index 3 with the BDF codes
    !> are the loosest).
    subroutine test_all_forms(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: forms(4) = [formulation_index1, formulation_index2, &
                                          formulation_index3, formulation_ggl]
        character(len=6), parameter :: form_names(4) = ['index1', 'index2', 'index3', 'ggl   ']
        character(len=6), parameter :: solver_names(3) = ['radau5', 'ddassl', 'ida   ']
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dae
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(mexax_t) :: mexax
        real(wp) :: q0(21), t, b(3), c(3), r(3, 3), dev
        real(wp), allocatable :: y(:), yp(:)
        integer :: f, k
        character(len=200) :: line
        options%rtol = 1.0e-6_wp
        options%atol = 1.0e-6_wp
        do f = 1, size(forms)
            do k = 1, size(solver_names)
                call new_mechanism(2, sys, q0, status)
                dae = new_formulation(sys, forms(f), q0, constant_mass=.true., status=status)
                allocate (y(dae%n), yp(dae%n), source=0.0_wp)
                y(1:21) = q0
                call dae%consistent_initial(0.0_wp, y, yp, status)
                select case (k)
                case (1); allocate (radau5_t :: solver)
                case (2); allocate (ddassl_t :: solver)
                case (3); allocate (ida_t :: solver)
                end select
                t = 0.0_wp
                call solver%integrate(dae, t, y, 0.5_wp, options, stats, status)
                call four_bar_exact(crank_angle(t), b, c)
                r = rotation_matrix(y(11:14) / norm2(y(11:14)))
                dev = norm2(y(8:10) + 0.5_wp * bar_b * r(:, 1) - c)
                write (line, '(a,1x,a,a,i0,a,es9.2,1x,a)') trim(form_names(f)), &
                    trim(solver_names(k)), ': NST=', stats%nst, ', closed-form deviation ', &
                    dev, trim(merge('ok    ', 'failed', status%ok()))
                print '(4x,a)', trim(line)
                call check(error, status%ok() .and. dev <= 1.0e-4_wp, trim(line) // ' ' // &
                           status%text())
                deallocate (y, yp, solver)
            end do
        end do
        ! MEXAX integrates the mechanical form directly
        call new_mechanism(2, sys, q0, status)
        dae = new_formulation(sys, formulation_index2, q0, constant_mass=.true., status=status)
        allocate (y(dae%n), yp(dae%n), source=0.0_wp)
        y(1:21) = q0
        call dae%consistent_initial(0.0_wp, y, yp, status)
        t = 0.0_wp
        call mexax%integrate_mechanical(sys, t, y(1:21), y(22:39), 0.5_wp, options, stats, &
                                        status, lambda=y(40:57))
        call four_bar_exact(crank_angle(t), b, c)
        r = rotation_matrix(y(11:14))
        dev = norm2(y(8:10) + 0.5_wp * bar_b * r(:, 1) - c)
        print '(4x,a,es9.2)', 'mexax: closed-form deviation ', dev
        call check(error, status%ok() .and. dev <= 1.0e-4_wp, 'mexax: ' // status%text())
    end subroutine test_all_forms
end module test_mechanisms
