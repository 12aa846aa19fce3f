!> Two driven closed-loop mechanisms with closed-form kinematics, assembled
!> from rigid bodies and joints (flexmbs_mbs_system): a slider-crank and a
!> Grashof four-bar (crank–rocker). Both are planar (xy plane), built in 3-D
!> with a non-redundant set of 17 rows for 3 bodies: revolute (5)
!> crank–ground, spherical (3) crank–coupler, universal (4) coupler–slider
!> or –rocker (pins: the slider's/rocker's global z and the coupler's
!> in-plane normal), prismatic (5) or revolute (5) to the ground; the 18th
!> row drives the crank angle θ = θ0 + ω t. (All-revolute planar chains in
!> 3-D would be redundant: 20 rows for 18 velocities.)
!>
!> q = (r, p) per body: 1 crank, 2 coupler (rod), 3 slider or rocker.
module flexmbs_problems_mechanisms
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_rotation, only: quat_from_axis_angle
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_joint, only: joint_spherical, joint_revolute, joint_prismatic, &
        joint_universal, joint_primitive
    use flexmbs_mbs_primitive_kinds, only: primitive_angle_driver
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t, &
        driver_t
    implicit none
    private

    integer, parameter, public :: mechanism_slider_crank = 1
    integer, parameter, public :: mechanism_four_bar = 2

    real(wp), parameter, public :: mechanism_omega = 6.283185307179586_wp !! rad/s
    real(wp), parameter, public :: mechanism_theta0 = 0.3_wp             !! rad at t = 0
    !> Slider-crank lengths: crank r, rod l
    real(wp), parameter, public :: crank_r = 0.1_wp, rod_l = 0.3_wp
    !> Four-bar lengths: crank a, coupler b, rocker c, ground d (0.1 + 0.4 < 0.3 + 0.35)
    real(wp), parameter, public :: bar_a = 0.1_wp, bar_b = 0.4_wp, bar_c = 0.3_wp, &
        bar_d = 0.35_wp

    real(wp), parameter :: ez(3) = [0.0_wp, 0.0_wp, 1.0_wp]
    !> Marker axes: identity; the coupler's universal pin (z = local y); the
    !> prismatic guide (z = global x).
    real(wp), parameter :: axes_id(3, 3) = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1] * 1.0_wp, [3, 3])
    real(wp), parameter :: axes_pin(3, 3) = reshape([0, 0, 1, 1, 0, 0, 0, 1, 0] * 1.0_wp, [3, 3])
    real(wp), parameter :: axes_guide(3, 3) = reshape([0, 1, 0, 0, 0, 1, 1, 0, 0] * 1.0_wp, &
                                                     [3, 3])

    public :: new_mechanism, slider_crank_exact, four_bar_exact, four_bar_torque, crank_angle

