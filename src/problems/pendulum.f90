!> The planar pendulum in Cartesian coordinates, the reference problem of
!> every solver: a point mass m on a massless rod of length L, gravity g in
!> -y, written by hand in the four formulations of docs/theory.md §3.
!>
!> Position invariant and constraint Jacobian (one scaling used throughout,
!> so that G = g_q and the velocity constraint is G v):
!>
!>   g(q) = (x² + y² - L²) / 2,   G = g_q = (x, y).
!>
!> With our sign M v' = f - Gᵀλ, f = (0, -m g), the unknowns
!> y = (x, y, u, v, λ[, μ]) and M = diag(1, 1, m, m, 0[, 0]):
!>
!>   x' = u - x μ,   y' = v - y μ            (μ only in GGL)
!>   m u' = -x λ,    m v' = -m g - y λ
!>   index 3:  0 = (x² + y² - L²) / 2                     classes 1 1 2 2 3
!>   index 2:  0 = x u + y v                  (eq. 8)     classes 1 1 1 1 2
!>   index 1:  0 = u² + v² - g y - (x² + y²) λ / m        classes 1 1 1 1 1
!>             (eq. 9: G a + (G v)_q v with a = M⁻¹(f - Gᵀλ))
!>   GGL:      0 = x u + y v,  0 = (x² + y² - L²) / 2   (eq. 10), classes 1 1 1 1 2 2
!>
!> On the exact solution λ = m (u² + v² - g y) / L² (the rod tension is L λ)
!> and μ = 0. In the angle φ from the downward vertical, x = L sin φ,
!> y = -L cos φ and φ'' = -ω² sin φ, ω² = g/L. Starting at rest from φ0
!> (|φ0| < π) the exact solution is the classical one in Jacobi's functions
!>
!>   sin(φ/2) = k sn(ω t + K(k), k),   φ' = 2 k ω cn(ω t + K(k), k),
!>   k = sin(φ0/2),
!>
!> with sn, cn evaluated by the arithmetic-geometric mean (descending Landen
!> transformation, [Abramowitz & Stegun §16.4, §17.6]). A fixed-step classical
!> Runge-Kutta integration of the angle ODE is provided as an independent
!> second method.
module flexmbs_problems_pendulum
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    implicit none
    private

    !> Formulation selectors (constructor argument).
    integer, parameter, public :: pendulum_index1 = 1
    integer, parameter, public :: pendulum_index2 = 2
    integer, parameter, public :: pendulum_index3 = 3
    integer, parameter, public :: pendulum_ggl = 4

    !> Default parameters: unit mass and length, standard gravity.
    real(wp), parameter, public :: pendulum_default_mass = 1.0_wp
    real(wp), parameter, public :: pendulum_default_length = 1.0_wp
    real(wp), parameter, public :: pendulum_default_gravity = 9.81_wp

    real(wp), parameter :: pi = acos(-1.0_wp)
    ! Most structural non-zeros of ∂F/∂y (the GGL form).
    integer, parameter :: max_entries = 16
    ! The AGM converges quadratically; 40 levels cover k' down to 1e-300.
    integer, parameter :: max_agm_levels = 40

    !> The pendulum as M y' = F(t, y) in one of the four formulations.
    type, extends(dae_problem_t), public :: pendulum_t
        integer :: formulation = pendulum_index3
        real(wp) :: point_mass = pendulum_default_mass
        real(wp) :: length = pendulum_default_length
        real(wp) :: gravity = pendulum_default_gravity
        real(wp) :: phi0 = 0.0_wp          !! initial angle (at rest) from the downward vertical
        logical :: sparse = .false.        !! report ∂F/∂y as CSC
        logical :: sparse_mass = .false.   !! report M as CSC
        logical :: projection = .false.    !! project onto both constraints after steps
    contains
        procedure :: rhs => pendulum_rhs
        procedure :: jacobian_storage => pendulum_jacobian_storage
        procedure :: jacobian_dense => pendulum_jacobian_dense
        procedure :: jacobian_pattern => pendulum_jacobian_pattern
        procedure :: jacobian_sparse => pendulum_jacobian_sparse
        procedure :: mass_storage => pendulum_mass_storage
        procedure :: mass_dense => pendulum_mass_dense
        procedure :: mass_sparse => pendulum_mass_sparse
        procedure :: index_classes => pendulum_index_classes
        procedure :: differential_flags => pendulum_differential_flags
        procedure :: has_projection => pendulum_has_projection
        procedure :: project => pendulum_project
        procedure :: consistent_initial => pendulum_consistent_initial
    end type pendulum_t

    !> The pendulum as a mechanical problem: q = (x, y), v = (u, v), T = I,
    !> M = m I, f = (0, -m g), one constraint g(q) = (x² + y² - L²)/2.
    type, extends(mechanical_problem_t), public :: pendulum_mechanical_t
        real(wp) :: point_mass = pendulum_default_mass
        real(wp) :: length = pendulum_default_length
        real(wp) :: gravity = pendulum_default_gravity
    contains
        procedure :: kinematics => mechanical_kinematics
        procedure :: mass => mechanical_mass
        procedure :: forces => mechanical_forces
        procedure :: constraint => mechanical_constraint
        procedure :: constraint_jacobian => mechanical_constraint_jacobian
        procedure :: constraint_curvature => mechanical_constraint_curvature
        procedure :: kinematics_derivative => mechanical_zero_nq_derivative
        procedure :: mass_derivative => mechanical_zero_nq_derivative
        procedure :: force_derivatives => mechanical_force_derivatives
        procedure :: constraint_position_jacobian => mechanical_constraint_position_jacobian
        procedure :: constraint_jacobian_derivatives => mechanical_constraint_jacobian_derivatives
        procedure :: constraint_time_derivative_jacobian => mechanical_zero_time_jacobian
        procedure :: constraint_curvature_derivatives => mechanical_curvature_derivatives
    end type pendulum_mechanical_t

    public :: new_pendulum, pendulum_initial, pendulum_reference
    public :: pendulum_position_residual, pendulum_velocity_residual
    public :: pendulum_angle_exact, pendulum_angle_rk4
    public :: new_pendulum_mechanical, pendulum_mechanical_initial

