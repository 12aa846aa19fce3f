!> A modal body in a floating frame of reference (docs/theory.md §2.7): a
!> rigid frame (position r of the reference centre of mass, unit quaternion
!> p) carrying small elastic deformations u = Σ_k η_k Φ_k in the modal
!> basis of flexmbs_fe_modal_basis, with the inertia invariants of
!> flexmbs_fe_modal_invariants.
!>
!> Coordinates q = (r, p, η), velocities v = (ṙ, ω′, η̇): ṙ global, ω′ the
!> frame's body-fixed angular velocity, q' = T v with T = diag(I₃,
!> L(p)ᵀ/2, I) as for a rigid body. A material point at X (from the centre
!> of mass) is at x = r + A(p) s, s = X + Φ(X) η, with velocity ẋ = ṙ −
!> A s̃ ω′ + A Φ η̇. The kinetic energy ½ ∫ρ |ẋ|² dV gives, in the
!> mean-axis frame of the basis (∫ρ Φ = 0, ∫ρ X × Φ = 0, hence ∫ρ s = 0
!> for every η):
!>
!>   M(η) = [m I₃  0        0     ]
!>          [0     J(η)     H(η)  ]   J = tr(P) I − P, P = ∫ρ s sᵀ,
!>          [0     H(η)ᵀ    M_ηη  ]   H_l = ∫ρ s × Φ_l, M_ηη,kl = ∫ρ Φ_k·Φ_l,
!>
!> and by d'Alembert's principle the forces (Q = −∫ρ Lᵀ A a_v, a_v = ω̃ω̃ s
!> + 2 ω̃ Φ η̇ the velocity-dependent acceleration in the frame), with
!> A_l = ∫ρ s Φ_lᵀ and B = Σ_l η̇_l A_l:
!>
!>   f_r = m g + F,
!>   f_ω = τ′ − ω × J ω − 2 (tr(B) ω − Bᵀ ω),
!>   f_l = −ωᵀ A_l ω + |ω|² tr(A_l) − 2 ω · Σ_k η̇_k (∫ρ Φ_k × Φ_l)
!>         − ω_l² η_l − (D η̇)_l,
!>
!> elastic and damping forces from the reduced K = diag(ω_l²) and D of the
!> linearisation: no geometric stiffening (the classical limit of linear
!> modal bodies, which a spinning beam exposes). Gravity acts on r alone:
!> ∫ρ s = 0 and ∫ρ Φ = 0 leave it no moment and no modal part.
!>
!> As a mechanical problem on its own (nc = 0) it is one free body; the
!> multibody system uses its bindings on its slices of q and v.
module flexmbs_mbs_modal_body
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_fe_modal_basis, only: modal_basis_t
    use flexmbs_fe_modal_invariants, only: modal_invariants_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_rotation, only: skew, cross, quat_l, rotation_matrix, quat_normalize
    use flexmbs_mbs_rigid_body, only: quaternion_rate_derivative, gyroscopic_derivative
    implicit none
    private

    public :: new_modal_body

    !> One modal body: invariants, reduced stiffness and damping, interfaces.
    type, extends(mechanical_problem_t), public :: modal_body_t
        integer :: modes = 0                     !! elastic coordinates n
        real(wp) :: total_mass = 0.0_wp          !! m
        real(wp) :: gravity(3) = 0.0_wp          !! global
        real(wp) :: force(3) = 0.0_wp            !! applied global force at r
        real(wp) :: torque(3) = 0.0_wp           !! applied body-fixed torque
        real(wp) :: second(3, 3) = 0.0_wp        !! P₀ = ∫ρ X Xᵀ
        real(wp), allocatable :: coupling(:, :, :)    !! (3, 3, n) C_k = ∫ρ X Φ_kᵀ
        real(wp), allocatable :: products(:, :, :, :) !! (3, 3, n, n) P_kl = ∫ρ Φ_k Φ_lᵀ
        real(wp), allocatable :: cross_products(:, :, :) !! (3, n, n) ∫ρ Φ_k × Φ_l
        real(wp), allocatable :: modal_mass(:, :)     !! (n, n) M_ηη
        real(wp), allocatable :: stiffness(:)         !! ω_l² (n)
        real(wp), allocatable :: damping(:, :)        !! D (n, n)
        !> interface j: its centroid from the centre of mass (3, j) and its
        !> translation (1:3) and rotation (4:6) per unit η (6, n, j)
        real(wp), allocatable :: interface_offset(:, :)
        real(wp), allocatable :: interface_motion(:, :, :)
        !> for output: the mesh's reference positions from the centre of mass
        !> (3, nodes), the shapes (3 nodes, n), and the FE body of the same
        !> mesh and materials (element stresses of the reconstructed field)
        real(wp), allocatable :: reference(:, :), shapes(:, :)
        real(wp), private :: centre(3) = 0.0_wp !! reference_centre
        type(flexible_body_t), allocatable :: fe
        ! workspace: A_l (3, 3, n), filled by moments()
        real(wp), allocatable :: a(:, :, :)
    contains
        procedure :: kinematics => modal_kinematics
        procedure :: mass_matrix => modal_mass_matrix
        procedure :: mass => modal_mass
        procedure :: forces => modal_forces
        procedure :: constraint => modal_constraint
        procedure :: constraint_jacobian => modal_constraint_jacobian
        procedure :: normalize => modal_normalize
        procedure :: kinematics_derivative => modal_kinematics_derivative
        procedure :: mass_derivative => modal_mass_derivative
        procedure :: force_derivatives => modal_force_derivatives
        procedure :: energy => modal_energy
        procedure :: elastic_energy => modal_elastic_energy
        procedure :: total_energy => modal_total_energy
        procedure :: momenta => modal_momenta
        procedure :: interface_pose => modal_interface_pose
        procedure :: node_positions => modal_node_positions
        procedure :: node_velocities => modal_node_velocities
        procedure :: frequencies => modal_frequencies
        procedure :: reference_centre => modal_reference_centre
        procedure :: mode_count => modal_mode_count
        procedure :: fe_body => modal_fe_body
        procedure :: centroid => modal_centroid
        procedure :: interface_position => modal_interface_position
    end type modal_body_t

