!> MEXAX under Deuflhard's order and step-size control (docs/theory.md
!> §7.3, flexmbs_dae_mexax_deuflhard).
!>
!> The model's step ratios α(j, q) are checked against the model itself,
!> solved numerically: with the errors ε_j(H_q) = ε^((A_j − A_1 + 1)/(A_q −
!> A_1 + 1)) that the model gives column j at column q's step H_q, and
!> err_j ∝ H^γ_j, the step H_j at which column j meets ε is found by
!> bisection and H_q/H_j compared with the closed form. The convergence
!> monitor and the choice after acceptance are checked on constructed
!> tableaus where the right decision is plain. On the 8-bar anchor of
!> docs/theory.md §7.7 the counters are compared with the original's
!> (ensemble means over H0, as in test_mexax).
module test_mexax_deuflhard
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_control_deuflhard
    use flexmbs_dae_mexax_deuflhard, only: alpha_table, window_top, window_test, &
        order_after_accept_window, window_continue, window_accept, window_reject
    use test_mexax, only: anchor_run
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mexax_deuflhard

    ! MEXAX's sequences (docs/theory.md §7.2) and work A_1 = n_1 + 4, A_j =
    ! A_{j−1} + n_j (§7.3)
    integer, parameter :: euler_n(12) = [2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 30]
    ! the original's anchor: NSTEP NACCPT NREJCT at TOL 1e-3, 1e-5, 1e-7, 1e-9
    ! and its cost counters NFPROB NFCN NGCN NMULT NDEC NSOL at 1e-3
    integer, parameter :: anchor_counts(3, 4) = reshape([49, 38, 11, 58, 45, 13, 54, 45, 9, &
                                                         68, 60, 8], [3, 4])
    integer, parameter :: anchor_cost(6) = [2080, 871, 44, 1126, 1160, 1165]

