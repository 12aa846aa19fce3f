!> The assembled multibody system (DESIGN.md, the mechanical model): rigid
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
!> Joint reactions (`joint_reaction`), our sign of λ (DESIGN.md: M v' =
!> f − Gᵀλ): the generalised force of joint k on a body is −C_bᵀλ_k, C_b
!> the joint's columns of G for that body; it is reported as the force F
!> (global) and the torque n (global) about the marker's origin that the
!> joint exerts on the body. A body hanging at rest from a spherical joint
!> is held up: F = −m g (upwards, for gravity g).
module flexmbs_mbs_system
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
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
    use flexmbs_mbs_jet, only: jet_t
    use flexmbs_mbs_constraint_primitives_jet, only: marker_state_j => marker_state_t, &
        ground_marker_state_j => ground_marker_state, joint_value_j => joint_value
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use flexmbs_mbs_node_frame, only: node_frame_t, node_frame_rows, frame_columns, &
        frame_value, frame_jacobian, frame_curvature, frame_jacobian_ad, frame_curvature_ad, &
        frame_rate_q, frame_gtl_q, frame_curvature_qv
    implicit none
    private

    !> constraint_derivatives: hand-coded first derivatives of the joint rows.
    integer, parameter, public :: constraint_derivatives_analytic = 1
    !> constraint_derivatives: AD of the joints' vector relations on the
    !> marker frames (dual numbers seeded with the markers' Jacobians; jets
    !> along the markers' motion for γ).
    integer, parameter, public :: constraint_derivatives_ad = 2
    !> constraint_derivatives: AD through the body coordinates (quaternions,
    !> chain angles) as well: slower, verifies the markers' Jacobians too.
    integer, parameter, public :: constraint_derivatives_ad_full = 3

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

    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])

    !> A frame fixed in a body (body >= 1) or in the ground (body = 0), or a
    !> node of a flexible body (flexible >= 1, node >= 1; body and position
    !> unused): the node's position with constant axes, for joints that use
    !> no marker rotation (spherical, distance).
    type, public :: marker_t
        integer :: body = 0 !! body number, 0 for the ground
        real(wp) :: position(3) = 0.0_wp !! origin: body coordinates (ground: global)
        real(wp) :: axes(3, 3) = identity3 !! orthonormal axes as columns, same frame
        integer :: flexible = 0 !! flexible body number (node markers)
        integer :: node = 0     !! its mesh node
        integer :: chain = 0    !! rigid chain number (chain markers; position, axes
        integer :: link = 0     !! in the frame of this body of the chain)
    end type marker_t

    !> A chain's joint geometry as plain arrays (for the marker formulas).
    type :: chain_geometry_t
        integer, allocatable :: parent(:), kinds(:), iq(:), iv(:)
        real(wp), allocatable :: jpos(:, :), jrot(:, :, :), axis(:, :)
    end type chain_geometry_t

    !> A prescribed function of time, s(t) = Σ_k poly(k) t^k + amplitude
    !> sin(frequency t + phase): constant, constant rate, polynomial, harmonic.
    type, public :: driver_t
        real(wp) :: poly(0:3) = 0.0_wp
        real(wp) :: amplitude = 0.0_wp
        real(wp) :: frequency = 0.0_wp !! ω [rad/s]
        real(wp) :: phase = 0.0_wp     !! φ [rad]
    end type driver_t

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
    end type assembled_joint_t

    !> Rigid bodies, markers and joints as a mechanical problem (module header).
    type, extends(mechanical_problem_t), public :: mbs_system_t
        type(rigid_bodies_t) :: rigid
        type(marker_t), allocatable :: markers(:)
        type(assembled_joint_t), allocatable :: joints(:)
        integer :: derivatives = constraint_derivatives_analytic
        integer :: nq_rigid = 0, nv_rigid = 0
        !> flexible bodies after the rigid ones in q and v; flexible body f's
        !> free coordinates are q(flex_q(f)+1 : flex_q(f)+nq_f), its velocities
        !> v(flex_v(f)+1 : flex_v(f)+nv_f)
        type(flexible_body_t), allocatable :: flex(:)
        integer, allocatable :: flex_q(:), flex_v(:)
        !> rigid chains in relative coordinates (revolute and prismatic joints,
        !> at most 7 coordinates each), between the rigid and the flexible bodies
        type(rigid_chain_t), allocatable :: chains(:)
        type(chain_geometry_t), allocatable :: chain_geom(:)
        integer, allocatable :: chain_q(:), chain_v(:)
        !> node frames (flexmbs_mbs_node_frame): massless rigid bodies held on
        !> node sets of the flexible bodies, rows after the joints' rows
        type(node_frame_t), allocatable :: frames(:)
        real(wp), allocatable :: zero_v(:) !! v = 0 for position-only evaluations
        !> copies of the CSC patterns handed out (their triplet maps place values)
        type(csc_matrix_t) :: mass_csc, jacobian_csc
        !> the derivative blocks' patterns (derivative_patterns) and two
        !> accumulators the derivative code adds into, dense or sparse
        type(mechanical_patterns_t) :: patterns
        type(accumulator_t) :: acc(2)
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
        procedure :: energy => system_energy
        procedure :: momenta => system_momenta
    end type mbs_system_t

    public :: new_mbs_system, driver_values, node_frame_t

