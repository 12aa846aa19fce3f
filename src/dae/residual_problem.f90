!> The fully implicit DAE `G(t, y, y') = 0` that DDASSL (and IDA) integrate.
!>
!> The iteration matrix ∂G/∂y + c ∂G/∂y' is handed to the linear solvers,
!> which factor c*A − B, as the pair A = ∂G/∂y' and B = −∂G/∂y. Any
!> `dae_problem_t` becomes a residual problem through `dae_residual_t`:
!> G = M y' − F(t, y), so A = M (constant) and B = J = ∂F/∂y (docs/theory.md §1).
module flexmbs_dae_residual_problem
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, &
        storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_problem, only: dae_problem_t
    implicit none
    private

    !> A DAE G(t, y, y') = 0 with n unknowns: the residual and its partials
    !> A = ∂G/∂y', B = −∂G/∂y are required; index information has defaults.
    type, abstract, public :: residual_problem_t
        integer :: n = 0 !! number of unknowns
    contains
        procedure(residual_i), deferred :: residual
        procedure(setup_partials_i), deferred :: setup_partials
        procedure(partials_i), deferred :: partials
        procedure :: index_classes => residual_index_classes
        procedure :: differential_flags => residual_differential_flags
        procedure :: multiplier_flags => residual_multiplier_flags
        procedure :: has_iteration_matrix => residual_has_iteration_matrix
        procedure :: iteration_matrix => residual_iteration_matrix
        procedure :: admissible => residual_admissible
        procedure :: iteration_solver => residual_iteration_solver
    end type residual_problem_t

    abstract interface
        !> g = G(t, y, y'). A failing evaluation (illegal y) sets status.
        subroutine residual_i(self, t, y, yp, g, status)
            import :: residual_problem_t, wp, status_t
            class(residual_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, y(:), yp(:)
            real(wp), intent(out) :: g(:)
            type(status_t), intent(inout) :: status
        end subroutine residual_i
        !> Fix the storage of A = ∂G/∂y' and B = −∂G/∂y once. With
        !> `differenced` (or when the problem has no analytic partials) B gets
        !> storage_none: the solver then differences G itself.
        subroutine setup_partials_i(self, differenced, a, b, status)
            import :: residual_problem_t, matrix_t, status_t
            class(residual_problem_t), intent(inout) :: self
            logical, intent(in) :: differenced
            type(matrix_t), intent(inout) :: a, b
            type(status_t), intent(inout) :: status
        end subroutine setup_partials_i
        !> Values of A = ∂G/∂y' and B = −∂G/∂y at (t, y, y').
        subroutine partials_i(self, t, y, yp, a, b, status)
            import :: residual_problem_t, matrix_t, wp, status_t
            class(residual_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, y(:), yp(:)
            type(matrix_t), intent(inout) :: a, b
            type(status_t), intent(inout) :: status
        end subroutine partials_i
    end interface

    !> G = M y' − F(t, y) for a `dae_problem_t` it points to.
    type, extends(residual_problem_t), public :: dae_residual_t
        class(dae_problem_t), pointer :: problem => null()
        type(matrix_t) :: mass
        real(wp), allocatable :: work(:) !! M y'
    contains
        procedure :: residual => wrapper_residual
        procedure :: setup_partials => wrapper_setup
        procedure :: partials => wrapper_partials
        procedure :: index_classes => wrapper_index_classes
        procedure :: differential_flags => wrapper_differential_flags
        procedure :: multiplier_flags => wrapper_multiplier_flags
        procedure :: admissible => wrapper_admissible
        procedure :: iteration_solver => wrapper_iteration_solver
    end type dae_residual_t

contains

    !> Acceptance test of a corrected state (dae_problem_t%admissible);
    !> default: every state.
    subroutine residual_admissible(self, t, y, status)
        class(residual_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(out) :: status
        call status%clear()
    end subroutine residual_admissible

    !> A linear solver for c A − B that knows the problem's structure
    !> (dae_problem_t%iteration_solver); default: none (left unallocated).
    subroutine residual_iteration_solver(self, options, solver, status)
        class(residual_problem_t), intent(inout) :: self
        type(dae_options_t), intent(in) :: options
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(inout) :: status
    end subroutine residual_iteration_solver

    !> The wrapped problem's solver: A = M and B = J are the problem's own.
    subroutine wrapper_iteration_solver(self, options, solver, status)
        class(dae_residual_t), intent(inout) :: self
        type(dae_options_t), intent(in) :: options
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(inout) :: status
        call self%problem%iteration_solver(options, solver, status)
    end subroutine wrapper_iteration_solver

    !> By default every component of index 1.
    subroutine residual_index_classes(self, classes)
        class(residual_problem_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        classes = 1
    end subroutine residual_index_classes

    !> By default, no. A problem that computes PD = ∂G/∂y + cj ∂G/∂y' itself
    !> (the classic DDASSL JAC) says yes and gives `setup_partials` B in
    !> dense storage; the solver then factors PD as it stands.
    logical function residual_has_iteration_matrix(self)
        class(residual_problem_t), intent(in) :: self
        residual_has_iteration_matrix = .false.
    end function residual_has_iteration_matrix

    !> PD = ∂G/∂y + cj ∂G/∂y' at (t, y, y'), dense n x n.
    subroutine residual_iteration_matrix(self, t, y, yp, cj, pd, status)
        class(residual_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:), cj
        real(wp), intent(out) :: pd(:, :)
        type(status_t), intent(inout) :: status
        pd = 0.0_wp
        call status%set(status_bad_input, 'residual problem: no iteration matrix')
    end subroutine residual_iteration_matrix

    !> By default every component differential.
    subroutine residual_differential_flags(self, flags)
        class(residual_problem_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .true.
    end subroutine residual_differential_flags

    !> By default no multipliers (see dae_problem_t%multiplier_flags).
    subroutine residual_multiplier_flags(self, flags)
        class(residual_problem_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .false.
    end subroutine residual_multiplier_flags

    subroutine wrapper_residual(self, t, y, yp, g, status)
        class(dae_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        call self%problem%rhs(t, y, g, status)
        if (self%mass%storage == storage_identity) then
            g = yp - g
        else
            call self%mass%matvec(yp, self%work)
            g = self%work - g
        end if
    end subroutine wrapper_residual

    !> A = M from the problem; B = J in the problem's storage (or none).
    subroutine wrapper_setup(self, differenced, a, b, status)
        class(dae_residual_t), intent(inout) :: self
        logical, intent(in) :: differenced
        type(matrix_t), intent(inout) :: a, b
        type(status_t), intent(inout) :: status
        integer :: n, stat
        if (.not. associated(self%problem)) then
            call status%set(status_bad_input, 'dae_residual_t: no problem attached')
            return
        end if
        n = self%problem%n
        self%n = n
        if (allocated(self%work)) deallocate (self%work)
        allocate (self%work(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'residual work vector', int(n, i8), 8)
            return
        end if
        self%mass%n = n
        self%mass%storage = self%problem%mass_storage()
        select case (self%mass%storage)
        case (storage_dense)
            if (allocated(self%mass%dense)) deallocate (self%mass%dense)
            allocate (self%mass%dense(n, n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'dense mass matrix', int(n, i8) * n, 8)
                return
            end if
            call self%problem%mass_dense(self%mass%dense)
        case (storage_sparse)
            call self%problem%mass_sparse(self%mass%csc, status)
            if (.not. status%ok()) return
        case default
            self%mass%storage = storage_identity
        end select
        a = self%mass
        b%n = n
        b%storage = self%problem%jacobian_storage()
        if (differenced) b%storage = storage_none
        select case (b%storage)
        case (storage_sparse)
            call self%problem%jacobian_pattern(b%csc, status)
        case (storage_dense)
            if (allocated(b%dense)) deallocate (b%dense)
            allocate (b%dense(n, n), stat=stat)
            if (stat /= 0) call out_of_memory(status, 'dense Jacobian', int(n, i8) * n, 8)
        case default
            b%storage = storage_none
        end select
    end subroutine wrapper_setup

    !> A = M is constant; B = J(t, y).
    subroutine wrapper_partials(self, t, y, yp, a, b, status)
        class(dae_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:)
        type(matrix_t), intent(inout) :: a, b
        type(status_t), intent(inout) :: status
        select case (b%storage)
        case (storage_sparse)
            call self%problem%jacobian_sparse(t, y, b%csc%values, status)
        case (storage_dense)
            call self%problem%jacobian_dense(t, y, b%dense, status)
        case default
            call status%set(status_bad_input, 'dae_residual_t: no analytic Jacobian')
        end select
    end subroutine wrapper_partials

    subroutine wrapper_index_classes(self, classes)
        class(dae_residual_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        call self%problem%index_classes(classes)
    end subroutine wrapper_index_classes

    subroutine wrapper_differential_flags(self, flags)
        class(dae_residual_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        call self%problem%differential_flags(flags)
    end subroutine wrapper_differential_flags

    subroutine wrapper_multiplier_flags(self, flags)
        class(dae_residual_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        call self%problem%multiplier_flags(flags)
    end subroutine wrapper_multiplier_flags

    subroutine wrapper_admissible(self, t, y, status)
        class(dae_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(out) :: status
        call self%problem%admissible(t, y, status)
    end subroutine wrapper_admissible
end module flexmbs_dae_residual_problem
