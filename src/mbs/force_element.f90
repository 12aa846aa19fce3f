!> Force elements between two markers, or applied loads on one marker
!> (docs/multibody.md, "Force elements"):
!>
!>   spring_damper  along the line x_j − x_i of the marker origins, tension
!>                  F = Σ_m k_m (ℓ − ℓ₀)^m + c ℓ' (m ≤ 5; linear: k₁ only)
!>   rotational     about z_i (a revolute joint's axis): torque on j
!>                  τ = −k (φ − φ₀) − c φ', φ the angle from x_i to x_j about z_i
!>   bushing        (f, n) = −K s − C s' in marker i's frame, s = (d, θ): d the
!>                  origin of j in i's frame, θ the small-rotation vector of
!>                  R = A_iᵀ A_j (vee of (R − Rᵀ)/2)
!>   applied        force s(t) F and torque s(t) n at marker i's origin, F and n
!>                  in the world or in the marker's frame, s(t) a driver_t
!>
!> Every law is written once, on dual numbers: evaluated on the marker frames
!> seeded with the derivatives of their bodies' coordinates (or velocities)
!> it gives the wrench and its exact first derivatives (flexmbs_mbs_system
!> maps both through the markers' Jacobians). The wrench on marker i acts at
!> x_i, the one on marker j at x_j; the pair is equal and opposite (zero
!> total force and zero total moment about any point).
module flexmbs_mbs_force_element
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_user_function
    use flexmbs_core_text, only: real_text
    use flexmbs_mbs_dual, only: dual_t, operator(+), operator(-), operator(*), &
        operator(/), operator(**), assignment(=), sqrt, atan2, dot_product, matmul
    use flexmbs_mbs_rotation_dual, only: cross
    use flexmbs_mbs_driver, only: driver_t, driver_values
    implicit none
    private

    integer, parameter, public :: force_spring_damper = 1
    integer, parameter, public :: force_rotational = 2
    integer, parameter, public :: force_bushing = 3
    integer, parameter, public :: force_applied = 4
    !> Highest power of the elongation in a spring's law.
    integer, parameter, public :: max_spring_order = 5
    !> A spring whose markers come closer than this fraction of max(ℓ₀, 1 m)
    !> has no direction: its evaluation fails instead of returning NaN.
    real(wp), parameter, public :: min_relative_length = 1.0e-9_wp

    real(wp), parameter :: two_pi = 6.283185307179586_wp

    !> One force element (module header); the fields a kind does not use stay zero.
    type, public :: force_element_t
        integer :: kind = 0
        integer :: marker_i = 0
        integer :: marker_j = 0 !! 0 for an applied load
        !> ℓ₀ [m] of a spring_damper, φ₀ [rad] of a rotational spring
        real(wp) :: reference = 0.0_wp
        !> k_1 .. k_5 of a spring_damper, k = stiffness(1) of a rotational one
        real(wp) :: stiffness(max_spring_order) = 0.0_wp
        real(wp) :: damping = 0.0_wp !! c (spring_damper, rotational)
        real(wp) :: stiffness6(6, 6) = 0.0_wp !! bushing K (force, torque rows)
        real(wp) :: damping6(6, 6) = 0.0_wp   !! bushing C
        type(driver_t) :: driver !! s(t) of an applied load
        real(wp) :: force(3) = 0.0_wp, torque(3) = 0.0_wp !! F and n of an applied load
        !> F and n in world axes (else in the marker's)
        logical :: world_frame = .true.
    end type force_element_t

    !> A marker frame as the laws see it: origin, axes (columns), origin
    !> velocity and world angular velocity; dual numbers.
    type, public :: element_frame_t
        type(dual_t) :: x(3), a(3, 3), xd(3), w(3)
    end type element_frame_t

    public :: element_wrench, element_energy, force_element_name, element_uses_rotation

contains

    !> The scene's word for a force element kind ('spring_damper', 'rotational',
    !> 'bushing', 'applied'; 'unknown' otherwise), for messages.
    pure function force_element_name(kind) result(name)
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        select case (kind)
        case (force_spring_damper); name = 'spring_damper'
        case (force_rotational); name = 'rotational'
        case (force_bushing); name = 'bushing'
        case (force_applied); name = 'applied'
        case default; name = 'unknown'
        end select
    end function force_element_name

    !> Whether the element needs its markers' rotation (a node marker has none).
    pure logical function element_uses_rotation(e)
        type(force_element_t), intent(in) :: e
        element_uses_rotation = e%kind == force_rotational .or. e%kind == force_bushing .or. &
            (e%kind == force_applied .and. (any(abs(e%torque) > 0.0_wp) .or. .not. e%world_frame))
    end function element_uses_rotation

    !> Forces (global) and torques (global, about the marker origins) on
    !> marker i (column 1) and marker j (column 2) at time t.
    pure subroutine element_wrench(e, t, fi, fj, force, torque, status)
        type(force_element_t), intent(in) :: e
        real(wp), intent(in) :: t
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t), intent(out) :: force(3, 2), torque(3, 2)
        type(status_t), intent(inout) :: status
        real(wp) :: s(3)
        force = 0.0_wp
        torque = 0.0_wp
        select case (e%kind)
        case (force_spring_damper)
            call spring_damper(e, fi, fj, force, status)
        case (force_rotational)
            call rotational(e, fi, fj, torque)
        case (force_bushing)
            call bushing(e, fi, fj, force, torque)
        case (force_applied)
            s = driver_values(e%driver, t)
            if (e%world_frame) then
                force(:, 1) = s(1) * e%force
                torque(:, 1) = s(1) * e%torque
            else
                force(:, 1) = matmul(fi%a, s(1) * e%force)
                torque(:, 1) = matmul(fi%a, s(1) * e%torque)
            end if
        end select
    end subroutine element_wrench

    !> Tension along u = (x_j − x_i)/ℓ: j is pulled towards i when F > 0.
    pure subroutine spring_damper(e, fi, fj, force, status)
        type(force_element_t), intent(in) :: e
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t), intent(inout) :: force(3, 2)
        type(status_t), intent(inout) :: status
        type(dual_t) :: r(3), u(3), l, ld, f, stretch
        integer :: m
        r = fj%x - fi%x
        l = sqrt(dot_product(r, r))
        if (l%val < min_relative_length * max(e%reference, 1.0_wp)) then
            call status%set(status_solver_failure, 'spring_damper: the markers are ' // real_text(l%val) // &
                ' m apart: the line of the force is undefined (a bushing takes coinciding &
                &markers)', reason_user_function)
            return
        end if
        u = r / l
        ld = dot_product(u, fj%xd - fi%xd)
        stretch = l - e%reference
        f = e%damping * ld
        do m = 1, max_spring_order
            if (abs(e%stiffness(m)) > 0.0_wp) f = f + e%stiffness(m) * stretch**m
        end do
        force(:, 1) = f * u
        force(:, 2) = -(f * u)
    end subroutine spring_damper

    !> The angle from x_i to x_j about z_i, relative to φ₀ and wrapped into
    !> (−π, π]: the element counts no whole turns.
    pure function relative_angle(e, fi, fj) result(phi)
        type(force_element_t), intent(in) :: e
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t) :: phi
        phi = atan2(dot_product(cross(fi%a(:, 1), fj%a(:, 1)), fi%a(:, 3)), &
                    dot_product(fi%a(:, 1), fj%a(:, 1))) - e%reference
        phi = phi - two_pi * anint(phi%val / two_pi)
    end function relative_angle

    !> A couple about z_i: τ on j, −τ on i (φ' = (ω_j − ω_i)·z_i while the
    !> z axes are parallel, as a revolute joint holds them).
    pure subroutine rotational(e, fi, fj, torque)
        type(force_element_t), intent(in) :: e
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t), intent(inout) :: torque(3, 2)
        type(dual_t) :: tau
        tau = -(e%stiffness(1) * relative_angle(e, fi, fj)) &
            - e%damping * dot_product(fj%w - fi%w, fi%a(:, 3))
        torque(:, 2) = tau * fi%a(:, 3)
        torque(:, 1) = -(tau * fi%a(:, 3))
    end subroutine rotational

    !> s = (d, θ) and s' = (d', θ') of marker j relative to marker i, in i's axes.
    pure subroutine bushing_motion(fi, fj, s, sd)
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t), intent(out) :: s(6), sd(6)
        type(dual_t) :: r(3), rel(3, 3), wrel(3)
        integer :: k
        r = fj%x - fi%x
        wrel = fj%xd - fi%xd - cross(fi%w, r)
        do k = 1, 3
            s(k) = dot_product(fi%a(:, k), r)
            sd(k) = dot_product(fi%a(:, k), wrel)
            sd(3 + k) = dot_product(fi%a(:, k), fj%w - fi%w)
        end do
        rel = matmul(transpose(fi%a), fj%a)
        s(4) = 0.5_wp * (rel(3, 2) - rel(2, 3))
        s(5) = 0.5_wp * (rel(1, 3) - rel(3, 1))
        s(6) = 0.5_wp * (rel(2, 1) - rel(1, 2))
    end subroutine bushing_motion

    !> (f, n) = −K s − C s' on j at x_j (i's axes); −f on i at x_j.
    pure subroutine bushing(e, fi, fj, force, torque)
        type(force_element_t), intent(in) :: e
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t), intent(inout) :: force(3, 2), torque(3, 2)
        type(dual_t) :: s(6), sd(6), g(6)
        call bushing_motion(fi, fj, s, sd)
        g = -(matmul(e%stiffness6, s) + matmul(e%damping6, sd))
        force(:, 2) = matmul(fi%a, g(1:3))
        torque(:, 2) = matmul(fi%a, g(4:6))
        force(:, 1) = -force(:, 2)
        torque(:, 1) = -torque(:, 2) - cross(fj%x - fi%x, force(:, 2))
    end subroutine bushing

    !> Potential energy of the springs: Σ k_m e^(m+1)/(m+1), k (φ − φ₀)²/2,
    !> sᵀ K s / 2 (the bushing's for small rotations); 0 for applied loads.
    pure real(wp) function element_energy(e, fi, fj) result(v)
        type(force_element_t), intent(in) :: e
        type(element_frame_t), intent(in) :: fi, fj
        type(dual_t) :: r(3), phi, s(6), sd(6)
        real(wp) :: stretch, sv(6)
        integer :: m
        v = 0.0_wp
        select case (e%kind)
        case (force_spring_damper)
            r = fj%x - fi%x
            stretch = norm2(r%val) - e%reference
            do m = 1, max_spring_order
                v = v + e%stiffness(m) * stretch**(m + 1) / (m + 1)
            end do
        case (force_rotational)
            phi = relative_angle(e, fi, fj)
            v = 0.5_wp * e%stiffness(1) * phi%val**2
        case (force_bushing)
            call bushing_motion(fi, fj, s, sd)
            sv = s%val
            v = 0.5_wp * dot_product(sv, matmul(e%stiffness6, sv))
        end select
    end function element_energy
end module flexmbs_mbs_force_element
