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
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_midpoint, mexax_base_euler, &
        mexax_control_hairer, mexax_control_deuflhard
    use flexmbs_io_scene_input, only: scene_input_t, setting_given
    use flexmbs_run_catalogue, only: solver_id, solver_radau5, solver_ddassl, solver_ida, &
        solver_mexax, solver_choices
    implicit none
    private

    public :: new_solver, build_solver

contains

    !> The solver the catalogue names `name`, with its type's defaults.
    subroutine new_solver(name, solver, status)
        character(len=*), intent(in) :: name
        class(dae_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        select case (solver_id(name))
        case (solver_radau5)
            allocate (radau5_t :: solver)
        case (solver_ddassl)
            allocate (ddassl_t :: solver)
        case (solver_ida)
            allocate (ida_t :: solver)
        case (solver_mexax)
            allocate (mexax_t :: solver)
        case default
            call status%set(status_bad_input, 'solver ''' // trim(name) // ''': not in the &
                &catalogue (' // solver_choices // ')')
        end select
    end subroutine new_solver

    !> The solver the scene names, with the settings it gives.
    subroutine build_solver(scene, solver, status)
        type(scene_input_t), intent(in) :: scene
        class(dae_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        call new_solver(scene%solver_name, solver, status)
        if (.not. status%ok()) then
            status%message = scene%path // ': &solver: name: ' // status%message
            return
        end if
        select type (solver)
        type is (radau5_t)
            call set_radau5(scene, solver)
        type is (ddassl_t)
            call set_ddassl(scene, solver)
        type is (mexax_t)
            call set_mexax(scene, solver)
        end select
    end subroutine build_solver

    subroutine set_radau5(scene, radau5)
        type(scene_input_t), intent(in) :: scene
        type(radau5_t), intent(inout) :: radau5
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
    end subroutine set_radau5

    !> p_max reaches DDASSL through dae_options_t (MAXORD).
    subroutine set_ddassl(scene, ddassl)
        type(scene_input_t), intent(in) :: scene
        type(ddassl_t), intent(inout) :: ddassl
        if (setting_given(scene, 'initial_derivative')) &
            ddassl%initial_derivative = scene%initial_derivative
        if (setting_given(scene, 'exclude_index23')) ddassl%exclude_index23 = scene%exclude_index23
        if (setting_given(scene, 'netlib')) ddassl%netlib = scene%netlib
    end subroutine set_ddassl

    subroutine set_mexax(scene, mexax)
        type(scene_input_t), intent(in) :: scene
        type(mexax_t), intent(inout) :: mexax
        if (setting_given(scene, 'max_extrapolation')) &
            mexax%max_extrapolation = scene%max_extrapolation
        if (setting_given(scene, 'mexax_base')) mexax%base = merge(mexax_base_euler, &
            mexax_base_midpoint, scene%mexax_base == 'euler')
        if (setting_given(scene, 'mexax_control')) mexax%control = merge(mexax_control_hairer, &
            mexax_control_deuflhard, scene%mexax_control == 'hairer')
    end subroutine set_mexax
end module flexmbs_run_solver_factory
