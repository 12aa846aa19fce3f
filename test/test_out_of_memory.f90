!> Allocation failures come back as a status with a message (issue 16):
!> the library is asked for storage that cannot exist (more bytes than the
!> 128 TiB address space of x86-64 and arm64), or, where the size cannot be
!> made that large from small inputs, for storage beyond a lowered
!> RLIMIT_AS. Without stat= on the allocation each test would abort the run.
module test_out_of_memory
    use, intrinsic :: iso_c_binding, only: c_long
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_ok, status_solver_failure
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_identity, storage_none
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_band, only: band_solver_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_ida, only: ida_t
    use memory_limit, only: limit_address_space, restore_address_space
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_out_of_memory

    !> Order of the problems: a dense n x n matrix is 8e14 bytes, more than
    !> any address space, while the n-vectors (80 MB) are cheap.
    integer, parameter :: huge_order = 10**7

    !> y' = -y of order huge_order, with a dense M when asked.
    type, extends(dae_problem_t) :: huge_ode_t
        logical :: dense_mass = .false.
    contains
        procedure :: rhs => huge_rhs
        procedure :: mass_storage => huge_mass_storage
    end type huge_ode_t

contains

    function collect_out_of_memory() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('dense_solver', test_dense_solver), &
                 new_test('band_solver', test_band_solver), &
                 new_test('csc_build_under_rlimit', test_csc_build), &
                 new_test('box_mesh_under_rlimit', test_box_mesh), &
                 new_test('radau5_ddassl_ida', test_integrators)]
    end function collect_out_of_memory

    !> The failure as the tests expect it: a solver failure whose message
    !> names `what` and a size in TB.
    subroutine check_failure(error, status, what)
        type(error_t), allocatable, intent(inout) :: error
        type(status_t), intent(in) :: status
        character(len=*), intent(in) :: what
        call check(error, status%code == status_solver_failure, &
            'expected a solver failure, got: ' // status%text())
        if (allocated(error)) return
        call check(error, index(status%text(), 'out of memory: ' // what) == 1 .and. &
            index(status%text(), ' TB)') > 0, 'message: ' // status%text())
    end subroutine check_failure

    subroutine test_dense_solver(error)
        type(error_t), allocatable, intent(out) :: error
        type(dense_solver_t) :: solver
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        call operands(huge_order, mass, jac)
        call solver%init(mass, jac, status)
        call check_failure(error, status, 'dense solver matrices of order 10000000')
        if (allocated(error)) return
        ! nothing half-allocated is left behind: a new init succeeds
        call operands(3, mass, jac)
        call solver%init(mass, jac, status)
        call check(error, status%ok(), 'init after the failure: ' // status%text())
    end subroutine test_dense_solver

    subroutine test_band_solver(error)
        type(error_t), allocatable, intent(out) :: error
        type(band_solver_t) :: solver
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        call operands(huge_order, mass, jac)
        solver%lower = 10**6
        solver%upper = 10**6
        call solver%init(mass, jac, status)
        call check_failure(error, status, 'band solver storage')
        if (allocated(error)) return
        call operands(3, mass, jac)
        solver%lower = 1
        solver%upper = 1
        call solver%init(mass, jac, status)
        call check(error, status%ok(), 'init after the failure: ' // status%text())
    end subroutine test_band_solver

    !> 2e9 columns: the column counts alone are 32 GB, which an overcommitting
    !> machine might grant; under RLIMIT_AS (256 MB beyond what the tests use)
    !> they fail on any machine.
    !> M = I and a J still to come (a difference Jacobian), of order n.
    subroutine operands(n, mass, jac)
        integer, intent(in) :: n
        type(matrix_t), intent(out) :: mass, jac
        mass%storage = storage_identity
        mass%n = n
        jac%storage = storage_none
        jac%n = n
    end subroutine operands

    subroutine test_csc_build(error)
        type(error_t), allocatable, intent(out) :: error
        type(csc_matrix_t) :: a
        type(status_t) :: status
        integer :: none(0)
        if (.not. limit_address_space(256_c_long * 2**20)) then
            call check(error, .false., 'cannot lower RLIMIT_AS')
            return
        end if
        call a%build(1, 2 * 10**9, none, none, status)
        call restore_address_space()
        call check(error, status%code == status_solver_failure .and. &
            index(status%text(), 'out of memory: sparse pattern work arrays') == 1 .and. &
            index(status%text(), ' GB)') > 0, 'message: ' // status%text())
        call check(error, .not. a%is_built(), 'a failed build left a pattern')
    end subroutine test_csc_build

    !> 1000³ hex8 elements: 1e9 nodes, 24 GB of coordinates.
    subroutine test_box_mesh(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(status_t) :: status
        if (.not. limit_address_space(256_c_long * 2**20)) then
            call check(error, .false., 'cannot lower RLIMIT_AS')
            return
        end if
        call box_mesh(mesh, 8, [1000, 1000, 1000], [1.0_wp, 1.0_wp, 1.0_wp], status)
        call restore_address_space()
        call check(error, status%code == status_solver_failure .and. &
            index(status%text(), 'out of memory: box mesh node coordinates') == 1 .and. &
            index(status%text(), ' GB)') > 0, 'message: ' // status%text())
    end subroutine test_box_mesh

    !> Each integrator with its own dense matrix of order 1e7 (ida: M, whose
    !> dense J SUNDIALS would allocate later).
    subroutine test_integrators(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: radau5
        type(ddassl_t) :: ddassl
        type(ida_t) :: ida
        type(status_t) :: status
        call integrate_huge(radau5, .false., status)
        call check_failure(error, status, 'radau5 dense Jacobian')
        if (allocated(error)) return
        call integrate_huge(ddassl, .false., status)
        call check_failure(error, status, 'ddassl difference iteration matrix')
        if (allocated(error)) return
        call integrate_huge(ida, .true., status)
        call check_failure(error, status, 'ida dense mass matrix')
    end subroutine test_integrators

    !> The status of `solver` on huge_ode_t over [0, 1] (dense LU, a
    !> difference Jacobian).
    subroutine integrate_huge(solver, dense_mass, status)
        class(dae_solver_t), intent(inout) :: solver
        logical, intent(in) :: dense_mass
        type(status_t), intent(out) :: status
        type(huge_ode_t) :: problem
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        real(wp), allocatable :: y(:), yp(:)
        real(wp) :: t
        problem%n = huge_order
        problem%dense_mass = dense_mass
        allocate (y(huge_order), yp(huge_order), source=1.0_wp)
        yp = -y
        t = 0.0_wp
        options%linear_solver = 'dense'
        call solver%integrate(problem, t, y, 1.0_wp, options, stats, status, yp=yp)
    end subroutine integrate_huge

    subroutine huge_rhs(self, t, y, f, status)
        class(huge_ode_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f = -y
    end subroutine huge_rhs

    integer function huge_mass_storage(self)
        class(huge_ode_t), intent(in) :: self
        huge_mass_storage = merge(storage_dense, storage_identity, self%dense_mass)
    end function huge_mass_storage
end module test_out_of_memory
