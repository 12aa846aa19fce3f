!> `DDASSL`: variable-order, variable-step BDF for G(t, y, y') = 0.
!>
!> Implemented from [BCP89, ch. 5] as specified in docs/theory.md §6:
!> fixed-leading-coefficient BDF of orders 1..pmax in modified divided
!> differences, a modified Newton corrector with iteration matrix
!> PD = ∂G/∂y + cj ∂G/∂y' reused across steps, error estimates at orders
!> k−2..k+1 deciding order and step, and the BDF interpolant for output.
!> The SLATEC revision 910624 is the default; `netlib` switches to the
!> later revision (§2.9). A `dae_problem_t` is integrated as G = M y' − F.
module flexmbs_dae_ddassl
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_step_too_small, reason_max_steps, reason_singular_matrix, &
        reason_newton_failure, reason_user_function, reason_non_finite, reason_det_f
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_dense, storage_identity
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_residual_problem, only: residual_problem_t, dae_residual_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t, index3_warning, projection_refusal
    use flexmbs_dae_multiplier_scaling, only: multiplier_kappa
    use flexmbs_dae_rejections, only: rejections_t, cause_error_test, cause_newton_diverged, &
        cause_newton_slow, cause_singular_matrix, cause_model_refused
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private

    integer, parameter, public :: ddassl_max_order = 5 !! §2.2: MAXORD ≤ 5
    integer, parameter :: mx = ddassl_max_order + 1    !! coefficient arrays hold k+1 entries

    ! Corrector (§2.3).
    real(wp), parameter :: s_fresh = 100.0_wp         !! §2.3: s = 100 with a new PD or cj
    real(wp), parameter :: rate_max = 0.9_wp          !! §2.3: ρ > 0.9 fails
    real(wp), parameter :: conv_tol = 0.33_wp         !! §2.3: s·d ≤ 0.33 converges
    integer, parameter :: max_iter = 4                !! §2.3: m ≥ 4 fails
    real(wp), parameter :: cj_ratio_low = 0.6_wp      !! §2.3: (1 − 0.25)/(1 + 0.25)
    real(wp), parameter :: roundoff_conv = 100.0_wp   !! §2.3: d ≤ 100·uround·pnorm
    ! Error test, order and step selection (§2.4, §2.6).
    real(wp), parameter :: est_offset = 1.0e-4_wp     !! §2.4: r = (2 est + 1e-4)^(−1/(k+1))
    !> §2.4: k = 2 lowers if TERKM1 ≤ 0.5 TERK; k = 1 raises if TERKP1 < 0.5 TERK.
    real(wp), parameter :: half = 0.5_wp
    real(wp), parameter :: r_raise = 2.0_wp           !! §2.4: r ≥ 2 doubles h
    real(wp), parameter :: r_min = 0.5_wp, r_max = 0.9_wp  !! §2.4: clamp(r, 0.5, 0.9)
    real(wp), parameter :: fail_safety = 0.9_wp       !! §2.6: 0.9 (2 est + 1e-4)^(...)
    real(wp), parameter :: fail_min = 0.25_wp         !! §2.6: clamp(·, 0.25, 0.9)
    real(wp), parameter :: fail_quarter = 0.25_wp     !! §2.6: h/4
    integer, parameter :: max_ncf = 10                !! §2.6: ncf ≥ 10 gives up
    integer, parameter :: max_nsf = 3                 !! §2.6: nsf ≥ 3 gives up
    integer, parameter :: nef_after_conv = 3          !! §2.6: −9 when nef ≥ 3
    ! Driver (§2.7).
    real(wp), parameter :: h0_fraction = 0.001_wp     !! §2.7: H0 = 0.001 |TOUT − T|
    real(wp), parameter :: h0_slope = 0.5_wp          !! §2.7: H0 ≤ 0.5/‖y0'‖
    real(wp), parameter :: hmin_factor = 4.0_wp       !! §2.7: hmin = 4 uround max(|T|, |TOUT|)
    real(wp), parameter :: tstop_tol = 100.0_wp       !! §2.7: |T_N − TSTOP| ≤ 100 uround (…)
    ! DDAINI (§2.8).
    integer, parameter :: ini_max_iter = 10           !! §2.8: at most 10 iterations
    integer, parameter :: ini_jac_every = 5           !! §2.8: new PD every 5 iterations
    real(wp), parameter :: ini_s = 1.0e6_wp           !! §2.8: s = 1e6 after each PD
    real(wp), parameter :: ini_damp = 0.75_wp         !! §2.8: residual × 0.75
    integer, parameter :: ini_max_nef = 10            !! §2.8 [R]: nef ≥ 10 gives up
    real(wp), parameter :: ini_r_min = 0.1_wp, ini_r_max = 0.5_wp !! §2.8 [R]

    !> The BDF interpolant of the last accepted step (§2.5).
    type, extends(dense_output_t), public :: ddassl_dense_t
        real(wp) :: tn = 0.0_wp      !! time of the last accepted step
        integer :: kold = 0          !! order of that step
        real(wp) :: psi(mx) = 0.0_wp !! ψ_i = t_n − t_{n−i}
        real(wp), allocatable :: phi(:, :) !! modified divided differences φ_1..φ_{kold+1}
    contains
        procedure :: evaluate => dense_evaluate
        procedure :: interpolate => dense_interpolate
        procedure :: order => dense_order
    end type ddassl_dense_t

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
    !> those of docs/theory.md §6.
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
    end type ddassl_work_t

    integer, parameter :: action_begin = 1, action_step = 2

    !> DDASSL settings (the INFO switches of the classic code that make
    !> sense in the modern core) and the results of the last integration.
    type, extends(dae_solver_t), public :: ddassl_t
        logical :: netlib = .false.              !! later netlib revision (§2.9) instead of SLATEC
        logical :: exclude_index23 = .true.      !! index-2/3 out of the error test (§2.10)
        logical :: initial_derivative = .false.  !! y' by DDAINI (§2.8, INFO(11) = 1)
        logical :: nonnegative = .false.         !! enforce y ≥ 0 (INFO(10) = 1)
        logical :: tstop = .false.               !! never step past t_end (INFO(4) = 1)
        !> H0 rule of §2.7 with TOUT = the first output time (as the classic
        !> driver called with that TOUT) instead of t_end.
        logical :: h0_from_first_output = .false.
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
        integer :: k_last = 0        !! order of the last step (IWORK(8))
        integer :: k_next = 0        !! order for the next step (IWORK(7))
        real(wp) :: h_next = 0.0_wp  !! next step size (RWORK(3))
        type(ddassl_dense_t) :: dense
        type(ddassl_work_t) :: work  !! the state between steps (begin/step)
    contains
        procedure :: integrate_dae => ddassl_integrate
        procedure :: integrate_residual => ddassl_integrate_residual
        procedure :: begin => ddassl_begin
        procedure :: step => ddassl_step
        procedure :: interpolate => ddassl_interpolate
        procedure :: name => ddassl_name
        procedure :: step_counts => ddassl_step_counts
    end type ddassl_t

contains

    function ddassl_name(self) result(name)
        class(ddassl_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'ddassl'
    end function ddassl_name

    !> Live counts for a display: DDASSL's NST counts accepted steps only.
    subroutine ddassl_step_counts(self, attempted, accepted)
        class(ddassl_t), intent(in) :: self
        integer, intent(out) :: attempted, accepted
        attempted = self%native%nst
        accepted = self%native%nst
    end subroutine ddassl_step_counts

    subroutine dense_evaluate(self, s, y)
        class(ddassl_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        call interpolate_history(self%phi, self%psi, self%kold, self%tn, s, y)
    end subroutine dense_evaluate

    !> The BDF order of the last accepted step.
    integer function dense_order(self)
        class(ddassl_dense_t), intent(in) :: self
        dense_order = self%kold
    end function dense_order

    !> y(s) and y'(s).
    subroutine dense_interpolate(self, s, y, yp)
        class(ddassl_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:), yp(:)
        call interpolate_history(self%phi, self%psi, self%kold, self%tn, s, y, yp)
    end subroutine dense_interpolate

    !> §2.5: y(t̄) = Σ c_j φ_j, y'(t̄) = Σ d_j φ_j.
    pure subroutine interpolate_history(phi, psi, kold, tn, tbar, y, yp)
        real(wp), intent(in) :: phi(:, :), psi(:)
        integer, intent(in) :: kold
        real(wp), intent(in) :: tn, tbar
        real(wp), intent(out) :: y(:)
        real(wp), intent(out), optional :: yp(:)
        real(wp) :: tau, c, d, g, psim2
        integer :: j
        tau = tbar - tn
        c = 1.0_wp
        d = 0.0_wp
        y = phi(:, 1)
        if (present(yp)) yp = 0.0_wp
        psim2 = 0.0_wp
        do j = 2, kold + 1
            if (j > 2) psim2 = psi(j - 2)
            g = (tau + psim2) / psi(j - 1)
            d = d * g + c / psi(j - 1)
            c = c * g
            y = y + c * phi(:, j)
            if (present(yp)) yp = yp + d * phi(:, j)
        end do
    end subroutine interpolate_history

    !> Integrate M y' = F(t, y) as G = M y' − F = 0 (docs/theory.md §6).
    !> Without yp, y' comes from `problem%consistent_initial` or, when the
    !> problem offers none or `initial_derivative` is set, from DDAINI.
    subroutine ddassl_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ddassl_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)
        call run_dae(self, problem, t, y, t_end, options, stats, status, sink, yp)
    end subroutine ddassl_integrate

    !> `target` lets the wrapper point at the problem for this call.
    subroutine run_dae(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ddassl_t), intent(inout) :: self
        class(dae_problem_t), intent(inout), target :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)
        type(dae_residual_t) :: res
        real(wp), allocatable :: ypw(:)
        type(status_t) :: local
        logical :: ddaini
        integer :: stat

        if (problem%has_projection()) then
            call status%set(status_bad_input, projection_refusal('ddassl', 'radau5'))
            return
        end if
        if (problem%n <= 0 .or. size(y) /= problem%n) then
            call status%set(status_bad_input, 'ddassl: size of y differs from problem%n')
            return
        end if
        res%problem => problem
        res%n = problem%n
        allocate (ypw(problem%n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'ddassl initial derivative', int(problem%n, i8), 8)
            return
        end if
        ddaini = self%initial_derivative
        if (present(yp)) then
            if (size(yp) /= problem%n) then
                call status%set(status_bad_input, 'ddassl: size of yp differs from problem%n')
                return
            end if
            ypw = yp
        else
            ypw = 0.0_wp
            if (.not. ddaini) then
                call problem%consistent_initial(t, y, ypw, local)
                if (.not. local%ok() .and. problem%mass_storage() == storage_identity) then
                    ! An ODE: y' = F(t0, y0) is consistent (the caller's job in
                    ! the classic code, hence not counted in NRE).
                    call local%clear()
                    call problem%rhs(t, y, ypw, local)
                end if
                if (.not. local%ok()) then
                    ypw = 0.0_wp
                    ddaini = .true.
                end if
            end if
        end if
        call self%integrate_residual(res, t, y, ypw, t_end, options, stats, status, sink, &
            initial_derivative=ddaini)
        if (present(yp)) yp = ypw
        nullify (res%problem)
    end subroutine run_dae

    !> Integrate G(t, y, y') = 0 from (t, y, yp) to t_end (docs/theory.md §6).
    !> On return t, y, yp hold the last point reached (t_end on success).
    subroutine ddassl_integrate_residual(self, res, t, y, yp, t_end, options, stats, status, &
                                         sink, initial_derivative)
        class(ddassl_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        logical, intent(in), optional :: initial_derivative !! overrides the component

        real(wp), allocatable :: y0(:), ytmp(:)
        type(timer_t) :: timer
        integer :: iout, nout, stat
        real(wp) :: dir, tout_h0, hmin
        logical :: want_steps, stop_requested, done

        call timer%start()
        stats%t_reached = t
        dir = sign(1.0_wp, t_end - t)
        tout_h0 = t_end
        nout = 0
        if (allocated(options%output_times)) nout = size(options%output_times)
        if (self%h0_from_first_output) then
            do iout = 1, nout
                if ((options%output_times(iout) - t) * dir > 0.0_wp) then
                    tout_h0 = options%output_times(iout)
                    exit
                end if
            end do
        end if
        hmin = hmin_factor * self%uround * max(abs(t), abs(tout_h0))
        if (abs(t_end - t) < hmin .or. t_end == t) then
            call status%set(status_bad_input, 'ddassl: t_end = ' // real_text(t_end) // &
                ' is too close to t = ' // real_text(t))
            return
        end if
        y0 = y
        if (self%tstop) then
            call self%begin(res, t, y, yp, tout_h0, options, status, initial_derivative, t_end)
        else
            call self%begin(res, t, y, yp, tout_h0, options, status, initial_derivative)
        end if
        if (.not. allocated(self%work%phi)) return  ! bad input: nothing was set up
        if (allocated(self%dense%phi)) deallocate (self%dense%phi)
        allocate (ytmp(size(y)), self%dense%phi(size(self%work%phi, 1), size(self%work%phi, 2)), &
            stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'ddassl output work', &
                size(y, kind=i8) + size(self%work%phi, kind=i8), 8)
            call finish()
            return
        end if

        ! Outputs at t0.
        want_steps = .false.
        stop_requested = .false.
        if (present(sink)) want_steps = sink%wants_steps()
        iout = 1
        do while (iout <= nout .and. status%ok())
            if ((options%output_times(iout) - t) * dir > 0.0_wp) exit
            if (present(sink) .and. options%output_times(iout) == t) &
                call sink%output(t, y0, status)
            iout = iout + 1
        end do
        if (.not. status%ok()) then
            call finish()
            return
        end if
        associate (w => self%work)
            if (want_steps) then
                call copy_dense()
                call sink%step(1, w%tn, w%tn, y, self%dense, stop_requested, status)
                if (.not. status%ok()) then
                    call finish()
                    return
                end if
            end if
            done = (w%tn - t_end) * dir >= 0.0_wp

            main: do while (.not. done)
                if (self%native%nst >= options%max_steps) then
                    call status%set(status_solver_failure, 'ddassl: more than ' // &
                        int_text(options%max_steps) // ' steps needed at t = ' // &
                        real_text(w%tn) // ' (h = ' // real_text(w%h) // ')', reason_max_steps)
                    exit main
                end if
                call self%step(res, y, yp, t_end, status, self%tstop)
                if (.not. status%ok()) then
                    call self%interpolate(w%tn, y, yp)
                    exit main
                end if

                ! ---- output ----
                stats%t_reached = w%tn
                stats%h_last = w%hold
                do while (iout <= nout)
                    if ((options%output_times(iout) - w%tn) * dir > 0.0_wp) exit
                    if (present(sink)) then
                        call self%interpolate(options%output_times(iout), ytmp)
                        call sink%output(options%output_times(iout), ytmp, status)
                    end if
                    iout = iout + 1
                    if (.not. status%ok()) exit main
                end do
                if (want_steps) then
                    call copy_dense()
                    call sink%step(self%native%nst + 1, w%tn - w%hold, w%tn, w%phi(:, 1), &
                        self%dense, stop_requested, status)
                    if (.not. status%ok()) exit main
                    if (stop_requested) then
                        call status%set(status_interrupted, &
                            'ddassl: interrupted by the output routine at t = ' // real_text(w%tn))
                        call self%interpolate(w%tn, y, yp)
                        exit main
                    end if
                end if
                if (self%tstop) then
                    done = abs(w%tn - t_end) <= tstop_tol * w%uround * (abs(w%tn) + abs(w%h)) &
                        .or. (w%tn - t_end) * dir >= 0.0_wp
                else
                    done = (w%tn - t_end) * dir >= 0.0_wp
                end if
            end do main

            if (done .and. status%ok()) then
                call self%interpolate(t_end, y, yp)
                t = t_end
            else
                t = w%tn
            end if
        end associate
        call copy_dense()
        call finish()

    contains

        !> Common statistics from the native counters (docs/solvers.md).
        subroutine finish()
            type(status_t) :: sink_status
            stats%nst = self%native%nst + self%native%netf + self%native%ncfn
            stats%nac = self%native%nst
            stats%nrj = self%native%netf + self%native%ncfn
            stats%nfe = self%native%nre
            stats%nfe_jac = self%nfe_jac
            stats%nje = self%native%nje
            stats%ndec = self%ndec
            stats%nsol = self%nsol
            stats%rejections = self%rejections
            call stats%rejections%annotate(status)
            stats%t_reached = t
            if (allocated(self%warning)) stats%warning = self%warning
            self%k_last = self%work%kold
            self%k_next = self%work%k
            self%h_next = self%work%h
            stats%cpu = timer%cpu()
            stats%wall = timer%wall()
            if (present(sink)) then
                call sink%finish(sink_status)
                if (status%ok() .and. .not. sink_status%ok()) status = sink_status
            end if
        end subroutine finish

        subroutine copy_dense()
            associate (w => self%work)
                ! allocated with its shape after begin, so nothing is allocated here
                self%dense%phi = w%phi
                self%dense%psi = w%psi
                self%dense%kold = w%kold
                self%dense%tn = w%tn
            end associate
        end subroutine copy_dense
    end subroutine ddassl_integrate_residual

    !> Start an integration of G(t, y, y') = 0 at (t, y, yp) (§2.7, first
    !> call): validate, fix the storages and the linear solver, choose H0
    !> from `tout` (and options%h0, options%hmax), run DDAINI when asked, and
    !> set up the history. The state is kept in `self%work` for `step`.
    !> Counters restart at zero. With DDAINI the history starts at t + h, and
    !> (y, yp) hold DDAINI's values there; t is left unchanged.
    subroutine ddassl_begin(self, res, t, y, yp, tout, options, status, initial_derivative, tstop)
        class(ddassl_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: tout                !! H0 rule and hmin (§2.7)
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: initial_derivative !! overrides the component
        real(wp), intent(in), optional :: tstop    !! H0 never passes it (INFO(4))
        logical :: ddaini
        ddaini = self%initial_derivative
        if (present(initial_derivative)) ddaini = initial_derivative
        call ddassl_engine(self, res, action_begin, t, y, yp, tout, status, options, ddaini, &
            tlimit=tstop)
    end subroutine ddassl_begin

    !> One accepted step after `begin` (§2.7 "before every step" items 2–6,
    !> then §2.2–§2.6): on success `self%work%tn` is the new t_n; on failure
    !> status says why and `self%work%failure` gives the classic IDID. `y`,
    !> `yp` are work space here (the last iterate); `interpolate` gives values.
    !> `tout` enters hmin; with `tstop` the step never passes it (INFO(4)).
    subroutine ddassl_step(self, res, y, yp, tout, status, stop_at_tout, tstop)
        class(ddassl_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: tout
        type(status_t), intent(out) :: status
        logical, intent(in) :: stop_at_tout         !! never pass tout (modern tstop)
        real(wp), intent(in), optional :: tstop     !! never pass tstop (classic INFO(4))
        real(wp) :: t, tlimit
        logical :: limited
        if (.not. self%work%ready) then
            call status%set(status_bad_input, 'ddassl: step called before a successful begin')
            return
        end if
        t = self%work%tn
        limited = stop_at_tout .or. present(tstop)
        tlimit = tout
        if (present(tstop)) tlimit = tstop
        call ddassl_engine(self, res, action_step, t, y, yp, tout, status, &
            limited=limited, tlimit=tlimit)
    end subroutine ddassl_step

    !> y(tbar) and y'(tbar) from the BDF interpolant of the last step (§2.5).
    subroutine ddassl_interpolate(self, tbar, y, yp)
        class(ddassl_t), intent(in) :: self
        real(wp), intent(in) :: tbar
        real(wp), intent(out) :: y(:)
        real(wp), intent(out), optional :: yp(:)
        call interpolate_history(self%work%phi, self%work%psi, self%work%kold, self%work%tn, &
            tbar, y, yp)
    end subroutine ddassl_interpolate

    !> The machinery of begin and step. The state lives in self%work between
    !> calls and in locals (moved, not copied) during one, so that the
    !> procedures below read as the algorithm does in docs/theory.md §6.
    subroutine ddassl_engine(self, res, action, t, y, yp, tout, status, options, ddaini, &
                             limited, tlimit)
        class(ddassl_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        integer, intent(in) :: action
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: tout
        type(status_t), intent(out) :: status
        type(dae_options_t), intent(in), optional :: options
        logical, intent(in), optional :: ddaini
        logical, intent(in), optional :: limited
        real(wp), intent(in), optional :: tlimit

        real(wp), allocatable :: phi(:, :), delta(:), e(:), wt(:), rtol(:), atol(:)
        real(wp), allocatable :: ytmp(:), yptmp(:), ysave(:), ypsave(:)
        logical, allocatable :: in_test(:)
        !> correction components (GGL's μ) in the Newton test as h δ (§2.10)
        integer, allocatable :: newton_power(:)
        logical, allocatable :: multiplier(:)
        real(wp) :: psi(mx), alpha(mx), beta(mx), gamma(mx), sigma(mx)
        type(matrix_t), allocatable :: amat, bmat
        class(linear_solver_t), allocatable :: ls
        type(status_t) :: st
        type(status_t) :: model_failure !! the model's last refusal in this step
        integer :: n, pmax, k, kold, ns, iphase, jcalc, nef, ncf, nsf, knew, stat
        logical :: pd_refused !! the last PD failed in the model, not in the LU
        real(wp) :: tn, h, hold, cj, cjlast, cjold, s, hmin, hmax, dir, uround
        real(wp) :: t0, h_fixed, est, erkm1, terkm1, terk, r
        logical :: fd, ires_stop, direct

        if (action == action_begin) then
            call begin_integration()
        else
            call load_state()
            call before_step()
            if (status%ok()) then
                call take_step(st)
                if (.not. st%ok()) status = st
            end if
            call save_state()
        end if

    contains

        subroutine begin_integration()
            integer, allocatable :: classes(:)
            self%work = ddassl_work_t()
            if (allocated(self%warning)) deallocate (self%warning)
            self%native = ddassl_native_t()
            self%rejections = rejections_t()
            self%ndec = 0
            self%nsol = 0
            self%nfe_jac = 0
            self%k_last = 0
            self%k_next = 0
            self%h_next = 0.0_wp
            n = res%n
            tn = t
            t0 = t
            uround = self%uround
            pmax = options%pmax
            h = 0.0_wp
            hold = 0.0_wp
            ires_stop = .false.
            k = 0
            kold = 0

            ! ---- validation (§2.7 first call) ----
            if (n <= 0 .or. size(y) /= n .or. size(yp) /= n) then
                call bad('sizes of y and yp must equal the problem size n > 0')
                return
            end if
            call options%validate(n, status)
            if (.not. status%ok()) return
            if (pmax > ddassl_max_order) then
                call bad('pmax = ' // int_text(pmax) // ': must lie in 1..5')
                return
            end if
            if (.not. (uround > 0.0_wp .and. uround < 1.0_wp)) then
                call bad('uround must lie in (0, 1)')
                return
            end if
            if (self%fixed_step .and. .not. options%h0 > 0.0_wp) then
                call bad('fixed_step needs a positive h0')
                return
            end if
            allocate (rtol(n), atol(n), wt(n), in_test(n), classes(n), newton_power(n), &
                      multiplier(n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'ddassl weights and index classes', 6_i8 * n, 8)
                return
            end if
            call options%tolerances(rtol, atol)
            call res%index_classes(classes)
            in_test = .true.
            newton_power = 0
            if (self%exclude_index23) then
                in_test = classes < 2
                call res%multiplier_flags(multiplier)
                where (multiplier .and. .not. in_test) newton_power = classes - 1
            end if
            if (any(classes >= 3)) self%warning = index3_warning('ddassl')
            dir = sign(1.0_wp, tout - t)
            call set_weights(y)
            if (any(.not. wt > 0.0_wp)) then
                call bad('some weight rtol*|y0| + atol is not positive')
                return
            end if
            hmin = hmin_factor * uround * max(abs(t), abs(tout))
            if (abs(tout - t) < hmin .or. tout == t) then
                call bad('tout = ' // real_text(tout) // ' is too close to t = ' // real_text(t))
                return
            end if
            hmax = huge(1.0_wp)
            if (options%hmax > 0.0_wp) hmax = options%hmax

            ! Matrices and the linear solver: storages fixed here, once.
            allocate (amat, bmat)
            call res%setup_partials(options%jacobian == 'fd', amat, bmat, status)
            if (.not. status%ok()) return
            fd = bmat%storage == storage_none
            direct = .not. fd .and. res%has_iteration_matrix()
            call new_linear_solver(options%linear_solver, n, bmat%storage, ls, status, &
                lower=options%band_lower, upper=options%band_upper, &
                ordering=options%sparse_ordering, classic_order=options%classic_lu, &
                mass=amat, jac=bmat)
            if (.not. status%ok()) return
            if (fd) then
                ! The difference PD is held as −PD and factored with shift 0.
                bmat%storage = storage_dense
                allocate (bmat%dense(n, n), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'ddassl difference iteration matrix', &
                        int(n, i8) * n, 8)
                    return
                end if
            end if
            call ls%init(amat, bmat, status)
            if (.not. status%ok()) return
            allocate (phi(n, pmax + 1), delta(n), e(n), ytmp(n), yptmp(n), ysave(n), ypsave(n), &
                stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'ddassl history and workspace', &
                    int(n, i8) * (pmax + 7), 8)
                return
            end if
            phi = 0.0_wp
            delta = 0.0_wp
            e = 0.0_wp

            ! ---- initial step (§2.7 steps 4 and 5) ----
            if (options%h0 > 0.0_wp) then
                h = sign(options%h0, dir)
            else
                h = h0_fraction * abs(tout - t)
                if (vnorm(yp) > h0_slope / h) h = h0_slope / vnorm(yp)
                h = sign(h, dir)
            end if
            h_fixed = h
            if (abs(h) > hmax) h = h / (abs(h) / hmax)
            if (present(tlimit)) then
                if ((t + h - tlimit) * dir > 0.0_wp) h = tlimit - t
            end if

            if (ddaini) then
                call initial_step(st)
                if (.not. st%ok()) then
                    status = st
                    self%work%failure = ddassl_fail_initial
                    if (st%code == status_interrupted) self%work%failure = ddassl_fail_stop
                    call save_state()
                    self%work%ready = .false.
                    return
                end if
            end if

            ! §2.7 step 7: the history after the first call.
            phi(:, 1) = y
            phi(:, 2) = h * yp
            k = 1
            kold = 0
            hold = 0.0_wp
            psi = 0.0_wp
            psi(1) = h
            cj = 1.0_wp / h
            cjold = cj
            cjlast = cj
            s = s_fresh
            jcalc = -1
            iphase = 0
            ns = 0
            nef = 0
            ncf = 0
            nsf = 0
            knew = 1
            est = 0.0_wp
            erkm1 = 0.0_wp
            terkm1 = 0.0_wp
            terk = 0.0_wp
            alpha = 0.0_wp; beta = 0.0_wp; gamma = 0.0_wp; sigma = 0.0_wp
            if (self%fixed_step .and. allocated(self%start_history)) then
                if (size(self%start_history, 1) /= n .or. &
                    size(self%start_history, 2) /= pmax + 1) then
                    call bad('start_history must have shape (n, pmax + 1)')
                    return
                end if
                call history_from_values()
            end if
            call save_state()
            self%work%ready = .true.
        end subroutine begin_integration

        !> §2.7, before every step, items 2–6.
        subroutine before_step()
            call set_weights(phi(:, 1))
            if (any(.not. wt > 0.0_wp)) then
                call fail('a weight rtol*|y| + atol became non-positive', reason_non_finite, &
                    ddassl_fail_weights)
                return
            end if
            r = roundoff_conv * uround * vnorm(phi(:, 1))
            if (r > 1.0_wp) then
                ! The classic code scales the tolerances and reports −2.
                rtol = r * rtol
                atol = r * atol
                self%work%tol_scale = r
                call fail('tolerances too small for the machine precision (rtol, atol ' // &
                    'scaled by ' // real_text(r) // ')', reason_step_too_small, &
                    ddassl_fail_tolerances)
                return
            end if
            hmin = hmin_factor * uround * max(abs(tn), abs(tout))
            if (abs(h) > hmax) h = h / (abs(h) / hmax)
            if (present(limited) .and. present(tlimit)) then
                if (limited .and. (tn + h - tlimit) * dir > 0.0_wp) h = tlimit - tn
            end if
        end subroutine before_step

        !> Locals from self%work (arrays moved, not copied).
        subroutine load_state()
            associate (w => self%work)
                n = w%n; pmax = w%pmax; k = w%k; kold = w%kold; ns = w%ns
                iphase = w%iphase; jcalc = w%jcalc; knew = w%knew
                nef = w%nef; ncf = w%ncf; nsf = w%nsf
                tn = w%tn; h = w%h; hold = w%hold; cj = w%cj; cjlast = w%cjlast
                cjold = w%cjold; s = w%s; hmin = w%hmin; hmax = w%hmax; uround = w%uround
                t0 = w%t0; h_fixed = w%h_fixed; est = w%est; erkm1 = w%erkm1
                terkm1 = w%terkm1; terk = w%terk; fd = w%fd; ires_stop = .false.
                direct = w%direct
                psi = w%psi; alpha = w%alpha; beta = w%beta; gamma = w%gamma; sigma = w%sigma
                w%failure = ddassl_fail_none
                dir = sign(1.0_wp, h)
                call move_alloc(w%phi, phi)
                call move_alloc(w%delta, delta)
                call move_alloc(w%e, e)
                call move_alloc(w%wt, wt)
                call move_alloc(w%rtol, rtol)
                call move_alloc(w%atol, atol)
                call move_alloc(w%ytmp, ytmp)
                call move_alloc(w%yptmp, yptmp)
                call move_alloc(w%ysave, ysave)
                call move_alloc(w%ypsave, ypsave)
                call move_alloc(w%in_test, in_test)
                call move_alloc(w%newton_power, newton_power)
                call move_alloc(w%amat, amat)
                call move_alloc(w%bmat, bmat)
                call move_alloc(w%ls, ls)
            end associate
        end subroutine load_state

        !> Locals back into self%work.
        subroutine save_state()
            associate (w => self%work)
                w%n = n; w%pmax = pmax; w%k = k; w%kold = kold; w%ns = ns
                w%iphase = iphase; w%jcalc = jcalc; w%knew = knew
                w%nef = nef; w%ncf = ncf; w%nsf = nsf
                w%tn = tn; w%h = h; w%hold = hold; w%cj = cj; w%cjlast = cjlast
                w%cjold = cjold; w%s = s; w%hmin = hmin; w%hmax = hmax; w%uround = uround
                w%t0 = t0; w%h_fixed = h_fixed; w%est = est; w%erkm1 = erkm1
                w%terkm1 = terkm1; w%terk = terk; w%fd = fd; w%ires_stop = ires_stop
                w%direct = direct
                w%psi = psi; w%alpha = alpha; w%beta = beta; w%gamma = gamma; w%sigma = sigma
                call move_alloc(phi, w%phi)
                call move_alloc(delta, w%delta)
                call move_alloc(e, w%e)
                call move_alloc(wt, w%wt)
                call move_alloc(rtol, w%rtol)
                call move_alloc(atol, w%atol)
                call move_alloc(ytmp, w%ytmp)
                call move_alloc(yptmp, w%yptmp)
                call move_alloc(ysave, w%ysave)
                call move_alloc(ypsave, w%ypsave)
                call move_alloc(in_test, w%in_test)
                call move_alloc(newton_power, w%newton_power)
                call move_alloc(amat, w%amat)
                call move_alloc(bmat, w%bmat)
                call move_alloc(ls, w%ls)
            end associate
        end subroutine save_state

        subroutine bad(reason)
            character(len=*), intent(in) :: reason
            call status%set(status_bad_input, 'ddassl: ' // reason)
        end subroutine bad

        subroutine fail(reason, code, idid)
            character(len=*), intent(in) :: reason
            integer, intent(in) :: code, idid
            call status%set(status_solver_failure, 'ddassl: ' // reason // ' at t = ' // &
                real_text(tn) // ' (h = ' // real_text(h) // ')', code)
            self%work%failure = idid
        end subroutine fail

        !> §2.7: wt_i = rtol_i |v_i| + atol_i.
        subroutine set_weights(v)
            real(wp), intent(in) :: v(:)
            wt = rtol * abs(v) + atol
        end subroutine set_weights

        !> §2.7: ‖v‖ = vmax ((1/n) Σ ((v_i/wt_i)/vmax)²)^(1/2).
        real(wp) function vnorm(v)
            real(wp), intent(in) :: v(:)
            real(wp) :: vmax, acc
            integer :: i
            vmax = 0.0_wp
            do i = 1, n
                vmax = max(vmax, abs(v(i) / wt(i)))
            end do
            if (.not. ieee_is_finite(vmax)) then
                vnorm = vmax
                return
            end if
            vnorm = 0.0_wp
            if (vmax <= 0.0_wp) return
            acc = 0.0_wp
            do i = 1, n
                acc = acc + ((v(i) / wt(i)) / vmax)**2
            end do
            vnorm = vmax * sqrt(acc / real(n, wp))
        end function vnorm

        !> The Newton-test norm: the multipliers out of the error test (index
        !> 2 and 3) count as h^(k-1) δ / κ for index k: h^(k-1) δ is their
        !> effect on the components of index 1 (a correction δλ changes the
        !> velocities by about h M⁻¹Gᵀδλ), as RADAU5 scales them, and κ keeps
        !> them as accurate as before at moderate tolerances. Measured as δ
        !> against their tolerance, the round-off of δ (amplified like 1/h)
        !> stopped tight runs at t0 (the four-bar, the five-body at 1e-10).
        real(wp) function newton_norm(v)
            real(wp), intent(in) :: v(:)
            integer :: i
            real(wp) :: kappa
            if (all(newton_power == 0)) then
                newton_norm = vnorm(v)
                return
            end if
            kappa = multiplier_kappa(minval(rtol))
            do i = 1, n
                ytmp(i) = v(i)
                if (newton_power(i) > 0) ytmp(i) = abs(h)**newton_power(i) * v(i) / kappa
            end do
            newton_norm = vnorm(ytmp)
        end function newton_norm

        !> The error-test norm: excluded components zeroed, RMS still over n (§2.10).
        real(wp) function enorm(v)
            real(wp), intent(in) :: v(:)
            integer :: i
            do i = 1, n
                if (in_test(i)) then
                    ytmp(i) = v(i)
                else
                    ytmp(i) = 0.0_wp
                end if
            end do
            enorm = vnorm(ytmp)
        end function enorm

        !> Constant-step history at order pmax: φ_{j+1} = ∇^j y_0 (§2.2 with
        !> ψ_i = i·h0), from the values y(t0 − j·h0).
        subroutine history_from_values()
            integer :: i, j
            real(wp), allocatable :: table(:, :)
            table = self%start_history
            phi(:, 1) = table(:, 1)
            do j = 1, pmax
                do i = 1, pmax + 1 - j
                    table(:, i) = table(:, i) - table(:, i + 1)
                end do
                phi(:, j + 1) = table(:, 1)
            end do
            h = h_fixed
            hold = h
            k = pmax
            kold = pmax
            do i = 1, mx
                psi(i) = real(i, wp) * h
            end do
            cj = real(pmax, wp) / h
            cjold = cj
            cjlast = cj
            iphase = 1
        end subroutine history_from_values

        !> Form and factor PD at (tn, y, yp) with cj; delta holds G there.
        subroutine form_pd(singular)
            logical, intent(out) :: singular
            integer :: j
            real(wp) :: del, ysafe, ypsafe, squr
            type(status_t) :: fst
            singular = .true.
            pd_refused = .true.
            if (fd) then
                ! §2.3: column j = (G(y + δ_j e_j, y' + cj δ_j e_j) − δ)/δ_j; held as −PD.
                squr = sqrt(uround)
                do j = 1, n
                    del = squr * max(abs(y(j)), abs(h * yp(j)), wt(j))
                    del = sign(del, h * yp(j))
                    del = (y(j) + del) - y(j)
                    ysafe = y(j)
                    ypsafe = yp(j)
                    y(j) = y(j) + del
                    yp(j) = yp(j) + cj * del
                    call res%residual(tn, y, yp, yptmp, fst)
                    self%nfe_jac = self%nfe_jac + 1
                    y(j) = ysafe
                    yp(j) = ypsafe
                    if (.not. fst%ok()) then
                        model_failure = fst
                        return
                    end if
                    bmat%dense(:, j) = -(yptmp - delta) / del
                end do
                if (.not. all(ieee_is_finite(bmat%dense))) then
                    call model_failure%set(status_solver_failure, 'non-finite residual in ' // &
                        'the difference iteration matrix at t = ' // real_text(tn), &
                        reason_non_finite)
                    return
                end if
                call ls%factor_real(0.0_wp, amat, bmat, fst)
            else if (direct) then
                call res%iteration_matrix(tn, y, yp, cj, bmat%dense, fst)
                if (.not. fst%ok()) then
                    model_failure = fst
                    return
                end if
                bmat%dense = -bmat%dense
                call ls%factor_real(0.0_wp, amat, bmat, fst)
            else
                call res%partials(tn, y, yp, amat, bmat, fst)
                if (.not. fst%ok()) then
                    model_failure = fst
                    return
                end if
                call ls%factor_real(cj, amat, bmat, fst)
            end if
            pd_refused = .false.
            singular = .not. fst%ok()
            if (.not. singular) self%ndec = self%ndec + 1
        end subroutine form_pd

        !> g = G(tn, y, yp) into delta; false on failure or non-finite values
        !> (both the model's refusal, kept in model_failure).
        logical function residual_ok()
            type(status_t) :: fst
            integer :: j
            self%native%nre = self%native%nre + 1
            call res%residual(tn, y, yp, delta, fst)
            ! IRES = −2 of the classic code: the residual asks to stop.
            if (fst%code == status_interrupted) ires_stop = .true.
            if (.not. fst%ok()) model_failure = fst
            residual_ok = fst%ok()
            if (.not. residual_ok) return
            do j = 1, n
                if (ieee_is_finite(delta(j))) cycle
                call model_failure%set(status_solver_failure, 'non-finite residual in ' // &
                    'component ' // int_text(j) // ' at t = ' // real_text(tn), reason_non_finite)
                residual_ok = .false.
                return
            end do
        end function residual_ok

        !> §2.3: the corrector iteration from the predictor in (y, yp); `why`
        !> is the cause (cause_*) of a failure.
        subroutine corrector(pnorm, converged, singular, early, why)
            real(wp), intent(in) :: pnorm
            logical, intent(out) :: converged, singular, early
            integer, intent(out) :: why
            integer :: m
            real(wp) :: d, d0, rate
            converged = .false.
            singular = .false.
            early = .false.
            why = cause_model_refused
            if (.not. residual_ok()) then
                early = .true.
                return
            end if
            if (jcalc == -1) then
                self%native%nje = self%native%nje + 1
                jcalc = 0
                call form_pd(singular)
                cjold = cj
                s = s_fresh
                if (singular .and. .not. pd_refused) why = cause_singular_matrix
                if (singular) return
                nsf = 0
            end if
            why = cause_newton_diverged
            e = 0.0_wp
            m = 0
            d0 = 0.0_wp
            do
                delta = delta * (2.0_wp / (1.0_wp + cj / cjold))
                call ls%solve_real(delta)
                self%nsol = self%nsol + 1
                y = y - delta
                e = e - delta
                yp = yp - cj * delta
                d = newton_norm(delta)
                if (.not. ieee_is_finite(d)) return
                if (d <= roundoff_conv * uround * pnorm .and. (.not. self%netlib .or. m == 0)) then
                    converged = .true.
                    return
                end if
                if (m == 0) then
                    d0 = d
                else
                    rate = (d / d0)**(1.0_wp / real(m, wp))
                    if (rate > rate_max) return
                    s = rate / (1.0_wp - rate)
                end if
                if (s * d <= conv_tol) then
                    converged = .true.
                    return
                end if
                m = m + 1
                why = cause_newton_slow
                if (m >= max_iter) return
                why = cause_model_refused
                if (.not. residual_ok()) return
                why = cause_newton_diverged
            end do
        end subroutine corrector

        !> One step of §2.2–§2.6; on return either accepted or st says why not.
        subroutine take_step(st)
            type(status_t), intent(out) :: st
            integer :: i, j, kdiff
            real(wp) :: temp1, temp2, alphas, alpha0, ck, pnorm, enrm, erk, err, r, hnew
            real(wp) :: erkm2, terkm2, erkp1, terkp1
            logical :: converged, singular, early, passed
            type(status_t) :: refusal
            integer :: why

            nef = 0
            ncf = 0
            nsf = 0
            call model_failure%clear()
            attempt: do
                ! ---- §2.2: coefficients ----
                if (h /= hold .or. k /= kold) ns = 0
                ns = min(ns + 1, kold + 2)
                if (k + 1 >= ns) then
                    beta(1) = 1.0_wp
                    alpha(1) = 1.0_wp
                    sigma(1) = 1.0_wp
                    gamma(1) = 0.0_wp
                    temp1 = h
                    do i = 2, k + 1
                        temp2 = psi(i - 1)
                        psi(i - 1) = temp1
                        beta(i) = beta(i - 1) * psi(i - 1) / temp2
                        temp1 = temp2 + h
                        alpha(i) = h / temp1
                        sigma(i) = real(i - 1, wp) * sigma(i - 1) * alpha(i)
                        gamma(i) = gamma(i - 1) + alpha(i - 1) / h
                    end do
                    psi(k + 1) = temp1
                end if
                alphas = 0.0_wp
                alpha0 = 0.0_wp
                do i = 1, k
                    alphas = alphas - 1.0_wp / real(i, wp)
                    alpha0 = alpha0 - alpha(i)
                end do
                cjlast = cj
                cj = -alphas / h
                ck = max(abs(alpha(k + 1) + alphas - alpha0), alpha(k + 1))
                ! §2.3: a new PD when cj moved too far from that of the current PD.
                temp1 = cj / cjold
                if (temp1 < cj_ratio_low .or. temp1 > 1.0_wp / cj_ratio_low) jcalc = -1
                if (cj /= cjlast) s = s_fresh
                do j = ns + 1, k + 1
                    phi(:, j) = beta(j) * phi(:, j)
                end do
                tn = tn + h

                ! ---- §2.2 predictor, §2.3 corrector (redone once with a fresh PD) ----
                do
                    y = phi(:, 1)
                    yp = 0.0_wp
                    do j = 2, k + 1
                        y = y + phi(:, j)
                        yp = yp + gamma(j) * phi(:, j)
                    end do
                    pnorm = vnorm(y)
                    call corrector(pnorm, converged, singular, early, why)
                    if (converged .or. jcalc /= 1 .or. early) exit
                    jcalc = -1
                end do
                jcalc = 1
                ! A corrected state the model cannot hold (det F <= 0) is a
                ! corrector failure: h/4, as for IRES = -1.
                if (converged) then
                    call res%admissible(tn, y, refusal)
                    if (.not. refusal%ok()) then
                        converged = .false.
                        why = cause_model_refused
                        model_failure = refusal
                    end if
                end if
                if (converged .and. self%nonnegative) then
                    delta = min(y, 0.0_wp)
                    if (vnorm(delta) > conv_tol) then
                        ! the user's rule y ≥ 0 refuses the corrected state
                        converged = .false.
                        why = cause_model_refused
                        call model_failure%set(status_solver_failure, 'negative components ' &
                            // '(nonnegative) at t = ' // real_text(tn), reason_newton_failure)
                    else
                        e = e - delta
                    end if
                end if

                passed = .false.
                if (converged) then
                    ! ---- §2.4: error estimates ----
                    enrm = enorm(e)
                    erk = sigma(k + 1) * enrm
                    terk = real(k + 1, wp) * erk
                    est = erk
                    knew = k
                    if (k >= 2) then
                        delta = phi(:, k + 1) + e
                        erkm1 = sigma(k) * enorm(delta)
                        terkm1 = real(k, wp) * erkm1
                        if (k > 2) then
                            delta = phi(:, k) + delta
                            erkm2 = sigma(k - 1) * enorm(delta)
                            terkm2 = real(k - 1, wp) * erkm2
                            if (max(terkm1, terkm2) <= terk) then
                                knew = k - 1
                                est = erkm1
                            end if
                        else if (terkm1 <= half * terk) then
                            knew = k - 1
                            est = erkm1
                        end if
                    end if
                    err = ck * enrm
                    if (.not. ieee_is_finite(err) .or. .not. ieee_is_finite(est)) then
                        est = huge(1.0_wp)
                        passed = .false.
                    else
                        passed = err <= 1.0_wp
                    end if
                    if (self%fixed_step) passed = .true.
                    if (passed) exit attempt
                end if

                ! ---- §2.6: failed step; restore the history ----
                if (self%fixed_step) then
                    call st%set(status_solver_failure, 'ddassl: fixed-step corrector ' // &
                        'failed at t = ' // real_text(tn - h), reason_newton_failure)
                    self%work%failure = ddassl_fail_corrector
                    call restore()
                    return
                end if
                call restore()
                temp2 = h
                if (converged) then
                    ! Error-test failure.
                    nef = nef + 1
                    self%native%netf = self%native%netf + 1
                    call self%rejections%add(cause_error_test)
                    if (nef == 1) then
                        k = knew
                        r = fail_safety * (2.0_wp * est + est_offset)**(-1.0_wp / real(k + 1, wp))
                        r = min(max(r, fail_min), r_max)
                        h = h * r
                    else if (nef == 2) then
                        k = knew
                        h = h * fail_quarter
                    else
                        k = 1
                        h = h * fail_quarter
                    end if
                    if (abs(h) < hmin) then
                        call st%set(status_solver_failure, 'ddassl: error test failed ' // &
                            'repeatedly, step size too small at t = ' // real_text(tn) // &
                            ' (h = ' // real_text(h) // ')', reason_step_too_small)
                        self%work%failure = ddassl_fail_error_test
                        return
                    end if
                else
                    self%native%ncfn = self%native%ncfn + 1
                    if (ires_stop) then
                        call self%rejections%refuse('the residual asked to stop (IRES = -2)')
                    else if (why == cause_model_refused) then
                        call self%rejections%refuse(model_failure%text())
                    else
                        call self%rejections%add(why)
                    end if
                    if (ires_stop) then
                        call st%set(status_interrupted, 'ddassl: the residual asked to stop ' &
                            // 'at t = ' // real_text(tn + h))
                        self%work%failure = ddassl_fail_stop
                        return
                    else if (singular) then
                        nsf = nsf + 1
                        h = h * fail_quarter
                        if (nsf >= max_nsf .or. abs(h) < hmin) then
                            call st%set(status_solver_failure, 'ddassl: iteration matrix ' // &
                                'repeatedly singular at t = ' // real_text(tn) // ' (h = ' // &
                                real_text(h) // ')', reason_singular_matrix)
                            self%work%failure = ddassl_fail_singular
                            return
                        end if
                    else
                        ncf = ncf + 1
                        h = h * fail_quarter
                        if (ncf >= max_ncf .or. abs(h) < hmin) then
                            if (nef >= nef_after_conv) then
                                call st%set(status_solver_failure, 'ddassl: corrector failed ' // &
                                    'after repeated error-test failures at t = ' // &
                                    real_text(tn) // ' (h = ' // real_text(h) // ')', &
                                    reason_newton_failure)
                                self%work%failure = ddassl_fail_after_error_test
                            else if (model_failure%reason == reason_det_f) then
                                call st%set(status_solver_failure, 'ddassl: step size too ' // &
                                    'small at t = ' // real_text(tn) // ' (h = ' // &
                                    real_text(h) // '): the model refused every corrected ' // &
                                    'state: ' // model_failure%text(), reason_det_f)
                                self%work%failure = ddassl_fail_residual
                            else if (early) then
                                call st%set(status_solver_failure, 'ddassl: residual failed ' // &
                                    'repeatedly at t = ' // real_text(tn) // ' (h = ' // &
                                    real_text(h) // ')', reason_user_function)
                                self%work%failure = ddassl_fail_residual
                            else
                                call st%set(status_solver_failure, 'ddassl: corrector ' // &
                                    'failed repeatedly at t = ' // real_text(tn) // ' (h = ' // &
                                    real_text(h) // ')', reason_newton_failure)
                                self%work%failure = ddassl_fail_corrector
                            end if
                            return
                        end if
                    end if
                end if
                if (self%netlib .and. kold == 0) then
                    ! §2.9: rescale the first-step history to the new h.
                    psi(1) = h
                    phi(:, 2) = (h / temp2) * phi(:, 2)
                end if
            end do attempt

            ! ---- §2.4: success ----
            self%native%nst = self%native%nst + 1
            kdiff = k - kold
            kold = k
            hold = h
            hnew = h
            if (self%fixed_step) then
                k = min(k + 1, pmax)
            else
                if (knew == k - 1 .or. k == pmax) iphase = 1
                if (iphase == 0) then
                    k = k + 1
                    hnew = 2.0_wp * h
                else
                    if (knew == k - 1) then
                        k = k - 1
                        est = erkm1
                    else if (.not. (k == pmax .or. k + 1 >= ns .or. kdiff == 1)) then
                        delta = e - phi(:, k + 2)
                        erkp1 = enorm(delta) / real(k + 2, wp)
                        terkp1 = real(k + 2, wp) * erkp1
                        if (k == 1) then
                            if (terkp1 < half * terk) then
                                k = k + 1
                                est = erkp1
                            end if
                        else if (terkm1 <= min(terk, terkp1)) then
                            k = k - 1
                            est = erkm1
                        else if (terkp1 < terk) then
                            k = k + 1
                            est = erkp1
                        end if
                    end if
                    r = (2.0_wp * est + est_offset)**(-1.0_wp / real(k + 1, wp))
                    if (r >= r_raise) then
                        hnew = 2.0_wp * h
                    else if (r <= 1.0_wp) then
                        hnew = h * min(max(r, r_min), r_max)
                    end if
                end if
            end if
            ! History, with kold the order used in this step.
            if (kold /= pmax) phi(:, kold + 2) = e
            phi(:, kold + 1) = phi(:, kold + 1) + e
            do j = kold, 1, -1
                phi(:, j) = phi(:, j) + phi(:, j + 1)
            end do
            h = hnew
        end subroutine take_step

        !> §2.6: undo the β scaling, t_n and ψ of the failed attempt.
        subroutine restore()
            integer :: i, j
            iphase = 1
            tn = tn - h
            do j = ns + 1, k + 1
                phi(:, j) = phi(:, j) / beta(j)
            end do
            do i = 2, k + 1
                psi(i - 1) = psi(i) - h
            end do
        end subroutine restore

        !> §2.8 DDAINI: one damped backward-Euler step from (t0, y0) with y0'
        !> as the guess; advances tn to t0 + h and leaves (y, yp) there.
        subroutine initial_step(st)
            type(status_t), intent(out) :: st
            integer :: m, mb, nefi, ncfi, nsfi
            real(wp) :: ynorm, d, d0, rate, err, r
            logical :: converged, singular
            ysave = y
            ypsave = yp
            ynorm = vnorm(y)
            call model_failure%clear()
            nefi = 0
            ncfi = 0
            nsfi = 0
            do
                cj = 1.0_wp / h
                tn = t0 + h
                y = ysave + h * ypsave
                yp = ypsave
                converged = .false.
                singular = .false.
                m = 0
                mb = 0
                d0 = 0.0_wp
                newton: do
                    if (.not. residual_ok()) exit newton
                    if (mod(m, ini_jac_every) == 0) then
                        self%native%nje = self%native%nje + 1
                        call form_pd(singular)
                        if (singular) exit newton
                        s = ini_s
                        mb = 0
                    end if
                    delta = ini_damp * delta
                    call ls%solve_real(delta)
                    self%nsol = self%nsol + 1
                    y = y - delta
                    yp = yp - cj * delta
                    if (self%nonnegative) then
                        ! Clip y and keep y' = (y − y0)/h consistent with it.
                        where (y < 0.0_wp) yp = yp - cj * y
                        y = max(y, 0.0_wp)
                    end if
                    d = vnorm(delta)
                    if (.not. ieee_is_finite(d)) exit newton
                    if (d <= roundoff_conv * uround * ynorm) then
                        converged = .true.
                        exit newton
                    end if
                    if (mb == 0) then
                        d0 = d
                    else
                        rate = (d / d0)**(1.0_wp / real(mb, wp))
                        if (rate > rate_max) exit newton
                        s = rate / (1.0_wp - rate)
                    end if
                    if (s * d <= conv_tol) then
                        converged = .true.
                        exit newton
                    end if
                    m = m + 1
                    mb = mb + 1
                    if (m >= ini_max_iter) exit newton
                end do newton
                if (ires_stop) then
                    call st%set(status_interrupted, 'ddassl: the residual asked to stop ' // &
                        'in DDAINI at t = ' // real_text(tn))
                    exit
                else if (converged) then
                    delta = y - ysave
                    err = vnorm(delta)
                    if (err <= 1.0_wp) return
                    nefi = nefi + 1
                    r = min(max(fail_safety / (2.0_wp * err + est_offset), ini_r_min), ini_r_max)
                    h = h * r
                    if (nefi >= ini_max_nef .or. abs(h) < hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI) failed the error test at t = ' // real_text(t0), &
                            reason_step_too_small)
                        exit
                    end if
                else if (singular) then
                    nsfi = nsfi + 1
                    h = h * fail_quarter
                    if (nsfi >= max_nsf .or. abs(h) < hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI): iteration matrix singular at t = ' // real_text(t0), &
                            reason_singular_matrix)
                        exit
                    end if
                else
                    ncfi = ncfi + 1
                    h = h * fail_quarter
                    if (ncfi >= max_ncf .or. abs(h) < hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI): Newton iteration failed at t = ' // real_text(t0), &
                            reason_newton_failure)
                        if (model_failure%reason == reason_det_f) call st%set( &
                            status_solver_failure, st%message // ': ' // &
                            model_failure%text(), reason_det_f)
                        exit
                    end if
                end if
            end do
            y = ysave
            yp = ypsave
            tn = t0
        end subroutine initial_step
    end subroutine ddassl_engine
end module flexmbs_dae_ddassl
