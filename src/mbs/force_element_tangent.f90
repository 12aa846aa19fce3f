!> The force elements' laws (flexmbs_mbs_force_element) in real numbers,
!> with their hand-coded directional derivatives: given the marker frames
!> (origin x, axes a, origin velocity ẋ, angular velocity ω, all global)
!> and a tangent of each (δx, δa, δẋ, δω: the change of each per unit of a
!> coordinate or rate of the bodies), the wrench w = (F_i, n_i, F_j, n_j)
!> and its change δw. flexmbs_mbs_system maps both through the markers'
!> Jacobians ('analytic' derivatives); the dual-number laws, which give the
!> same by AD, check them (test force_elements).
!>
!> Spring–damper, r = x_j − x_i, ℓ = |r|, u = r/ℓ, Δ = ẋ_j − ẋ_i:
!>   δℓ = u·δr, δu = (δr − u δℓ)/ℓ, δℓ' = δu·Δ + u·δΔ,
!>   δF_i = (f'(ℓ − ℓ₀) δℓ + c δℓ') u + f δu,  δF_j = −δF_i.
!> Rotational, φ = atan2(y, x) with y = (a₁ × b₁)·a₃, x = a₁·b₁ (a: axes
!> of marker i, b: of j), Ω = ω_j − ω_i:
!>   δφ = (x δy − y δx)/(x² + y²),  δτ = −k δφ − c (δΩ·a₃ + Ω·δa₃),
!>   δn_j = δτ a₃ + τ δa₃,  δn_i = −δn_j.
!> Bushing, s = (Aᵀr, vee(AᵀB)), s' = (Aᵀ(Δ − ω_i × r), AᵀΩ), g = −K s − C s':
!>   δs and δs' by the product rule, δg = −K δs − C δs',
!>   δF_j = δA g₁ + A δg₁, δn_j = δA g₂ + A δg₂, δF_i = −δF_j,
!>   δn_i = −δn_j − δr × F_j − r × δF_j.
!> Applied load in the marker's axes: δF = δA (s F₀), δn = δA (s n₀).
module flexmbs_mbs_force_element_tangent
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_user_function
    use flexmbs_core_text, only: real_text
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_mbs_driver, only: driver_values
    use flexmbs_mbs_force_element, only: force_element_t, force_spring_damper, &
        force_rotational, force_bushing, force_applied, max_spring_order, min_relative_length
    implicit none
    private

    real(wp), parameter :: two_pi = 6.283185307179586_wp

    !> A marker's frame and motion (global), or a tangent of them.
    type, public :: frame_t
        real(wp) :: x(3) = 0.0_wp
        real(wp) :: a(3, 3) = 0.0_wp
        real(wp) :: xd(3) = 0.0_wp
        real(wp) :: w(3) = 0.0_wp
    end type frame_t

    public :: element_wrench_real, element_wrench_tangent

