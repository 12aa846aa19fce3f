!> RADAU5 on DAEs: Robertson (index 1) and the pendulum in index-3, index-2,
!> index-1 and GGL form, against exact references and invariants.
module test_radau5_dae
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: storage_dense
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_robertson, only: robertson_t, new_robertson, robertson_initial, &
        robertson_k1, robertson_k2, robertson_k3
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_reference, pendulum_position_residual, pendulum_velocity_residual, &
        pendulum_index1, pendulum_index2, pendulum_index3, pendulum_ggl
    use reference_integrator, only: reference_ode_t, integrate_reference
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_radau5_dae

    !> Robertson as the original stiff ODE (y3' = k2 y2²): an independent
    !> formulation for the reference of the index-1 DAE.
    type, extends(dae_problem_t) :: robertson_ode_t
    contains
        procedure :: rhs => robertson_ode_rhs
    end type robertson_ode_t

    !> Robertson's ODE form for the independent integrator, written anew
    !> from the equations, with its exact Jacobian.
    type, extends(reference_ode_t) :: robertson_reference_t
    contains
        procedure :: rhs => robertson_reference_rhs
        procedure :: jacobian => robertson_reference_jacobian
    end type robertson_reference_t

    !> Tracks invariants after every accepted step.
    type, extends(sink_t) :: drift_sink_t
        integer :: kind = 0            !! 0 Robertson, 1 pendulum
        type(pendulum_t), pointer :: pendulum => null()
        real(wp) :: max_sum_error = 0.0_wp
        real(wp) :: max_position = 0.0_wp
        real(wp) :: max_velocity = 0.0_wp
        integer :: nsteps = 0
    contains
        procedure :: output => drift_output
        procedure :: wants_steps => drift_wants_steps
        procedure :: step => drift_step
    end type drift_sink_t

    real(wp), parameter :: phi0 = 1.0_wp     !! pendulum start angle [rad]
    real(wp), parameter :: t_pendulum = 3.0_wp
    real(wp), parameter :: t_end = 1.0e5_wp    !! end of the Robertson runs

contains

    function collect_radau5_dae() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('robertson_sum_and_accuracy', test_robertson), &
                 new_test('pendulum_index3', test_pendulum_index3), &
                 new_test('pendulum_index2', test_pendulum_index2), &
                 new_test('pendulum_ggl', test_pendulum_ggl), &
                 new_test('pendulum_index1', test_pendulum_index1), &
                 new_test('pendulum_projection_hook', test_pendulum_projection), &
                 new_test('sparse_storage_same_trajectory', test_sparse_storage)]
    end function collect_radau5_dae

    subroutine test_robertson(error)
        type(error_t), allocatable, intent(out) :: error
        type(robertson_t) :: problem
        type(robertson_ode_t) :: ode
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(drift_sink_t) :: sink
        real(wp) :: t, y(3), yref(3), yode(3), y_coarse(3), y_fine(3), rtol, err
        real(wp), parameter :: atol_factor = 1.0e-4_wp
        integer :: k
        logical :: ok_coarse, ok_fine
        character(len=120) :: msg
        ! Reference: the DAE form at 1e-12, compared with the ODE form at 1e-12
        ! (same method, other formulation).
        ode%n = 3
        options%rtol = 1.0e-12_wp
        options%atol = 1.0e-16_wp
        t = 0.0_wp
        yode = [1.0_wp, 0.0_wp, 0.0_wp]
        call solver%integrate(ode, t, yode, t_end, options, stats, status)
        call check(error, status%ok(), 'reference ODE run: ' // status%text())
        problem = new_robertson()
        call robertson_initial(problem, yref)
        t = 0.0_wp
        call solver%integrate(problem, t, yref, t_end, options, stats, status)
        call check(error, status%ok(), 'reference DAE run: ' // status%text())
        call check(error, paper_error(yode, yref, 1.0e-10_wp, 1.0e-14_wp) <= 1.0e-10_wp, &
            'ODE and DAE references disagree')
        ! Independent confirmation: Lobatto IIIC on the ODE form. Its runs at
        ! rtol 1e-12 and 1e-13 differ by ERR ≈ 1.8e-11 (the error of the first;
        ! global error ∝ tol^0.8), so the second is good to ~3e-12 (measured
        ! ERR to the reference 6.9e-13); 0.12 s (debug), 930 + 2100 steps.
        call run_robertson_reference(1.0e-12_wp, y_coarse, ok_coarse)
        call run_robertson_reference(1.0e-13_wp, y_fine, ok_fine)
        call check(error, ok_coarse .and. ok_fine, 'independent Robertson run failed')
        err = paper_error(y_coarse, y_fine, 1.0e-10_wp, 1.0e-14_wp)
        write (msg, '(a,es9.2)') 'independent integrator not accurate enough: ERR = ', err
        call check(error, err <= 3.0e-11_wp, trim(msg))
        err = paper_error(y_fine, yref, 1.0e-10_wp, 1.0e-14_wp)
        write (msg, '(a,es9.2)') 'reference not confirmed by the independent integrator: ERR = ', &
            err
        call check(error, err <= 1.0e-11_wp, trim(msg))
        if (allocated(error)) return
        do k = 4, 8
            rtol = 10.0_wp**(-k)
            options%rtol = rtol
            options%atol = rtol * atol_factor
            sink = drift_sink_t()
            call robertson_initial(problem, y)
            t = 0.0_wp
            call solver%integrate(problem, t, y, t_end, options, stats, status, sink)
            call check(error, status%ok(), 'run failed: ' // status%text())
            call check(error, sink%max_sum_error <= 1.0e-10_wp, 'y1+y2+y3 drifted from 1')
            err = paper_error(y, yref, rtol, rtol * atol_factor)
            write (msg, '(a,es8.1,a,es10.3)') 'rtol ', rtol, ': ERR/rtol = ', err / rtol
            call check(error, err <= 10.0_wp * rtol, trim(msg))
            call check(error, stats%nst == stats%nac + stats%nrj, 'NST /= NAC + NRJ')
        end do
    end subroutine test_robertson

    !> The independent integrator on Robertson's ODE form, atol = 1e-4 rtol.
    subroutine run_robertson_reference(rtol, y, ok)
        real(wp), intent(in) :: rtol
        real(wp), intent(out) :: y(3)
        logical, intent(out) :: ok
        type(robertson_reference_t) :: ode
        real(wp) :: t
        integer :: nsteps
        t = 0.0_wp
        y = [1.0_wp, 0.0_wp, 0.0_wp]
        call integrate_reference(ode, t, y, t_end, rtol, 1.0e-4_wp * rtol, nsteps, ok, &
            h0=1.0e-6_wp)
    end subroutine run_robertson_reference

    !> Run the pendulum in one formulation; return ERR over the positions at
    !> t_pendulum and the largest constraint residuals after accepted steps.
    subroutine run_pendulum(formulation, rtol, err, max_position, max_velocity, stats, &
                            status, sparse, linear_solver, projection, y_end)
        integer, intent(in) :: formulation
        real(wp), intent(in) :: rtol
        real(wp), intent(out) :: err, max_position, max_velocity
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: sparse, projection
        character(len=*), intent(in), optional :: linear_solver
        real(wp), allocatable, intent(out), optional :: y_end(:)
        type(pendulum_t), target :: problem
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(drift_sink_t) :: sink
        real(wp), allocatable :: y(:), yref(:)
        real(wp) :: t
        problem = new_pendulum(formulation, phi0, sparse=sparse, sparse_mass=sparse, &
            projection=projection)
        allocate (y(problem%n), yref(problem%n))
        call pendulum_initial(problem, y)
        options%rtol = rtol
        options%atol = rtol
        if (present(linear_solver)) options%linear_solver = linear_solver
        sink%kind = 1
        sink%pendulum => problem
        t = 0.0_wp
        call solver%integrate(problem, t, y, t_pendulum, options, stats, status, sink)
        call pendulum_reference(problem, t_pendulum, yref, status)
        err = paper_error(y(1:2), yref(1:2), rtol, rtol)
        max_position = sink%max_position
        max_velocity = sink%max_velocity
        if (present(y_end)) y_end = y
    end subroutine run_pendulum

    !> Index 3: the position constraint is a stage equation, so it holds to
    !> Newton accuracy; the velocity constraint is not enforced (its error is
    !> weighted by 1/h). Positions lose accuracy at tight tolerances because
    !> λ's weight is scaled by 1/h² [HLR89]: 10× tolerance down to 1e-6,
    !> 50× below.
    subroutine test_pendulum_index3(error)
        type(error_t), allocatable, intent(out) :: error
        call check_formulation(error, pendulum_index3, 'index 3', &
            position_bound=1.0_wp, velocity_bound=huge(1.0_wp), tight_accuracy=50.0_wp)
    end subroutine test_pendulum_index3

    !> Index 2 (eq. 8): the velocity constraint holds to Newton accuracy (its
    !> weight scales with 1/h, hence 20 rtol); positions drift slowly, below
    !> rtol over the 3 s here.
    subroutine test_pendulum_index2(error)
        type(error_t), allocatable, intent(out) :: error
        call check_formulation(error, pendulum_index2, 'index 2', &
            position_bound=1.0_wp, velocity_bound=20.0_wp)
    end subroutine test_pendulum_index2

    !> GGL (eq. 10): both constraints hold, with no drift.
    subroutine test_pendulum_ggl(error)
        type(error_t), allocatable, intent(out) :: error
        call check_formulation(error, pendulum_ggl, 'GGL', &
            position_bound=1.0_wp, velocity_bound=20.0_wp)
    end subroutine test_pendulum_ggl

    !> Index 1 (eq. 9): accurate, but both constraints drift (bounded by
    !> the tolerance over the interval).
    subroutine test_pendulum_index1(error)
        type(error_t), allocatable, intent(out) :: error
        call check_formulation(error, pendulum_index1, 'index 1', &
            position_bound=10.0_wp, velocity_bound=10.0_wp)
    end subroutine test_pendulum_index1

    !> Sweep rtol = 1e-4 … 1e-8. Bounds are on residual / rtol; ERR ≤ 10 rtol
    !> (or tight_accuracy·rtol for rtol < 1e-6).
    subroutine check_formulation(error, formulation, label, position_bound, velocity_bound, &
                                 tight_accuracy)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: formulation
        character(len=*), intent(in) :: label
        real(wp), intent(in) :: position_bound, velocity_bound
        real(wp), intent(in), optional :: tight_accuracy
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: rtol, err, max_position, max_velocity, accuracy
        integer :: k
        character(len=160) :: msg
        do k = 4, 8
            rtol = 10.0_wp**(-k)
            call run_pendulum(formulation, rtol, err, max_position, max_velocity, stats, status)
            call check(error, status%ok(), label // ': run failed: ' // status%text())
            write (msg, '(a,a,es8.1,3(a,es10.3))') label, ': rtol ', rtol, ': ERR/rtol = ', &
                err / rtol, ' |g|/rtol = ', max_position / rtol, ' |Gv|/rtol = ', &
                max_velocity / rtol
            accuracy = 10.0_wp
            if (present(tight_accuracy) .and. k > 6) accuracy = tight_accuracy
            call check(error, err <= accuracy * rtol, trim(msg))
            call check(error, max_position <= position_bound * rtol, trim(msg))
            call check(error, max_velocity <= velocity_bound * rtol, trim(msg))
            call check(error, stats%nst == stats%nac + stats%nrj, 'NST /= NAC + NRJ')
        end do
    end subroutine check_formulation

    !> The projection hook (eqs. 11–12) after every accepted step: index 2
    !> without drift, one projection per accepted step.
    subroutine test_pendulum_projection(error)
        type(error_t), allocatable, intent(out) :: error
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: err, max_position, max_velocity
        call run_pendulum(pendulum_index2, 1.0e-6_wp, err, max_position, max_velocity, &
            stats, status, projection=.true.)
        call check(error, status%ok(), 'run failed: ' // status%text())
        call check(error, stats%nprj == stats%nac, 'one projection per accepted step')
        call check(error, max_position <= 1.0e-12_wp, 'projected positions drift')
        call check(error, max_velocity <= 1.0e-12_wp, 'projected velocities drift')
        call check(error, err <= 1.0e-5_wp, 'projected run inaccurate')
    end subroutine test_pendulum_projection

    !> CSC Jacobian and mass give the dense trajectory to round-off.
    subroutine test_sparse_storage(error)
        type(error_t), allocatable, intent(out) :: error
        type(dae_stats_t) :: stats, stats_sparse
        type(status_t) :: status
        real(wp) :: err, max_position, max_velocity
        real(wp), allocatable :: y_dense(:), y_sparse(:)
        call run_pendulum(pendulum_ggl, 1.0e-6_wp, err, max_position, max_velocity, stats, &
            status, sparse=.false., y_end=y_dense)
        call check(error, status%ok(), 'dense run failed: ' // status%text())
        call run_pendulum(pendulum_ggl, 1.0e-6_wp, err, max_position, max_velocity, &
            stats_sparse, status, sparse=.true., y_end=y_sparse)
        call check(error, status%ok(), 'sparse run failed: ' // status%text())
        call check(error, maxval(abs(y_dense - y_sparse)) <= 1.0e-10_wp, &
            'sparse storage changes the trajectory')
        call check(error, stats%nst == stats_sparse%nst, 'sparse storage changes the steps')
    end subroutine test_sparse_storage

    ! ---- helpers ----

    subroutine robertson_ode_rhs(self, t, y, f, status)
        class(robertson_ode_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f(1) = -robertson_k1 * y(1) + robertson_k3 * y(2) * y(3)
        f(3) = robertson_k2 * y(2)**2
        f(2) = -f(1) - f(3)
    end subroutine robertson_ode_rhs

    subroutine robertson_reference_rhs(self, t, y, f)
        class(robertson_reference_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        f(1) = -robertson_k1 * y(1) + robertson_k3 * y(2) * y(3)
        f(2) = robertson_k1 * y(1) - robertson_k3 * y(2) * y(3) - robertson_k2 * y(2)**2
        f(3) = robertson_k2 * y(2)**2
    end subroutine robertson_reference_rhs

    subroutine robertson_reference_jacobian(self, t, y, dfdy)
        class(robertson_reference_t), intent(in) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: dfdy(:, :)
        dfdy(1, :) = [-robertson_k1, robertson_k3 * y(3), robertson_k3 * y(2)]
        dfdy(2, :) = [robertson_k1, -robertson_k3 * y(3) - 2.0_wp * robertson_k2 * y(2), &
            -robertson_k3 * y(2)]
        dfdy(3, :) = [0.0_wp, 2.0_wp * robertson_k2 * y(2), 0.0_wp]
    end subroutine robertson_reference_jacobian

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
        self%nsteps = self%nsteps + 1
        if (self%kind == 0) then
            self%max_sum_error = max(self%max_sum_error, abs(sum(y) - 1.0_wp))
        else
            self%max_position = max(self%max_position, &
                abs(pendulum_position_residual(self%pendulum, y)))
            self%max_velocity = max(self%max_velocity, &
                abs(pendulum_velocity_residual(self%pendulum, y)))
        end if
    end subroutine drift_step
end module test_radau5_dae
