!> Frames on the interfaces of modal bodies, so that joints of every type
!> reach a modal body (docs/theory.md §2.7). Like a node frame on a
!> nonlinear body, an interface frame is a massless rigid body (r_f, p_f)
!> held on the interface by six rows; markers on it are ordinary rigid
!> markers. The interface of a modal body (r, p, η) is rigid: its centroid
!> is at r + A u, u = d + U η, and it is turned by the small rotation θ =
!> Θ η (flexmbs_fe_modal_basis). The rows, polynomial in the quaternions
!> and linear in η like the node frame's,
!>
!>   c_pos = r + A u − r_f,
!>   c_rot = Σ_i (R e_i) × (T e_i),   R = A(p_f),  T = A (I + θ̃),
!>
!> put the origin on the centroid and say that Rᵀ T is symmetric: R is the
!> rotation nearest to T, A R(θ) to second order in θ (the order of the
!> linear model). The frame's mass is zero; [M Gᵀ; G 0] stays regular
!> since c_rot's block of ω_f′, −(τ I − R Tᵀ) R with τ = tr(RᵀT), is (τ ≈ 3).
!>
!> Local columns: position space (r_f, p_f, r, p, η), 14 + n; velocity
!> space (ṙ_f, ω_f′, ṙ, ω′, η̇), 12 + n. c, G, c_q and γ are hand-coded
!> (modal_frame.inc); with constraint_derivatives = 'ad' c_q, G and γ are
!> AD of c and of the hand-coded G v; the second derivatives ∂(G w)/∂q,
!> ∂(Gᵀλ)/∂q, ∂γ/∂q and ∂γ/∂v are AD of the hand-coded forms along the
!> frame's and the body's poses (one pass of 14 or 12 directions), and
!> hand-coded along η and η̇, where the forms are affine (each η_k, η̇_k
!> enters through u_k = U e_k and d_i = Θ e_k × e_i only): a body of many
!> modes costs no AD pass per 16 of them.
module flexmbs_mbs_modal_frame
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_rotation, only: quat_rate_matrix, rotation_matrix, cross
    use flexmbs_mbs_dual, only: dual_t, dual_size, assignment(=), matmul
    use flexmbs_mbs_modal_frame_forms, only: modal_interface_t, modal_frame_rows, &
        modal_frame_velocity_jacobian, modal_frame_position_jacobian, &
        modal_frame_curvature_rows
    use flexmbs_mbs_modal_frame_forms_dual, only: rows_d => modal_frame_rows, &
        velocity_jacobian_d => modal_frame_velocity_jacobian, &
        curvature_d => modal_frame_curvature_rows
    implicit none
    private

    public :: modal_interface_t
    public :: modal_frame_columns, modal_frame_value, modal_frame_jacobian, &
        modal_frame_curvature, modal_frame_jacobian_ad, modal_frame_curvature_ad, &
        modal_frame_rate_q, modal_frame_gtl_q, modal_frame_curvature_qv

    integer, parameter :: frame_nq = 14, frame_nv = 12

