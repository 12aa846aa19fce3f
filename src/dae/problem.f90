!> The linearly implicit DAE `M y' = F(t, y)` that every solver integrates.
!>
!> Users and formulations extend `dae_problem_t` and carry their own data.
!> Only `rhs` is required. The Jacobian ∂F/∂y is dense or CSC values on a
!> pattern reported once; when `jacobian_storage` says `storage_none`, the
!> solver differences F. M is identity unless `mass_storage` says otherwise.
module flexmbs_dae_problem
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_options, only: dae_options_t
    implicit none
    private

    public :: problem_mass_matrix

    !> A DAE M y' = F(t, y) with n unknowns: `rhs` is required, the Jacobian,
    !> the mass matrix and the index information have defaults (identity M,
    !> differenced J, index 1).
    type, abstract, public :: dae_problem_t
        integer :: n = 0 !! number of unknowns
    contains
        procedure(rhs_i), deferred :: rhs
        procedure :: jacobian_storage => default_jacobian_storage
        procedure :: jacobian_pattern => default_jacobian_pattern
        procedure :: jacobian_dense => default_jacobian_dense
        procedure :: jacobian_sparse => default_jacobian_sparse
        procedure :: mass_storage => default_mass_storage
        procedure :: mass_dense => default_mass_dense
        procedure :: mass_sparse => default_mass_sparse
        procedure :: index_classes => default_index_classes
        procedure :: differential_flags => default_differential_flags
        procedure :: multiplier_flags => default_multiplier_flags
        procedure :: has_projection => default_has_projection
        procedure :: project => default_project
        procedure :: consistent_initial => default_consistent_initial
        procedure :: admissible => default_admissible
        procedure :: iteration_solver => default_iteration_solver
    end type dae_problem_t

    abstract interface
        !> F(t, y). A failing evaluation (illegal y) sets status.
        subroutine rhs_i(self, t, y, f, status)
            import :: dae_problem_t, wp, status_t
            class(dae_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t
            real(wp), intent(in) :: y(:)
            real(wp), intent(out) :: f(:)
            type(status_t), intent(inout) :: status
        end subroutine rhs_i
    end interface

contains

    !> M of `problem` as a matrix_t in the storage the problem reports:
    !> identity, dense, or CSC values on the pattern it builds. `owner`
    !> heads an out-of-memory message ('radau5' → 'radau5 dense mass matrix').
    subroutine problem_mass_matrix(problem, mass, status, owner)
        class(dae_problem_t), intent(inout) :: problem
        type(matrix_t), intent(inout) :: mass
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: owner
        integer :: stat
        mass%n = problem%n
        mass%storage = problem%mass_storage()
        select case (mass%storage)
        case (storage_dense)
            allocate (mass%dense(problem%n, problem%n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, trim(owner // ' dense mass matrix'), &
                                   int(problem%n, i8) * problem%n, 8)
                return
            end if
            call problem%mass_dense(mass%dense)
        case (storage_sparse)
            call problem%mass_sparse(mass%csc, status)
        case default
            mass%storage = storage_identity
        end select
    end subroutine problem_mass_matrix

    !> storage_none (difference Jacobian), storage_dense or storage_sparse.
    integer function default_jacobian_storage(self)
        class(dae_problem_t), intent(in) :: self
        default_jacobian_storage = storage_none
    end function default_jacobian_storage

    !> The fixed CSC pattern of ∂F/∂y (called once, for storage_sparse).
    subroutine default_jacobian_pattern(self, pattern, status)
        class(dae_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        call status%set(status_bad_input, 'problem has no sparse Jacobian pattern')
    end subroutine default_jacobian_pattern

    !> Dense ∂F/∂y at (t, y): jac(i, j) = ∂F_i/∂y_j.
    subroutine default_jacobian_dense(self, t, y, jac, status)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        jac = 0.0_wp
        call status%set(status_bad_input, 'problem has no dense analytic Jacobian')
    end subroutine default_jacobian_dense

    !> Values of ∂F/∂y in the slots of the pattern.
    subroutine default_jacobian_sparse(self, t, y, values, status)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call status%set(status_bad_input, 'problem has no sparse analytic Jacobian')
    end subroutine default_jacobian_sparse

    !> storage_identity, storage_dense or storage_sparse.
    integer function default_mass_storage(self)
        class(dae_problem_t), intent(in) :: self
        default_mass_storage = storage_identity
    end function default_mass_storage

    !> Dense constant mass matrix.
    subroutine default_mass_dense(self, m)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        integer :: i
        m = 0.0_wp
        do i = 1, min(size(m, 1), size(m, 2))
            m(i, i) = 1.0_wp
        end do
    end subroutine default_mass_dense

    !> Constant mass matrix as CSC (pattern built here, values filled).
    subroutine default_mass_sparse(self, m, status)
        class(dae_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        integer :: i
        integer, allocatable :: idx(:)
        idx = [(i, i=1, self%n)]
        call m%build(self%n, self%n, idx, idx, status)
        if (status%ok()) m%values = 1.0_wp
    end subroutine default_mass_sparse

    !> Index class (1, 2, 3) of each component, ordered 1s, then 2s, then 3s.
    subroutine default_index_classes(self, classes)
        class(dae_problem_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        classes = 1
    end subroutine default_index_classes

    !> True for differential components (DDASSL INFO(11), IDASetId).
    subroutine default_differential_flags(self, flags)
        class(dae_problem_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .true.
    end subroutine default_differential_flags

    !> The Lagrange multipliers (and GGL's μ): they act on the differential
    !> components through h times themselves. Solvers that keep them out of
    !> the error test measure their Newton corrections as h^(k-1) δ (index
    !> k): unscaled, the round-off of δ (amplified like 1/h by the iteration
    !> matrix) against their tolerance stops tight runs at t0. Default: none.
    subroutine default_multiplier_flags(self, flags)
        class(dae_problem_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .false.
    end subroutine default_multiplier_flags

    !> Whether `project` does anything (solvers skip the hook otherwise).
    logical function default_has_projection(self)
        class(dae_problem_t), intent(in) :: self
        default_has_projection = .false.
    end function default_has_projection

    !> Acceptance test of a step's new state: a state that the model cannot
    !> hold (an inverted finite element: reason_det_f) fails with a reason,
    !> and the solver rejects the step. Default: every state is admissible.
    subroutine default_admissible(self, t, y, status)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(out) :: status
        call status%clear()
    end subroutine default_admissible

    !> A linear solver for the iteration matrices c M − ∂F/∂y that knows
    !> this problem's structure (the mechanical formulations' condensed
    !> Newton systems), chosen by `options` (linear_solver, sparse_ordering,
    !> newton_system); left unallocated when the problem offers none, and the
    !> solver then takes its own (flexmbs_linalg_factory). Solvers ask for it
    !> only with an analytic Jacobian. Default: none.
    subroutine default_iteration_solver(self, options, solver, status)
        class(dae_problem_t), intent(inout) :: self
        type(dae_options_t), intent(in) :: options
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(inout) :: status
    end subroutine default_iteration_solver

    !> Post-step hook: project y onto the constraint manifold.
    subroutine default_project(self, t, y, status)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:)
        type(status_t), intent(inout) :: status
    end subroutine default_project

    !> Complete (y, y') to consistent initial values.
    subroutine default_consistent_initial(self, t, y, yp, status)
        class(dae_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        type(status_t), intent(inout) :: status
        call status%set(status_bad_input, 'problem provides no consistent initial values')
    end subroutine default_consistent_initial
end module flexmbs_dae_problem
