!> The planar chain of NB rigid bars of docs/solvers.md (the MEXAX anchor
!> problem) as a mechanical problem in absolute coordinates.
!>
!> Body i has q = (x_i, y_i, φ_i) (centre and angle from the downward
!> vertical), mass m = 1/NB, half-length l = 0.5/NB, moment of inertia
!> m l²/3 about its centre, T = I and gravity 10 in -y. Bar 1's upper end is
!> pinned at the origin; the upper end of bar i meets the lower end of bar
!> i-1. With the upper end (x - l sin φ, y + l cos φ) and the lower end
!> (x + l sin φ, y - l cos φ) the 2 NB position constraints are
!>
!>   0 = -x_1 + l sin φ_1,                       0 = -y_1 - l cos φ_1,
!>   0 = x_{i-1} + l sin φ_{i-1} - x_i + l sin φ_i,
!>   0 = y_{i-1} - l cos φ_{i-1} - y_i - l cos φ_i        (i ≥ 2).
!>
!> M and f are constant, the constraints scleronomic (g_I = 0). The chain
!> starts horizontal at rest, φ_i = π/2, x_i = (2i - 1) l, y_i = 0.
!>
!> M (diagonal, 3 NB slots) and G (8 NB - 4 slots) are also given as CSC,
!> so that MEXAX can factor [M Gᵀ; G 0] with KLU when NB is large.
module flexmbs_problems_pendulum_chain
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    implicit none
    private

    !> §8: gravity of the anchor problem (in -y).
    real(wp), parameter, public :: chain_gravity = 10.0_wp
    !> §8: (x_1, y_1, φ_1) at t = 1 for NB = 8, computed by the original
    !> MEXX with TOL 1e-11.
    real(wp), parameter, public :: chain_anchor_t1(3) = [-4.86227554026e-2_wp, &
        -3.92692966204e-2_wp, -8.91418977542e-1_wp]

    real(wp), parameter :: half_pi = 0.5_wp * acos(-1.0_wp)

    !> The chain of NB bars (see the module): NB and the bars' mass, half-length
    !> and moment of inertia, all fixed by NB.
    type, extends(mechanical_problem_t), public :: pendulum_chain_t
        integer :: bodies = 0            !! NB
        real(wp) :: body_mass = 0.0_wp   !! m = 1/NB
        real(wp) :: half_length = 0.0_wp !! l = 0.5/NB
        real(wp) :: inertia = 0.0_wp     !! m l²/3
    contains
        procedure :: kinematics => pendulum_chain_kinematics
        procedure :: mass => pendulum_chain_mass
        procedure :: forces => pendulum_chain_forces
        procedure :: constraint => pendulum_chain_constraint
        procedure :: constraint_jacobian => pendulum_chain_constraint_jacobian
        procedure :: constraint_curvature => pendulum_chain_constraint_curvature
        procedure :: has_sparse => pendulum_chain_has_sparse
        procedure :: mass_pattern => pendulum_chain_mass_pattern
        procedure :: mass_sparse => pendulum_chain_mass_sparse
        procedure :: constraint_jacobian_pattern => pendulum_chain_constraint_jacobian_pattern
        procedure :: constraint_jacobian_sparse => pendulum_chain_constraint_jacobian_sparse
    end type pendulum_chain_t

    public :: new_pendulum_chain, pendulum_chain_initial

