!> A run plan: everything a run needs, built from a scene and checked
!> before any output exists — the problem (and its mechanical form), the
!> solver with its settings, the common options with a linear solver that
!> can be made for this problem, the initial state and its named blocks.
!> Its `integrate` is the one place a solver is called for a scene.
module flexmbs_run_plan
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_io_namelist, only: scene_input_t, scene_dae_options
    use flexmbs_run_catalogue, only: solver_mechanical_only, problem_id, problem_pendulum, &
        problem_flexible_body, problem_multibody, problem_rigid_chain
    use flexmbs_run_problem_factory, only: block_spec_t, build_problem
    use flexmbs_run_solver_factory, only: build_solver
    implicit none
    private

    !> A checked run (see the module): problem, mechanical form, solver, options,
    !> initial state, the named blocks of y and what the output needs to know.
    type, public :: run_plan_t
        class(dae_problem_t), allocatable :: problem
        !> the mechanical form, for mechanical scenes (`problem` is then its
        !> formulation and points to it: the plan must not move once made)
        class(mechanical_problem_t), allocatable :: mechanical
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        real(wp), allocatable :: y0(:)
        type(block_spec_t), allocatable :: blocks(:)
        !> a multibody scene: how far the initial assembly moved each body
        character(len=:), allocatable :: assembly
        !> the positions in y (block 'q'), all of y when there is none
        integer :: q_first = 0, q_last = 0
        !> a multibody scene: per joint of the system, 'joints/NAME' or
        !> 'drivers/NAME'
        character(len=:), allocatable :: joint_names(:)
    contains
        procedure :: integrate => plan_integrate
    end type run_plan_t

    public :: make_plan, scene_stab

contains

    !> The plan of a validated scene; `status` is bad_input (naming the file
    !> and group) when the scene cannot be run as given.
    subroutine make_plan(scene, plan, status)
        type(scene_input_t), intent(in) :: scene
        type(run_plan_t), intent(out), target :: plan
        type(status_t), intent(out) :: status
        class(linear_solver_t), allocatable :: linear_solver
        integer :: i
        call build_problem(scene, plan%problem, plan%y0, plan%blocks, status, &
                           plan%mechanical, plan%assembly, plan%joint_names)
        if (.not. status%ok()) return
        plan%q_first = 1
        plan%q_last = size(plan%y0)
        do i = 1, size(plan%blocks)
            if (plan%blocks(i)%name /= 'q') cycle
            plan%q_first = plan%blocks(i)%first
            plan%q_last = plan%blocks(i)%last
        end do
        call build_solver(scene, plan%solver, status)
        if (.not. status%ok()) return
        plan%options = scene_dae_options(scene)
        call plan%options%validate(plan%problem%n, status)
        if (status%ok()) then
            ! the linear solver must exist before any file is created
            call new_linear_solver(plan%options%linear_solver, plan%problem%n, &
                                   plan%problem%jacobian_storage(), linear_solver, status, &
                                   ordering=plan%options%sparse_ordering)
        end if
        if (.not. status%ok()) status%message = scene%path // ': &solver: ' // status%message
    end subroutine make_plan

    !> Integrate from (t, y) to t_end: the mechanical form with its
    !> formulation when the scene has one (the solver decides which it
    !> integrates), the problem otherwise.
    subroutine plan_integrate(self, t, y, t_end, stats, status, sink)
        class(run_plan_t), intent(inout) :: self
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        if (allocated(self%mechanical)) then
            call self%solver%integrate(self%mechanical, self%problem, t, y, t_end, &
                                       self%options, stats, status, sink)
        else
            call self%solver%integrate(self%problem, t, y, t_end, self%options, stats, &
                                       status, sink)
        end if
    end subroutine plan_integrate

    !> The "stab." column of the tables: the formulation where there is
    !> one, 'mech' for a solver that integrates the mechanical form itself.
    function scene_stab(scene) result(stab)
        type(scene_input_t), intent(in) :: scene
        character(len=:), allocatable :: stab
        if (solver_mechanical_only(scene%solver_name)) then
            stab = 'mech'
            return
        end if
        select case (problem_id(scene%problem))
        case (problem_pendulum)
            stab = trim(scene%pendulum_formulation)
        case (problem_flexible_body)
            stab = trim(scene%bodies(1)%formulation)
        case (problem_multibody, problem_rigid_chain)
            stab = trim(scene%multibody%formulation)
        case default
            stab = '-'
        end select
    end function scene_stab
end module flexmbs_run_plan
