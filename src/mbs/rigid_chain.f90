!> Rigid chains: loop-free substructures in relative coordinates (docs/theory.md §2.3,
!> the paper's rigid substructures). Body i hangs from its parent (0 = the
!> ground) by a revolute or prismatic joint (one coordinate q_i, rate v_i,
!> q_i' = v_i) or a spherical joint (a unit quaternion p_i of the relative
!> rotation, 4 coordinates, and the relative angular velocity w_i in the
!> child's frame, 3 rates, p_i' = T(p_i) w_i), so q' = T(q) v,
!> M(q) v' = f(t, q, v) with f = −b(q, v), and no constraints (nc = 0).
!>
!> Geometry, for body i with parent p (frames: origin o, rotation R, world):
!>   joint origin   o_i = o_p + R_p x_i (+ R_p R0_i a_i q_i, prismatic)
!>   orientation    R_i = R_p R0_i Rot(a_i, q_i) (revolute), R_p R0_i (prismatic),
!>                  R_p R0_i R(p_i) (spherical)
!>   centre of mass c_i = o_i + R_i s_i
!> with x_i the joint's position and R0_i its rotation in the parent's frame,
!> a_i the unit joint axis (joint frame = child frame at q = 0), s_i the
!> child's centre of mass in its frame, m_i, J_i (about the centre of mass,
!> child frame).
!>
!> Dynamics in world-frame spatial vectors about the world origin
!> (Featherstone, Rigid Body Dynamics Algorithms, 2008, chs. 2, 5, 6):
!> motion [ω; v_O], force [n_O; f]. Joint i's motion subspace is
!> S_i = [u; o_i × u] (revolute about the world axis u = R_p R0_i a_i
!> through o_i), [0; u] (prismatic), or the three columns [u_k; o_i × u_k],
!> u_k = R_i e_k (spherical); body i's spatial inertia about O is
!>   I_i = [Ī + m [c]×[c]×ᵀ, m [c]×; m [c]×ᵀ, m 1],  Ī = R J Rᵀ.
!> Composite-rigid-body algorithm: I^c_i = I_i + Σ_children I^c_c, then
!> M_ii = S_iᵀ I^c_i S_i and M_ij = M_ji = S_jᵀ I^c_i S_i for the ancestors
!> j of i (no transforms: every vector is about O). Recursive Newton–Euler:
!> v_i = v_p + S_i v_i, a_i = a_p + S_i v̇_i + v_i ×m S_i v_i (a_0 = −[0; g];
!> S_i is fixed in the child, so Ṡ_i = v_i ×m S_i),
!> f_i = I_i a_i + v_i ×* I_i v_i, τ_i = S_iᵀ (f_i + Σ_children f_c);
!> b(q, v) = τ(q, v, q̈ = 0) holds the Coriolis, centrifugal and gravity terms.
!>
!> Markers on chain bodies: their pose and their Jacobians ∂(ẋ, ω)/∂v.
!> The derivatives ∂(M w)/∂q, ∂f/∂q and ∂f/∂v are the RNEA's recursion
!> differentiated along each coordinate (submodule rigid_chain_derivatives).
module flexmbs_mbs_rigid_chain
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross, skew, &
        quat_rate_matrix, quat_normalize
    implicit none
    private

    integer, parameter, public :: chain_joint_revolute = 1
    integer, parameter, public :: chain_joint_prismatic = 2
    integer, parameter, public :: chain_joint_spherical = 3

    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])

    !> One body of a chain and the joint to its parent.
    type, public :: chain_body_t
        integer :: parent = 0                     !! 0: the ground; else an earlier body
        integer :: joint = chain_joint_revolute
        real(wp) :: joint_position(3) = 0.0_wp    !! x_i, in the parent's frame
        real(wp) :: joint_rotation(3, 3) = identity3 !! R0_i, in the parent's frame
        real(wp) :: axis(3) = [0.0_wp, 0.0_wp, 1.0_wp] !! a_i, unit, joint frame
        real(wp) :: centre(3) = 0.0_wp            !! s_i, centre of mass, own frame
        real(wp) :: mass = 1.0_wp
        real(wp) :: inertia(3, 3) = identity3     !! J_i about the centre of mass, own frame
    end type chain_body_t

    !> A marker on a chain body (body 0: the ground).
    type, public :: chain_marker_t
        integer :: body = 0
        real(wp) :: position(3) = 0.0_wp          !! in the body's frame
        real(wp) :: axes(3, 3) = identity3        !! columns, in the body's frame
    end type chain_marker_t

    !> A tree of rigid bodies in relative coordinates as a mechanical problem
    !> (see the module): bodies, markers, gravity and the recursions' workspaces.
    type, extends(mechanical_problem_t), public :: rigid_chain_t
        type(chain_body_t), allocatable :: bodies(:)
        type(chain_marker_t), allocatable :: markers(:)
        real(wp) :: gravity(3) = 0.0_wp
        ! workspace, one column per body: frames, motion subspaces, velocities,
        ! accelerations, spatial inertias and forces
        real(wp), allocatable :: o(:, :), r(:, :, :), s(:, :), vel(:, :), acc(:, :), &
            inert(:, :, :), comp(:, :, :), frc(:, :)
        !> coordinates iq(i)+1 .. iq(i+1) and rates iv(i)+1 .. iv(i+1) of body i;
        !> s holds the motion subspace columns by rate index
        integer, allocatable :: iq(:), iv(:)
        !> each joint's own rotation (Rot(a, q), 1 or R(p)), set by the frames
        real(wp), allocatable :: rloc(:, :, :)
        !> tangents of the frames, subspaces, inertias, velocities,
        !> accelerations and forces along one coordinate (rigid_chain_derivatives),
        !> the bodies that direction moves, and two rate-sized scratch vectors
        real(wp), allocatable :: tan_o(:, :), tan_r(:, :, :), tan_s(:, :), tan_inert(:, :, :), &
            tan_vel(:, :), tan_acc(:, :), tan_frc(:, :), rates0(:), tau0(:)
        logical, allocatable :: moved(:)
    contains
        procedure :: kinematics => chain_kinematics
        procedure :: mass => chain_mass
        procedure :: forces => chain_forces
        procedure :: constraint => chain_constraint
        procedure :: constraint_jacobian => chain_constraint_jacobian
        procedure :: kinematics_derivative => chain_kinematics_derivative
        procedure :: normalize => chain_normalize
        procedure :: inverse_dynamics => chain_inverse_dynamics
        procedure :: body_frame => chain_body_frame
        procedure :: marker_pose => chain_marker_pose
        procedure :: marker_jacobian => chain_marker_jacobian
        procedure :: energy => chain_energy
        procedure :: total_energy => chain_total_energy
        procedure :: body_velocity => chain_body_velocity
        procedure :: mass_derivative => chain_mass_derivative
        procedure :: force_derivatives => chain_force_derivatives
        procedure :: link_count => chain_link_count
        procedure :: link_joint => chain_link_joint
        procedure :: link_centre => chain_link_centre
        procedure :: link_coordinates => chain_link_coordinates
    end type rigid_chain_t

    public :: new_rigid_chain, new_chain_body

    interface
        !> ∂(M(q) w)/∂q, nv x nq (rigid_chain_derivatives).
        module subroutine chain_mass_derivative(self, t, q, w, dq, status)
            class(rigid_chain_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: dq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine chain_mass_derivative
        !> ∂f/∂q (nv x nq) and ∂f/∂v (nv x nv), f = −b (rigid_chain_derivatives).
        module subroutine chain_force_derivatives(self, t, q, v, fq, fv, status)
            class(rigid_chain_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: fq(:, :), fv(:, :)
            type(status_t), intent(inout) :: status
        end subroutine chain_force_derivatives
        !> Spatial motion cross product v ×m u (rigid_chain_derivatives).
        pure module function cross_motion(v, u) result(w)
            real(wp), intent(in) :: v(6), u(6)
            real(wp) :: w(6)
        end function cross_motion
        !> Spatial force cross product v ×* f (rigid_chain_derivatives).
        pure module function cross_force(v, f) result(w)
            real(wp), intent(in) :: v(6), f(6)
            real(wp) :: w(6)
        end function cross_force
    end interface

contains

    !> A chain body (the components' meanings are chain_body_t's); its joint
    !> rotation R0_i stays the identity.
    pure function new_chain_body(parent, joint, joint_position, axis, centre, mass, &
                                 inertia) result(body)
        integer, intent(in) :: parent, joint
        real(wp), intent(in) :: joint_position(3), axis(3), centre(3), mass, inertia(3, 3)
        type(chain_body_t) :: body
        body%parent = parent
        body%joint = joint
        body%joint_position = joint_position
        body%axis = axis
        body%centre = centre
        body%mass = mass
        body%inertia = inertia
    end function new_chain_body

    !> A chain of `bodies` (each body's parent listed before it) with
    !> `markers`, under `gravity`.
    function new_rigid_chain(bodies, status, markers, gravity) result(self)
        type(chain_body_t), intent(in) :: bodies(:)
        type(status_t), intent(out) :: status
        type(chain_marker_t), intent(in), optional :: markers(:)
        real(wp), intent(in), optional :: gravity(3)
        type(rigid_chain_t) :: self
        integer :: i, n, stat
        character(len=:), allocatable :: where
        n = size(bodies)
        do i = 1, n
            where = 'rigid chain: body ' // int_text(i)
            if (bodies(i)%parent < 0 .or. bodies(i)%parent >= i) then
                call status%set(status_bad_input, where // ': parent ' // &
                    int_text(bodies(i)%parent) // ' must be 0 (ground) or an earlier body')
                return
            end if
            if (bodies(i)%joint < chain_joint_revolute .or. &
                bodies(i)%joint > chain_joint_spherical) then
                call status%set(status_bad_input, where // ': joint must be revolute, ' // &
                                'prismatic or spherical')
                return
            end if
            if (abs(norm2(bodies(i)%axis) - 1.0_wp) > 1.0e-12_wp) then
                call status%set(status_bad_input, where // ': joint axis is not a unit vector')
                return
            end if
            if (.not. bodies(i)%mass > 0.0_wp) then
                call status%set(status_bad_input, where // ': mass must be positive')
                return
            end if
        end do
        self%bodies = bodies
        if (present(markers)) then
            if (any(markers%body < 0 .or. markers%body > n)) then
                call status%set(status_bad_input, 'rigid chain: a marker names a body ' // &
                                'outside 0..' // int_text(n))
                return
            end if
            self%markers = markers
        else
            allocate (self%markers(0))
        end if
        if (present(gravity)) self%gravity = gravity
        allocate (self%iq(n + 1), self%iv(n + 1))
        self%iq(1) = 0
        self%iv(1) = 0
        do i = 1, n
            self%iq(i + 1) = self%iq(i) + merge(4, 1, bodies(i)%joint == chain_joint_spherical)
            self%iv(i + 1) = self%iv(i) + merge(3, 1, bodies(i)%joint == chain_joint_spherical)
        end do
        self%nq = self%iq(n + 1)
        self%nv = self%iv(n + 1)
        self%nc = 0
        allocate (self%o(3, 0:n), self%r(3, 3, 0:n), self%s(6, self%nv), self%vel(6, 0:n), &
                  self%acc(6, 0:n), self%inert(6, 6, n), self%comp(6, 6, n), self%frc(6, n), &
                  self%rloc(3, 3, n), self%tan_o(3, 0:n), self%tan_r(3, 3, 0:n), &
                  self%tan_s(6, self%nv), self%tan_inert(6, 6, n), self%tan_vel(6, 0:n), &
                  self%tan_acc(6, 0:n), self%tan_frc(6, n), self%rates0(self%nv), &
                  self%tau0(self%nv), self%moved(0:n), stat=stat)
        ! 24 + 24 values per frame (n + 1), 6 + 6 + 2 per velocity,
        ! 78 + 9 + 42 per body (the moved flags counted as values)
        if (stat /= 0) call out_of_memory(status, 'rigid chain workspace', &
            49 * (n + 1_i8) + 14_i8 * self%nv + 129_i8 * n, 8)
    end function new_rigid_chain

    !> Forward kinematics: frames o, R, motion subspaces S and spatial
    !> inertias about the world origin, for all bodies at q.
    pure subroutine frames(self, q)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        integer :: i, p, k, jq, jv
        real(wp) :: u(3), c(3), rj(3, 3), ibar(3, 3), cx(3, 3)
        self%o(:, 0) = 0.0_wp
        self%r(:, :, 0) = identity3
        do i = 1, size(self%bodies)
            associate (b => self%bodies(i))
                p = b%parent
                jq = self%iq(i) + 1
                jv = self%iv(i) + 1
                rj = matmul(self%r(:, :, p), b%joint_rotation)
                u = matmul(rj, b%axis)
                self%o(:, i) = self%o(:, p) + matmul(self%r(:, :, p), b%joint_position)
                select case (b%joint)
                case (chain_joint_revolute)
                    self%rloc(:, :, i) = rotation_matrix(quat_from_axis_angle(b%axis, q(jq)))
                    self%r(:, :, i) = matmul(rj, self%rloc(:, :, i))
                    self%s(1:3, jv) = u
                    self%s(4:6, jv) = cross(self%o(:, i), u)
                case (chain_joint_prismatic)
                    self%o(:, i) = self%o(:, i) + u * q(jq)
                    self%rloc(:, :, i) = identity3
                    self%r(:, :, i) = rj
                    self%s(1:3, jv) = 0.0_wp
                    self%s(4:6, jv) = u
                case default
                    self%rloc(:, :, i) = rotation_matrix(q(jq:jq + 3))
                    self%r(:, :, i) = matmul(rj, self%rloc(:, :, i))
                    do k = 0, 2
                        self%s(1:3, jv + k) = self%r(:, k + 1, i)
                        self%s(4:6, jv + k) = cross(self%o(:, i), self%r(:, k + 1, i))
                    end do
                end select
                c = self%o(:, i) + matmul(self%r(:, :, i), b%centre)
                ibar = matmul(self%r(:, :, i), matmul(b%inertia, transpose(self%r(:, :, i))))
                cx = skew(c)
                self%inert(1:3, 1:3, i) = ibar + b%mass * matmul(cx, transpose(cx))
                self%inert(1:3, 4:6, i) = b%mass * cx
                self%inert(4:6, 1:3, i) = b%mass * transpose(cx)
                self%inert(4:6, 4:6, i) = b%mass * identity3
            end associate
        end do
    end subroutine frames

    !> Recursive Newton–Euler: tau = M(q) qdd + b(q, qd), gravity included
    !> when `with_gravity` (default true).
    subroutine chain_inverse_dynamics(self, q, qd, qdd, tau, with_gravity)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), qd(:), qdd(:)
        real(wp), intent(out) :: tau(:)
        logical, intent(in), optional :: with_gravity
        integer :: i, p, c
        real(wp) :: sv(6), sa(6)
        call frames(self, q)
        self%vel(:, 0) = 0.0_wp
        self%acc(:, 0) = 0.0_wp
        self%acc(4:6, 0) = -self%gravity
        if (present(with_gravity)) then
            if (.not. with_gravity) self%acc(4:6, 0) = 0.0_wp
        end if
        do i = 1, size(self%bodies)
            p = self%bodies(i)%parent
            ! S v and S v' over the joint's rate columns (no temporaries)
            sv = 0.0_wp
            sa = 0.0_wp
            do c = self%iv(i) + 1, self%iv(i + 1)
                sv = sv + self%s(:, c) * qd(c)
                sa = sa + self%s(:, c) * qdd(c)
            end do
            self%vel(:, i) = self%vel(:, p) + sv
            self%acc(:, i) = self%acc(:, p) + sa + cross_motion(self%vel(:, i), sv)
            self%frc(:, i) = matmul(self%inert(:, :, i), self%acc(:, i)) &
                             + cross_force(self%vel(:, i), matmul(self%inert(:, :, i), &
                                                                  self%vel(:, i)))
        end do
        do i = size(self%bodies), 1, -1
            do c = self%iv(i) + 1, self%iv(i + 1)
                tau(c) = dot_product(self%s(:, c), self%frc(:, i))
            end do
            p = self%bodies(i)%parent
            if (p > 0) self%frc(:, p) = self%frc(:, p) + self%frc(:, i)
        end do
    end subroutine chain_inverse_dynamics

    !> M(q) by the composite-rigid-body algorithm.
    subroutine chain_mass(self, t, q, m, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: f(6)
        integer :: i, j, p, a, b
        call frames(self, q)
        self%comp = self%inert
        do i = size(self%bodies), 1, -1
            p = self%bodies(i)%parent
            if (p > 0) self%comp(:, :, p) = self%comp(:, :, p) + self%comp(:, :, i)
        end do
        m = 0.0_wp
        do i = 1, size(self%bodies)
            do a = self%iv(i) + 1, self%iv(i + 1)
                f = matmul(self%comp(:, :, i), self%s(:, a))
                do b = self%iv(i) + 1, self%iv(i + 1)
                    m(b, a) = dot_product(self%s(:, b), f)
                end do
                j = self%bodies(i)%parent
                do while (j > 0)
                    do b = self%iv(j) + 1, self%iv(j + 1)
                        m(b, a) = dot_product(self%s(:, b), f)
                        m(a, b) = m(b, a)
                    end do
                    j = self%bodies(j)%parent
                end do
            end do
        end do
    end subroutine chain_mass

    !> f = −b(q, v): Coriolis, centrifugal and gravity terms (RNEA at v' = 0).
    subroutine chain_forces(self, t, q, v, f, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        self%rates0 = 0.0_wp
        call chain_inverse_dynamics(self, q, v, self%rates0, f)
        f = -f
    end subroutine chain_forces

    !> q' = T(q) v: the rate itself, or T(p) w for a spherical joint.
    subroutine chain_kinematics(self, t, q, w, qdot, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        integer :: i, jq, jv
        do i = 1, size(self%bodies)
            jq = self%iq(i) + 1
            jv = self%iv(i) + 1
            if (self%bodies(i)%joint == chain_joint_spherical) then
                qdot(jq:jq + 3) = matmul(quat_rate_matrix(q(jq:jq + 3)), w(jv:jv + 2))
            else
                qdot(jq) = w(jv)
            end if
        end do
    end subroutine chain_kinematics

    !> ∂(T w)/∂q: zero but for spherical joints, where T(p) w is linear in p,
    !> so column k is T(e_k) w.
    subroutine chain_kinematics_derivative(self, t, q, w, dq, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        real(wp) :: e(4)
        integer :: i, k, jq, jv
        dq = 0.0_wp
        do i = 1, size(self%bodies)
            if (self%bodies(i)%joint /= chain_joint_spherical) cycle
            jq = self%iq(i) + 1
            jv = self%iv(i) + 1
            do k = 1, 4
                e = 0.0_wp
                e(k) = 1.0_wp
                dq(jq:jq + 3, jq + k - 1) = matmul(quat_rate_matrix(e), w(jv:jv + 2))
            end do
        end do
    end subroutine chain_kinematics_derivative

    !> Unit quaternions of the spherical joints.
    subroutine chain_normalize(self, q)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(inout) :: q(:)
        integer :: i, jq
        do i = 1, size(self%bodies)
            if (self%bodies(i)%joint /= chain_joint_spherical) cycle
            jq = self%iq(i) + 1
            q(jq:jq + 3) = quat_normalize(q(jq:jq + 3))
        end do
    end subroutine chain_normalize

    !> No constraints on their own (a chain is loop-free).
    subroutine chain_constraint(self, t, q, g, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
    end subroutine chain_constraint

    subroutine chain_constraint_jacobian(self, t, q, gmat, status)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
    end subroutine chain_constraint_jacobian

    !> Origin o and rotation R of body i's frame at q (body 0: the ground),
    !> the spherical joints' quaternions taken at unit length: R is a
    !> rotation even where the integration let |p| drift (R(p) of the
    !> dynamics is |p|² times one), as the results and ParaView show it.
    subroutine chain_body_frame(self, q, i, o, r)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: i
        real(wp), intent(out) :: o(3), r(3, 3)
        real(wp) :: unit(size(q))
        unit = q
        call self%normalize(unit)
        call frames(self, unit)
        o = self%o(:, i)
        r = self%r(:, :, i)
    end subroutine chain_body_frame

    !> World position x and axes (columns) of marker k at q.
    subroutine chain_marker_pose(self, q, k, x, axes)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: k
        real(wp), intent(out) :: x(3), axes(3, 3)
        integer :: b
        call frames(self, q)
        b = self%markers(k)%body
        x = self%o(:, b) + matmul(self%r(:, :, b), self%markers(k)%position)
        axes = matmul(self%r(:, :, b), self%markers(k)%axes)
    end subroutine chain_marker_pose

    !> Marker k's velocity ẋ = jx v and angular velocity ω = jr v (world):
    !> the columns S_j of the body's ancestors, taken at the marker point.
    subroutine chain_marker_jacobian(self, q, k, jx, jr)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: k
        real(wp), intent(out) :: jx(:, :), jr(:, :)
        real(wp) :: x(3), axes(3, 3)
        integer :: j, c
        call chain_marker_pose(self, q, k, x, axes)
        jx = 0.0_wp
        jr = 0.0_wp
        j = self%markers(k)%body
        do while (j > 0)
            ! spatial [ω; v_O] → point velocity v_O + ω × x
            do c = self%iv(j) + 1, self%iv(j + 1)
                jr(:, c) = self%s(1:3, c)
                jx(:, c) = self%s(4:6, c) + cross(self%s(1:3, c), x)
            end do
            j = self%bodies(j)%parent
        end do
    end subroutine chain_marker_jacobian

    !> Body i's centre-of-mass velocity and angular velocity (world).
    subroutine chain_body_velocity(self, q, v, i, vc, omega)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        integer, intent(in) :: i
        real(wp), intent(out) :: vc(3), omega(3)
        real(wp) :: twist(6), c(3)
        integer :: j, a
        call frames(self, q)
        twist = 0.0_wp
        j = i
        do while (j > 0)
            do a = self%iv(j) + 1, self%iv(j + 1)
                twist = twist + self%s(:, a) * v(a)
            end do
            j = self%bodies(j)%parent
        end do
        c = self%o(:, i) + matmul(self%r(:, :, i), self%bodies(i)%centre)
        omega = twist(1:3)
        vc = twist(4:6) + cross(twist(1:3), c)
    end subroutine chain_body_velocity

    !> Kinetic energy ½ vᵀ M v and potential −Σ m_i g·c_i.
    subroutine chain_energy(self, q, v, kinetic, potential)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: kinetic, potential
        real(wp) :: m(size(v), size(v))
        type(status_t) :: st
        integer :: i
        call chain_mass(self, 0.0_wp, q, m, st)
        kinetic = 0.5_wp * dot_product(v, matmul(m, v))
        potential = 0.0_wp
        do i = 1, size(self%bodies)
            potential = potential - self%bodies(i)%mass * dot_product(self%gravity, &
                self%o(:, i) + matmul(self%r(:, :, i), self%bodies(i)%centre))
        end do
    end subroutine chain_energy

    !> Kinetic plus potential energy (mechanical_problem_t%total_energy).
    real(wp) function chain_total_energy(self, q, v, q_ref) result(e)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(in), optional :: q_ref(:)
        real(wp) :: kinetic, potential
        call self%energy(q, v, kinetic, potential)
        e = kinetic + potential
    end function chain_total_energy

    !> The number of links (bodies) of the chain.
    pure integer function chain_link_count(self) result(n)
        class(rigid_chain_t), intent(in) :: self
        n = 0
        if (allocated(self%bodies)) n = size(self%bodies)
    end function chain_link_count

    !> The kind of link i's joint to its parent (chain_joint_revolute, _prismatic, _spherical).
    pure integer function chain_link_joint(self, i) result(kind)
        class(rigid_chain_t), intent(in) :: self
        integer, intent(in) :: i
        kind = self%bodies(i)%joint
    end function chain_link_joint

    !> Link i's centre of mass in its own frame (s_i).
    pure function chain_link_centre(self, i) result(centre)
        class(rigid_chain_t), intent(in) :: self
        integer, intent(in) :: i
        real(wp) :: centre(3)
        centre = self%bodies(i)%centre
    end function chain_link_centre

    !> Where link i's joint sits in the chain's q and v: its coordinates
    !> q(oq + 1:oq + nq), its rates v(ov + 1:ov + nv).
    pure subroutine chain_link_coordinates(self, i, oq, nq, ov, nv)
        class(rigid_chain_t), intent(in) :: self
        integer, intent(in) :: i
        integer, intent(out) :: oq, nq, ov, nv
        oq = self%iq(i)
        nq = self%iq(i + 1) - self%iq(i)
        ov = self%iv(i)
        nv = self%iv(i + 1) - self%iv(i)
    end subroutine chain_link_coordinates
end module flexmbs_mbs_rigid_chain
