!> Building flexmbs_mbs_system: the checks of bodies, chains, markers,
!> joints, force elements and node frames, and where each body's
!> coordinates and each joint's rows lie in q, v and c.
submodule (flexmbs_mbs_system) flexmbs_mbs_system_build
    implicit none
contains

    !> The system of `bodies` under `gravity`, with `markers` and `joints`;
    !> `constraint_derivatives` is 'analytic' (default) or 'ad'. On bad input
    !> `status` says which item is wrong and why.
    module procedure new_mbs_system
        integer :: row0

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
        call place_chains(self, chains, status)
        if (.not. status%ok()) return
        call place_modal(self, modal)
        call check_markers(self, bodies, markers, status)
        if (.not. status%ok()) return
        call place_joints(self, markers, joints, row0, status)
        if (.not. status%ok()) return
        self%markers = markers
        if (present(elements)) then
            call place_elements(self, elements, status)
            if (.not. status%ok()) return
        else
            allocate (self%elements(0))
        end if
        call place_coordinates(self)
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
        call allocate_marker_work(self)
    end procedure new_mbs_system

    !> The markers' workspace (marker_work_t), sized by the largest marker
    !> body: a rigid body's 7 coordinates or a chain's.
    subroutine allocate_marker_work(self)
        type(mbs_system_t), intent(inout) :: self
        integer :: n, f, side
        n = rigid_body_nq
        do f = 1, size(self%chains)
            n = max(n, self%chains(f)%nq)
        end do
        allocate (self%work(2))
        do side = 1, 2
            associate (w => self%work(side))
                allocate (w%jx(3, n), w%ja(3, n, 3), w%c(max_rows, n), w%jw(3, n), &
                          w%p(2 * n), w%jxd(3, n), w%jad(3, n, 3), w%cd(max_rows, n), w%g(n))
            end associate
        end do
    end subroutine allocate_marker_work

    !> The rigid chains and the geometry the constraints read from them.
    subroutine place_chains(self, chains, status)
        type(mbs_system_t), intent(inout) :: self
        type(rigid_chain_t), intent(in), optional :: chains(:)
        type(status_t), intent(inout) :: status
        integer :: k, f, nq, nv
        if (present(chains)) then
            self%chains = chains
        else
            allocate (self%chains(0))
        end if
        allocate (self%chain_geom(size(self%chains)))
        nq = 0
        nv = 0
        do f = 1, size(self%chains)
            nq = max(nq, self%chains(f)%nq)
            nv = max(nv, self%chains(f)%nv)
        end do
        allocate (self%chain_vq(nv, nq), self%chain_vv(nv, nv), self%chain_qq(nq, nq), &
                  self%chain_unit(nv), self%chain_rate(nq))
        do f = 1, size(self%chains)
            associate (ch => self%chains(f), g => self%chain_geom(f))
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
    end subroutine place_chains

    !> Each marker names a body, chain link or free node that exists, and
    !> has orthonormal axes.
    subroutine check_markers(self, bodies, markers, status)
        type(mbs_system_t), intent(in) :: self
        type(rigid_body_t), intent(in) :: bodies(:)
        type(marker_t), intent(in) :: markers(:)
        type(status_t), intent(inout) :: status
        integer :: k, i
        character(len=:), allocatable :: where
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
                if (allocated(markers(k)%nodes)) then
                    if (size(markers(k)%nodes) == 0 .or. markers(k)%node /= 0) then
                        call status%set(status_bad_input, where // ': a set marker needs &
                            &nodes and no single node')
                        return
                    end if
                    do i = 1, size(markers(k)%nodes)
                        call check_free_node(self%flex(markers(k)%flexible), &
                            markers(k)%nodes(i), where, status)
                        if (.not. status%ok()) return
                    end do
                else
                    call check_free_node(self%flex(markers(k)%flexible), markers(k)%node, &
                        where, status)
                    if (.not. status%ok()) return
                end if
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
    end subroutine check_markers

    !> Node `node` of body fb exists and is free (x, y, z consecutive in q).
    subroutine check_free_node(fb, node, where, status)
        type(flexible_body_t), intent(in) :: fb
        integer, intent(in) :: node
        character(len=*), intent(in) :: where
        type(status_t), intent(inout) :: status
        if (node < 1 .or. node > fb%mesh%node_count()) then
            call status%set(status_bad_input, where // ': node ' // int_text(node) // &
                ' outside the mesh')
            return
        end if
        if (any(fb%dof(:, node) == 0) .or. fb%dof(2, node) /= fb%dof(1, node) + 1 .or. &
            fb%dof(3, node) /= fb%dof(1, node) + 2) then
            call status%set(status_bad_input, where // ': node ' // int_text(node) // &
                ' is fixed (a node or set marker needs free nodes)')
        end if
    end subroutine check_free_node

    !> The joints between the markers, their rows in c from 0 (row0 out:
    !> the rows they take).
    subroutine place_joints(self, markers, joints, row0, status)
        type(mbs_system_t), intent(inout) :: self
        type(marker_t), intent(in) :: markers(:)
        type(mbs_joint_t), intent(in) :: joints(:)
        integer, intent(out) :: row0
        type(status_t), intent(inout) :: status
        integer :: k
        character(len=:), allocatable :: where
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
                    jt%linear = ji%kind == joint_spherical .and. &
                        point_or_ground(markers(ji%marker_i)) .and. &
                        point_or_ground(markers(ji%marker_j))
                    if ((allocated(markers(ji%marker_i)%nodes) .or. &
                         allocated(markers(ji%marker_j)%nodes)) .and. &
                        ji%kind /= joint_spherical) then
                        call status%set(status_bad_input, where // ': a set marker (the &
                            &centroid of a node set) takes spherical joints only')
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
    end subroutine place_joints

    !> A point of a flexible body (node or set centroid) or the ground.
    pure logical function point_or_ground(m)
        type(marker_t), intent(in) :: m
        point_or_ground = m%flexible > 0 .or. (m%body == 0 .and. m%chain == 0)
    end function point_or_ground

    !> The modal bodies and the scratch blocks of the largest.
    subroutine place_modal(self, modal)
        type(mbs_system_t), intent(inout) :: self
        type(modal_body_t), intent(in), optional :: modal(:)
        integer :: f, nq, nv
        if (present(modal)) then
            self%modal = modal
        else
            allocate (self%modal(0))
        end if
        nq = 0
        nv = 0
        do f = 1, size(self%modal)
            nq = max(nq, self%modal(f)%nq)
            nv = max(nv, self%modal(f)%nv)
        end do
        allocate (self%modal_vq(nv, nq), self%modal_vv(nv, nv))
    end subroutine place_modal

    !> Offsets in q and v: the rigid bodies, then the chains, then the
    !> flexible bodies, then the modal bodies.
    subroutine place_coordinates(self)
        type(mbs_system_t), intent(inout) :: self
        integer :: f
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
        allocate (self%modal_q(size(self%modal)), self%modal_v(size(self%modal)))
        do f = 1, size(self%modal)
            self%modal_q(f) = self%nq
            self%modal_v(f) = self%nv
            self%nq = self%nq + self%modal(f)%nq
            self%nv = self%nv + self%modal(f)%nv
        end do
    end subroutine place_coordinates

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
                if (fr%modal > 0) then
                    call place_modal_frame(self, fr, where, status)
                    if (.not. status%ok()) return
                    fr%row0 = row0
                    row0 = row0 + node_frame_rows
                    cycle
                end if
                if (f < 1 .or. f > size(self%flex)) then
                    call status%set(status_bad_input, where // ': flexible = ' // int_text(f) &
                        // ': must name a flexible body 1 .. ' // int_text(size(self%flex)))
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

    !> An interface frame of a modal body (its frame body checked): body and
    !> interface checked, the interface's offset, translation and rotation
    !> per unit η copied, the offsets of the frame body and the modal body
    !> in q and v.
    subroutine place_modal_frame(self, fr, where, status)
        type(mbs_system_t), intent(in) :: self
        type(node_frame_t), intent(inout) :: fr
        character(len=*), intent(in) :: where
        type(status_t), intent(inout) :: status
        integer :: m, j, b
        m = fr%modal
        j = fr%modal_interface
        b = fr%body
        if (m > size(self%modal)) then
            call status%set(status_bad_input, where // ': modal = ' // int_text(m) // &
                ': must name a modal body 1 .. ' // int_text(size(self%modal)))
            return
        end if
        if (j < 1 .or. j > size(self%modal(m)%interface_offset, 2)) then
            call status%set(status_bad_input, where // ': interface ' // int_text(j) // &
                ' of modal body ' // int_text(m) // ': it has ' // &
                int_text(size(self%modal(m)%interface_offset, 2)))
            return
        end if
        fr%flexible = 0
        allocate (fr%nodes(0), fr%nq(0), fr%nv(0), fr%s(3, 0))
        fr%weight = 0.0_wp
        fr%rigid_interface%offset = self%modal(m)%interface_offset(:, j)
        fr%rigid_interface%translation = self%modal(m)%interface_motion(1:3, :, j)
        fr%rigid_interface%rotation = self%modal(m)%interface_motion(4:6, :, j)
        fr%iq = rigid_body_nq * (b - 1)
        fr%iv = rigid_body_nv * (b - 1)
        fr%mq = self%modal_q(m)
        fr%mv = self%modal_v(m)
    end subroutine place_modal_frame
end submodule flexmbs_mbs_system_build
