!> Robertson's chemical kinetics [HW96, IV.1] as an index-1 DAE
!> M y' = F(t, y):
!>
!>   y1' = -k1 y1 + k3 y2 y3
!>   y2' =  k1 y1 - k3 y2 y3 - k2 y2²
!>   0   =  y1 + y2 + y3 - 1
!>
!> k1 = 0.04, k2 = 3e7, k3 = 1e4, M = diag(1, 1, 0), y0 = (1, 0, 0). The
!> algebraic equation is the conservation law that the ODE form
!> (y3' = k2 y2²) keeps, so d/dt (y1 + y2 + y3) = 0. It is the DDASSL anchor
!> of docs/solvers.md. The Jacobian is reported dense or as CSC (full 3x3
!> pattern), the mass matrix dense or as CSC.
module flexmbs_problems_robertson
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    implicit none
    private

    ! Rate constants of the reactions [HW96, IV.1].
    real(wp), parameter, public :: robertson_k1 = 0.04_wp
    real(wp), parameter, public :: robertson_k2 = 3.0e7_wp
    real(wp), parameter, public :: robertson_k3 = 1.0e4_wp

    !> Robertson's problem in the index-1 form M y' = F(t, y), n = 3.
    type, extends(dae_problem_t), public :: robertson_t
        logical :: sparse = .false.      !! report ∂F/∂y as CSC
        logical :: sparse_mass = .false. !! report M as CSC
    contains
        procedure :: rhs => robertson_rhs
        procedure :: jacobian_storage => robertson_jacobian_storage
        procedure :: jacobian_dense => robertson_jacobian_dense
        procedure :: jacobian_pattern => robertson_jacobian_pattern
        procedure :: jacobian_sparse => robertson_jacobian_sparse
        procedure :: mass_storage => robertson_mass_storage
        procedure :: mass_dense => robertson_mass_dense
        procedure :: mass_sparse => robertson_mass_sparse
        procedure :: differential_flags => robertson_differential_flags
        procedure :: consistent_initial => robertson_consistent_initial
    end type robertson_t

    public :: new_robertson, robertson_initial

contains

    !> Robertson's problem; `sparse` and `sparse_mass` choose CSC storage.
    function new_robertson(sparse, sparse_mass) result(problem)
        logical, intent(in), optional :: sparse      !! Jacobian as CSC (default dense)
        logical, intent(in), optional :: sparse_mass !! mass matrix as CSC (default dense)
        type(robertson_t) :: problem
        problem%n = 3
        if (present(sparse)) problem%sparse = sparse
        if (present(sparse_mass)) problem%sparse_mass = sparse_mass
    end function new_robertson

    !> The standard initial value y0 = (1, 0, 0) (consistent, y'0 = (-k1, k1, 0)).
    subroutine robertson_initial(problem, y0)
        class(robertson_t), intent(in) :: problem
        real(wp), intent(out) :: y0(:) !! size 3
        y0 = 0.0_wp
        y0(1) = 1.0_wp
    end subroutine robertson_initial

    subroutine robertson_rhs(self, t, y, f, status)
        class(robertson_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f(1) = -robertson_k1 * y(1) + robertson_k3 * y(2) * y(3)
        f(2) = robertson_k1 * y(1) - robertson_k3 * y(2) * y(3) - robertson_k2 * y(2)**2
        f(3) = y(1) + y(2) + y(3) - 1.0_wp
    end subroutine robertson_rhs

    integer function robertson_jacobian_storage(self)
        class(robertson_t), intent(in) :: self
        robertson_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function robertson_jacobian_storage

    subroutine robertson_jacobian_dense(self, t, y, jac, status)
        class(robertson_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        jac(1, :) = [-robertson_k1, robertson_k3 * y(3), robertson_k3 * y(2)]
        jac(2, :) = [robertson_k1, -robertson_k3 * y(3) - 2.0_wp * robertson_k2 * y(2), &
                     -robertson_k3 * y(2)]
        jac(3, :) = 1.0_wp
    end subroutine robertson_jacobian_dense

    !> Full 3x3 pattern; the slots are in column-major order.
    subroutine robertson_jacobian_pattern(self, pattern, status)
        class(robertson_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        call pattern%build(3, 3, [1, 2, 3, 1, 2, 3, 1, 2, 3], [1, 1, 1, 2, 2, 2, 3, 3, 3], &
                           status)
    end subroutine robertson_jacobian_pattern

    subroutine robertson_jacobian_sparse(self, t, y, values, status)
        class(robertson_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        ! column 1: ∂F/∂y1
        values(1) = -robertson_k1
        values(2) = robertson_k1
        values(3) = 1.0_wp
        ! column 2: ∂F/∂y2
        values(4) = robertson_k3 * y(3)
        values(5) = -robertson_k3 * y(3) - 2.0_wp * robertson_k2 * y(2)
        values(6) = 1.0_wp
        ! column 3: ∂F/∂y3
        values(7) = robertson_k3 * y(2)
        values(8) = -robertson_k3 * y(2)
        values(9) = 1.0_wp
    end subroutine robertson_jacobian_sparse

    integer function robertson_mass_storage(self)
        class(robertson_t), intent(in) :: self
        robertson_mass_storage = merge(storage_sparse, storage_dense, self%sparse_mass)
    end function robertson_mass_storage

    !> M = diag(1, 1, 0).
    subroutine robertson_mass_dense(self, m)
        class(robertson_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        m = 0.0_wp
        m(1, 1) = 1.0_wp
        m(2, 2) = 1.0_wp
    end subroutine robertson_mass_dense

    !> M = diag(1, 1, 0) as CSC with the two non-zero entries only.
    subroutine robertson_mass_sparse(self, m, status)
        class(robertson_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        call m%build(3, 3, [1, 2], [1, 2], status)
        if (status%ok()) m%values = 1.0_wp
    end subroutine robertson_mass_sparse

    !> y1, y2 differential; y3 algebraic.
    subroutine robertson_differential_flags(self, flags)
        class(robertson_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = [.true., .true., .false.]
    end subroutine robertson_differential_flags

    !> Keep y1, y2; set y3 from the conservation law and y' from the
    !> equations, y3' = -(y1' + y2') by differentiating the algebraic one.
    subroutine robertson_consistent_initial(self, t, y, yp, status)
        class(robertson_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        type(status_t), intent(inout) :: status
        real(wp) :: f(3)
        y(3) = 1.0_wp - y(1) - y(2)
        call self%rhs(t, y, f, status)
        yp(1:2) = f(1:2)
        yp(3) = -(f(1) + f(2))
    end subroutine robertson_consistent_initial
end module flexmbs_problems_robertson
