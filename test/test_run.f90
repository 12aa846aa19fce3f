!> The run layer: the catalogue and its factories, and the common
!> interface that drives every solver the same way — a mechanical problem
!> with its formulation goes to `dae_solver_t%integrate`, and each solver of
!> the catalogue integrates it (MEXAX the mechanical form, the others the
!> formulation) to the exact pendulum.
module test_run
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_ddassl, only: ddassl_max_order
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_pendulum, only: pendulum_mechanical_t, new_pendulum_mechanical, &
        pendulum_mechanical_initial, pendulum_angle_exact
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_run_catalogue, only: solvers, problems, solver_info, problem_info, &
        solver_info_t, problem_info_t, solver_choices, problem_choices
    use flexmbs_run_solver_factory, only: new_solver, build_solver
    use flexmbs_run_plan, only: run_plan_t, make_plan
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_run

    real(wp), parameter :: phi0 = 1.0_wp, t_end = 1.0_wp, tol = 1.0e-7_wp

contains

    function collect_run() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('catalogue_factories', test_catalogue), &
                 new_test('integrate_mechanical_all_solvers', test_all_solvers), &
                 new_test('mechanical_core_refuses_formulation_alone', test_refusals), &
                 new_test('plan_mechanical_capability', test_plan)]
    end function collect_run

    !> Every catalogue solver is built by name and calls itself by that
    !> name; the choices offered to scenes are the table's names; an unknown
    !> name is bad input naming the choices.
    subroutine test_catalogue(error)
        type(error_t), allocatable, intent(out) :: error
        class(dae_solver_t), allocatable :: solver
        type(status_t) :: status
        character(len=:), allocatable :: joined
        type(solver_info_t) :: info
        type(problem_info_t) :: pinfo
        integer :: k
        joined = ''
        do k = 1, size(solvers)
            call new_solver(solvers(k)%name, solver, status)
            call check(error, status%ok(), trim(solvers(k)%name) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, solver%name() == trim(solvers(k)%name), 'catalogue name ' // &
                trim(solvers(k)%name) // ' builds ' // solver%name())
            if (allocated(error)) return
            joined = joined // merge('|', ' ', k > 1) // trim(solvers(k)%name)
        end do
        call check(error, joined(2:) == solver_choices, 'solver_choices ' // solver_choices)
        if (allocated(error)) return
        joined = ''
        do k = 1, size(problems)
            joined = joined // merge('|', ' ', k > 1) // trim(problems(k)%name)
        end do
        call check(error, joined(2:) == problem_choices, 'problem_choices ' // problem_choices)
        if (allocated(error)) return
        call new_solver('rk45', solver, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), solver_choices) > 0, 'unknown solver: ' // status%text())
        ! lookups ignore trailing blanks; an unknown name has no capabilities
        info = solver_info('mexax   ')
        call check(error, info%mechanical_only .and. info%projects, 'mexax capabilities')
        info = solver_info('ddassl')
        call check(error, info%pmax_grid .and. info%max_order == ddassl_max_order .and. &
            info%band, 'ddassl capabilities (max_order: the solver''s own)')
        info = solver_info('nonsense')
        call check(error, len_trim(info%name) == 0 .and. .not. info%mechanical_only, &
            'unknown name')
        pinfo = problem_info('multibody')
        call check(error, pinfo%mechanical .and. pinfo%stabilisations .and. pinfo%bodies, &
            'multibody capabilities')
        pinfo = problem_info('robertson')
        call check(error, .not. (pinfo%mechanical .or. pinfo%bodies), 'robertson')
    end subroutine test_catalogue

    !> The pendulum released at φ0 = 1, at rest: its mechanical form and
    !> the index-2 formulation of it; y = (q, v, λ).
    subroutine pendulum(mech, formulation, y, status)
        type(pendulum_mechanical_t), target, intent(inout) :: mech
        type(formulation_t), intent(out) :: formulation
        real(wp), intent(out) :: y(5)
        type(status_t), intent(out) :: status
        mech = new_pendulum_mechanical(status=status)
        if (.not. status%ok()) return
        call pendulum_mechanical_initial(mech, phi0, y(1:2), y(3:4), y(5:5))
        formulation = new_formulation(mech, formulation_index2, y(1:2), constant_mass=.true., &
                                      status=status)
    end subroutine pendulum

    !> Each solver of the catalogue, through the same call, reaches the
    !> exact pendulum: ERR of eq. (13) over the positions at t = 1 within
    !> 50 TOL (RADAU5 and MEXAX are far better; the BDF codes about 5-20
    !> TOL), with consistent counters.
    subroutine test_all_solvers(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(formulation_t) :: formulation
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: y(5), t, phi, dphi, err, exact(2)
        character(len=16) :: text
        integer :: k
        options%rtol = tol
        options%atol = tol
        call pendulum_angle_exact(phi0, sqrt(9.81_wp), t_end, phi, dphi, status)
        exact = [sin(phi), -cos(phi)]
        do k = 1, size(solvers)
            call pendulum(mech, formulation, y, status)
            call check(error, status%ok(), 'pendulum: ' // status%text())
            if (allocated(error)) return
            call new_solver(solvers(k)%name, solver, status)
            t = 0.0_wp
            call solver%integrate(mech, formulation, t, y, t_end, options, stats, status)
            call check(error, status%ok(), trim(solvers(k)%name) // ': ' // status%text())
            if (allocated(error)) return
            err = paper_error(y(1:2), exact, tol, tol)
            write (text, '(es9.2)') err / tol
            write (*, '(4x,a,a,a,a)') trim(solvers(k)%name), ': ERR/TOL = ', trim(text), &
                ', ' // stats%summary()
            call check(error, t == t_end .and. err <= 50.0_wp * tol, trim(solvers(k)%name) // &
                ': t = 1 with ERR/TOL ' // text)
            call check(error, stats%nst == stats%nac + stats%nrj .and. stats%nac > 0, &
                trim(solvers(k)%name) // ': counters ' // stats%summary())
            if (allocated(error)) return
        end do
    end subroutine test_all_solvers

    !> MEXAX has no formulation path: a formulation alone is bad input that
    !> says what to give it, and a state of the wrong size is refused.
    subroutine test_refusals(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t), target :: mech
        type(formulation_t) :: formulation
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(solver_info_t) :: info
        real(wp) :: y(5), t, short(4)
        integer :: k
        do k = 1, size(solvers)
            info = solvers(k)
            if (.not. info%mechanical_only) cycle
            call pendulum(mech, formulation, y, status)
            call new_solver(info%name, solver, status)
            t = 0.0_wp
            call solver%integrate(formulation, t, y, t_end, options, stats, status)
            call check(error, status%code == status_bad_input .and. &
                index(status%text(), 'mechanical') > 0 .and. t == 0.0_wp, &
                trim(info%name) // ' on a formulation alone: ' // status%text())
            short = y(1:4)
            call solver%integrate(mech, formulation, t, short, t_end, options, stats, status)
            call check(error, status%code == status_bad_input .and. &
                index(status%text(), '4 components') > 0, trim(info%name) // &
                ' with 4 of 5 components: ' // status%text())
            if (allocated(error)) return
        end do
    end subroutine test_refusals

    !> A scene's plan gives a mechanical-core solver the mechanical form
    !> with y = (q, v, λ) and the others the formulation the scene names
    !> (GGL: y = (q, v, λ, μ)); the plan integrates either to the same
    !> pendulum.
    subroutine test_plan(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(run_plan_t), target :: plan
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(solver_info_t) :: info
        real(wp), allocatable :: y(:)
        real(wp) :: t, phi, dphi
        integer :: k
        character(len=*), parameter :: sim = '&simulation problem = ''pendulum'', t_end = 1, &
            &pendulum_angle = 1, pendulum_formulation = ''ggl'' /' // new_line('a') // &
            '&output file = ''none'', progress = .false. /' // new_line('a')
        call pendulum_angle_exact(phi0, sqrt(9.81_wp), t_end, phi, dphi, status)
        do k = 1, size(solvers)
            info = solvers(k)
            call parse_scene(sim // '&solver name = ''' // trim(info%name) // &
                ''', rtol = 1e-7, atol = 1e-7 /', 'plan.nml', scene, status)
            if (status%ok()) call make_plan(scene, plan, status)
            call check(error, status%ok(), trim(info%name) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, allocated(plan%mechanical) .eqv. info%mechanical_only, &
                trim(info%name) // ': mechanical form given to exactly the mechanical core')
            call check(error, size(plan%y0) == merge(5, 6, info%mechanical_only), &
                trim(info%name) // ': layout')
            if (allocated(error)) return
            y = plan%y0
            t = 0.0_wp
            call plan%integrate(t, y, t_end, stats, status)
            call check(error, status%ok() .and. paper_error(y(1:2), [sin(phi), -cos(phi)], &
                1.0e-7_wp, 1.0e-7_wp) <= 50.0_wp, trim(info%name) // ' plan: ' // status%text())
            if (allocated(error)) return
        end do
    end subroutine test_plan
end module test_run
