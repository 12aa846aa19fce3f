!> Reproducible random configurations for the multibody tests: a xorshift64*
!> generator (Vigna 2016), independent of the intrinsic generator's state.
module mbs_random
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_mbs_rotation, only: quat_normalize
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_system, only: mbs_system_t
    implicit none
    private
    public :: random_state_t, uniform, random_vector, random_quaternion, ad_deviation

    type :: random_state_t
        integer(i8) :: s = 88172645463325252_i8
    end type random_state_t

contains

    !> Uniform in [lo, hi).
    function uniform(rng, lo, hi) result(x)
        type(random_state_t), intent(inout) :: rng
        real(wp), intent(in) :: lo, hi
        real(wp) :: x
        rng%s = ieor(rng%s, ishft(rng%s, -12))
        rng%s = ieor(rng%s, ishft(rng%s, 25))
        rng%s = ieor(rng%s, ishft(rng%s, -27))
        x = lo + (hi - lo) * real(ishft(rng%s * 2685821657736338717_i8, -11), wp) / 2.0_wp**53
    end function uniform

    !> n components uniform in [lo, hi).
    function random_vector(rng, n, lo, hi) result(x)
        type(random_state_t), intent(inout) :: rng
        integer, intent(in) :: n
        real(wp), intent(in) :: lo, hi
        real(wp) :: x(n)
        integer :: i
        do i = 1, n
            x(i) = uniform(rng, lo, hi)
        end do
    end function random_vector

    !> A unit quaternion away from the degenerate small-norm draws.
    function random_quaternion(rng) result(p)
        type(random_state_t), intent(inout) :: rng
        real(wp) :: p(4)
        p = random_vector(rng, 4, -1.0_wp, 1.0_wp)
        do while (norm2(p) < 0.2_wp)
            p = random_vector(rng, 4, -1.0_wp, 1.0_wp)
        end do
        p = quat_normalize(p)
    end function random_quaternion

    !> The largest deviation of the 'ad' system from the 'analytic' one at
    !> (t, q, v): c absolute; G, c_q, γ relative to their largest entry; c_t
    !> absolute.
    real(wp) function ad_deviation(hand, ad, t, q, v, status) result(worst)
        type(mbs_system_t), intent(inout) :: hand, ad
        real(wp), intent(in) :: t, q(:), v(:)
        type(status_t), intent(inout) :: status
        real(wp) :: ch(hand%nc), cd(hand%nc), gh(hand%nc, hand%nv), gd(hand%nc, hand%nv), &
            qh(hand%nc, hand%nq), qd(hand%nc, hand%nq), th(hand%nc), td(hand%nc), &
            yh(hand%nc), yd(hand%nc)
        call hand%constraint(t, q, ch, status)
        call ad%constraint(t, q, cd, status)
        call hand%constraint_jacobian(t, q, gh, status)
        call ad%constraint_jacobian(t, q, gd, status)
        call hand%constraint_position_jacobian(t, q, qh, status)
        call ad%constraint_position_jacobian(t, q, qd, status)
        call hand%constraint_time_derivative(t, q, th, status)
        call ad%constraint_time_derivative(t, q, td, status)
        call hand%constraint_curvature(t, q, v, yh, status)
        call ad%constraint_curvature(t, q, v, yd, status)
        worst = max(maxval(abs(ch - cd)), maxval(abs(gh - gd)) / maxval(abs(gh)), &
                    maxval(abs(qh - qd)) / maxval(abs(qh)), maxval(abs(th - td)), &
                    maxval(abs(yh - yd)) / max(maxval(abs(yh)), 1.0_wp))
    end function ad_deviation
end module mbs_random
