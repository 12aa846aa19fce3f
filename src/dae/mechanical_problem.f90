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
!>
!> The formulations (src/mbs/formulation.f90) need the derivatives of these
!> terms with respect to q and v for their Jacobians. A problem may override
!> the `*_derivative(s)` bindings with analytic ones; the defaults difference
!> the base bindings by forward differences (step sqrt(eps) max(1, |x_j|),
!> one routine for all, which stops at the first evaluation that fails),
!> one evaluation per column, so they are accurate to about sqrt(eps).
!>
!> Large models (flexible bodies) also provide those derivatives sparse
!> (`has_sparse_derivatives` true): `derivative_patterns` reports the fixed
!> CSC patterns of every block once (mechanical_patterns_t), and the
!> `*_sparse` bindings refill their values in place. The formulations then
!> assemble a sparse ∂F/∂y without any n x n array.
module flexmbs_dae_mechanical_problem
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    !> The fixed CSC patterns of a mechanical problem's blocks (values unused).
    type, public :: mechanical_patterns_t
        type(csc_matrix_t) :: mass           !! M, nv x nv
        type(csc_matrix_t) :: constraint_v   !! G and ∂γ/∂v, nc x nv
        type(csc_matrix_t) :: constraint_q   !! g_q, ∂(G w)/∂q, ∂g_I/∂q, ∂γ/∂q, nc x nq
        type(csc_matrix_t) :: reaction_q     !! ∂(Gᵀλ)/∂q, nv x nq
        type(csc_matrix_t) :: kinematics     !! T, nq x nv
        type(csc_matrix_t) :: kinematics_q   !! ∂(T w)/∂q, nq x nq
        type(csc_matrix_t) :: force_q        !! ∂f/∂q and ∂(M w)/∂q, nv x nq
        type(csc_matrix_t) :: force_v        !! ∂f/∂v, nv x nv
    end type mechanical_patterns_t

    !> A constrained mechanical system (the module's equations): kinematics T,
    !> mass M, forces f, constraints g and G as deferred bindings; derivatives
    !> and sparse forms with defaults that a problem may override.
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
        procedure :: normalize => default_normalize
        procedure :: total_energy => default_total_energy
        procedure :: admissible => default_admissible
        procedure :: kinematics_derivative => default_kinematics_derivative
        procedure :: mass_derivative => default_mass_derivative
        procedure :: force_derivatives => default_force_derivatives
        procedure :: constraint_position_jacobian => default_constraint_position_jacobian
        procedure :: constraint_jacobian_derivatives => default_constraint_jacobian_derivatives
        procedure :: constraint_time_derivative_jacobian => &
            default_constraint_time_derivative_jacobian
        procedure :: constraint_curvature_derivatives => default_constraint_curvature_derivatives
        procedure :: has_sparse_derivatives => default_has_sparse_derivatives
        procedure :: derivative_patterns => default_derivative_patterns
        procedure :: kinematics_sparse => default_kinematics_sparse
        procedure :: kinematics_derivative_sparse => default_kinematics_derivative_sparse
        procedure :: mass_derivative_sparse => default_mass_derivative_sparse
        procedure :: force_derivatives_sparse => default_force_derivatives_sparse
        procedure :: constraint_position_jacobian_sparse => &
            default_constraint_position_jacobian_sparse
        procedure :: constraint_jacobian_derivatives_sparse => &
            default_constraint_jacobian_derivatives_sparse
        procedure :: constraint_time_derivative_jacobian_sparse => &
            default_constraint_time_derivative_jacobian_sparse
        procedure :: constraint_curvature_derivatives_sparse => &
            default_constraint_curvature_derivatives_sparse
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

    public :: difference_step

    ! The quantities forward_differences differences (evaluate).
    integer, parameter :: of_kinematics = 1, of_mass = 2, of_forces = 3, of_constraint = 4, &
        of_jacobian = 5, of_time = 6, of_curvature = 7

contains

    !> Forward-difference step for a variable of value x.
    pure real(wp) function difference_step(x) result(delta)
        real(wp), intent(in) :: x
        delta = sqrt(epsilon(1.0_wp)) * max(1.0_wp, abs(x))
    end function difference_step

    !> Restore invariants of the kinematics that are not constraints (a
    !> quaternion's unit length: T w is tangent to the unit sphere, so the
    !> length is an invariant of q' = T w that the integration lets drift).
    !> Called by the formulations' projection; default: nothing to restore.
    !> Kinetic plus potential energy at (q, v) [J], the work of constant
    !> applied forces counted from positions q_ref; NaN when the model
    !> does not define it.
    real(wp) function default_total_energy(self, q, v, q_ref) result(e)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(in), optional :: q_ref(:)
        e = ieee_value(1.0_wp, ieee_quiet_nan)
    end function default_total_energy

    subroutine default_normalize(self, q)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(inout) :: q(:)
    end subroutine default_normalize

    !> Whether positions q are a state the model can hold (see
    !> dae_problem_t%admissible); default: always.
    subroutine default_admissible(self, q, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        type(status_t), intent(out) :: status
        call status%clear()
    end subroutine default_admissible

    !> Forward differences of y = F(q, v) along q (or, with `along_v`,
    !> along v) into the columns of jac, F the quantity `what` (of_*) and
    !> `base` = F at (q, v): step difference_step per column, one evaluation
    !> each. An evaluation that fails ends the differences with its status
    !> (nothing of a failed state enters jac). A selector rather than a
    !> procedure argument: an internal procedure passed on would need an
    !> executable stack for its trampoline.
    subroutine forward_differences(self, what, t, q, v, w, lambda, along_v, base, jac, status)
        class(mechanical_problem_t), intent(inout) :: self
        integer, intent(in) :: what
        real(wp), intent(in) :: t, q(:), v(:), w(:), lambda(:)
        logical, intent(in) :: along_v
        real(wp), intent(in) :: base(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: qp(size(q)), vp(size(v)), pert(size(base)), delta
        integer :: j
        if (.not. status%ok()) return
        qp = q
        vp = v
        do j = 1, size(jac, 2)
            if (along_v) then
                delta = difference_step(v(j))
                vp(j) = v(j) + delta
            else
                delta = difference_step(q(j))
                qp(j) = q(j) + delta
            end if
            call evaluate(self, what, t, qp, vp, w, lambda, pert, status)
            if (.not. status%ok()) return
            jac(:, j) = (pert - base) / delta
            if (along_v) then
                vp(j) = v(j)
            else
                qp(j) = q(j)
            end if
        end do
    end subroutine forward_differences

    !> The quantity `what` (of_*) at (t, q, v): T w, M w, f, g, (G w, Gᵀ λ),
    !> g_I or γ.
    subroutine evaluate(self, what, t, q, v, w, lambda, y, status)
        class(mechanical_problem_t), intent(inout) :: self
        integer, intent(in) :: what
        real(wp), intent(in) :: t, q(:), v(:), w(:), lambda(:)
        real(wp), intent(out) :: y(:)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: m(:, :)
        select case (what)
        case (of_kinematics)
            call self%kinematics(t, q, w, y, status)
        case (of_mass)
            allocate (m(self%nv, self%nv))
            call self%mass(t, q, m, status)
            y = matmul(m, w)
        case (of_forces)
            call self%forces(t, q, v, y, status)
        case (of_constraint)
            call self%constraint(t, q, y, status)
        case (of_jacobian)
            allocate (m(self%nc, self%nv))
            call self%constraint_jacobian(t, q, m, status)
            y(1:self%nc) = matmul(m, w)
            y(self%nc + 1:) = matmul(lambda, m)
        case (of_time)
            call self%constraint_time_derivative(t, q, y, status)
        case (of_curvature)
            call self%constraint_curvature(t, q, v, y, status)
        end select
    end subroutine evaluate

    !> ∂(T(t,q) w)/∂q, nq x nq (default: forward differences).
    subroutine default_kinematics_derivative(self, t, q, w, dq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nq), none(0)
        call self%kinematics(t, q, w, base, status)
        call forward_differences(self, of_kinematics, t, q, none, w, none, .false., base, dq, &
                                 status)
    end subroutine default_kinematics_derivative

    !> ∂(M(t,q) w)/∂q, nv x nq (default: forward differences).
    subroutine default_mass_derivative(self, t, q, w, dq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:) !! the vector M acts on (an acceleration)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nv), none(0)
        call evaluate(self, of_mass, t, q, none, w, none, base, status)
        call forward_differences(self, of_mass, t, q, none, w, none, .false., base, dq, status)
    end subroutine default_mass_derivative

    !> ∂f/∂q (nv x nq) and ∂f/∂v (nv x nv) (default: forward differences).
    subroutine default_force_derivatives(self, t, q, v, fq, fv, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nv), none(0)
        call self%forces(t, q, v, base, status)
        call forward_differences(self, of_forces, t, q, v, none, none, .false., base, fq, status)
        call forward_differences(self, of_forces, t, q, v, none, none, .true., base, fv, status)
    end subroutine default_force_derivatives

    !> g_q, nc x nq (default: forward differences of g).
    subroutine default_constraint_position_jacobian(self, t, q, gq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nc), none(0)
        call self%constraint(t, q, base, status)
        call forward_differences(self, of_constraint, t, q, none, none, none, .false., base, gq, &
                                 status)
    end subroutine default_constraint_position_jacobian

    !> ∂(G(t,q) w)/∂q (nc x nq) and ∂(G(t,q)ᵀ λ)/∂q (nv x nq) (default:
    !> forward differences of G; both from one evaluation of G per column).
    subroutine default_constraint_jacobian_derivatives(self, t, q, w, lambda, gwq, gtlq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:, :), gtlq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nc + self%nv), none(0)
        real(wp), allocatable :: both(:, :)   ! on the heap: (nc + nv) x nq
        allocate (both(self%nc + self%nv, self%nq))
        call evaluate(self, of_jacobian, t, q, none, w, lambda, base, status)
        call forward_differences(self, of_jacobian, t, q, none, w, lambda, .false., base, both, &
                                 status)
        if (.not. status%ok()) return
        gwq = both(1:self%nc, :)
        gtlq = both(self%nc + 1:, :)
    end subroutine default_constraint_jacobian_derivatives

    !> ∂g_I/∂q, nc x nq (default: forward differences of g_I).
    subroutine default_constraint_time_derivative_jacobian(self, t, q, dq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nc), none(0)
        call self%constraint_time_derivative(t, q, base, status)
        call forward_differences(self, of_time, t, q, none, none, none, .false., base, dq, status)
    end subroutine default_constraint_time_derivative_jacobian

    !> ∂γ/∂q (nc x nq) and ∂γ/∂v (nc x nv) (default: forward differences).
    subroutine default_constraint_curvature_derivatives(self, t, q, v, gq, gv, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:, :), gv(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: base(self%nc), none(0)
        call self%constraint_curvature(t, q, v, base, status)
        call forward_differences(self, of_curvature, t, q, v, none, none, .false., base, gq, &
                                 status)
        call forward_differences(self, of_curvature, t, q, v, none, none, .true., base, gv, &
                                 status)
    end subroutine default_constraint_curvature_derivatives

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
    ! ------------------------------------------------ sparse derivatives

    !> True when `derivative_patterns` and every `*_sparse` binding below
    !> are provided (and has_sparse, for M and G).
    logical function default_has_sparse_derivatives(self)
        class(mechanical_problem_t), intent(in) :: self
        default_has_sparse_derivatives = .false.
    end function default_has_sparse_derivatives

    !> The patterns of every block (called once per formulation).
    subroutine default_derivative_patterns(self, patterns, status)
        class(mechanical_problem_t), intent(inout) :: self
        type(mechanical_patterns_t), intent(inout) :: patterns
        type(status_t), intent(inout) :: status
        call not_sparse(status, 'derivative patterns')
    end subroutine default_derivative_patterns

    !> Values of T(t, q) (pattern `kinematics`).
    subroutine default_kinematics_sparse(self, t, q, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call not_sparse(status, 'T')
    end subroutine default_kinematics_sparse

    !> Values of ∂(T w)/∂q (pattern `kinematics_q`).
    subroutine default_kinematics_derivative_sparse(self, t, q, w, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call not_sparse(status, 'd(T w)/dq')
    end subroutine default_kinematics_derivative_sparse

    !> Values of ∂(M w)/∂q (pattern `force_q`).
    subroutine default_mass_derivative_sparse(self, t, q, w, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call not_sparse(status, 'd(M w)/dq')
    end subroutine default_mass_derivative_sparse

    !> Values of ∂f/∂q (pattern `force_q`) and ∂f/∂v (pattern `force_v`).
    subroutine default_force_derivatives_sparse(self, t, q, v, fq, fv, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:), fv(:)
        type(status_t), intent(inout) :: status
        fq = 0.0_wp
        fv = 0.0_wp
        call not_sparse(status, 'df/dq, df/dv')
    end subroutine default_force_derivatives_sparse

    !> Values of g_q (pattern `constraint_q`).
    subroutine default_constraint_position_jacobian_sparse(self, t, q, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call not_sparse(status, 'g_q')
    end subroutine default_constraint_position_jacobian_sparse

    !> Values of ∂(G w)/∂q (pattern `constraint_q`) and ∂(Gᵀλ)/∂q (pattern
    !> `reaction_q`).
    subroutine default_constraint_jacobian_derivatives_sparse(self, t, q, w, lambda, gwq, &
                                                              gtlq, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:), gtlq(:)
        type(status_t), intent(inout) :: status
        gwq = 0.0_wp
        gtlq = 0.0_wp
        call not_sparse(status, 'd(G w)/dq, d(G^T lambda)/dq')
    end subroutine default_constraint_jacobian_derivatives_sparse

    !> Values of ∂g_I/∂q (pattern `constraint_q`).
    subroutine default_constraint_time_derivative_jacobian_sparse(self, t, q, values, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
        call not_sparse(status, 'dg_I/dq')
    end subroutine default_constraint_time_derivative_jacobian_sparse

    !> Values of ∂γ/∂q (pattern `constraint_q`) and ∂γ/∂v (pattern
    !> `constraint_v`).
    subroutine default_constraint_curvature_derivatives_sparse(self, t, q, v, gq, gv, status)
        class(mechanical_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:), gv(:)
        type(status_t), intent(inout) :: status
        gq = 0.0_wp
        gv = 0.0_wp
        call not_sparse(status, 'dgamma/dq, dgamma/dv')
    end subroutine default_constraint_curvature_derivatives_sparse

    subroutine not_sparse(status, what)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: what
        call status%set(status_bad_input, 'mechanical problem provides no sparse ' // what)
    end subroutine not_sparse
end module flexmbs_dae_mechanical_problem
