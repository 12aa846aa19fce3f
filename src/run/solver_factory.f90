!> The solver factories of the catalogue (run/catalogue): the solver a
!> scene names. A solver's own settings keep the defaults of its type
!> unless the scene gives them (scene_input's `solver_settings`, which the
!> solver takes by name: dae_solver_t's apply_setting): those defaults are
!> kept in the solver types alone, as the classic faces use them too.
module flexmbs_run_solver_factory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_io_scene_input, only: scene_input_t
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
        logical :: applied
        integer :: k
        call new_solver(scene%solver_name, solver, status)
        if (.not. status%ok()) then
            status%message = scene%path // ': &solver: name: ' // status%message
            return
        end if
        if (.not. allocated(scene%solver_settings)) return
        do k = 1, size(scene%solver_settings)
            ! a setting of another solver is ignored, as the scene may keep it
            call solver%apply_setting(scene%solver_settings(k), applied)
        end do
    end subroutine build_solver
end module flexmbs_run_solver_factory