contains

    !> w = (F_i, n_i, F_j, n_j) at time t (forces global, torques global
    !> about the marker origins); for a load, F_j = n_j = 0.
    pure subroutine element_wrench_real(e, t, fi, fj, w, status)
        type(force_element_t), intent(in) :: e
        real(wp), intent(in) :: t
        type(frame_t), intent(in) :: fi, fj
        real(wp), intent(out) :: w(12)
        type(status_t), intent(inout) :: status
        type(frame_t) :: zero
        real(wp) :: dw(12)
        call element_wrench_tangent(e, t, fi, fj, zero, zero, w, dw, status)
    end subroutine element_wrench_real

    !> w and its change dw along the tangents di of marker i's frame and dj
    !> of marker j's (dj unused by a load).
    pure subroutine element_wrench_tangent(e, t, fi, fj, di, dj, w, dw, status)
        type(force_element_t), intent(in) :: e
        real(wp), intent(in) :: t
        type(frame_t), intent(in) :: fi, fj, di, dj
        real(wp), intent(out) :: w(12), dw(12)
        type(status_t), intent(inout) :: status
        real(wp) :: s(3)
        w = 0.0_wp
        dw = 0.0_wp
        select case (e%kind)
        case (force_spring_damper)
            call spring_damper(e, fi, fj, di, dj, w, dw, status)
        case (force_rotational)
            call rotational(e, fi, fj, di, dj, w, dw)
        case (force_bushing)
            call bushing(e, fi, fj, di, dj, w, dw)
        case (force_applied)
            s = driver_values(e%driver, t)
            if (e%world_frame) then
                w(1:3) = s(1) * e%force
                w(4:6) = s(1) * e%torque
            else
                w(1:3) = matmul(fi%a, s(1) * e%force)
                w(4:6) = matmul(fi%a, s(1) * e%torque)
                dw(1:3) = matmul(di%a, s(1) * e%force)
                dw(4:6) = matmul(di%a, s(1) * e%torque)
            end if
        end select
    end subroutine element_wrench_tangent

    pure subroutine spring_damper(e, fi, fj, di, dj, w, dw, status)
        type(force_element_t), intent(in) :: e
        type(frame_t), intent(in) :: fi, fj, di, dj
        real(wp), intent(inout) :: w(12), dw(12)
        type(status_t), intent(inout) :: status
        real(wp) :: r(3), u(3), du(3), dr(3), delta(3), l, ld, stretch, f, fp, dl, dld, df
        integer :: m
        r = fj%x - fi%x
        l = norm2(r)
        if (l < min_relative_length * max(e%reference, 1.0_wp)) then
            call status%set(status_solver_failure, 'spring_damper: the markers are ' // &
                real_text(l) // ' m apart: the line of the force is undefined (a bushing &
                &takes coinciding markers)', reason_user_function)
            return
        end if
        u = r / l
        delta = fj%xd - fi%xd
        ld = dot_product(u, delta)
        stretch = l - e%reference
        f = e%damping * ld
        fp = 0.0_wp
        do m = 1, max_spring_order
            if (abs(e%stiffness(m)) == 0.0_wp) cycle
            f = f + e%stiffness(m) * stretch**m
            fp = fp + m * e%stiffness(m) * stretch**(m - 1)
        end do
        w(1:3) = f * u
        w(7:9) = -w(1:3)
        dr = dj%x - di%x
        dl = dot_product(u, dr)
        du = (dr - u * dl) / l
        dld = dot_product(du, delta) + dot_product(u, dj%xd - di%xd)
        df = fp * dl + e%damping * dld
        dw(1:3) = df * u + f * du
        dw(7:9) = -dw(1:3)
    end subroutine spring_damper

    pure subroutine rotational(e, fi, fj, di, dj, w, dw)
        type(force_element_t), intent(in) :: e
        type(frame_t), intent(in) :: fi, fj, di, dj
        real(wp), intent(inout) :: w(12), dw(12)
        real(wp) :: c(3), y, x, dy, dx, phi, dphi, omega(3), tau, dtau
        associate (a1 => fi%a(:, 1), a3 => fi%a(:, 3), b1 => fj%a(:, 1))
            c = cross(a1, b1)
            y = dot_product(c, a3)
            x = dot_product(a1, b1)
            dy = dot_product(cross(di%a(:, 1), b1) + cross(a1, dj%a(:, 1)), a3) + &
                 dot_product(c, di%a(:, 3))
            dx = dot_product(di%a(:, 1), b1) + dot_product(a1, dj%a(:, 1))
            phi = atan2(y, x) - e%reference
            phi = phi - two_pi * anint(phi / two_pi)
            dphi = (x * dy - y * dx) / (x**2 + y**2)
            omega = fj%w - fi%w
            tau = -e%stiffness(1) * phi - e%damping * dot_product(omega, a3)
            dtau = -e%stiffness(1) * dphi - e%damping * (dot_product(dj%w - di%w, a3) + &
                                                         dot_product(omega, di%a(:, 3)))
            w(10:12) = tau * a3
            w(4:6) = -w(10:12)
            dw(10:12) = dtau * a3 + tau * di%a(:, 3)
            dw(4:6) = -dw(10:12)
        end associate
    end subroutine rotational

    pure subroutine bushing(e, fi, fj, di, dj, w, dw)
        type(force_element_t), intent(in) :: e
        type(frame_t), intent(in) :: fi, fj, di, dj
        real(wp), intent(inout) :: w(12), dw(12)
        real(wp) :: r(3), dr(3), wrel(3), dwrel(3), omega(3), domega(3), s(6), ds(6), &
            sd(6), dsd(6), g(6), dg(6)
        associate (a => fi%a, da => di%a)
            r = fj%x - fi%x
            dr = dj%x - di%x
            wrel = fj%xd - fi%xd - cross(fi%w, r)
            dwrel = dj%xd - di%xd - cross(di%w, r) - cross(fi%w, dr)
            omega = fj%w - fi%w
            domega = dj%w - di%w
            s(1:3) = matmul(transpose(a), r)
            ds(1:3) = matmul(transpose(da), r) + matmul(transpose(a), dr)
            s(4:6) = vee(matmul(transpose(a), fj%a))
            ds(4:6) = vee(matmul(transpose(da), fj%a) + matmul(transpose(a), dj%a))
            sd(1:3) = matmul(transpose(a), wrel)
            dsd(1:3) = matmul(transpose(da), wrel) + matmul(transpose(a), dwrel)
            sd(4:6) = matmul(transpose(a), omega)
            dsd(4:6) = matmul(transpose(da), omega) + matmul(transpose(a), domega)
            g = -(matmul(e%stiffness6, s) + matmul(e%damping6, sd))
            dg = -(matmul(e%stiffness6, ds) + matmul(e%damping6, dsd))
            w(7:9) = matmul(a, g(1:3))
            w(10:12) = matmul(a, g(4:6))
            dw(7:9) = matmul(da, g(1:3)) + matmul(a, dg(1:3))
            dw(10:12) = matmul(da, g(4:6)) + matmul(a, dg(4:6))
            w(1:3) = -w(7:9)
            w(4:6) = -w(10:12) - cross(r, w(7:9))
            dw(1:3) = -dw(7:9)
            dw(4:6) = -dw(10:12) - cross(dr, w(7:9)) - cross(r, dw(7:9))
        end associate
    contains
        !> The small-rotation vector of R: vee of (R − Rᵀ)/2.
        pure function vee(rel) result(theta)
            real(wp), intent(in) :: rel(3, 3)
            real(wp) :: theta(3)
            theta = 0.5_wp * [rel(3, 2) - rel(2, 3), rel(1, 3) - rel(3, 1), rel(2, 1) - rel(1, 2)]
        end function vee
    end subroutine bushing
end module flexmbs_mbs_force_element_tangent
