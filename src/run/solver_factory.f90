!> The solver factories of the catalogue (run/catalogue): the solver a
!> scene names. A solver's own settings keep the defaults of its type
!> unless the scene gives them (scene_input's `solver_settings`): those
!> defaults are kept in the solver types alone, as the classic faces use
!> them too.
module flexmbs_run_solver_factory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t, radau5_controller_predictive, &
        radau5_controller_classical
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_midpoint, mexax_base_euler
    use flexmbs_io_scene_input, only: scene_input_t, setting_given
    use flexmbs_run_catalogue, only: solver_id, solver_radau5, solver_ddassl, solver_ida, &
        solver_mexax
    implicit none
    private

    public :: build_solver

contains

    !> The solver the scene names, with the settings it gives.
    subroutine build_solver(scene, solver, status)
        type(scene_input_t), intent(in) :: scene
        class(dae_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        select case (solver_id(scene%solver_name))
        case (solver_radau5)
            allocate (solver, source=new_radau5(scene))
        case (solver_ida)
            allocate (ida_t :: solver)
        case (solver_ddassl)
            allocate (solver, source=new_ddassl(scene))
        case (solver_mexax)
            allocate (solver, source=new_mexax(scene))
        case default
            call status%set(status_bad_input, scene%path // ': &solver: name = ''' // &
                trim(scene%solver_name) // ''': not available in this build')
        end select
    end subroutine build_solver

    function new_radau5(scene) result(radau5)
        type(scene_input_t), intent(in) :: scene
        type(radau5_t) :: radau5
        if (setting_given(scene, 'nit')) radau5%nit = scene%nit
        if (setting_given(scene, 'thet')) radau5%thet = scene%thet
        if (setting_given(scene, 'fnewt')) radau5%fnewt = scene%fnewt
        if (setting_given(scene, 'quot1')) radau5%quot1 = scene%quot1
        if (setting_given(scene, 'quot2')) radau5%quot2 = scene%quot2
        if (setting_given(scene, 'safe')) radau5%safe = scene%safe
        if (setting_given(scene, 'fac_min')) radau5%fac_min = scene%fac_min
        if (setting_given(scene, 'fac_max')) radau5%fac_max = scene%fac_max
        if (setting_given(scene, 'controller')) radau5%controller = merge( &
            radau5_controller_classical, radau5_controller_predictive, &
            scene%controller == 'classical')
        if (setting_given(scene, 'zero_start')) radau5%zero_start = scene%zero_start
    end function new_radau5

    !> p_max reaches DDASSL through dae_options_t (MAXORD).
    function new_ddassl(scene) result(ddassl)
        type(scene_input_t), intent(in) :: scene
        type(ddassl_t) :: ddassl
        if (setting_given(scene, 'initial_derivative')) &
            ddassl%initial_derivative = scene%initial_derivative
        if (setting_given(scene, 'exclude_index23')) ddassl%exclude_index23 = scene%exclude_index23
        if (setting_given(scene, 'netlib')) ddassl%netlib = scene%netlib
    end function new_ddassl

    function new_mexax(scene) result(mexax)
        type(scene_input_t), intent(in) :: scene
        type(mexax_t) :: mexax
        if (setting_given(scene, 'max_extrapolation')) &
            mexax%max_extrapolation = scene%max_extrapolation
        if (setting_given(scene, 'mexax_base')) mexax%base = merge(mexax_base_euler, &
            mexax_base_midpoint, scene%mexax_base == 'euler')
    end function new_mexax
end module flexmbs_run_solver_factory