contains

    !> Local columns: position space 14 + n, velocity space 12 + n.
    pure integer function modal_frame_columns(m, position_space) result(n)
        type(modal_interface_t), intent(in) :: m
        logical, intent(in) :: position_space
        n = merge(frame_nq, frame_nv, position_space) + size(m%translation, 2)
    end function modal_frame_columns

    !> c (6) at the local positions z = (r_f, p_f, r, p, η).
    pure subroutine modal_frame_value(m, z, c)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:)
        real(wp), intent(out) :: c(6)
        c = modal_frame_rows(m, z(1:3), z(4:7), z(8:10), z(11:14), z(15:))
    end subroutine modal_frame_value

    !> G (velocity space) or c_q (position space), hand-coded.
    pure subroutine modal_frame_jacobian(m, z, position_space, block)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: block(:, :)
        if (position_space) then
            block = modal_frame_position_jacobian(m, z(4:7), z(11:14), z(15:))
        else
            block = modal_frame_velocity_jacobian(m, z(4:7), z(11:14), z(15:))
        end if
    end subroutine modal_frame_jacobian

    !> γ (6) at positions z and velocities w = (ṙ_f, ω_f′, ṙ, ω′, η̇).
    pure subroutine modal_frame_curvature(m, z, w, gamma)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), w(:)
        real(wp), intent(out) :: gamma(6)
        gamma = modal_frame_curvature_rows(m, z(4:7), z(11:14), z(15:), w(1:6), w(7:))
    end subroutine modal_frame_curvature

    ! ------------------------------------------------ AD passes

    !> Dual positions with the batch of local columns lo..hi seeded, hi =
    !> min(n, lo + dual_size − 1) of n columns: unit directions in position
    !> space; in velocity space the directions T e_l (a quaternion's tangents
    !> for ω_f′ and ω′).
    pure subroutine seed_positions(z, lo, n, position_space, zd, hi)
        real(wp), intent(in) :: z(:)
        integer, intent(in) :: lo, n
        logical, intent(in) :: position_space
        type(dual_t), intent(out) :: zd(:)
        integer, intent(out) :: hi
        real(wp) :: tf(4, 3), tm(4, 3)
        integer :: c, d
        hi = min(n, lo + dual_size - 1)
        zd = z
        tf = quat_rate_matrix(z(4:7))
        tm = quat_rate_matrix(z(11:14))
        do c = lo, hi
            d = c - lo + 1
            if (position_space) then
                zd(c)%der(d) = 1.0_wp
            else if (c <= 3) then
                zd(c)%der(d) = 1.0_wp
            else if (c <= 6) then
                zd(4:7)%der(d) = tf(:, c - 3)
            else if (c <= 9) then
                zd(c + 1)%der(d) = 1.0_wp
            else if (c <= 12) then
                zd(11:14)%der(d) = tm(:, c - 9)
            else
                zd(c + 2)%der(d) = 1.0_wp
            end if
        end do
    end subroutine seed_positions

    !> block(:, lo + d − 1) = tangent d of y.
    pure subroutine scatter(y, lo, hi, block)
        type(dual_t), intent(in) :: y(:)
        integer, intent(in) :: lo, hi
        real(wp), intent(inout) :: block(:, :)
        integer :: i, c
        do c = lo, hi
            do i = 1, size(y)
                block(i, c) = y(i)%der(c - lo + 1)
            end do
        end do
    end subroutine scatter

    !> G or c_q by AD of c.
    pure subroutine modal_frame_jacobian_ad(m, z, position_space, block)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:)
        logical, intent(in) :: position_space
        real(wp), intent(out) :: block(:, :)
        type(dual_t) :: zd(size(z))
        integer :: lo, hi
        block = 0.0_wp
        do lo = 1, size(block, 2), dual_size
            call seed_positions(z, lo, size(block, 2), position_space, zd, hi)
            call scatter(rows_d(m, zd(1:3), zd(4:7), zd(8:10), zd(11:14), zd(15:)), lo, hi, &
                         block)
        end do
    end subroutine modal_frame_jacobian_ad

    !> q' = T w of the local positions (the frame's and the body's).
    pure function local_rates(z, w) result(zdot)
        real(wp), intent(in) :: z(:), w(:)
        real(wp) :: zdot(size(z))
        zdot(1:3) = w(1:3)
        zdot(4:7) = matmul(quat_rate_matrix(z(4:7)), w(4:6))
        zdot(8:10) = w(7:9)
        zdot(11:14) = matmul(quat_rate_matrix(z(11:14)), w(10:12))
        zdot(15:) = w(13:)
    end function local_rates

    !> γ by AD of the hand-coded G w along q' = T w.
    pure subroutine modal_frame_curvature_ad(m, z, w, gamma)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), w(:)
        real(wp), intent(out) :: gamma(6)
        type(dual_t) :: zd(size(z)), c(6)
        real(wp) :: zdot(size(z))
        integer :: i
        zd = z
        zdot = local_rates(z, w)
        do i = 1, size(z)
            zd(i)%der(1) = zdot(i)
        end do
        c = matmul(velocity_jacobian_d(m, zd(4:7), zd(11:14), zd(15:)), w)
        do i = 1, 6
            gamma(i) = c(i)%der(1)
        end do
    end subroutine modal_frame_curvature_ad

    !> ∂(G w)/∂q, (6, 14 + n).
    pure subroutine modal_frame_rate_q(m, z, w, block)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), w(:)
        real(wp), intent(out) :: block(:, :)
        call position_tangents(m, z, w, .false., block)
        call eta_columns(m, z, w, rate=block(:, frame_nq + 1:))
    end subroutine modal_frame_rate_q

    !> ∂(Gᵀλ)/∂q, (12 + n, 14 + n), λ the frame's six multipliers.
    pure subroutine modal_frame_gtl_q(m, z, lam, block)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), lam(6)
        real(wp), intent(out) :: block(:, :)
        call position_tangents(m, z, lam, .true., block)
        call eta_columns(m, z, lam=lam, gtl=block(:, frame_nq + 1:))
    end subroutine modal_frame_gtl_q

    !> The frame_nq position columns of ∂(G x)/∂q, or of ∂(Gᵀx)/∂q when
    !> `transposed`, by AD of G in batches of position seeds; the η columns
    !> are left zero (eta_columns).
    pure subroutine position_tangents(m, z, x, transposed, block)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), x(:)
        logical, intent(in) :: transposed
        real(wp), intent(out) :: block(:, :)
        type(dual_t) :: zd(size(z))
        integer :: lo, hi
        block = 0.0_wp
        do lo = 1, frame_nq, dual_size
            call seed_positions(z, lo, frame_nq, .true., zd, hi)
            if (transposed) then
                call scatter(matmul(transpose(velocity_jacobian_d(m, zd(4:7), zd(11:14), &
                                                                  zd(15:))), x), lo, hi, block)
            else
                call scatter(matmul(velocity_jacobian_d(m, zd(4:7), zd(11:14), zd(15:)), x), &
                             lo, hi, block)
            end if
        end do
    end subroutine position_tangents

    !> ∂γ/∂q (6, 14 + n) and ∂γ/∂v (6, 12 + n).
    pure subroutine modal_frame_curvature_qv(m, z, w, gq, gv)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:), w(:)
        real(wp), intent(out) :: gq(:, :), gv(:, :)
        type(dual_t) :: zd(size(z)), wd(size(w))
        integer :: lo, hi, c
        gq = 0.0_wp
        gv = 0.0_wp
        wd = w
        do lo = 1, frame_nq, dual_size
            call seed_positions(z, lo, frame_nq, .true., zd, hi)
            call scatter(curvature_d(m, zd(4:7), zd(11:14), zd(15:), wd(1:6), wd(7:)), lo, hi, &
                         gq)
        end do
        call eta_columns(m, z, w, gamma_q=gq(:, frame_nq + 1:), gamma_v=gv(:, frame_nv + 1:))
        zd = z
        do lo = 1, frame_nv, dual_size
            hi = min(frame_nv, lo + dual_size - 1)
            wd = w
            do c = lo, hi
                wd(c)%der(c - lo + 1) = 1.0_wp
            end do
            call scatter(curvature_d(m, zd(4:7), zd(11:14), zd(15:), wd(1:6), wd(7:)), lo, hi, &
                         gv)
        end do
    end subroutine modal_frame_curvature_qv

    !> The η (and η̇) columns of ∂(G w)/∂q (rate), ∂(Gᵀλ)/∂q (gtl), ∂γ/∂q
    !> (gamma_q) and ∂γ/∂v (gamma_v), hand-coded (the forms of
    !> modal_frame.inc): η_k moves u by u_k = U e_k and s_i = (I + θ̃) e_i by
    !> d_i = θ_k × e_i, θ_k = Θ e_k; G's ω_f′ column l has Σ_i R (e_l × e_i)
    !> × A s_i, its ω′ column l (A (e_l × u), Σ_i y_i × A (e_l × s_i)); its
    !> η̇ columns do not depend on η; γ of modal_frame_curvature_rows.
    pure subroutine eta_columns(m, z, w, lam, rate, gtl, gamma_q, gamma_v)
        type(modal_interface_t), intent(in) :: m
        real(wp), intent(in) :: z(:)
        real(wp), intent(in), optional :: w(:), lam(6)
        real(wp), intent(out), optional :: rate(:, :), gtl(:, :), gamma_q(:, :), gamma_v(:, :)
        real(wp) :: rm(3, 3), am(3, 3), th(3), thd(3), wf(3), wm(3), e(3, 3), d(3), s(3), &
            uk(3), tk(3), yd(3), ydd(3), a(3), b(3)
        integer :: k, i, l
        rm = rotation_matrix(z(4:7))
        am = rotation_matrix(z(11:14))
        th = matmul(m%rotation, z(15:))
        e = 0.0_wp
        do i = 1, 3
            e(i, i) = 1.0_wp
        end do
        if (present(w)) then
            wf = w(4:6)
            wm = w(10:12)
            thd = matmul(m%rotation, w(13:))
        end if
        if (present(gtl)) gtl = 0.0_wp
        do k = 1, size(m%translation, 2)
            uk = m%translation(:, k)
            tk = m%rotation(:, k)
            if (present(rate)) then
                rate(1:3, k) = matmul(am, cross(wm, uk))
                rate(4:6, k) = 0.0_wp
            end if
            if (present(gamma_q)) then
                gamma_q(1:3, k) = matmul(am, cross(wm, cross(wm, uk)))
                gamma_q(4:6, k) = 0.0_wp
            end if
            if (present(gamma_v)) then
                gamma_v(1:3, k) = 2.0_wp * matmul(am, cross(wm, uk))
                gamma_v(4:6, k) = 0.0_wp
            end if
            if (present(gtl)) then
                ! ω′ columns of ∂G/∂η_k: position rows A (e_l × u_k)
                do l = 1, 3
                    gtl(9 + l, k) = dot_product(lam(1:3), matmul(am, cross(e(:, l), uk)))
                end do
            end if
            do i = 1, 3
                d = cross(tk, e(:, i))
                if (present(rate)) rate(4:6, k) = rate(4:6, k) &
                    + cross(matmul(rm, cross(wf, e(:, i))), matmul(am, d)) &
                    + cross(rm(:, i), matmul(am, cross(wm, d)))
                if (present(gtl)) then
                    do l = 1, 3
                        gtl(3 + l, k) = gtl(3 + l, k) + dot_product(lam(4:6), &
                            cross(matmul(rm, cross(e(:, l), e(:, i))), matmul(am, d)))
                        gtl(9 + l, k) = gtl(9 + l, k) + dot_product(lam(4:6), &
                            cross(rm(:, i), matmul(am, cross(e(:, l), d))))
                    end do
                end if
                if (present(gamma_q) .or. present(gamma_v)) then
                    s = e(:, i) + cross(th, e(:, i))
                    yd = matmul(rm, cross(wf, e(:, i)))
                    ydd = matmul(rm, cross(wf, cross(wf, e(:, i))))
                end if
                if (present(gamma_q)) gamma_q(4:6, k) = gamma_q(4:6, k) &
                    + cross(ydd, matmul(am, d)) + 2.0_wp * cross(yd, matmul(am, cross(wm, d))) &
                    + cross(rm(:, i), matmul(am, cross(wm, cross(wm, d))))
                if (present(gamma_v)) then
                    a = matmul(am, d)
                    b = matmul(am, 2.0_wp * cross(wm, d))
                    gamma_v(4:6, k) = gamma_v(4:6, k) + 2.0_wp * cross(yd, a) + cross(rm(:, i), b)
                end if
            end do
        end do
    end subroutine eta_columns
end module flexmbs_mbs_modal_frame
