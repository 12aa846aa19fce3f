!> A multibody system from the `&multibody`, `&rigid_body`, `&rigid_chain`,
!> `&flexible_body`, `&marker`, `&force`,
!> `&joint` and `&driver` groups of a validated scene (names already
!> checked): rigid bodies in absolute coordinates, markers (axes from z_axis
!> and x_axis, made orthonormal), joints and drivers, as an mbs_system_t
!> with its initial positions and velocities.
!>
!> The constraint set is checked before anything is written: the rows of G
!> at the initial configuration must be independent (rank by SVD), so a
!> redundant constraint set, or one singular at the start, is bad input that
!> names the joints involved. Inconsistent initial positions are corrected
!> by the formulation's consistent-initial projection (scene.f90), which
!> fails with its own message when no assembly is found.
module flexmbs_run_multibody_builder
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text, real_text
    use flexmbs_linalg_lapack, only: dgesvd_quiet
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_inertia, only: inertia_tensor, inertia_defect
    use flexmbs_mbs_joint, only: joint_spherical, joint_primitive
    use flexmbs_mbs_joint_types, only: joint_kind, joint_choices
    use flexmbs_mbs_primitive_kinds, only: primitive_angle_driver, &
        primitive_translation_driver, primitive_distance
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        driver_t, node_frame_t
    use flexmbs_mbs_force_element, only: force_element_t, force_spring_damper, &
        force_rotational, force_bushing, force_applied
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_scene_input, only: marker_index, flexible_index
    use flexmbs_run_body_builder, only: build_flexible_body
    use flexmbs_run_modal_builder, only: build_modal_body, modal_interfaces, interface_number
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_run_chain_builder, only: build_rigid_chains, chain_link
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    implicit none
    private

    !> Relative singular-value threshold for independent constraint rows.
    real(wp), parameter :: rank_tolerance = 1.0e-10_wp

    !> What build_multibody assembles, phase by phase, for new_mbs_system:
    !> the parts, the initial state, and what each node-set marker became.
    type :: parts_t
        type(rigid_body_t), allocatable :: bodies(:)  !! the rigid bodies, then the frames
        type(marker_t), allocatable :: markers(:)
        type(mbs_joint_t), allocatable :: joints(:)
        type(flexible_body_t), allocatable :: flex(:)
        type(rigid_chain_t), allocatable :: chains(:)
        type(node_frame_t), allocatable :: frames(:)
        type(modal_body_t), allocatable :: modal(:)
        real(wp), allocatable :: q0(:), v0(:)
        !> per scene marker: its node frame (0: none), whether it is a
        !> set's centroid for spherical joints alone
        integer, allocatable :: frame_of(:)
        logical, allocatable :: centroid(:)
        !> per &flexible_body: its number among the nonlinear (flex_of) or
        !> modal (modal_of) bodies, where its v (flex_v0) or q (modal_q0) start
        integer, allocatable :: flex_of(:), modal_of(:), flex_v0(:), modal_q0(:)
        !> per joint: the scene's label and the output's name; per frame its label
        character(len=80), allocatable :: labels(:), names(:), frame_labels(:)
    end type parts_t

    public :: build_multibody

