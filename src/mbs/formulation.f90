!> The formulations of docs/theory.md §3: any `mechanical_problem_t` turned
!> into the linearly implicit DAE `M y' = F(t, y)` of `dae_problem_t`.
!>
!> Mechanical system (docs/theory.md §2.1, our sign of λ): q' = T(q) v,
!> M(q) v' = f(t,q,v) - Gᵀλ, constraints g(t,q) = 0, G = g_q T,
!> velocity constraint G v + g_I = 0, acceleration constraint G a + γ = 0.
!>
!> Layouts (unknowns y, DAE mass matrix):
!>   with accelerations:  y = (q, v, a, λ[, μ]),  diag(I, I, 0, 0[, 0]); any M(q)
!>     q' = T v,  v' = a,  0 = f - M a - Gᵀλ,  constraint rows below;
!>   constant mass:       y = (q, v, λ[, μ]),     diag(I, M, 0[, 0]); M constant
!>     q' = T v,  M v' = f - Gᵀλ,  constraint rows below.
!> Constraint rows and index classes (RADAU5 NIND1/2/3):
!>   index 3:         0 = g                                  q: 1; v: 2; a, λ: 3
!>   index 2 (eq. 8): 0 = G v + g_I                          q, v: 1; a, λ: 2
!>   index 1 (eq. 9): 0 = G a + γ  (+ 2ζω (G v + g_I) + ω² g, Baumgarte)   all 1
!>                    (constant-mass layout: a = M⁻¹(f - Gᵀλ))
!>   GGL (eq. 10):    q' = T (v - Gᵀμ),  0 = G v + g_I,  0 = g    q, v: 1; a, λ, μ: 2
!> GGL's correction is written T Gᵀμ = T Tᵀ g_qᵀ μ rather than g_qᵀ μ: it is
!> the same for T = I (the pendulum, FE nodes) and keeps the correction in
!> the range of T, so that invariants of q' = T w (a quaternion's unit length)
!> are not disturbed by it. On the exact solution μ = 0 either way.
!>
!> Sparse path (`sparse` at construction, for problems that provide sparse
!> derivative blocks: the multibody systems): ∂F/∂y, the DAE mass matrix and
!> [M Gᵀ; G 0] are CSC values on patterns built once
!> (flexmbs_mbs_formulation_sparse), and F uses sparse products with G and M;
!> no n x n array is allocated (index 1 in the constant-mass layout keeps
!> nc dense rows: G M⁻¹ couples every coordinate).
!>
!> Dense Jacobians ∂F/∂y are analytic in the unknowns that enter F
!> linearly (a, λ, μ and T's, G's and M's action on them); the derivatives in
!> q and v come from the mechanical problem's `*_derivative(s)` bindings,
!> which are analytic when the problem overrides them and forward differences
!> (mechanical_problem.f90) otherwise.
!>
!> Coordinate projection (eqs. 11-12), the post-step hook: positions by the
!> simplified Newton iteration of docs/theory.md §7.4 step 1 with
!> K = [M Gᵀ; G 0] at the step's q̃, q ← q + T(q̃) δ, converged when the
!> weighted RMS norm of the correction is ≤ EPSREQ; then velocities by one
!> solve with K at the projected q, every `velocity_interval` calls. Before
!> the positions, the mechanical problem's `normalize` restores invariants of
!> the kinematics that are not constraints (unit quaternions): with projection
!> on, the formulation keeps them; without it they drift at tolerance level.
!>
!> Submodules: formulation_products (G(t, q) once, then G x, Gᵀ x, M x and
!> G v + g_I, shared by F, ∂F/∂y and the projection) and
!> formulation_projection (the projection, the consistent initial values and
!> multipliers, the drift).
module flexmbs_mbs_formulation
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix, reason_projection
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_formulation_sparse, only: sparse_formulation_t, sparse_layout_t
    use flexmbs_linalg_saddle_point, only: saddle_point_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_mbs_condensed_structure, only: condensed_layout_t
    use flexmbs_mbs_condensed_newton, only: new_condensed_solver
    implicit none
    private

    interface solve_mass
        module procedure solve_mass_matrix, solve_mass_vector
    end interface solve_mass

    !> Formulation selectors.
    integer, parameter, public :: formulation_index1 = 1
    integer, parameter, public :: formulation_index2 = 2
    integer, parameter, public :: formulation_index3 = 3
    integer, parameter, public :: formulation_ggl = 4

    !> The blocks of y, for formulation_t's offset, block_size and last:
    !> positions q, velocities v, accelerations a, multipliers λ, GGL's μ.
    integer, parameter, public :: block_q = 1, block_v = 2, block_a = 3, &
        block_lambda = 4, block_mu = 5

    ! docs/theory.md §7.4: convergence bound and iteration limit of the
    ! position projection.
    real(wp), parameter :: projection_epsreq = 1.0e-2_wp
    integer, parameter :: projection_itmax = 10

    !> A mechanical problem in one formulation, as a `dae_problem_t`.
    type, extends(dae_problem_t), public :: formulation_t
        class(mechanical_problem_t), pointer :: mechanical => null()
        integer, private :: form = formulation_index2 !! outside the module: form_kind
        logical :: accelerations = .true.  !! layout (q, v, a, λ[, μ]) or (q, v, λ[, μ])
        real(wp), private :: baumgarte_zeta = 0.0_wp  !! index 1: damping ratio ζ
        !> index 1: frequency ω (0: no Baumgarte)
        real(wp), private :: baumgarte_omega = 0.0_wp
        logical :: projection = .false.      !! offer the projection hook
        integer, private :: velocity_interval = 1 !! project velocities every k-th call
        real(wp) :: projection_rtol = 1.0e-6_wp !! weights rtol |q| + atol of §6
        real(wp) :: projection_atol = 1.0e-6_wp
        integer, private :: projection_calls = 0
        !> outside the module: block_size of block_q, block_v, block_lambda
        integer, private :: nq = 0, nv = 0, nc = 0
        !> offsets of the blocks in y (outside the module: offset, block_size, last)
        integer, private :: oq = 0, ov = 0, oa = 0, ol = 0, om = 0
        real(wp), allocatable, private :: q_mass(:)   !! where the constant M is evaluated
        ! workspaces, allocated once by the constructor
        real(wp), allocatable, private :: m(:, :), gmat(:, :), force(:), w(:), b(:), c(:), &
            ct(:)
        real(wp), allocatable, private :: qq(:, :), vq(:, :), vv(:, :), cq(:, :), cq2(:, :), &
            cv(:, :)
        real(wp), allocatable, private :: gtlq(:, :), minv_gt(:, :), tq(:), q0(:), &
            mass_lu(:, :)
        real(wp), allocatable, private :: kkt_rhs(:)
        !> consistent_multipliers' last state (t, q, v), its λ, and its
        !> right-hand side and iterate (size nv + nc)
        real(wp), private :: multipliers_t = huge(1.0_wp)
        real(wp), allocatable, private :: multipliers_state(:), multipliers(:), kkt_b(:), &
            kkt_x(:)
        logical, private :: kkt_factored = .false.    !! a factorization of K at some q is held
        integer, allocatable, private :: mass_pivots(:)
        !> dense [M Gᵀ; G 0] (the sparse one is in sp)
        type(saddle_point_t), private :: kkt
        logical, private :: mass_factored = .false.
        logical :: sparse = .false.          !! the sparse path (module header)
        !> allocated on the sparse path only. Allocatable: gfortran 12's
        !> finalization wrapper skipped a matrix of a non-allocatable sp (trq)
        type(sparse_formulation_t), allocatable, private :: sp
    contains
        procedure :: rhs => formulation_rhs
        procedure :: jacobian_storage => formulation_jacobian_storage
        procedure :: jacobian_dense => formulation_jacobian_dense
        procedure :: jacobian_pattern => formulation_jacobian_pattern
        procedure :: jacobian_sparse => formulation_jacobian_sparse
        procedure :: mass_storage => formulation_mass_storage
        procedure :: mass_dense => formulation_mass_dense
        procedure :: mass_sparse => formulation_mass_sparse
        procedure :: is_sparse => formulation_is_sparse
        procedure :: index_classes => formulation_index_classes
        procedure :: differential_flags => formulation_differential_flags
        procedure :: multiplier_flags => formulation_multiplier_flags
        procedure :: has_projection => formulation_has_projection
        procedure :: offset => formulation_offset
        procedure :: block_size => formulation_block_size
        procedure :: form_kind => formulation_form_kind
        procedure :: last => formulation_last
        procedure :: project => formulation_project
        procedure :: consistent_initial => formulation_consistent_initial
        procedure :: consistent_multipliers => formulation_consistent_multipliers
        procedure :: drift => formulation_drift
        procedure :: admissible => formulation_admissible
        procedure :: iteration_solver => formulation_iteration_solver
    end type formulation_t

    ! the G and M products (submodule formulation_products) and the
    ! projection and consistent values (submodule formulation_projection)
    interface
        !> G v + g_I with G(t, q) already evaluated (eval_g).
        module subroutine velocity_constraint(self, t, q, v, c, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: c(:)
            type(status_t), intent(inout) :: status
        end subroutine velocity_constraint
        !> G(t, q), dense (self%gmat) or sparse (self%sp).
        module subroutine eval_g(self, t, q, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            type(status_t), intent(inout) :: status
        end subroutine eval_g
        !> y = G x with the G of the last eval_g.
        module subroutine g_times(self, x, y)
            class(formulation_t), intent(in) :: self
            real(wp), intent(in) :: x(:)
            real(wp), intent(out) :: y(:)
        end subroutine g_times
        !> y = Gᵀ x with the G of the last eval_g.
        module subroutine gt_times(self, x, y)
            class(formulation_t), intent(in) :: self
            real(wp), intent(in) :: x(:)
            real(wp), intent(out) :: y(:)
        end subroutine gt_times
        !> y = M(t, q) x.
        module subroutine mass_times(self, t, q, x, y, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), x(:)
            real(wp), intent(out) :: y(:)
            type(status_t), intent(inout) :: status
        end subroutine mass_times
        !> Eqs. (11)-(12) after an accepted step (module header).
        module subroutine formulation_project(self, t, y, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t
            real(wp), intent(inout) :: y(:)
            type(status_t), intent(inout) :: status
        end subroutine formulation_project
        !> Consistent (y, y'): q and v projected onto g = 0 and G v + g_I = 0
        !> (iterated to round-off), a and λ from [M Gᵀ; G 0] [a; λ] = [f; -γ],
        !> μ = 0; y' = (T v, a, 0, ...) (v' = a in both layouts).
        module subroutine formulation_consistent_initial(self, t, y, yp, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t
            real(wp), intent(inout) :: y(:), yp(:)
            type(status_t), intent(inout) :: status
        end subroutine formulation_consistent_initial
        !> The multipliers λ consistent with the positions and velocities in y:
        !> [M Gᵀ; G 0] [a; λ] = [f; -γ] at y's (q, v), as λ of index 1. In the
        !> index-2, index-3 and GGL forms the integrator's λ is an index-2/3
        !> variable, less accurate than q and v (RADAU5: order 3 against 5, its
        !> error weighted by the step), so reactions are computed from these
        !> (docs/multibody.md). The last state's λ is kept: asked again for the
        !> same (t, q, v), as every reaction series of one output record asks,
        !> nothing is solved. K is not refactored at every record: the solve
        !> is refined with the factorization held (of a nearby q), and K is
        !> factored afresh only when that converges slowly.
        module subroutine formulation_consistent_multipliers(self, t, y, lambda, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t, y(:)
            real(wp), intent(out) :: lambda(:)  !! size nc
            type(status_t), intent(inout) :: status
        end subroutine formulation_consistent_multipliers
        !> Drift of a state: max-norms of g(t, q) and G v + g_I.
        module subroutine formulation_drift(self, t, y, position, velocity, status)
            class(formulation_t), intent(inout) :: self
            real(wp), intent(in) :: t, y(:)
            real(wp), intent(out) :: position, velocity
            type(status_t), intent(inout) :: status
        end subroutine formulation_drift
    end interface

    public :: new_formulation

contains

    !> The mechanical problem `mechanical` (kept by pointer: it must outlive
    !> the formulation) in formulation `form`. `constant_mass` selects the
    !> layout y = (q, v, λ[, μ]) with DAE mass diag(I, M, 0), M evaluated at
    !> q0 (the caller asserts M does not depend on q); otherwise accelerations
    !> are unknowns. `sparse` asks for the sparse path, which is taken when
    !> the mechanical problem provides sparse derivatives (has_sparse_derivatives);
    !> On bad arguments `status` says why and n = 0.
    function new_formulation(mechanical, form, q0, constant_mass, baumgarte_zeta, &
                             baumgarte_omega, projection, status, sparse) result(self)
        class(mechanical_problem_t), target, intent(inout) :: mechanical
        integer, intent(in) :: form                  !! formulation_index1/2/3, formulation_ggl
        real(wp), intent(in) :: q0(:)                !! a configuration (size nq)
        logical, intent(in), optional :: constant_mass  !! layout without a (default false)
        real(wp), intent(in), optional :: baumgarte_zeta  !! index 1 only
        real(wp), intent(in), optional :: baumgarte_omega !! index 1 only, >= 0
        logical, intent(in), optional :: projection  !! offer the post-step projection
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: sparse      !! sparse matrices (default false)
        type(formulation_t) :: self
        integer :: nq, nv, nc, nk, ios
        character(len=160) :: msg

        nq = mechanical%nq
        nv = mechanical%nv
        nc = mechanical%nc
        if (form < formulation_index1 .or. form > formulation_ggl) then
            write (msg, '(a,i0,a)') 'formulation: form = ', form, &
                ': must be formulation_index1, _index2, _index3 or formulation_ggl'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (nq < 1 .or. nv < 1 .or. size(q0) /= nq) then
            write (msg, '(a,3(i0,a))') 'formulation: nq = ', nq, ', nv = ', nv, &
                ', size(q0) = ', size(q0), ': need nq, nv >= 1 and size(q0) = nq'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        self%mechanical => mechanical
        self%form = form
        if (present(constant_mass)) self%accelerations = .not. constant_mass
        if (present(baumgarte_zeta)) self%baumgarte_zeta = baumgarte_zeta
        if (present(baumgarte_omega)) self%baumgarte_omega = baumgarte_omega
        if (present(projection)) self%projection = projection
        if (self%baumgarte_omega < 0.0_wp .or. self%baumgarte_zeta < 0.0_wp) then
            call status%set(status_bad_input, 'formulation: Baumgarte zeta and omega &
                &must be >= 0')
            return
        end if
        self%nq = nq
        self%nv = nv
        self%nc = nc
        self%oq = 0
        self%ov = nq
        self%oa = nq + nv
        self%ol = nq + nv
        if (self%accelerations) self%ol = nq + 2 * nv
        self%om = self%ol + nc
        self%n = self%om
        if (form == formulation_ggl) self%n = self%om + nc
        self%q_mass = q0
        nk = nv + nc
        if (present(sparse)) self%sparse = sparse .and. mechanical%has_sparse() .and. &
            mechanical%has_sparse_derivatives()
        if (self%sparse) then
            allocate (self%sp)
            call self%sp%init(mechanical, sparse_layout_t(form=form, &
                accelerations=self%accelerations, ggl=form == formulation_ggl, n=self%n, &
                nq=nq, nv=nv, nc=nc, oq=self%oq, ov=self%ov, oa=self%oa, ol=self%ol, &
                om=self%om, baumgarte_zeta=self%baumgarte_zeta, &
                baumgarte_omega=self%baumgarte_omega), q0, status)
            if (.not. status%ok()) then
                status%message = 'formulation: ' // status%message
                self%n = 0
                return
            end if
            allocate (self%force(nv), self%w(nv), self%b(nv), self%c(nc), self%ct(nc), &
                      self%tq(nq), self%q0(nq), self%kkt_rhs(nk), stat=ios)
            if (ios /= 0) then
                call out_of_memory(status, 'formulation vectors', int(nq + nv + nk, i8), 8)
                self%n = 0
            end if
            return
        end if
        ! dense: a dozen n x n blocks, the largest of all
        allocate (self%m(nv, nv), self%gmat(nc, nv), self%force(nv), self%w(nv), self%b(nv), &
                  self%c(nc), self%ct(nc), self%qq(nq, nq), self%vq(nv, nq), self%vv(nv, nv), &
                  self%cq(nc, nq), self%cq2(nc, nq), self%cv(nc, nv), self%tq(nq), &
                  self%gtlq(nv, nq), self%minv_gt(nv, nc), &
                  self%q0(nq), self%mass_lu(nv, nv), self%kkt_rhs(nk), &
                  self%mass_pivots(nv), stat=ios)
        if (ios /= 0) then
            call out_of_memory(status, 'dense formulation matrices', &
                               8_i8 * int(nq + nv + nc, i8)**2, 8)
            self%n = 0
            return
        end if
        call self%kkt%init_dense(nv, nc, status=status)
        if (.not. status%ok()) self%n = 0
    end function new_formulation

    !> Factor the constant M once (constant-mass layout, index 1 needs M⁻¹).
    subroutine factor_mass(self, t, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t
        type(status_t), intent(inout) :: status
        integer :: info
        call self%mechanical%mass(t, self%q_mass, self%mass_lu, status)
        call dgetrf(self%nv, self%nv, self%mass_lu, self%nv, self%mass_pivots, info)
        if (info /= 0) then
            call status%set(status_solver_failure, 'formulation: mass matrix is singular', &
                reason_singular_matrix)
            return
        end if
        self%mass_factored = .true.
    end subroutine factor_mass

    !> x ← M⁻¹ x with the constant M.
    subroutine solve_mass_vector(self, t, x, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: x(:)
        type(status_t), intent(inout) :: status
        integer :: info
        if (.not. self%mass_factored) call factor_mass(self, t, status)
        if (.not. status%ok()) return
        call dgetrs('N', self%nv, 1, self%mass_lu, self%nv, self%mass_pivots, x, self%nv, info)
    end subroutine solve_mass_vector

    !> X ← M⁻¹ X with the constant M.
    subroutine solve_mass_matrix(self, t, x, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: x(:, :)
        type(status_t), intent(inout) :: status
        integer :: info
        if (.not. self%mass_factored) call factor_mass(self, t, status)
        if (.not. status%ok()) return
        call dgetrs('N', self%nv, size(x, 2), self%mass_lu, self%nv, self%mass_pivots, x, &
                    self%nv, info)
    end subroutine solve_mass_matrix

    subroutine formulation_rhs(self, t, y, f, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        associate (mech => self%mechanical, nq => self%nq, nv => self%nv, nc => self%nc, &
                   q => y(self%oq + 1:self%oq + self%nq), v => y(self%ov + 1:self%ov + self%nv), &
                   lam => y(self%ol + 1:self%ol + self%nc), &
                   fq => f(self%oq + 1:self%oq + self%nq), fv => f(self%ov + 1:self%ov + self%nv), &
                   fc => f(self%ol + 1:self%ol + self%nc))
            call mech%forces(t, q, v, self%force, status)
            call eval_g(self, t, q, status)
            ! q' = T v, or T (v - Gᵀμ) in GGL
            self%w = v
            if (self%form == formulation_ggl) then
                call gt_times(self, y(self%om + 1:self%om + nc), self%b)
                self%w = v - self%b
            end if
            call mech%kinematics(t, q, self%w, fq, status)
            call gt_times(self, lam, self%b)
            self%b = self%force - self%b
            if (self%accelerations) then
                associate (a => y(self%oa + 1:self%oa + nv), fa => f(self%oa + 1:self%oa + nv))
                    fv = a
                    call mass_times(self, t, q, a, fa, status)
                    fa = self%b - fa
                    self%b = a
                end associate
            else
                fv = self%b
            end if
            select case (self%form)
            case (formulation_index3)
                call mech%constraint(t, q, fc, status)
            case (formulation_index2)
                call velocity_constraint(self, t, q, v, fc, status)
            case (formulation_ggl)
                call velocity_constraint(self, t, q, v, fc, status)
                call mech%constraint(t, q, f(self%om + 1:self%om + nc), status)
            case (formulation_index1)
                ! b = a, or M⁻¹(f - Gᵀλ) with the constant M
                if (.not. self%accelerations) then
                    if (self%sparse) then
                        call self%sp%solve_mass(self%b, status)
                    else
                        call solve_mass(self, t, self%b, status)
                    end if
                end if
                call mech%constraint_curvature(t, q, v, fc, status)
                call g_times(self, self%b, self%c)
                fc = fc + self%c
                if (self%baumgarte_omega > 0.0_wp) then
                    call velocity_constraint(self, t, q, v, self%c, status)
                    fc = fc + 2.0_wp * self%baumgarte_zeta * self%baumgarte_omega * self%c
                    call mech%constraint(t, q, self%c, status)
                    fc = fc + self%baumgarte_omega**2 * self%c
                end if
            end select
        end associate
    end subroutine formulation_rhs


    integer function formulation_jacobian_storage(self)
        class(formulation_t), intent(in) :: self
        formulation_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function formulation_jacobian_storage

    !> Whether the sparse path was taken (new_formulation's `sparse`).
    pure logical function formulation_is_sparse(self)
        class(formulation_t), intent(in) :: self
        formulation_is_sparse = self%sparse
    end function formulation_is_sparse

    !> The fixed CSC pattern of ∂F/∂y (sparse path).
    subroutine formulation_jacobian_pattern(self, pattern, status)
        class(formulation_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        call self%sp%jacobian_pattern(pattern)
    end subroutine formulation_jacobian_pattern

    !> ∂F/∂y's values in its pattern (sparse path).
    subroutine formulation_jacobian_sparse(self, t, y, values, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        call self%sp%jacobian(self%mechanical, t, y, values, status)
    end subroutine formulation_jacobian_sparse

    !> The DAE mass matrix in CSC (sparse path).
    subroutine formulation_mass_sparse(self, m, status)
        class(formulation_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        call self%sp%mass_matrix(m)
    end subroutine formulation_mass_sparse

    !> ∂F/∂y, block by block (module header).
    subroutine formulation_jacobian_dense(self, t, y, jac, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: kz
        integer :: j, k, rq, rv, ra, rl, rm
        jac = 0.0_wp
        rq = self%oq
        rv = self%ov
        ra = self%oa
        rl = self%ol
        rm = self%om
        associate (mech => self%mechanical, nq => self%nq, nv => self%nv, nc => self%nc, &
                   q => y(self%oq + 1:self%oq + self%nq), v => y(self%ov + 1:self%ov + self%nv), &
                   lam => y(self%ol + 1:self%ol + self%nc))
            call mech%constraint_jacobian(t, q, self%gmat, status)
            call mech%forces(t, q, v, self%force, status)
            ! rows q' = T w, w = v (- Gᵀμ)
            self%w = v
            if (self%form == formulation_ggl) &
                self%w = v - matmul(y(rm + 1:rm + nc), self%gmat)
            call mech%kinematics_derivative(t, q, self%w, self%qq, status)
            jac(rq + 1:rq + nq, rq + 1:rq + nq) = self%qq
            do j = 1, nv
                self%b = 0.0_wp
                self%b(j) = 1.0_wp
                call mech%kinematics(t, q, self%b, self%tq, status)
                jac(rq + 1:rq + nq, rv + j) = self%tq
            end do
            if (self%form == formulation_ggl) then
                ! -T ∂(Gᵀμ)/∂q and -T Gᵀ
                call mech%constraint_jacobian_derivatives(t, q, v, y(rm + 1:rm + nc), &
                                                          self%cq, self%vq, status)
                do j = 1, nq
                    call mech%kinematics(t, q, self%vq(:, j), self%tq, status)
                    jac(rq + 1:rq + nq, rq + j) = jac(rq + 1:rq + nq, rq + j) - self%tq
                end do
                do k = 1, nc
                    call mech%kinematics(t, q, self%gmat(k, :), self%tq, status)
                    jac(rq + 1:rq + nq, rm + k) = -self%tq
                end do
            end if
            ! force rows: f - M a - Gᵀλ (accelerations) or f - Gᵀλ
            call mech%force_derivatives(t, q, v, self%vq, self%vv, status)
            call mech%constraint_jacobian_derivatives(t, q, v, lam, self%cq, self%gtlq &
                                                      , status)
            if (self%accelerations) then
                do j = 1, nv
                    jac(rv + j, ra + j) = 1.0_wp
                end do
                associate (a => y(ra + 1:ra + nv))
                    jac(ra + 1:ra + nv, rq + 1:rq + nq) = self%vq - self%gtlq
                    call mech%mass_derivative(t, q, a, self%vq, status)
                    jac(ra + 1:ra + nv, rq + 1:rq + nq) = jac(ra + 1:ra + nv, rq + 1:rq + nq) &
                        - self%vq
                    jac(ra + 1:ra + nv, rv + 1:rv + nv) = self%vv
                    call mech%mass(t, q, self%m, status)
                    jac(ra + 1:ra + nv, ra + 1:ra + nv) = -self%m
                    jac(ra + 1:ra + nv, rl + 1:rl + nc) = -transpose(self%gmat)
                end associate
            else
                jac(rv + 1:rv + nv, rq + 1:rq + nq) = self%vq - self%gtlq
                jac(rv + 1:rv + nv, rv + 1:rv + nv) = self%vv
                jac(rv + 1:rv + nv, rl + 1:rl + nc) = -transpose(self%gmat)
            end if
            ! constraint rows
            select case (self%form)
            case (formulation_index3)
                call mech%constraint_position_jacobian(t, q, self%cq, status)
                jac(rl + 1:rl + nc, rq + 1:rq + nq) = self%cq
            case (formulation_index2, formulation_ggl)
                call velocity_constraint_derivatives(self, t, q, v, status)
                jac(rl + 1:rl + nc, rq + 1:rq + nq) = self%cq
                jac(rl + 1:rl + nc, rv + 1:rv + nv) = self%gmat
                if (self%form == formulation_ggl) then
                    call mech%constraint_position_jacobian(t, q, self%cq, status)
                    jac(rm + 1:rm + nc, rq + 1:rq + nq) = self%cq
                end if
            case (formulation_index1)
                call mech%constraint_curvature_derivatives(t, q, v, self%cq, self%cv, status)
                jac(rl + 1:rl + nc, rq + 1:rq + nq) = self%cq
                jac(rl + 1:rl + nc, rv + 1:rv + nv) = self%cv
                if (self%accelerations) then
                    associate (a => y(ra + 1:ra + nv))
                        call mech%constraint_jacobian_derivatives(t, q, a, lam, self%cq, &
                                                                  self%vq, status)
                    end associate
                    jac(rl + 1:rl + nc, rq + 1:rq + nq) = jac(rl + 1:rl + nc, rq + 1:rq + nq) &
                        + self%cq
                    jac(rl + 1:rl + nc, ra + 1:ra + nv) = self%gmat
                else
                    call index1_constant_mass_rows(self, t, q, lam, jac, status)
                end if
                if (self%baumgarte_omega > 0.0_wp) then
                    kz = 2.0_wp * self%baumgarte_zeta * self%baumgarte_omega
                    call velocity_constraint_derivatives(self, t, q, v, status)
                    jac(rl + 1:rl + nc, rq + 1:rq + nq) = jac(rl + 1:rl + nc, rq + 1:rq + nq) &
                        + kz * self%cq
                    jac(rl + 1:rl + nc, rv + 1:rv + nv) = jac(rl + 1:rl + nc, rv + 1:rv + nv) &
                        + kz * self%gmat
                    call mech%constraint_position_jacobian(t, q, self%cq, status)
                    jac(rl + 1:rl + nc, rq + 1:rq + nq) = jac(rl + 1:rl + nc, rq + 1:rq + nq) &
                        + self%baumgarte_omega**2 * self%cq
                end if
            end select
        end associate
    end subroutine formulation_jacobian_dense

    !> self%cq = ∂(G v + g_I)/∂q.
    subroutine velocity_constraint_derivatives(self, t, q, v, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        type(status_t), intent(inout) :: status
        self%c = 0.0_wp
        call self%mechanical%constraint_jacobian_derivatives(t, q, v, self%c, self%cq, &
                                                             self%vq, status)
        call self%mechanical%constraint_time_derivative_jacobian(t, q, self%cq2, status)
        self%cq = self%cq + self%cq2
    end subroutine velocity_constraint_derivatives

    !> Index 1, constant M: the G M⁻¹(f - Gᵀλ) part of the constraint rows,
    !> added to the γ part already in jac. Uses self%vq = f_q - ∂(Gᵀλ)/∂q and
    !> self%vv = f_v left by the force rows.
    subroutine index1_constant_mass_rows(self, t, q, lam, jac, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), lam(:)
        real(wp), intent(inout) :: jac(:, :)
        type(status_t), intent(inout) :: status
        integer :: rq, rv, rl
        rq = self%oq
        rv = self%ov
        rl = self%ol
        associate (nq => self%nq, nv => self%nv, nc => self%nc)
            ! rows of ∂/∂q and ∂/∂v of M⁻¹(f - Gᵀλ): the force-row blocks times M⁻¹
            self%vq = jac(rv + 1:rv + nv, rq + 1:rq + nq)
            call solve_mass(self, t, self%vq, status)
            self%vv = jac(rv + 1:rv + nv, rv + 1:rv + nv)
            call solve_mass(self, t, self%vv, status)
            self%minv_gt = transpose(self%gmat)
            call solve_mass(self, t, self%minv_gt, status)
            ! b = M⁻¹(f - Gᵀλ); ∂(G b)/∂q at fixed b
            self%b = self%force - matmul(lam, self%gmat)
            call solve_mass(self, t, self%b, status)
            call self%mechanical%constraint_jacobian_derivatives(t, q, self%b, lam, self%cq, &
                                                                 self%gtlq, status)
            jac(rl + 1:rl + nc, rq + 1:rq + nq) = jac(rl + 1:rl + nc, rq + 1:rq + nq) &
                + self%cq + matmul(self%gmat, self%vq)
            jac(rl + 1:rl + nc, rv + 1:rv + nv) = jac(rl + 1:rl + nc, rv + 1:rv + nv) &
                + matmul(self%gmat, self%vv)
            jac(rl + 1:rl + nc, rl + 1:rl + nc) = -matmul(self%gmat, self%minv_gt)
        end associate
    end subroutine index1_constant_mass_rows

    integer function formulation_mass_storage(self)
        class(formulation_t), intent(in) :: self
        formulation_mass_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function formulation_mass_storage

    !> diag(I, I, 0, ...) or diag(I, M, 0, ...).
    subroutine formulation_mass_dense(self, m)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        type(status_t) :: status
        integer :: i
        m = 0.0_wp
        do i = 1, self%nq
            m(self%oq + i, self%oq + i) = 1.0_wp
        end do
        if (self%accelerations) then
            do i = 1, self%nv
                m(self%ov + i, self%ov + i) = 1.0_wp
            end do
        else
            call self%mechanical%mass(0.0_wp, self%q_mass, self%m, status)
            m(self%ov + 1:self%ov + self%nv, self%ov + 1:self%ov + self%nv) = self%m
        end if
    end subroutine formulation_mass_dense

    !> docs/theory.md §3.
    subroutine formulation_index_classes(self, classes)
        class(formulation_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        classes = 1
        select case (self%form)
        case (formulation_index3)
            classes(self%ov + 1:self%ov + self%nv) = 2
            classes(self%ov + self%nv + 1:) = 3
        case (formulation_index2, formulation_ggl)
            classes(self%ov + self%nv + 1:) = 2
        end select
    end subroutine formulation_index_classes

    !> λ, GGL's μ, and in the acceleration layout with constraints the
    !> accelerations, which λ determines through M a = f − Gᵀλ (without
    !> constraints a is M⁻¹f, a function of q and v, and keeps its weight).
    subroutine formulation_multiplier_flags(self, flags)
        class(formulation_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .false.
        if (self%nc == 0) return
        flags(self%ol + 1:self%ol + self%nc) = .true.
        if (self%form == formulation_ggl) flags(self%om + 1:self%om + self%nc) = .true.
        if (self%accelerations) flags(self%oa + 1:self%oa + self%nv) = .true.
    end subroutine formulation_multiplier_flags

    subroutine formulation_differential_flags(self, flags)
        class(formulation_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .false.
        flags(1:self%nq + self%nv) = .true.
    end subroutine formulation_differential_flags

    logical function formulation_has_projection(self)
        class(formulation_t), intent(in) :: self
        formulation_has_projection = self%projection
    end function formulation_has_projection

    !> Where block `block` (block_q, _v, _a, _lambda, _mu) starts in y: its
    !> entries are y(offset + 1:offset + block_size); -1 for another number.
    pure integer function formulation_offset(self, block) result(offset)
        class(formulation_t), intent(in) :: self
        integer, intent(in) :: block
        select case (block)
        case (block_q)
            offset = self%oq
        case (block_v)
            offset = self%ov
        case (block_a)
            offset = self%oa
        case (block_lambda)
            offset = self%ol
        case (block_mu)
            offset = self%om
        case default
            offset = -1
        end select
    end function formulation_offset

    !> The formulation (formulation_index1, _index2, _index3, formulation_ggl).
    pure integer function formulation_form_kind(self) result(form)
        class(formulation_t), intent(in) :: self
        form = self%form
    end function formulation_form_kind

    !> The length of block `block` in y: 0 for a block the layout has not
    !> (a without accelerations, μ outside GGL) and for another number.
    pure integer function formulation_block_size(self, block) result(n)
        class(formulation_t), intent(in) :: self
        integer, intent(in) :: block
        n = 0
        select case (block)
        case (block_q)
            n = self%nq
        case (block_v)
            n = self%nv
        case (block_a)
            if (self%accelerations) n = self%nv
        case (block_lambda)
            n = self%nc
        case (block_mu)
            if (self%form == formulation_ggl) n = self%nc
        end select
    end function formulation_block_size

    !> The last entry of block `block` in y, offset + block_size.
    pure integer function formulation_last(self, block) result(last)
        class(formulation_t), intent(in) :: self
        integer, intent(in) :: block
        last = self%offset(block) + self%block_size(block)
    end function formulation_last


    !> The condensed Newton systems (docs/theory.md §3.7) on the sparse path
    !> with newton_system = 'condensed' and a sparse LU ('auto', 'klu',
    !> 'mumps'); otherwise none, and the solvers factor ∂F/∂y's matrices.
    !> With the condensed systems the formulation's own saddle-point systems
    !> (projection, the outputs' multipliers) go by the structure of M.
    subroutine formulation_iteration_solver(self, options, solver, status)
        class(formulation_t), intent(inout) :: self
        type(dae_options_t), intent(in) :: options
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(inout) :: status
        if (.not. self%sparse .or. options%newton_system /= 'condensed' .or. &
            options%jacobian == 'fd') return
        select case (trim(options%linear_solver))
        case ('auto', 'klu', 'mumps')
            allocate (solver, source=new_condensed_solver(condensed_layout_t(n=self%n, &
                nq=self%nq, nv=self%nv, oq=self%oq, ov=self%ov, oa=self%oa, ol=self%ol, &
                accelerations=self%accelerations), options%linear_solver, &
                options%sparse_ordering))
            ! the projection and the multipliers of the outputs solve [M Gᵀ; G 0]
            ! by the structure of M too (theory §7.8); K is refactored afresh.
            ! The consistent initial values, made before, keep KLU on K: the
            ! state a run starts from is the same on both paths (an index-3
            ! pencil's infinite eigenvalues move with its round-off:
            ! flexmbs modes counted 272 finite of five-body's, not 266)
            self%kkt_factored = .false.
            call self%sp%use_structure()
        end select
    end subroutine formulation_iteration_solver

    !> The mechanical problem's test of the positions in y.
    subroutine formulation_admissible(self, t, y, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(out) :: status
        call self%mechanical%admissible(y(self%oq + 1:self%oq + self%nq), status)
    end subroutine formulation_admissible
end module flexmbs_mbs_formulation
