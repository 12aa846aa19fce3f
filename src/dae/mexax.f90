!> `MEXAX`: half-explicit extrapolation for constrained mechanical systems
!> (docs/theory.md §7; [Lub91], [LNPE95], [HW96 VII.6], ODEX control of
!> [HNW93 II.9]).
!>
!> For q' = T(t,q) v, M(t,q) v' = f(t,q,v) − G(t,q)ᵀλ, 0 = G v + g_I, with
!> the position invariant g(t,q) = 0. A macro step H is split into n_j
!> substeps of a half-explicit base method (explicit in the differential
!> equations, one solve of the augmented system [M Gᵀ; G 0] per substep);
!> the results are extrapolated (Aitken–Neville in h for the Euler base,
!> in h² for the midpoint base), the error of the diagonal is estimated from
!> the subdiagonal, and column and step size are chosen as in ODEX. After
!> every converged step the positions are projected onto g = 0 (simplified
!> Newton) and the velocities onto G v + g_I = 0. Errors are controlled on
!> q and v only; a = v' and λ are outputs.
!>
!> Only the mechanical form is integrated (`integrate_mechanical`); the
!> generic `integrate` of a `dae_problem_t` is refused (§6).
!>
!> The augmented matrix is factored densely (LAPACK LU), or, with
!> `options%linear_solver = 'klu'` (or 'auto' for a problem with sparse M and
!> G and nv + nc ≥ `mexax_auto_klu_order`), by KLU on the CSC pattern of
!> [M Gᵀ; G 0] built once from the patterns of M and G and analysed once;
!> each substep only refills its values and refactors.
module flexmbs_dae_mexax
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_step_too_small, reason_max_steps, reason_singular_matrix, &
        reason_non_finite, reason_projection, reason_user_function, reason_det_f
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_csc, only: csc_matrix_t, pattern_matvec
    use flexmbs_linalg_klu, only: klu_ordering_auto
    use flexmbs_linalg_saddle_point, only: saddle_point_t
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_linalg_factory, only: klu_ordering_code
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_singular_matrix, &
        cause_model_refused, cause_projection, cause_unstable
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private

    !> Base methods (§3.2).
    integer, parameter, public :: mexax_base_midpoint = 1 !! (M), h²-extrapolation (default)
    integer, parameter, public :: mexax_base_euler = 2    !! (E), h-extrapolation (MEXX21)
    !> Where a stopping failure happened (mexax_t%failed_in): the classic face
    !> tells IERR −15/−17 (in a step) from −16/−18 (in the projection).
    integer, parameter, public :: mexax_failed_none = 0, mexax_failed_step = 1, &
        mexax_failed_projection = 2
    !> At most this many extrapolation columns (KDMAX).
    integer, parameter, public :: mexax_max_columns = 12
    !> linear_solver = 'auto' factors [M Gᵀ; G 0] with KLU from this order
    !> nv + nc on (problems with sparse M and G), densely below. KLU is the
    !> faster from order 25 on (pendulum chain, release: about 0.2 against
    !> 0.6 ms a step at NB = 5, 0.3 against 1.6 ms at NB = 10), but below
    !> 50 both cost under 2 ms a step, and dense LU there keeps the original's
    !> full LU (JOB = 0) and so the §8 anchor (NB = 8, order 40) exactly: the
    !> round-off difference of KLU moves its TOL 1e-9 counters by ~3 %.
    integer, parameter, public :: mexax_auto_klu_order = 50

    ! §3.3 step-number sequence of (E); (M) uses n_j = 2j [R].
    integer, parameter :: euler_sequence(mexax_max_columns) = &
        [2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 30]
    ! §3.4 (ODEX): safety factors and limits of the column step sizes.
    real(wp), parameter :: safe1 = 0.8_wp, safe2 = 0.93_wp
    real(wp), parameter :: fac1 = 0.1_wp, fac2 = 4.0_wp
    ! §3.4 [R] (ODEX): order decrease / increase thresholds on the work per step,
    ! as published for the midpoint base (M).
    real(wp), parameter :: fac3 = 0.8_wp, fac4 = 0.9_wp
    ! §3.4 [R], base (E): FAC3, FAC4 calibrated on the §8 chain anchor (NB = 8,
    ! TOL 1e-3..1e-9; published ODEX values 0.8, 0.9).
    real(wp), parameter :: euler_fac3 = 0.7_wp, euler_fac4 = 0.95_wp
    ! §3.4 [R], base (E): exponent ϖ of the convergence monitor
    ! err_{k−1} > (n_{k+1} n_k / n_1²)^ϖ, calibrated on the §8 chain anchor
    ! (published 1; with 1 the monitor rejects steps whose column k would have
    ! converged, since err_{k−1}/err_k grows like 1/H for the h-expansion).
    ! The hope test keeps ϖ = 1.
    real(wp), parameter :: euler_monitor_power = 3.0_wp
    ! §3.4: the work of column 1 is n_1 + this.
    integer, parameter :: work_offset = 4
    ! §3.4 [R]: start column from -0.6 log10(r_min) + 1.5, (E) within [3, 10].
    real(wp), parameter :: start_slope = -0.6_wp, start_offset = 1.5_wp
    integer, parameter :: euler_start_min = 3, euler_start_max = 10
    ! §3.4: the step ends at TFIN when t + 1.01 H passes it.
    real(wp), parameter :: end_factor = 1.01_wp
    ! §3.3 [R]: divergence when err_j ≥ max(ϱ err_{j−1}, 1); ϱ = 4 for (M) (ODEX).
    ! For (E) ϱ = 4 too, calibrated on the §8 chain anchor (published 1, which
    ! restarts where the original never does).
    real(wp), parameter :: divergence_euler = 4.0_wp, divergence_midpoint = 4.0_wp
    ! §3.5 [R]: stability check ‖v2 − v1‖ > 2 ‖v2‖ in columns 1 and 2.
    real(wp), parameter :: stability_ratio = 2.0_wp
    integer, parameter :: stability_columns = 2
    ! §3.3/§3.5/§3.8: divergence, instability and non-finite values halve H.
    real(wp), parameter :: restart_factor = 0.5_wp
    ! §3.5 [R counting]: a restart counts in NREJCT as well as in NSTEP,
    ! calibrated on the §8 chain anchor, where the original's NSTEP equals
    ! NACCPT + NREJCT at every tolerance (published: NSTEP only).
    logical, parameter :: restart_is_rejection = .true.
    ! §3.8 [R]: stop when |H| ≤ 10 EPMACH |t| (the original's EPMACH = 1e-17);
    ! |t_end − t0| stands in for |t| near t = 0, where the rule never fires.
    real(wp), parameter :: epmach = 1.0e-17_wp, small_step_factor = 10.0_wp
    ! §4.2 [R]: automatic initial step 1e-3 |t_end − t0|.
    real(wp), parameter :: h0_fraction = 1.0e-3_wp
    ! §3.6: projection stops at ε ≤ EPSREQ, fails when ε grows by 2 or after ITMAX.
    real(wp), parameter :: epsreq = 1.0e-2_wp, projection_growth = 2.0_wp
    integer, parameter :: itmax = 10
    ! §3.6 [R normalisation]: rejection when the projection moved (p, v) by more
    ! than FACP, FACV weighted units; then H ← H max(0.45, 0.9/c).
    real(wp), parameter :: facp = 5.0_wp, facv = 5.0_wp
    real(wp), parameter :: projection_reject_min = 0.45_wp, projection_reject_safe = 0.9_wp

    ! Outcomes of a column (ev_restart: H/2 for an unstable column,
    ! ev_refused: H/2 when the model refused a substep) or an attempt.
    integer, parameter :: ev_ok = 0, ev_restart = 1, ev_stop = 2, ev_refused = 3
    integer, parameter :: undecided = 0, do_accept = 1, do_reject = 2, do_restart = 3, do_stop = 4

    !> Cubic Hermite interpolation on the last accepted step (§3.7): q from
    !> (q, T v), v from (v, a) at both ends; λ linear.
    type, extends(dense_output_t), public :: mexax_dense_t
        real(wp) :: t_old = 0.0_wp, t = 0.0_wp
        real(wp), allocatable :: y0(:), y1(:), d0(:), d1(:) !! (q, v, λ) and derivatives
    contains
        procedure :: evaluate => dense_evaluate
    end type mexax_dense_t

    !> The original's counters, MXJOB(51..59).
    type, public :: mexax_native_t
        integer :: nstep = 0, naccpt = 0, nrejct = 0, nfprob = 0, nfcn = 0, ngcn = 0
        integer :: nmult = 0, ndec = 0, nsol = 0
    end type mexax_native_t

    !> MEXAX settings and the results of the last integration.
    type, extends(dae_solver_t), public :: mexax_t
        integer :: max_extrapolation = mexax_max_columns !! KDMAX, 2..12
        integer :: base = mexax_base_midpoint            !! mexax_base_midpoint | _euler
        !> a and λ at every accepted point from the index-1 system
        !> [M Gᵀ; G 0][a; λ] = [f; −γ] (one more LU a step; needs
        !> constraint_curvature). False, or without γ: the extrapolated values
        !> of the last substeps (§3.7, the original's), which for the
        !> midpoint base lag by a substep.
        logical :: consistent_accelerations = .true.
        type(mexax_native_t) :: native
        integer :: nstab = 0        !! restarts by the stability check, divergence, NaN/Inf
        integer :: nprj_reject = 0  !! rejections by the projection test (the classic face counts 2 each)
        real(wp) :: h_next = 0.0_wp !! proposed next step (classic H on return)
        integer :: column = 0       !! column used next (k)
        integer :: failed_in = mexax_failed_none !! mexax_failed_step | _projection
        type(mexax_dense_t) :: dense
    contains
        procedure :: integrate_dae => mexax_integrate
        procedure :: integrate_mechanical => mexax_integrate_mechanical
        procedure :: integrate_system => mexax_integrate_system
        procedure :: extrapolate => mexax_extrapolate
        procedure :: name => mexax_name
        procedure :: step_counts => mexax_step_counts
    end type mexax_t

    !> M (nv x nv) or G (nc x nv) at one point: dense, or the values in the
    !> slots of the problem's fixed CSC pattern (KLU path).
    type :: block_t
        real(wp), allocatable :: dense(:, :)
        real(wp), allocatable :: values(:)
    end type block_t

    !> Workspace of one integration, allocated once.
    type :: workspace_t
        integer :: nq = 0, nv = 0, nc = 0, na = 0, ny = 0, ne = 0, km = 0
        integer :: klu_ordering = klu_ordering_auto !! KLU's fill-reducing ordering
        real(wp) :: varpi = 1.0_wp
        real(wp) :: order_down = fac3, order_up = fac4 !! FAC3, FAC4 of the base
        real(wp) :: monitor_power = 1.0_wp         !! ϖ of the convergence monitor
        integer, allocatable :: nj(:)
        real(wp), allocatable :: rtol(:), atol(:), wt(:), wst(:)
        real(wp), allocatable :: p0(:), v0(:), a0(:), lam0(:), f0(:), pdot0(:)
        type(block_t) :: m0, g0, mm, gm, gn
        ! augmented matrix [M Gᵀ; G 0]: dense (LAPACK, or the classic elimination
        ! order) or sparse (KLU), flexmbs_linalg_saddle_point
        logical :: sparse = .false.
        logical :: classic_lu = .false. !! dense LU in the classic elimination order (options)
        type(csc_matrix_t) :: mpat, gpat
        type(saddle_point_t) :: kkt
        real(wp), allocatable :: p(:), pp(:), pn(:), v(:), vp(:), f(:), pdot(:), gt(:)
        real(wp), allocatable :: rhs(:), acc(:), lam(:), x(:), d(:), tab(:, :)
        real(wp), allocatable :: err(:), hh(:), work(:), awork(:)
    end type workspace_t

contains

    function mexax_name(self) result(name)
        class(mexax_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'mexax'
    end function mexax_name

    !> Live counts for a display: the classic counters NSTEP and NACCPT.
    subroutine mexax_step_counts(self, attempted, accepted)
        class(mexax_t), intent(in) :: self
        integer, intent(out) :: attempted, accepted
        attempted = self%native%nstep
        accepted = self%native%naccpt
    end subroutine mexax_step_counts

    subroutine dense_evaluate(self, s, y)
        class(mexax_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        real(wp) :: h, th, h00, h10, h01, h11
        h = self%t - self%t_old
        if (h == 0.0_wp) then
            y = self%y1
            return
        end if
        th = (s - self%t_old) / h
        h00 = (1.0_wp + 2.0_wp * th) * (1.0_wp - th)**2
        h10 = th * (1.0_wp - th)**2
        h01 = th**2 * (3.0_wp - 2.0_wp * th)
        h11 = th**2 * (th - 1.0_wp)
        y = h00 * self%y0 + h10 * h * self%d0 + h01 * self%y1 + h11 * h * self%d1
    end subroutine dense_evaluate

    !> MEXAX takes mechanical problems only (docs/theory.md §3).
    subroutine mexax_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(mexax_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)
        stats%t_reached = t
        call status%set(status_bad_input, 'mexax: integrates mechanical problems only &
            &(q'' = T v, M v'' = f - G^T lambda, projection built in); give integrate &
            &a mechanical_problem_t with its formulation, not a formulation alone')
    end subroutine mexax_integrate

    !> The mechanical problem through the common interface: y = (q, v, λ)
    !> (the layout of `formulation`, the index-2 formulation with constant
    !> mass, which MEXAX itself does not need).
    subroutine mexax_integrate_system(self, mechanical, formulation, t, y, t_end, options, &
                                      stats, status, sink)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mechanical
        class(dae_problem_t), intent(inout) :: formulation
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        integer :: nq, nv, nc
        nq = mechanical%nq
        nv = mechanical%nv
        nc = mechanical%nc
        if (size(y) /= nq + nv + nc) then
            stats%t_reached = t
            call status%set(status_bad_input, 'mexax: y has ' // int_text(size(y)) // &
                ' components; the mechanical problem''s (q, v, lambda) has ' // &
                int_text(nq + nv + nc) // ': give it the state of the index-2 formulation &
                &with constant mass (formulation_index2, constant_mass = .true.)')
            return
        end if
        call self%integrate_mechanical(mechanical, t, y(1:nq), y(nq + 1:nq + nv), t_end, &
            options, stats, status, sink, lambda=y(nq + nv + 1:nq + nv + nc))
    end subroutine mexax_integrate_system

    !> Integrate the mechanical problem from (t, q, v) to t_end. On return
    !> t, q, v hold the last accepted point (t_end on success), `lambda` and
    !> `accel` the multipliers and accelerations there (extrapolated). The
    !> sink sees y = (q, v, λ). `status` names what failed and when.
    subroutine mexax_integrate_mechanical(self, problem, t, q, v, t_end, options, stats, &
                                          status, sink, lambda, accel)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: q(:)            !! positions, size nq
        real(wp), intent(inout) :: v(:)            !! velocities, size nv
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options !! rtol/atol vectors have size nq + nv
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: lambda(:) !! on exit: λ at t (size nc)
        real(wp), intent(inout), optional :: accel(:)  !! on exit: a = v' at t (size nv)

        type(workspace_t) :: w
        type(timer_t) :: timer
        type(status_t) :: fst
        type(status_t) :: refusal !! the model's last refusal since an accepted step
        real(wp), allocatable :: yout(:)
        integer :: k, kc, kopt, km, decision, j, iout, nout, nstab_nonfinite, stat
        integer :: cause !! why the attempt of a restart or a stop failed (cause_*)
        real(wp) :: h, hmax, posneg, tscale, rmin, c, t_old
        logical :: first, last, reject, need_start, basic_entry, want_steps, stop_requested

        call timer%start()
        self%native = mexax_native_t()
        self%nstab = 0
        self%nprj_reject = 0
        self%h_next = 0.0_wp
        self%failed_in = mexax_failed_none
        stats%t_reached = t
        nstab_nonfinite = 0
        stop_requested = .false.

        ! ---- validation ----
        if (problem%nq <= 0 .or. problem%nv <= 0 .or. problem%nc < 0) then
            call bad('the problem needs nq > 0, nv > 0 and nc >= 0')
            return
        end if
        if (size(q) /= problem%nq .or. size(v) /= problem%nv) then
            call bad('sizes of q and v differ from problem%nq and problem%nv')
            return
        end if
        if (present(lambda)) then
            if (size(lambda) /= problem%nc) then
                call bad('size of lambda differs from problem%nc')
                return
            end if
        end if
        if (present(accel)) then
            if (size(accel) /= problem%nv) then
                call bad('size of accel differs from problem%nv')
                return
            end if
        end if
        km = self%max_extrapolation
        if (km < 2 .or. km > mexax_max_columns) then
            call bad('max_extrapolation = ' // int_text(km) // ': must lie in 2..12')
            return
        end if
        if (self%base /= mexax_base_midpoint .and. self%base /= mexax_base_euler) then
            call bad('base must be mexax_base_midpoint or mexax_base_euler')
            return
        end if
        call options%validate(problem%nq + problem%nv, status)
        if (.not. status%ok()) then
            status%message = 'mexax: ' // status%message // ' (tolerances cover q and v)'
            return
        end if
        if (t_end == t) then
            call bad('t_end equals t')
            return
        end if

        call setup_workspace(w, problem, self%base, km, options%linear_solver, status, &
            options%sparse_ordering, options%classic_lu)
        if (.not. status%ok()) return
        call options%tolerances(w%rtol, w%atol)
        self%dense = mexax_dense_t()  ! drops the last run's arrays
        associate (m => w%nq + w%nv + w%nc)
            allocate (yout(m), self%dense%y0(m), self%dense%y1(m), self%dense%d0(m), &
                self%dense%d1(m), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'mexax output vectors', 5_i8 * m, 8)
                self%dense = mexax_dense_t()
                return
            end if
        end associate
        w%p0 = q
        w%v0 = v
        w%a0 = 0.0_wp
        w%lam0 = 0.0_wp
        if (present(lambda)) w%lam0 = lambda

        posneg = sign(1.0_wp, t_end - t)
        tscale = abs(t_end - t)
        hmax = tscale
        if (options%hmax > 0.0_wp) hmax = min(options%hmax, tscale)
        h = options%h0
        if (h == 0.0_wp) h = h0_fraction * tscale
        h = posneg * min(abs(h), hmax)
        ! §3.4 start column.
        rmin = minval(w%rtol + w%atol)
        k = int(start_slope * log10(rmin) + start_offset)
        if (self%base == mexax_base_euler) then
            k = max(euler_start_min, min(euler_start_max, k))
        end if
        k = max(2, min(k, km - 1))
        kc = k
        first = .true.
        last = .false.
        reject = .false.
        basic_entry = .false.

        ! ---- t0: projection (no rejection test), consistent a and λ ----
        w%wt(1:w%nq) = w%rtol(1:w%nq) * abs(w%p0) + w%atol(1:w%nq)
        w%wt(w%nq + 1:) = w%rtol(w%nq + 1:) * abs(w%v0) + w%atol(w%nq + 1:)
        w%p = w%p0
        w%v = w%v0
        call project(self, problem, w, t, c, status)
        stats%nprj = 1
        if (.not. status%ok()) then
            self%failed_in = mexax_failed_projection
            status%message = 'mexax: ' // status%message // ' at t0 = ' // real_text(t)
            call finish()
            return
        end if
        w%p0 = w%p
        w%v0 = w%v
        call start_point(self, problem, w, t, status)
        if (status%ok()) call consistent_acceleration(self, problem, w, t, status)
        if (.not. status%ok()) then
            self%failed_in = mexax_failed_step
            call finish()
            return
        end if
        need_start = .false.

        ! Output at t0.
        call set_dense_start()
        want_steps = .false.
        nout = 0
        iout = 1
        if (present(sink)) then
            want_steps = sink%wants_steps()
            if (allocated(options%output_times)) nout = size(options%output_times)
            do while (iout <= nout)
                if ((options%output_times(iout) - t) * posneg > 0.0_wp) exit
                if (options%output_times(iout) == t) call sink%output(t, self%dense%y1, status)
                iout = iout + 1
                if (.not. status%ok()) exit
            end do
            if (want_steps .and. status%ok()) &
                call sink%step(1, t, t, self%dense%y1, self%dense, stop_requested, status)
            if (status%ok() .and. stop_requested) call interrupted()
            if (.not. status%ok()) then
                call finish()
                return
            end if
        end if

        main: do
            if (need_start) then
                call start_point(self, problem, w, t, status)
                if (.not. status%ok()) then
                    self%failed_in = mexax_failed_step
                    exit main
                end if
                need_start = .false.
            end if
            if (abs(h) <= small_step_factor * epmach * max(abs(t), tscale)) then
                if (nstab_nonfinite > 0) then
                    call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                        // real_text(h) // ', at t = ' // real_text(t) // ' after ' // &
                        int_text(nstab_nonfinite) // ' steps with non-finite values (NaN/Inf)', &
                        reason_non_finite)
                else if (refusal%reason == reason_det_f) then
                    call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                        // real_text(h) // ', at t = ' // real_text(t) // &
                        '; the model refused the last attempt: ' // refusal%text(), reason_det_f)
                else
                    call status%set(status_solver_failure, 'mexax: step size too small, H = ' &
                        // real_text(h) // ', at t = ' // real_text(t), reason_step_too_small)
                end if
                exit main
            end if
            if ((t + end_factor * h - t_end) * posneg >= 0.0_wp) then
                h = t_end - t
                last = .true.
            end if
            self%native%nstep = self%native%nstep + 1
            if (self%native%nstep > options%max_steps) then
                self%native%nstep = self%native%nstep - 1
                call status%set(status_solver_failure, 'mexax: more than ' // &
                    int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                    real_text(t), reason_max_steps)
                exit main
            end if

            ! ---- one attempt: the ODEX column sequence (§3.4) ----
            decision = undecided
            if (.not. basic_entry .and. (first .or. last)) then
                do j = 1, k
                    if (.not. column(j)) exit
                    if (j >= 2 .and. w%err(j) <= 1.0_wp) then
                        kc = j
                        decision = do_accept
                        exit
                    end if
                end do
                if (decision == undecided) then
                    kc = k
                    call hope()
                end if
            else
                do j = 1, k - 1
                    if (.not. column(j)) exit
                end do
                if (decision == undecided .and. k /= 2 .and. .not. reject) then
                    ! convergence monitor on column k−1
                    kc = k - 1
                    if (w%err(k - 1) <= 1.0_wp) then
                        decision = do_accept
                    else if (w%err(k - 1) > (real(w%nj(k + 1) * w%nj(k), wp) &
                                              / real(w%nj(1)**2, wp))**w%monitor_power) then
                        decision = do_reject
                    end if
                end if
                if (decision == undecided) then
                    if (column(k)) then
                        kc = k
                        if (w%err(k) <= 1.0_wp) then
                            decision = do_accept
                        else
                            call hope()
                        end if
                    end if
                end if
            end if

            select case (decision)
            case (do_stop)
                call count_failure(fst)
                exit main
            case (do_restart)
                ! §3.3/§3.5: H/2, counted in NSTEP and (calibrated) in NREJCT.
                call count_failure(fst)
                self%nstab = self%nstab + 1
                if (restart_is_rejection) self%native%nrejct = self%native%nrejct + 1
                h = h * restart_factor
                reject = .true.
                last = .false.
                basic_entry = .false.
                cycle main
            case (do_reject)
                k = min(k, kc, km - 1)
                k = max(k, 2)
                if (k > 2) then
                    if (w%work(k - 1) < w%order_down * w%work(k)) k = k - 1
                end if
                self%native%nrejct = self%native%nrejct + 1
                call stats%rejections%add(cause_error_test)
                h = posneg * w%hh(k)
                reject = .true.
                last = .false.
                basic_entry = .true.
                cycle main
            end select

            ! ---- converged: project (§3.6), then accept ----
            w%p = w%tab(1:w%nq, kc)
            w%v = w%tab(w%nq + 1:w%nq + w%nv, kc)
            call step_weights(w, kc)
            call project(self, problem, w, t + h, c, status)
            stats%nprj = stats%nprj + 1
            if (.not. status%ok()) then
                cause = cause_projection
                call count_failure(status)
                self%failed_in = mexax_failed_projection
                status%message = 'mexax: ' // status%message // ' at t = ' // &
                    real_text(t + h) // ' (step from t = ' // real_text(t) // ')'
                exit main
            end if
            ! A state the model cannot hold (det F <= 0) is rejected like a
            ! projection that moved too far.
            call problem%admissible(w%p, fst)
            if (.not. fst%ok()) then
                refusal = fst
                c = huge(1.0_wp)
                call stats%rejections%refuse(fst%text())
            else if (c > 1.0_wp) then
                call stats%rejections%add(cause_projection)
            end if
            if (c > 1.0_wp) then
                self%nprj_reject = self%nprj_reject + 1
                self%native%nrejct = self%native%nrejct + 1
                h = h * max(projection_reject_min, projection_reject_safe / c)
                reject = .true.
                last = .false.
                basic_entry = .true.
                cycle main
            end if

            self%native%naccpt = self%native%naccpt + 1
            call refusal%clear()
            t_old = t
            t = t + h
            if (last) t = t_end
            call accept_point(self, problem, w, kc, t_old, t, need_start, status)
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_step
                exit main
            end if
            stats%t_reached = t
            stats%h_last = h
            first = .false.
            if (present(sink)) then
                call emit_outputs()
                if (.not. status%ok()) exit main
                if (stop_requested) then
                    call interrupted()
                    exit main
                end if
            end if

            ! ---- order and step size after acceptance (§3.4) ----
            if (kc == 2) then
                kopt = min(3, km - 1)
                if (reject) kopt = 2
            else if (kc <= k) then
                kopt = kc
                if (w%work(kc - 1) < w%order_down * w%work(kc)) kopt = kc - 1
                if (w%work(kc) < w%order_up * w%work(kc - 1)) kopt = min(kc + 1, km - 1)
            else
                kopt = kc - 1
                if (kc > 3) then
                    if (w%work(kc - 2) < w%order_down * w%work(kc - 1)) kopt = kc - 2
                end if
                if (w%work(kc) < w%order_up * w%work(kopt)) kopt = min(kc, km - 1)
            end if
            kopt = max(kopt, 2)
            if (reject) then
                k = max(min(kopt, kc), 2)
                h = min(abs(h), w%hh(k))
                reject = .false.
            else
                if (kopt <= kc) then
                    h = w%hh(kopt)
                else if (kc < k .and. w%work(kc) < w%order_up * w%work(kc - 1)) then
                    h = w%hh(kc) * w%awork(kopt + 1) / w%awork(kc)
                else
                    h = w%hh(kc) * w%awork(kopt) / w%awork(kc)
                end if
                k = kopt
            end if
            h = posneg * min(abs(h), hmax)
            self%h_next = h
            self%column = k
            if (last) exit main
            basic_entry = .false.
        end do main

        q = w%p0
        v = w%v0
        if (present(lambda)) lambda = w%lam0
        if (present(accel)) accel = w%a0
        call finish()

    contains

        subroutine bad(reason)
            character(len=*), intent(in) :: reason
            call status%set(status_bad_input, 'mexax: ' // reason)
        end subroutine bad

        subroutine interrupted()
            call status%set(status_interrupted, &
                'mexax: interrupted by the output routine at t = ' // real_text(t))
        end subroutine interrupted

        !> Column j of the tableau; false (with `decision` set) on a restart
        !> or a stop.
        logical function column(j) result(ok)
            integer, intent(in) :: j
            integer :: ev
            call base_column(self, problem, w, t, h, w%nj(j), j <= stability_columns, ev, fst)
            if (ev == ev_ok) then
                call extrapolate_column(w, j)
                if (j >= 2) call column_error(w, j, h, hmax, ev)
                if (ev == ev_restart .and. .not. ieee_is_finite(w%err(j))) &
                    nstab_nonfinite = nstab_nonfinite + 1
            else if (ev /= ev_stop .and. fst%reason == reason_non_finite) then
                nstab_nonfinite = nstab_nonfinite + 1
            end if
            if (ev == ev_refused) refusal = fst
            cause = merge(cause_model_refused, cause_unstable, ev == ev_refused)
            select case (ev)
            case (ev_restart, ev_refused)
                decision = do_restart
            case (ev_stop)
                cause = merge(cause_singular_matrix, cause_model_refused, &
                    fst%reason == reason_singular_matrix)
                self%failed_in = mexax_failed_step
                status = fst
                status%message = 'mexax: ' // fst%message // ' at t = ' // real_text(t) // &
                    ' (step H = ' // real_text(h) // ')'
                decision = do_stop
            end select
            ok = ev == ev_ok
        end function column

        !> Count the failed attempt by `cause`; a refusal (`why` says by
        !> whom) keeps its reason. A failed projection is the model's when
        !> a user function failed in it, and a singular matrix's.
        subroutine count_failure(why)
            type(status_t), intent(in) :: why
            if (cause == cause_projection .and. why%reason == reason_singular_matrix) then
                cause = cause_singular_matrix
            else if (cause == cause_projection .and. (why%reason == reason_user_function .or. &
                                                       why%reason == reason_det_f)) then
                cause = cause_model_refused
            end if
            if (cause == cause_model_refused) then
                call stats%rejections%refuse(why%text())
            else
                call stats%rejections%add(cause)
            end if
        end subroutine count_failure

        !> Hope for convergence in column k+1 (§3.4).
        subroutine hope()
            if (k + 1 > km) then
                decision = do_reject
            else if (w%err(k) > (real(w%nj(k + 1), wp) / real(w%nj(1), wp))**w%varpi) then
                decision = do_reject
            else if (column(k + 1)) then
                kc = k + 1
                decision = merge(do_accept, do_reject, w%err(k + 1) <= 1.0_wp)
            end if
        end subroutine hope

        subroutine set_dense_start()
            integer :: nq, nv
            nq = w%nq
            nv = w%nv
            self%dense%t_old = t
            self%dense%t = t
            self%dense%y1(1:nq) = w%p0
            self%dense%y1(nq + 1:nq + nv) = w%v0
            self%dense%y1(nq + nv + 1:) = w%lam0
            self%dense%d1(1:nq) = w%pdot0
            self%dense%d1(nq + 1:nq + nv) = w%a0
            self%dense%d1(nq + nv + 1:) = 0.0_wp
            self%dense%y0 = self%dense%y1
            self%dense%d0 = self%dense%d1
        end subroutine set_dense_start

        !> Dense output at requested times in (t_old, t], then the step sink.
        subroutine emit_outputs()
            do while (iout <= nout)
                if ((options%output_times(iout) - t) * posneg > 0.0_wp) exit
                call self%dense%evaluate(options%output_times(iout), yout)
                call sink%output(options%output_times(iout), yout, status)
                iout = iout + 1
                if (.not. status%ok()) return
            end do
            if (want_steps) call sink%step(self%native%naccpt + 1, t_old, t, self%dense%y1, &
                self%dense, stop_requested, status)
        end subroutine emit_outputs

        !> Common statistics from the native counters (docs/solvers.md).
        subroutine finish()
            type(status_t) :: sink_status
            stats%nst = self%native%nstep
            stats%nac = self%native%naccpt
            stats%nrj = stats%nst - stats%nac
            stats%nfe = self%native%nfcn
            stats%nje = 0
            stats%ndec = self%native%ndec
            stats%nsol = self%native%nsol
            stats%t_reached = t
            stats%cpu = timer%cpu()
            stats%wall = timer%wall()
            call stats%rejections%annotate(status)
            if (present(sink)) then
                call sink%finish(sink_status)
                if (status%ok() .and. .not. sink_status%ok()) status = sink_status
            end if
        end subroutine finish
    end subroutine mexax_integrate_mechanical

    !> One macro step of size big_h from (t, q, v) without projection or
    !> control: the diagonal T_{j,j} of columns j = 1..columns in q_out(:, j),
    !> v_out(:, j). For order studies (§8: local error of T_{j,j} in q is
    !> O(H^{j+1}) for (E), O(H^{2j+1}) for (M)).
    subroutine mexax_extrapolate(self, problem, t, q, v, big_h, columns, q_out, v_out, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, q(:), v(:), big_h
        integer, intent(in) :: columns          !! 1..12
        real(wp), intent(out) :: q_out(:, :)    !! (nq, columns)
        real(wp), intent(out) :: v_out(:, :)    !! (nv, columns)
        type(status_t), intent(out) :: status
        type(workspace_t) :: w
        integer :: j, ev
        self%native = mexax_native_t()
        if (columns < 1 .or. columns > mexax_max_columns) then
            call status%set(status_bad_input, 'mexax: columns must lie in 1..12')
            return
        end if
        call setup_workspace(w, problem, self%base, columns, 'auto', status)
        if (.not. status%ok()) return
        w%rtol = 1.0_wp
        w%atol = 1.0_wp
        w%p0 = q
        w%v0 = v
        call start_point(self, problem, w, t, status)
        if (.not. status%ok()) return
        do j = 1, columns
            call base_column(self, problem, w, t, big_h, w%nj(j), .false., ev, status)
            if (ev /= ev_ok) then
                if (status%ok()) call status%set(status_solver_failure, &
                    'mexax: non-finite values in the base step', reason_non_finite)
                return
            end if
            call extrapolate_column(w, j)
            q_out(:, j) = w%tab(1:w%nq, j)
            v_out(:, j) = w%tab(w%nq + 1:w%nq + w%nv, j)
        end do
    end subroutine mexax_extrapolate

    !> Allocate the workspace for `km` columns and set up the linear solver
    !> of the augmented system ('auto' | 'dense' | 'klu').
    subroutine setup_workspace(w, problem, base, km, linear_solver, status, ordering, &
                               classic_lu)
        type(workspace_t), intent(out) :: w
        class(mechanical_problem_t), intent(inout) :: problem
        integer, intent(in) :: base, km
        character(len=*), intent(in) :: linear_solver
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: ordering !! 'auto' | 'amd' | 'nd'
        !> dense: the classic elimination order (options%classic_lu)
        logical, intent(in), optional :: classic_lu
        integer :: j, nq, nv, nc, stat
        integer(i8) :: entries
        call default_blas_threads()
        if (present(classic_lu)) w%classic_lu = classic_lu
        nq = problem%nq
        nv = problem%nv
        nc = problem%nc
        w%nq = nq
        w%nv = nv
        w%nc = nc
        w%na = nv + nc
        w%ne = nq + nv
        w%ny = nq + 2 * nv + nc
        w%km = km
        allocate (w%nj(km), w%err(km), w%hh(km), w%work(km), w%awork(km))
        if (base == mexax_base_euler) then
            w%nj = euler_sequence(1:km)
            w%varpi = 1.0_wp
            w%order_down = euler_fac3
            w%order_up = euler_fac4
            w%monitor_power = euler_monitor_power
        else
            w%nj = [(2 * j, j = 1, km)]
            w%varpi = 2.0_wp
            w%monitor_power = w%varpi
        end if
        w%awork(1) = real(w%nj(1) + work_offset, wp)
        do j = 2, km
            w%awork(j) = w%awork(j - 1) + real(w%nj(j), wp)
        end do
        w%err = 0.0_wp
        w%hh = 0.0_wp
        w%work = 0.0_wp
        allocate (w%rtol(w%ne), w%atol(w%ne), w%wt(w%ne), w%wst(nv), w%p0(nq), w%v0(nv), &
            w%a0(nv), w%lam0(nc), w%f0(nv), w%pdot0(nq), w%rhs(w%na), w%p(nq), w%pp(nq), &
            w%pn(nq), w%v(nv), w%vp(nv), w%f(nv), w%pdot(nq), w%gt(nc), w%acc(nv), w%lam(nc), &
            w%x(w%ny), w%d(w%ny), w%tab(w%ny, km), stat=stat)
        if (stat /= 0) then
            entries = 3_i8 * w%ne + w%na + 6_i8 * nq + 8_i8 * nv + 3_i8 * nc + (2_i8 + km) * w%ny
            call out_of_memory(status, 'mexax workspace', entries, 8)
            return
        end if
        select case (trim(adjustl(linear_solver)))
        case ('auto')
            w%sparse = problem%has_sparse() .and. w%na >= mexax_auto_klu_order
        case ('dense')
            w%sparse = .false.
        case ('klu')
            if (.not. problem%has_sparse()) then
                call status%set(status_bad_input, "mexax: linear_solver = 'klu' needs M and " // &
                    'G in sparse form, which this mechanical problem does not provide ' // &
                    '(has_sparse, mass_pattern/mass_sparse, constraint_jacobian_pattern/' // &
                    "constraint_jacobian_sparse); use 'dense' or 'auto'")
                return
            end if
            w%sparse = .true.
        case default
            call status%set(status_bad_input, "mexax: linear_solver = '" // &
                trim(linear_solver) // "': the augmented matrix [M G^T; G 0] is " // &
                "factored by 'dense' (LAPACK) or 'klu'; use 'auto', 'dense' or 'klu'")
            return
        end select
        if (w%sparse) then
            if (present(ordering)) w%klu_ordering = klu_ordering_code(ordering)
            call setup_sparse(w, problem, status)
        else
            allocate (w%m0%dense(nv, nv), w%g0%dense(nc, nv), w%mm%dense(nv, nv), &
                w%gm%dense(nc, nv), w%gn%dense(nc, nv), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'mexax dense M and G', &
                    int(nv, i8) * (2_i8 * nv + 3_i8 * nc), 8)
                return
            end if
            call w%kkt%init_dense(nv, nc, w%classic_lu, status)
        end if
    end subroutine setup_workspace

    !> KLU path: the patterns of M and G from the problem and the saddle-point
    !> matrix K = [M Gᵀ; G 0] on them (flexmbs_linalg_saddle_point).
    subroutine setup_sparse(w, problem, status)
        type(workspace_t), intent(inout) :: w
        class(mechanical_problem_t), intent(inout) :: problem
        type(status_t), intent(out) :: status
        integer :: nv, nc, stat
        nv = w%nv
        nc = w%nc
        call problem%mass_pattern(w%mpat, status)
        if (.not. pattern_ok(w%mpat, nv, nv, 'mass_pattern')) return
        call problem%constraint_jacobian_pattern(w%gpat, status)
        if (.not. pattern_ok(w%gpat, nc, nv, 'constraint_jacobian_pattern')) return
        call w%kkt%init(w%mpat, w%gpat, status, w%klu_ordering)
        if (.not. status%ok()) then
            status%message = 'mexax: ' // status%message
            return
        end if
        allocate (w%m0%values(w%mpat%nnz), w%mm%values(w%mpat%nnz), w%g0%values(w%gpat%nnz), &
            w%gm%values(w%gpat%nnz), w%gn%values(w%gpat%nnz), stat=stat)
        if (stat /= 0) call out_of_memory(status, 'mexax sparse M and G values', &
            2 * w%mpat%nnz + 3 * w%gpat%nnz, 8)
    contains
        logical function pattern_ok(pattern, nrow, ncol, what) result(ok)
            type(csc_matrix_t), intent(in) :: pattern
            integer, intent(in) :: nrow, ncol
            character(len=*), intent(in) :: what
            ok = .false.
            if (.not. status%ok()) then
                status%message = 'mexax: ' // what // ': ' // status%message
            else if (.not. pattern%is_built()) then
                call status%set(status_bad_input, 'mexax: ' // what // ' built no pattern')
            else if (pattern%nrow /= nrow .or. pattern%ncol /= ncol) then
                call status%set(status_bad_input, 'mexax: ' // what // ' is ' // &
                    int_text(pattern%nrow) // ' x ' // int_text(pattern%ncol) // &
                    ', expected ' // int_text(nrow) // ' x ' // int_text(ncol))
            else
                ok = .true.
            end if
        end function pattern_ok
    end subroutine setup_sparse

    !> M(t, q) into blk (dense or CSC values).
    subroutine eval_mass(problem, w, t, q, blk, status)
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(in) :: w
        real(wp), intent(in) :: t, q(:)
        type(block_t), intent(inout) :: blk
        type(status_t), intent(inout) :: status
        if (w%sparse) then
            call problem%mass_sparse(t, q, blk%values, status)
        else
            call problem%mass(t, q, blk%dense, status)
        end if
    end subroutine eval_mass

    !> G(t, q) into blk (dense or CSC values).
    subroutine eval_jacobian(problem, w, t, q, blk, status)
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(in) :: w
        real(wp), intent(in) :: t, q(:)
        type(block_t), intent(inout) :: blk
        type(status_t), intent(inout) :: status
        if (w%sparse) then
            call problem%constraint_jacobian_sparse(t, q, blk%values, status)
        else
            call problem%constraint_jacobian(t, q, blk%dense, status)
        end if
    end subroutine eval_jacobian

    !> dst = src without reallocation.
    pure subroutine copy_block(dst, src)
        type(block_t), intent(inout) :: dst
        type(block_t), intent(in) :: src
        if (allocated(src%dense)) dst%dense(:, :) = src%dense
        if (allocated(src%values)) dst%values(:) = src%values
    end subroutine copy_block

    !> f, T v, M and G at the start point of a macro step: shared by every
    !> column and every attempt from this point (§3.2).
    subroutine start_point(self, problem, w, t, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t
        type(status_t), intent(out) :: status
        call problem%forces(t, w%p0, w%v0, w%f0, status)
        if (status%ok()) call problem%kinematics(t, w%p0, w%v0, w%pdot0, status)
        if (status%ok()) call eval_mass(problem, w, t, w%p0, w%m0, status)
        if (status%ok()) call eval_jacobian(problem, w, t, w%p0, w%g0, status)
        self%native%nfprob = self%native%nfprob + 1
        self%native%nfcn = self%native%nfcn + 1
        if (.not. status%ok()) then
            status%message = 'mexax: user function failed at the step start t = ' // &
                real_text(t) // ': ' // status%text()
            status%code = status_solver_failure
            if (status%reason /= reason_det_f) status%reason = reason_user_function
        end if
    end subroutine start_point

    !> a and λ at t0 from [M Gᵀ; G 0][a; λ] = [f; −γ] when the problem
    !> provides the curvature γ; otherwise a = 0 and λ as given. They serve
    !> the dense output of the first step and the output at t0.
    subroutine consistent_acceleration(self, problem, w, t, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t
        type(status_t), intent(out) :: status
        type(status_t) :: cst
        integer :: nv
        nv = w%nv
        call problem%constraint_curvature(t, w%p0, w%v0, w%gt, cst)
        if (.not. cst%ok()) return
        call assemble(w, w%m0, w%g0, w%g0)
        call factor(w, cst)
        if (.not. cst%ok()) then
            call status%set(status_solver_failure, 'mexax: augmented matrix [M G^T; G 0] &
                &is singular at t0 = ' // real_text(t), reason_singular_matrix)
            return
        end if
        self%native%ndec = self%native%ndec + 1
        w%rhs(1:nv) = w%f0
        w%rhs(nv + 1:) = -w%gt
        call solve(w, w%rhs)
        self%native%nsol = self%native%nsol + 1
        w%a0 = w%rhs(1:nv)
        w%lam0 = w%rhs(nv + 1:)
    end subroutine consistent_acceleration

    !> K = [mtop gtopᵀ; gbot 0] into the saddle-point matrix (no allocation).
    subroutine assemble(w, mtop, gtop, gbot)
        type(workspace_t), intent(inout) :: w
        type(block_t), intent(in) :: mtop, gtop, gbot
        if (w%sparse) then
            call w%kkt%assemble(mtop%values, gbot%values, gtop%values)
        else
            call w%kkt%assemble(mtop%dense, gbot%dense, gtop%dense)
        end if
    end subroutine assemble

    !> LU of the assembled K: LAPACK or the classic order, or KLU reusing the
    !> last pivot order while it stays good (klu_factor_t%refactor).
    subroutine factor(w, status)
        type(workspace_t), intent(inout) :: w
        type(status_t), intent(out) :: status
        call w%kkt%factor(status)
    end subroutine factor

    !> b ← K⁻¹ b with the factorisation of `factor`.
    subroutine solve(w, b)
        type(workspace_t), intent(inout) :: w
        real(wp), intent(inout) :: b(:)
        type(status_t) :: lst
        ! fails only without a factorisation, which `factor` excluded
        call w%kkt%solve(b, lst)
    end subroutine solve

    !> Factor the augmented matrix and solve for w%rhs; ev_stop on a singular matrix.
    subroutine factor_solve(self, w, where, ev, status)
        class(mexax_t), intent(inout) :: self
        type(workspace_t), intent(inout) :: w
        character(len=*), intent(in) :: where
        integer, intent(out) :: ev
        type(status_t), intent(inout) :: status
        type(status_t) :: lst
        ev = ev_ok
        call factor(w, lst)
        if (.not. lst%ok() .and. lst%reason == reason_non_finite) then
            ! KLU refuses Inf/NaN entries (of M or G: the model's), which LAPACK
            ! would pass on: restart
            call status%set(status_solver_failure, 'non-finite values in the augmented ' // &
                'matrix ' // where, reason_non_finite)
            ev = ev_refused
            return
        else if (.not. lst%ok()) then
            call status%set(status_solver_failure, 'augmented matrix [M G^T; G 0] is singular ' &
                // where, reason_singular_matrix)
            ev = ev_stop
            return
        end if
        self%native%ndec = self%native%ndec + 1
        call solve(w, w%rhs)
        self%native%nsol = self%native%nsol + 1
    end subroutine factor_solve

    !> A failed user call becomes a stop with the routine's name; non-finite
    !> `values` it returned fail it too (reason_non_finite: a refusal).
    logical function user_failed(status, what, values) result(failed)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: what
        real(wp), intent(in), optional :: values(:)
        integer :: i
        if (status%ok() .and. present(values)) then
            do i = 1, size(values)
                if (ieee_is_finite(values(i))) cycle
                call status%set(status_solver_failure, 'non-finite value in component ' // &
                    int_text(i), reason_non_finite)
                exit
            end do
        end if
        failed = .not. status%ok()
        if (failed) then
            status%message = 'user function ' // what // ' failed: ' // status%text()
            status%code = status_solver_failure
            ! det F <= 0 and non-finite values are the model refusing the
            ! trial state: a restart with H/2 (base_column), not a stop.
            if (status%reason /= reason_det_f .and. status%reason /= reason_non_finite) &
                status%reason = reason_user_function
        end if
    end function user_failed

    !> T_{j,1} in w%x = (q, v, a, λ) after n substeps of the base method.
    !> ev_restart on non-finite values or a failed stability check (§3.5),
    !> ev_refused when the model refused a substep (det F ≤ 0, non-finite
    !> forces), ev_stop (status set) on a singular matrix or a failed user
    !> function.
    subroutine base_column(self, problem, w, t, big_h, n, check_stability, ev, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t, big_h
        integer, intent(in) :: n
        logical, intent(in) :: check_stability
        integer, intent(out) :: ev
        type(status_t), intent(out) :: status
        integer :: nq, nv
        nq = w%nq
        nv = w%nv
        w%wst = w%rtol(nq + 1:) * abs(w%v0) + w%atol(nq + 1:)
        if (self%base == mexax_base_euler) then
            call euler_substeps()
        else
            call midpoint_substeps()
        end if
        if (ev /= ev_ok) return
        w%x(1:nq) = w%p
        w%x(nq + 1:nq + nv) = w%v
        w%x(nq + nv + 1:nq + 2 * nv) = w%acc
        w%x(nq + 2 * nv + 1:) = w%lam

    contains

        !> (E), §3.2: p_{i+1} = p_i + h T v_i, then one augmented solve for
        !> (v_{i+1}, h λ_{i+1}) with the matrices at p_{i+1}.
        subroutine euler_substeps()
            integer :: i
            real(wp) :: h, ti, tn
            h = big_h / n
            w%p = w%p0
            w%v = w%v0
            w%f = w%f0
            ev = ev_ok
            do i = 0, n - 1
                ti = t + big_h * real(i, wp) / n
                tn = t + big_h * real(i + 1, wp) / n
                if (i > 0) then
                    ! one FPROB call (flags 4, 5): f and T v at (t_i, p_i, v_i)
                    call problem%forces(ti, w%p, w%v, w%f, status)
                    self%native%nfcn = self%native%nfcn + 1
                    self%native%nfprob = self%native%nfprob + 1
                    if (user_failed(status, 'forces', w%f)) exit
                    call problem%kinematics(ti, w%p, w%v, w%pdot, status)
                    if (user_failed(status, 'kinematics')) exit
                else
                    w%pdot = w%pdot0   ! shared start point (§3.2)
                end if
                w%pn = w%p + h * w%pdot
                call eval_mass(problem, w, tn, w%pn, w%mm, status)
                if (user_failed(status, 'mass')) exit
                call eval_jacobian(problem, w, tn, w%pn, w%gm, status)
                if (user_failed(status, 'constraint_jacobian')) exit
                call problem%constraint_time_derivative(tn, w%pn, w%gt, status)
                if (user_failed(status, 'constraint_time_derivative')) exit
                self%native%nfprob = self%native%nfprob + 1
                call block_times(w, w%mm, w%mpat, w%v, w%rhs(1:nv))
                w%rhs(1:nv) = w%rhs(1:nv) + h * w%f
                self%native%nmult = self%native%nmult + 1
                w%rhs(nv + 1:) = -w%gt
                call assemble(w, w%mm, w%gm, w%gm)
                call factor_solve(self, w, 'in a step', ev, status)
                if (ev /= ev_ok) return
                w%vp = w%v
                w%v = w%rhs(1:nv)
                w%lam = w%rhs(nv + 1:) / h
                w%acc = (w%v - w%vp) / h
                w%p = w%pn
                if (unstable(i)) return
            end do
            if (.not. status%ok()) ev = merge(ev_refused, ev_stop, status%reason == reason_det_f &
                                              .or. status%reason == reason_non_finite)
        end subroutine euler_substeps

        !> (M), §3.2: an explicit start step, then q_{i+1} = q_{i−1} + 2h T v_i,
        !> v_{i+1} = v_{i−1} + 2h a_i with [M(q_i) G(q_i)ᵀ; G(q_{i+1}) 0].
        subroutine midpoint_substeps()
            integer :: i
            real(wp) :: h, ti, tn
            h = big_h / n
            ev = ev_ok
            tn = t + big_h / n
            w%pp = w%p0
            w%vp = w%v0
            w%p = w%p0 + h * w%pdot0
            call eval_jacobian(problem, w, tn, w%p, w%gn, status)
            if (user_failed(status, 'constraint_jacobian')) then
                ev = ev_stop
                return
            end if
            call problem%constraint_time_derivative(tn, w%p, w%gt, status)
            if (user_failed(status, 'constraint_time_derivative')) then
                ev = ev_stop
                return
            end if
            self%native%nfprob = self%native%nfprob + 1
            w%rhs(1:nv) = w%f0
            call block_times(w, w%gn, w%gpat, w%v0, w%rhs(nv + 1:))
            w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt) / h
            call assemble(w, w%m0, w%g0, w%gn)
            call factor_solve(self, w, 'in a step', ev, status)
            if (ev /= ev_ok) return
            w%acc = w%rhs(1:nv)
            w%lam = w%rhs(nv + 1:)
            w%v = w%v0 + h * w%acc
            call copy_block(w%gm, w%gn)
            do i = 1, n - 1
                ti = t + big_h * real(i, wp) / n
                tn = t + big_h * real(i + 1, wp) / n
                ! one FPROB call (flags 1, 4, 5) at (t_i, q_i, v_i), one (2, 8) at q_{i+1}
                call problem%forces(ti, w%p, w%v, w%f, status)
                self%native%nfcn = self%native%nfcn + 1
                self%native%nfprob = self%native%nfprob + 1
                if (user_failed(status, 'forces', w%f)) exit
                call eval_mass(problem, w, ti, w%p, w%mm, status)
                if (user_failed(status, 'mass')) exit
                call problem%kinematics(ti, w%p, w%v, w%pdot, status)
                if (user_failed(status, 'kinematics')) exit
                w%pn = w%pp + 2.0_wp * h * w%pdot
                call eval_jacobian(problem, w, tn, w%pn, w%gn, status)
                if (user_failed(status, 'constraint_jacobian')) exit
                call problem%constraint_time_derivative(tn, w%pn, w%gt, status)
                if (user_failed(status, 'constraint_time_derivative')) exit
                self%native%nfprob = self%native%nfprob + 1
                w%rhs(1:nv) = w%f
                call block_times(w, w%gn, w%gpat, w%vp, w%rhs(nv + 1:))
                w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt) / (2.0_wp * h)
                call assemble(w, w%mm, w%gm, w%gn)
                call factor_solve(self, w, 'in a step', ev, status)
                if (ev /= ev_ok) return
                w%acc = w%rhs(1:nv)
                w%lam = w%rhs(nv + 1:)
                w%pp = w%p
                w%p = w%pn
                ! v_{i+1} = v_{i−1} + 2h a_i; vp becomes v_i
                w%f = w%vp + 2.0_wp * h * w%acc
                w%vp = w%v
                w%v = w%f
                call copy_block(w%gm, w%gn)
                if (unstable(i)) return
            end do
            if (.not. status%ok()) ev = merge(ev_refused, ev_stop, status%reason == reason_det_f &
                                              .or. status%reason == reason_non_finite)
        end subroutine midpoint_substeps

        !> Non-finite values, or the §3.5 check after the second substep
        !> (i = 1): ‖v2 − v1‖ > 2 ‖v2‖ in the weights of the step start.
        logical function unstable(i)
            integer, intent(in) :: i
            unstable = .not. (all(ieee_is_finite(w%v)) .and. all(ieee_is_finite(w%p)))
            if (unstable) then
                call status%set(status_solver_failure, 'non-finite values', reason_non_finite)
            else if (check_stability .and. i == 1) then
                unstable = rms(w%v - w%vp, w%wst) > stability_ratio * rms(w%v, w%wst)
            end if
            if (unstable) ev = ev_restart
        end function unstable
    end subroutine base_column

    !> Aitken–Neville: w%tab(:, l) holds T_{j−1,l}; afterwards T_{j,l}.
    subroutine extrapolate_column(w, j)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        integer :: l
        real(wp) :: ratio
        do l = 1, j - 1
            ratio = (real(w%nj(j), wp) / real(w%nj(j - l), wp))**w%varpi
            w%d = (w%x - w%tab(:, l)) / (ratio - 1.0_wp)
            w%tab(:, l) = w%x
            w%x = w%x + w%d
        end do
        w%tab(:, j) = w%x
    end subroutine extrapolate_column

    !> Weights rtol max(|y0|, |T_{j,j}|) + atol on (q, v) (§3.3).
    subroutine step_weights(w, j)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        w%wt(1:w%nq) = w%rtol(1:w%nq) * max(abs(w%p0), abs(w%tab(1:w%nq, j))) &
            + w%atol(1:w%nq)
        w%wt(w%nq + 1:) = w%rtol(w%nq + 1:) * max(abs(w%v0), abs(w%tab(w%nq + 1:w%ne, j))) &
            + w%atol(w%nq + 1:)
    end subroutine step_weights

    !> err_j, the column step size H_j and the work W_j (§3.3, §3.4);
    !> ev_restart on divergence or non-finite error.
    subroutine column_error(w, j, big_h, hmax, ev)
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: j
        real(wp), intent(in) :: big_h, hmax
        integer, intent(out) :: ev
        real(wp) :: expo, fmin, fac, err, rho
        ev = ev_ok
        call step_weights(w, j)
        err = rms(w%tab(1:w%ne, j) - w%tab(1:w%ne, j - 1), w%wt)
        w%err(j) = err
        rho = merge(divergence_euler, divergence_midpoint, w%varpi == 1.0_wp)
        if (.not. ieee_is_finite(err) .or. err * epsilon(1.0_wp) >= 1.0_wp) then
            ev = ev_restart
            return
        end if
        if (j > 2) then
            if (err >= max(rho * w%err(j - 1), 1.0_wp)) then
                ev = ev_restart
                return
            end if
        end if
        if (w%varpi == 1.0_wp) then
            expo = 1.0_wp / j
        else
            expo = 1.0_wp / (2 * j - 1)
        end if
        fmin = fac1**expo
        fac = min(fac2 / fmin, max(fmin, (err / safe1)**expo / safe2))
        w%hh(j) = min(abs(big_h) / fac, hmax)
        w%work(j) = w%awork(j) / w%hh(j)
    end subroutine column_error

    !> Projection of (w%p, w%v) at time t (§3.6): positions onto g = 0 by
    !> simplified Newton with the matrix at p̃, then velocities onto
    !> G v + g_I = 0 at the projected p. c is the rejection ratio.
    subroutine project(self, problem, w, t, c, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        real(wp), intent(in) :: t
        real(wp), intent(out) :: c
        type(status_t), intent(out) :: status
        integer :: m, nq, nv, ev
        real(wp) :: eps, eps_old
        nq = w%nq
        nv = w%nv
        c = 0.0_wp
        w%pn = w%p   ! p̃
        w%vp = w%v   ! ṽ
        call eval_mass(problem, w, t, w%pn, w%mm, status)
        if (.not. user_failed(status, 'mass')) &
            call eval_jacobian(problem, w, t, w%pn, w%gm, status)
        if (user_failed(status, 'constraint_jacobian')) return
        self%native%nfprob = self%native%nfprob + 1
        call assemble(w, w%mm, w%gm, w%gm)
        call factor(w, status)
        if (.not. status%ok()) then
            status%message = 'augmented matrix [M C^T; C 0] is singular in the position &
                &projection'
            return
        end if
        self%native%ndec = self%native%ndec + 1
        eps_old = 0.0_wp
        do m = 0, itmax - 1
            call problem%constraint(t, w%p, w%gt, status)
            self%native%ngcn = self%native%ngcn + 1
            self%native%nfprob = self%native%nfprob + 1
            if (user_failed(status, 'constraint')) return
            w%rhs(1:nv) = 0.0_wp
            w%rhs(nv + 1:) = -w%gt
            call solve(w, w%rhs)
            self%native%nsol = self%native%nsol + 1
            ! one FPROB call (flag 5): T(p̃) δ
            call problem%kinematics(t, w%pn, w%rhs(1:nv), w%pdot, status)
            self%native%nfprob = self%native%nfprob + 1
            if (user_failed(status, 'kinematics')) return
            w%p = w%p + w%pdot
            eps = rms(w%pdot, w%wt(1:nq))
            if (eps <= epsreq) exit
            if (.not. ieee_is_finite(eps) .or. (m >= 1 .and. eps > projection_growth * eps_old) &
                .or. m + 1 >= itmax) then
                call status%set(status_solver_failure, 'position projection did not converge &
                    &(iteration ' // int_text(m + 1) // ', weighted correction ' // &
                    real_text(eps) // ')', reason_projection)
                return
            end if
            eps_old = eps
        end do
        call eval_mass(problem, w, t, w%p, w%mm, status)
        if (.not. user_failed(status, 'mass')) &
            call eval_jacobian(problem, w, t, w%p, w%gm, status)
        if (.not. user_failed(status, 'constraint_jacobian')) &
            call problem%constraint_time_derivative(t, w%p, w%gt, status)
        if (user_failed(status, 'constraint_time_derivative')) return
        self%native%nfprob = self%native%nfprob + 1
        w%rhs(1:nv) = 0.0_wp
        call block_times(w, w%gm, w%gpat, w%vp, w%rhs(nv + 1:))
        w%rhs(nv + 1:) = -(w%rhs(nv + 1:) + w%gt)
        call assemble(w, w%mm, w%gm, w%gm)
        call factor_solve(self, w, 'in the velocity projection', ev, status)
        if (ev /= ev_ok) return
        w%v = w%vp + w%rhs(1:nv)
        c = max(rms(w%p - w%pn, w%wt(1:nq)) / facp, rms(w%v - w%vp, w%wt(nq + 1:)) / facv)
        if (.not. ieee_is_finite(c)) call status%set(status_solver_failure, &
            'non-finite values in the projection', reason_non_finite)
    end subroutine project

    !> Take the projected (w%p, w%v) and the extrapolated a, λ of column kc
    !> as the new point, and update the dense output.
    subroutine accept_point(self, problem, w, kc, t_old, t, need_start, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(inout) :: w
        integer, intent(in) :: kc
        real(wp), intent(in) :: t_old, t
        logical, intent(out) :: need_start !! start_point still to be evaluated at t
        type(status_t), intent(out) :: status
        integer :: nq, nv, nc
        nq = w%nq
        nv = w%nv
        nc = w%nc
        associate (dn => self%dense)
            dn%t_old = t_old
            dn%t = t
            dn%y0 = dn%y1
            dn%d0 = dn%d1
            w%p0 = w%p
            w%v0 = w%v
            w%a0 = w%tab(nq + nv + 1:nq + 2 * nv, kc)
            w%lam0 = w%tab(nq + 2 * nv + 1:, kc)
            need_start = .true.
            if (self%consistent_accelerations) then
                ! f, T v, M, G at t serve the next step as well
                call start_point(self, problem, w, t, status)
                if (.not. status%ok()) return
                need_start = .false.
                call consistent_acceleration(self, problem, w, t, status)
                if (.not. status%ok()) return
                w%pdot = w%pdot0
            else
                call problem%kinematics(t, w%p0, w%v0, w%pdot, status)
                if (user_failed(status, 'kinematics')) return
            end if
            dn%y1(1:nq) = w%p0
            dn%y1(nq + 1:nq + nv) = w%v0
            dn%y1(nq + nv + 1:) = w%lam0
            dn%d1(1:nq) = w%pdot
            dn%d1(nq + 1:nq + nv) = w%a0
            if (nc > 0) then
                ! λ linear on the step: both end slopes are the secant.
                dn%d1(nq + nv + 1:) = (dn%y1(nq + nv + 1:) - dn%y0(nq + nv + 1:)) / (t - t_old)
                dn%d0(nq + nv + 1:) = dn%d1(nq + nv + 1:)
            end if
        end associate
        if (.not. all(ieee_is_finite(self%dense%y1))) then
            call status%set(status_solver_failure, 'mexax: non-finite values accepted at t = ' &
                // real_text(t), reason_non_finite)
        end if
    end subroutine accept_point

    !> y = B x for a block B (M or G) stored dense or on its pattern `pat`.
    pure subroutine block_times(w, b, pat, x, y)
        type(workspace_t), intent(in) :: w
        type(block_t), intent(in) :: b
        type(csc_matrix_t), intent(in) :: pat !! w%mpat for M, w%gpat for G
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: y(:)
        if (w%sparse) then
            call pattern_matvec(pat, b%values, x, y)
        else
            call matvec(b%dense, x, y)
        end if
    end subroutine block_times

    !> y = a x without temporaries.
    pure subroutine matvec(a, x, y)
        real(wp), intent(in) :: a(:, :), x(:)
        real(wp), intent(out) :: y(:)
        integer :: j
        y = 0.0_wp
        do j = 1, size(x)
            y = y + a(:, j) * x(j)
        end do
    end subroutine matvec

    !> RMS norm of x/w.
    pure real(wp) function rms(x, w)
        real(wp), intent(in) :: x(:), w(:)
        if (size(x) == 0) then
            rms = 0.0_wp
        else
            rms = sqrt(sum((x / w)**2) / size(x))
        end if
    end function rms
end module flexmbs_dae_mexax
