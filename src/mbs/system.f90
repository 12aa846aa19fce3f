!> The assembled multibody system (docs/theory.md §2): rigid
!> bodies in absolute coordinates and joints between markers on them (or on
!> the ground), as one `mechanical_problem_t`.
!>
!> Coordinates: q = (r₁, p₁, r₂, p₂, ...), v = (ṙ₁, ω′₁, ...) as in
!> flexmbs_mbs_rigid_body (q' = T v, M = diag(m I₃, J) per body, gravity,
!> gyroscopic terms, applied force and torque), which the system delegates
!> to. Joint k (flexmbs_mbs_joint: a list of constraint primitives between
!> marker i and marker j) owns the rows row0+1 .. row0+nrows of
!>
!>   c(t, q) = 0,   G = c_q T (velocity space),   c_t,
!>   γ = (G v)_q T v + 2 G_t v + c_tt   (index 1, eq. 9).
!>
!> `constraint_derivatives` selects how the joint rows' first derivatives G,
!> c_q, c_t and γ are evaluated: 'analytic' by the hand-coded formulas of
!> constraint_primitives.inc, 'ad' by the same formulas' values on dual
!> numbers (forward-mode AD; γ as AD of the hand-coded G v along q' = T v).
!> The second derivatives the formulations' Newton Jacobians need —
!> ∂(G w)/∂q, ∂(Gᵀλ)/∂q, ∂c_t/∂q, ∂γ/∂q, ∂γ/∂v — are always AD of the
!> hand-coded first derivatives (exact, one dual pass per joint and block),
!> in place of the forward-difference defaults of mechanical_problem_t.
!>
!> Storage: M and G also in CSC (`has_sparse`, patterns fixed once: per body
!> the m I₃ diagonal and the 3 × 3 inertia block; per joint its rows times
!> the 6 velocity columns of each marker's body), which MEXAX's KLU path
!> uses; the derivatives the formulations need are dense arrays.
!> Drivers: a joint of one primitive (kind joint_primitive) that is an angle
!> driver, a translation driver or a distance follows s(t) of its driver_t,
!> s = Σ c_k t^k (k ≤ 3) + a sin(ω t + φ), with s', s'' exact; c_t and the
!> time terms of γ come from them (dual time direction). A driven revolute
!> is the revolute plus an angle driver on the same markers, axes 1 and 1:
!> the angle from x_i to x_j about z_i.
!>
!> Joint reactions (`joint_reaction`), our sign of λ (docs/theory.md §2.1: M v' =
!> f − Gᵀλ): the generalised force of joint k on a body is −C_bᵀλ_k, C_b
!> the joint's columns of G for that body; it is reported as the force F
!> (global) and the torque n (global) about the marker's origin that the
!> joint exerts on the body. A body hanging at rest from a spherical joint
!> is held up: F = −m g (upwards, for gravity g). On the ground (a marker
!> of body 0) it is the load the joint puts on the ground, the bearing
!> load: for the hanging body F = m g, downwards.
module flexmbs_mbs_system
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t, mechanical_patterns_t, &
        difference_step
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_accumulator, only: accumulator_t
    use flexmbs_linalg_triplets, only: triplets_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_primitive_kinds, only: primitive_distance
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_rate_matrix, cross, quat_l
    use flexmbs_mbs_dual, only: dual_t, operator(+), assignment(=), dot_product
    use flexmbs_mbs_rigid_body, only: rigid_body_t, rigid_bodies_t, new_rigid_bodies, &
        rigid_body_nq, rigid_body_nv, rigid_body_energy, rigid_body_momenta, &
        quaternion_rate_derivative, gyroscopic_derivative
    use flexmbs_mbs_joint, only: joint_t, new_joint, new_primitive_joint, joint_primitive, &
        joint_spherical, &
        joint_part_time_derivative, &
        joint_part_convective, joint_part_time_terms
    use flexmbs_mbs_constraint_primitives, only: marker_state_t, rigid_marker_state, &
        ground_marker_state, rigid_marker_jacobian, rigid_marker_jacobian_q, joint_value, &
        joint_jacobian, joint_rows, chain_marker_state, chain_marker_jacobian
    use flexmbs_mbs_constraint_primitives_dual, only: marker_state_d => marker_state_t, &
        rigid_marker_state_d => rigid_marker_state, rigid_marker_pose_d => rigid_marker_pose, &
        ground_marker_state_d => ground_marker_state, &
        rigid_marker_jacobian_d => rigid_marker_jacobian, joint_value_d => joint_value, &
        joint_jacobian_d => joint_jacobian, joint_rows_d => joint_rows, &
        chain_marker_state_d => chain_marker_state, &
        chain_marker_jacobian_d => chain_marker_jacobian
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, chain_joint_spherical
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_mbs_driver, only: driver_t, driver_values
    use flexmbs_mbs_force_element, only: force_element_t, element_frame_t
    use flexmbs_mbs_jet, only: jet_t
    use flexmbs_mbs_constraint_primitives_jet, only: marker_state_j => marker_state_t, &
        ground_marker_state_j => ground_marker_state, joint_value_j => joint_value
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use flexmbs_mbs_node_frame, only: node_frame_t, node_frame_rows, frame_columns, &
        frame_value, frame_jacobian, frame_curvature, frame_jacobian_ad, frame_curvature_ad, &
        frame_rate_q, frame_gtl_q, frame_curvature_qv
    implicit none
    private

    !> `constraint_derivatives`: hand-coded first derivatives of the joint rows.
    integer, parameter, public :: constraint_derivatives_analytic = 1
    !> `constraint_derivatives`: AD of the joints' vector relations on the
    !> marker frames (dual numbers seeded with the markers' Jacobians; jets
    !> along the markers' motion for γ).
    integer, parameter, public :: constraint_derivatives_ad = 2
    !> `constraint_derivatives`: AD through the body coordinates (quaternions,
    !> chain angles) as well: slower, verifies the markers' Jacobians too.
    integer, parameter, public :: constraint_derivatives_ad_full = 3

    ! The derivative blocks' accumulators (mbs_system_t%acc): g_q and the
    ! other nc x nq blocks, G and ∂γ/∂v, ∂(Gᵀλ)/∂q, ∂f/∂q and ∂(M w)/∂q,
    ! ∂f/∂v, T, ∂(T w)/∂q.
    integer, parameter :: block_cq = 1, block_cv = 2, block_rq = 3, block_fq = 4, &
        block_fv = 5, block_kin = 6, block_kinq = 7

    ! marker_offsets reports a chain marker's body as -(chain_body_flag + chain).
    integer, parameter :: chain_body_flag = 1000
    ! The most rows of a joint (fixed: spherical + 3 dot-1).
    integer, parameter :: max_rows = 6
    ! Marker axes must be orthonormal to this (max |UᵀU - I|).
    real(wp), parameter :: axes_tolerance = 1.0e-10_wp
    ! Dual seeds of one marker's body (directions used): velocity-space
    ! tangents T e_l (6), position unit vectors e_l (7), velocity unit vectors
    ! (6), the rate q' = T v (1).
    integer, parameter :: seed_velocity_space = 1, seed_position = 2, seed_velocity = 3, &
        seed_rate = 4
    ! A marker's body columns are seeded in windows of at most this many per
    ! dual pass: two markers and time stay within dual_size = 16 directions
    ! (a chain of any size takes several passes; first derivatives are
    ! linear in the columns, so each window adds its own).
    integer, parameter :: window_columns = rigid_body_nq

    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])

    !> A frame fixed in a body (body >= 1) or in the ground (body = 0), or a
    !> point of a flexible body (flexible >= 1; body and position unused): a
    !> node (node >= 1), or the centroid of a node set (nodes, equal
    !> weights), with constant axes, for joints that use no marker rotation
    !> (a node: spherical, distance; a set: spherical, whose rows are then
    !> linear in the set's nodes).
    type, public :: marker_t
        integer :: body = 0 !! body number, 0 for the ground
        real(wp) :: position(3) = 0.0_wp !! origin: body coordinates (ground: global)
        real(wp) :: axes(3, 3) = identity3 !! orthonormal axes as columns, same frame
        integer :: flexible = 0 !! flexible body number (node and set markers)
        integer :: node = 0     !! its mesh node (node markers)
        integer :: chain = 0    !! rigid chain number (chain markers; position, axes
        integer :: link = 0     !! in the frame of this body of the chain)
        integer, allocatable :: nodes(:) !! set markers: the set's mesh nodes
    contains
        procedure :: on_node_set => marker_on_node_set
        procedure :: attached_to => marker_attached_to
    end type marker_t

    !> Workspace of one marker side of a joint or force element, sized by the
    !> largest marker body (a chain's columns): real and dual Jacobians
    !> (jw: angular velocity), joint-row blocks, an element's generalised
    !> forces g, and the pose duals p (a chain's coordinates, then its rates).
    type :: marker_work_t
        real(wp), allocatable :: jx(:, :), ja(:, :, :), c(:, :), jw(:, :)
        type(dual_t), allocatable :: p(:), jxd(:, :), jad(:, :, :), cd(:, :), g(:)
    end type marker_work_t

    !> A chain's joint geometry as plain arrays (for the marker formulas).
    type :: chain_geometry_t
        integer, allocatable :: parent(:), kinds(:), iq(:), iv(:)
        real(wp), allocatable :: jpos(:, :), jrot(:, :, :), axis(:, :)
    end type chain_geometry_t

    !> A joint of kind `kind` (joint_spherical ... joint_fixed) between two
    !> markers, or (kind joint_primitive) one constraint primitive on axes
    !> axis_i, axis_j of the markers, driven by `driver` where it has s(t).
    type, public :: mbs_joint_t
        integer :: kind = 0
        integer :: marker_i = 0
        integer :: marker_j = 0
        integer :: primitive = 0 !! joint_primitive: primitive_* kind
        integer :: axis_i = 1, axis_j = 1
        type(driver_t) :: driver
    end type mbs_joint_t

    type :: assembled_joint_t
        type(joint_t) :: joint
        type(driver_t) :: driver
        integer :: marker_i = 0, marker_j = 0
        integer :: row0 = 0 !! rows row0+1 .. row0+joint%nrows of c
        !> a spherical joint between points (nodes, set centroids) or a point
        !> and the ground: c is linear in q, so G is constant and every
        !> second derivative vanishes
        logical :: linear = .false.
    end type assembled_joint_t

    !> Where a flexible body's tangent entries go in the system's ∂f/∂q (q)
    !> and ∂f/∂v (v) patterns, slot by slot of its own pattern.
    type :: tangent_slots_t
        integer(i8), allocatable :: q(:), v(:)
    end type tangent_slots_t

    !> Rigid bodies, markers and joints as a mechanical problem (module header).
    type, extends(mechanical_problem_t), public :: mbs_system_t
        private
        type(rigid_bodies_t) :: rigid
        type(marker_t), allocatable :: markers(:)
        type(assembled_joint_t), allocatable :: joints(:)
        !> the constraint derivatives (constraint_derivatives_*): a setting, open to callers
        integer, public :: derivatives = constraint_derivatives_analytic
        integer :: nq_rigid = 0, nv_rigid = 0
        !> flexible bodies after the rigid ones in q and v; flexible body f's
        !> free coordinates are q(flex_q(f)+1 : flex_q(f)+nq_f), its velocities
        !> v(flex_v(f)+1 : flex_v(f)+nv_f)
        type(flexible_body_t), allocatable :: flex(:)
        integer, allocatable :: flex_q(:), flex_v(:)
        !> rigid chains in relative coordinates (revolute, prismatic and
        !> spherical joints, any number of coordinates), between the rigid and
        !> the flexible bodies
        type(rigid_chain_t), allocatable :: chains(:)
        !> scratch blocks of the largest chain (nv x nq, nv x nv, nq x nq) and
        !> vectors (nv, nq), for the chains' dense derivative blocks
        real(wp), allocatable :: chain_vq(:, :), chain_vv(:, :), chain_qq(:, :), &
            chain_unit(:), chain_rate(:)
        type(chain_geometry_t), allocatable :: chain_geom(:)
        !> modal bodies (floating frame, flexmbs_mbs_modal_body) after the
        !> flexible bodies: body f's (r, p, η) at q(modal_q(f)+1 ...), its
        !> velocities at v(modal_v(f)+1 ...); joints reach them through
        !> interface frames (node_frame_t with `modal` set)
        type(modal_body_t), allocatable :: modal(:)
        integer, allocatable :: modal_q(:), modal_v(:)
        !> scratch blocks of the largest modal body (nv x nq, nv x nv)
        real(wp), allocatable :: modal_vq(:, :), modal_vv(:, :)
        !> the markers' workspace (marker i, marker j), allocated when built;
        !> the evaluations that fill it take the system intent(inout)
        type(marker_work_t), allocatable :: work(:)
        integer, allocatable :: chain_q(:), chain_v(:)
        !> node frames (flexmbs_mbs_node_frame): massless rigid bodies held on
        !> node sets of the flexible bodies, rows after the joints' rows
        type(node_frame_t), allocatable :: frames(:)
        real(wp), allocatable :: zero_v(:) !! v = 0 for position-only evaluations
        !> copies of the CSC patterns handed out (their triplet maps place values)
        type(csc_matrix_t) :: mass_csc, jacobian_csc
        !> the derivative blocks' patterns (derivative_patterns) and one
        !> accumulator per block (block_*), dense or sparse, which the
        !> derivative code adds into: each keeps its shape and pattern, so
        !> no evaluation allocates. Allocatable: gfortran 12's finalization
        !> wrapper, which frees a polymorphic mbs_system_t, skipped three of
        !> the eight matrices of a non-allocatable `patterns` (a leak).
        type(mechanical_patterns_t), allocatable :: patterns
        type(accumulator_t) :: acc(7)
        !> each flexible body's tangent slots in patterns%force_q and %force_v
        type(tangent_slots_t), allocatable :: flex_slots(:)
        !> force elements between markers and applied loads (system_elements.f90)
        type(force_element_t), allocatable :: elements(:)
    contains
        procedure :: kinematics => system_kinematics
        procedure :: has_sparse => system_has_sparse
        procedure :: mass_pattern => system_mass_pattern
        procedure :: mass_sparse => system_mass_sparse
        procedure :: constraint_jacobian_pattern => system_constraint_jacobian_pattern
        procedure :: constraint_jacobian_sparse => system_constraint_jacobian_sparse
        procedure :: mass => system_mass
        procedure :: forces => system_forces
        procedure :: normalize => system_normalize
        procedure :: admissible => system_admissible
        procedure :: kinematics_derivative => system_kinematics_derivative
        procedure :: mass_derivative => system_mass_derivative
        procedure :: force_derivatives => system_force_derivatives
        procedure :: constraint => system_constraint
        procedure :: constraint_jacobian => system_constraint_jacobian
        procedure :: constraint_time_derivative => system_constraint_time_derivative
        procedure :: constraint_curvature => system_constraint_curvature
        procedure :: constraint_position_jacobian => system_constraint_position_jacobian
        procedure :: constraint_jacobian_derivatives => system_constraint_jacobian_derivatives
        procedure :: constraint_time_derivative_jacobian => &
            system_constraint_time_derivative_jacobian
        procedure :: constraint_curvature_derivatives => system_constraint_curvature_derivatives
        procedure :: has_sparse_derivatives => system_has_sparse_derivatives
        procedure :: derivative_patterns => system_derivative_patterns
        procedure :: kinematics_sparse => system_kinematics_sparse
        procedure :: kinematics_derivative_sparse => system_kinematics_derivative_sparse
        procedure :: mass_derivative_sparse => system_mass_derivative_sparse
        procedure :: force_derivatives_sparse => system_force_derivatives_sparse
        procedure :: constraint_position_jacobian_sparse => &
            system_constraint_position_jacobian_sparse
        procedure :: constraint_jacobian_derivatives_sparse => &
            system_constraint_jacobian_derivatives_sparse
        procedure :: constraint_time_derivative_jacobian_sparse => &
            system_constraint_time_derivative_jacobian_sparse
        procedure :: constraint_curvature_derivatives_sparse => &
            system_constraint_curvature_derivatives_sparse
        procedure :: joint_first_row => system_joint_first_row
        procedure :: joint_reaction => system_joint_reaction
        procedure :: element_wrench => system_element_wrench
        procedure :: marker_pose => system_marker_pose
        procedure :: energy => system_energy
        procedure :: total_energy => system_total_energy
        procedure :: momenta => system_momenta
        procedure :: chain_count => system_chain_count
        procedure :: link_count => system_link_count
        procedure :: link_coordinates => system_link_coordinates
        procedure :: flexible_count => system_flexible_count
        procedure :: flexible_coordinates => system_flexible_coordinates
        procedure :: joint_count => system_joint_count
        procedure :: joint_bodies => system_joint_bodies
        procedure :: joint_rows => system_joint_rows
        procedure :: element_count => system_element_count
        procedure :: element_bodies => system_element_bodies
        procedure :: part_count => system_part_count
        procedure :: part_offsets => system_part_offsets
        procedure :: chain_of => system_chain_of
        procedure :: flexible_of => system_flexible_of
        procedure :: modal_of => system_modal_of
        procedure :: joint_kind => system_joint_kind
        procedure :: joint_markers => system_joint_markers
        procedure :: joint_primitive_count => system_joint_primitive_count
        procedure :: joint_primitive => system_joint_primitive
        procedure :: joint_axis => system_joint_axis
        procedure :: marker_of => system_marker_of
        procedure :: rigid_body_of => system_rigid_body_of
        procedure :: element_of => system_element_of
        procedure :: frame_of => system_frame_of
    end type mbs_system_t

    public :: new_mbs_system, driver_t, driver_values, node_frame_t, force_element_t

    !> The kinds of parts, for mbs_system_t's part_count and part_offsets:
    !> rigid bodies, rigid chains, flexible bodies, modal bodies, node frames.
    integer, parameter, public :: part_rigid = 1, part_chain = 2, part_flexible = 3, &
        part_modal = 4, part_frame = 5


    interface
        ! sparse forms and derivative blocks (system_patterns.f90)
        logical module function system_has_sparse(self)
            class(mbs_system_t), intent(in) :: self
        end function system_has_sparse
        module subroutine system_mass_pattern(self, pattern, status)
            class(mbs_system_t), intent(inout) :: self
            type(csc_matrix_t), intent(inout) :: pattern
            type(status_t), intent(inout) :: status
        end subroutine system_mass_pattern
        module subroutine system_mass_sparse(self, t, q, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_mass_sparse
        module subroutine system_constraint_jacobian_pattern(self, pattern, status)
            class(mbs_system_t), intent(inout) :: self
            type(csc_matrix_t), intent(inout) :: pattern
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_jacobian_pattern
        module subroutine system_constraint_jacobian_sparse(self, t, q, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_jacobian_sparse
        logical module function system_has_sparse_derivatives(self)
            class(mbs_system_t), intent(in) :: self
        end function system_has_sparse_derivatives
        module subroutine system_derivative_patterns(self, patterns, status)
            class(mbs_system_t), intent(inout) :: self
            type(mechanical_patterns_t), intent(inout) :: patterns
            type(status_t), intent(inout) :: status
        end subroutine system_derivative_patterns
        module subroutine system_kinematics_sparse(self, t, q, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_kinematics_sparse
        module subroutine system_kinematics_derivative_sparse(self, t, q, w, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_kinematics_derivative_sparse
        module subroutine system_mass_derivative_sparse(self, t, q, w, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_mass_derivative_sparse
        module subroutine system_force_derivatives_sparse(self, t, q, v, fq, fv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: fq(:), fv(:)
            type(status_t), intent(inout) :: status
        end subroutine system_force_derivatives_sparse
        module subroutine system_constraint_position_jacobian_sparse(self, t, q, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_position_jacobian_sparse

        ! bodies, delegated (system_bodies.f90)
        module subroutine system_kinematics(self, t, q, w, qdot, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: qdot(:)
            type(status_t), intent(inout) :: status
        end subroutine system_kinematics
        module subroutine system_kinematics_derivative(self, t, q, w, dq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: dq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_kinematics_derivative
        module subroutine system_mass(self, t, q, m, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: m(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_mass
        module subroutine system_mass_derivative(self, t, q, w, dq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            real(wp), intent(out) :: dq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_mass_derivative
        module subroutine mass_derivative_into(self, t, q, w, dq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:)
            type(accumulator_t), intent(inout) :: dq
            type(status_t), intent(inout) :: status
        end subroutine mass_derivative_into
        module subroutine system_forces(self, t, q, v, f, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: f(:)
            type(status_t), intent(inout) :: status
        end subroutine system_forces
        module subroutine system_force_derivatives(self, t, q, v, fq, fv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: fq(:, :), fv(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_force_derivatives
        module subroutine system_admissible(self, q, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: q(:)
            type(status_t), intent(out) :: status
        end subroutine system_admissible
        module subroutine system_normalize(self, q)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(inout) :: q(:)
        end subroutine system_normalize
        real(wp) module function system_energy(self, q, v) result(e)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: q(:), v(:)
        end function system_energy
        real(wp) module function system_total_energy(self, q, v, q_ref) result(e)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: q(:), v(:)
            real(wp), intent(in), optional :: q_ref(:)
        end function system_total_energy
        module subroutine system_momenta(self, q, v, linear, angular)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: q(:), v(:)
            real(wp), intent(out) :: linear(3), angular(3)
        end subroutine system_momenta

        ! markers, real and dual; drivers (system_markers.f90)
        pure integer module function frame_column(fr, l, position_space) result(c)
            type(node_frame_t), intent(in) :: fr
            integer, intent(in) :: l
            logical, intent(in) :: position_space
        end function frame_column
        pure module subroutine add_frame_columns(fr, position_space, block, row0, out)
            type(node_frame_t), intent(in) :: fr
            logical, intent(in) :: position_space
            real(wp), intent(in) :: block(:, :)
            integer, intent(in) :: row0
            type(accumulator_t), intent(inout) :: out
        end subroutine add_frame_columns
        module subroutine frame_first_derivatives(self, i, q, position_space, block)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: i
            real(wp), intent(in) :: q(:)
            logical, intent(in) :: position_space
            real(wp), intent(out) :: block(:, :)
        end subroutine frame_first_derivatives
        pure module subroutine marker_offsets(self, k, body, iq, iv)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            integer, intent(out) :: body, iq, iv
        end subroutine marker_offsets
        pure integer module function marker_columns(self, k, position_space) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            logical, intent(in) :: position_space
        end function marker_columns
        !> World position x and axes (columns) of marker k at positions q.
        pure module subroutine system_marker_pose(self, k, q, x, axes)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: q(:)
            real(wp), intent(out) :: x(3), axes(3, 3)
        end subroutine system_marker_pose
        pure module subroutine marker_state(self, k, q, v, m)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: q(:), v(:)
            type(marker_state_t), intent(out) :: m
        end subroutine marker_state
        pure module subroutine marker_jacobian(self, k, q, position_space, jx, ja, n, p)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: q(:)
            logical, intent(in) :: position_space
            real(wp), intent(out) :: jx(:, :), ja(:, :, :) !! 3 x n (x 3) at least
            integer, intent(out) :: n
            !> pose duals (position space on a chain with quaternions)
            type(dual_t), intent(inout), optional :: p(:)
        end subroutine marker_jacobian
        pure module subroutine marker_state_dual(self, k, q, v, seed, first, m, p, n, pose_only, &
                                                 window)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k, seed, first
            logical, intent(in), optional :: pose_only
            !> seed the body's columns (window - 1) window_columns + 1 .. (default 1)
            integer, intent(in), optional :: window
            real(wp), intent(in) :: q(:), v(:)
            type(marker_state_d), intent(out) :: m
            type(dual_t), intent(inout) :: p(:) !! pose duals (marker_work_t)
            integer, intent(out) :: n
        end subroutine marker_state_dual
        pure module subroutine marker_jacobian_dual(self, k, p, jx, ja)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            type(dual_t), intent(in) :: p(:)
            type(dual_t), intent(out) :: jx(:, :), ja(:, :, :) !! 3 x nv (x 3) at least
        end subroutine marker_jacobian_dual
        pure module subroutine chain_state_dual(self, k, q, v, seed, first, iq, iv, c0, m, p, n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k, seed, first, iq, iv, c0
            real(wp), intent(in) :: q(:), v(:)
            type(marker_state_d), intent(out) :: m
            type(dual_t), intent(inout) :: p(:)
            integer, intent(out) :: n
        end subroutine chain_state_dual
        pure integer module function marker_windows(self, k, position_space) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            logical, intent(in) :: position_space
        end function marker_windows
        pure module subroutine chain_rates(self, c, qc, vc, rate)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: c
            real(wp), intent(in) :: qc(:), vc(:)
            real(wp), intent(out) :: rate(:)
        end subroutine chain_rates
        pure module subroutine chain_jacobian_real(self, k, q, iq, position_space, jx, ja, p)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k, iq
            real(wp), intent(in) :: q(:)
            logical, intent(in) :: position_space
            real(wp), intent(out) :: jx(:, :), ja(:, :, :)
            type(dual_t), intent(inout), optional :: p(:)
        end subroutine chain_jacobian_real
        pure module function joint_driver(self, k, t) result(drv)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: t
            real(wp) :: drv(3)
        end function joint_driver
        pure module function driver_dual(drv, td) result(d)
            real(wp), intent(in) :: drv(3)
            integer, intent(in) :: td
            type(dual_t) :: d(3)
        end function driver_dual
        !> Whether marker k is the centroid of a node set.
        pure logical module function is_set_marker(self, k)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
        end function is_set_marker
        !> Offset in q (position space) or v of node a of set marker k's x coordinate.
        pure integer module function set_node_offset(self, k, a, position_space) result(c)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k, a
            logical, intent(in) :: position_space
        end function set_node_offset
        pure module subroutine add_columns(self, k, position_space, block, row0, out)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            logical, intent(in) :: position_space
            real(wp), intent(in) :: block(:, :)
            integer, intent(in) :: row0
            type(accumulator_t), intent(inout) :: out
        end subroutine add_columns
        pure module subroutine seeded_frame(m, jx, ja, off, md)
            type(marker_state_t), intent(in) :: m
            real(wp), intent(in) :: jx(:, :), ja(:, :, :)
            integer, intent(in) :: off
            type(marker_state_d), intent(out) :: md
        end subroutine seeded_frame
        pure module subroutine moving_frame(m, mj)
            type(marker_state_t), intent(in) :: m
            type(marker_state_j), intent(out) :: mj
        end subroutine moving_frame

        ! joint rows and their first derivatives; reactions (system_constraints.f90)
        module subroutine joint_first_derivatives(self, k, t, q, position_space, ci, cj, ni, nj, ct)
            class(mbs_system_t), intent(inout) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: t, q(:)
            logical, intent(in) :: position_space
            !> max_rows x ni, nj at least (the workspace's c)
            real(wp), intent(out) :: ci(:, :), cj(:, :)
            integer, intent(out) :: ni, nj
            real(wp), intent(out) :: ct(max_rows)
        end subroutine joint_first_derivatives
        module subroutine system_constraint(self, t, q, g, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: g(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint
        module subroutine system_constraint_jacobian(self, t, q, gmat, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: gmat(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_jacobian
        module subroutine system_constraint_position_jacobian(self, t, q, gq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: gq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_position_jacobian
        module subroutine assemble_first_derivative(self, t, q, position_space, out)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            logical, intent(in) :: position_space
            type(accumulator_t), intent(inout) :: out
        end subroutine assemble_first_derivative
        module subroutine system_constraint_time_derivative(self, t, q, gt, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: gt(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_time_derivative
        module subroutine system_constraint_curvature(self, t, q, v, gamma, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: gamma(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_curvature
        module subroutine system_joint_reaction(self, k, t, q, lambda, force, torque)
            class(mbs_system_t), intent(inout) :: self
            integer, intent(in) :: k
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(in) :: lambda(:) !! all nc multipliers
            real(wp), intent(out) :: force(3, 2), torque(3, 2)
        end subroutine system_joint_reaction

        ! force elements (system_elements.f90)
        module subroutine place_elements(self, elements, status)
            type(mbs_system_t), intent(inout) :: self
            type(force_element_t), intent(in) :: elements(:)
            type(status_t), intent(inout) :: status
        end subroutine place_elements
        module subroutine element_generalised(self, ie, t, q, v, seed, window, gi, gj, ni, nj, &
                                              di, dj, offj, status)
            class(mbs_system_t), intent(inout) :: self
            integer, intent(in) :: ie, seed, window
            real(wp), intent(in) :: t, q(:), v(:)
            type(dual_t), intent(out) :: gi(:), gj(:) !! the workspace's g
            integer, intent(out) :: ni, nj, di, dj, offj
            type(status_t), intent(inout) :: status
        end subroutine element_generalised
        module subroutine add_element_forces(self, t, q, v, f, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(inout) :: f(:)
            type(status_t), intent(inout) :: status
        end subroutine add_element_forces
        module subroutine add_element_derivatives(self, t, q, v, fq, fv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            type(accumulator_t), intent(inout) :: fq, fv
            type(status_t), intent(inout) :: status
        end subroutine add_element_derivatives
        ! force elements, hand-coded derivatives (system_element_tangents.f90)
        module subroutine add_element_forces_analytic(self, t, q, v, f, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(inout) :: f(:)
            type(status_t), intent(inout) :: status
        end subroutine add_element_forces_analytic
        module subroutine add_element_derivatives_analytic(self, t, q, v, fq, fv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            type(accumulator_t), intent(inout) :: fq, fv
            type(status_t), intent(inout) :: status
        end subroutine add_element_derivatives_analytic
        pure module subroutine frame_of_state(ms, fr)
            type(marker_state_d), intent(in) :: ms
            type(element_frame_t), intent(out) :: fr
        end subroutine frame_of_state
        module subroutine add_element_patterns(self, fq, fv)
            class(mbs_system_t), intent(in) :: self
            type(triplets_t), intent(inout) :: fq, fv
        end subroutine add_element_patterns
        real(wp) module function elements_energy(self, q, v) result(e)
            class(mbs_system_t), intent(in) :: self
            real(wp), intent(in) :: q(:), v(:)
        end function elements_energy
        !> Force and torque (global; torque about the marker's origin) that
        !> force element ie exerts on marker i (column 1) and marker j (column 2).
        module subroutine system_element_wrench(self, ie, t, q, v, force, torque, status)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: ie
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: force(3, 2), torque(3, 2)
            type(status_t), intent(inout) :: status
        end subroutine system_element_wrench

        ! second derivatives by AD (system_second_derivatives.f90)
        module subroutine system_constraint_jacobian_derivatives(self, t, q, w, lambda, gwq, gtlq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:), lambda(:)
            real(wp), intent(out) :: gwq(:, :), gtlq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_jacobian_derivatives
        module subroutine system_constraint_jacobian_derivatives_sparse(self, t, q, w, lambda, gwq, &
                                                                 gtlq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:), lambda(:)
            real(wp), intent(out) :: gwq(:), gtlq(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_jacobian_derivatives_sparse
        module subroutine jacobian_derivatives_into(self, t, q, w, lambda, gwq, gtlq)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), w(:), lambda(:)
            type(accumulator_t), intent(inout) :: gwq, gtlq
        end subroutine jacobian_derivatives_into
        !> keep_i, keep_j false: that side is a set marker, whose tangents
        !> vanish (its rows are linear in the nodes) and whose three
        !> columns are no body's
        pure module subroutine add_tangents(out, row, s, qi, iqi, qj, iqj, keep_i, keep_j)
            type(accumulator_t), intent(inout) :: out
            integer, intent(in) :: row, qi, iqi, qj, iqj
            type(dual_t), intent(in) :: s
            logical, intent(in) :: keep_i, keep_j
        end subroutine add_tangents
        module subroutine system_constraint_time_derivative_jacobian(self, t, q, dq, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: dq(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_time_derivative_jacobian
        module subroutine system_constraint_time_derivative_jacobian_sparse(self, t, q, values, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            real(wp), intent(out) :: values(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_time_derivative_jacobian_sparse
        module subroutine time_derivative_jacobian_into(self, t, q, dq)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:)
            type(accumulator_t), intent(inout) :: dq
        end subroutine time_derivative_jacobian_into
        module subroutine system_constraint_curvature_derivatives(self, t, q, v, gq, gv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: gq(:, :), gv(:, :)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_curvature_derivatives
        module subroutine system_constraint_curvature_derivatives_sparse(self, t, q, v, gq, gv, status)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            real(wp), intent(out) :: gq(:), gv(:)
            type(status_t), intent(inout) :: status
        end subroutine system_constraint_curvature_derivatives_sparse
        module subroutine curvature_derivatives_into(self, t, q, v, gq, gv)
            class(mbs_system_t), intent(inout) :: self
            real(wp), intent(in) :: t, q(:), v(:)
            type(accumulator_t), intent(inout) :: gq, gv
        end subroutine curvature_derivatives_into
        !> The system of `bodies` under `gravity`, with `markers` and `joints`;
        !> `constraint_derivatives` is 'analytic' (default) or 'ad'. On bad input
        !> `status` says which item is wrong and why.
        module function new_mbs_system(bodies, markers, joints, gravity, constraint_derivatives, &
                                           status, flexible, chains, frames, elements, modal) &
                                           result(self)
            type(rigid_body_t), intent(in) :: bodies(:)
            type(marker_t), intent(in) :: markers(:)
            type(mbs_joint_t), intent(in) :: joints(:)
            real(wp), intent(in), optional :: gravity(3)
            character(len=*), intent(in), optional :: constraint_derivatives !! 'analytic' | 'ad'
            type(status_t), intent(out) :: status
            !> flexible bodies (their own gravity and loads), after the rigid ones
            type(flexible_body_t), intent(in), optional :: flexible(:)
            !> rigid chains (their own gravity), after the rigid bodies
            type(rigid_chain_t), intent(in), optional :: chains(:)
            !> node frames: flexible, body (a frame body of `bodies`) and nodes
            !> given; the rest is filled in here
            type(node_frame_t), intent(in), optional :: frames(:)
            !> force elements between the markers and applied loads on them
            type(force_element_t), intent(in), optional :: elements(:)
            !> modal bodies (their own gravity), after the flexible bodies
            type(modal_body_t), intent(in), optional :: modal(:)
            type(mbs_system_t) :: self
        end function new_mbs_system

        ! The system's parts as the outer layers see them (system_views).
        !> The number of rigid chains.
        pure integer module function system_chain_count(self) result(n)
            class(mbs_system_t), intent(in) :: self
        end function system_chain_count
        !> The number of links (bodies) of chain c.
        pure integer module function system_link_count(self, c) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: c
        end function system_link_count
        !> The joint coordinates of link i of chain c: q(offset + 1:offset + n).
        pure module subroutine system_link_coordinates(self, c, i, offset, n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: c, i
            integer, intent(out) :: offset, n
        end subroutine system_link_coordinates
        !> The number of (nonlinear) flexible bodies.
        pure integer module function system_flexible_count(self) result(n)
            class(mbs_system_t), intent(in) :: self
        end function system_flexible_count
        !> The free nodal coordinates of flexible body i: q(offset + 1:offset + n).
        pure module subroutine system_flexible_coordinates(self, i, offset, n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: i
            integer, intent(out) :: offset, n
        end subroutine system_flexible_coordinates
        !> The number of joints (node frames not counted).
        pure integer module function system_joint_count(self) result(n)
            class(mbs_system_t), intent(in) :: self
        end function system_joint_count
        !> The bodies of joint j's markers i and j (their `body`: 0 the ground).
        pure module function system_joint_bodies(self, j) result(bodies)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
            integer :: bodies(2)
        end function system_joint_bodies
        !> The number of constraint rows of joint j (from joint_first_row on).
        pure integer module function system_joint_rows(self, j) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
        end function system_joint_rows
        !> The number of force elements.
        pure integer module function system_element_count(self) result(n)
            class(mbs_system_t), intent(in) :: self
        end function system_element_count
        !> The bodies force element k acts on: 1 (an applied load, marker i's)
        !> or 2 (between markers i and j).
        pure integer module function system_element_bodies(self, k) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
        end function system_element_bodies
        !> The number of parts of kind `part` (part_rigid: the rigid bodies,
        !> node frames' massless bodies counted; part_chain, part_flexible,
        !> part_modal; part_frame: the node frames); 0 for another number.
        pure integer module function system_part_count(self, part) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: part
        end function system_part_count
        !> Where part i of kind `part` (part_chain, part_flexible, part_modal)
        !> starts in q and v: q(oq + 1 ...), v(ov + 1 ...); -1 for another kind.
        pure module subroutine system_part_offsets(self, part, i, oq, ov)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: part, i
            integer, intent(out) :: oq, ov
        end subroutine system_part_offsets
        !> Chain c itself (the system, and so the pointer's target, must be a target).
        module function system_chain_of(self, c) result(chain)
            class(mbs_system_t), intent(in), target :: self
            integer, intent(in) :: c
            type(rigid_chain_t), pointer :: chain
        end function system_chain_of
        !> Flexible body i itself (the system must be a target).
        module function system_flexible_of(self, i) result(body)
            class(mbs_system_t), intent(in), target :: self
            integer, intent(in) :: i
            type(flexible_body_t), pointer :: body
        end function system_flexible_of
        !> Modal body i itself (the system must be a target).
        module function system_modal_of(self, i) result(body)
            class(mbs_system_t), intent(in), target :: self
            integer, intent(in) :: i
            type(modal_body_t), pointer :: body
        end function system_modal_of
        !> The kind of joint j (joint_spherical ... joint_primitive of the joint table).
        pure integer module function system_joint_kind(self, j) result(kind)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
        end function system_joint_kind
        !> Joint j's markers i and j (for marker_pose).
        pure module function system_joint_markers(self, j) result(markers)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
            integer :: markers(2)
        end function system_joint_markers
        !> The number of constraint primitives joint j is made of.
        pure integer module function system_joint_primitive_count(self, j) result(n)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
        end function system_joint_primitive_count
        !> The kind (primitive_*) of joint j's primitive p, in the order of its rows.
        pure integer module function system_joint_primitive(self, j, p) result(kind)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j, p
        end function system_joint_primitive
        !> The axis (1, 2, 3 of marker i's frame) of joint j's first primitive.
        pure integer module function system_joint_axis(self, j) result(axis)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: j
        end function system_joint_axis
        !> Marker k (a copy).
        pure module function system_marker_of(self, k) result(marker)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            type(marker_t) :: marker
        end function system_marker_of
        !> Rigid body b, node frames after the scene's bodies (a copy).
        pure module function system_rigid_body_of(self, b) result(body)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: b
            type(rigid_body_t) :: body
        end function system_rigid_body_of
        !> Force element e (a copy).
        pure module function system_element_of(self, e) result(element)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: e
            type(force_element_t) :: element
        end function system_element_of
        !> Node frame k (a copy).
        pure module function system_frame_of(self, k) result(frame)
            class(mbs_system_t), intent(in) :: self
            integer, intent(in) :: k
            type(node_frame_t) :: frame
        end function system_frame_of
    end interface

contains

    !> First row of joint k in c (rows joint_first_row(k) + 0 .. nrows - 1);
    !> k = size(joints) + i: node frame i (6 rows).
    pure integer function system_joint_first_row(self, k) result(row)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        if (k > size(self%joints)) then
            row = self%frames(k - size(self%joints))%row0 + 1
        else
            row = self%joints(k)%row0 + 1
        end if
    end function system_joint_first_row

    !> Makes the marker a set marker: on the nodes `nodes` of flexible body
    !> `flexible` (component by component: a structure constructor with an
    !> allocatable component leaks its temporary in gfortran 12).
    pure subroutine marker_on_node_set(self, flexible, nodes)
        class(marker_t), intent(inout) :: self
        integer, intent(in) :: flexible, nodes(:)
        self%flexible = flexible
        self%nodes = nodes
    end subroutine marker_on_node_set

    !> What carries the marker: its body (0: the ground or none), its chain
    !> and the chain's link (0: none).
    pure subroutine marker_attached_to(self, body, chain, link)
        class(marker_t), intent(in) :: self
        integer, intent(out) :: body, chain, link
        body = self%body
        chain = self%chain
        link = self%link
    end subroutine marker_attached_to
end module flexmbs_mbs_system
