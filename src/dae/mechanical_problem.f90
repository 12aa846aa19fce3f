!> Constrained mechanical systems in the form MEXAX and the formulations use:
!>
!>   q' = T(t,q) v,   M(t,q) v' = f(t,q,v) - G(t,q)ᵀ λ,
!>   0 = G(t,q) v + g_I(t,q)   (velocity constraint, g_I = ∂g/∂t),
!>   0 = g(t,q)                (position invariant), with G = g_q T.
!>
!> Sign: our λ is the negative of the paper's (+Cqᵀλ on the force side).
!> Dense matrices here; CSC variants join with the multibody assembly.
module flexmbs_dae_mechanical_problem
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
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
end module flexmbs_dae_mechanical_problem
