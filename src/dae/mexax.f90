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
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_singular_matrix, &
        cause_model_refused, cause_projection, cause_unstable
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_mexax_control, only: mexax_base_midpoint, mexax_base_euler, &
        mexax_max_columns
    use flexmbs_dae_mexax_workspace, only: workspace_t, mexax_native_t, mexax_auto_klu_order, &
        setup_workspace, ev_ok, ev_restart, ev_stop, ev_refused, user_failed
    use flexmbs_dae_mexax_tableau, only: start_point, base_column, extrapolate_column, &
        step_weights, column_error
    use flexmbs_dae_mexax_projection, only: project
    implicit none
    private

    public :: mexax_base_midpoint, mexax_base_euler, mexax_max_columns, mexax_native_t, &
        mexax_auto_klu_order

    !> Where a stopping failure happened (mexax_t%failed_in): the classic face
    !> tells IERR −15/−17 (in a step) from −16/−18 (in the projection).
    integer, parameter, public :: mexax_failed_none = 0, mexax_failed_step = 1, &
        mexax_failed_projection = 2

    ! §3.5: the stability check runs in columns 1..2 (ODEX's JSTAB = 2).
    integer, parameter :: stability_columns = 2
    ! §3.3/§3.5/§3.8: divergence, instability and non-finite values halve H
    ! (ODEX's SAFE3 = 0.5); such a restart counts in NSTEP, not in NREJCT (ODEX).
    real(wp), parameter :: restart_factor = 0.5_wp
    ! §3.4: the step ends at TFIN when t + 1.01 H passes it (ODEX).
    real(wp), parameter :: end_factor = 1.01_wp
    ! §3.8 [R]: stop when |H| ≤ 10 EPMACH |t| (the original's EPMACH = 1e-17;
    ! the form is RADAU5's 0.1 |H| ≤ uround |t| [HW96 IV.8]); |t_end − t0|
    ! stands in for |t| near t = 0, where the rule never fires (own rule).
    real(wp), parameter :: epmach = 1.0e-17_wp, small_step_factor = 10.0_wp
    ! §4.2 [R]: automatic initial step 1e-3 |t_end − t0| (reconstructed).
    real(wp), parameter :: h0_fraction = 1.0e-3_wp
    ! §3.6: after a projection rejection H ← H max(0.45, 0.9/c) (reconstructed).
    real(wp), parameter :: projection_reject_min = 0.45_wp, projection_reject_safe = 0.9_wp

    ! Outcomes of an attempt.
    integer, parameter :: undecided = 0, do_accept = 1, do_reject = 2, do_restart = 3, do_stop = 4

    !> Cubic Hermite interpolation on the last accepted step (§3.7): q from
    !> (q, T v), v from (v, a) at both ends; λ linear.
    type, extends(dense_output_t), public :: mexax_dense_t
        real(wp) :: t_old = 0.0_wp, t = 0.0_wp
        real(wp), allocatable :: y0(:), y1(:), d0(:), d1(:) !! (q, v, λ) and derivatives
    contains
        procedure :: evaluate => dense_evaluate
    end type mexax_dense_t

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
        integer :: k, kc, km, decision, iout, nout, nstab_nonfinite, stat
        integer :: cause !! why the attempt of a restart or a stop failed (cause_*)
        real(wp) :: h, hmax, posneg, tscale, c, t_old
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

        if (.not. valid_input()) return

        call setup_workspace(w, problem, self%base, km, options%linear_solver, status, &
            options%sparse_ordering, options%classic_lu, options%newton_system == 'condensed')
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
        k = w%ctl%start_column(w%rtol, w%atol)
        kc = k
        first = .true.
        last = .false.
        reject = .false.
        basic_entry = .false.

        if (.not. started()) then
            call finish()
            return
        end if

        main: do
            if (need_start) then
                call start_point(self%native, problem, w, t, status, accelerations=.false.)
                if (.not. status%ok()) then
                    self%failed_in = mexax_failed_step
                    exit main
                end if
                need_start = .false.
            end if
            if (abs(h) <= small_step_factor * epmach * max(abs(t), tscale)) then
                call too_small()
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
            call attempt()

            select case (decision)
            case (do_stop)
                call count_failure(fst)
                exit main
            case (do_restart)
                ! §3.3/§3.5: H/2, counted in NSTEP, not in NREJCT (ODEX). Only
                ! the very first attempt and the last step take the first-step path.
                call count_failure(fst)
                self%nstab = self%nstab + 1
                h = h * restart_factor
                reject = .true.
                last = .false.
                first = .false.
                basic_entry = .false.
                cycle main
            case (do_reject)
                call w%ctl%order_after_reject(kc, k, h)
                h = posneg * h
                self%native%nrejct = self%native%nrejct + 1
                call stats%rejections%add(cause_error_test)
                reject = .true.
                last = .false.
                basic_entry = .true.
                cycle main
            end select

            ! ---- converged: project (§3.6), then accept ----
            call project_converged()
            if (decision == do_stop) exit main
            if (decision == do_reject) cycle main

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
            h = abs(h)
            call w%ctl%order_after_accept(kc, k, reject, h)
            reject = .false.
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

        !> At t0: project (no rejection test), a and λ from the index-1 system,
        !> the dense output's start and the outputs at t0. False on a failure
        !> or an interruption (status set).
        logical function started()
            started = .false.
            w%wt(1:w%nq) = w%rtol(1:w%nq) * abs(w%p0) + w%atol(1:w%nq)
            w%wt(w%nq + 1:) = w%rtol(w%nq + 1:) * abs(w%v0) + w%atol(w%nq + 1:)
            w%p = w%p0
            w%v = w%v0
            call project(self%native, problem, w, t, c, status)
            stats%nprj = 1
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_projection
                status%message = 'mexax: ' // status%message // ' at t0 = ' // real_text(t)
                return
            end if
            w%p0 = w%p
            w%v0 = w%v
            call start_point(self%native, problem, w, t, status, accelerations=.true.)
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_step
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
                if (.not. status%ok()) return
            end if
            started = .true.
        end function started

        !> The problem, the arrays and the settings fit (sets km); else bad input.
        logical function valid_input() result(valid)
            logical :: lambda_ok, accel_ok
            valid = .false.
            km = self%max_extrapolation
            lambda_ok = .true.
            accel_ok = .true.
            if (present(lambda)) lambda_ok = size(lambda) == problem%nc
            if (present(accel)) accel_ok = size(accel) == problem%nv
            if (problem%nq <= 0 .or. problem%nv <= 0 .or. problem%nc < 0) then
                call bad('the problem needs nq > 0, nv > 0 and nc >= 0')
            else if (size(q) /= problem%nq .or. size(v) /= problem%nv) then
                call bad('sizes of q and v differ from problem%nq and problem%nv')
            else if (.not. lambda_ok) then
                call bad('size of lambda differs from problem%nc')
            else if (.not. accel_ok) then
                call bad('size of accel differs from problem%nv')
            else if (km < 2 .or. km > mexax_max_columns) then
                call bad('max_extrapolation = ' // int_text(km) // ': must lie in 2..12')
            else if (self%base /= mexax_base_midpoint .and. self%base /= mexax_base_euler) then
                call bad('base must be mexax_base_midpoint or mexax_base_euler')
            else
                call options%validate(problem%nq + problem%nv, status)
                if (.not. status%ok()) then
                    status%message = 'mexax: ' // status%message // ' (tolerances cover q and v)'
                else if (t_end == t) then
                    call bad('t_end equals t')
                else
                    valid = .true.
                end if
            end if
        end function valid_input

        !> The step-too-small stop, naming non-finite values or the model's
        !> refusal when they drove H down.
        subroutine too_small()
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
        end subroutine too_small

        !> Project the converged column kc at t + H (§3.6) and apply the
        !> rejection test; `decision` stays do_accept, or becomes do_reject
        !> (H reduced) or do_stop (status set).
        subroutine project_converged()
            w%p = w%tab(1:w%nq, kc)
            w%v = w%tab(w%nq + 1:w%nq + w%nv, kc)
            call step_weights(w, kc)
            call project(self%native, problem, w, t + h, c, status)
            stats%nprj = stats%nprj + 1
            if (.not. status%ok()) then
                cause = cause_projection
                call count_failure(status)
                self%failed_in = mexax_failed_projection
                status%message = 'mexax: ' // status%message // ' at t = ' // &
                    real_text(t + h) // ' (step from t = ' // real_text(t) // ')'
                decision = do_stop
                return
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
                decision = do_reject
            end if
        end subroutine project_converged

        subroutine bad(reason)
            character(len=*), intent(in) :: reason
            call status%set(status_bad_input, 'mexax: ' // reason)
        end subroutine bad

        subroutine interrupted()
            call status%set(status_interrupted, &
                'mexax: interrupted by the output routine at t = ' // real_text(t))
        end subroutine interrupted

        !> One attempt from t with H and the planned column k: the columns in
        !> the order of ODEX (§3.4); `decision` and kc say how it ended.
        subroutine attempt()
            integer :: j
            decision = undecided
            if (.not. basic_entry .and. (first .or. last)) then
                do j = 1, k
                    if (.not. column(j)) exit
                    if (j >= 2 .and. w%ctl%err(j) <= 1.0_wp) then
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
                    if (w%ctl%err(k - 1) <= 1.0_wp) then
                        decision = do_accept
                    else if (w%ctl%monitor_rejects(k)) then
                        decision = do_reject
                    end if
                end if
                if (decision == undecided) then
                    if (column(k)) then
                        kc = k
                        if (w%ctl%err(k) <= 1.0_wp) then
                            decision = do_accept
                        else
                            call hope()
                        end if
                    end if
                end if
            end if
        end subroutine attempt

        !> Column j of the tableau; false (with `decision` set) on a restart
        !> or a stop.
        logical function column(j) result(ok)
            integer, intent(in) :: j
            integer :: ev
            call base_column(self%native, problem, w, t, h, w%ctl%nj(j), &
                             j <= stability_columns, ev, fst)
            if (ev == ev_ok) then
                call extrapolate_column(w, j)
                if (j >= 2) call column_error(w, j, h, hmax, ev)
                if (ev == ev_restart .and. .not. ieee_is_finite(w%ctl%err(j))) &
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
            if (w%ctl%hope_rejects(k)) then
                decision = do_reject
            else if (column(k + 1)) then
                kc = k + 1
                decision = merge(do_accept, do_reject, w%ctl%err(k + 1) <= 1.0_wp)
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
        call start_point(self%native, problem, w, t, status, accelerations=.false.)
        if (.not. status%ok()) return
        do j = 1, columns
            call base_column(self%native, problem, w, t, big_h, w%ctl%nj(j), .false., ev, status)
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
                call start_point(self%native, problem, w, t, status, accelerations=.true.)
                if (.not. status%ok()) return
                need_start = .false.
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

end module flexmbs_dae_mexax
