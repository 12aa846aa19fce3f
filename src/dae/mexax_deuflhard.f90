!> Deuflhard's order and step-size control for MEXAX's extrapolation
!> tableau (docs/theory.md §7.3, `mexax_control = 'deuflhard'`): the
!> control of the extrapolation codes of Deuflhard's school [Deu83; Deu85;
!> DB02], to which MEXX belongs. The pieces work on the column data of
!> flexmbs_dae_mexax_control's control_t, passed as arrays.
!>
!> The model [Deu83]: for the step H_q with which column q just meets
!> the accuracy ε, the error estimates of the lower columns gain the same
!> number of digits per unit of work, ε_j = ε^((A_j − A_1 + 1)/(A_q − A_1 +
!> 1)). With err_j = O(H^γ_j) this gives the ratio of the columns' step
!> sizes α(j, q) = H_q/H_j = ε^((A_j − A_q)/((A_q − A_1 + 1) γ_j)), j < q,
!> which drives the whole control: the highest column worth computing, the
!> convergence monitor that abandons a step as soon as no column of the
!> order window {q − 1, q, q + 1} is expected to converge, and the step size
!> when the order rises.
module flexmbs_dae_mexax_deuflhard
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: alpha_table, window_top, window_test, order_after_accept_window

    !> Decisions of the convergence monitor on one column.
    integer, parameter, public :: window_continue = 0, window_accept = 1, window_reject = 2

    !> Safety factor ρ: a column's step size aims at the error ρ TOL (the
    !> value of SAFE1 in Numerical Recipes' Deuflhard control, [PTVF96]).
    real(wp), parameter, public :: deuflhard_safety = 0.25_wp
    !> A retry aimed at the window's top column, the last one there is,
    !> takes this further factor (docs/theory.md §7.3: without it, 1e-9 on
    !> the 8-bar chain rejects the retries again; the value of [PTVF96]'s
    !> SAFE2).
    real(wp), parameter :: top_safety = 0.7_wp
    !> A step grows by at most this factor after an acceptance (the
    !> original's FAC2 of the column step sizes, docs/theory.md §7.3).
    real(wp), parameter, public :: deuflhard_growth = 4.0_wp
    !> A rejected step shrinks to between these fractions of itself (own
    !> bounds; the monitor's reduction lies inside them unless an estimate
    !> is far off). [PTVF96]'s [1e-5, 0.7] put a 12-bar chain's angle
    !> error above 20 TOL in one run of the test (docs/theory.md §7.3).
    real(wp), parameter :: reduction_max = 0.9_wp, reduction_min = 0.01_wp

contains

    !> α(j, q) for 1 ≤ j < q ≤ size(awork) at the model's accuracy eps,
    !> with gam(j) = γ_j, the order in H of column j's error estimate.
    pure function alpha_table(awork, gam, eps) result(alpha)
        real(wp), intent(in) :: awork(:), gam(:), eps
        real(wp) :: alpha(size(awork), size(awork))
        integer :: j, q
        alpha = 1.0_wp
        do q = 2, size(awork)
            do j = 1, q - 1
                alpha(j, q) = eps**((awork(j) - awork(q)) / &
                    ((awork(q) - awork(1) + 1.0_wp) * gam(j)))
            end do
        end do
    end function alpha_table

    !> The highest column worth computing [Deu83]: the first q ≥ 2 whose
    !> next column costs more per unit step under the model, A_{q+1} >
    !> A_q α(q, q + 1); at most km.
    pure integer function window_top(awork, alpha, km) result(qmax)
        real(wp), intent(in) :: awork(:), alpha(:, :)
        integer, intent(in) :: km
        do qmax = 2, km - 1
            if (awork(qmax + 1) > awork(qmax) * alpha(qmax, qmax + 1)) return
        end do
        qmax = km
    end function window_top

    !> The convergence monitor on column j ≥ 2 of a step planned for column
    !> q (window {q − 1, q, q + 1}, below qmax) [Deu83; DB02]:
    !> accept when err_j ≤ 1; reject at the window's top; below it, reject
    !> when the step factor fac_j = H/H_j exceeds α(j, top) — not even the
    !> top column is expected to converge — and retry with the step for
    !> which column q is expected to converge, H α(j, q)/fac_j. Columns
    !> below the window are only monitored on the first step.
    pure subroutine window_test(err, fac, alpha, j, q, qmax, first, h, decision, h_retry)
        real(wp), intent(in) :: err, fac, alpha(:, :)
        integer, intent(in) :: j, q, qmax
        logical, intent(in) :: first
        real(wp), intent(in) :: h           !! |H| of the attempt
        integer, intent(out) :: decision    !! window_continue | _accept | _reject
        real(wp), intent(inout) :: h_retry  !! |H| of the next attempt on rejection
        integer :: top
        real(wp) :: reduction
        decision = window_continue
        if (j < 2 .or. (j < q - 1 .and. .not. first)) return
        if (err <= 1.0_wp) then
            decision = window_accept
            return
        end if
        top = min(q + 1, qmax)
        if (j >= top) then
            reduction = 1.0_wp / fac
        else if (fac > alpha(j, top)) then
            reduction = alpha(j, max(q, j)) / fac
            if (q >= top) reduction = reduction * top_safety
        else
            return
        end if
        decision = window_reject
        h_retry = h * min(reduction_max, max(reduction_min, reduction))
    end subroutine window_test

    !> After acceptance in column kc [Deu83]: the next column is the one
    !> of least work per unit step among 2..kc, and its step size; when
    !> that is kc itself, below qmax and no rejection preceded in this step,
    !> the order rises by one with the model's step H_kc α(kc, kc + 1).
    pure subroutine order_after_accept_window(awork, hh, work, alpha, kc, qmax, &
                                              after_reject, h_step, hmax, q, h)
        real(wp), intent(in) :: awork(:), hh(:), work(:), alpha(:, :)
        integer, intent(in) :: kc, qmax
        logical, intent(in) :: after_reject
        real(wp), intent(in) :: h_step     !! |H| of the accepted step
        real(wp), intent(in) :: hmax
        integer, intent(out) :: q
        real(wp), intent(out) :: h
        real(wp) :: h_up
        q = 1 + minloc(work(2:kc), dim=1)
        h = hh(q)
        if (q == kc .and. kc < qmax .and. .not. after_reject) then
            h_up = min(hh(kc) * alpha(kc, kc + 1), deuflhard_growth * h_step, hmax)
            if (awork(kc + 1) / h_up <= work(kc)) then
                q = kc + 1
                h = h_up
            end if
        end if
    end subroutine order_after_accept_window
end module flexmbs_dae_mexax_deuflhard
