!> Constrained mechanical systems in the form MEXAX and the formulations use:
!>
!>   q' = T(t,q) v,   M(t,q) v' = f(t,q,v) - G(t,q)ᵀ λ,
!>   0 = G(t,q) v + g_I(t,q)   (velocity constraint, g_I = ∂g/∂t),
!>   0 = g(t,q)                (position invariant), with G = g_q T.
!>
!> Sign: our λ is the negative of the paper's (+Cqᵀλ on the force side).
!> M and G are always available dense. A problem may in addition provide
!> them as values in fixed CSC patterns (`has_sparse` true, the patterns
!> reported once by `mass_pattern` and `constraint_jacobian_pattern`, the
!> values refilled by `mass_sparse` and `constraint_jacobian_sparse`), which
!> lets MEXAX factor the augmented matrix [M Gᵀ; G 0] with KLU. The
!> defaults say "not provided", as `dae_problem_t`'s sparse Jacobian does.
module flexmbs_dae_mechanical_problem
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    type, abstract, public :: mechanical_problem_t
        integer :: nq = 0 !! positions
        integer :: nv = 0 !! velocities
        integer :: nc = 0 !! constraints (= multipliers)
    contains
        procedure(kinematics_i), deferred :: kinematics
        procedure(mass_i), deferred :: mass
        procedure(forces_i), deferred :: forces
        procedure(constraint_i), deferred :: constraint
        procedure(constraint_jacobian_i), deferred :: constraint_jacobian
        procedure :: constraint_time_derivative => default_constraint_time_derivative
        procedure :: constraint_curvature => default_constraint_curvature
        procedure :: has_sparse => default_has_sparse
        procedure :: mass_pattern => default_mass_pattern
        procedure :: mass_sparse => default_mass_sparse
        procedure :: constraint_jacobian_pattern => default_constraint_jacobian_pattern
        procedure :: constraint_jacobian_sparse => default_constraint_jacobian_sparse
    end type mechanical_problem_t

    abstract interface
        !> qdot = T(t, q) w (w a velocity-space vector).
        subroutine kinematics_i(self, t, q, w, qdot, status)
            import :: mechanical_problem_t, wp, status_t
            class(mechanical_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: qdot(:)
            type(status_t), intent(inout) :: status
        end subroutine kinematics_i
        !> M(t, q), nv x nv.
        subroutine mass_i(self, t, q, m, status)
            import :: mechanical_problem_t, wp, status_t
            class(mechanical_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: m(:, :)
            type(status_t), intent(inout) :: status
        end subroutine mass_i
        !> Applied and internal forces f(t, q, v).
        subroutine forces_i(self, t, q, v, f, status)
            import :: mechanical_problem_t, wp, status_t
            class(mechanical_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: f(:)
            type(status_t), intent(inout) :: status
        end subroutine forces_i
        !> Position constraints g(t, q).
        subroutine constraint_i(self, t, q, g, status)
            import :: mechanical_problem_t, wp, status_t
            class(mechanical_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: g(:)
            type(status_t), intent(inout) :: status
        end subroutine constraint_i
        !> G(t, q) = g_q T, nc x nv.
        subroutine constraint_jacobian_i(self, t, q, gmat, status)
            import :: mechanical_problem_t, wp, status_t
            class(mechanical_problem_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: gmat(:, :)
            type(status_t), intent(inout) :: status
        end subroutine constraint_jacobian_i
    end interface

contains

    !> g_I = ∂g/∂t; zero for scleronomic constraints.
    subroutine default_constraint_time_derivative(self, t, q, gt, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gt(:)
        type(status_t), intent(inout) :: status
        gt = 0.0_wp
    end subroutine default_constraint_time_derivative

    !> γ = (G v)_q T v + 2 G_t v + g_tt, the index-1 (acceleration) terms.
    subroutine default_constraint_curvature(self, t, q, v, gamma, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
        gamma = 0.0_wp
        call status%set(status_bad_input, 'mechanical problem provides no constraint curvature')
    end subroutine default_constraint_curvature

    !> True when the four sparse bindings below are provided.
    logical function default_has_sparse(self)
        class(mechanical_problem_t), intent(in) :: self
        default_has_sparse = .false.
    end function default_has_sparse

    !> The fixed CSC pattern of M(t, q), nv x nv (called once per integration).
    subroutine default_mass_pattern(self, pattern, status)
        class(mechanical_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern !! built here; its values are not used
        type(status_t), intent(inout) :: status
        call status%set(status_bad_input, 'mechanical problem has no sparse mass pattern')
    end subroutine default_mass_pattern

    !> Values of M(t, q) in the slots of `mass_pattern`.
    subroutine default_mass_sparse(self, t, q, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:) !! one per pattern slot
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call status%set(status_bad_input, 'mechanical problem has no sparse mass matrix')
    end subroutine default_mass_sparse

    !> The fixed CSC pattern of G(t, q) = g_q T, nc x nv (called once).
    subroutine default_constraint_jacobian_pattern(self, pattern, status)
        class(mechanical_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern !! built here; its values are not used
        type(status_t), intent(inout) :: status
        call status%set(status_bad_input, &
            'mechanical problem has no sparse constraint Jacobian pattern')
    end subroutine default_constraint_jacobian_pattern

    !> Values of G(t, q) in the slots of `constraint_jacobian_pattern`.
    subroutine default_constraint_jacobian_sparse(self, t, q, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:) !! one per pattern slot
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call status%set(status_bad_input, 'mechanical problem has no sparse constraint Jacobian')
    end subroutine default_constraint_jacobian_sparse
end module flexmbs_dae_mechanical_problem
