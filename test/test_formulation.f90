!> The generic formulations (src/mbs/formulation.f90) on the mechanical
!> pendulum: against the hand-written forms of src/problems/pendulum.f90
!> (residuals, Jacobians, mass, classes, RADAU5 trajectories), difference
!> Jacobians of the acceleration layout, RADAU5 and DDASSL runs against the
!> exact solution, and the drift behaviour of the formulations.
module test_formulation
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_user_function
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_reference, pendulum_mechanical_t, new_pendulum_mechanical, &
        pendulum_mechanical_initial
    use flexmbs_mbs_formulation, only: block_a, block_lambda, block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_index3, formulation_ggl
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_formulation, difference_jacobian

    !> Records the drift ‖g‖ after every accepted step, binned in time.
    type, extends(sink_t) :: drift_sink_t
        type(formulation_t), pointer :: formulation => null()
        real(wp) :: bin_width = 1.0_wp
        real(wp), allocatable :: position(:)  !! max |g| per bin
        real(wp), allocatable :: velocity(:)  !! max |G v| per bin
    contains
        procedure :: output => drift_output
        procedure :: wants_steps => drift_wants_steps
        procedure :: step => drift_step
    end type drift_sink_t

    !> The mechanical pendulum with only the bindings a problem must give:
    !> every derivative is the default forward difference; its forces fail
    !> for x above `fail_above`.
    type, extends(mechanical_problem_t) :: plain_pendulum_t
        type(pendulum_mechanical_t) :: p
        real(wp) :: fail_above = huge(1.0_wp)
    contains
        procedure :: kinematics => plain_kinematics
        procedure :: mass => plain_mass
        procedure :: forces => plain_forces
        procedure :: constraint => plain_constraint
        procedure :: constraint_jacobian => plain_constraint_jacobian
    end type plain_pendulum_t

    real(wp), parameter :: phi0 = 1.0_wp
    ! a state off the constraint manifold (residual and Jacobian checks)
    real(wp), parameter :: y_test(6) = [0.6_wp, -0.7_wp, 0.3_wp, 0.4_wp, 2.5_wp, 0.1_wp]
    real(wp), parameter :: eps = epsilon(1.0_wp)
    character(len=*), parameter :: form_names(4) = ['index 1', 'index 2', 'index 3', 'GGL    ']

