!> Frames that follow a node set of a flexible body, so that joints of every
!> type can use a marker on a flexible body (flexible_marker.f90 defines the
!> frame; FE nodes carry no rotations).
!>
!> A node frame is a massless rigid body (r, p) held on the best rigid fit of
!> the set S (n nodes, weight w = 1/n, reference offsets s_a = X_a − X̄) by
!> six constraints, polynomial in (p, x) so that no SVD enters the equations:
!>
!>   c_pos = w Σ x_a − r                         (origin at the centroid)
!>   c_rot = w Σ (R s_a) × x_a = Σ_j R e_j × A e_j,   A = w Σ x_a s_aᵀ
!>
!> c_rot = R axial(RᵀA − AᵀR), so c_rot = 0 says RᵀA is symmetric: R is a
!> stationary point of tr(RᵀA), the Kabsch fit (its maximum near the start;
!> the frame starts on it). Markers on the frame body are then ordinary rigid
!> markers. The frame adds 7 coordinates, 6 velocities and 6 rows; its M is
!> zero, yet [M Gᵀ; G 0] stays regular (the frame's 6 velocity columns of G
!> are regular while tr(U) I − U, U = RᵀA, is: a non-collinear set).
!>
!> Hand-coded derivatives, y_a = R s_a, ω = R ω′, τ = tr(RᵀA):
!>   G v:  c_pos˙ = w Σ ẋ_a − ṙ,
!>         c_rot˙ = −(τ I − R Aᵀ) R ω′ + w Σ y_a × ẋ_a,
!>   c_p (position space) = −Σ_j [A e_j]× ∂(R e_j)/∂p,
!>   (G v)_q T v = (0, w Σ (ω × (ω × y_a)) × x_a + 2 (ω × y_a) × ẋ_a),  c_t = 0.
!> Second derivatives ∂(G w)/∂q, ∂(Gᵀλ)/∂q, ∂γ/∂q, ∂γ/∂v and, with
!> constraint_derivatives = 'ad', c_q, G and γ themselves, come from forward
!> AD of these forms, in passes of the body's directions plus three nodes.
!>
!> Local columns of a frame: position space (r, p, x_1, …, x_n), 7 + 3n;
!> velocity space (ṙ, ω′, ẋ_1, …, ẋ_n), 6 + 3n.
!>
!> A frame on an interface of a modal body (`modal` > 0) has the rows and
!> local columns of flexmbs_mbs_modal_frame instead, which every procedure
!> here hands it to, so that the system treats both kinds alike.
module flexmbs_mbs_node_frame
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_rotation, only: rotation_matrix, rotated_vector_jacobian, skew, cross, &
        quat_rate_matrix
    use flexmbs_mbs_dual, only: dual_t, dual_size, operator(+), operator(-), operator(*), &
        assignment(=), matmul
    use flexmbs_mbs_rotation_dual, only: rotation_matrix_d => rotation_matrix, &
        cross_d => cross
    use flexmbs_mbs_modal_frame, only: modal_interface_t, modal_frame_columns, &
        modal_frame_value, modal_frame_jacobian, modal_frame_curvature, &
        modal_frame_jacobian_ad, modal_frame_curvature_ad, modal_frame_rate_q, &
        modal_frame_gtl_q, modal_frame_curvature_qv
    implicit none
    private

    integer, parameter, public :: node_frame_rows = 6
    integer, parameter :: body_nq = 7, body_nv = 6
    !> nodes per AD pass: 7 body directions + 3 × 3 node directions ≤ dual_size
    integer, parameter :: pass_nodes = (dual_size - body_nq) / 3

    !> A frame held on a node set by six constraints (see the module), or on an
    !> interface of a modal body: its node set and the offsets the system gives it.
    type, public :: node_frame_t
        integer :: flexible = 0            !! flexible body number
        integer :: body = 0                !! the frame's (massless) rigid body
        integer, allocatable :: nodes(:)   !! mesh nodes of the set
        real(wp), allocatable :: s(:, :)   !! (3, n): X_a − X̄
        real(wp) :: weight = 0.0_wp        !! w = 1/n
        ! placed by the system:
        integer :: iq = 0, iv = 0          !! the frame body's offsets in q, v
        integer, allocatable :: nq(:), nv(:) !! node a's x offset in q, v
        integer :: row0 = 0                !! rows row0 + 1 .. row0 + 6
        !> an interface frame of a modal body (flexmbs_mbs_modal_frame) instead:
        !> the body's number and interface; placed by the system: the
        !> interface's data and the body's offsets in q and v. Its local
        !> columns are the frame body's, then the modal body's.
        integer :: modal = 0
        integer :: modal_interface = 0
        type(modal_interface_t) :: rigid_interface
        integer :: mq = 0, mv = 0
    end type node_frame_t

    interface transpose_times
        module procedure transpose_times_r, transpose_times_d
    end interface transpose_times

    public :: frame_columns, frame_value, frame_jacobian, frame_curvature, &
        frame_jacobian_ad, frame_curvature_ad, frame_rate_q, frame_gtl_q, &
        frame_curvature_qv