contains

    function collect_mexax_deuflhard() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [ &
            new_test('alpha_is_the_model_step_ratio', test_alpha), &
            new_test('window_top_least_model_work', test_window_top), &
            new_test('monitor_decisions', test_monitor), &
            new_test('order_after_accept', test_after_accept), &
            new_test('anchor_ensemble_euler', test_anchor)]
    end function collect_mexax_deuflhard

    function work_of(n) result(a)
        integer, intent(in) :: n(:)
        real(wp) :: a(size(n))
        integer :: j
        a(1) = real(n(1) + 4, wp)
        do j = 2, size(n)
            a(j) = a(j - 1) + real(n(j), wp)
        end do
    end function work_of

    !> Work numbers and error orders γ_j of base 1 (Euler) or 2 (midpoint).
    subroutine base_columns(base, a, g)
        integer, intent(in) :: base
        real(wp), allocatable, intent(out) :: a(:), g(:)
        integer :: j
        if (base == 1) then
            a = work_of(euler_n)
        else
            a = work_of([(2 * j, j = 1, 12)])
        end if
        g = gammas(base == 1, 12)
    end subroutine base_columns

    function gammas(base_euler, km) result(g)
        logical, intent(in) :: base_euler
        integer, intent(in) :: km
        real(wp) :: g(km)
        integer :: j
        if (base_euler) then
            g = [(real(j, wp), j = 1, km)]
        else
            g = [(real(2 * j - 1, wp), j = 1, km)]
        end if
    end function gammas

    !> H_q/H_j of the model, with H_q = 1, by bisection on log H.
    real(wp) function model_ratio(a, g, eps, j, q) result(ratio)
        real(wp), intent(in) :: a(:), g(:), eps
        integer, intent(in) :: j, q
        real(wp) :: lo, hi, mid, eps_j
        integer :: it
        eps_j = eps**((a(j) - a(1) + 1.0_wp) / (a(q) - a(1) + 1.0_wp))
        lo = -60.0_wp
        hi = 60.0_wp
        do it = 1, 200
            mid = 0.5_wp * (lo + hi)
            ! err_j(H) = eps_j H^γ_j (H_q = 1): too large → H_j below exp(mid)
            if (log(eps_j) + g(j) * mid > log(eps)) then
                hi = mid
            else
                lo = mid
            end if
        end do
        ratio = 1.0_wp / exp(0.5_wp * (lo + hi))
    end function model_ratio

    subroutine test_alpha(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: tols(3) = [1.0e-3_wp, 1.0e-6_wp, 1.0e-9_wp]
        real(wp), allocatable :: a(:), g(:), alpha(:, :)
        integer :: base, t, j, q
        real(wp) :: worst
        worst = 0.0_wp
        do base = 1, 2
            call base_columns(base, a, g)
            do t = 1, size(tols)
                alpha = alpha_table(a, g, tols(t))
                do q = 2, 12
                    do j = 1, q - 1
                        worst = max(worst, abs(alpha(j, q) / model_ratio(a, g, tols(t), j, q) - 1))
                        call check(error, alpha(j, q) > 1.0_wp, 'alpha(j, q) <= 1 for j < q')
                    end do
                end do
            end do
        end do
        call check(error, worst < 1.0e-10_wp, 'alpha differs from the model''s step ratio')
        ! one value by hand: (E), ε = 1e-3, A_2 = 9, A_3 = 13, A_1 = 6, γ_2 = 2:
        ! ε^(−4/(8·2)) = 10^0.75
        a = work_of(euler_n)
        alpha = alpha_table(a, gammas(.true., 12), 1.0e-3_wp)
        call check(error, abs(alpha(2, 3) - 10.0_wp**0.75_wp) < 1.0e-12_wp, 'alpha(2, 3) by hand')
    end subroutine test_alpha

    !> The top column is where the model's work per unit step A_q/H_q first
    !> rises, with H_q from the bisection above.
    subroutine test_window_top(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: tols(3) = [1.0e-3_wp, 1.0e-6_wp, 1.0e-9_wp]
        real(wp), allocatable :: a(:), g(:), alpha(:, :)
        integer :: base, t, j, q, expected
        character(len=80) :: msg
        do base = 1, 2
            call base_columns(base, a, g)
            do t = 1, size(tols)
                alpha = alpha_table(a, g, tols(t))
                expected = 12
                do q = 2, 11
                    ! W_{q+1}/W_q = (A_{q+1}/A_q) (H_q/H_{q+1})
                    if (a(q + 1) / a(q) / model_ratio(a, g, tols(t), q, q + 1) > 1.0_wp) then
                        expected = q
                        exit
                    end if
                end do
                write (msg, '(a,i0,a,es8.1,a,i0,a,i0)') 'base ', base, ', eps ', tols(t), &
                    ': window top ', window_top(a, alpha, 12), ', model ', expected
                call check(error, window_top(a, alpha, 12) == expected, trim(msg))
                call check(error, window_top(a, alpha, 5) == min(expected, 5), trim(msg) // &
                           ' (km = 5)')
            end do
        end do
    end subroutine test_window_top

    subroutine test_monitor(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: alpha(6, 6), h_retry
        integer :: decision
        alpha = 1.0_wp
        alpha(2, 4) = 3.0_wp
        alpha(2, 5) = 4.0_wp
        alpha(3, 4) = 1.5_wp
        alpha(3, 5) = 2.0_wp
        alpha(4, 5) = 1.3_wp
        ! converged in the window: accept
        call window_test(0.5_wp, 0.9_wp, alpha, 3, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, decision == window_accept, 'err <= 1 in the window accepts')
        ! below the window (j < q - 1): no decision, even when converged
        call window_test(0.5_wp, 0.9_wp, alpha, 2, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, decision == window_continue, 'below the window: continue')
        ! ... except on the first step
        call window_test(0.5_wp, 0.9_wp, alpha, 2, 4, 6, .true., 1.0_wp, decision, h_retry)
        call check(error, decision == window_accept, 'first step: converged column 2 accepts')
        ! j = q - 1, fac 2.5 > α(3, 5) = 2: column 5 not expected to converge;
        ! retry with H α(3, 4)/fac = 0.6
        h_retry = 0.0_wp
        call window_test(5.0_wp, 2.5_wp, alpha, 3, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, decision == window_reject .and. abs(h_retry - 0.6_wp) < 1.0e-14_wp, &
                   'j = q - 1, fac > alpha(j, q + 1): reject with H alpha(j, q)/fac')
        ! j = q - 1, fac 1.8 <= α(3, 5): go on to column q
        call window_test(5.0_wp, 1.8_wp, alpha, 3, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, decision == window_continue, 'fac <= alpha(j, q + 1): continue')
        ! at the window's top (j = q + 1), not converged: reject with H/fac
        call window_test(1.2_wp, 1.25_wp, alpha, 5, 4, 6, .false., 2.0_wp, decision, h_retry)
        call check(error, decision == window_reject .and. abs(h_retry - 1.6_wp) < 1.0e-14_wp, &
                   'top of the window: reject with H/fac')
        ! q = qmax: the top is q itself; a retry aimed at it takes 0.7 more
        call window_test(5.0_wp, 1.5_wp, alpha, 4, 5, 5, .false., 1.0_wp, decision, h_retry)
        call check(error, decision == window_reject .and. &
                   abs(h_retry - 0.7_wp * 1.3_wp / 1.5_wp) < 1.0e-14_wp, &
                   'q = qmax: reject with 0.7 H alpha(j, q)/fac')
        ! reductions stay within [0.01, 0.9]
        call window_test(1.0e9_wp, 1.0e4_wp, alpha, 5, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, abs(h_retry - 0.01_wp) < 1.0e-14_wp, 'reduction at least 0.01')
        call window_test(1.01_wp, 1.01_wp, alpha, 5, 4, 6, .false., 1.0_wp, decision, h_retry)
        call check(error, abs(h_retry - 0.9_wp) < 1.0e-14_wp, 'reduction at most 0.9')
    end subroutine test_monitor

    subroutine test_after_accept(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: awork(6), hh(6), work(6), alpha(6, 6), h
        integer :: q
        awork = [6.0_wp, 9.0_wp, 13.0_wp, 18.0_wp, 24.0_wp, 32.0_wp]
        alpha = 1.0_wp
        alpha(3, 4) = 2.0_wp
        alpha(4, 5) = 1.1_wp
        ! least work per unit step in column 3 of 2..4: q = 3, H = H_3
        hh = [0.0_wp, 1.0_wp, 2.0_wp, 2.1_wp, 0.0_wp, 0.0_wp]
        work = awork / max(hh, tiny(1.0_wp))
        call order_after_accept_window(awork, hh, work, alpha, 4, 6, .false., 1.0_wp, 10.0_wp, q, h)
        call check(error, q == 3 .and. h == 2.0_wp, 'least work in column 3 of 2..4')
        ! least work in the last column kc = 3 and α(3, 4) promises less work
        ! in column 4 (W_4 = 18/(2 * 2) < W_3 = 13/2): the order rises
        hh = [0.0_wp, 1.0_wp, 2.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        work = awork / max(hh, tiny(1.0_wp))
        call order_after_accept_window(awork, hh, work, alpha, 3, 6, .false., 1.0_wp, 10.0_wp, q, h)
        call check(error, q == 4 .and. abs(h - 4.0_wp) < 1.0e-14_wp, 'order rises with H_3 alpha(3, 4)')
        ! not after a rejection in the same step
        call order_after_accept_window(awork, hh, work, alpha, 3, 6, .true., 1.0_wp, 10.0_wp, q, h)
        call check(error, q == 3 .and. h == 2.0_wp, 'no rise after a rejection')
        ! not at the top of the window
        call order_after_accept_window(awork, hh, work, alpha, 3, 3, .false., 1.0_wp, 10.0_wp, q, h)
        call check(error, q == 3, 'no rise above the window top')
        ! the rise is bounded by the growth factor 4 on the accepted step
        call order_after_accept_window(awork, hh, work, alpha, 3, 6, .false., 0.5_wp, 10.0_wp, q, h)
        call check(error, q == 3, 'H_3 alpha(3, 4) = 4 > 4 H: no cheaper rise')
        ! W_5 = 24/(2.1 * 1.1) > W_4: no rise from kc = 4
        hh = [0.0_wp, 1.0_wp, 2.0_wp, 2.1_wp, 0.0_wp, 0.0_wp]
        work = awork / max(hh, tiny(1.0_wp))
        work(3) = 100.0_wp
        call order_after_accept_window(awork, hh, work, alpha, 4, 6, .false., 1.0_wp, 10.0_wp, q, h)
        call check(error, q == 4 .and. h == 2.1_wp, 'no rise when the model promises no gain')
    end subroutine test_after_accept

    !> The 8-bar anchor (base (E), a and λ extrapolated, the classic
    !> elimination order) over H0 = 1e-3 (1 + 1e-4 m), m = 0..9: ensemble
    !> means against the original's. Within 15 %: NSTEP and NACCPT at TOL
    !> 1e-5 … 1e-9 and the six cost counters at 1e-3 (measured 2-10 %);
    !> NSTEP and NACCPT at 1e-3 (+17 %, +15 %) within 20 %. NREJCT is printed
    !> beside the original's (docs/theory.md §7.7: high at 1e-7 and 1e-9).
    subroutine test_anchor(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: members = 10
        type(mexax_t) :: solver
        type(status_t) :: status
        real(wp) :: tol, mean(9), band
        integer :: e, m, counts(9)
        character(len=300) :: msg
        do e = 1, 4
            tol = 10.0_wp**(-(2 * e + 1))
            mean = 0.0_wp
            do m = 0, members - 1
                call anchor_run(solver, tol, 1.0e-3_wp * (1.0_wp + 1.0e-4_wp * m), status, &
                                mexax_control_deuflhard)
                call check(error, status%ok(), 'ensemble member: ' // status%text())
                if (allocated(error)) return
                associate (n => solver%native)
                    counts = [n%nstep, n%naccpt, n%nrejct, n%nfprob, n%nfcn, n%ngcn, n%nmult, &
                              n%ndec, n%nsol]
                    call check(error, n%nstep == n%naccpt + n%nrejct + solver%nstab, &
                               'NSTEP /= NACCPT + NREJCT + restarts')
                end associate
                mean = mean + real(counts, wp) / members
            end do
            write (msg, '(a,es7.0,a,9(1x,f7.1),a,3(1x,i0))') 'TOL ', tol, &
                ': mean NSTEP NACCPT NREJCT NFPROB NFCN NGCN NMULT NDEC NSOL =', mean, &
                '; original', anchor_counts(:, e)
            write (*, '(a)') '  mexax deuflhard anchor ' // trim(msg)
            band = merge(0.20_wp, 0.15_wp, e == 1)
            call check(error, all(abs(mean(1:2) - anchor_counts(1:2, e)) <= &
                band * anchor_counts(1:2, e)), trim(msg) // ': NSTEP or NACCPT off')
            if (e == 1) call check(error, all(abs(mean(4:9) - anchor_cost) <= &
                0.15_wp * anchor_cost), trim(msg) // ': a cost counter not within 15 %')
            if (allocated(error)) return
        end do
    end subroutine test_anchor
end module test_mexax_deuflhard