contains

    !> The chain of `bodies` bars (nq = nv = 3 NB, nc = 2 NB).
    function new_pendulum_chain(bodies, status) result(problem)
        integer, intent(in) :: bodies !! NB ≥ 1
        type(status_t), intent(out), optional :: status
        type(pendulum_chain_t) :: problem
        type(status_t) :: local
        character(len=80) :: msg
        if (bodies < 1) then
            write (msg, '(a,i0,a)') 'pendulum chain: bodies = ', bodies, ': must be at least 1'
            call local%set(status_bad_input, trim(msg))
        else
            problem%bodies = bodies
            problem%body_mass = 1.0_wp / bodies
            problem%half_length = 0.5_wp / bodies
            problem%inertia = problem%body_mass * problem%half_length**2 / 3.0_wp
            problem%nq = 3 * bodies
            problem%nv = 3 * bodies
            problem%nc = 2 * bodies
        end if
        if (present(status)) status = local
    end function new_pendulum_chain

    !> §8 start: horizontal at rest; λ = 0 (the start is not an equilibrium,
    !> λ is an output of the solver).
    pure subroutine pendulum_chain_initial(problem, q, v, lambda)
        class(pendulum_chain_t), intent(in) :: problem
        real(wp), intent(out) :: q(:), v(:), lambda(:) !! sizes 3 NB, 3 NB, 2 NB
        integer :: i
        do i = 1, problem%bodies
            q(3 * i - 2) = real(2 * i - 1, wp) * problem%half_length
            q(3 * i - 1) = 0.0_wp
            q(3 * i) = half_pi
        end do
        v = 0.0_wp
        lambda = 0.0_wp
    end subroutine pendulum_chain_initial

    subroutine pendulum_chain_kinematics(self, t, q, w, qdot, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        qdot = w
    end subroutine pendulum_chain_kinematics

    !> M = diag(m, m, m l²/3) per body.
    subroutine pendulum_chain_mass(self, t, q, m, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        integer :: i
        m = 0.0_wp
        do i = 1, self%bodies
            m(3 * i - 2, 3 * i - 2) = self%body_mass
            m(3 * i - 1, 3 * i - 1) = self%body_mass
            m(3 * i, 3 * i) = self%inertia
        end do
    end subroutine pendulum_chain_mass

    subroutine pendulum_chain_forces(self, t, q, v, f, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        integer :: i
        f = 0.0_wp
        do i = 1, self%bodies
            f(3 * i - 1) = -self%body_mass * chain_gravity
        end do
    end subroutine pendulum_chain_forces

    subroutine pendulum_chain_constraint(self, t, q, g, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        integer :: i
        real(wp) :: l
        l = self%half_length
        g(1) = -q(1) + l * sin(q(3))
        g(2) = -q(2) - l * cos(q(3))
        do i = 2, self%bodies
            g(2 * i - 1) = q(3 * i - 5) + l * sin(q(3 * i - 3)) - q(3 * i - 2) + l * sin(q(3 * i))
            g(2 * i) = q(3 * i - 4) - l * cos(q(3 * i - 3)) - q(3 * i - 1) - l * cos(q(3 * i))
        end do
    end subroutine pendulum_chain_constraint

    !> G = g_q (T = I), 2 NB x 3 NB.
    subroutine pendulum_chain_constraint_jacobian(self, t, q, gmat, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
        integer :: i
        real(wp) :: l
        l = self%half_length
        gmat = 0.0_wp
        gmat(1, 1) = -1.0_wp
        gmat(1, 3) = l * cos(q(3))
        gmat(2, 2) = -1.0_wp
        gmat(2, 3) = l * sin(q(3))
        do i = 2, self%bodies
            gmat(2 * i - 1, 3 * i - 5) = 1.0_wp
            gmat(2 * i - 1, 3 * i - 3) = l * cos(q(3 * i - 3))
            gmat(2 * i - 1, 3 * i - 2) = -1.0_wp
            gmat(2 * i - 1, 3 * i) = l * cos(q(3 * i))
            gmat(2 * i, 3 * i - 4) = 1.0_wp
            gmat(2 * i, 3 * i - 3) = l * sin(q(3 * i - 3))
            gmat(2 * i, 3 * i - 1) = -1.0_wp
            gmat(2 * i, 3 * i) = l * sin(q(3 * i))
        end do
    end subroutine pendulum_chain_constraint_jacobian

    !> γ = (G v)_q v: only the angle entries of G depend on q.
    subroutine pendulum_chain_constraint_curvature(self, t, q, v, gamma, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
        integer :: i
        real(wp) :: l
        l = self%half_length
        gamma(1) = -l * sin(q(3)) * v(3)**2
        gamma(2) = l * cos(q(3)) * v(3)**2
        do i = 2, self%bodies
            gamma(2 * i - 1) = -l * (sin(q(3 * i - 3)) * v(3 * i - 3)**2 &
                + sin(q(3 * i)) * v(3 * i)**2)
            gamma(2 * i) = l * (cos(q(3 * i - 3)) * v(3 * i - 3)**2 + cos(q(3 * i)) * v(3 * i)**2)
        end do
    end subroutine pendulum_chain_constraint_curvature

    logical function pendulum_chain_has_sparse(self)
        class(pendulum_chain_t), intent(in) :: self
        pendulum_chain_has_sparse = .true.
    end function pendulum_chain_has_sparse

    !> M is diagonal.
    subroutine pendulum_chain_mass_pattern(self, pattern, status)
        class(pendulum_chain_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer :: i
        call pattern%build(self%nv, self%nv, [(i, i=1, self%nv)], [(i, i=1, self%nv)], status)
    end subroutine pendulum_chain_mass_pattern

    !> diag(m, m, m l²/3) per body, in the slots of the diagonal pattern.
    subroutine pendulum_chain_mass_sparse(self, t, q, values, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: i
        do i = 1, self%bodies
            values(3 * i - 2) = self%body_mass
            values(3 * i - 1) = self%body_mass
            values(3 * i) = self%inertia
        end do
    end subroutine pendulum_chain_mass_sparse

    !> The 8 NB - 4 slots of G, column by column.
    subroutine pendulum_chain_constraint_jacobian_pattern(self, pattern, status)
        class(pendulum_chain_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: values(:)
        real(wp), allocatable :: q(:)
        integer :: nnz
        nnz = 8 * self%bodies - 4
        allocate (rows(nnz), cols(nnz), values(nnz), q(self%nq))
        q = half_pi
        call jacobian_entries(self, q, values, rows, cols)
        call pattern%build(self%nc, self%nv, rows, cols, status)
    end subroutine pendulum_chain_constraint_jacobian_pattern

    !> Values of G in the slots of its pattern.
    subroutine pendulum_chain_constraint_jacobian_sparse(self, t, q, values, status)
        class(pendulum_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        call jacobian_entries(self, q, values)
    end subroutine pendulum_chain_constraint_jacobian_sparse

    !> The nonzeros of G in CSC order (by column, rows ascending), so that
    !> the pattern built from (rows, cols) has them in exactly these slots.
    !> Column x_i holds rows 2i-1 (bar i's upper end) and 2i+1 (bar i+1's),
    !> y_i rows 2i and 2i+2, φ_i all four.
    subroutine jacobian_entries(self, q, values, rows, cols)
        class(pendulum_chain_t), intent(in) :: self
        real(wp), intent(in) :: q(:)
        real(wp), intent(out) :: values(:)
        integer, intent(out), optional :: rows(:), cols(:)
        integer :: i, k, nb
        real(wp) :: l, lc, ls
        l = self%half_length
        nb = self%bodies
        k = 0
        do i = 1, nb
            lc = l * cos(q(3 * i))
            ls = l * sin(q(3 * i))
            call put(2 * i - 1, 3 * i - 2, -1.0_wp)
            if (i < nb) call put(2 * i + 1, 3 * i - 2, 1.0_wp)
            call put(2 * i, 3 * i - 1, -1.0_wp)
            if (i < nb) call put(2 * i + 2, 3 * i - 1, 1.0_wp)
            call put(2 * i - 1, 3 * i, lc)
            call put(2 * i, 3 * i, ls)
            if (i < nb) then
                call put(2 * i + 1, 3 * i, lc)
                call put(2 * i + 2, 3 * i, ls)
            end if
        end do
    contains
        subroutine put(row, col, value)
            integer, intent(in) :: row, col
            real(wp), intent(in) :: value
            k = k + 1
            values(k) = value
            if (present(rows)) rows(k) = row
            if (present(cols)) cols(k) = col
        end subroutine put
    end subroutine jacobian_entries
end module flexmbs_problems_pendulum_chain