contains

    !> The system of the scene, q0 = (r, p) per body and v0 = (ṙ, ω′) per body.
    subroutine build_multibody(scene, sys, q0, v0, status, joint_labels, joint_names)
        type(scene_input_t), intent(in) :: scene
        type(mbs_system_t), intent(out) :: sys
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        !> per system joint, what the scene calls it ('&joint ''J''', ...)
        character(len=:), allocatable, intent(out), optional :: joint_labels(:)
        !> per joint of the system (not the node frames): 'joints/NAME' or
        !> 'drivers/NAME' ('joints/NAME (node N)' for the joints of an attach)
        character(len=:), allocatable, intent(out), optional :: joint_names(:)
        type(parts_t) :: parts
        call choose_frames(scene, parts)
        call place_rigid_bodies(scene, parts, status)
        if (.not. status%ok()) return
        call add_bodies(scene, parts, status)
        if (.not. status%ok()) return
        call place_frames(scene, parts, status)
        if (.not. status%ok()) return
        call place_markers(scene, parts, status)
        if (.not. status%ok()) return
        call add_joints(scene, parts, status)
        if (.not. status%ok()) return
        call add_drivers(scene, parts)
        sys = new_mbs_system(parts%bodies, parts%markers, parts%joints, &
            gravity=scene%multibody%gravity, &
            constraint_derivatives=trim(scene%multibody%constraint_derivatives), status=status, &
            flexible=parts%flex, chains=parts%chains, frames=parts%frames, &
            elements=scene_forces(scene), modal=parts%modal)
        call move_alloc(parts%q0, q0)
        call move_alloc(parts%v0, v0)
        if (.not. status%ok()) then
            call status%set(status_bad_input, scene%path // ': ' // status%text())
            return
        end if
        call check_rank(scene, sys, q0, [character(len=80) :: parts%labels, parts%frame_labels], &
                        status)
        if (present(joint_labels)) &
            joint_labels = [character(len=80) :: parts%labels, parts%frame_labels]
        if (present(joint_names)) joint_names = parts%names
    end subroutine build_multibody

    !> Node-set markers that a joint other than 'attach', a driver or a force
    !> uses get a node frame (a massless body after the scene's rigid
    !> bodies), unless spherical joints to points alone use them
    !> (centroid_markers): parts%frame_of, parts%centroid.
    subroutine choose_frames(scene, parts)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        integer :: i
        parts%centroid = centroid_markers(scene)
        allocate (parts%frame_of(size(scene%markers)), source=0)
        do i = 1, size(scene%joints)
            if (scene%joints(i)%type == 'attach') cycle
            call use_frame(scene%joints(i)%marker_i)
            call use_frame(scene%joints(i)%marker_j)
        end do
        do i = 1, size(scene%drivers)
            call use_frame(scene%drivers(i)%marker_i)
            call use_frame(scene%drivers(i)%marker_j)
        end do
        do i = 1, size(scene%forces)
            call use_frame(scene%forces(i)%marker_i)
            call use_frame(scene%forces(i)%marker_j)
        end do

    contains

        !> Marker `name` gets a node frame if it is a node-set marker.
        subroutine use_frame(name)
            character(len=*), intent(in) :: name
            integer :: k
            k = marker_index(scene, name)
            if (k == 0) return
            if (len_trim(scene%markers(k)%node_set) == 0 .or. parts%frame_of(k) > 0 .or. &
                parts%centroid(k)) return
            parts%frame_of(k) = maxval(parts%frame_of) + 1
        end subroutine use_frame
    end subroutine choose_frames

    !> The scene's rigid bodies, and room for the node frames after them:
    !> their masses and inertias, q0 and v0.
    subroutine place_rigid_bodies(scene, parts, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: defect
        real(wp) :: p(4), r(3, 3), inertia(3, 3)
        integer :: i, nb
        nb = size(scene%rigid_bodies) + count(parts%frame_of > 0)
        allocate (parts%bodies(nb))
        allocate (parts%q0(7 * nb), parts%v0(6 * nb), source=0.0_wp)
        do i = 1, size(scene%rigid_bodies)
            associate (b => scene%rigid_bodies(i))
                inertia = inertia_tensor(b%inertia, b%inertia_products)
                parts%bodies(i) = rigid_body_t(mass=b%mass, inertia=inertia)
                defect = inertia_defect(inertia)
                if (len(defect) > 0) then
                    call status%set(status_bad_input, scene%path // ': &rigid_body ''' // &
                        trim(b%name) // ''': inertia, inertia_products: ' // defect // &
                        ' (line ' // int_text(b%line) // ')')
                    return
                end if
                p = quat_from_axis_angle(b%rotation_axis / norm2(b%rotation_axis), &
                                         b%rotation_angle)
                r = rotation_matrix(p)
                parts%q0(7 * i - 6:7 * i) = [b%position, p]
                parts%v0(6 * i - 5:6 * i) = [b%velocity, matmul(transpose(r), b%angular_velocity)]
            end associate
        end do
    end subroutine place_rigid_bodies

    !> The rigid chains (one per &rigid_chain tree) after the rigid bodies,
    !> then the flexible bodies (body fb's velocities after v0(flex_v0(fb))),
    !> then the modal bodies (their q after q0(modal_q0(fb))).
    subroutine add_bodies(scene, parts, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: qf(:), vf(:), qc(:), vc(:)
        integer :: fb
        call build_rigid_chains(scene, parts%chains, qc, vc, status)
        if (.not. status%ok()) return
        parts%q0 = [parts%q0, qc]
        parts%v0 = [parts%v0, vc]
        call number_bodies(scene, parts%flex_of, parts%modal_of)
        allocate (parts%flex(count(parts%flex_of > 0)), parts%flex_v0(size(scene%bodies)), &
                  parts%modal(count(parts%modal_of > 0)), parts%modal_q0(size(scene%bodies)))
        do fb = 1, size(scene%bodies)
            if (parts%flex_of(fb) == 0) cycle
            call build_flexible_body(scene, fb, parts%flex(parts%flex_of(fb)), qf, vf, status)
            if (.not. status%ok()) return
            parts%flex_v0(fb) = size(parts%v0)
            parts%q0 = [parts%q0, qf]
            parts%v0 = [parts%v0, vf]
        end do
        do fb = 1, size(scene%bodies)
            if (parts%modal_of(fb) == 0) cycle
            call build_modal_body(scene, fb, modal_interfaces(scene, fb), &
                                  parts%modal(parts%modal_of(fb)), qf, vf, status)
            if (.not. status%ok()) return
            parts%modal_q0(fb) = size(parts%q0)
            parts%q0 = [parts%q0, qf]
            parts%v0 = [parts%v0, vf]
        end do
    end subroutine add_bodies

    !> The node frames: at the set's centroid with the reference axes (a
    !> flexible body starts in its reference configuration), moving with
    !> the mean velocity of the set and the body's initial spin; on a modal
    !> body, at its interface (modal_frame).
    subroutine place_frames(scene, parts, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        type(status_t), intent(inout) :: status
        integer, allocatable :: nodes(:)
        real(wp) :: anchor(3)
        integer :: i, k, b, fb
        allocate (parts%frames(count(parts%frame_of > 0)))
        allocate (parts%frame_labels(size(parts%frames)))
        do i = 1, size(scene%markers)
            k = parts%frame_of(i)
            if (k == 0) cycle
            fb = flexible_index(scene, scene%markers(i)%body)
            b = size(scene%rigid_bodies) + k
            if (parts%modal_of(fb) > 0) then
                call modal_frame(scene, parts, i, k, b, status)
                if (.not. status%ok()) return
                cycle
            end if
            associate (body => parts%flex(parts%flex_of(fb)))
                call body%node_set(trim(scene%markers(i)%node_set), nodes, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, scene%path // ': &marker ''' // &
                        trim(scene%markers(i)%name) // ''': ' // status%text())
                    return
                end if
                parts%bodies(b) = rigid_body_t(frame=.true.)
                parts%frames(k) = node_frame_t(flexible=parts%flex_of(fb), body=b, nodes=nodes)
                parts%frame_labels(k) = '&marker ''' // trim(scene%markers(i)%name) // &
                    ''' (node frame)'
                anchor = body%centroid(nodes)
                parts%q0(7 * b - 6:7 * b) = [anchor, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
                parts%v0(6 * b - 5:6 * b) = [mean_velocity(body, parts%v0(parts%flex_v0(fb) + 1:), &
                    nodes), scene%bodies(fb)%initial_angular_velocity]
            end associate
        end do
    end subroutine place_frames

    !> The interface frame of node-set marker i on a modal body: frame k,
    !> rigid body b, at the interface's centroid with the mesh's axes,
    !> moving with the body's initial rigid field.
    subroutine modal_frame(scene, parts, i, k, b, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        integer, intent(in) :: i, k, b
        type(status_t), intent(inout) :: status
        integer :: j, mb, fm
        real(wp) :: d(3), c(3)
        fm = flexible_index(scene, scene%markers(i)%body)
        mb = parts%modal_of(fm)
        j = interface_number(scene, fm, scene%markers(i)%node_set)
        if (j == 0) then
            call status%set(status_bad_input, scene%path // ': &marker ''' // &
                trim(scene%markers(i)%name) // ''': node_set = ''' // &
                trim(scene%markers(i)%node_set) // ''': not an interface of the modal &
                &body ''' // trim(scene%bodies(fm)%name) // ''' (line ' // &
                int_text(scene%markers(i)%line) // ')')
            return
        end if
        parts%bodies(b) = rigid_body_t(frame=.true.)
        parts%frames(k) = node_frame_t(body=b, modal=mb, modal_interface=j)
        parts%frame_labels(k) = '&marker ''' // trim(scene%markers(i)%name) // &
            ''' (interface frame)'
        d = parts%modal(mb)%interface_position(j)
        c = parts%q0(parts%modal_q0(fm) + 1:parts%modal_q0(fm) + 3)
        parts%q0(7 * b - 6:7 * b) = [c + d, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        associate (bd => scene%bodies(fm))
            ! the rigid field v₀ + ω × (X − X̄) at the interface's centroid
            parts%v0(6 * b - 5:6 * b) = [bd%initial_velocity + &
                cross(bd%initial_angular_velocity, c + d - parts%modal(mb)%centroid()), &
                bd%initial_angular_velocity]
        end associate
    end subroutine modal_frame

    !> Mean initial velocity of the nodes `set` of a flexible body whose free
    !> velocities are v (fixed nodes at rest).
    function mean_velocity(body, v, set) result(u)
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: v(:)
        integer, intent(in) :: set(:)
        real(wp) :: u(3)
        integer :: a, l, dofs(3)
        u = 0.0_wp
        do a = 1, size(set)
            dofs = body%node_dofs(set(a))
            do l = 1, 3
                if (dofs(l) > 0) u(l) = u(l) + v(dofs(l))
            end do
        end do
        u = u / size(set)
    end function mean_velocity

    !> The scene's markers first (node-set markers of 'attach' joints are
    !> placeholders: the joint expands into node markers, add_joints).
    subroutine place_markers(scene, parts, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        type(status_t), intent(inout) :: status
        integer, allocatable :: nodes(:)
        real(wp) :: position(3)
        integer :: i, b, c, link, fb
        allocate (parts%markers(size(scene%markers)))
        do i = 1, size(parts%markers)
            associate (m => scene%markers(i))
                if (parts%frame_of(i) > 0) then
                    ! on the frame: the origin relative to the centroid, the
                    ! reference axes (the frame's at the start)
                    b = size(scene%rigid_bodies) + parts%frame_of(i)
                    position = 0.0_wp
                    if (m%position_given) position = m%position - parts%q0(7 * b - 6:7 * b - 4)
                    ! a position at the centroid (to round-off) is the centroid
                    if (norm2(position) <= 1.0e-12_wp * max(1.0_wp, norm2(m%position))) &
                        position = 0.0_wp
                    parts%markers(i) = marker_t(body=b, position=position, &
                                                axes=axes_from(m%z_axis, m%x_axis))
                    cycle
                end if
                if (parts%centroid(i)) then
                    fb = parts%flex_of(flexible_index(scene, m%body))
                    call parts%flex(fb)%node_set(trim(m%node_set), nodes, status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, scene%path // ': &marker ''' // &
                            trim(m%name) // ''': ' // status%text())
                        return
                    end if
                    call parts%markers(i)%on_node_set(fb, nodes)
                    cycle
                end if
                b = 0
                c = 0
                link = 0
                if (m%body /= 'ground' .and. len_trim(m%node_set) == 0) &
                    b = body_index(scene, m%body)
                if (b == 0 .and. m%body /= 'ground') call chain_link(scene, m%body, c, link)
                parts%markers(i) = marker_t(body=b, position=m%position, &
                                            axes=axes_from(m%z_axis, m%x_axis), chain=c, &
                                            link=link)
            end associate
        end do
    end subroutine place_markers

    !> The scene's joints: one of the table's types each, or for 'attach' a
    !> spherical joint per node of the set, the rigid side's marker at the
    !> node's reference position in that body's (or chain link's) frame.
    subroutine add_joints(scene, parts, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        type(status_t), intent(inout) :: status
        integer :: i
        allocate (parts%joints(0), parts%labels(0), parts%names(0))
        do i = 1, size(scene%joints)
            associate (jt => scene%joints(i))
                if (jt%type == 'attach') then
                    call attach(scene, parts, i, status)
                    if (.not. status%ok()) return
                    cycle
                end if
                if (joint_kind(jt%type) == 0) then
                    call status%set(status_bad_input, scene%path // ': &joint ''' // &
                        trim(jt%name) // ''': type = ''' // trim(jt%type) // ''': no joint &
                        &type of that name; use one of ' // joint_choices // '|attach')
                    return
                end if
                parts%joints = [parts%joints, mbs_joint_t(joint_kind(jt%type), &
                    marker_index(scene, jt%marker_i), marker_index(scene, jt%marker_j))]
                parts%labels = [character(len=80) :: parts%labels, &
                                '&joint ''' // trim(jt%name) // '''']
                parts%names = [character(len=80) :: parts%names, 'joints/' // trim(jt%name)]
            end associate
        end do
    end subroutine add_joints

    !> Joint i, an 'attach': its spherical joints, one per node of marker
    !> j's set, and their markers.
    subroutine attach(scene, parts, i, status)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        integer, intent(in) :: i
        type(status_t), intent(inout) :: status
        integer, allocatable :: nodes(:)
        real(wp) :: anchor(3), origin(3), r(3, 3)
        integer :: mi, fb, b, c, link, n
        associate (jt => scene%joints(i))
            mi = marker_index(scene, jt%marker_i)
            associate (mj => scene%markers(marker_index(scene, jt%marker_j)))
                fb = parts%flex_of(flexible_index(scene, mj%body))
                if (fb == 0) then
                    call status%set(status_bad_input, scene%path // ': &joint ''' // &
                        trim(jt%name) // ''': type = ''attach'' ties nodes of a nonlinear &
                        &body; on the modal body ''' // trim(mj%body) // ''' use a &
                        &''fixed'' joint on its interface')
                    return
                end if
                call parts%flex(fb)%node_set(trim(mj%node_set), nodes, status)
            end associate
            if (.not. status%ok()) then
                call status%set(status_bad_input, scene%path // ': &joint ''' // &
                    trim(jt%name) // ''': marker_j ''' // trim(jt%marker_j) // ''': ' // &
                    status%text())
                return
            end if
            call parts%markers(mi)%attached_to(b, c, link)
            if (c > 0) call link_frame(parts, c, link, origin, r)
            do n = 1, size(nodes)
                anchor = parts%flex(fb)%reference_node(nodes(n))
                if (c > 0) then
                    anchor = matmul(transpose(r), anchor - origin)
                else if (b > 0) then
                    r = rotation_matrix(parts%q0(7 * b - 3:7 * b))
                    anchor = matmul(transpose(r), anchor - parts%q0(7 * b - 6:7 * b - 4))
                end if
                parts%markers = [parts%markers, marker_t(b, anchor, chain=c, link=link), &
                                 marker_t(0, flexible=fb, node=nodes(n))]
                parts%joints = [parts%joints, mbs_joint_t(joint_spherical, &
                    size(parts%markers) - 1, size(parts%markers))]
                parts%labels = [character(len=80) :: parts%labels, '&joint ''' // &
                    trim(jt%name) // ''' (node ' // int_text(nodes(n)) // ')']
                parts%names = [character(len=80) :: parts%names, 'joints/' // trim(jt%name) // &
                               ' (node ' // int_text(nodes(n)) // ')']
            end do
        end associate
    end subroutine attach

    !> Origin and axes of link `link` of chain c at q0 (the chains' q
    !> follow the rigid bodies', chain by chain).
    subroutine link_frame(parts, c, link, origin, axes)
        type(parts_t), intent(inout) :: parts
        integer, intent(in) :: c, link
        real(wp), intent(out) :: origin(3), axes(3, 3)
        integer :: first, k
        first = 7 * size(parts%bodies)   ! the rigid bodies' and frames' q first
        do k = 1, c - 1
            first = first + parts%chains(k)%nq
        end do
        call parts%chains(c)%body_frame(parts%q0(first + 1:first + parts%chains(c)%nq), link, &
                                        origin, axes)
    end subroutine link_frame

    !> The scene's drivers, after the joints: a driven primitive each.
    subroutine add_drivers(scene, parts)
        type(scene_input_t), intent(in) :: scene
        type(parts_t), intent(inout) :: parts
        integer :: i
        do i = 1, size(scene%drivers)
            associate (d => scene%drivers(i))
                parts%joints = [parts%joints, mbs_joint_t(joint_primitive, &
                    marker_index(scene, d%marker_i), marker_index(scene, d%marker_j), &
                    driver_kind(d%type), d%axis_i, d%axis_j, &
                    driver_t(d%coefficients, d%amplitude, d%frequency, d%phase, d%ramp_rate, &
                             d%ramp_time))]
                parts%labels = [character(len=80) :: parts%labels, &
                                '&driver ''' // trim(d%name) // '''']
                parts%names = [character(len=80) :: parts%names, 'drivers/' // trim(d%name)]
            end associate
        end do
    end subroutine add_drivers

    !> Each &flexible_body's number among the nonlinear ones (flex_of) or
    !> the modal ones (modal_of), 0 in the other.
    pure subroutine number_bodies(scene, flex_of, modal_of)
        type(scene_input_t), intent(in) :: scene
        integer, allocatable, intent(out) :: flex_of(:), modal_of(:)
        integer :: fb
        allocate (flex_of(size(scene%bodies)), modal_of(size(scene%bodies)), source=0)
        do fb = 1, size(scene%bodies)
            if (scene%bodies(fb)%model == 'modal') then
                modal_of(fb) = maxval([0, modal_of]) + 1
            else
                flex_of(fb) = maxval([0, flex_of]) + 1
            end if
        end do
    end subroutine number_bodies

    !> The node-set markers that need no node frame: without a `position`
    !> (at the set's centroid) and used by spherical joints only (besides
    !> 'attach', which works node by node). A spherical joint loads no
    !> rotation, so its rows can take the centroid of the set, linear in the
    !> nodes' positions, and the system keeps a constant mass matrix (no
    !> massless frame body). A marker that a driver, a force element or
    !> another joint uses keeps its frame.
    pure function centroid_markers(scene) result(centroid)
        type(scene_input_t), intent(in) :: scene
        logical :: centroid(size(scene%markers))
        logical :: used(size(scene%markers))
        integer :: i, k
        do k = 1, size(scene%markers)
            centroid(k) = len_trim(scene%markers(k)%node_set) > 0 .and. &
                .not. scene%markers(k)%position_given
            ! a modal body's interfaces are reached through interface frames
            i = flexible_index(scene, scene%markers(k)%body)
            if (i > 0) then
                if (scene%bodies(i)%model == 'modal') centroid(k) = .false.
            end if
        end do
        used = .false.
        do i = 1, size(scene%drivers)
            call exclude(marker_index(scene, scene%drivers(i)%marker_i))
            call exclude(marker_index(scene, scene%drivers(i)%marker_j))
        end do
        do i = 1, size(scene%forces)
            call exclude(marker_index(scene, scene%forces(i)%marker_i))
            call exclude(marker_index(scene, scene%forces(i)%marker_j))
        end do
        do i = 1, size(scene%joints)
            select case (scene%joints(i)%type)
            case ('attach')
            case ('spherical')
                k = marker_index(scene, scene%joints(i)%marker_i)
                if (k > 0) used(k) = .true.
                k = marker_index(scene, scene%joints(i)%marker_j)
                if (k > 0) used(k) = .true.
            case default
                call exclude(marker_index(scene, scene%joints(i)%marker_i))
                call exclude(marker_index(scene, scene%joints(i)%marker_j))
            end select
        end do
        centroid = centroid .and. used
    contains
        pure subroutine exclude(k)
            integer, intent(in) :: k
            if (k > 0) centroid(k) = .false.
        end subroutine exclude
    end function centroid_markers

    !> The force elements of the scene's &force groups (checked already).
    pure function scene_forces(scene) result(el)
        type(scene_input_t), intent(in) :: scene
        type(force_element_t) :: el(size(scene%forces))
        integer :: i, k
        do i = 1, size(scene%forces)
            associate (f => scene%forces(i), e => el(i))
                e%marker_i = marker_index(scene, f%marker_i)
                e%marker_j = marker_index(scene, f%marker_j)
                select case (f%type)
                case ('spring_damper')
                    e%kind = force_spring_damper
                    e%reference = f%free_length
                case ('rotational')
                    e%kind = force_rotational
                    e%reference = f%free_angle
                case ('bushing')
                    e%kind = force_bushing
                case ('applied')
                    e%kind = force_applied
                    e%marker_j = 0
                    e%force = f%force
                    e%torque = f%torque
                    e%world_frame = f%frame == 'world'
                    e%driver = driver_t(f%coefficients, f%amplitude, f%frequency, f%phase)
                end select
                if (e%kind == force_bushing) then
                    e%stiffness6 = bushing_matrix(f%has_stiffness_matrix, &
                                                  f%stiffness_matrix, f%stiffness)
                    e%damping6 = bushing_matrix(f%has_damping_matrix, f%damping_matrix, &
                                                f%damping)
                else
                    k = min(size(f%stiffness), size(e%stiffness))
                    e%stiffness(1:k) = f%stiffness(1:k)
                    if (size(f%damping) > 0) e%damping = f%damping(1)
                end if
            end associate
        end do
    end function scene_forces

    !> A bushing's K or C: the full matrix (given row by row) or the diagonal.
    pure function bushing_matrix(full, rows, diagonal) result(a)
        logical, intent(in) :: full
        real(wp), intent(in) :: rows(36), diagonal(:)
        real(wp) :: a(6, 6)
        integer :: k
        if (full) then
            a = transpose(reshape(rows, [6, 6]))
            return
        end if
        a = 0.0_wp
        do k = 1, min(6, size(diagonal))
            a(k, k) = diagonal(k)
        end do
    end function bushing_matrix

    !> G(t0, q0) must have full row rank: otherwise the constraints are
    !> redundant (or singular at the start); the message names the joints
    !> whose rows are dependent (the least singular vector's support).
    subroutine check_rank(scene, sys, q0, labels, status)
        type(scene_input_t), intent(in) :: scene
        type(mbs_system_t), intent(inout) :: sys
        real(wp), intent(in) :: q0(:)
        character(len=*), intent(in) :: labels(:) !! per system joint
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: g(:, :), gt(:, :), sv(:), u(:, :), vt(:, :), work(:)
        integer :: nc, nv, info, rank, k, row, first, last, nj, stat
        character(len=:), allocatable :: names
        nc = sys%nc
        nv = sys%nv
        if (nc == 0) return
        if (nc > nv) then
            call status%set(status_bad_input, scene%path // ': the joints and drivers give ' &
                // int_text(nc) // ' constraint rows for ' // int_text(nv) // ' velocities: &
                &the constraint set is redundant')
            return
        end if
        allocate (g(nc, nv), gt(nv, nc), sv(nc), u(1, 1), vt(nc, nc), &
            work(max(1, 5 * (nc + nv))), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, scene%path // ': dense constraint Jacobian for its rank', &
                2 * int(nc, i8) * nv + int(nc, i8) * nc, 8)
            return
        end if
        call sys%constraint_jacobian(scene%t_start, q0, g, status)
        if (.not. status%ok()) return
        ! Gᵀ = U Σ Vᵀ: a dependence yᵀ G = 0 among the rows is the last row of Vᵀ.
        gt = transpose(g)
        call dgesvd_quiet('N', 'A', nv, nc, gt, nv, sv, u, 1, vt, nc, work, size(work), info)
        if (info /= 0) return
        rank = count(sv > rank_tolerance * sv(1))
        if (rank == nc) return
        ! rows taking part in the dependence: vt(nc, :) (last right singular vector of Gᵀ)
        names = ''
        nj = size(labels)
        do k = 1, nj
            first = sys%joint_first_row(k)
            last = nc
            if (k < nj) last = sys%joint_first_row(k + 1) - 1
            do row = first, last
                if (abs(vt(nc, row)) > 1.0e-6_wp) then
                    if (len(names) > 0) names = names // ', '
                    names = names // trim(labels(k))
                    exit
                end if
            end do
        end do
        call status%set(status_bad_input, scene%path // ': the constraint set is redundant &
            &or singular at t_start: ' // int_text(nc) // ' rows of rank ' // int_text(rank) // &
            ' (smallest singular value ' // real_text(sv(nc)) // '); involved: ' // names)
    end subroutine check_rank

    pure integer function body_index(scene, name)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        do body_index = 1, size(scene%rigid_bodies)
            if (scene%rigid_bodies(body_index)%name == name) return
        end do
        body_index = 0
    end function body_index


    !> Orthonormal axes (columns) with z along z_axis and x from x_axis made
    !> normal to it (any normal when x_axis is zero).
    pure function axes_from(z_axis, x_axis) result(a)
        real(wp), intent(in) :: z_axis(3), x_axis(3)
        real(wp) :: a(3, 3), h(3)
        a(:, 3) = z_axis / norm2(z_axis)
        h = x_axis
        if (norm2(cross(h, a(:, 3))) <= 1.0e-12_wp * max(norm2(h), 1.0e-300_wp)) then
            h = [1.0_wp, 0.0_wp, 0.0_wp]
            if (abs(a(1, 3)) > 0.9_wp) h = [0.0_wp, 1.0_wp, 0.0_wp]
        end if
        a(:, 1) = h - dot_product(h, a(:, 3)) * a(:, 3)
        a(:, 1) = a(:, 1) / norm2(a(:, 1))
        a(:, 2) = cross(a(:, 3), a(:, 1))
    end function axes_from

    pure integer function driver_kind(name)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ('angle'); driver_kind = primitive_angle_driver
        case ('translation'); driver_kind = primitive_translation_driver
        case default; driver_kind = primitive_distance
        end select
    end function driver_kind
end module flexmbs_run_multibody_builder