contains

    !> The body of `basis` and its invariants `inv` (of the same shapes);
    !> with `fe`, the FE body they were computed from, the body can also
    !> give its nodes' positions and velocities and its elements' stresses.
    subroutine new_modal_body(self, basis, inv, status, gravity, fe)
        type(modal_body_t), intent(out) :: self
        type(modal_basis_t), intent(in) :: basis
        type(modal_invariants_t), intent(in) :: inv
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: gravity(3)
        type(flexible_body_t), intent(in), optional :: fe
        integer :: n, k, l
        n = basis%count
        if (size(inv%coupling, 3) /= n .or. .not. inv%mass > 0.0_wp) then
            call status%set(status_bad_input, 'modal body: invariants of another basis, or &
                &no mass')
            return
        end if
        self%modes = n
        self%nq = 7 + n
        self%nv = 6 + n
        self%nc = 0
        self%total_mass = inv%mass
        if (present(gravity)) self%gravity = gravity
        self%second = inv%second
        self%coupling = inv%coupling
        self%products = inv%products
        allocate (self%cross_products(3, n, n), self%modal_mass(n, n), self%a(3, 3, n))
        do l = 1, n
            do k = 1, n
                self%cross_products(:, k, l) = axial(self%products(:, :, k, l))
                self%modal_mass(k, l) = trace(self%products(:, :, k, l))
            end do
        end do
        self%stiffness = basis%frequencies**2
        self%damping = basis%damping
        self%interface_offset = basis%interface_centre - spread(inv%centre, 2, &
            size(basis%interface_centre, 2))
        self%interface_motion = basis%interface_motion
        self%centre = inv%centre
        if (present(fe)) then
            self%fe = fe
            self%reference = fe%mesh%x - spread(inv%centre, 2, fe%mesh%node_count())
            self%shapes = basis%shapes
        end if
    end subroutine new_modal_body

    !> Every node's world position r + A (X − c + Φ η), node by node x y z.
    pure subroutine modal_node_positions(self, q, x)
        class(modal_body_t), intent(in) :: self
        real(wp), intent(in) :: q(:)
        real(wp), intent(out) :: x(:)
        real(wp) :: a(3, 3), s(size(x))
        integer :: i
        a = rotation_matrix(q(4:7))
        s = reshape(self%reference, [size(x)])
        if (self%modes > 0) s = s + matmul(self%shapes, q(8:))
        do i = 1, size(x) / 3
            x(3 * i - 2:3 * i) = q(1:3) + matmul(a, s(3 * i - 2:3 * i))
        end do
    end subroutine modal_node_positions

    !> Every node's world velocity ṙ + A (ω′ × s + Φ η̇), s = X − c + Φ η.
    pure subroutine modal_node_velocities(self, q, v, xd)
        class(modal_body_t), intent(in) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: xd(:)
        real(wp) :: a(3, 3), s(size(xd)), sd(size(xd))
        integer :: i
        a = rotation_matrix(q(4:7))
        s = reshape(self%reference, [size(xd)])
        sd = 0.0_wp
        if (self%modes > 0) then
            s = s + matmul(self%shapes, q(8:))
            sd = matmul(self%shapes, v(7:))
        end if
        do i = 1, size(xd) / 3
            xd(3 * i - 2:3 * i) = v(1:3) + matmul(a, cross(v(4:6), s(3 * i - 2:3 * i)) + &
                                                  sd(3 * i - 2:3 * i))
        end do
    end subroutine modal_node_velocities

    !> The body's own frequencies ω_l [rad/s], one per modal coordinate.
    pure function modal_frequencies(self) result(omega)
        class(modal_body_t), intent(in) :: self
        real(wp), allocatable :: omega(:)
        omega = sqrt(self%stiffness)
    end function modal_frequencies

    !> The reference centre of mass in the mesh's frame: where the body's
    !> frame starts (r at η = 0).
    pure function modal_reference_centre(self) result(centre)
        class(modal_body_t), intent(in) :: self
        real(wp) :: centre(3)
        centre = self%centre
    end function modal_reference_centre

    !> The number n of elastic coordinates η.
    pure integer function modal_mode_count(self) result(n)
        class(modal_body_t), intent(in) :: self
        n = self%modes
    end function modal_mode_count

    !> The FE body the modes were computed on (its mesh, its stresses at the
    !> reconstructed nodes); the modal body must be a target.
    function modal_fe_body(self) result(fe)
        class(modal_body_t), intent(in), target :: self
        type(flexible_body_t), pointer :: fe
        fe => self%fe
    end function modal_fe_body

    !> The mean of the mesh's reference positions (the FE body's centroid).
    pure function modal_centroid(self) result(c)
        class(modal_body_t), intent(in) :: self
        real(wp) :: c(3)
        c = self%fe%centroid()
    end function modal_centroid

    !> Interface j's centroid from the centre of mass, in the body's axes.
    pure function modal_interface_position(self, j) result(position)
        class(modal_body_t), intent(in) :: self
        integer, intent(in) :: j
        real(wp) :: position(3)
        position = self%interface_offset(:, j)
    end function modal_interface_position

    !> (a₂₃ − a₃₂, a₃₁ − a₁₃, a₁₂ − a₂₁): ∫ρ a × b for a = ∫ρ a bᵀ.
    pure function axial(a) result(w)
        real(wp), intent(in) :: a(3, 3)
        real(wp) :: w(3)
        w = [a(2, 3) - a(3, 2), a(3, 1) - a(1, 3), a(1, 2) - a(2, 1)]
    end function axial

    pure real(wp) function trace(a)
        real(wp), intent(in) :: a(3, 3)
        trace = a(1, 1) + a(2, 2) + a(3, 3)
    end function trace

    !> J(η) = tr(P) I − P, P = ∫ρ s sᵀ; and A_l = ∫ρ s Φ_lᵀ into self%a.
    pure subroutine moments(self, eta, j)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: eta(:)
        real(wp), intent(out) :: j(3, 3)
        real(wp) :: p(3, 3)
        integer :: k, l
        p = self%second
        do l = 1, self%modes
            self%a(:, :, l) = self%coupling(:, :, l)
            do k = 1, self%modes
                self%a(:, :, l) = self%a(:, :, l) + eta(k) * self%products(:, :, k, l)
            end do
            ! P = P₀ + Σ_l η_l (C_l + C_lᵀ) + Σ_kl η_k η_l P_kl is the
            ! symmetric part of P₀ + Σ_l η_l (C_l + A_l)
            p = p + eta(l) * (self%coupling(:, :, l) + self%a(:, :, l))
        end do
        p = 0.5_wp * (p + transpose(p))
        j = -p
        do k = 1, 3
            j(k, k) = j(k, k) + trace(p)
        end do
    end subroutine moments

    !> J(η), A_l (into self%a), B = Σ_l η̇_l A_l, ω′ and |ω′|² at (q, v).
    pure subroutine velocity_terms(self, q, v, j, b, om, om2)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: j(3, 3), b(3, 3), om(3), om2
        integer :: l
        call moments(self, q(8:), j)
        om = v(4:6)
        om2 = dot_product(om, om)
        b = 0.0_wp
        do l = 1, self%modes
            b = b + v(6 + l) * self%a(:, :, l)
        end do
    end subroutine velocity_terms

    !> ṙ = w_r, ṗ = L(p)ᵀ w_ω / 2, η̇ = w_η.
    subroutine modal_kinematics(self, t, q, w, qdot, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        qdot(1:3) = w(1:3)
        qdot(4:7) = 0.5_wp * matmul(w(4:6), quat_l(q(4:7)))
        qdot(8:) = w(7:)
    end subroutine modal_kinematics

    !> ∂(T w)/∂q: the quaternion block only.
    subroutine modal_kinematics_derivative(self, t, q, w, dq, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
        dq(4:7, 4:7) = quaternion_rate_derivative(w(4:6))
    end subroutine modal_kinematics_derivative

    !> M(η) of the module header, (6 + n) x (6 + n).
    pure subroutine modal_mass_matrix(self, q, m)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        real(wp), intent(out) :: m(:, :)
        real(wp) :: j(3, 3)
        integer :: k, l
        call moments(self, q(8:), j)
        m = 0.0_wp
        do k = 1, 3
            m(k, k) = self%total_mass
        end do
        m(4:6, 4:6) = j
        do l = 1, self%modes
            m(4:6, 6 + l) = axial(self%a(:, :, l))
            m(6 + l, 4:6) = m(4:6, 6 + l)
        end do
        m(7:, 7:) = self%modal_mass
    end subroutine modal_mass_matrix

    subroutine modal_mass(self, t, q, m, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        call self%mass_matrix(q, m)
    end subroutine modal_mass

    !> f(q, v) of the module header.
    subroutine modal_forces(self, t, q, v, f, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        real(wp) :: j(3, 3), b(3, 3), om(3), om2
        integer :: k, l
        associate (eta => q(8:), etad => v(7:), n => self%modes)
            call velocity_terms(self, q, v, j, b, om, om2)
            f(1:3) = self%total_mass * self%gravity + self%force
            f(4:6) = self%torque - cross(om, matmul(j, om)) &
                - 2.0_wp * (trace(b) * om - matmul(transpose(b), om))
            do l = 1, n
                f(6 + l) = -dot_product(om, matmul(self%a(:, :, l), om)) &
                    + om2 * trace(self%a(:, :, l)) - self%stiffness(l) * eta(l) &
                    - dot_product(self%damping(l, :), etad)
                do k = 1, n
                    f(6 + l) = f(6 + l) - 2.0_wp * etad(k) * &
                        dot_product(om, self%cross_products(:, k, l))
                end do
            end do
        end associate
    end subroutine modal_forces

    !> ∂(M(η) w)/∂q: through η only.
    subroutine modal_mass_derivative(self, t, q, w, dq, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: dp(3, 3), dj(3, 3)
        integer :: k, l
        dq = 0.0_wp
        associate (eta => q(8:), n => self%modes)
            do k = 1, n
                call inertia_derivative(self, eta, k, dp, dj)
                dq(4:6, 7 + k) = matmul(dj, w(4:6))
                do l = 1, n
                    ! ∂H_l/∂η_k = axial(P_kl)
                    dq(4:6, 7 + k) = dq(4:6, 7 + k) + w(6 + l) * self%cross_products(:, k, l)
                    dq(6 + l, 7 + k) = dot_product(self%cross_products(:, k, l), w(4:6))
                end do
            end do
        end associate
    end subroutine modal_mass_derivative

    !> ∂P/∂η_k = C_k + C_kᵀ + Σ_l η_l (P_kl + P_klᵀ), and ∂J/∂η_k from it.
    pure subroutine inertia_derivative(self, eta, k, dp, dj)
        class(modal_body_t), intent(in) :: self
        real(wp), intent(in) :: eta(:)
        integer, intent(in) :: k
        real(wp), intent(out) :: dp(3, 3), dj(3, 3)
        integer :: l, i
        dp = self%coupling(:, :, k)
        do l = 1, self%modes
            dp = dp + eta(l) * self%products(:, :, k, l)
        end do
        dp = dp + transpose(dp)
        dj = -dp
        do i = 1, 3
            dj(i, i) = dj(i, i) + trace(dp)
        end do
    end subroutine inertia_derivative

    !> ∂f/∂q (through η) and ∂f/∂v.
    subroutine modal_force_derivatives(self, t, q, v, fq, fv, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: j(3, 3), b(3, 3), db(3, 3), dp(3, 3), dj(3, 3), om(3), om2, cw(3)
        integer :: k, l, i
        fq = 0.0_wp
        fv = 0.0_wp
        associate (eta => q(8:), etad => v(7:), n => self%modes)
            call velocity_terms(self, q, v, j, b, om, om2)
            ! f_ω
            fv(4:6, 4:6) = gyroscopic_derivative(j, om) + 2.0_wp * transpose(b)
            do i = 1, 3
                fv(3 + i, 3 + i) = fv(3 + i, 3 + i) - 2.0_wp * trace(b)
            end do
            do l = 1, n
                associate (al => self%a(:, :, l))
                    fv(4:6, 6 + l) = -2.0_wp * (trace(al) * om - matmul(transpose(al), om))
                    ! f_l over ω and η̇
                    cw = 0.0_wp
                    do k = 1, n
                        cw = cw + etad(k) * self%cross_products(:, k, l)
                        fv(6 + l, 6 + k) = -2.0_wp * dot_product(om, self%cross_products(:, k, l))
                    end do
                    fv(6 + l, 4:6) = -matmul(al + transpose(al), om) + 2.0_wp * trace(al) * om &
                        - 2.0_wp * cw
                    fv(6 + l, 7:) = fv(6 + l, 7:) - self%damping(l, :)
                end associate
            end do
            ! over η_k
            do k = 1, n
                call inertia_derivative(self, eta, k, dp, dj)
                db = 0.0_wp
                do l = 1, n
                    db = db + etad(l) * self%products(:, :, k, l)
                end do
                fq(4:6, 7 + k) = -cross(om, matmul(dj, om)) &
                    - 2.0_wp * (trace(db) * om - matmul(transpose(db), om))
                do l = 1, n
                    associate (pkl => self%products(:, :, k, l))
                        fq(6 + l, 7 + k) = -dot_product(om, matmul(pkl, om)) + om2 * trace(pkl)
                    end associate
                end do
                fq(6 + k, 7 + k) = fq(6 + k, 7 + k) - self%stiffness(k)
            end do
        end associate
    end subroutine modal_force_derivatives

    !> The elastic energy ½ Σ ω_l² η_l² of the reduced model at q = (r, p, η).
    pure real(wp) function modal_elastic_energy(self, q) result(e)
        class(modal_body_t), intent(in) :: self
        real(wp), intent(in) :: q(:)
        e = 0.5_wp * dot_product(self%stiffness, q(8:)**2)
    end function modal_elastic_energy

    !> Kinetic energy ½ vᵀ M v, elastic ½ Σ ω_l² η_l², gravity −m g·r.
    subroutine modal_energy(self, q, v, kinetic, potential)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: kinetic, potential
        real(wp) :: m(self%nv, self%nv)
        call self%mass_matrix(q, m)
        kinetic = 0.5_wp * dot_product(v, matmul(m, v))
        potential = self%elastic_energy(q) &
            - self%total_mass * dot_product(self%gravity, q(1:3))
    end subroutine modal_energy

    real(wp) function modal_total_energy(self, q, v, q_ref) result(e)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(in), optional :: q_ref(:)
        real(wp) :: kinetic, potential
        call self%energy(q, v, kinetic, potential)
        e = kinetic + potential
    end function modal_total_energy

    !> Linear momentum m ṙ and angular momentum about the global origin,
    !> m r × ṙ + A (J ω′ + Σ_l H_l η̇_l).
    subroutine modal_momenta(self, q, v, linear, angular)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: linear(3), angular(3)
        real(wp) :: m(self%nv, self%nv)
        call self%mass_matrix(q, m)
        linear = self%total_mass * v(1:3)
        angular = cross(q(1:3), linear) + matmul(rotation_matrix(q(4:7)), &
                                                 matmul(m(4:6, 4:), v(4:)))
    end subroutine modal_momenta

    !> Interface j's centroid (global) and its rotation matrix (body to
    !> global): r + A (d_j + U_j η) and A R(θ_j), θ_j = Θ_j η, R the
    !> rotation by the angle |θ| about θ (exact for a rigid interface's
    !> small rotation, orthonormal for any).
    pure subroutine modal_interface_pose(self, q, j, position, rotation)
        class(modal_body_t), intent(in) :: self
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: j
        real(wp), intent(out) :: position(3), rotation(3, 3)
        real(wp) :: a(3, 3), theta(3), angle, e(4)
        a = rotation_matrix(q(4:7))
        position = q(1:3) + matmul(a, self%interface_offset(:, j) + &
                                   matmul(self%interface_motion(1:3, :, j), q(8:)))
        theta = matmul(self%interface_motion(4:6, :, j), q(8:))
        angle = norm2(theta)
        e = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        if (angle > 0.0_wp) e = [cos(angle / 2), sin(angle / 2) * theta / angle]
        rotation = matmul(a, rotation_matrix(e))
    end subroutine modal_interface_pose

    !> No constraints of its own.
    subroutine modal_constraint(self, t, q, g, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
    end subroutine modal_constraint

    subroutine modal_constraint_jacobian(self, t, q, gmat, status)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
    end subroutine modal_constraint_jacobian

    !> p ← p / |p|.
    subroutine modal_normalize(self, q)
        class(modal_body_t), intent(inout) :: self
        real(wp), intent(inout) :: q(:)
        q(4:7) = quat_normalize(q(4:7))
    end subroutine modal_normalize
end module flexmbs_mbs_modal_body
