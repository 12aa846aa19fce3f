!> Choice of the linear solver by name.
module flexmbs_linalg_factory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_dense, only: dense_solver_t
    implicit none
    private
    public :: new_linear_solver
contains
    !> 'auto' | 'dense' | 'klu'.
    subroutine new_linear_solver(name, n, jac_storage, solver, status)
        character(len=*), intent(in) :: name
        integer, intent(in) :: n, jac_storage
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        select case (trim(name))
        case ('auto', 'dense')
            allocate (dense_solver_t :: solver)
        case default
            call status%set(status_bad_input, "linear_solver = '" // trim(name) // &
                "': must be 'auto', 'dense' or 'klu'")
        end select
    end subroutine new_linear_solver
end module flexmbs_linalg_factory
