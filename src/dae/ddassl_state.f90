!> DDASSL's state (docs/theory.md §6): the classic code's constants, the
!> state an integration carries from step to step (`ddassl_work_t`), the
!> part of the solver that begin and step work on (`ddassl_engine_t`:
!> switches, counters and that state), and the weights and norms of §2.7
!> and §2.10.
module flexmbs_dae_ddassl_state
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_multiplier_scaling, only: multiplier_kappa
    use flexmbs_dae_rejections, only: rejections_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private
    public :: set_weights, vnorm, newton_norm, enorm

    integer, parameter, public :: ddassl_max_order = 5 !! §2.2: MAXORD ≤ 5
    integer, parameter, public :: mx = ddassl_max_order + 1 !! coefficient arrays hold k+1 entries

    ! Corrector (§2.3).
    real(wp), parameter, public :: s_fresh = 100.0_wp     !! §2.3: s = 100 with a new PD or cj
    real(wp), parameter, public :: rate_max = 0.9_wp      !! §2.3: ρ > 0.9 fails
    real(wp), parameter, public :: conv_tol = 0.33_wp     !! §2.3: s·d ≤ 0.33 converges
    integer, parameter, public :: max_iter = 4            !! §2.3: m ≥ 4 fails
    real(wp), parameter, public :: cj_ratio_low = 0.6_wp  !! §2.3: (1 − 0.25)/(1 + 0.25)
    real(wp), parameter, public :: roundoff_conv = 100.0_wp !! §2.3: d ≤ 100·uround·pnorm
    ! Error test, order and step selection (§2.4, §2.6).
    real(wp), parameter, public :: est_offset = 1.0e-4_wp !! §2.4: r = (2 est + 1e-4)^(−1/(k+1))
    !> §2.4: k = 2 lowers if TERKM1 ≤ 0.5 TERK; k = 1 raises if TERKP1 < 0.5 TERK.
    real(wp), parameter, public :: half = 0.5_wp
    real(wp), parameter, public :: r_raise = 2.0_wp       !! §2.4: r ≥ 2 doubles h
    real(wp), parameter, public :: r_min = 0.5_wp, r_max = 0.9_wp !! §2.4: clamp(r, 0.5, 0.9)
    real(wp), parameter, public :: fail_safety = 0.9_wp   !! §2.6: 0.9 (2 est + 1e-4)^(...)
    real(wp), parameter, public :: fail_min = 0.25_wp     !! §2.6: clamp(·, 0.25, 0.9)
    real(wp), parameter, public :: fail_quarter = 0.25_wp !! §2.6: h/4
    integer, parameter, public :: max_ncf = 10            !! §2.6: ncf ≥ 10 gives up
    integer, parameter, public :: max_nsf = 3             !! §2.6: nsf ≥ 3 gives up
    integer, parameter, public :: nef_after_conv = 3      !! §2.6: −9 when nef ≥ 3
    ! Driver (§2.7).
    real(wp), parameter, public :: h0_fraction = 0.001_wp !! §2.7: H0 = 0.001 |TOUT − T|
    real(wp), parameter, public :: h0_slope = 0.5_wp      !! §2.7: H0 ≤ 0.5/‖y0'‖
    real(wp), parameter, public :: hmin_factor = 4.0_wp   !! §2.7: hmin = 4 uround max(|T|, |TOUT|)
    real(wp), parameter, public :: tstop_tol = 100.0_wp   !! §2.7: |T_N − TSTOP| ≤ 100 uround (…)
    ! DDAINI (§2.8).
    integer, parameter, public :: ini_max_iter = 10       !! §2.8: at most 10 iterations
    integer, parameter, public :: ini_jac_every = 5       !! §2.8: new PD every 5 iterations
    real(wp), parameter, public :: ini_s = 1.0e6_wp       !! §2.8: s = 1e6 after each PD
    real(wp), parameter, public :: ini_damp = 0.75_wp     !! §2.8: residual × 0.75
    integer, parameter, public :: ini_max_nef = 10        !! §2.8 [R]: nef ≥ 10 gives up
    real(wp), parameter, public :: ini_r_min = 0.1_wp, ini_r_max = 0.5_wp !! §2.8 [R]

    !> The classic code's counters, IWORK(11..15).
    type, public :: ddassl_native_t
        integer :: nst = 0, nre = 0, nje = 0, netf = 0, ncfn = 0
    end type ddassl_native_t

    ! Classic IDID of a failure (§2.11), recorded in `ddassl_work_t%failure`.
    integer, parameter, public :: ddassl_fail_none = 0
    integer, parameter, public :: ddassl_fail_tolerances = -2 !! rtol, atol scaled up
    integer, parameter, public :: ddassl_fail_weights = -3    !! some wt_i ≤ 0
    integer, parameter, public :: ddassl_fail_error_test = -6 !! error test, |h| < hmin
    integer, parameter, public :: ddassl_fail_corrector = -7
    integer, parameter, public :: ddassl_fail_singular = -8
    integer, parameter, public :: ddassl_fail_after_error_test = -9
    integer, parameter, public :: ddassl_fail_residual = -10  !! IRES = −1 repeatedly
    integer, parameter, public :: ddassl_fail_stop = -11      !! IRES = −2
    integer, parameter, public :: ddassl_fail_initial = -12   !! DDAINI

    !> Everything a DDASSL integration carries from step to step: the BDF
    !> history and coefficients, the Newton state, tolerances and weights,
    !> the iteration matrix and its factors. It lives in `ddassl_t%work`
    !> between calls, so that a driver can stop after any step and resume
    !> (the classic face's INFO(3) and continuation calls); the names are
    !> those of docs/theory.md §6. The classic face reads and sets its
    !> components as the classic code's RWORK and IWORK.
    type, public :: ddassl_work_t
        logical :: ready = .false.       !! begin succeeded; step may be called
        integer :: n = 0, pmax = 0
        integer :: k = 0, kold = 0, ns = 0, iphase = 0, jcalc = 0, knew = 0
        integer :: nef = 0, ncf = 0, nsf = 0
        real(wp) :: tn = 0.0_wp, h = 0.0_wp, hold = 0.0_wp
        real(wp) :: cj = 0.0_wp, cjlast = 0.0_wp, cjold = 0.0_wp, s = 0.0_wp
        real(wp) :: hmin = 0.0_wp, hmax = huge(1.0_wp), uround = epsilon(1.0_wp)
        real(wp) :: t0 = 0.0_wp, h_fixed = 0.0_wp
        real(wp) :: est = 0.0_wp, erkm1 = 0.0_wp, terkm1 = 0.0_wp, terk = 0.0_wp
        real(wp) :: tol_scale = 1.0_wp   !! factor applied to rtol, atol (failure −2)
        integer :: failure = ddassl_fail_none !! ddassl_fail_* of the last failure
        logical :: fd = .false., ires_stop = .false.
        logical :: direct = .false.      !! PD from the problem as it stands (classic JAC)
        real(wp) :: psi(mx) = 0.0_wp, alpha(mx) = 0.0_wp, beta(mx) = 0.0_wp
        real(wp) :: gamma(mx) = 0.0_wp, sigma(mx) = 0.0_wp
        real(wp), allocatable :: phi(:, :), delta(:), e(:), wt(:), rtol(:), atol(:)
        real(wp), allocatable :: ytmp(:), yptmp(:), ysave(:), ypsave(:)
        logical, allocatable :: in_test(:)
        integer, allocatable :: newton_power(:) !! h^p δ in the Newton test (p = class - 1)
        type(matrix_t), allocatable :: amat, bmat
        class(linear_solver_t), allocatable :: ls
        type(status_t) :: model_failure !! the model's last refusal in this step
    end type ddassl_work_t

    !> What begin and step (the modules flexmbs_dae_ddassl_*) read and write:
    !> the switches of the classic code they follow, the counters of the
    !> last integration and the state between steps. `ddassl_t` extends it
    !> with the drivers and their own switches.
    type, extends(dae_solver_t), abstract, public :: ddassl_engine_t
        logical :: netlib = .false.              !! later netlib revision (§2.9) instead of SLATEC
        logical :: exclude_index23 = .true.      !! index-2/3 out of the error test (§2.10)
        logical :: nonnegative = .false.         !! enforce y ≥ 0 (INFO(10) = 1)
        !> Order studies: steps of size h0, every converged step accepted, the
        !> order raised each step to pmax (the start-up then limits the global
        !> error to O(h0²)) or, with `start_history`, BDF-pmax throughout.
        logical :: fixed_step = .false.
        !> With fixed_step: y(t0 − j·h0) in column j = 0..pmax. The integration
        !> then starts at order pmax from this exact history, so every step is
        !> BDF-pmax with constant step (order studies).
        real(wp), allocatable :: start_history(:, :)
        real(wp) :: uround = epsilon(1.0_wp)     !! D1MACH(4)
        ! Results of the last integration.
        type(ddassl_native_t) :: native
        integer :: ndec = 0          !! successful PD factorisations
        integer :: nsol = 0          !! solves (corrector and DDAINI)
        integer :: nfe_jac = 0       !! residual calls of difference PDs
        type(rejections_t) :: rejections !! the NETF + NCFN failed attempts by cause
        character(len=:), allocatable :: warning !! for stats%warning (§6: index 3)
        type(ddassl_work_t) :: work  !! the state between steps (begin/step)
    end type ddassl_engine_t

contains

    !> §2.7: wt_i = rtol_i |v_i| + atol_i.
    subroutine set_weights(w, v)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(in) :: v(:)
        w%wt = w%rtol * abs(v) + w%atol
    end subroutine set_weights

    !> §2.7: ‖v‖ = vmax ((1/n) Σ ((v_i/wt_i)/vmax)²)^(1/2).
    real(wp) function vnorm(w, v)
        type(ddassl_work_t), intent(in) :: w
        real(wp), intent(in) :: v(:)
        real(wp) :: vmax, acc
        integer :: i
        vmax = 0.0_wp
        do i = 1, w%n
            vmax = max(vmax, abs(v(i) / w%wt(i)))
        end do
        if (.not. ieee_is_finite(vmax)) then
            vnorm = vmax
            return
        end if
        vnorm = 0.0_wp
        if (vmax <= 0.0_wp) return
        acc = 0.0_wp
        do i = 1, w%n
            acc = acc + ((v(i) / w%wt(i)) / vmax)**2
        end do
        vnorm = vmax * sqrt(acc / real(w%n, wp))
    end function vnorm

    !> The Newton-test norm: the multipliers out of the error test (index
    !> 2 and 3) count as h^(k-1) δ / κ for index k: h^(k-1) δ is their
    !> effect on the components of index 1 (a correction δλ changes the
    !> velocities by about h M⁻¹Gᵀδλ), as RADAU5 scales them, and κ keeps
    !> them as accurate as before at moderate tolerances. Measured as δ
    !> against their tolerance, the round-off of δ (amplified like 1/h)
    !> stopped tight runs at t0 (the four-bar, the five-body at 1e-10).
    !> `w%ytmp` is its scratch, so v must be another array.
    real(wp) function newton_norm(w, v)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(in) :: v(:)
        integer :: i
        real(wp) :: kappa
        if (all(w%newton_power == 0)) then
            newton_norm = vnorm(w, v)
            return
        end if
        kappa = multiplier_kappa(minval(w%rtol))
        do i = 1, w%n
            w%ytmp(i) = v(i)
            if (w%newton_power(i) > 0) w%ytmp(i) = abs(w%h)**w%newton_power(i) * v(i) / kappa
        end do
        newton_norm = vnorm(w, w%ytmp)
    end function newton_norm

    !> The error-test norm: excluded components zeroed, RMS still over n
    !> (§2.10). `w%ytmp` is its scratch, so v must be another array.
    real(wp) function enorm(w, v)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(in) :: v(:)
        integer :: i
        do i = 1, w%n
            if (w%in_test(i)) then
                w%ytmp(i) = v(i)
            else
                w%ytmp(i) = 0.0_wp
            end if
        end do
        enorm = vnorm(w, w%ytmp)
    end function enorm
end module flexmbs_dae_ddassl_state