contains

    !> Crank angle θ0 + ω t.
    pure real(wp) function crank_angle(t)
        real(wp), intent(in) :: t
        crank_angle = mechanism_theta0 + mechanism_omega * t
    end function crank_angle

    !> Slider-crank exact solution: crank pin B, slider C = (s, 0, 0), rod angle φ.
    pure subroutine slider_crank_exact(theta, b, c, phi)
        real(wp), intent(in) :: theta
        real(wp), intent(out) :: b(3), c(3), phi
        b = crank_r * [cos(theta), sin(theta), 0.0_wp]
        c = [crank_r * cos(theta) + sqrt(rod_l**2 - (crank_r * sin(theta))**2), 0.0_wp, 0.0_wp]
        phi = atan2(c(2) - b(2), c(1) - b(1))
    end subroutine slider_crank_exact

    !> Four-bar exact solution: crank pin B and coupler–rocker pin C, the intersection of
    !> |C − B| = b and |C − D| = c in the assembly mode above the ground line.
    pure subroutine four_bar_exact(theta, b, c)
        real(wp), intent(in) :: theta
        real(wp), intent(out) :: b(3), c(3)
        real(wp) :: d(3), u(3), e, alpha
        b = bar_a * [cos(theta), sin(theta), 0.0_wp]
        d = [bar_d, 0.0_wp, 0.0_wp]
        e = norm2(b - d)
        u = (b - d) / e
        alpha = acos((e**2 + bar_c**2 - bar_b**2) / (2.0_wp * e * bar_c))
        c = d + bar_c * [cos(alpha) * u(1) + sin(alpha) * u(2), &
                         -sin(alpha) * u(1) + cos(alpha) * u(2), 0.0_wp]
    end subroutine four_bar_exact

    !> The torque about z that the four-bar's driver exerts on the crank at
    !> time t (θ = crank_angle(t), θ' = mechanism_omega), links of masses
    !> `mass` and moments of inertia `inertia` about z at their midpoints,
    !> gravity −g y: the power balance τ θ' = Σ m a·v + I ω ω' + m g v_y
    !> with the velocities and accelerations of the closed form (the loop
    !> B + b e(φ) = D + c e(ψ) differentiated once and twice).
    pure real(wp) function four_bar_torque(t, mass, inertia, g) result(torque)
        real(wp), intent(in) :: t, mass(3), inertia(3), g
        real(wp) :: b(3), c(3), theta, w, phi, psi, rate(2), accel(2), loop(2, 2), &
            v(2, 3), a(2, 3), omega(3), alpha(3), power
        integer :: k
        theta = crank_angle(t)
        w = mechanism_omega
        call four_bar_exact(theta, b, c)
        phi = atan2(c(2) - b(2), c(1) - b(1))
        psi = atan2(c(2), c(1) - bar_d)
        ! [b n(φ), −c n(ψ)] (φ', ψ') = −a θ' n(θ), and likewise for (φ'', ψ'')
        loop(:, 1) = bar_b * normal(phi)
        loop(:, 2) = -bar_c * normal(psi)
        rate = solve2(loop, -bar_a * w * normal(theta))
        accel = solve2(loop, bar_a * w**2 * unit(theta) + bar_b * rate(1)**2 * unit(phi) &
                       - bar_c * rate(2)**2 * unit(psi))
        v(:, 1) = 0.5_wp * bar_a * w * normal(theta)
        a(:, 1) = -0.5_wp * bar_a * w**2 * unit(theta)
        v(:, 2) = bar_a * w * normal(theta) + 0.5_wp * bar_b * rate(1) * normal(phi)
        a(:, 2) = -bar_a * w**2 * unit(theta) + 0.5_wp * bar_b * (accel(1) * normal(phi) &
                  - rate(1)**2 * unit(phi))
        v(:, 3) = 0.5_wp * bar_c * rate(2) * normal(psi)
        a(:, 3) = 0.5_wp * bar_c * (accel(2) * normal(psi) - rate(2)**2 * unit(psi))
        omega = [w, rate]
        alpha = [0.0_wp, accel]
        power = 0.0_wp
        do k = 1, 3
            power = power + mass(k) * (dot_product(a(:, k), v(:, k)) + g * v(2, k)) &
                + inertia(k) * omega(k) * alpha(k)
        end do
        torque = power / w
    contains
        pure function unit(x) result(e)
            real(wp), intent(in) :: x
            real(wp) :: e(2)
            e = [cos(x), sin(x)]
        end function unit
        pure function normal(x) result(e)
            real(wp), intent(in) :: x
            real(wp) :: e(2)
            e = [-sin(x), cos(x)]
        end function normal
        pure function solve2(m, r) result(x)
            real(wp), intent(in) :: m(2, 2), r(2)
            real(wp) :: x(2)
            x = [r(1) * m(2, 2) - m(1, 2) * r(2), m(1, 1) * r(2) - m(2, 1) * r(1)] &
                / (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
        end function solve2
    end function four_bar_torque

    !> The mechanism (mechanism_slider_crank or mechanism_four_bar) under
    !> gravity −9.81 y, and its closed-form positions at t = 0 (velocities:
    !> the consistent-initial projection gives them).
    subroutine new_mechanism(mechanism, sys, q0, status, constraint_derivatives)
        integer, intent(in) :: mechanism
        type(mbs_system_t), intent(out) :: sys
        real(wp), intent(out) :: q0(21)
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: constraint_derivatives !! 'analytic' | 'ad'
        type(marker_t) :: m(8)
        type(mbs_joint_t) :: j(5)
        type(driver_t) :: drive
        type(rigid_body_t) :: bodies(3)
        real(wp) :: b(3), c(3), phi, l1, l2
        integer :: k
        drive%poly(0:1) = [mechanism_theta0, mechanism_omega]
        do k = 1, 3
            bodies(k)%mass = 1.0_wp / k
            bodies(k)%inertia = 0.01_wp * axes_id
        end do
        if (mechanism == mechanism_slider_crank) then
            l1 = crank_r
            l2 = rod_l
            call slider_crank_exact(mechanism_theta0, b, c, phi)
            call set_body(q0, 1, 0.5_wp * b, mechanism_theta0)
            call set_body(q0, 2, 0.5_wp * (b + c), phi)
            call set_body(q0, 3, c, 0.0_wp)
            m(6) = marker_t(3, [0.0_wp, 0.0_wp, 0.0_wp], axes_id)
            m(7) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp], axes_guide)
            m(8) = marker_t(3, [0.0_wp, 0.0_wp, 0.0_wp], axes_guide)
            j(5) = mbs_joint_t(joint_prismatic, 7, 8)
        else
            l1 = bar_a
            l2 = bar_b
            call four_bar_exact(mechanism_theta0, b, c)
            call set_body(q0, 1, 0.5_wp * b, mechanism_theta0)
            call set_body(q0, 2, 0.5_wp * (b + c), atan2(c(2) - b(2), c(1) - b(1)))
            call set_body(q0, 3, 0.5_wp * (c + [bar_d, 0.0_wp, 0.0_wp]), &
                          atan2(c(2), c(1) - bar_d))
            ! the rocker's local x points from D to C
            m(6) = marker_t(3, [0.5_wp * bar_c, 0.0_wp, 0.0_wp], axes_id)
            m(7) = marker_t(3, [-0.5_wp * bar_c, 0.0_wp, 0.0_wp], axes_id)
            m(8) = marker_t(0, [bar_d, 0.0_wp, 0.0_wp], axes_id)
            j(5) = mbs_joint_t(joint_revolute, 8, 7)
        end if
        m(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp], axes_id)
        m(2) = marker_t(1, [-0.5_wp * l1, 0.0_wp, 0.0_wp], axes_id)
        m(3) = marker_t(1, [0.5_wp * l1, 0.0_wp, 0.0_wp], axes_id)
        m(4) = marker_t(2, [-0.5_wp * l2, 0.0_wp, 0.0_wp], axes_id)
        m(5) = marker_t(2, [0.5_wp * l2, 0.0_wp, 0.0_wp], axes_pin)
        j(1) = mbs_joint_t(joint_revolute, 1, 2)
        j(2) = mbs_joint_t(joint_primitive, 1, 2, primitive_angle_driver, 1, 1, drive)
        j(3) = mbs_joint_t(joint_spherical, 3, 4)
        j(4) = mbs_joint_t(joint_universal, 5, 6)
        sys = new_mbs_system(bodies, m, j, gravity=[0.0_wp, -9.81_wp, 0.0_wp], &
                             constraint_derivatives=constraint_derivatives, status=status)
    end subroutine new_mechanism

    !> A planar body state: centre, rotation about z.
    pure subroutine set_body(q, k, centre, angle)
        real(wp), intent(inout) :: q(:)
        integer, intent(in) :: k
        real(wp), intent(in) :: centre(3), angle
        q(7 * k - 6:7 * k - 4) = centre
        q(7 * k - 3:7 * k) = quat_from_axis_angle(ez, angle)
    end subroutine set_body
end module flexmbs_problems_mechanisms
