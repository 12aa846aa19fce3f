!> MEXAX order and step-size control (docs/theory.md §7.3): the step-number
!> sequences, the column step sizes and work, the convergence monitor and
!> hope test, and the order and step chosen after an accepted or a rejected
!> step.
!>
!> The structure is that of ODEX [HNW93 II.9]. The midpoint base (M), an
!> h²-extrapolation like ODEX's GBS method, takes ODEX's published rules;
!> the Euler base (E), an h-extrapolation like the linearly implicit Euler
!> method of SEULEX [HW96 IV.9], takes SEULEX's, which transfer ODEX's
!> control to h-expansions. Each constant below names its source.
!>
!> `mexax_control_deuflhard` selects instead the control of Deuflhard's
!> school (flexmbs_dae_mexax_deuflhard): the same tableau, sequences and
!> work, other rules for the order, the step size and the rejections.
module flexmbs_dae_mexax_control
    use flexmbs_core_kinds, only: wp
    use flexmbs_dae_mexax_deuflhard, only: alpha_table, window_top, window_test, &
        order_after_accept_window, deuflhard_safety, deuflhard_growth, window_continue, &
        window_accept, window_reject
    implicit none
    private
    public :: window_continue, window_accept, window_reject

    !> Base methods (§3.2).
    integer, parameter, public :: mexax_base_midpoint = 1 !! (M), h²-extrapolation (default)
    integer, parameter, public :: mexax_base_euler = 2    !! (E), h-extrapolation (MEXX21)
    !> At most this many extrapolation columns (KDMAX).
    integer, parameter, public :: mexax_max_columns = 12
    !> Order and step-size controls (docs/theory.md §7.3).
    integer, parameter, public :: mexax_control_hairer = 1    !! ODEX / SEULEX [HNW93; HW96]
    integer, parameter, public :: mexax_control_deuflhard = 2 !! Deuflhard's [Deu83]

    ! Step-number sequence of (E) (LNPE95: MEXX21); (M) uses n_j = 2j, the
    ! default sequence of ODEX [HNW93 II.9].
    integer, parameter :: euler_sequence(mexax_max_columns) = &
        [2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 30]
    ! Safety factors and limits of the column step sizes: the original's
    ! values (docs/theory.md §7.3), for both bases. SAFE2, FAC1 and FAC2 are
    ! SEULEX's; ODEX has 0.94, 0.02, 4; SAFE1 is 0.65 in ODEX, 0.6 in SEULEX.
    real(wp), parameter :: safe1 = 0.8_wp, safe2 = 0.93_wp
    real(wp), parameter :: fac1 = 0.1_wp, fac2 = 4.0_wp
    ! Order decrease / increase thresholds FAC3, FAC4 on the work per unit
    ! step: ODEX 0.8, 0.9 (M); SEULEX 0.7, 0.9 (E).
    real(wp), parameter :: midpoint_fac3 = 0.8_wp, midpoint_fac4 = 0.9_wp
    real(wp), parameter :: euler_fac3 = 0.7_wp, euler_fac4 = 0.9_wp
    ! Divergence of the tableau: err_j ≥ max(4 err_{j−1}, 1), j > 2
    ! (ODEX and SEULEX alike).
    real(wp), parameter :: divergence_ratio = 4.0_wp
    ! The work of column 1 is n_1 + this (docs/theory.md §7.3; ODEX: 1).
    integer, parameter :: work_offset = 4
    ! Start column from −0.6 log10(tol) + 1.5, with tol = rtol (ODEX, (M)) or
    ! rtol + atol (SEULEX, (E)); (E) within [3, KDMAX − 2] (SEULEX).
    real(wp), parameter :: start_slope = -0.6_wp, start_offset = 1.5_wp
    integer, parameter :: euler_start_min = 3
    ! Deuflhard's model accuracy ε = min rtol within these bounds (own)
    real(wp), parameter :: model_eps_min = 1.0e-14_wp, model_eps_max = 0.1_wp

    !> The control state of one integration: sequence, work, and per column
    !> the error estimate, the step size it proposes and the work per unit step.
    type, public :: control_t
        integer :: base = mexax_base_midpoint
        integer :: scheme = mexax_control_hairer !! mexax_control_hairer | _deuflhard
        integer :: km = 0                   !! KDMAX
        real(wp) :: varpi = 2.0_wp          !! the expansion is in h^varpi
        real(wp) :: order_down = midpoint_fac3, order_up = midpoint_fac4 !! FAC3, FAC4
        integer, allocatable :: nj(:)       !! step numbers n_j
        real(wp), allocatable :: awork(:)   !! A_j
        real(wp), allocatable :: err(:)     !! err_j
        real(wp), allocatable :: hh(:)      !! H_j
        real(wp), allocatable :: work(:)    !! W_j = A_j / H_j
        ! Deuflhard's control only
        real(wp), allocatable :: fac(:)     !! step factor H/H_j of column j
        real(wp), allocatable :: alpha(:, :) !! α(j, q) at the run's tolerance
        integer :: qmax = 0                 !! the highest column worth computing
        real(wp) :: h_retry = 0.0_wp        !! |H| after the monitor's rejection
    contains
        procedure :: init => control_init
        procedure :: start_column
        procedure :: column_step
        procedure :: diverged
        procedure :: monitor_rejects
        procedure :: hope_rejects
        procedure :: window
        procedure :: order_after_accept
        procedure :: order_after_reject
    end type control_t