contains

    !> The system of `bodies` under `gravity`, with `markers` and `joints`;
    !> `constraint_derivatives` is 'analytic' (default) or 'ad'. On bad input
    !> `status` says which item is wrong and why.
    function new_mbs_system(bodies, markers, joints, gravity, constraint_derivatives, &
                            status, flexible, chains, frames) result(self)
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
        type(mbs_system_t) :: self
        integer :: k, row0, f
        character(len=:), allocatable :: where

        self%rigid = new_rigid_bodies(bodies, gravity, status)
        if (.not. status%ok()) return
        if (present(constraint_derivatives)) then
            select case (constraint_derivatives)
            case ('analytic')
                self%derivatives = constraint_derivatives_analytic
            case ('ad')
                self%derivatives = constraint_derivatives_ad
            case ('ad_full')
                self%derivatives = constraint_derivatives_ad_full
            case default
                call status%set(status_bad_input, 'mbs system: constraint_derivatives = ''' &
                                // constraint_derivatives // ''': use ''analytic'', ''ad'' or &
                                &''ad_full''')
                return
            end select
        end if
        if (present(flexible)) then
            self%flex = flexible
        else
            allocate (self%flex(0))
        end if
        if (present(chains)) then
            self%chains = chains
        else
            allocate (self%chains(0))
        end if
        allocate (self%chain_geom(size(self%chains)))
        do f = 1, size(self%chains)
            associate (ch => self%chains(f), g => self%chain_geom(f))
                if (ch%nq > rigid_body_nq) then
                    call status%set(status_bad_input, 'mbs system: chain ' // int_text(f) // &
                        ': at most ' // int_text(rigid_body_nq) // ' coordinates inside a system')
                    return
                end if
                g%parent = ch%bodies%parent
                g%kinds = ch%bodies%joint
                g%iq = ch%iq(1:size(ch%bodies))
                g%iv = ch%iv(1:size(ch%bodies))
                allocate (g%jpos(3, size(ch%bodies)), g%jrot(3, 3, size(ch%bodies)), &
                          g%axis(3, size(ch%bodies)))
                do k = 1, size(ch%bodies)
                    g%jpos(:, k) = ch%bodies(k)%joint_position
                    g%jrot(:, :, k) = ch%bodies(k)%joint_rotation
                    g%axis(:, k) = ch%bodies(k)%axis
                end do
            end associate
        end do
        do k = 1, size(markers)
            where = 'mbs system: marker ' // int_text(k)
            if (markers(k)%chain /= 0) then
                if (markers(k)%chain < 1 .or. markers(k)%chain > size(self%chains)) then
                    call status%set(status_bad_input, where // ': chain = ' // &
                        int_text(markers(k)%chain) // ': must name a chain 1 .. ' // &
                        int_text(size(self%chains)))
                    return
                end if
                if (markers(k)%link < 1 .or. &
                    markers(k)%link > size(self%chains(markers(k)%chain)%bodies)) then
                    call status%set(status_bad_input, where // ': link ' // &
                        int_text(markers(k)%link) // ' is not a body of its chain')
                    return
                end if
            end if
            if (markers(k)%flexible /= 0) then
                if (markers(k)%flexible < 1 .or. markers(k)%flexible > size(self%flex)) then
                    call status%set(status_bad_input, where // ': flexible = ' // &
                        int_text(markers(k)%flexible) // ': must name a flexible body 1 .. ' &
                        // int_text(size(self%flex)))
                    return
                end if
                associate (fb => self%flex(markers(k)%flexible))
                    if (markers(k)%node < 1 .or. markers(k)%node > fb%mesh%node_count()) then
                        call status%set(status_bad_input, where // ': node ' // &
                            int_text(markers(k)%node) // ' outside the mesh')
                        return
                    end if
                    if (any(fb%dof(:, markers(k)%node) == 0) .or. &
                        fb%dof(2, markers(k)%node) /= fb%dof(1, markers(k)%node) + 1 .or. &
                        fb%dof(3, markers(k)%node) /= fb%dof(1, markers(k)%node) + 2) then
                        call status%set(status_bad_input, where // ': node ' // &
                            int_text(markers(k)%node) // ' is fixed (a node marker needs &
                            &a free node)')
                        return
                    end if
                end associate
            end if
            if (markers(k)%body < 0 .or. markers(k)%body > size(bodies)) then
                call status%set(status_bad_input, where // ': body = ' // &
                                int_text(markers(k)%body) // ': must be 0 (ground) .. ' // &
                                int_text(size(bodies)))
                return
            end if
            if (maxval(abs(matmul(transpose(markers(k)%axes), markers(k)%axes) - identity3)) &
                > axes_tolerance) then
                call status%set(status_bad_input, where // ': axes are not orthonormal')
                return
            end if
        end do
        allocate (self%joints(size(joints)))
        row0 = 0
        do k = 1, size(joints)
            where = 'mbs system: joint ' // int_text(k)
            associate (ji => joints(k), jt => self%joints(k))
                if (min(ji%marker_i, ji%marker_j) < 1 .or. &
                    max(ji%marker_i, ji%marker_j) > size(markers)) then
                    call status%set(status_bad_input, where // ': markers ' // &
                                    int_text(ji%marker_i) // ', ' // int_text(ji%marker_j) // &
                                    ': must name markers 1 .. ' // int_text(size(markers)))
                    return
                end if
                if (markers(ji%marker_i)%flexible + markers(ji%marker_j)%flexible > 0) then
                    if (ji%kind /= joint_spherical .and. .not. (ji%kind == joint_primitive &
                        .and. ji%primitive == primitive_distance)) then
                        call status%set(status_bad_input, where // ': a node marker (no &
                            &rotation) takes spherical joints and distances only')
                        return
                    end if
                else if (markers(ji%marker_i)%body == markers(ji%marker_j)%body .and. &
                         markers(ji%marker_i)%chain == 0 .and. &
                         markers(ji%marker_j)%chain == 0) then
                    call status%set(status_bad_input, where // ': both markers are on body ' &
                                    // int_text(markers(ji%marker_i)%body) // &
                                    ': a joint connects two different bodies (or a body &
                                    &and the ground)')
                    return
                end if
                if (ji%kind == joint_primitive) then
                    call new_primitive_joint(jt%joint, ji%primitive, ji%axis_i, ji%axis_j, &
                                             status)
                else
                    call new_joint(jt%joint, ji%kind, status)
                end if
                jt%driver = ji%driver
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // ': ' // status%text())
                    return
                end if
                jt%marker_i = ji%marker_i
                jt%marker_j = ji%marker_j
                jt%row0 = row0
                row0 = row0 + jt%joint%nrows
            end associate
        end do
        self%markers = markers
        self%nq_rigid = self%rigid%nq
        self%nv_rigid = self%rigid%nv
        allocate (self%flex_q(size(self%flex)), self%flex_v(size(self%flex)), &
                  self%chain_q(size(self%chains)), self%chain_v(size(self%chains)))
        self%nq = self%nq_rigid
        self%nv = self%nv_rigid
        do f = 1, size(self%chains)
            self%chain_q(f) = self%nq
            self%chain_v(f) = self%nv
            self%nq = self%nq + self%chains(f)%nq
            self%nv = self%nv + self%chains(f)%nv
        end do
        do f = 1, size(self%flex)
            self%flex_q(f) = self%nq
            self%flex_v(f) = self%nv
            self%nq = self%nq + self%flex(f)%nq
            self%nv = self%nv + self%flex(f)%nv
        end do
        if (present(frames)) then
            self%frames = frames
        else
            allocate (self%frames(0))
        end if
        call place_frames(self, bodies, row0, status)
        if (.not. status%ok()) return
        self%nc = row0
        allocate (self%zero_v(self%nv))
        self%zero_v = 0.0_wp
    end function new_mbs_system

    !> Check the node frames and place them: reference offsets, their bodies'
    !> and nodes' offsets in q and v, six rows each after row0 (updated).
    subroutine place_frames(self, bodies, row0, status)
        type(mbs_system_t), intent(inout) :: self
        type(rigid_body_t), intent(in) :: bodies(:)
        integer, intent(inout) :: row0
        type(status_t), intent(inout) :: status
        type(flexible_marker_t) :: fit
        character(len=:), allocatable :: where
        integer :: i, a, b, f, node
        do b = 1, size(bodies)
            if (bodies(b)%frame .and. count(self%frames%body == b) /= 1) then
                call status%set(status_bad_input, 'mbs system: rigid body ' // int_text(b) // &
                    ' is a frame: exactly one node frame must hold it')
                return
            end if
        end do
        do i = 1, size(self%frames)
            where = 'mbs system: node frame ' // int_text(i)
            associate (fr => self%frames(i))
                f = fr%flexible
                b = fr%body
                if (f < 1 .or. f > size(self%flex)) then
                    call status%set(status_bad_input, where // ': flexible = ' // int_text(f) &
                        // ': must name a flexible body 1 .. ' // int_text(size(self%flex)))
                    return
                end if
                if (b < 1 .or. b > size(bodies)) then
                    call status%set(status_bad_input, where // ': body = ' // int_text(b) // &
                        ': must name a rigid body 1 .. ' // int_text(size(bodies)))
                    return
                end if
                if (.not. bodies(b)%frame) then
                    call status%set(status_bad_input, where // ': rigid body ' // int_text(b) &
                        // ' is not a frame (massless) body')
                    return
                end if
                associate (fb => self%flex(f))
                    do a = 1, size(fr%nodes)
                        node = fr%nodes(a)
                        if (node < 1 .or. node > fb%mesh%node_count()) then
                            call status%set(status_bad_input, where // ': node ' // &
                                int_text(node) // ' outside the mesh')
                            return
                        end if
                        if (any(fb%dof(:, node) == 0) .or. &
                            fb%dof(2, node) /= fb%dof(1, node) + 1 .or. &
                            fb%dof(3, node) /= fb%dof(1, node) + 2) then
                            call status%set(status_bad_input, where // ': node ' // &
                                int_text(node) // ' is fixed (a node frame needs free nodes)')
                            return
                        end if
                    end do
                    call new_flexible_marker(fit, fb%mesh%x, fr%nodes, status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, where // ': ' // status%text())
                        return
                    end if
                    fr%s = fit%dx_ref
                    fr%weight = fit%weight
                    fr%iq = rigid_body_nq * (b - 1)
                    fr%iv = rigid_body_nv * (b - 1)
                    allocate (fr%nq(size(fr%nodes)), fr%nv(size(fr%nodes)))
                    do a = 1, size(fr%nodes)
                        fr%nq(a) = self%flex_q(f) + fb%dof(1, fr%nodes(a)) - 1
                        fr%nv(a) = self%flex_v(f) + fb%dof(1, fr%nodes(a)) - 1
                    end do
                end associate
                fr%row0 = row0
                row0 = row0 + node_frame_rows
            end associate
        end do
    end subroutine place_frames

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

    !> Global column of frame fr's local column l (flexmbs_mbs_node_frame).
    pure integer function frame_column(fr, l, position_space) result(c)
        type(node_frame_t), intent(in) :: fr
        integer, intent(in) :: l
        logical, intent(in) :: position_space
        integer :: nb, a
        nb = merge(rigid_body_nq, rigid_body_nv, position_space)
        if (l <= nb) then
            c = merge(fr%iq, fr%iv, position_space) + l
        else
            a = (l - nb - 1) / 3 + 1
            c = merge(fr%nq(a), fr%nv(a), position_space) + l - nb - 3 * (a - 1)
        end if
    end function frame_column

    !> out(row0 + rows, global columns) += block (local columns of frame fr).
    pure subroutine add_frame_columns(fr, position_space, block, row0, out)
        type(node_frame_t), intent(in) :: fr
        logical, intent(in) :: position_space
        real(wp), intent(in) :: block(:, :)
        integer, intent(in) :: row0
        type(accumulator_t), intent(inout) :: out
        integer :: l, r, c
        do l = 1, size(block, 2)
            c = frame_column(fr, l, position_space)
            do r = 1, size(block, 1)
                call out%add(row0 + r, c, block(r, l))
            end do
        end do
    end subroutine add_frame_columns

    !> Frame i's rows of G (velocity space) or c_q, local columns.
    subroutine frame_first_derivatives(self, i, q, position_space, block)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: i
        real(wp), intent(in) :: q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: block(:, :)
        if (self%derivatives == constraint_derivatives_analytic) then
            call frame_jacobian(self%frames(i), q, position_space, block)
        else
            call frame_jacobian_ad(self%frames(i), q, position_space, block)
        end if
    end subroutine frame_first_derivatives

    ! ------------------------------------------------ sparse (CSC) forms

    logical function system_has_sparse(self)
        class(mbs_system_t), intent(in) :: self
        system_has_sparse = .true.
    end function system_has_sparse

    !> M: per body m I₃ (3 slots) and the full 3 × 3 inertia block, in the
    !> triplet order mass_sparse fills.
    subroutine system_mass_pattern(self, pattern, status)
        class(mbs_system_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        integer :: b, i, j, n, iv, f
        integer(i8) :: p
        n = 12 * size(self%rigid%bodies)
        do f = 1, size(self%flex)
            n = n + int(self%flex(f)%mass_matrix%nnz)
        end do
        do f = 1, size(self%chains)
            n = n + self%chains(f)%nv**2
        end do
        allocate (rows(n), cols(n))
        n = 0
        do b = 1, size(self%rigid%bodies)
            iv = rigid_body_nv * (b - 1)
            do i = 1, 3
                n = n + 1
                rows(n) = iv + i
                cols(n) = iv + i
            end do
            do j = 4, 6
                do i = 4, 6
                    n = n + 1
                    rows(n) = iv + i
                    cols(n) = iv + j
                end do
            end do
        end do
        ! chains: dense blocks M(q), column by column
        do f = 1, size(self%chains)
            do j = 1, self%chains(f)%nv
                do i = 1, self%chains(f)%nv
                    n = n + 1
                    rows(n) = self%chain_v(f) + i
                    cols(n) = self%chain_v(f) + j
                end do
            end do
        end do
        ! flexible bodies: their own mass patterns, column by column
        do f = 1, size(self%flex)
            associate (mm => self%flex(f)%mass_matrix)
                do j = 1, mm%ncol
                    do p = mm%colptr(j) + 1, mm%colptr(j + 1)
                        n = n + 1
                        rows(n) = self%flex_v(f) + int(mm%rowind(p)) + 1
                        cols(n) = self%flex_v(f) + j
                    end do
                end do
            end associate
        end do
        call pattern%build(self%nv, self%nv, rows, cols, status)
        if (status%ok()) self%mass_csc = pattern
    end subroutine system_mass_pattern

    subroutine system_mass_sparse(self, t, q, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: b, i, j, n, f
        integer(i8) :: p
        real(wp) :: mc(rigid_body_nq, rigid_body_nq)
        n = 0
        values = 0.0_wp
        do b = 1, size(self%rigid%bodies)
            do i = 1, 3
                n = n + 1
                values(self%mass_csc%triplet_map(n)) = self%rigid%bodies(b)%mass
            end do
            do j = 1, 3
                do i = 1, 3
                    n = n + 1
                    values(self%mass_csc%triplet_map(n)) = self%rigid%bodies(b)%inertia(i, j)
                end do
            end do
        end do
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), nc => self%chains(f)%nv, nq => self%chains(f)%nq)
                call self%chains(f)%mass(t, q(iq + 1:iq + nq), mc(1:nc, 1:nc), status)
                do j = 1, nc
                    do i = 1, nc
                        n = n + 1
                        values(self%mass_csc%triplet_map(n)) = mc(i, j)
                    end do
                end do
            end associate
        end do
        do f = 1, size(self%flex)
            associate (mm => self%flex(f)%mass_matrix)
                do p = 1, mm%nnz
                    n = n + 1
                    values(self%mass_csc%triplet_map(n)) = mm%values(p)
                end do
            end associate
        end do
    end subroutine system_mass_sparse

    !> G: joint k's rows times the 6 velocity columns of each of its
    !> markers' bodies (none for the ground), joint by joint.
    subroutine system_constraint_jacobian_pattern(self, pattern, status)
        class(mbs_system_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        integer :: k, n, r, c, side, mk, b, iq, iv, nt
        nt = 0
        do k = 1, size(self%joints)
            do side = 1, 2
                mk = merge(self%joints(k)%marker_i, self%joints(k)%marker_j, side == 1)
                nt = nt + self%joints(k)%joint%nrows * marker_columns(self, mk, .false.)
            end do
        end do
        do k = 1, size(self%frames)
            nt = nt + node_frame_rows * frame_columns(self%frames(k), .false.)
        end do
        allocate (rows(nt), cols(nt))
        n = 0
        do k = 1, size(self%joints)
            do side = 1, 2
                mk = merge(self%joints(k)%marker_i, self%joints(k)%marker_j, side == 1)
                call marker_offsets(self, mk, b, iq, iv)
                do c = 1, marker_columns(self, mk, .false.)
                    do r = 1, self%joints(k)%joint%nrows
                        n = n + 1
                        rows(n) = self%joints(k)%row0 + r
                        cols(n) = iv + c
                    end do
                end do
            end do
        end do
        do k = 1, size(self%frames)
            do c = 1, frame_columns(self%frames(k), .false.)
                do r = 1, node_frame_rows
                    n = n + 1
                    rows(n) = self%frames(k)%row0 + r
                    cols(n) = frame_column(self%frames(k), c, .false.)
                end do
            end do
        end do
        call pattern%build(self%nc, self%nv, rows, cols, status)
        if (status%ok()) self%jacobian_csc = pattern
    end subroutine system_constraint_jacobian_pattern

    subroutine system_constraint_jacobian_sparse(self, t, q, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: ci(max_rows, rigid_body_nq), cj(max_rows, rigid_body_nq), ct(max_rows)
        integer :: k, n, r, c, ni, nj, nr
        n = 0
        values = 0.0_wp
        do k = 1, size(self%joints)
            nr = self%joints(k)%joint%nrows
            call joint_first_derivatives(self, k, t, q, .false., ci, cj, ni, nj, ct)
            do c = 1, ni
                do r = 1, nr
                    n = n + 1
                    values(self%jacobian_csc%triplet_map(n)) = ci(r, c)
                end do
            end do
            do c = 1, nj
                do r = 1, nr
                    n = n + 1
                    values(self%jacobian_csc%triplet_map(n)) = cj(r, c)
                end do
            end do
        end do
        do k = 1, size(self%frames)
            block
                real(wp) :: fb(node_frame_rows, frame_columns(self%frames(k), .false.))
                call frame_first_derivatives(self, k, q, .false., fb)
                do c = 1, size(fb, 2)
                    do r = 1, node_frame_rows
                        n = n + 1
                        values(self%jacobian_csc%triplet_map(n)) = fb(r, c)
                    end do
                end do
            end block
        end do
    end subroutine system_constraint_jacobian_sparse

    ! ------------------------------------------------ sparse derivative blocks

    logical function system_has_sparse_derivatives(self)
        class(mbs_system_t), intent(in) :: self
        system_has_sparse_derivatives = .true.
    end function system_has_sparse_derivatives

    !> Patterns of the derivative blocks (mechanical_patterns_t): rigid
    !> bodies' quaternion and gyroscopic blocks, the chains' full blocks, the
    !> flexible bodies' tangent patterns, and per joint or node frame its rows
    !> times the columns of its markers' bodies.
    subroutine system_derivative_patterns(self, patterns, status)
        class(mbs_system_t), intent(inout) :: self
        type(mechanical_patterns_t), intent(inout) :: patterns
        type(status_t), intent(inout) :: status
        type(triplets_t) :: cq, rq, tk, tq, fq, fv
        integer :: b, f, k, side, mk, iq, iv, nq, nv, i, other, oq, ov, bo
        call self%mass_pattern(patterns%mass, status)
        if (status%ok()) call self%constraint_jacobian_pattern(patterns%constraint_v, status)
        if (.not. status%ok()) return
        do b = 1, size(self%rigid%bodies)
            iq = rigid_body_nq * (b - 1)
            iv = rigid_body_nv * (b - 1)
            do i = 1, 3
                call tk%add(iq + i, iv + i)
            end do
            call tk%add_range(iq + 3, iv + 3, 4, 3)
            call tq%add_range(iq + 3, iq + 3, 4, 4)
            call fv%add_range(iv + 3, iv + 3, 3, 3)
        end do
        do f = 1, size(self%chains)
            nq = self%chains(f)%nq
            nv = self%chains(f)%nv
            call tk%add_range(self%chain_q(f), self%chain_v(f), nq, nv)
            call tq%add_range(self%chain_q(f), self%chain_q(f), nq, nq)
            call fq%add_range(self%chain_v(f), self%chain_q(f), nv, nq)
            call fv%add_range(self%chain_v(f), self%chain_v(f), nv, nv)
        end do
        do f = 1, size(self%flex)
            do i = 1, self%flex(f)%nv
                call tk%add(self%flex_q(f) + i, self%flex_v(f) + i)
            end do
            call fq%add_pattern(self%flex_v(f), self%flex_q(f), self%flex(f)%stiffness)
            call fv%add_pattern(self%flex_v(f), self%flex_v(f), self%flex(f)%damping)
        end do
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                do side = 1, 2
                    mk = merge(jt%marker_i, jt%marker_j, side == 1)
                    call marker_offsets(self, mk, b, iq, iv)
                    if (marker_columns(self, mk, .true.) == 0) cycle
                    call cq%add_range(jt%row0, iq, jt%joint%nrows, &
                                      marker_columns(self, mk, .true.))
                    do other = 1, 2
                        call marker_offsets(self, merge(jt%marker_i, jt%marker_j, other == 1), &
                                            bo, oq, ov)
                        call rq%add_range(iv, oq, marker_columns(self, mk, .false.), &
                            marker_columns(self, merge(jt%marker_i, jt%marker_j, other == 1), &
                                           .true.))
                    end do
                end do
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                do i = 1, frame_columns(fr, .true.)
                    call cq%add_range(fr%row0, frame_column(fr, i, .true.) - 1, &
                                      node_frame_rows, 1)
                    do b = 1, frame_columns(fr, .false.)
                        call rq%add(frame_column(fr, b, .false.), frame_column(fr, i, .true.))
                    end do
                end do
            end associate
        end do
        call cq%build(self%nc, self%nq, patterns%constraint_q, status)
        if (status%ok()) call rq%build(self%nv, self%nq, patterns%reaction_q, status)
        if (status%ok()) call tk%build(self%nq, self%nv, patterns%kinematics, status)
        if (status%ok()) call tq%build(self%nq, self%nq, patterns%kinematics_q, status)
        if (status%ok()) call fq%build(self%nv, self%nq, patterns%force_q, status)
        if (status%ok()) call fv%build(self%nv, self%nv, patterns%force_v, status)
        if (.not. status%ok()) then
            status%message = 'mbs system: derivative patterns: ' // status%message
            return
        end if
        self%patterns = patterns
    end subroutine system_derivative_patterns

    !> T: I₃ and L(p)ᵀ/2 per rigid body, the chains' columns T e_l, I for
    !> flexible bodies.
    subroutine system_kinematics_sparse(self, t, q, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: e(rigid_body_nq), rate(rigid_body_nq), l(3, 4)
        integer :: b, f, i, iq, iv
        associate (acc => self%acc(1))
            call acc%start_sparse(self%patterns%kinematics)
            do b = 1, size(self%rigid%bodies)
                iq = rigid_body_nq * (b - 1)
                iv = rigid_body_nv * (b - 1)
                do i = 1, 3
                    call acc%add(iq + i, iv + i, 1.0_wp)
                end do
                l = quat_l(q(iq + 4:iq + 7))
                call acc%add_range(iq + 3, iv + 3, 0.5_wp * transpose(l))
            end do
            do f = 1, size(self%chains)
                associate (cq => self%chain_q(f), nq => self%chains(f)%nq, &
                           nv => self%chains(f)%nv)
                    do i = 1, nv
                        e(1:nv) = 0.0_wp
                        e(i) = 1.0_wp
                        call chain_rates(self, f, q(cq + 1:cq + nq), e(1:nv), rate(1:nq))
                        call acc%add_range(cq, self%chain_v(f) + i - 1, &
                                           reshape(rate(1:nq), [nq, 1]))
                    end do
                end associate
            end do
            do f = 1, size(self%flex)
                do i = 1, self%flex(f)%nv
                    call acc%add(self%flex_q(f) + i, self%flex_v(f) + i, 1.0_wp)
                end do
            end do
            call acc%get_values(values, 'mbs system: T', status)
        end associate
    end subroutine system_kinematics_sparse

    !> ∂(T w)/∂q: the quaternion blocks of the rigid bodies, the chains' blocks.
    subroutine system_kinematics_derivative_sparse(self, t, q, w, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: blk(rigid_body_nq, rigid_body_nq)
        integer :: b, f, iq, iv
        associate (acc => self%acc(1))
            call acc%start_sparse(self%patterns%kinematics_q)
            do b = 1, size(self%rigid%bodies)
                iq = rigid_body_nq * (b - 1)
                iv = rigid_body_nv * (b - 1)
                call acc%add_range(iq + 3, iq + 3, quaternion_rate_derivative(w(iv + 4:iv + 6)))
            end do
            do f = 1, size(self%chains)
                associate (cq => self%chain_q(f), cv => self%chain_v(f), &
                           nq => self%chains(f)%nq, nv => self%chains(f)%nv)
                    call self%chains(f)%kinematics_derivative(t, q(cq + 1:cq + nq), &
                        w(cv + 1:cv + nv), blk(1:nq, 1:nq), status)
                    call acc%add_range(cq, cq, blk(1:nq, 1:nq))
                end associate
            end do
            call acc%get_values(values, 'mbs system: d(T w)/dq', status)
        end associate
    end subroutine system_kinematics_derivative_sparse

    subroutine system_mass_derivative_sparse(self, t, q, w, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_sparse(self%patterns%force_q)
        call mass_derivative_into(self, t, q, w, self%acc(1), status)
        call self%acc(1)%get_values(values, 'mbs system: d(M w)/dq', status)
    end subroutine system_mass_derivative_sparse

    !> ∂f/∂q, ∂f/∂v: gyroscopic blocks, the chains' blocks, and −∂k/∂q,
    !> −∂k/∂v of the flexible bodies from their analytic tangents.
    subroutine system_force_derivatives_sparse(self, t, q, v, fq, fv, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:), fv(:)
        type(status_t), intent(inout) :: status
        real(wp) :: bq(rigid_body_nq, rigid_body_nq), bv(rigid_body_nq, rigid_body_nq)
        type(status_t) :: local
        integer :: b, iv
        associate (aq => self%acc(1), av => self%acc(2))
            call aq%start_sparse(self%patterns%force_q)
            call av%start_sparse(self%patterns%force_v)
            do b = 1, size(self%rigid%bodies)
                iv = rigid_body_nv * (b - 1)
                call av%add_range(iv + 3, iv + 3, gyroscopic_derivative( &
                    self%rigid%bodies(b)%inertia, v(iv + 4:iv + 6)))
            end do
            do b = 1, size(self%chains)
                associate (cq => self%chain_q(b), cv => self%chain_v(b), &
                           nq => self%chains(b)%nq, nv => self%chains(b)%nv)
                    call self%chains(b)%force_derivatives(t, q(cq + 1:cq + nq), &
                        v(cv + 1:cv + nv), bq(1:nv, 1:nq), bv(1:nv, 1:nv), status)
                    call aq%add_range(cv, cq, bq(1:nv, 1:nq))
                    call av%add_range(cv, cv, bv(1:nv, 1:nv))
                end associate
            end do
            do b = 1, size(self%flex)
                associate (fq0 => self%flex_q(b), fv0 => self%flex_v(b), n => self%flex(b)%nv)
                    call self%flex(b)%assemble_tangents(q(fq0 + 1:fq0 + n), v(fv0 + 1:fv0 + n), &
                                                        local)
                    if (.not. local%ok()) then
                        status = local
                        return
                    end if
                    call aq%add_csc(fv0, fq0, self%flex(b)%stiffness, -1.0_wp)
                    call av%add_csc(fv0, fv0, self%flex(b)%damping, -1.0_wp)
                end associate
            end do
            call aq%get_values(fq, 'mbs system: df/dq', status)
            call av%get_values(fv, 'mbs system: df/dv', status)
        end associate
    end subroutine system_force_derivatives_sparse

    subroutine system_constraint_position_jacobian_sparse(self, t, q, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_sparse(self%patterns%constraint_q)
        call assemble_first_derivative(self, t, q, .true., self%acc(1))
        call self%acc(1)%get_values(values, 'mbs system: g_q', status)
    end subroutine system_constraint_position_jacobian_sparse

    ! ------------------------------------------------ bodies (delegated)

    subroutine system_kinematics(self, t, q, w, qdot, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        integer :: f
        call self%rigid%kinematics(t, q(1:self%nq_rigid), w(1:self%nv_rigid), &
                                   qdot(1:self%nq_rigid), status)
        do f = 1, size(self%chains)
            call chain_rates(self, f, q(self%chain_q(f) + 1:self%chain_q(f) + self%chains(f)%nq), &
                             w(self%chain_v(f) + 1:self%chain_v(f) + self%chains(f)%nv), &
                             qdot(self%chain_q(f) + 1:self%chain_q(f) + self%chains(f)%nq))
        end do
        ! flexible bodies: q' = v
        do f = 1, size(self%flex)
            qdot(self%flex_q(f) + 1:self%flex_q(f) + self%flex(f)%nq) = &
                w(self%flex_v(f) + 1:self%flex_v(f) + self%flex(f)%nv)
        end do
    end subroutine system_kinematics

    subroutine system_kinematics_derivative(self, t, q, w, dq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        integer :: f
        dq = 0.0_wp
        call self%rigid%kinematics_derivative(t, q(1:self%nq_rigid), w(1:self%nv_rigid), &
                                              dq(1:self%nq_rigid, 1:self%nq_rigid), status)
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), nq => self%chains(f)%nq, &
                       nv => self%chains(f)%nv)
                call self%chains(f)%kinematics_derivative(t, q(iq + 1:iq + nq), &
                    w(iv + 1:iv + nv), dq(iq + 1:iq + nq, iq + 1:iq + nq), status)
            end associate
        end do
    end subroutine system_kinematics_derivative

    subroutine system_mass(self, t, q, m, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        integer :: f
        m = 0.0_wp
        call self%rigid%mass(t, q(1:self%nq_rigid), m(1:self%nv_rigid, 1:self%nv_rigid), status)
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), n => self%chains(f)%nv, &
                       nq => self%chains(f)%nq)
                call self%chains(f)%mass(t, q(iq + 1:iq + nq), m(iv + 1:iv + n, iv + 1:iv + n), &
                                         status)
            end associate
        end do
        do f = 1, size(self%flex)
            associate (i0 => self%flex_v(f), n => self%flex(f)%nv)
                call self%flex(f)%mass_matrix%to_dense(m(i0 + 1:i0 + n, i0 + 1:i0 + n))
            end associate
        end do
    end subroutine system_mass

    subroutine system_mass_derivative(self, t, q, w, dq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nv, self%nq)
        call mass_derivative_into(self, t, q, w, self%acc(1), status)
        call self%acc(1)%get_dense(dq)
    end subroutine system_mass_derivative

    !> ∂(M w)/∂q added into dq: zero for rigid and flexible bodies (constant
    !> M), central differences of the chains' M(q) w (at most 7 coordinates each).
    subroutine mass_derivative_into(self, t, q, w, dq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        type(accumulator_t), intent(inout) :: dq
        type(status_t), intent(inout) :: status
        real(wp) :: mp(rigid_body_nq, rigid_body_nq), mm(rigid_body_nq, rigid_body_nq), &
            qc(rigid_body_nq), h, col(rigid_body_nq)
        integer :: f, j, i
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), n => self%chains(f)%nv, &
                       nq => self%chains(f)%nq)
                do j = 1, nq
                    qc(1:nq) = q(iq + 1:iq + nq)
                    h = difference_step(qc(j))
                    qc(j) = q(iq + j) + h
                    call self%chains(f)%mass(t, qc(1:nq), mp(1:n, 1:n), status)
                    qc(j) = q(iq + j) - h
                    call self%chains(f)%mass(t, qc(1:nq), mm(1:n, 1:n), status)
                    col(1:n) = matmul(mp(1:n, 1:n) - mm(1:n, 1:n), w(iv + 1:iv + n)) / (2 * h)
                    do i = 1, n
                        call dq%add(iv + i, iq + j, col(i))
                    end do
                end do
            end associate
        end do
    end subroutine mass_derivative_into

    subroutine system_forces(self, t, q, v, f, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        integer :: b
        call self%rigid%forces(t, q(1:self%nq_rigid), v(1:self%nv_rigid), &
                               f(1:self%nv_rigid), status)
        do b = 1, size(self%chains)
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%forces(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                                           f(iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%flex)
            if (.not. status%ok()) return
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%forces(t, q(iq + 1:iq + n), v(iv + 1:iv + n), &
                                         f(iv + 1:iv + n), status)
            end associate
        end do
    end subroutine system_forces

    subroutine system_force_derivatives(self, t, q, v, fq, fv, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        integer :: b
        fq = 0.0_wp
        fv = 0.0_wp
        call self%rigid%force_derivatives(t, q(1:self%nq_rigid), v(1:self%nv_rigid), &
                                          fq(1:self%nv_rigid, 1:self%nq_rigid), &
                                          fv(1:self%nv_rigid, 1:self%nv_rigid), status)
        do b = 1, size(self%chains)
            ! the chains' defaults: differences of their RNEA forces
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%force_derivatives(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                    fq(iv + 1:iv + n, iq + 1:iq + nq), fv(iv + 1:iv + n, iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%flex)
            if (.not. status%ok()) return
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%force_derivatives(t, q(iq + 1:iq + n), v(iv + 1:iv + n), &
                    fq(iv + 1:iv + n, iq + 1:iq + n), fv(iv + 1:iv + n, iv + 1:iv + n), status)
            end associate
        end do
    end subroutine system_force_derivatives

    !> det F > 0 in every flexible body (see dae_problem_t%admissible).
    subroutine system_admissible(self, q, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        type(status_t), intent(out) :: status
        integer :: b
        call status%clear()
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), n => self%flex(b)%nq)
                call self%flex(b)%admissible(q(iq + 1:iq + n), status)
            end associate
            if (.not. status%ok()) return
        end do
    end subroutine system_admissible

    subroutine system_normalize(self, q)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(inout) :: q(:)
        integer :: f
        call self%rigid%normalize(q(1:self%nq_rigid))
        do f = 1, size(self%chains)
            call self%chains(f)%normalize(q(self%chain_q(f) + 1:self%chain_q(f) + &
                                            self%chains(f)%nq))
        end do
    end subroutine system_normalize

    !> Kinetic plus potential energy; flexible bodies add kinetic and strain
    !> energy and the potential −g·(q − X) of their constant applied forces.
    real(wp) function system_energy(self, q, v) result(e)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        type(status_t) :: st
        integer :: b
        real(wp) :: ek, ep
        e = rigid_body_energy(self%rigid, q(1:self%nq_rigid), v(1:self%nv_rigid))
        do b = 1, size(self%chains)
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%energy(q(iq + 1:iq + nq), v(iv + 1:iv + n), ek, ep)
            end associate
            e = e + ek + ep
        end do
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                e = e + self%flex(b)%kinetic_energy(v(iv + 1:iv + n)) &
                    + self%flex(b)%strain_energy(q(iq + 1:iq + n), st) &
                    - dot_product(self%flex(b)%applied_force, &
                                  q(iq + 1:iq + n) - self%flex(b)%free_positions())
            end associate
        end do
    end function system_energy

    !> Total linear momentum and angular momentum about the global origin.
    subroutine system_momenta(self, q, v, linear, angular)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: linear(3), angular(3)
        real(wp) :: lf(3), af(3)
        integer :: b
        call rigid_body_momenta(self%rigid, q(1:self%nq_rigid), v(1:self%nv_rigid), linear, &
                                angular)
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%momenta(q(iq + 1:iq + n), v(iv + 1:iv + n), lf, af)
            end associate
            linear = linear + lf
            angular = angular + af
        end do
    end subroutine system_momenta

    ! ------------------------------------------------ markers, real and dual

    !> Offsets of marker k's body in q and v; ground: body = 0.
    !> A node marker reports body = −(its flexible body) and the offsets of
    !> the node's x coordinate.
    pure subroutine marker_offsets(self, k, body, iq, iv)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        integer, intent(out) :: body, iq, iv
        integer :: f, d
        if (self%markers(k)%chain > 0) then
            ! negative like a node marker (not the ground, not a rigid body)
            body = -chain_body_flag - self%markers(k)%chain
            iq = self%chain_q(self%markers(k)%chain)
            iv = self%chain_v(self%markers(k)%chain)
            return
        end if
        f = self%markers(k)%flexible
        if (f > 0) then
            body = -f
            d = self%flex(f)%dof(1, self%markers(k)%node) - 1
            iq = self%flex_q(f) + d
            iv = self%flex_v(f) + d
            return
        end if
        body = self%markers(k)%body
        iq = rigid_body_nq * (body - 1)
        iv = rigid_body_nv * (body - 1)
    end subroutine marker_offsets

    !> Columns of marker k's body in velocity space (6) or position space (7); 0 on ground.
    pure integer function marker_columns(self, k, position_space) result(n)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        logical, intent(in) :: position_space
        n = 0
        if (self%markers(k)%body > 0) n = merge(rigid_body_nq, rigid_body_nv, position_space)
        if (self%markers(k)%flexible > 0) n = 3
        if (self%markers(k)%chain > 0) n = merge(self%chains(self%markers(k)%chain)%nq, &
            self%chains(self%markers(k)%chain)%nv, position_space)
    end function marker_columns

    !> Real frame and motion of marker k at (q, v).
    pure subroutine marker_state(self, k, q, v, m)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: q(:), v(:)
        type(marker_state_t), intent(out) :: m
        integer :: b, iq, iv
        call marker_offsets(self, k, b, iq, iv)
        associate (mk => self%markers(k))
            if (mk%chain > 0) then
                associate (g => self%chain_geom(mk%chain), nq => self%chains(mk%chain)%nq, &
                           nv => self%chains(mk%chain)%nv)
                    call chain_marker_state(g%parent, g%kinds, g%iq, g%iv, g%jpos, g%jrot, &
                        g%axis, mk%link, mk%position, mk%axes, q(iq + 1:iq + nq), &
                        v(iv + 1:iv + nv), m)
                end associate
            else if (b < 0) then
                ! a node: its position and velocity, constant axes
                call ground_marker_state(q(iq + 1:iq + 3), mk%axes, m)
                m%xd = v(iv + 1:iv + 3)
            else if (b == 0) then
                call ground_marker_state(mk%position, mk%axes, m)
            else
                call rigid_marker_state(q(iq + 1:iq + 3), q(iq + 4:iq + 7), v(iv + 1:iv + 3), &
                                        v(iv + 4:iv + 6), mk%position, mk%axes, m)
            end if
        end associate
    end subroutine marker_state

    !> Hand-coded marker Jacobians of marker k: velocity space (3 x 6) or
    !> position space (3 x 7) in the leading columns of jx, ja; n columns.
    pure subroutine marker_jacobian(self, k, q, position_space, jx, ja, n)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: jx(3, rigid_body_nq), ja(3, rigid_body_nq, 3)
        integer, intent(out) :: n
        real(wp) :: jx6(3, 6), ja6(3, 6, 3)
        integer :: b, iq, iv
        call marker_offsets(self, k, b, iq, iv)
        n = marker_columns(self, k, position_space)
        jx = 0.0_wp
        ja = 0.0_wp
        if (b == 0) return
        if (self%markers(k)%chain > 0) then
            call chain_jacobian_real(self, k, q, iq, position_space, jx, ja)
            return
        end if
        if (b < 0) then
            ! a node: x = q_node in both spaces (T = I), axes constant
            jx(1, 1) = 1.0_wp
            jx(2, 2) = 1.0_wp
            jx(3, 3) = 1.0_wp
            return
        end if
        associate (mk => self%markers(k))
            if (position_space) then
                call rigid_marker_jacobian_q(q(iq + 4:iq + 7), mk%position, mk%axes, jx, ja)
            else
                call rigid_marker_jacobian(q(iq + 4:iq + 7), mk%position, mk%axes, jx6, ja6)
                jx(:, 1:6) = jx6
                ja(:, 1:6, :) = ja6
            end if
        end associate
    end subroutine marker_jacobian

    !> Dual frame and motion of marker k at (q, v) with its body's tangents
    !> `seed` in directions first, first+1, ...; p the dual quaternion (for the
    !> dual marker Jacobians); n the directions used (0 on the ground).
    pure subroutine marker_state_dual(self, k, q, v, seed, first, m, p, n, pose_only)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k, seed, first
        !> the frame only (rigid markers): values and first derivatives of c
        logical, intent(in), optional :: pose_only
        real(wp), intent(in) :: q(:), v(:)
        type(marker_state_d), intent(out) :: m
        !> the pose coordinates the dual Jacobians need: the quaternion of a
        !> rigid body (1:4), the coordinates of a chain (1:n)
        type(dual_t), intent(out) :: p(rigid_body_nq)
        integer, intent(out) :: n
        type(dual_t) :: r(3), rd(3), wb(3), sb(3), ub(3, 3), x(3), a(3, 3)
        real(wp) :: tp(4, 3)
        integer :: b, iq, iv, l
        call marker_offsets(self, k, b, iq, iv)
        n = 0
        p = 0.0_wp
        associate (mk => self%markers(k))
            if (mk%chain > 0) then
                call chain_state_dual(self, k, q, v, seed, first, iq, iv, m, p, n)
                return
            end if
            if (b == 0) then
                x = mk%position
                a = mk%axes
                p = 0.0_wp
                call ground_marker_state_d(x, a, m)
                return
            end if
            if (b < 0) then
                ! a node: x = q_node, ẋ = v_node; every seed space is (x, y, z)
                x = q(iq + 1:iq + 3)
                rd = v(iv + 1:iv + 3)
                a = mk%axes
                p = 0.0_wp
                select case (seed)
                case (seed_velocity_space, seed_position)
                    n = 3
                    do l = 1, 3
                        x(l)%der(first + l - 1) = 1.0_wp
                    end do
                case (seed_velocity)
                    n = 3
                    do l = 1, 3
                        rd(l)%der(first + l - 1) = 1.0_wp
                    end do
                case (seed_rate)
                    n = 1
                    x%der(first) = v(iv + 1:iv + 3)
                end select
                call ground_marker_state_d(x, a, m)
                m%xd = rd
                return
            end if
            r = q(iq + 1:iq + 3)
            p(1:4) = q(iq + 4:iq + 7)
            rd = v(iv + 1:iv + 3)
            wb = v(iv + 4:iv + 6)
            sb = mk%position
            ub = mk%axes
            tp = quat_rate_matrix(q(iq + 4:iq + 7))
            select case (seed)
            case (seed_velocity_space)
                n = rigid_body_nv
                do l = 1, 3
                    r(l)%der(first + l - 1) = 1.0_wp
                    p(1:4)%der(first + 2 + l) = tp(:, l)
                end do
            case (seed_position)
                n = rigid_body_nq
                do l = 1, 3
                    r(l)%der(first + l - 1) = 1.0_wp
                end do
                do l = 1, 4
                    p(l)%der(first + 2 + l) = 1.0_wp
                end do
            case (seed_velocity)
                n = rigid_body_nv
                do l = 1, 3
                    rd(l)%der(first + l - 1) = 1.0_wp
                    wb(l)%der(first + 2 + l) = 1.0_wp
                end do
            case (seed_rate)
                n = 1
                r%der(first) = v(iv + 1:iv + 3)
                p(1:4)%der(first) = matmul(tp, v(iv + 4:iv + 6))
            end select
            if (present(pose_only)) then
                if (pose_only) then
                    call rigid_marker_pose_d(r, p(1:4), sb, ub, m)
                    return
                end if
            end if
            call rigid_marker_state_d(r, p(1:4), rd, wb, sb, ub, m)
        end associate
    end subroutine marker_state_dual

    !> Dual velocity-space Jacobians of marker k from its dual quaternion p.
    pure subroutine marker_jacobian_dual(self, k, p, jx, ja)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        type(dual_t), intent(in) :: p(rigid_body_nq)
        type(dual_t), intent(out) :: jx(3, rigid_body_nq), ja(3, rigid_body_nq, 3)
        type(dual_t) :: sb(3), ub(3, 3), jx6(3, 6), ja6(3, 6, 3)
        integer :: c
        if (self%markers(k)%chain > 0) then
            c = self%markers(k)%chain
            associate (ch => self%chains(c), g => self%chain_geom(c))
                jx = 0.0_wp
                ja = 0.0_wp
                call chain_marker_jacobian_d(g%parent, g%kinds, g%iq, g%iv, g%jpos, g%jrot, &
                    g%axis, &
                    self%markers(k)%link, self%markers(k)%position, self%markers(k)%axes, &
                    p(1:ch%nq), jx(:, 1:ch%nv), ja(:, 1:ch%nv, :))
            end associate
            return
        end if
        if (self%markers(k)%body == 0 .or. self%markers(k)%flexible > 0) then
            jx = 0.0_wp
            ja = 0.0_wp
            if (self%markers(k)%flexible > 0) then
                jx(1, 1) = 1.0_wp
                jx(2, 2) = 1.0_wp
                jx(3, 3) = 1.0_wp
            end if
            return
        end if
        sb = self%markers(k)%position
        ub = self%markers(k)%axes
        call rigid_marker_jacobian_d(p(1:4), sb, ub, jx6, ja6)
        jx(:, 1:6) = jx6
        ja(:, 1:6, :) = ja6
        jx(:, 7) = 0.0_wp
        ja(:, 7, :) = 0.0_wp
    end subroutine marker_jacobian_dual

    !> Dual state of chain marker k: the chain's coordinates (and rates)
    !> seeded as for a body (T = I: velocity space = position space).
    pure subroutine chain_state_dual(self, k, q, v, seed, first, iq, iv, m, p, n)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k, seed, first, iq, iv
        real(wp), intent(in) :: q(:), v(:)
        type(marker_state_d), intent(out) :: m
        type(dual_t), intent(inout) :: p(rigid_body_nq)
        integer, intent(out) :: n
        type(dual_t) :: vc(rigid_body_nq)
        real(wp) :: tp(4, 3), rate(rigid_body_nq)
        integer :: c, l, nq, nv, b, jq, jv
        c = self%markers(k)%chain
        nq = self%chains(c)%nq
        nv = self%chains(c)%nv
        p(1:nq) = q(iq + 1:iq + nq)
        vc(1:nv) = v(iv + 1:iv + nv)
        select case (seed)
        case (seed_velocity_space)
            ! the tangents T e_l: unit for single-coordinate joints, T(p) e_k
            ! for a spherical joint's quaternion
            n = nv
            associate (g => self%chain_geom(c))
                do b = 1, size(g%parent)
                    jq = g%iq(b)
                    jv = g%iv(b)
                    if (g%kinds(b) == chain_joint_spherical) then
                        tp = quat_rate_matrix(q(iq + jq + 1:iq + jq + 4))
                        do l = 1, 3
                            p(jq + 1:jq + 4)%der(first + jv + l - 1) = tp(:, l)
                        end do
                    else
                        p(jq + 1)%der(first + jv) = 1.0_wp
                    end if
                end do
            end associate
        case (seed_position)
            n = nq
            do l = 1, nq
                p(l)%der(first + l - 1) = 1.0_wp
            end do
        case (seed_velocity)
            n = nv
            do l = 1, nv
                vc(l)%der(first + l - 1) = 1.0_wp
            end do
        case (seed_rate)
            n = 1
            call chain_rates(self, c, q(iq + 1:iq + nq), v(iv + 1:iv + nv), rate(1:nq))
            p(1:nq)%der(first) = rate(1:nq)
        end select
        associate (g => self%chain_geom(c))
            call chain_marker_state_d(g%parent, g%kinds, g%iq, g%iv, g%jpos, g%jrot, &
                    g%axis, &
                self%markers(k)%link, self%markers(k)%position, self%markers(k)%axes, &
                p(1:nq), vc(1:nv), m)
        end associate
    end subroutine chain_state_dual

    !> q' = T(q) v of chain c (pure: the chain's own kinematics, inlined).
    pure subroutine chain_rates(self, c, qc, vc, rate)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: c
        real(wp), intent(in) :: qc(:), vc(:)
        real(wp), intent(out) :: rate(:)
        integer :: b, jq, jv
        associate (g => self%chain_geom(c))
            do b = 1, size(g%parent)
                jq = g%iq(b)
                jv = g%iv(b)
                if (g%kinds(b) == chain_joint_spherical) then
                    rate(jq + 1:jq + 4) = matmul(quat_rate_matrix(qc(jq + 1:jq + 4)), &
                                                 vc(jv + 1:jv + 3))
                else
                    rate(jq + 1) = vc(jv + 1)
                end if
            end do
        end associate
    end subroutine chain_rates

    !> Real Jacobians of chain marker k: velocity space by the formulas,
    !> position space (quaternion coordinates) by one dual pass.
    pure subroutine chain_jacobian_real(self, k, q, iq, position_space, jx, ja)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k, iq
        real(wp), intent(in) :: q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: jx(3, rigid_body_nq), ja(3, rigid_body_nq, 3)
        type(marker_state_d) :: m
        type(dual_t) :: p(rigid_body_nq)
        integer :: c, nq, nv, n, l
        c = self%markers(k)%chain
        nq = self%chains(c)%nq
        nv = self%chains(c)%nv
        jx = 0.0_wp
        ja = 0.0_wp
        if (.not. position_space .or. nq == nv) then
            associate (mk => self%markers(k), g => self%chain_geom(c))
                call chain_marker_jacobian(g%parent, g%kinds, g%iq, g%iv, g%jpos, g%jrot, &
                    g%axis, mk%link, mk%position, mk%axes, q(iq + 1:iq + nq), jx(:, 1:nv), &
                    ja(:, 1:nv, :))
            end associate
            return
        end if
        p = 0.0_wp
        call chain_state_dual(self, k, q, self%zero_v, seed_position, 1, iq, 0, m, p, n)
        do l = 1, 3
            jx(l, 1:nq) = m%x(l)%der(1:nq)
            ja(l, 1:nq, 1) = m%a(l, 1)%der(1:nq)
            ja(l, 1:nq, 2) = m%a(l, 2)%der(1:nq)
            ja(l, 1:nq, 3) = m%a(l, 3)%der(1:nq)
        end do
    end subroutine chain_jacobian_real

    !> Driver values (s, s', s'') of joint k at t (zero for joints without s).
    pure function joint_driver(self, k, t) result(drv)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: t
        real(wp) :: drv(3)
        drv = driver_values(self%joints(k)%driver, t)
    end function joint_driver

    !> (s, s', s'') of a driver at t.
    pure function driver_values(driver, t) result(drv)
        type(driver_t), intent(in) :: driver
        real(wp), intent(in) :: t
        real(wp) :: drv(3), arg
        associate (c => driver%poly)
            drv(1) = c(0) + t * (c(1) + t * (c(2) + t * c(3)))
            drv(2) = c(1) + t * (2.0_wp * c(2) + 3.0_wp * t * c(3))
            drv(3) = 2.0_wp * c(2) + 6.0_wp * t * c(3)
        end associate
        arg = driver%frequency * t + driver%phase
        drv = drv + driver%amplitude * [sin(arg), driver%frequency * cos(arg), &
                                        -driver%frequency**2 * sin(arg)]
    end function driver_values

    !> Dual driver values, with the time tangent in direction td (none if td = 0).
    pure function driver_dual(drv, td) result(d)
        real(wp), intent(in) :: drv(3)
        integer, intent(in) :: td
        type(dual_t) :: d(3)
        d = drv
        if (td > 0) then
            d(1)%der(td) = drv(2)
            d(2)%der(td) = drv(3)
        end if
    end function driver_dual

    !> out(row0 + rows, columns of marker k's body) += block (velocity or
    !> position space).
    pure subroutine add_columns(self, k, position_space, block, row0, out)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        logical, intent(in) :: position_space
        real(wp), intent(in) :: block(:, :)
        integer, intent(in) :: row0
        type(accumulator_t), intent(inout) :: out
        integer :: b, iq, iv
        call marker_offsets(self, k, b, iq, iv)
        if (b == 0) return
        call out%add_range(row0, merge(iq, iv, position_space), block)
    end subroutine add_columns

    ! ------------------------------------------------ joint rows, first derivatives

    !> Joint k's blocks ci, cj of G (velocity space) or c_q (position space),
    !> and its c_t, by the selected constraint_derivatives; ni, nj columns.
    subroutine joint_first_derivatives(self, k, t, q, position_space, ci, cj, ni, nj, ct)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: t, q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: ci(max_rows, rigid_body_nq), cj(max_rows, rigid_body_nq)
        integer, intent(out) :: ni, nj
        real(wp), intent(out) :: ct(max_rows)
        type(marker_state_t) :: mi, mj
        type(marker_state_d) :: mid, mjd
        real(wp) :: jxi(3, rigid_body_nq), jai(3, rigid_body_nq, 3), jxj(3, rigid_body_nq), &
            jaj(3, rigid_body_nq, 3), drv(3)
        type(dual_t) :: pd(rigid_body_nq), cd(max_rows)
        integer :: seed, nr, r, td
        ci = 0.0_wp
        cj = 0.0_wp
        ct = 0.0_wp
        associate (jt => self%joints(k))
            nr = jt%joint%nrows
            drv = joint_driver(self, k, t)
            if (self%derivatives == constraint_derivatives_analytic) then
                call marker_state(self, jt%marker_i, q, self%zero_v, mi)
                call marker_state(self, jt%marker_j, q, self%zero_v, mj)
                call marker_jacobian(self, jt%marker_i, q, position_space, jxi, jai, ni)
                call marker_jacobian(self, jt%marker_j, q, position_space, jxj, jaj, nj)
                call joint_jacobian(jt%joint, mi, jxi(:, 1:ni), jai(:, 1:ni, :), mj, &
                                    jxj(:, 1:nj), jaj(:, 1:nj, :), drv, ci(1:nr, 1:ni), &
                                    cj(1:nr, 1:nj))
                call joint_rows(joint_part_time_derivative, jt%joint, mi, mj, drv, ct(1:nr))
            else if (self%derivatives == constraint_derivatives_ad) then
                ! the frames' tangents are the markers' Jacobian columns: AD of the
                ! vector relations only
                call marker_state(self, jt%marker_i, q, self%zero_v, mi)
                call marker_state(self, jt%marker_j, q, self%zero_v, mj)
                call marker_jacobian(self, jt%marker_i, q, position_space, jxi, jai, ni)
                call marker_jacobian(self, jt%marker_j, q, position_space, jxj, jaj, nj)
                call seeded_frame(mi, jxi(:, 1:ni), jai(:, 1:ni, :), 0, mid)
                call seeded_frame(mj, jxj(:, 1:nj), jaj(:, 1:nj, :), ni, mjd)
            else
                seed = merge(seed_position, seed_velocity_space, position_space)
                call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed, 1, mid, pd, ni, &
                                       pose_only=.true.)
                call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed, 1 + ni, mjd, &
                                       pd, nj, pose_only=.true.)
            end if
            if (self%derivatives /= constraint_derivatives_analytic) then
                ! tangents: marker i's columns, marker j's, time
                td = ni + nj + 1
                call joint_value_d(jt%joint, mid, mjd, driver_dual(drv, td), cd(1:nr))
                do r = 1, nr
                    ci(r, 1:ni) = cd(r)%der(1:ni)
                    cj(r, 1:nj) = cd(r)%der(ni + 1:ni + nj)
                    ct(r) = cd(r)%der(td)
                end do
            end if
        end associate
    end subroutine joint_first_derivatives

    !> The dual pose of a marker with frame m: tangent d of x is jx(:, d), of
    !> axis k ja(:, d, k), in directions off + d (its motion is left unset).
    pure subroutine seeded_frame(m, jx, ja, off, md)
        type(marker_state_t), intent(in) :: m
        real(wp), intent(in) :: jx(:, :), ja(:, :, :)
        integer, intent(in) :: off
        type(marker_state_d), intent(out) :: md
        integer :: l, k, n
        ! the pose only (the vector relations' values use nothing else)
        n = size(jx, 2)
        md%x = m%x
        md%a = m%a
        do l = 1, 3
            md%x(l)%der(off + 1:off + n) = jx(l, :)
            do k = 1, 3
                md%a(l, k)%der(off + 1:off + n) = ja(l, :, k)
            end do
        end do
    end subroutine seeded_frame

    !> The jet pose of a marker along its motion at zero accelerations: x, ẋ
    !> and the convective acceleration, for the origin and the axes.
    pure subroutine moving_frame(m, mj)
        type(marker_state_t), intent(in) :: m
        type(marker_state_j), intent(out) :: mj
        type(jet_t) :: x(3), a(3, 3)
        integer :: l, k
        do l = 1, 3
            x(l) = jet_t(m%x(l), m%xd(l), m%gx(l))
            do k = 1, 3
                a(l, k) = jet_t(m%a(l, k), m%ad(l, k), m%ga(l, k))
            end do
        end do
        call ground_marker_state_j(x, a, mj)
    end subroutine moving_frame

    subroutine system_constraint(self, t, q, g, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        type(marker_state_t) :: mi, mj
        integer :: k
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                call marker_state(self, jt%marker_i, q, self%zero_v, mi)
                call marker_state(self, jt%marker_j, q, self%zero_v, mj)
                call joint_value(jt%joint, mi, mj, joint_driver(self, k, t), &
                                 g(jt%row0 + 1:jt%row0 + jt%joint%nrows))
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                call frame_value(fr, q, g(fr%row0 + 1:fr%row0 + node_frame_rows))
            end associate
        end do
    end subroutine system_constraint

    !> G = c_q T, nc x nv.
    subroutine system_constraint_jacobian(self, t, q, gmat, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nc, self%nv)
        call assemble_first_derivative(self, t, q, .false., self%acc(1))
        call self%acc(1)%get_dense(gmat)
    end subroutine system_constraint_jacobian

    !> c_q, nc x nq.
    subroutine system_constraint_position_jacobian(self, t, q, gq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gq(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nc, self%nq)
        call assemble_first_derivative(self, t, q, .true., self%acc(1))
        call self%acc(1)%get_dense(gq)
    end subroutine system_constraint_position_jacobian

    !> G (velocity space) or c_q (position space) added into out.
    subroutine assemble_first_derivative(self, t, q, position_space, out)
        class(mbs_system_t), intent(in) :: self
        real(wp), intent(in) :: t, q(:)
        logical, intent(in) :: position_space
        type(accumulator_t), intent(inout) :: out
        real(wp) :: ci(max_rows, rigid_body_nq), cj(max_rows, rigid_body_nq), ct(max_rows)
        integer :: k, ni, nj, r0, nr
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                r0 = jt%row0
                nr = jt%joint%nrows
                call joint_first_derivatives(self, k, t, q, position_space, ci, cj, ni, nj, ct)
                call add_columns(self, jt%marker_i, position_space, ci(1:nr, 1:ni), r0, out)
                call add_columns(self, jt%marker_j, position_space, cj(1:nr, 1:nj), r0, out)
            end associate
        end do
        do k = 1, size(self%frames)
            block
                real(wp) :: fb(node_frame_rows, frame_columns(self%frames(k), position_space))
                call frame_first_derivatives(self, k, q, position_space, fb)
                r0 = self%frames(k)%row0
                call add_frame_columns(self%frames(k), position_space, fb, r0, out)
            end block
        end do
    end subroutine assemble_first_derivative

    !> c_t = ∂c/∂t.
    subroutine system_constraint_time_derivative(self, t, q, gt, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gt(:)
        type(status_t), intent(inout) :: status
        real(wp) :: ci(max_rows, rigid_body_nq), cj(max_rows, rigid_body_nq), ct(max_rows)
        integer :: k, ni, nj
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                call joint_first_derivatives(self, k, t, q, .false., ci, cj, ni, nj, ct)
                gt(jt%row0 + 1:jt%row0 + jt%joint%nrows) = ct(1:jt%joint%nrows)
            end associate
        end do
        ! node frames do not depend on t
        do k = 1, size(self%frames)
            gt(self%frames(k)%row0 + 1:self%frames(k)%row0 + node_frame_rows) = 0.0_wp
        end do
    end subroutine system_constraint_time_derivative

    !> γ = (G v)_q T v + 2 G_t v + c_tt: hand-coded (convective accelerations
    !> of the markers), or AD of the hand-coded G v along q' = T v (direction
    !> 1) and t (direction 2).
    subroutine system_constraint_curvature(self, t, q, v, gamma, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
        type(marker_state_t) :: mi, mj
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: pi(rigid_body_nq), pj(rigid_body_nq), jxi(3, rigid_body_nq), &
            jai(3, rigid_body_nq, 3), jxj(3, rigid_body_nq), jaj(3, rigid_body_nq, 3), &
            cid(max_rows, rigid_body_nq), cjd(max_rows, rigid_body_nq), ctd(max_rows), drvd(3), cv
        type(marker_state_j) :: mij, mjj
        type(jet_t) :: drvj(3), cjet(max_rows)
        real(wp) :: drv(3), tt(max_rows)
        integer :: k, r0, nr, ni, nj, r, bi, bj, iqi, iqj, ivi, ivj
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                r0 = jt%row0
                nr = jt%joint%nrows
                drv = joint_driver(self, k, t)
                if (self%derivatives == constraint_derivatives_analytic) then
                    call marker_state(self, jt%marker_i, q, v, mi)
                    call marker_state(self, jt%marker_j, q, v, mj)
                    call joint_rows(joint_part_convective, jt%joint, mi, mj, drv, &
                                    gamma(r0 + 1:r0 + nr))
                    call joint_rows(joint_part_time_terms, jt%joint, mi, mj, drv, tt(1:nr))
                    gamma(r0 + 1:r0 + nr) = gamma(r0 + 1:r0 + nr) + tt(1:nr)
                else if (self%derivatives == constraint_derivatives_ad) then
                    ! c(s) along the markers' motion and t + s: γ = c''(0)
                    call marker_state(self, jt%marker_i, q, v, mi)
                    call marker_state(self, jt%marker_j, q, v, mj)
                    call moving_frame(mi, mij)
                    call moving_frame(mj, mjj)
                    ! s(t + σ) to second order (the values use s only)
                    drvj(1) = jet_t(drv(1), drv(2), drv(3))
                    drvj(2) = jet_t(drv(2), drv(3), 0.0_wp)
                    drvj(3) = jet_t(drv(3), 0.0_wp, 0.0_wp)
                    call joint_value_j(jt%joint, mij, mjj, drvj, cjet(1:nr))
                    gamma(r0 + 1:r0 + nr) = cjet(1:nr)%f2
                else
                    call marker_state_dual(self, jt%marker_i, q, v, seed_rate, 1, mid, pi, ni)
                    call marker_state_dual(self, jt%marker_j, q, v, seed_rate, 1, mjd, pj, nj)
                    call marker_jacobian_dual(self, jt%marker_i, pi, jxi, jai)
                    call marker_jacobian_dual(self, jt%marker_j, pj, jxj, jaj)
                    ni = marker_columns(self, jt%marker_i, .false.)
                    nj = marker_columns(self, jt%marker_j, .false.)
                    drvd = driver_dual(drv, 2)
                    call joint_jacobian_d(jt%joint, mid, jxi(:, 1:ni), jai(:, 1:ni, :), mjd, &
                                          jxj(:, 1:nj), jaj(:, 1:nj, :), drvd, &
                                          cid(1:nr, 1:ni), cjd(1:nr, 1:nj))
                    call joint_rows_d(joint_part_time_derivative, jt%joint, mid, mjd, drvd, &
                                      ctd(1:nr))
                    call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                    call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                    do r = 1, nr
                        cv = dot_product(cid(r, 1:ni), v(ivi + 1:ivi + ni)) &
                             + dot_product(cjd(r, 1:nj), v(ivj + 1:ivj + nj))
                        gamma(r0 + r) = cv%der(1) + 2.0_wp * cv%der(2) + ctd(r)%der(2)
                    end do
                end if
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                if (self%derivatives == constraint_derivatives_analytic) then
                    call frame_curvature(fr, q, v, gamma(fr%row0 + 1:fr%row0 + node_frame_rows))
                else
                    call frame_curvature_ad(fr, q, v, &
                                            gamma(fr%row0 + 1:fr%row0 + node_frame_rows))
                end if
            end associate
        end do
    end subroutine system_constraint_curvature

    ! ------------------------------------------------ second derivatives (AD)

    subroutine system_constraint_jacobian_derivatives(self, t, q, w, lambda, gwq, gtlq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:, :), gtlq(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nc, self%nq)
        call self%acc(2)%start_dense(self%nv, self%nq)
        call jacobian_derivatives_into(self, t, q, w, lambda, self%acc(1), self%acc(2))
        call self%acc(1)%get_dense(gwq)
        call self%acc(2)%get_dense(gtlq)
    end subroutine system_constraint_jacobian_derivatives

    subroutine system_constraint_jacobian_derivatives_sparse(self, t, q, w, lambda, gwq, &
                                                             gtlq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:), gtlq(:)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_sparse(self%patterns%constraint_q)
        call self%acc(2)%start_sparse(self%patterns%reaction_q)
        call jacobian_derivatives_into(self, t, q, w, lambda, self%acc(1), self%acc(2))
        call self%acc(1)%get_values(gwq, 'mbs system: d(G w)/dq', status)
        call self%acc(2)%get_values(gtlq, 'mbs system: d(G^T lambda)/dq', status)
    end subroutine system_constraint_jacobian_derivatives_sparse

    !> ∂(G w)/∂q (nc x nq) and ∂(Gᵀλ)/∂q (nv x nq) added into gwq, gtlq: AD of
    !> the hand-coded G along the position unit vectors of the joint's two bodies.
    subroutine jacobian_derivatives_into(self, t, q, w, lambda, gwq, gtlq)
        class(mbs_system_t), intent(in) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        type(accumulator_t), intent(inout) :: gwq, gtlq
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: pi(rigid_body_nq), pj(rigid_body_nq), jxi(3, rigid_body_nq), &
            jai(3, rigid_body_nq, 3), jxj(3, rigid_body_nq), jaj(3, rigid_body_nq, 3), &
            cid(max_rows, rigid_body_nq), cjd(max_rows, rigid_body_nq), s
        integer :: k, r0, nr, qi, qj, ni, nj, r, l, bi, bj, iqi, iqj, ivi, ivj
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                r0 = jt%row0
                nr = jt%joint%nrows
                call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed_position, 1, &
                                       mid, pi, qi, pose_only=.true.)
                call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed_position, &
                                       1 + qi, mjd, pj, qj, pose_only=.true.)
                call marker_jacobian_dual(self, jt%marker_i, pi, jxi, jai)
                call marker_jacobian_dual(self, jt%marker_j, pj, jxj, jaj)
                ni = marker_columns(self, jt%marker_i, .false.)
                nj = marker_columns(self, jt%marker_j, .false.)
                call joint_jacobian_d(jt%joint, mid, jxi(:, 1:ni), jai(:, 1:ni, :), mjd, &
                                      jxj(:, 1:nj), jaj(:, 1:nj, :), &
                                      driver_dual(joint_driver(self, k, t), 0), &
                                      cid(1:nr, 1:ni), cjd(1:nr, 1:nj))
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                do r = 1, nr
                    s = dot_product(cid(r, 1:ni), w(ivi + 1:ivi + ni)) &
                        + dot_product(cjd(r, 1:nj), w(ivj + 1:ivj + nj))
                    call add_tangents(gwq, r0 + r, s, qi, iqi, qj, iqj)
                end do
                do l = 1, ni
                    call add_tangents(gtlq, ivi + l, &
                                      dot_product(cid(1:nr, l), lambda(r0 + 1:r0 + nr)), &
                                      qi, iqi, qj, iqj)
                end do
                do l = 1, nj
                    call add_tangents(gtlq, ivj + l, &
                                      dot_product(cjd(1:nr, l), lambda(r0 + 1:r0 + nr)), &
                                      qi, iqi, qj, iqj)
                end do
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                block
                    real(wp) :: bq(node_frame_rows, frame_columns(fr, .true.)), &
                        bl(frame_columns(fr, .false.), frame_columns(fr, .true.))
                    integer :: c
                    call frame_rate_q(fr, q, w, bq)
                    call add_frame_columns(fr, .true., bq, fr%row0, gwq)
                    call frame_gtl_q(fr, q, lambda(fr%row0 + 1:fr%row0 + node_frame_rows), bl)
                    do l = 1, size(bl, 2)
                        c = frame_column(fr, l, .true.)
                        do r = 1, size(bl, 1)
                            call gtlq%add(frame_column(fr, r, .false.), c, bl(r, l))
                        end do
                    end do
                end block
            end associate
        end do
    end subroutine jacobian_derivatives_into

    !> out(row, q columns of body i and j) += tangents of s (directions 1..qi
    !> for body i at offset iqi, qi+1..qi+qj for body j at offset iqj).
    pure subroutine add_tangents(out, row, s, qi, iqi, qj, iqj)
        type(accumulator_t), intent(inout) :: out
        integer, intent(in) :: row, qi, iqi, qj, iqj
        type(dual_t), intent(in) :: s
        integer :: l
        do l = 1, qi
            call out%add(row, iqi + l, s%der(l))
        end do
        do l = 1, qj
            call out%add(row, iqj + l, s%der(qi + l))
        end do
    end subroutine add_tangents

    subroutine system_constraint_time_derivative_jacobian(self, t, q, dq, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nc, self%nq)
        call time_derivative_jacobian_into(self, t, q, self%acc(1))
        call self%acc(1)%get_dense(dq)
    end subroutine system_constraint_time_derivative_jacobian

    subroutine system_constraint_time_derivative_jacobian_sparse(self, t, q, values, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_sparse(self%patterns%constraint_q)
        call time_derivative_jacobian_into(self, t, q, self%acc(1))
        call self%acc(1)%get_values(values, 'mbs system: dg_I/dq', status)
    end subroutine system_constraint_time_derivative_jacobian_sparse

    !> ∂c_t/∂q added into dq: AD of the hand-coded c_t.
    subroutine time_derivative_jacobian_into(self, t, q, dq)
        class(mbs_system_t), intent(in) :: self
        real(wp), intent(in) :: t, q(:)
        type(accumulator_t), intent(inout) :: dq
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: pd(rigid_body_nq), ctd(max_rows)
        integer :: k, nr, qi, qj, r, bi, bj, iqi, iqj, ivi, ivj
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                nr = jt%joint%nrows
                call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed_position, 1, &
                                       mid, pd, qi, pose_only=.true.)
                call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed_position, &
                                       1 + qi, mjd, pd, qj, pose_only=.true.)
                call joint_rows_d(joint_part_time_derivative, jt%joint, mid, mjd, &
                                  driver_dual(joint_driver(self, k, t), 0), ctd(1:nr))
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                do r = 1, nr
                    call add_tangents(dq, jt%row0 + r, ctd(r), qi, iqi, qj, iqj)
                end do
            end associate
        end do
    end subroutine time_derivative_jacobian_into

    subroutine system_constraint_curvature_derivatives(self, t, q, v, gq, gv, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:, :), gv(:, :)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_dense(self%nc, self%nq)
        call self%acc(2)%start_dense(self%nc, self%nv)
        call curvature_derivatives_into(self, t, q, v, self%acc(1), self%acc(2))
        call self%acc(1)%get_dense(gq)
        call self%acc(2)%get_dense(gv)
    end subroutine system_constraint_curvature_derivatives

    subroutine system_constraint_curvature_derivatives_sparse(self, t, q, v, gq, gv, status)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:), gv(:)
        type(status_t), intent(inout) :: status
        call self%acc(1)%start_sparse(self%patterns%constraint_q)
        call self%acc(2)%start_sparse(self%patterns%constraint_v)
        call curvature_derivatives_into(self, t, q, v, self%acc(1), self%acc(2))
        call self%acc(1)%get_values(gq, 'mbs system: dgamma/dq', status)
        call self%acc(2)%get_values(gv, 'mbs system: dgamma/dv', status)
    end subroutine system_constraint_curvature_derivatives_sparse

    !> ∂γ/∂q and ∂γ/∂v added into gq, gv: AD of the hand-coded γ, one pass
    !> along the positions and one along the velocities of the joint's two bodies.
    subroutine curvature_derivatives_into(self, t, q, v, gq, gv)
        class(mbs_system_t), intent(in) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        type(accumulator_t), intent(inout) :: gq, gv
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: pd(rigid_body_nq), conv(max_rows), tt(max_rows), drvd(3)
        integer :: k, nr, ni, nj, r, bi, bj, iqi, iqj, ivi, ivj, pass, seed
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                nr = jt%joint%nrows
                drvd = driver_dual(joint_driver(self, k, t), 0)
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                do pass = 1, 2
                    seed = merge(seed_position, seed_velocity, pass == 1)
                    call marker_state_dual(self, jt%marker_i, q, v, seed, 1, mid, pd, ni)
                    call marker_state_dual(self, jt%marker_j, q, v, seed, 1 + ni, mjd, pd, nj)
                    call joint_rows_d(joint_part_convective, jt%joint, mid, mjd, drvd, &
                                      conv(1:nr))
                    call joint_rows_d(joint_part_time_terms, jt%joint, mid, mjd, drvd, tt(1:nr))
                    do r = 1, nr
                        if (pass == 1) then
                            call add_tangents(gq, jt%row0 + r, conv(r) + tt(r), ni, iqi, nj, &
                                              iqj)
                        else
                            call add_tangents(gv, jt%row0 + r, conv(r) + tt(r), ni, ivi, nj, &
                                              ivj)
                        end if
                    end do
                end do
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                block
                    real(wp) :: bq(node_frame_rows, frame_columns(fr, .true.)), &
                        bv(node_frame_rows, frame_columns(fr, .false.))
                    call frame_curvature_qv(fr, q, v, bq, bv)
                    call add_frame_columns(fr, .true., bq, fr%row0, gq)
                    call add_frame_columns(fr, .false., bv, fr%row0, gv)
                end block
            end associate
        end do
    end subroutine curvature_derivatives_into

    ! ------------------------------------------------ reactions

    !> The force and torque joint k exerts on the body of marker i (column 1)
    !> and of marker j (column 2), global components, the torque about the
    !> marker's origin: the generalised force −C_bᵀλ_k of the equations of
    !> motion M v' = f − Gᵀλ (module header). A ground side reports zeros
    !> (the ground's share is the opposite of the body's for joints whose
    !> markers' origins coincide).
    subroutine system_joint_reaction(self, k, t, q, lambda, force, torque)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(in) :: lambda(:) !! all nc multipliers
        real(wp), intent(out) :: force(3, 2), torque(3, 2)
        real(wp) :: ci(max_rows, rigid_body_nq), cj(max_rows, rigid_body_nq), ct(max_rows)
        real(wp) :: gen(6), a(3, 3)
        integer :: ni, nj, side, b, iq, iv, mk, r0, nr
        force = 0.0_wp
        torque = 0.0_wp
        associate (jt => self%joints(k))
            r0 = jt%row0
            nr = jt%joint%nrows
            call joint_first_derivatives(self, k, t, q, .false., ci, cj, ni, nj, ct)
            do side = 1, 2
                mk = merge(jt%marker_i, jt%marker_j, side == 1)
                call marker_offsets(self, mk, b, iq, iv)
                if (b == 0) cycle
                if (b < 0) then
                    ! a node takes the force only
                    if (side == 1) force(:, side) = -matmul(lambda(r0 + 1:r0 + nr), ci(1:nr, 1:3))
                    if (side == 2) force(:, side) = -matmul(lambda(r0 + 1:r0 + nr), cj(1:nr, 1:3))
                    cycle
                end if
                if (side == 1) then
                    gen = -matmul(lambda(r0 + 1:r0 + nr), ci(1:nr, 1:6))
                else
                    gen = -matmul(lambda(r0 + 1:r0 + nr), cj(1:nr, 1:6))
                end if
                a = rotation_matrix(q(iq + 4:iq + 7))
                force(:, side) = gen(1:3)
                ! gen(4:6) = s_b × Aᵀ F + n′ (body-fixed moment about the centre)
                torque(:, side) = matmul(a, gen(4:6) - cross(self%markers(mk)%position, &
                                                              matmul(transpose(a), gen(1:3))))
            end do
        end associate
    end subroutine system_joint_reaction
end module flexmbs_mbs_system
