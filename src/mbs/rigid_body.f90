!> Rigid bodies in absolute coordinates (docs/theory.md §2).
!>
!> Body i has positions q_i = (r, p): centre of mass r (global) and a unit
!> quaternion p (scalar first, body to global A(p), flexmbs_mbs_rotation),
!> and velocities v_i = (ṙ, ω'): the centre's velocity and the body-fixed
!> angular velocity. Hence q' = T(q) v with T_i = diag(I₃, L(p)ᵀ/2)
!> (ṗ = L(p)ᵀ ω'/2 is tangent to the unit sphere, so |p| is an invariant).
!> Newton-Euler with constant mass m and body-fixed inertia J:
!>
!>   m r̈ = m g + F,     J ω̇' = τ' - ω' × J ω'    (gyroscopic term),
!>
!> with gravity g, a constant global force F and a constant body-fixed torque
!> τ'. M = diag(m I₃, J) is constant. `rigid_bodies_t` is a set of free
!> bodies (no constraints) as a `mechanical_problem_t`; its `normalize`
!> rescales each quaternion to unit length, which the formulations' projection
!> calls, so that the formulation keeps |p| = 1.
module flexmbs_mbs_rigid_body
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_rotation, only: skew, cross, quat_l, rotation_matrix, quat_normalize
    implicit none
    private

    integer, parameter, public :: rigid_body_nq = 7 !! positions per body (r, p)
    integer, parameter, public :: rigid_body_nv = 6 !! velocities per body (ṙ, ω')

    !> One rigid body's constant data.
    type, public :: rigid_body_t
        real(wp) :: mass = 1.0_wp
        real(wp) :: inertia(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, &
            0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3]) !! body-fixed, about the centre of mass
        real(wp) :: force(3) = 0.0_wp  !! applied global force at the centre of mass
        real(wp) :: torque(3) = 0.0_wp !! applied body-fixed torque
        !> a massless frame that constraints carry (flexmbs_mbs_node_frame):
        !> mass, inertia, force and torque are taken as zero
        logical :: frame = .false.
    end type rigid_body_t

    !> Free rigid bodies under gravity as a mechanical problem (nc = 0).
    type, extends(mechanical_problem_t), public :: rigid_bodies_t
        type(rigid_body_t), allocatable :: bodies(:)
        real(wp) :: gravity(3) = 0.0_wp !! global gravitational acceleration
    contains
        procedure :: kinematics => bodies_kinematics
        procedure :: mass => bodies_mass
        procedure :: forces => bodies_forces
        procedure :: constraint => bodies_constraint
        procedure :: constraint_jacobian => bodies_constraint_jacobian
        procedure :: constraint_curvature => bodies_constraint_curvature
        procedure :: normalize => bodies_normalize
        procedure :: kinematics_derivative => bodies_kinematics_derivative
        procedure :: mass_derivative => bodies_mass_derivative
        procedure :: force_derivatives => bodies_force_derivatives
    end type rigid_bodies_t

    public :: new_rigid_bodies, rigid_body_energy, rigid_body_momenta, quaternion_rate_derivative, &
        gyroscopic_derivative

contains

    !> The bodies `bodies` under `gravity`; masses must be positive and the
    !> inertias symmetric positive definite (checked by Cholesky), except for
    !> frames (massless; only constraints can hold them).
    function new_rigid_bodies(bodies, gravity, status) result(self)
        type(rigid_body_t), intent(in) :: bodies(:)
        real(wp), intent(in), optional :: gravity(3)
        type(status_t), intent(out) :: status
        type(rigid_bodies_t) :: self
        integer :: i
        character(len=120) :: msg
        do i = 1, size(bodies)
            if (bodies(i)%frame) cycle
            if (.not. (bodies(i)%mass > 0.0_wp) .or. .not. spd(bodies(i)%inertia)) then
                write (msg, '(a,i0,a,es10.3,a)') 'rigid body ', i, ': mass = ', &
                    bodies(i)%mass, ': need mass > 0 and a symmetric positive definite inertia'
                call status%set(status_bad_input, trim(msg))
                return
            end if
        end do
        self%bodies = bodies
        do i = 1, size(bodies)
            if (.not. bodies(i)%frame) cycle
            self%bodies(i)%mass = 0.0_wp
            self%bodies(i)%inertia = 0.0_wp
            self%bodies(i)%force = 0.0_wp
            self%bodies(i)%torque = 0.0_wp
        end do
        if (present(gravity)) self%gravity = gravity
        self%nq = rigid_body_nq * size(bodies)
        self%nv = rigid_body_nv * size(bodies)
        self%nc = 0
    end function new_rigid_bodies

    !> Symmetric and positive definite (3x3 Cholesky succeeds).
    pure logical function spd(j)
        real(wp), intent(in) :: j(3, 3)
        real(wp) :: l11, l21, l31, l22, l32, d33
        spd = .false.
        if (any(abs(j - transpose(j)) > 1.0e-12_wp * maxval(abs(j)))) return
        if (.not. (j(1, 1) > 0.0_wp)) return
        l11 = sqrt(j(1, 1))
        l21 = j(2, 1) / l11
        l31 = j(3, 1) / l11
        if (.not. (j(2, 2) - l21**2 > 0.0_wp)) return
        l22 = sqrt(j(2, 2) - l21**2)
        l32 = (j(3, 2) - l31 * l21) / l22
        d33 = j(3, 3) - l31**2 - l32**2
        spd = d33 > 0.0_wp
    end function spd

    !> Kinetic plus potential energy of all bodies (potential -m g·r).
    pure real(wp) function rigid_body_energy(self, q, v) result(e)
        class(rigid_bodies_t), intent(in) :: self
        real(wp), intent(in) :: q(:), v(:)
        integer :: i, iq, iv
        e = 0.0_wp
        do i = 1, size(self%bodies)
            iq = rigid_body_nq * (i - 1)
            iv = rigid_body_nv * (i - 1)
            associate (b => self%bodies(i), w => v(iv + 4:iv + 6))
                e = e + 0.5_wp * b%mass * sum(v(iv + 1:iv + 3)**2) &
                    + 0.5_wp * dot_product(w, matmul(b%inertia, w)) &
                    - b%mass * dot_product(self%gravity, q(iq + 1:iq + 3))
            end associate
        end do
    end function rigid_body_energy

    !> Total linear momentum and angular momentum about the global origin.
    pure subroutine rigid_body_momenta(self, q, v, linear, angular)
        class(rigid_bodies_t), intent(in) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: linear(3), angular(3)
        real(wp) :: p(3)
        integer :: i, iq, iv
        linear = 0.0_wp
        angular = 0.0_wp
        do i = 1, size(self%bodies)
            iq = rigid_body_nq * (i - 1)
            iv = rigid_body_nv * (i - 1)
            associate (b => self%bodies(i))
                p = b%mass * v(iv + 1:iv + 3)
                linear = linear + p
                angular = angular + cross(q(iq + 1:iq + 3), p) &
                    + matmul(rotation_matrix(q(iq + 4:iq + 7)), &
                             matmul(b%inertia, v(iv + 4:iv + 6)))
            end associate
        end do
    end subroutine rigid_body_momenta

    !> ṙ = w_r, ṗ = L(p)ᵀ w_ω / 2.
    subroutine bodies_kinematics(self, t, q, w, qdot, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        integer :: i, iq, iv
        do i = 1, size(self%bodies)
            iq = rigid_body_nq * (i - 1)
            iv = rigid_body_nv * (i - 1)
            qdot(iq + 1:iq + 3) = w(iv + 1:iv + 3)
            qdot(iq + 4:iq + 7) = 0.5_wp * matmul(w(iv + 4:iv + 6), quat_l(q(iq + 4:iq + 7)))
        end do
    end subroutine bodies_kinematics

    !> ∂(L(p)ᵀ ω / 2)/∂p = [0, -ωᵀ; ω, -skew(ω)] / 2 (Lᵀω = (-e·ω, e0 ω + e × ω)).
    subroutine bodies_kinematics_derivative(self, t, q, w, dq, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        integer :: i, iq, iv
        dq = 0.0_wp
        do i = 1, size(self%bodies)
            iq = rigid_body_nq * (i - 1)
            iv = rigid_body_nv * (i - 1)
            dq(iq + 4:iq + 7, iq + 4:iq + 7) = quaternion_rate_derivative(w(iv + 4:iv + 6))
        end do
    end subroutine bodies_kinematics_derivative

    !> ∂(L(p)ᵀ ω / 2)/∂p, 4 x 4 (it does not depend on p).
    pure function quaternion_rate_derivative(om) result(d)
        real(wp), intent(in) :: om(3)
        real(wp) :: d(4, 4)
        d(1, 1) = 0.0_wp
        d(1, 2:4) = -0.5_wp * om
        d(2:4, 1) = 0.5_wp * om
        d(2:4, 2:4) = -0.5_wp * skew(om)
    end function quaternion_rate_derivative

    !> ∂(-ω × J ω)/∂ω = skew(J ω) - skew(ω) J.
    pure function gyroscopic_derivative(inertia, om) result(d)
        real(wp), intent(in) :: inertia(3, 3), om(3)
        real(wp) :: d(3, 3)
        d = skew(matmul(inertia, om)) - matmul(skew(om), inertia)
    end function gyroscopic_derivative

    !> M = diag(m₁ I₃, J₁, m₂ I₃, J₂, ...).
    subroutine bodies_mass(self, t, q, m, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        integer :: i, iv, k
        m = 0.0_wp
        do i = 1, size(self%bodies)
            iv = rigid_body_nv * (i - 1)
            do k = 1, 3
                m(iv + k, iv + k) = self%bodies(i)%mass
            end do
            m(iv + 4:iv + 6, iv + 4:iv + 6) = self%bodies(i)%inertia
        end do
    end subroutine bodies_mass

    !> M is constant.
    subroutine bodies_mass_derivative(self, t, q, w, dq, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
    end subroutine bodies_mass_derivative

    !> f = (m g + F, τ' - ω' × J ω') per body.
    subroutine bodies_forces(self, t, q, v, f, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        integer :: i, iv
        do i = 1, size(self%bodies)
            iv = rigid_body_nv * (i - 1)
            associate (b => self%bodies(i), om => v(iv + 4:iv + 6))
                f(iv + 1:iv + 3) = b%mass * self%gravity + b%force
                f(iv + 4:iv + 6) = b%torque - cross(om, matmul(b%inertia, om))
            end associate
        end do
    end subroutine bodies_forces

    !> f_q = 0; ∂(-ω × J ω)/∂ω = skew(J ω) - skew(ω) J.
    subroutine bodies_force_derivatives(self, t, q, v, fq, fv, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        integer :: i, iv
        fq = 0.0_wp
        fv = 0.0_wp
        do i = 1, size(self%bodies)
            iv = rigid_body_nv * (i - 1)
            fv(iv + 4:iv + 6, iv + 4:iv + 6) = gyroscopic_derivative(self%bodies(i)%inertia, &
                                                                     v(iv + 4:iv + 6))
        end do
    end subroutine bodies_force_derivatives

    !> No constraints.
    subroutine bodies_constraint(self, t, q, g, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
    end subroutine bodies_constraint

    subroutine bodies_constraint_jacobian(self, t, q, gmat, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
    end subroutine bodies_constraint_jacobian

    subroutine bodies_constraint_curvature(self, t, q, v, gamma, status)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
    end subroutine bodies_constraint_curvature

    !> p ← p / |p| for every body.
    subroutine bodies_normalize(self, q)
        class(rigid_bodies_t), intent(inout) :: self
        real(wp), intent(inout) :: q(:)
        integer :: i, iq
        do i = 1, size(self%bodies)
            iq = rigid_body_nq * (i - 1)
            q(iq + 4:iq + 7) = quat_normalize(q(iq + 4:iq + 7))
        end do
    end subroutine bodies_normalize
end module flexmbs_mbs_rigid_body