contains

    !> Sequence, work and constants of `base` and `scheme` for `km` columns.
    subroutine control_init(self, base, km, scheme)
        class(control_t), intent(inout) :: self
        integer, intent(in) :: base, km
        integer, intent(in) :: scheme !! mexax_control_hairer | _deuflhard
        integer :: j
        self%base = base
        self%km = km
        self%scheme = scheme
        if (allocated(self%nj)) deallocate (self%nj, self%awork, self%err, self%hh, self%work, &
                                            self%fac, self%alpha)
        allocate (self%nj(km), self%awork(km), self%err(km), self%hh(km), self%work(km), &
                  self%fac(km), self%alpha(km, km))
        if (base == mexax_base_euler) then
            self%nj = euler_sequence(1:km)
            self%varpi = 1.0_wp
            self%order_down = euler_fac3
            self%order_up = euler_fac4
        else
            self%nj = [(2 * j, j = 1, km)]
            self%varpi = 2.0_wp
            self%order_down = midpoint_fac3
            self%order_up = midpoint_fac4
        end if
        self%awork(1) = real(self%nj(1) + work_offset, wp)
        do j = 2, km
            self%awork(j) = self%awork(j - 1) + real(self%nj(j), wp)
        end do
        self%err = 0.0_wp
        self%hh = 0.0_wp
        self%work = 0.0_wp
        self%fac = 0.0_wp
        self%alpha = 1.0_wp
    end subroutine control_init

    !> The first column k: ODEX from min rtol (M), SEULEX from min(rtol +
    !> atol) within [3, KDMAX − 2] (E); always within [2, KDMAX − 1].
    !> Deuflhard's control: the model's α at ε = min rtol, and its highest
    !> column worth computing, where the first step's window lies [Deu83].
    integer function start_column(self, rtol, atol) result(k)
        class(control_t), intent(inout) :: self
        real(wp), intent(in) :: rtol(:), atol(:)
        integer :: j
        if (self%scheme == mexax_control_deuflhard) then
            ! ε = TOL [Deu83], kept below 1 and above round-off (α ≥ 1 needs ε < 1)
            self%alpha = alpha_table(self%awork, [(1.0_wp / error_exponent(self, j), &
                j = 1, self%km)], min(max(minval(rtol), model_eps_min), model_eps_max))
            self%qmax = window_top(self%awork, self%alpha, self%km)
            k = self%qmax
            return
        end if
        if (self%base == mexax_base_euler) then
            k = int(start_slope * log10(minval(rtol + atol)) + start_offset)
            k = max(euler_start_min, min(self%km - 2, k))
        else
            k = int(start_slope * log10(minval(rtol)) + start_offset)
        end if
        k = max(2, min(k, self%km - 1))
    end function start_column

    !> From err_j of a macro step `big_h`: the step H_j that column j
    !> proposes and its work per unit step W_j. The exponent is 1/j for (E)
    !> (SEULEX: err_j = O(H^j)) and 1/(2j − 1) for (M) (ODEX).
    subroutine column_step(self, j, big_h, hmax)
        class(control_t), intent(inout) :: self
        integer, intent(in) :: j
        real(wp), intent(in) :: big_h, hmax
        real(wp) :: expo, fmin, fac
        expo = error_exponent(self, j)
        if (self%scheme == mexax_control_deuflhard) then
            ! [Deu83]: H_j aims at ρ TOL; the growth bounded
            self%fac(j) = (self%err(j) / deuflhard_safety)**expo
            self%hh(j) = min(abs(big_h) / max(self%fac(j), 1.0_wp / deuflhard_growth), hmax)
            self%work(j) = self%awork(j) / self%hh(j)
            return
        end if
        fmin = fac1**expo
        fac = min(fac2 / fmin, max(fmin, (self%err(j) / safe1)**expo / safe2))
        self%hh(j) = min(abs(big_h) / fac, hmax)
        self%work(j) = self%awork(j) / self%hh(j)
    end subroutine column_step

    !> 1/γ_j, with err_j = O(H^γ_j): γ_j = j for (E), 2j − 1 for (M).
    pure real(wp) function error_exponent(self, j)
        class(control_t), intent(in) :: self
        integer, intent(in) :: j
        if (self%base == mexax_base_euler) then
            error_exponent = 1.0_wp / j
        else
            error_exponent = 1.0_wp / (2 * j - 1)
        end if
    end function error_exponent

    !> Deuflhard's convergence monitor on column j of a step planned for
    !> column q (flexmbs_dae_mexax_deuflhard's window_test): window_continue,
    !> window_accept or window_reject (then h_retry holds the next |H|).
    integer function window(self, j, q, first, h) result(decision)
        class(control_t), intent(inout) :: self
        integer, intent(in) :: j, q
        logical, intent(in) :: first
        real(wp), intent(in) :: h
        call window_test(self%err(j), self%fac(j), self%alpha, j, q, self%qmax, first, &
                         abs(h), decision, self%h_retry)
    end function window

    !> The tableau diverges in column j > 2 (ODEX, SEULEX): restart with H/2.
    logical function diverged(self, j)
        class(control_t), intent(in) :: self
        integer, intent(in) :: j
        diverged = .false.
        if (j > 2) diverged = self%err(j) >= max(divergence_ratio * self%err(j - 1), 1.0_wp)
    end function diverged

    !> Convergence monitor on column k − 1: column k + 1 is not expected to
    !> converge. ODEX: err_{k−1} > (n_k n_{k+1}/4)²; SEULEX: > 4 n_k n_{k+1}.
    logical function monitor_rejects(self, k)
        class(control_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp) :: nn
        nn = real(self%nj(k), wp) * real(self%nj(k + 1), wp)
        if (self%base == mexax_base_euler) then
            monitor_rejects = self%err(k - 1) > 4.0_wp * nn
        else
            monitor_rejects = self%err(k - 1) > (nn / 4.0_wp)**2
        end if
    end function monitor_rejects

    !> Hope test on column k: no hope that column k + 1 converges. ODEX:
    !> err_k > (n_{k+1}/2)²; SEULEX: > 2 n_{k+1}. No column k + 1 beyond KDMAX.
    logical function hope_rejects(self, k)
        class(control_t), intent(in) :: self
        integer, intent(in) :: k
        if (k + 1 > self%km) then
            hope_rejects = .true.
        else if (self%base == mexax_base_euler) then
            hope_rejects = self%err(k) > 2.0_wp * real(self%nj(k + 1), wp)
        else
            hope_rejects = self%err(k) > (real(self%nj(k + 1), wp) / 2.0_wp)**2
        end if
    end function hope_rejects

    !> After acceptance with column kc, planned column k: the next column and
    !> step size (ODEX = SEULEX). After a rejected step neither grows.
    subroutine order_after_accept(self, kc, k, after_reject, h, hmax)
        class(control_t), intent(in) :: self
        integer, intent(in) :: kc
        integer, intent(inout) :: k         !! planned column in, next column out
        logical, intent(in) :: after_reject !! the previous attempt was rejected
        real(wp), intent(inout) :: h        !! |H| of the step in, next |H| out
        real(wp), intent(in) :: hmax
        integer :: kopt
        if (self%scheme == mexax_control_deuflhard) then
            call order_after_accept_window(self%awork, self%hh, self%work, self%alpha, kc, &
                                           self%qmax, after_reject, abs(h), hmax, k, h)
            return
        end if
        associate (w => self%work, km => self%km)
            if (kc == 2) then
                kopt = min(3, km - 1)
                if (after_reject) kopt = 2
            else if (kc <= k) then
                kopt = kc
                if (w(kc - 1) < self%order_down * w(kc)) kopt = kc - 1
                if (w(kc) < self%order_up * w(kc - 1)) kopt = min(kc + 1, km - 1)
            else
                kopt = kc - 1
                if (kc > 3) then
                    if (w(kc - 2) < self%order_down * w(kc - 1)) kopt = kc - 2
                end if
                if (w(kc) < self%order_up * w(kopt)) kopt = min(kc, km - 1)
            end if
            kopt = max(kopt, 2)
            if (after_reject) then
                k = max(min(kopt, kc), 2)
                h = min(abs(h), self%hh(k))
                return
            end if
            if (kopt <= kc) then
                h = self%hh(kopt)
            else if (kc < k .and. w(kc) < self%order_up * w(kc - 1)) then
                h = self%hh(kc) * self%awork(kopt + 1) / self%awork(kc)
            else
                h = self%hh(kc) * self%awork(kopt) / self%awork(kc)
            end if
            k = kopt
        end associate
    end subroutine order_after_accept

    !> After a rejection in column kc: the column k to retry with (lowered
    !> when the lower order is cheaper) and its step size |H| = H_k.
    !> Deuflhard's control keeps the column and takes the monitor's step.
    subroutine order_after_reject(self, kc, k, h)
        class(control_t), intent(in) :: self
        integer, intent(in) :: kc
        integer, intent(inout) :: k
        real(wp), intent(out) :: h
        if (self%scheme == mexax_control_deuflhard) then
            h = self%h_retry
            return
        end if
        k = max(min(k, kc, self%km - 1), 2)
        if (k > 2) then
            if (self%work(k - 1) < self%order_down * self%work(k)) k = k - 1
        end if
        h = self%hh(k)
    end subroutine order_after_reject
end module flexmbs_dae_mexax_control
