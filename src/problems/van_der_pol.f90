!> Van der Pol's equation in the scaled stiff form of [HW96, IV.1]:
!>   y1' = y2,  y2' = ((1 - y1²) y2 - y1) / ε.
!> With ε = 1e-6, y0 = (2, -0.66), x in [0, 2] it is the RADAU5 anchor of
!> docs/solvers.md.
module flexmbs_problems_van_der_pol
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    implicit none
    private

    !> Van der Pol's oscillator with stiffness parameter ε (eps), dense or
    !> (sparse = .true.) CSC Jacobian.
    type, extends(dae_problem_t), public :: van_der_pol_t
        real(wp) :: eps = 1.0e-6_wp
        !> Report the Jacobian as CSC (to exercise the sparse path).
        logical :: sparse = .false.
    contains
        procedure :: rhs => vdp_rhs
        procedure :: jacobian_storage => vdp_jacobian_storage
        procedure :: jacobian_dense => vdp_jacobian_dense
        procedure :: jacobian_pattern => vdp_jacobian_pattern
        procedure :: jacobian_sparse => vdp_jacobian_sparse
    end type van_der_pol_t

    public :: new_van_der_pol

contains

    !> The oscillator with parameter eps and n = 2; `sparse` (default false)
    !> reports its Jacobian in CSC.
    function new_van_der_pol(eps, sparse) result(problem)
        real(wp), intent(in) :: eps
        logical, intent(in), optional :: sparse
        type(van_der_pol_t) :: problem
        problem%n = 2
        problem%eps = eps
        if (present(sparse)) problem%sparse = sparse
    end function new_van_der_pol

    subroutine vdp_rhs(self, t, y, f, status)
        class(van_der_pol_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f(1) = y(2)
        f(2) = ((1.0_wp - y(1)**2) * y(2) - y(1)) / self%eps
    end subroutine vdp_rhs

    integer function vdp_jacobian_storage(self)
        class(van_der_pol_t), intent(in) :: self
        vdp_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function vdp_jacobian_storage

    subroutine vdp_jacobian_dense(self, t, y, jac, status)
        class(van_der_pol_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        jac(1, 1) = 0.0_wp
        jac(1, 2) = 1.0_wp
        jac(2, 1) = (-2.0_wp * y(1) * y(2) - 1.0_wp) / self%eps
        jac(2, 2) = (1.0_wp - y(1)**2) / self%eps
    end subroutine vdp_jacobian_dense

    subroutine vdp_jacobian_pattern(self, pattern, status)
        class(van_der_pol_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        call pattern%build(2, 2, [1, 2, 1, 2], [1, 1, 2, 2], status)
    end subroutine vdp_jacobian_pattern

    subroutine vdp_jacobian_sparse(self, t, y, values, status)
        class(van_der_pol_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        ! column-major slots: (1,1) (2,1) (1,2) (2,2)
        values(1) = 0.0_wp
        values(2) = (-2.0_wp * y(1) * y(2) - 1.0_wp) / self%eps
        values(3) = 1.0_wp
        values(4) = (1.0_wp - y(1)**2) / self%eps
    end subroutine vdp_jacobian_sparse
end module flexmbs_problems_van_der_pol