contains

    !> The pendulum in formulation `formulation` (pendulum_index1/2/3 or
    !> pendulum_ggl), starting at rest from angle `phi0`. On bad arguments
    !> `status` says why and the problem has n = 0.
    function new_pendulum(formulation, phi0, mass, length, gravity, sparse, sparse_mass, &
                          projection, status) result(problem)
        integer, intent(in) :: formulation           !! pendulum_index1/2/3, pendulum_ggl
        real(wp), intent(in) :: phi0                 !! initial angle [rad] from the vertical
        real(wp), intent(in), optional :: mass       !! m > 0 (default 1)
        real(wp), intent(in), optional :: length     !! L > 0 (default 1)
        real(wp), intent(in), optional :: gravity    !! g >= 0 (default 9.81)
        logical, intent(in), optional :: sparse      !! Jacobian as CSC (default dense)
        logical, intent(in), optional :: sparse_mass !! mass matrix as CSC (default dense)
        logical, intent(in), optional :: projection  !! offer the projection hook
        type(status_t), intent(out), optional :: status
        type(pendulum_t) :: problem
        type(status_t) :: local

        problem%formulation = formulation
        problem%phi0 = phi0
        if (present(mass)) problem%point_mass = mass
        if (present(length)) problem%length = length
        if (present(gravity)) problem%gravity = gravity
        if (present(sparse)) problem%sparse = sparse
        if (present(sparse_mass)) problem%sparse_mass = sparse_mass
        if (present(projection)) problem%projection = projection
        call check_parameters(problem%point_mass, problem%length, problem%gravity, local)
        if (local%ok()) then
            select case (formulation)
            case (pendulum_index1, pendulum_index2, pendulum_index3)
                problem%n = 5
            case (pendulum_ggl)
                problem%n = 6
            case default
                call local%set(status_bad_input, 'pendulum: formulation must be &
                    &pendulum_index1, pendulum_index2, pendulum_index3 or pendulum_ggl')
            end select
        end if
        if (present(status)) status = local
    end function new_pendulum

    subroutine check_parameters(mass, length, gravity, status)
        real(wp), intent(in) :: mass, length, gravity
        type(status_t), intent(inout) :: status
        character(len=120) :: msg
        if (.not. (mass > 0.0_wp .and. length > 0.0_wp .and. gravity >= 0.0_wp)) then
            write (msg, '(a,3(es10.3,1x),a)') 'pendulum: mass, length, gravity = ', &
                mass, length, gravity, ': need m > 0, L > 0, g >= 0'
            call status%set(status_bad_input, trim(msg))
        end if
    end subroutine check_parameters

    !> Consistent initial values at rest from phi0: positions on the circle,
    !> zero velocity, λ = m g cos(φ0) / L, μ = 0.
    subroutine pendulum_initial(problem, y0)
        class(pendulum_t), intent(in) :: problem
        real(wp), intent(out) :: y0(:) !! size problem%n
        call angle_state(problem, problem%phi0, 0.0_wp, y0)
    end subroutine pendulum_initial

    !> The exact solution y(t) in the problem's layout (elliptic functions).
    subroutine pendulum_reference(problem, t, y, status)
        class(pendulum_t), intent(in) :: problem
        real(wp), intent(in) :: t
        real(wp), intent(out) :: y(:) !! size problem%n
        type(status_t), intent(out) :: status
        real(wp) :: phi, dphi
        call pendulum_angle_exact(problem%phi0, sqrt(problem%gravity / problem%length), t, &
                                  phi, dphi, status)
        if (status%ok()) call angle_state(problem, phi, dphi, y)
    end subroutine pendulum_reference

    !> The Cartesian state of angle φ and angular velocity φ'; λ from the
    !> acceleration-level constraint, μ = 0.
    pure subroutine angle_state(problem, phi, dphi, y)
        class(pendulum_t), intent(in) :: problem
        real(wp), intent(in) :: phi, dphi
        real(wp), intent(out) :: y(:)
        real(wp) :: l
        l = problem%length
        y = 0.0_wp
        y(1) = l * sin(phi)
        y(2) = -l * cos(phi)
        y(3) = l * cos(phi) * dphi
        y(4) = l * sin(phi) * dphi
        ! λ = m (u² + v² - g y) / L² with u² + v² = L² φ'², -g y = g L cos φ
        y(5) = problem%point_mass * (dphi**2 + problem%gravity * cos(phi) / l)
    end subroutine angle_state

    !> Position constraint residual g(q) = (x² + y² - L²)/2 of a state.
    pure real(wp) function pendulum_position_residual(problem, y) result(r)
        class(pendulum_t), intent(in) :: problem
        real(wp), intent(in) :: y(:)
        r = 0.5_wp * (y(1)**2 + y(2)**2 - problem%length**2)
    end function pendulum_position_residual

    !> Velocity constraint residual G v = x u + y v of a state.
    pure real(wp) function pendulum_velocity_residual(problem, y) result(r)
        class(pendulum_t), intent(in) :: problem
        real(wp), intent(in) :: y(:)
        r = y(1) * y(3) + y(2) * y(4)
    end function pendulum_velocity_residual

    subroutine pendulum_rhs(self, t, y, f, status)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        real(wp) :: px, py, vx, vy, lam, m, g
        px = y(1); py = y(2); vx = y(3); vy = y(4); lam = y(5)
        m = self%point_mass
        g = self%gravity
        f(1) = vx
        f(2) = vy
        f(3) = -px * lam
        f(4) = -m * g - py * lam
        select case (self%formulation)
        case (pendulum_index3)
            f(5) = 0.5_wp * (px**2 + py**2 - self%length**2)
        case (pendulum_index2)
            f(5) = px * vx + py * vy
        case (pendulum_index1)
            f(5) = vx**2 + vy**2 - g * py - (px**2 + py**2) * lam / m
        case (pendulum_ggl)
            f(1) = vx - px * y(6)
            f(2) = vy - py * y(6)
            f(5) = px * vx + py * vy
            f(6) = 0.5_wp * (px**2 + py**2 - self%length**2)
        end select
    end subroutine pendulum_rhs

    integer function pendulum_jacobian_storage(self)
        class(pendulum_t), intent(in) :: self
        pendulum_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function pendulum_jacobian_storage

    subroutine pendulum_jacobian_dense(self, t, y, jac, status)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: px, py, vx, vy, lam, m, g
        px = y(1); py = y(2); vx = y(3); vy = y(4); lam = y(5)
        m = self%point_mass
        g = self%gravity
        jac = 0.0_wp
        jac(1, 3) = 1.0_wp
        jac(2, 4) = 1.0_wp
        jac(3, 1) = -lam
        jac(3, 5) = -px
        jac(4, 2) = -lam
        jac(4, 5) = -py
        select case (self%formulation)
        case (pendulum_index3)
            jac(5, 1:2) = [px, py]
        case (pendulum_index2)
            jac(5, 1:4) = [vx, vy, px, py]
        case (pendulum_index1)
            jac(5, :) = [-2.0_wp * px * lam / m, -g - 2.0_wp * py * lam / m, &
                         2.0_wp * vx, 2.0_wp * vy, -(px**2 + py**2) / m]
        case (pendulum_ggl)
            jac(1, 1) = -y(6)
            jac(1, 6) = -px
            jac(2, 2) = -y(6)
            jac(2, 6) = -py
            jac(5, 1:4) = [vx, vy, px, py]
            jac(6, 1:2) = [px, py]
        end select
    end subroutine pendulum_jacobian_dense

    !> The structural non-zeros of ∂F/∂y, emitted column by column with rows
    !> ascending, i.e. in CSC slot order: the pattern built from them maps
    !> entry k to slot k, so values need no scatter.
    subroutine pendulum_entries(self, y, rows, cols, vals, nnz)
        class(pendulum_t), intent(in) :: self
        real(wp), intent(in) :: y(:)
        integer, intent(out) :: rows(max_entries), cols(max_entries)
        real(wp), intent(out) :: vals(max_entries)
        integer, intent(out) :: nnz
        real(wp) :: px, py, vx, vy, lam, mu, m, g
        logical :: ggl, index1, velocity_row
        px = y(1); py = y(2); vx = y(3); vy = y(4); lam = y(5)
        mu = 0.0_wp
        if (self%n > 5) mu = y(6)
        m = self%point_mass
        g = self%gravity
        ggl = self%formulation == pendulum_ggl
        index1 = self%formulation == pendulum_index1
        ! rows of the form x u + y v (index 2 and GGL row 5)
        velocity_row = ggl .or. self%formulation == pendulum_index2
        nnz = 0
        ! column x
        if (ggl) call put(1, 1, -mu)
        call put(3, 1, -lam)
        if (velocity_row) call put(5, 1, vx)
        if (index1) call put(5, 1, -2.0_wp * px * lam / m)
        if (self%formulation == pendulum_index3) call put(5, 1, px)
        if (ggl) call put(6, 1, px)
        ! column y
        if (ggl) call put(2, 2, -mu)
        call put(4, 2, -lam)
        if (velocity_row) call put(5, 2, vy)
        if (index1) call put(5, 2, -g - 2.0_wp * py * lam / m)
        if (self%formulation == pendulum_index3) call put(5, 2, py)
        if (ggl) call put(6, 2, py)
        ! column u
        call put(1, 3, 1.0_wp)
        if (velocity_row) call put(5, 3, px)
        if (index1) call put(5, 3, 2.0_wp * vx)
        ! column v
        call put(2, 4, 1.0_wp)
        if (velocity_row) call put(5, 4, py)
        if (index1) call put(5, 4, 2.0_wp * vy)
        ! column λ
        call put(3, 5, -px)
        call put(4, 5, -py)
        if (index1) call put(5, 5, -(px**2 + py**2) / m)
        ! column μ
        if (ggl) then
            call put(1, 6, -px)
            call put(2, 6, -py)
        end if
    contains
        subroutine put(i, j, value)
            integer, intent(in) :: i, j
            real(wp), intent(in) :: value
            nnz = nnz + 1
            rows(nnz) = i
            cols(nnz) = j
            vals(nnz) = value
        end subroutine put
    end subroutine pendulum_entries

    subroutine pendulum_jacobian_pattern(self, pattern, status)
        class(pendulum_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer :: rows(max_entries), cols(max_entries), nnz
        real(wp) :: vals(max_entries), y(6)
        y = 0.0_wp
        call pendulum_entries(self, y, rows, cols, vals, nnz)
        call pattern%build(self%n, self%n, rows(:nnz), cols(:nnz), status)
    end subroutine pendulum_jacobian_pattern

    subroutine pendulum_jacobian_sparse(self, t, y, values, status)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: rows(max_entries), cols(max_entries), nnz
        real(wp) :: vals(max_entries)
        call pendulum_entries(self, y, rows, cols, vals, nnz)
        values(:nnz) = vals(:nnz)
    end subroutine pendulum_jacobian_sparse

    integer function pendulum_mass_storage(self)
        class(pendulum_t), intent(in) :: self
        pendulum_mass_storage = merge(storage_sparse, storage_dense, self%sparse_mass)
    end function pendulum_mass_storage

    !> M = diag(1, 1, m, m, 0[, 0]).
    subroutine pendulum_mass_dense(self, m)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        m = 0.0_wp
        m(1, 1) = 1.0_wp
        m(2, 2) = 1.0_wp
        m(3, 3) = self%point_mass
        m(4, 4) = self%point_mass
    end subroutine pendulum_mass_dense

    !> M as CSC with its four non-zero diagonal entries.
    subroutine pendulum_mass_sparse(self, m, status)
        class(pendulum_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        call m%build(self%n, self%n, [1, 2, 3, 4], [1, 2, 3, 4], status)
        if (status%ok()) m%values = [1.0_wp, 1.0_wp, self%point_mass, self%point_mass]
    end subroutine pendulum_mass_sparse

    !> docs/theory.md §3 with constant M and y = (q, v, λ[, μ]).
    subroutine pendulum_index_classes(self, classes)
        class(pendulum_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        classes = 1
        select case (self%formulation)
        case (pendulum_index3)
            classes(3:4) = 2
            classes(5) = 3
        case (pendulum_index2)
            classes(5) = 2
        case (pendulum_ggl)
            classes(5:6) = 2
        end select
    end subroutine pendulum_index_classes

    !> q and v differential; λ (and μ) algebraic.
    subroutine pendulum_differential_flags(self, flags)
        class(pendulum_t), intent(in) :: self
        logical, intent(out) :: flags(:)
        flags = .false.
        flags(1:4) = .true.
    end subroutine pendulum_differential_flags

    logical function pendulum_has_projection(self)
        class(pendulum_t), intent(in) :: self
        pendulum_has_projection = self%projection
    end function pendulum_has_projection

    !> Orthogonal projection onto g = 0 (radial: the nearest point of the
    !> circle), then onto G v = 0 at the projected q (eqs. 11-12 solved exactly).
    subroutine pendulum_project(self, t, y, status)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:)
        type(status_t), intent(inout) :: status
        call project_state(self, y, status)
    end subroutine pendulum_project

    subroutine project_state(self, y, status)
        class(pendulum_t), intent(in) :: self
        real(wp), intent(inout) :: y(:)
        type(status_t), intent(inout) :: status
        real(wp) :: r, radial
        r = hypot(y(1), y(2))
        if (.not. (r > 0.0_wp)) then
            call status%set(status_bad_input, 'pendulum: cannot project q = (0, 0) &
                &onto the circle x² + y² = L²')
            return
        end if
        y(1:2) = (self%length / r) * y(1:2)
        radial = (y(1) * y(3) + y(2) * y(4)) / self%length**2
        y(3:4) = y(3:4) - radial * y(1:2)
    end subroutine project_state

    !> Project (q, v) onto both constraints, set λ from the acceleration-level
    !> constraint, μ = 0, and y' from the equations; λ' = m (2 u u' + 2 v v'
    !> - g v) / L² is the derivative of λ along the solution (x u + y v = 0).
    subroutine pendulum_consistent_initial(self, t, y, yp, status)
        class(pendulum_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        type(status_t), intent(inout) :: status
        real(wp) :: m, g, l2
        call project_state(self, y, status)
        if (.not. status%ok()) return
        m = self%point_mass
        g = self%gravity
        l2 = self%length**2
        y(5) = m * (y(3)**2 + y(4)**2 - g * y(2)) / l2
        if (self%n > 5) y(6) = 0.0_wp
        yp = 0.0_wp
        yp(1:2) = y(3:4)
        yp(3) = -y(1) * y(5) / m
        yp(4) = -g - y(2) * y(5) / m
        yp(5) = m * (2.0_wp * (y(3) * yp(3) + y(4) * yp(4)) - g * y(4)) / l2
    end subroutine pendulum_consistent_initial

    !> Exact angle φ(t) and φ'(t) of φ'' = -ω² sin φ, φ(0) = phi0, φ'(0) = 0,
    !> by Jacobi's elliptic functions (module header); |phi0| < π.
    subroutine pendulum_angle_exact(phi0, omega, t, phi, dphi, status)
        real(wp), intent(in) :: phi0   !! initial angle [rad], |phi0| < π
        real(wp), intent(in) :: omega  !! sqrt(g/L) > 0
        real(wp), intent(in) :: t      !! time
        real(wp), intent(out) :: phi   !! φ(t)
        real(wp), intent(out) :: dphi  !! φ'(t)
        type(status_t), intent(out) :: status
        real(wp) :: a(0:max_agm_levels), c(0:max_agm_levels), b, an, k, kc, quarter, w, am
        integer :: levels, n
        character(len=120) :: msg

        phi = 0.0_wp
        dphi = 0.0_wp
        if (.not. (abs(phi0) < pi .and. omega > 0.0_wp)) then
            write (msg, '(a,es12.5,a,es12.5,a)') 'pendulum reference: phi0 = ', phi0, &
                ', omega = ', omega, ': need |phi0| < pi (libration) and omega > 0'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        k = sin(0.5_wp * phi0)
        ! complementary modulus from the angle, accurate as φ0 -> ±π
        kc = cos(0.5_wp * phi0)
        ! AGM of (1, k') with c_n = (a_{n-1} - b_{n-1})/2 [A&S §17.6]
        a(0) = 1.0_wp
        b = kc
        c(0) = abs(k)
        levels = 0
        do while (c(levels) > epsilon(1.0_wp) * a(levels))
            if (levels == max_agm_levels) then
                call status%set(status_bad_input, 'pendulum reference: AGM did not converge')
                return
            end if
            an = 0.5_wp * (a(levels) + b)
            c(levels + 1) = 0.5_wp * (a(levels) - b)
            b = sqrt(a(levels) * b)
            levels = levels + 1
            a(levels) = an
        end do
        quarter = pi / (2.0_wp * a(levels)) ! K(k) = π / (2 AGM(1, k')) [A&S §17.6]
        ! sn and cn have period 4K: reduce the argument to keep the amplitude small.
        w = modulo(omega * t + quarter, 4.0_wp * quarter)
        ! amplitude am(w) by the descending recursion [A&S §16.4]
        am = 2.0_wp**levels * a(levels) * w
        do n = levels, 1, -1
            am = 0.5_wp * (am + asin(c(n) / a(n) * sin(am)))
        end do
        phi = 2.0_wp * asin(k * sin(am))
        dphi = 2.0_wp * k * omega * cos(am)
    end subroutine pendulum_angle_exact

    !> φ(t), φ'(t) of φ'' = -ω² sin φ by `nsteps` classical Runge-Kutta steps
    !> (order 4) from (phi0, dphi0); the independent second reference method.
    pure subroutine pendulum_angle_rk4(phi0, dphi0, omega, t, nsteps, phi, dphi)
        real(wp), intent(in) :: phi0, dphi0 !! initial angle and angular velocity
        real(wp), intent(in) :: omega       !! sqrt(g/L)
        real(wp), intent(in) :: t           !! final time (from 0)
        integer, intent(in) :: nsteps       !! number of equal steps (>= 1)
        real(wp), intent(out) :: phi, dphi
        real(wp) :: h, w2, k1p, k1v, k2p, k2v, k3p, k3v, k4p, k4v
        integer :: i
        phi = phi0
        dphi = dphi0
        if (nsteps < 1) return
        h = t / nsteps
        w2 = omega**2
        do i = 1, nsteps
            k1p = dphi
            k1v = -w2 * sin(phi)
            k2p = dphi + 0.5_wp * h * k1v
            k2v = -w2 * sin(phi + 0.5_wp * h * k1p)
            k3p = dphi + 0.5_wp * h * k2v
            k3v = -w2 * sin(phi + 0.5_wp * h * k2p)
            k4p = dphi + h * k3v
            k4v = -w2 * sin(phi + h * k3p)
            phi = phi + h / 6.0_wp * (k1p + 2.0_wp * (k2p + k3p) + k4p)
            dphi = dphi + h / 6.0_wp * (k1v + 2.0_wp * (k2v + k3v) + k4v)
        end do
    end subroutine pendulum_angle_rk4

    !> The mechanical pendulum (nq = nv = 2, nc = 1). Arguments checked as
    !> for new_pendulum.
    function new_pendulum_mechanical(mass, length, gravity, status) result(problem)
        real(wp), intent(in), optional :: mass    !! m > 0 (default 1)
        real(wp), intent(in), optional :: length  !! L > 0 (default 1)
        real(wp), intent(in), optional :: gravity !! g >= 0 (default 9.81)
        type(status_t), intent(out), optional :: status
        type(pendulum_mechanical_t) :: problem
        type(status_t) :: local
        if (present(mass)) problem%point_mass = mass
        if (present(length)) problem%length = length
        if (present(gravity)) problem%gravity = gravity
        call check_parameters(problem%point_mass, problem%length, problem%gravity, local)
        if (local%ok()) then
            problem%nq = 2
            problem%nv = 2
            problem%nc = 1
        end if
        if (present(status)) status = local
    end function new_pendulum_mechanical

    !> Consistent initial values at rest from phi0 for the mechanical form.
    pure subroutine pendulum_mechanical_initial(problem, phi0, q, v, lambda)
        class(pendulum_mechanical_t), intent(in) :: problem
        real(wp), intent(in) :: phi0
        real(wp), intent(out) :: q(:), v(:), lambda(:) !! sizes 2, 2, 1
        q = [problem%length * sin(phi0), -problem%length * cos(phi0)]
        v = 0.0_wp
        lambda = problem%point_mass * problem%gravity * cos(phi0) / problem%length
    end subroutine pendulum_mechanical_initial

    subroutine mechanical_kinematics(self, t, q, w, qdot, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        qdot = w
    end subroutine mechanical_kinematics

    subroutine mechanical_mass(self, t, q, m, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        m = 0.0_wp
        m(1, 1) = self%point_mass
        m(2, 2) = self%point_mass
    end subroutine mechanical_mass

    subroutine mechanical_forces(self, t, q, v, f, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        f(1) = 0.0_wp
        f(2) = -self%point_mass * self%gravity
    end subroutine mechanical_forces

    subroutine mechanical_constraint(self, t, q, g, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        g(1) = 0.5_wp * (q(1)**2 + q(2)**2 - self%length**2)
    end subroutine mechanical_constraint

    subroutine mechanical_constraint_jacobian(self, t, q, gmat, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
        gmat(1, 1) = q(1)
        gmat(1, 2) = q(2)
    end subroutine mechanical_constraint_jacobian

    !> γ = (G v)_q T v = u² + v² (scleronomic: no time terms).
    subroutine mechanical_constraint_curvature(self, t, q, v, gamma, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
        gamma(1) = v(1)**2 + v(2)**2
    end subroutine mechanical_constraint_curvature

    !> T = I and M = m I are constant: ∂(T w)/∂q = ∂(M a)/∂q = 0.
    subroutine mechanical_zero_nq_derivative(self, t, q, w, dq, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
    end subroutine mechanical_zero_nq_derivative

    !> Gravity is constant: f_q = f_v = 0.
    subroutine mechanical_force_derivatives(self, t, q, v, fq, fv, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        fq = 0.0_wp
        fv = 0.0_wp
    end subroutine mechanical_force_derivatives

    !> g_q = (x, y) = G (T = I).
    subroutine mechanical_constraint_position_jacobian(self, t, q, gq, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gq(:, :)
        type(status_t), intent(inout) :: status
        gq(1, 1:2) = q(1:2)
    end subroutine mechanical_constraint_position_jacobian

    !> ∂(G w)/∂q = wᵀ and ∂(Gᵀλ)/∂q = λ I.
    subroutine mechanical_constraint_jacobian_derivatives(self, t, q, w, lambda, gwq, gtlq, &
                                                          status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:, :), gtlq(:, :)
        type(status_t), intent(inout) :: status
        gwq(1, 1:2) = w(1:2)
        gtlq = 0.0_wp
        gtlq(1, 1) = lambda(1)
        gtlq(2, 2) = lambda(1)
    end subroutine mechanical_constraint_jacobian_derivatives

    !> Scleronomic, g_I = 0.
    subroutine mechanical_zero_time_jacobian(self, t, q, dq, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
    end subroutine mechanical_zero_time_jacobian

    !> γ = u² + v²: γ_q = 0, γ_v = 2 vᵀ.
    subroutine mechanical_curvature_derivatives(self, t, q, v, gq, gv, status)
        class(pendulum_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:, :), gv(:, :)
        type(status_t), intent(inout) :: status
        gq = 0.0_wp
        gv(1, 1:2) = 2.0_wp * v(1:2)
    end subroutine mechanical_curvature_derivatives
end module flexmbs_problems_pendulum