contains

    function collect_formulation() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('pendulum_forms_match_hand_written', test_match_hand_written), &
                 new_test('acceleration_layout_jacobian', test_acceleration_jacobian), &
                 new_test('radau5_trajectory_matches', test_radau5_trajectory), &
                 new_test('radau5_acceleration_layout', test_radau5_accelerations), &
                 new_test('ddassl_runs', test_ddassl), &
                 new_test('consistent_initial', test_consistent_initial), &
                 new_test('drift_growth', test_drift), &
                 new_test('default_differences', test_default_differences)]
    end function collect_formulation

    !> Residuals, Jacobians, mass matrices and index classes of the constant-
    !> mass layout equal the hand-written pendulum's to a few ulps.
    subroutine test_match_hand_written(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(pendulum_t) :: hand
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: fh(:), fg(:), jh(:, :), jg(:, :), mh(:, :), mg(:, :)
        integer, allocatable :: ch(:), cg(:)
        integer :: form, n
        character(len=160) :: msg
        mech = new_pendulum_mechanical()
        do form = formulation_index1, formulation_ggl
            hand = new_pendulum(form, phi0)
            gen = new_formulation(mech, form, y_test(1:2), constant_mass=.true., status=status)
            call check(error, status%ok(), 'constructor: ' // status%text())
            if (allocated(error)) return
            n = hand%n
            call check(error, gen%n == n, form_names(form) // ': sizes differ')
            if (allocated(error)) return
            allocate (fh(n), fg(n), jh(n, n), jg(n, n), mh(n, n), mg(n, n), ch(n), cg(n))
            call hand%rhs(0.3_wp, y_test(1:n), fh, status)
            call gen%rhs(0.3_wp, y_test(1:n), fg, status)
            write (msg, '(2a,es10.3)') form_names(form), ': residuals differ by ', &
                maxval(abs(fh - fg))
            call check(error, maxval(abs(fh - fg)) <= 4 * eps * maxval(abs(fh)), trim(msg))
            call hand%jacobian_dense(0.3_wp, y_test(1:n), jh, status)
            call gen%jacobian_dense(0.3_wp, y_test(1:n), jg, status)
            write (msg, '(2a,es10.3)') form_names(form), ': Jacobians differ by ', &
                maxval(abs(jh - jg))
            call check(error, maxval(abs(jh - jg)) <= 4 * eps * maxval(abs(jh)), trim(msg))
            call hand%mass_dense(mh)
            call gen%mass_dense(mg)
            call check(error, all(mh == mg), form_names(form) // ': mass matrices differ')
            call hand%index_classes(ch)
            call gen%index_classes(cg)
            call check(error, all(ch == cg), form_names(form) // ': index classes differ')
            call check(error, status%ok(), form_names(form) // ': ' // status%text())
            deallocate (fh, fg, jh, jg, mh, mg, ch, cg)
        end do
    end subroutine test_match_hand_written

    !> The acceleration layout (q, v, a, λ[, μ]): analytic Jacobian against
    !> central differences of F; the classes of docs/theory.md §3.2.
    subroutine test_acceleration_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: y(:), jac(:, :), jfd(:, :)
        integer, allocatable :: classes(:)
        integer :: form, n
        character(len=160) :: msg
        integer, parameter :: expected(8, 4) = reshape([1, 1, 1, 1, 1, 1, 1, 0, &
                                                        1, 1, 1, 1, 2, 2, 2, 0, &
                                                        1, 1, 2, 2, 3, 3, 3, 0, &
                                                        1, 1, 1, 1, 2, 2, 2, 2], [8, 4])
        mech = new_pendulum_mechanical()
        do form = formulation_index1, formulation_ggl
            gen = new_formulation(mech, form, y_test(1:2), baumgarte_zeta=1.0_wp, &
                baumgarte_omega=merge(3.0_wp, 0.0_wp, form == formulation_index1), &
                status=status)
            n = gen%n
            allocate (y(n), jac(n, n), jfd(n, n), classes(n))
            y = [y_test(1:4), -0.2_wp, 0.5_wp, y_test(5:6)]
            y = y(1:n)
            call gen%jacobian_dense(0.0_wp, y, jac, status)
            call difference_jacobian(gen, y, jfd, status)
            write (msg, '(2a,es10.3)') form_names(form), ': Jacobian vs differences ', &
                maxval(abs(jac - jfd))
            call check(error, maxval(abs(jac - jfd)) <= 1.0e-8_wp, trim(msg))
            call gen%index_classes(classes)
            call check(error, all(classes == expected(1:n, form)), &
                form_names(form) // ': index classes')
            call check(error, status%ok(), status%text())
            deallocate (y, jac, jfd, classes)
        end do
    end subroutine test_acceleration_jacobian

    !> Central differences of F at t = 0 (step 1e-6), column by column.
    subroutine difference_jacobian(gen, y, jfd, status)
        type(formulation_t), intent(inout) :: gen
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: jfd(:, :)
        type(status_t), intent(inout) :: status
        real(wp), parameter :: delta = 1.0e-6_wp
        real(wp) :: yp(size(y)), fp(size(y)), fm(size(y))
        integer :: j
        do j = 1, size(y)
            yp = y
            yp(j) = y(j) + delta
            call gen%rhs(0.0_wp, yp, fp, status)
            yp(j) = y(j) - delta
            call gen%rhs(0.0_wp, yp, fm, status)
            jfd(:, j) = (fp - fm) / (2 * delta)
        end do
    end subroutine difference_jacobian

    !> RADAU5 on the hand-written and the generic constant-mass forms: the
    !> same trajectory to round-off.
    subroutine test_radau5_trajectory(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(pendulum_t) :: hand
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: sh, sg
        type(status_t) :: status
        real(wp), allocatable :: yh(:), yg(:)
        real(wp) :: t
        integer :: form
        character(len=160) :: msg
        mech = new_pendulum_mechanical()
        options%rtol = 1.0e-8_wp
        options%atol = 1.0e-8_wp
        do form = formulation_index1, formulation_ggl
            hand = new_pendulum(form, phi0)
            allocate (yh(hand%n), yg(hand%n))
            call pendulum_initial(hand, yh)
            yg = yh
            gen = new_formulation(mech, form, yh(1:2), constant_mass=.true., status=status)
            t = 0.0_wp
            call solver%integrate(hand, t, yh, 1.0_wp, options, sh, status)
            call check(error, status%ok(), 'hand-written: ' // status%text())
            t = 0.0_wp
            call solver%integrate(gen, t, yg, 1.0_wp, options, sg, status)
            call check(error, status%ok(), 'generic: ' // status%text())
            write (msg, '(2a,es10.3,a,2(i0,1x))') form_names(form), &
                ': trajectories differ by ', maxval(abs(yh - yg)), ', steps ', sh%nst, sg%nst
            print '(a)', '    ' // trim(msg)
            call check(error, maxval(abs(yh - yg)) <= 1.0e-12_wp .and. sh%nst == sg%nst &
                .and. sh%nfe == sg%nfe, trim(msg))
            deallocate (yh, yg)
        end do
    end subroutine test_radau5_trajectory

    !> Consistent initial values of the acceleration layout at rest from φ0.
    subroutine initial_state(gen, mech, y)
        type(formulation_t), intent(in) :: gen
        type(pendulum_mechanical_t), intent(in) :: mech
        real(wp), intent(out) :: y(:)
        real(wp) :: q(2), v(2), lam(1)
        call pendulum_mechanical_initial(mech, phi0, q, v, lam)
        y = 0.0_wp
        y(1:2) = q
        y(gen%offset(block_v) + 1:gen%offset(block_v) + 2) = v
        if (gen%accelerations) y(gen%offset(block_a) + 1:gen%offset(block_a) + 2) = &
            -q * lam(1) / mech%point_mass - [0.0_wp, mech%gravity]
        y(gen%offset(block_lambda) + 1) = lam(1)
    end subroutine initial_state

    !> RADAU5 runs every formulation in the acceleration layout (and index 2
    !> with projection) to t = 3 within 10 rtol (ERR, eq. 13, positions).
    subroutine test_radau5_accelerations(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(pendulum_t) :: hand
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: y(:)
        real(wp) :: t, yref(5), err, rtol
        integer :: form, k
        character(len=160) :: msg
        integer, parameter :: cases(5) = [formulation_index1, formulation_index2, &
            formulation_index3, formulation_ggl, formulation_index2]
        mech = new_pendulum_mechanical()
        hand = new_pendulum(formulation_index2, phi0)
        rtol = 1.0e-7_wp
        options%rtol = rtol
        options%atol = rtol
        call pendulum_reference(hand, 3.0_wp, yref, status)
        do k = 1, 5
            form = cases(k)
            gen = new_formulation(mech, form, yref(1:2), projection=k == 5, status=status)
            gen%projection_rtol = rtol
            gen%projection_atol = rtol
            allocate (y(gen%n))
            call initial_state(gen, mech, y)
            t = 0.0_wp
            call solver%integrate(gen, t, y, 3.0_wp, options, stats, status)
            err = paper_error(y(1:2), yref(1:2), rtol, rtol)
            write (msg, '(2a,l1,a,es10.3,1x,a)') form_names(form), ' projection ', k == 5, &
                ': ERR/rtol = ', err / rtol, status%text()
            call check(error, status%ok() .and. err <= 10 * rtol, trim(msg))
            if (k == 5) call check(error, stats%nprj == stats%nac, 'NPRJ /= NAC')
            deallocate (y)
        end do
    end subroutine test_radau5_accelerations

    !> DDASSL runs index 1, index 2 and GGL in both layouts, within 20 rtol.
    subroutine test_ddassl(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(pendulum_t) :: hand
        type(formulation_t) :: gen
        type(ddassl_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: y(:)
        real(wp) :: t, yref(5), err, rtol
        integer :: form, layout
        character(len=160) :: msg
        mech = new_pendulum_mechanical()
        hand = new_pendulum(formulation_index2, phi0)
        rtol = 1.0e-7_wp
        options%rtol = rtol
        options%atol = rtol
        call pendulum_reference(hand, 3.0_wp, yref, status)
        do layout = 0, 1
            do form = formulation_index1, formulation_ggl
                if (form == formulation_index3) cycle
                gen = new_formulation(mech, form, yref(1:2), constant_mass=layout == 1, &
                    status=status)
                allocate (y(gen%n))
                call initial_state(gen, mech, y)
                t = 0.0_wp
                call solver%integrate(gen, t, y, 3.0_wp, options, stats, status)
                err = paper_error(y(1:2), yref(1:2), rtol, rtol)
                write (msg, '(2a,i0,a,es10.3,1x,a)') form_names(form), ' layout ', layout, &
                    ': ERR/rtol = ', err / rtol, status%text()
                call check(error, status%ok() .and. err <= 20 * rtol, trim(msg))
                deallocate (y)
            end do
        end do
    end subroutine test_ddassl

    !> consistent_initial: from a perturbed state, q and v on the manifolds
    !> to round-off, λ and a from the acceleration level.
    subroutine test_consistent_initial(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp) :: y(8), yp(8), dpos, dvel, q(2), v(2), lam(1)
        mech = new_pendulum_mechanical()
        gen = new_formulation(mech, formulation_ggl, y_test(1:2), status=status)
        call pendulum_mechanical_initial(mech, phi0, q, v, lam)
        y = 0.0_wp
        y(1:2) = 1.01_wp * q
        y(3:4) = [0.1_wp, 0.2_wp]
        y(8) = 0.5_wp
        call gen%consistent_initial(0.0_wp, y, yp, status)
        call check(error, status%ok(), status%text())
        call gen%drift(0.0_wp, y, dpos, dvel, status)
        call check(error, dpos <= 10 * eps .and. dvel <= 10 * eps, 'not on the manifolds')
        ! λ = m (|v|² - g y) / L², a = -q λ / m - g e_y
        call check(error, abs(y(7) - (sum(y(3:4)**2) - mech%gravity * y(2))) <= 1.0e-12_wp, &
            'λ not from the acceleration level')
        call check(error, maxval(abs(y(5:6) - (-y(1:2) * y(7) - [0.0_wp, mech%gravity]))) &
            <= 1.0e-12_wp, 'a not from the equations of motion')
        call check(error, all(yp(1:2) == y(3:4)) .and. all(yp(3:4) == y(5:6)) .and. &
            y(8) == 0.0_wp, 'y'' or μ wrong')
    end subroutine test_consistent_initial

    !> Drift (docs/theory.md §3, paper sec. 5.1) on a 64 s run at rtol 1e-6
    !> (about 30 periods): max |g| over the last half of [0, T] for T = 8,
    !> 16, 32, 64 gives growth exponents; index 1 ≈ 2, index 2 ≈ 1; GGL and
    !> projection keep |g| at tolerance level without growth.
    subroutine test_drift(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(formulation_t), target :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(drift_sink_t) :: sink
        real(wp), allocatable :: y(:)
        real(wp) :: t, rtol, d(4), expo
        integer :: k, form, i
        real(wp), parameter :: t_end = 64.0_wp
        integer, parameter :: cases(4) = [formulation_index1, formulation_index2, &
                                          formulation_ggl, formulation_index2]
        character(len=200) :: msg
        mech = new_pendulum_mechanical()
        rtol = 1.0e-6_wp
        options%rtol = rtol
        options%atol = rtol
        do k = 1, 4
            form = cases(k)
            gen = new_formulation(mech, form, [0.0_wp, -1.0_wp], projection=k == 4, &
                status=status)
            gen%projection_rtol = rtol
            gen%projection_atol = rtol
            allocate (y(gen%n))
            call initial_state(gen, mech, y)
            sink = drift_sink_t()
            sink%formulation => gen
            allocate (sink%position(nint(t_end)), sink%velocity(nint(t_end)))
            sink%position = 0.0_wp
            sink%velocity = 0.0_wp
            t = 0.0_wp
            call solver%integrate(gen, t, y, t_end, options, stats, status, sink)
            call check(error, status%ok(), status%text())
            do i = 1, 4
                d(i) = maxval(sink%position(2**(i + 1) + 1:2**(i + 2)))
            end do
            ! the first window still carries the start-up; fit over 8..64
            expo = log(d(4) / d(2)) / log(4.0_wp)
            write (msg, '(a,i0,a,4es10.2,a,f6.2,a,i0)') 'case ', k, ': max|g| ', d, &
                ', exponent ', expo, ', steps ', stats%nst
            print '(a)', '    drift ' // trim(msg)
            select case (k)
            case (1)
                call check(error, expo >= 1.6_wp .and. expo <= 2.4_wp, 'index 1 ' // trim(msg))
            case (2)
                call check(error, expo >= 0.6_wp .and. expo <= 1.4_wp, 'index 2 ' // trim(msg))
            case default
                call check(error, maxval(d) <= rtol .and. d(4) <= 4 * d(1) + rtol * 1e-3_wp, &
                    'stabilised ' // trim(msg))
            end select
            deallocate (y)
        end do
    end subroutine test_drift

    subroutine drift_output(self, t, y, status)
        class(drift_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
    end subroutine drift_output

    logical function drift_wants_steps(self)
        class(drift_sink_t), intent(in) :: self
        drift_wants_steps = .true.
    end function drift_wants_steps

    subroutine drift_step(self, nr, t_old, t, y, dense, stop, status)
        class(drift_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        logical, intent(inout) :: stop
        type(status_t), intent(inout) :: status
        real(wp) :: dpos, dvel
        integer :: bin
        call self%formulation%drift(t, y, dpos, dvel, status)
        bin = min(size(self%position), max(1, ceiling(t / self%bin_width)))
        self%position(bin) = max(self%position(bin), dpos)
        self%velocity(bin) = max(self%velocity(bin), dvel)
    end subroutine drift_step

    !> The default derivatives (forward differences, one routine) against
    !> the pendulum's analytic ones; a failing evaluation ends them with its
    !> status.
    subroutine test_default_differences(error)
        type(error_t), allocatable, intent(out) :: error
        type(plain_pendulum_t) :: plain
        type(status_t) :: status
        real(wp) :: q(2), v(2), w(2), lam(1), fq(2, 2), fv(2, 2), aq(2, 2), av(2, 2), &
            gwq(1, 2), gtlq(2, 2), bwq(1, 2), btlq(2, 2), kq(2, 2), bq(2, 2), cq(1, 2), dcq(1, 2)
        plain%p = new_pendulum_mechanical(status=status)
        plain%nq = plain%p%nq
        plain%nv = plain%p%nv
        plain%nc = plain%p%nc
        q = [0.6_wp, -0.8_wp]
        v = [0.3_wp, 0.2_wp]
        w = [1.5_wp, -0.5_wp]
        lam = [2.0_wp]
        call plain%force_derivatives(0.0_wp, q, v, fq, fv, status)
        call plain%p%force_derivatives(0.0_wp, q, v, aq, av, status)
        call check(error, status%ok() .and. maxval(abs(fq - aq)) <= 1.0e-7_wp .and. &
                   maxval(abs(fv - av)) <= 1.0e-7_wp, 'df/dq, df/dv')
        call plain%constraint_jacobian_derivatives(0.0_wp, q, w, lam, gwq, gtlq, status)
        call plain%p%constraint_jacobian_derivatives(0.0_wp, q, w, lam, bwq, btlq, status)
        call check(error, status%ok() .and. maxval(abs(gwq - bwq)) <= 1.0e-7_wp .and. &
                   maxval(abs(gtlq - btlq)) <= 1.0e-7_wp, 'd(G w)/dq, d(G^T lambda)/dq')
        call plain%kinematics_derivative(0.0_wp, q, w, kq, status)
        call check(error, status%ok() .and. maxval(abs(kq)) == 0.0_wp, 'd(T w)/dq = 0')
        call plain%constraint_position_jacobian(0.0_wp, q, cq, status)
        call plain%p%constraint_position_jacobian(0.0_wp, q, dcq, status)
        call check(error, status%ok() .and. maxval(abs(cq - dcq)) <= 1.0e-7_wp, 'g_q')
        ! forces fail beyond x = 0.6 + 1e-9: the first column's step goes there
        plain%fail_above = 0.6_wp + 1.0e-9_wp
        call plain%force_derivatives(0.0_wp, q, v, fq, fv, status)
        call check(error, status%code == status_solver_failure .and. &
                   index(status%text(), 'x above') > 0, 'a failed evaluation: ' // status%text())
        call status%clear()
        call plain%mass_derivative(0.0_wp, q, w, bq, status)
        call check(error, status%ok() .and. maxval(abs(bq)) == 0.0_wp, 'd(M w)/dq = 0')
    end subroutine test_default_differences

    subroutine plain_kinematics(self, t, q, w, qdot, status)
        class(plain_pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        call self%p%kinematics(t, q, w, qdot, status)
    end subroutine plain_kinematics

    subroutine plain_mass(self, t, q, m, status)
        class(plain_pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        call self%p%mass(t, q, m, status)
    end subroutine plain_mass

    subroutine plain_forces(self, t, q, v, f, status)
        class(plain_pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        call self%p%forces(t, q, v, f, status)
        if (q(1) > self%fail_above) call status%set(status_solver_failure, &
            'plain pendulum: forces refused for x above the test''s bound', &
            reason_user_function)
    end subroutine plain_forces

    subroutine plain_constraint(self, t, q, g, status)
        class(plain_pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        call self%p%constraint(t, q, g, status)
    end subroutine plain_constraint

    subroutine plain_constraint_jacobian(self, t, q, gmat, status)
        class(plain_pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
        call self%p%constraint_jacobian(t, q, gmat, status)
    end subroutine plain_constraint_jacobian
end module test_formulation
