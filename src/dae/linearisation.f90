!> The linearisation of `M y' = F(t, y)` at one point: the Jacobian
!> J = ∂F/∂y and the mass matrix M as `matrix_t`, in the storage the problem
!> reports (dense or CSC on its pattern; M also identity). Their pencil
!> (J, M) is what an eigen-analysis of the DAE looks at (run/modes).
module flexmbs_dae_linearisation
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_non_finite
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t, problem_mass_matrix
    implicit none
    private

    public :: linearise

contains

    !> J = ∂F/∂y at (t, y) and the constant M of `problem`. J is analytic
    !> when the problem provides it; otherwise forward differences with the
    !> step sqrt(ε · max(1e-5, |y_j|)), ε = epsilon(1.0_wp), of RADAU5's difference Jacobian
    !> (docs/theory.md §5.7), dense.
    subroutine linearise(problem, t, y, jac, mass, status)
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t
        real(wp), intent(in) :: y(:)
        type(matrix_t), intent(out) :: jac      !! ∂F/∂y
        type(matrix_t), intent(out) :: mass     !! M
        type(status_t), intent(out) :: status
        integer :: n, stat
        n = problem%n
        jac%n = n
        jac%storage = problem%jacobian_storage()
        select case (jac%storage)
        case (storage_sparse)
            call problem%jacobian_pattern(jac%csc, status)
            if (status%ok()) call problem%jacobian_sparse(t, y, jac%csc%values, status)
            if (status%ok() .and. .not. all(ieee_is_finite(jac%csc%values))) call status%set( &
                status_solver_failure, 'the Jacobian dF/dy has non-finite entries', &
                reason_non_finite)
        case default
            allocate (jac%dense(n, n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'linearisation: dense Jacobian', int(n, i8) * n, 8)
                return
            end if
            if (jac%storage == storage_dense) then
                call problem%jacobian_dense(t, y, jac%dense, status)
            else
                call difference_jacobian(problem, t, y, jac%dense, status)
            end if
            jac%storage = storage_dense
            if (status%ok() .and. .not. all(ieee_is_finite(jac%dense))) call status%set( &
                status_solver_failure, 'the Jacobian dF/dy has non-finite entries', &
                reason_non_finite)
        end select
        if (.not. status%ok()) return
        call problem_mass_matrix(problem, mass, status, 'linearisation:')
    end subroutine linearise

    !> Forward differences of F, one column at a time.
    subroutine difference_jacobian(problem, t, y, jac, status)
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: f0(:), f1(:), yw(:)
        real(wp) :: delta
        integer :: j
        allocate (f0(size(y)), f1(size(y)))
        yw = y
        call problem%rhs(t, yw, f0, status)
        do j = 1, size(y)
            if (.not. status%ok()) return
            delta = sqrt(epsilon(1.0_wp) * max(1.0e-5_wp, abs(y(j))))
            yw(j) = y(j) + delta
            call problem%rhs(t, yw, f1, status)
            jac(:, j) = (f1 - f0) / delta
            yw(j) = y(j)
        end do
    end subroutine difference_jacobian
end module flexmbs_dae_linearisation