contains

    !> Number of local columns, position (7 + 3n) or velocity space (6 + 3n).
    pure integer function frame_columns(f, position_space) result(n)
        type(node_frame_t), intent(in) :: f
        logical, intent(in) :: position_space
        if (f%modal > 0) then
            n = modal_frame_columns(f%rigid_interface, position_space)
            return
        end if
        n = merge(body_nq, body_nv, position_space) + 3 * size(f%nodes)
    end function frame_columns

    !> A modal frame's local positions (the frame body's, the modal body's).
    pure function modal_positions(f, q) result(z)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        real(wp) :: z(frame_columns(f, .true.))
        z(1:body_nq) = q(f%iq + 1:f%iq + body_nq)
        z(body_nq + 1:) = q(f%mq + 1:f%mq + size(z) - body_nq)
    end function modal_positions

    !> A modal frame's local velocities.
    pure function modal_velocities(f, v) result(w)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: v(:)
        real(wp) :: w(frame_columns(f, .false.))
        w(1:body_nv) = v(f%iv + 1:f%iv + body_nv)
        w(body_nv + 1:) = v(f%mv + 1:f%mv + size(w) - body_nv)
    end function modal_velocities

    ! ------------------------------------------------ hand-coded (real)

    pure subroutine gather(f, q, r, p, x)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        real(wp), intent(out) :: r(3), p(4), x(:, :)
        integer :: a
        r = q(f%iq + 1:f%iq + 3)
        p = q(f%iq + 4:f%iq + 7)
        do a = 1, size(f%nodes)
            x(:, a) = q(f%nq(a) + 1:f%nq(a) + 3)
        end do
    end subroutine gather

    pure subroutine gather_rates(f, v, rd, wb, xd)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: v(:)
        real(wp), intent(out) :: rd(3), wb(3), xd(:, :)
        integer :: a
        rd = v(f%iv + 1:f%iv + 3)
        wb = v(f%iv + 4:f%iv + 6)
        do a = 1, size(f%nodes)
            xd(:, a) = v(f%nv(a) + 1:f%nv(a) + 3)
        end do
    end subroutine gather_rates

    !> c (6) at q.
    pure subroutine frame_value(f, q, c)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        real(wp), intent(out) :: c(node_frame_rows)
        real(wp) :: r(3), p(4), x(3, size(f%nodes)), rm(3, 3)
        integer :: a
        if (f%modal > 0) then
            call modal_frame_value(f%rigid_interface, modal_positions(f, q), c)
            return
        end if
        call gather(f, q, r, p, x)
        rm = rotation_matrix(p)
        c(1:3) = -r
        c(4:6) = 0.0_wp
        do a = 1, size(f%nodes)
            c(1:3) = c(1:3) + f%weight * x(:, a)
            c(4:6) = c(4:6) + f%weight * cross(matmul(rm, f%s(:, a)), x(:, a))
        end do
    end subroutine frame_value

    !> The local block (6, frame_columns) of G (velocity space) or c_q.
    pure subroutine frame_jacobian(f, q, position_space, block)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: block(:, :)
        real(wp) :: r(3), p(4), x(3, size(f%nodes)), rm(3, 3), am(3, 3), e(3)
        integer :: a, j, l, off
        if (f%modal > 0) then
            call modal_frame_jacobian(f%rigid_interface, modal_positions(f, q), position_space, &
                                      block)
            return
        end if
        call gather(f, q, r, p, x)
        rm = rotation_matrix(p)
        am = amat(f, x)
        block = 0.0_wp
        do l = 1, 3
            block(l, l) = -1.0_wp
        end do
        if (position_space) then
            do j = 1, 3
                e = 0.0_wp
                e(j) = 1.0_wp
                block(4:6, 4:7) = block(4:6, 4:7) &
                    - matmul(skew(am(:, j)), rotated_vector_jacobian(p, e))
            end do
        else
            block(4:6, 4:6) = -matmul(trace_form(rm, am), rm)
        end if
        off = merge(body_nq, body_nv, position_space)
        do a = 1, size(f%nodes)
            do l = 1, 3
                block(l, off + 3 * (a - 1) + l) = f%weight
            end do
            block(4:6, off + 3 * a - 2:off + 3 * a) = f%weight * skew(matmul(rm, f%s(:, a)))
        end do
    end subroutine frame_jacobian

    !> γ = (G v)_q T v (6); c_t = 0.
    pure subroutine frame_curvature(f, q, v, gamma)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: gamma(node_frame_rows)
        real(wp) :: r(3), p(4), x(3, size(f%nodes)), rd(3), wb(3), xd(3, size(f%nodes)), &
            rm(3, 3), w(3), wy(3)
        integer :: a
        if (f%modal > 0) then
            call modal_frame_curvature(f%rigid_interface, modal_positions(f, q), &
                                       modal_velocities(f, v), gamma)
            return
        end if
        call gather(f, q, r, p, x)
        call gather_rates(f, v, rd, wb, xd)
        rm = rotation_matrix(p)
        w = matmul(rm, wb)
        gamma = 0.0_wp
        do a = 1, size(f%nodes)
            wy = cross(w, matmul(rm, f%s(:, a)))
            gamma(4:6) = gamma(4:6) + f%weight * (cross(cross(w, wy), x(:, a)) &
                                                  + 2.0_wp * cross(wy, xd(:, a)))
        end do
    end subroutine frame_curvature

    !> A = w Σ x_a s_aᵀ.
    pure function amat(f, x) result(am)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: x(:, :)
        real(wp) :: am(3, 3)
        integer :: a, j
        am = 0.0_wp
        do a = 1, size(f%nodes)
            do j = 1, 3
                am(:, j) = am(:, j) + f%weight * f%s(j, a) * x(:, a)
            end do
        end do
    end function amat

    !> τ I − R Aᵀ, τ = tr(RᵀA).
    pure function trace_form(rm, am) result(k)
        real(wp), intent(in) :: rm(3, 3), am(3, 3)
        real(wp) :: k(3, 3)
        integer :: l
        k = -matmul(rm, transpose(am))
        do l = 1, 3
            k(l, l) = k(l, l) + sum(rm * am)
        end do
    end function trace_form

    ! ------------------------------------------------ the same forms on dual numbers

    ! Every form below is affine in x and ẋ at fixed p and ω′: a pass that
    ! seeds only nodes lo..hi (not the body) needs their terms alone, which
    ! makes the passes of a set of n nodes O(n), not O(n²). Their values are
    ! then partial; only the derivatives are used.

    !> c (6), the terms of nodes lo..hi.
    pure function value_d(f, r, p, x, lo, hi) result(c)
        type(node_frame_t), intent(in) :: f
        type(dual_t), intent(in) :: r(3), p(4), x(:, :)
        integer, intent(in) :: lo, hi
        type(dual_t) :: c(node_frame_rows), rm(3, 3)
        integer :: a
        rm = rotation_matrix_d(p)
        c(1:3) = -r
        c(4:6) = 0.0_wp
        do a = lo, hi
            c(1:3) = c(1:3) + f%weight * x(:, a)
            c(4:6) = c(4:6) + f%weight * cross_d(matmul(rm, f%s(:, a)), x(:, a))
        end do
    end function value_d

    !> The hand-coded G v (6), the terms of nodes lo..hi.
    pure function rate_d(f, p, x, rd, wb, xd, lo, hi) result(c)
        type(node_frame_t), intent(in) :: f
        type(dual_t), intent(in) :: p(4), x(:, :), rd(3), wb(3), xd(:, :)
        integer, intent(in) :: lo, hi
        type(dual_t) :: c(node_frame_rows), rm(3, 3), w(3), y(3)
        integer :: a
        rm = rotation_matrix_d(p)
        w = matmul(rm, wb)
        c(1:3) = -rd
        c(4:6) = 0.0_wp
        do a = lo, hi
            y = matmul(rm, f%s(:, a))
            c(1:3) = c(1:3) + f%weight * xd(:, a)
            c(4:6) = c(4:6) + f%weight * (cross_d(cross_d(w, y), x(:, a)) + cross_d(y, xd(:, a)))
        end do
    end function rate_d

    !> The hand-coded γ (6), the terms of nodes lo..hi.
    pure function gamma_d(f, p, x, wb, xd, lo, hi) result(c)
        type(node_frame_t), intent(in) :: f
        type(dual_t), intent(in) :: p(4), x(:, :), wb(3), xd(:, :)
        integer, intent(in) :: lo, hi
        type(dual_t) :: c(node_frame_rows), rm(3, 3), w(3), wy(3)
        integer :: a
        rm = rotation_matrix_d(p)
        w = matmul(rm, wb)
        c = 0.0_wp
        do a = lo, hi
            wy = cross_d(w, matmul(rm, f%s(:, a)))
            c(4:6) = c(4:6) + f%weight * (cross_d(cross_d(w, wy), x(:, a)) &
                                          + 2.0_wp * cross_d(wy, xd(:, a)))
        end do
    end function gamma_d

    !> Gᵀλ (6 + 3n, velocity-space local order) from the hand-coded G, the
    !> terms of nodes lo..hi (the rows of the other nodes 0).
    pure function gtl_d(f, p, x, lam, lo, hi) result(g)
        type(node_frame_t), intent(in) :: f
        type(dual_t), intent(in) :: p(4), x(:, :)
        real(wp), intent(in) :: lam(node_frame_rows)
        integer, intent(in) :: lo, hi
        type(dual_t) :: g(body_nv + 3 * size(f%nodes)), rm(3, 3), am(3, 3), tau, y(3), &
            art(3), lrot(3)
        integer :: a, j
        rm = rotation_matrix_d(p)
        lrot = lam(4:6)
        do j = 1, 3
            am(:, j) = 0.0_wp
        end do
        g = 0.0_wp
        do a = lo, hi
            do j = 1, 3
                am(:, j) = am(:, j) + (f%weight * f%s(j, a)) * x(:, a)
            end do
        end do
        tau = 0.0_wp
        do j = 1, 3
            tau = tau + rm(1, j) * am(1, j) + rm(2, j) * am(2, j) + rm(3, j) * am(3, j)
        end do
        ! ω′ rows: −Rᵀ (τ λ_rot − A Rᵀ λ_rot)
        art = matmul(am, transpose_times(rm, lam(4:6)))
        g(1:3) = -lam(1:3)
        g(4:6) = -transpose_times(rm, tau * lam(4:6) - art)
        do a = lo, hi
            y = matmul(rm, f%s(:, a))
            g(body_nv + 3 * a - 2:body_nv + 3 * a) = f%weight * (lam(1:3) + cross_d(lrot, y))
        end do
    end function gtl_d

    !> Rᵀ u (u real).
    pure function transpose_times_r(rm, u) result(y)
        type(dual_t), intent(in) :: rm(3, 3)
        real(wp), intent(in) :: u(3)
        type(dual_t) :: y(3)
        integer :: j
        do j = 1, 3
            y(j) = rm(1, j) * u(1) + rm(2, j) * u(2) + rm(3, j) * u(3)
        end do
    end function transpose_times_r

    !> Rᵀ u (u dual).
    pure function transpose_times_d(rm, u) result(y)
        type(dual_t), intent(in) :: rm(3, 3), u(3)
        type(dual_t) :: y(3)
        integer :: j
        do j = 1, 3
            y(j) = rm(1, j) * u(1) + rm(2, j) * u(2) + rm(3, j) * u(3)
        end do
    end function transpose_times_d

    ! ------------------------------------------------ AD passes

    !> Passes of pass_nodes nodes each (the body's directions in the first).
    pure integer function passes(f)
        type(node_frame_t), intent(in) :: f
        passes = max(1, (size(f%nodes) + pass_nodes - 1) / pass_nodes)
    end function passes

    !> The nodes whose terms pass k needs: all in the first (it seeds the
    !> body), else its own.
    pure integer function first(k)
        integer, intent(in) :: k
        first = merge(1, (k - 1) * pass_nodes + 1, k == 1)
    end function first

    pure integer function last(f, k)
        type(node_frame_t), intent(in) :: f
        integer, intent(in) :: k
        last = merge(size(f%nodes), min(size(f%nodes), k * pass_nodes), k == 1)
    end function last

    !> Dual positions for pass k: seeds the body (first pass only) and the
    !> pass's nodes, in position space (unit vectors) or along the velocity
    !> space (T e_l: the quaternion's tangents for ω′); cols(d) is the local
    !> column of direction d, nd the directions used.
    pure subroutine seed_positions(f, q, k, position_space, r, p, x, cols, nd)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: k
        logical, intent(in) :: position_space
        type(dual_t), intent(out) :: r(3), p(4), x(:, :)
        integer, intent(out) :: cols(dual_size), nd
        real(wp) :: rr(3), pr(4), xr(3, size(f%nodes)), tp(4, 3)
        integer :: a, l, off
        call gather(f, q, rr, pr, xr)
        r = rr
        p = pr
        ! the nodes the pass's forms read (the others stay unset)
        do a = first(k), last(f, k)
            x(:, a) = xr(:, a)
        end do
        nd = 0
        if (k == 1) then
            do l = 1, 3
                nd = nd + 1
                r(l)%der(nd) = 1.0_wp
                cols(nd) = l
            end do
            if (position_space) then
                do l = 1, 4
                    nd = nd + 1
                    p(l)%der(nd) = 1.0_wp
                    cols(nd) = 3 + l
                end do
            else
                tp = quat_rate_matrix(pr)
                do l = 1, 3
                    nd = nd + 1
                    p(:)%der(nd) = tp(:, l)
                    cols(nd) = 3 + l
                end do
            end if
        end if
        off = merge(body_nq, body_nv, position_space)
        do a = (k - 1) * pass_nodes + 1, min(size(f%nodes), k * pass_nodes)
            do l = 1, 3
                nd = nd + 1
                x(l, a)%der(nd) = 1.0_wp
                cols(nd) = off + 3 * (a - 1) + l
            end do
        end do
    end subroutine seed_positions

    !> Dual velocities for pass k (ṙ, ω′ in the first pass, the pass's nodes).
    pure subroutine seed_velocities(f, v, k, rd, wb, xd, cols, nd)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: v(:)
        integer, intent(in) :: k
        type(dual_t), intent(out) :: rd(3), wb(3), xd(:, :)
        integer, intent(out) :: cols(dual_size), nd
        real(wp) :: rr(3), wr(3), xr(3, size(f%nodes))
        integer :: a, l
        call gather_rates(f, v, rr, wr, xr)
        rd = rr
        wb = wr
        do a = first(k), last(f, k)
            xd(:, a) = xr(:, a)
        end do
        nd = 0
        if (k == 1) then
            do l = 1, 3
                nd = nd + 1
                rd(l)%der(nd) = 1.0_wp
                cols(nd) = l
                wb(l)%der(nd + 3) = 1.0_wp
                cols(nd + 3) = 3 + l
            end do
            nd = 6
        end if
        do a = (k - 1) * pass_nodes + 1, min(size(f%nodes), k * pass_nodes)
            do l = 1, 3
                nd = nd + 1
                xd(l, a)%der(nd) = 1.0_wp
                cols(nd) = body_nv + 3 * (a - 1) + l
            end do
        end do
    end subroutine seed_velocities

    !> block(i, cols(d)) = tangent d of y(i).
    pure subroutine scatter(y, cols, nd, block)
        type(dual_t), intent(in) :: y(:)
        integer, intent(in) :: cols(:), nd
        real(wp), intent(inout) :: block(:, :)
        integer :: i, d
        do d = 1, nd
            do i = 1, size(y)
                block(i, cols(d)) = y(i)%der(d)
            end do
        end do
    end subroutine scatter

    !> G or c_q by AD of c.
    pure subroutine frame_jacobian_ad(f, q, position_space, block)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: block(:, :)
        type(dual_t) :: r(3), p(4), x(3, size(f%nodes))
        integer :: k, cols(dual_size), nd
        if (f%modal > 0) then
            call modal_frame_jacobian_ad(f%rigid_interface, modal_positions(f, q), &
                                         position_space, block)
            return
        end if
        block = 0.0_wp
        do k = 1, passes(f)
            call seed_positions(f, q, k, position_space, r, p, x, cols, nd)
            call scatter(value_d(f, r, p, x, first(k), last(f, k)), cols, nd, block)
        end do
    end subroutine frame_jacobian_ad

    !> γ by AD of the hand-coded G v along q' = T v.
    pure subroutine frame_curvature_ad(f, q, v, gamma)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: gamma(node_frame_rows)
        type(dual_t) :: p(4), x(3, size(f%nodes)), rd(3), wb(3), xd(3, size(f%nodes)), &
            c(node_frame_rows)
        real(wp) :: rr(3), pr(4), xr(3, size(f%nodes)), rdr(3), wr(3), xdr(3, size(f%nodes))
        integer :: a, i
        if (f%modal > 0) then
            call modal_frame_curvature_ad(f%rigid_interface, modal_positions(f, q), &
                                          modal_velocities(f, v), gamma)
            return
        end if
        call gather(f, q, rr, pr, xr)
        call gather_rates(f, v, rdr, wr, xdr)
        p = pr
        p(:)%der(1) = matmul(quat_rate_matrix(pr), wr)
        rd = rdr
        wb = wr
        do a = 1, size(f%nodes)
            x(:, a) = xr(:, a)
            x(:, a)%der(1) = xdr(:, a)
            xd(:, a) = xdr(:, a)
        end do
        c = rate_d(f, p, x, rd, wb, xd, 1, size(f%nodes))
        do i = 1, node_frame_rows
            gamma(i) = c(i)%der(1)
        end do
    end subroutine frame_curvature_ad

    !> ∂(G w)/∂q, (6, 7 + 3n).
    pure subroutine frame_rate_q(f, q, w, block)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:), w(:)
        real(wp), intent(out) :: block(:, :)
        type(dual_t) :: r(3), p(4), x(3, size(f%nodes)), rd(3), wb(3), xd(3, size(f%nodes))
        real(wp) :: rdr(3), wr(3), xdr(3, size(f%nodes))
        integer :: k, a, cols(dual_size), nd
        if (f%modal > 0) then
            call modal_frame_rate_q(f%rigid_interface, modal_positions(f, q), &
                                    modal_velocities(f, w), block)
            return
        end if
        call gather_rates(f, w, rdr, wr, xdr)
        rd = rdr
        wb = wr
        do a = 1, size(f%nodes)
            xd(:, a) = xdr(:, a)
        end do
        block = 0.0_wp
        do k = 1, passes(f)
            call seed_positions(f, q, k, .true., r, p, x, cols, nd)
            call scatter(rate_d(f, p, x, rd, wb, xd, first(k), last(f, k)), cols, nd, &
                         block)
        end do
    end subroutine frame_rate_q

    !> ∂(Gᵀλ)/∂q, (6 + 3n, 7 + 3n), λ the frame's 6 multipliers.
    pure subroutine frame_gtl_q(f, q, lam, block)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:), lam(node_frame_rows)
        real(wp), intent(out) :: block(:, :)
        type(dual_t) :: r(3), p(4), x(3, size(f%nodes))
        integer :: k, cols(dual_size), nd
        if (f%modal > 0) then
            call modal_frame_gtl_q(f%rigid_interface, modal_positions(f, q), lam, block)
            return
        end if
        block = 0.0_wp
        do k = 1, passes(f)
            call seed_positions(f, q, k, .true., r, p, x, cols, nd)
            call scatter(gtl_d(f, p, x, lam, first(k), last(f, k)), cols, nd, block)
        end do
    end subroutine frame_gtl_q

    !> ∂γ/∂q (6, 7 + 3n) and ∂γ/∂v (6, 6 + 3n).
    pure subroutine frame_curvature_qv(f, q, v, gq, gv)
        type(node_frame_t), intent(in) :: f
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: gq(:, :), gv(:, :)
        type(dual_t) :: r(3), p(4), x(3, size(f%nodes)), rd(3), wb(3), xd(3, size(f%nodes))
        real(wp) :: rr(3), pr(4), xr(3, size(f%nodes)), rdr(3), wr(3), xdr(3, size(f%nodes))
        integer :: k, a, cols(dual_size), nd
        if (f%modal > 0) then
            call modal_frame_curvature_qv(f%rigid_interface, modal_positions(f, q), &
                                          modal_velocities(f, v), gq, gv)
            return
        end if
        call gather(f, q, rr, pr, xr)
        call gather_rates(f, v, rdr, wr, xdr)
        gq = 0.0_wp
        gv = 0.0_wp
        wb = wr
        do a = 1, size(f%nodes)
            xd(:, a) = xdr(:, a)
        end do
        do k = 1, passes(f)
            call seed_positions(f, q, k, .true., r, p, x, cols, nd)
            call scatter(gamma_d(f, p, x, wb, xd, first(k), last(f, k)), cols, nd, gq)
        end do
        p = pr
        do a = 1, size(f%nodes)
            x(:, a) = xr(:, a)
        end do
        do k = 1, passes(f)
            call seed_velocities(f, v, k, rd, wb, xd, cols, nd)
            call scatter(gamma_d(f, p, x, wb, xd, first(k), last(f, k)), cols, nd, gv)
        end do
    end subroutine frame_curvature_qv
end module flexmbs_mbs_node_frame
