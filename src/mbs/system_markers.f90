!> Markers, real and dual; drivers of flexmbs_mbs_system
!> (the type and the procedures' interfaces are there).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_markers
    implicit none

contains

    !> Global column of frame fr's local column l (flexmbs_mbs_node_frame).
    module procedure frame_column
        integer :: nb, a
        nb = merge(rigid_body_nq, rigid_body_nv, position_space)
        if (l <= nb) then
            c = merge(fr%iq, fr%iv, position_space) + l
        else if (fr%modal > 0) then
            c = merge(fr%mq, fr%mv, position_space) + l - nb
        else
            a = (l - nb - 1) / 3 + 1
            c = merge(fr%nq(a), fr%nv(a), position_space) + l - nb - 3 * (a - 1)
        end if
    end procedure frame_column

    !> out(row0 + rows, global columns) += block (local columns of frame fr).
    module procedure add_frame_columns
        integer :: l, r, c
        do l = 1, size(block, 2)
            c = frame_column(fr, l, position_space)
            do r = 1, size(block, 1)
                call out%add(row0 + r, c, block(r, l))
            end do
        end do
    end procedure add_frame_columns

    !> Frame i's rows of G (velocity space) or c_q, local columns.
    module procedure frame_first_derivatives
        if (self%derivatives == constraint_derivatives_analytic) then
            call frame_jacobian(self%frames(i), q, position_space, block)
        else
            call frame_jacobian_ad(self%frames(i), q, position_space, block)
        end if
    end procedure frame_first_derivatives

    ! ------------------------------------------------ markers, real and dual

    !> Offsets of marker k's body in q and v; ground: body = 0.
    !> A node marker reports body = −(its flexible body) and the offsets of
    !> the node's x coordinate; a set marker the same body and its body's
    !> offsets (its columns are spread over the set: set_node_offset).
    module procedure marker_offsets
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
            d = 0
            if (self%markers(k)%node > 0) d = self%flex(f)%dof(1, self%markers(k)%node) - 1
            iq = self%flex_q(f) + d
            iv = self%flex_v(f) + d
            return
        end if
        body = self%markers(k)%body
        iq = rigid_body_nq * (body - 1)
        iv = rigid_body_nv * (body - 1)
    end procedure marker_offsets

    module procedure is_set_marker
        is_set_marker = allocated(self%markers(k)%nodes)
    end procedure is_set_marker

    module procedure set_node_offset
        integer :: f
        f = self%markers(k)%flexible
        c = merge(self%flex_q(f), self%flex_v(f), position_space) &
            + self%flex(f)%dof(1, self%markers(k)%nodes(a)) - 1
    end procedure set_node_offset

    !> Position x and velocity xd of point marker k (its node, or the
    !> centroid of its set).
    pure subroutine point_motion(self, k, q, v, x, xd)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: x(3), xd(3)
        integer :: b, iq, iv, a, n
        if (.not. is_set_marker(self, k)) then
            call marker_offsets(self, k, b, iq, iv)
            x = q(iq + 1:iq + 3)
            xd = v(iv + 1:iv + 3)
            return
        end if
        x = 0.0_wp
        xd = 0.0_wp
        n = size(self%markers(k)%nodes)
        do a = 1, n
            iq = set_node_offset(self, k, a, .true.)
            iv = set_node_offset(self, k, a, .false.)
            x = x + q(iq + 1:iq + 3)
            xd = xd + v(iv + 1:iv + 3)
        end do
        x = x / n
        xd = xd / n
    end subroutine point_motion

    !> Columns of marker k's body in velocity space (6) or position space (7); 0 on ground.
    !> A point (node or set centroid) has 3: its x, y, z.
    module procedure marker_columns
        n = 0
        if (self%markers(k)%body > 0) n = merge(rigid_body_nq, rigid_body_nv, position_space)
        if (self%markers(k)%flexible > 0) n = 3
        if (self%markers(k)%chain > 0) n = merge(self%chains(self%markers(k)%chain)%nq, &
            self%chains(self%markers(k)%chain)%nv, position_space)
    end procedure marker_columns

    !> Dual passes marker k's body columns take (windows of window_columns;
    !> one on the ground, for the values and time).
    module procedure marker_windows
        n = max(1, (marker_columns(self, k, position_space) + window_columns - 1) &
                / window_columns)
    end procedure marker_windows

    !> Real frame and motion of marker k at (q, v).
    module procedure system_marker_pose
        type(marker_state_t) :: m
        call marker_state(self, k, q, self%zero_v, m)
        x = m%x
        axes = m%a
    end procedure system_marker_pose

    module procedure marker_state
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
                ! a point: its position and velocity, constant axes
                block
                    real(wp) :: x(3), xd(3)
                    call point_motion(self, k, q, v, x, xd)
                    call ground_marker_state(x, mk%axes, m)
                    m%xd = xd
                end block
            else if (b == 0) then
                call ground_marker_state(mk%position, mk%axes, m)
            else
                call rigid_marker_state(q(iq + 1:iq + 3), q(iq + 4:iq + 7), v(iv + 1:iv + 3), &
                                        v(iv + 4:iv + 6), mk%position, mk%axes, m)
            end if
        end associate
    end procedure marker_state

    !> Hand-coded marker Jacobians of marker k: velocity space (3 x 6) or
    !> position space (3 x 7), a chain's (3 x its columns), in the leading
    !> columns of jx, ja; n columns.
    module procedure marker_jacobian
        real(wp) :: jx6(3, 6), ja6(3, 6, 3), jx7(3, rigid_body_nq), ja7(3, rigid_body_nq, 3)
        integer :: b, iq, iv
        call marker_offsets(self, k, b, iq, iv)
        n = marker_columns(self, k, position_space)
        jx(:, 1:max(n, rigid_body_nq)) = 0.0_wp
        ja(:, 1:max(n, rigid_body_nq), :) = 0.0_wp
        if (b == 0) return
        if (self%markers(k)%chain > 0) then
            call chain_jacobian_real(self, k, q, iq, position_space, jx(:, 1:n), &
                                     ja(:, 1:n, :), p)
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
                call rigid_marker_jacobian_q(q(iq + 4:iq + 7), mk%position, mk%axes, jx7, ja7)
                jx(:, 1:rigid_body_nq) = jx7
                ja(:, 1:rigid_body_nq, :) = ja7
            else
                call rigid_marker_jacobian(q(iq + 4:iq + 7), mk%position, mk%axes, jx6, ja6)
                jx(:, 1:6) = jx6
                ja(:, 1:6, :) = ja6
            end if
        end associate
    end procedure marker_jacobian

    !> Dual frame and motion of marker k at (q, v) with its body's tangents
    !> `seed` in directions first, first+1, ... (the columns of `window`); p
    !> the pose duals (for the dual marker Jacobians: a rigid body's
    !> quaternion, a chain's coordinates and rates); n the directions used (0
    !> on the ground and past the body's last window).
    module procedure marker_state_dual
        !> the frame only (rigid markers): values and first derivatives of c
        !> the pose coordinates the dual Jacobians need: the quaternion of a
        !> rigid body (1:4), the coordinates of a chain (1:n)
        type(dual_t) :: r(3), rd(3), wb(3), sb(3), ub(3, 3), x(3), a(3, 3)
        real(wp) :: tp(4, 3)
        integer :: b, iq, iv, l, s
        call marker_offsets(self, k, b, iq, iv)
        n = 0
        s = seed
        if (present(window)) then
            ! a rigid body or node has one window: later ones seed nothing
            if (window > 1 .and. self%markers(k)%chain == 0) s = 0
        end if
        associate (mk => self%markers(k))
            if (mk%chain > 0) then
                l = 0
                if (present(window)) l = (window - 1) * window_columns
                call chain_state_dual(self, k, q, v, seed, first, iq, iv, l, m, p, n)
                return
            end if
            p(1:4) = 0.0_wp
            if (b == 0) then
                x = mk%position
                a = mk%axes
                call ground_marker_state_d(x, a, m)
                return
            end if
            if (b < 0) then
                ! a point: x = q_node (or the set's centroid), ẋ = v_node;
                ! every seed space is (x, y, z)
                block
                    real(wp) :: xp(3), xdp(3)
                    call point_motion(self, k, q, v, xp, xdp)
                    x = xp
                    rd = xdp
                end block
                a = mk%axes
                select case (s)
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
                    x%der(first) = rd%val
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
            select case (s)
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
    end procedure marker_state_dual

    !> Dual velocity-space Jacobians of marker k from its dual quaternion p.
    module procedure marker_jacobian_dual
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
    end procedure marker_jacobian_dual

    !> Dual state of chain marker k: the chain's coordinates (and rates)
    !> seeded as for a body (T = I: velocity space = position space), columns
    !> c0 + 1 .. c0 + window_columns only (directions first, first + 1, ...);
    !> p(1:nq) the dual coordinates, p(nq + 1:nq + nv) the dual rates.
    module procedure chain_state_dual
        real(wp) :: tp(4, 3)
        integer :: c, l, nq, nv, b, jq, jv, nb
        c = self%markers(k)%chain
        nq = self%chains(c)%nq
        nv = self%chains(c)%nv
        p(1:nq) = q(iq + 1:iq + nq)
        p(nq + 1:nq + nv) = v(iv + 1:iv + nv)
        nb = max(0, min(window_columns, merge(nq, nv, seed == seed_position) - c0))
        n = nb
        if (seed == seed_rate) n = merge(1, 0, c0 == 0)
        select case (seed)
        case (seed_velocity_space, seed_rate)
            ! the tangents T e_l in the window (unit for single-coordinate
            ! joints, T(p) e_k for a spherical joint's quaternion), or the rate
            ! q' = T v in direction first (first window only)
            if (n > 0) then
                associate (g => self%chain_geom(c))
                    do b = 1, size(g%parent)
                        jq = g%iq(b)
                        jv = g%iv(b)
                        if (g%kinds(b) == chain_joint_spherical) then
                            tp = quat_rate_matrix(q(iq + jq + 1:iq + jq + 4))
                            if (seed == seed_rate) then
                                p(jq + 1:jq + 4)%der(first) = matmul(tp, v(iv + jv + 1:iv + jv + 3))
                                cycle
                            end if
                            do l = 1, 3
                                if (jv + l <= c0 .or. jv + l > c0 + nb) cycle
                                p(jq + 1:jq + 4)%der(first + jv + l - 1 - c0) = tp(:, l)
                            end do
                        else if (seed == seed_rate) then
                            p(jq + 1)%der(first) = v(iv + jv + 1)
                        else if (jv + 1 > c0 .and. jv + 1 <= c0 + nb) then
                            p(jq + 1)%der(first + jv - c0) = 1.0_wp
                        end if
                    end do
                end associate
            end if
        case (seed_position)
            do l = 1, nb
                p(c0 + l)%der(first + l - 1) = 1.0_wp
            end do
        case (seed_velocity)
            do l = 1, nb
                p(nq + c0 + l)%der(first + l - 1) = 1.0_wp
            end do
        end select
        associate (g => self%chain_geom(c))
            call chain_marker_state_d(g%parent, g%kinds, g%iq, g%iv, g%jpos, g%jrot, &
                    g%axis, &
                self%markers(k)%link, self%markers(k)%position, self%markers(k)%axes, &
                p(1:nq), p(nq + 1:nq + nv), m)
        end associate
    end procedure chain_state_dual

    !> q' = T(q) v of chain c (pure: the chain's own kinematics, inlined).
    module procedure chain_rates
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
    end procedure chain_rates

    !> Real Jacobians of chain marker k: velocity space by the formulas,
    !> position space (quaternion coordinates) by dual passes of dual_size
    !> columns each, in the pose duals p.
    module procedure chain_jacobian_real
        type(marker_state_d) :: m
        integer :: c, nq, nv, n, l, c0
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
        do c0 = 0, nq - 1, window_columns
            call chain_state_dual(self, k, q, self%zero_v, seed_position, 1, iq, 0, c0, m, p, n)
            do l = 1, 3
                jx(l, c0 + 1:c0 + n) = m%x(l)%der(1:n)
                ja(l, c0 + 1:c0 + n, 1) = m%a(l, 1)%der(1:n)
                ja(l, c0 + 1:c0 + n, 2) = m%a(l, 2)%der(1:n)
                ja(l, c0 + 1:c0 + n, 3) = m%a(l, 3)%der(1:n)
            end do
        end do
    end procedure chain_jacobian_real

    !> Driver values (s, s', s'') of joint k at t (zero for joints without s).
    module procedure joint_driver
        drv = driver_values(self%joints(k)%driver, t)
    end procedure joint_driver

    !> Dual driver values, with the time tangent in direction td (none if td = 0).
    module procedure driver_dual
        d = drv
        if (td > 0) then
            d(1)%der(td) = drv(2)
            d(2)%der(td) = drv(3)
        end if
    end procedure driver_dual

    !> out(row0 + rows, columns of marker k's body) += block (velocity or
    !> position space).
    !> A set marker's three columns (its centroid's x, y, z) go to each node
    !> of the set with weight 1/n.
    module procedure add_columns
        integer :: b, iq, iv, a, n, c0, r, l
        call marker_offsets(self, k, b, iq, iv)
        if (b == 0) return
        if (is_set_marker(self, k)) then
            n = size(self%markers(k)%nodes)
            do a = 1, n
                c0 = set_node_offset(self, k, a, position_space)
                do l = 1, size(block, 2)
                    do r = 1, size(block, 1)
                        call out%add(row0 + r, c0 + l, block(r, l) / n)
                    end do
                end do
            end do
            return
        end if
        call out%add_range(row0, merge(iq, iv, position_space), block)
    end procedure add_columns

    !> The dual pose of a marker with frame m: tangent d of x is jx(:, d), of
    !> axis k ja(:, d, k), in directions off + d (its motion is left unset).
    module procedure seeded_frame
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
    end procedure seeded_frame

    !> The jet pose of a marker along its motion at zero accelerations: x, ẋ
    !> and the convective acceleration, for the origin and the axes.
    module procedure moving_frame
        type(jet_t) :: x(3), a(3, 3)
        integer :: l, k
        do l = 1, 3
            x(l) = jet_t(m%x(l), m%xd(l), m%gx(l))
            do k = 1, 3
                a(l, k) = jet_t(m%a(l, k), m%ad(l, k), m%ga(l, k))
            end do
        end do
        call ground_marker_state_j(x, a, mj)
    end procedure moving_frame
end submodule flexmbs_mbs_system_markers
