!> The start of a DDASSL integration (docs/theory.md §6, §2.7 first call
!> and §2.8): the input checked, the error control set up, the matrices and
!> the linear solver fixed and the work arrays allocated (once, here), H0,
!> DDAINI for a consistent y', and the first history.
module flexmbs_dae_ddassl_start
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_step_too_small, reason_singular_matrix, &
        reason_newton_failure, reason_det_f
    use flexmbs_linalg_matrix, only: storage_none, storage_dense, storage_sparse
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_residual_problem, only: residual_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: index3_warning
    use flexmbs_dae_rejections, only: rejections_t
    use flexmbs_dae_ddassl_state, only: ddassl_engine_t, ddassl_work_t, ddassl_native_t, &
        set_weights, vnorm, ddassl_max_order, mx, s_fresh, roundoff_conv, est_offset, &
        fail_safety, fail_quarter, max_ncf, max_nsf, h0_fraction, h0_slope, hmin_factor, &
        ini_max_iter, ini_jac_every, ini_s, ini_damp, ini_max_nef, ini_r_min, ini_r_max, &
        ddassl_fail_initial, ddassl_fail_stop
    use flexmbs_dae_ddassl_corrector, only: form_pd, residual_ok, rate_test
    implicit none
    private
    public :: begin_integration

contains

    !> §2.7, first call: validate, fix the storages and the linear solver,
    !> choose H0 from `tout` (and options%h0, options%hmax), run DDAINI when
    !> asked, and set up the history in self%work. Counters restart at zero.
    !> With DDAINI the history starts at t + h, and (y, yp) hold DDAINI's
    !> values there. On bad input self%work is left new (nothing to step
    !> from); after a failed DDAINI it holds where DDAINI stopped, not ready.
    subroutine begin_integration(self, res, t, y, yp, tout, options, ddaini, status, tlimit)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: tout                !! H0 rule and hmin (§2.7)
        type(dae_options_t), intent(in) :: options
        logical, intent(in) :: ddaini               !! y' by DDAINI (§2.8)
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: tlimit   !! H0 never passes it (INFO(4))
        type(status_t) :: st

        self%work = ddassl_work_t()
        if (allocated(self%warning)) deallocate (self%warning)
        self%native = ddassl_native_t()
        self%rejections = rejections_t()
        self%ndec = 0
        self%nsol = 0
        self%nfe_jac = 0
        self%work%n = res%n
        self%work%tn = t
        self%work%t0 = t
        self%work%uround = self%uround
        self%work%pmax = options%pmax

        call check_input(self, y, yp, options, status)
        if (status%ok()) call set_error_control(self, res, t, y, tout, options, status)
        if (status%ok()) call set_linear_algebra(self, res, options, status)
        if (.not. status%ok()) then
            self%work = ddassl_work_t()
            return
        end if
        call first_step_size(self%work, t, yp, tout, options, tlimit)
        if (ddaini) then
            call initial_step(self, res, y, yp, st)
            if (.not. st%ok()) then
                status = st
                self%work%failure = ddassl_fail_initial
                if (st%code == status_interrupted) self%work%failure = ddassl_fail_stop
                return
            end if
        end if
        call first_history(self, y, yp, status)
        if (.not. status%ok()) then
            self%work = ddassl_work_t()
            return
        end if
        self%work%ready = .true.
    end subroutine begin_integration

    subroutine bad(status, reason)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: reason
        call status%set(status_bad_input, 'ddassl: ' // reason)
    end subroutine bad

    !> §2.7, first call: the checks of the input.
    subroutine check_input(self, y, yp, options, status)
        class(ddassl_engine_t), intent(inout) :: self
        real(wp), intent(in) :: y(:), yp(:)
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        associate (w => self%work)
            if (w%n <= 0 .or. size(y) /= w%n .or. size(yp) /= w%n) then
                call bad(status, 'sizes of y and yp must equal the problem size n > 0')
                return
            end if
            call options%validate(w%n, status)
            if (.not. status%ok()) return
            if (w%pmax > ddassl_max_order) then
                call bad(status, 'pmax = ' // int_text(w%pmax) // ': must lie in 1..5')
                return
            end if
            if (.not. (w%uround > 0.0_wp .and. w%uround < 1.0_wp)) then
                call bad(status, 'uround must lie in (0, 1)')
                return
            end if
            if (self%fixed_step .and. .not. options%h0 > 0.0_wp) then
                call bad(status, 'fixed_step needs a positive h0')
                return
            end if
        end associate
    end subroutine check_input

    !> Tolerances, the components of the error and Newton tests by index
    !> class (§2.10), the weights at y0, hmin and hmax (§2.7).
    subroutine set_error_control(self, res, t, y, tout, options, status)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(in) :: t, y(:), tout
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        integer, allocatable :: classes(:)
        logical, allocatable :: multiplier(:)
        integer :: n, stat
        associate (w => self%work)
            n = w%n
            allocate (w%rtol(n), w%atol(n), w%wt(n), w%in_test(n), classes(n), &
                w%newton_power(n), multiplier(n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'ddassl weights and index classes', 6_i8 * n, 8)
                return
            end if
            call options%tolerances(w%rtol, w%atol)
            call res%index_classes(classes)
            w%in_test = .true.
            w%newton_power = 0
            if (self%exclude_index23) then
                w%in_test = classes < 2
                call res%multiplier_flags(multiplier)
                where (multiplier .and. .not. w%in_test) w%newton_power = classes - 1
            end if
            if (any(classes >= 3)) self%warning = index3_warning('ddassl')
            call set_weights(w, y)
            if (any(.not. w%wt > 0.0_wp)) then
                call bad(status, 'some weight rtol*|y0| + atol is not positive')
                return
            end if
            w%hmin = hmin_factor * w%uround * max(abs(t), abs(tout))
            if (abs(tout - t) < w%hmin .or. tout == t) then
                call bad(status, 'tout = ' // real_text(tout) // ' is too close to t = ' // &
                    real_text(t))
                return
            end if
            w%hmax = huge(1.0_wp)
            if (options%hmax > 0.0_wp) w%hmax = options%hmax
        end associate
    end subroutine set_error_control

    !> Matrices and the linear solver: storages fixed here, once; then the
    !> history and work arrays.
    subroutine set_linear_algebra(self, res, options, status)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        integer :: n, stat
        associate (w => self%work)
            n = w%n
            allocate (w%amat, w%bmat)
            call res%setup_partials(options%jacobian == 'fd', w%amat, w%bmat, status)
            if (.not. status%ok()) return
            w%fd = w%bmat%storage == storage_none
            w%direct = .not. w%fd .and. res%has_iteration_matrix()
            ! the problem's own solver of c A − B (condensed Newton systems), or ours
            if (w%bmat%storage == storage_sparse) &
                call res%iteration_solver(options, w%ls, status)
            if (.not. status%ok()) return
            if (.not. allocated(w%ls)) call new_linear_solver(options%linear_solver, n, &
                w%bmat%storage, w%ls, status, lower=options%band_lower, &
                upper=options%band_upper, ordering=options%sparse_ordering, &
                classic_order=options%classic_lu, mass=w%amat, jac=w%bmat)
            if (.not. status%ok()) return
            if (w%fd) then
                ! The difference PD is held as −PD and factored with shift 0.
                w%bmat%storage = storage_dense
                allocate (w%bmat%dense(n, n), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'ddassl difference iteration matrix', &
                        int(n, i8) * n, 8)
                    return
                end if
            end if
            call w%ls%init(w%amat, w%bmat, status)
            if (.not. status%ok()) return
            allocate (w%phi(n, w%pmax + 1), w%delta(n), w%e(n), w%ytmp(n), w%yptmp(n), &
                w%ysave(n), w%ypsave(n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'ddassl history and workspace', &
                    int(n, i8) * (w%pmax + 7), 8)
                return
            end if
            w%phi = 0.0_wp
            w%delta = 0.0_wp
            w%e = 0.0_wp
        end associate
    end subroutine set_linear_algebra

    !> §2.7 steps 4 and 5: the initial step H0, within hmax and tlimit.
    subroutine first_step_size(w, t, yp, tout, options, tlimit)
        type(ddassl_work_t), intent(inout) :: w
        real(wp), intent(in) :: t, yp(:), tout
        type(dae_options_t), intent(in) :: options
        real(wp), intent(in), optional :: tlimit
        real(wp) :: dir
        dir = sign(1.0_wp, tout - t)
        if (options%h0 > 0.0_wp) then
            w%h = sign(options%h0, dir)
        else
            w%h = h0_fraction * abs(tout - t)
            if (vnorm(w, yp) > h0_slope / w%h) w%h = h0_slope / vnorm(w, yp)
            w%h = sign(w%h, dir)
        end if
        w%h_fixed = w%h
        if (abs(w%h) > w%hmax) w%h = w%h / (abs(w%h) / w%hmax)
        if (present(tlimit)) then
            if ((t + w%h - tlimit) * dir > 0.0_wp) w%h = tlimit - t
        end if
    end subroutine first_step_size

    !> §2.7 step 7: the history after the first call.
    subroutine first_history(self, y, yp, status)
        class(ddassl_engine_t), intent(inout) :: self
        real(wp), intent(in) :: y(:), yp(:)
        type(status_t), intent(inout) :: status
        associate (w => self%work)
            w%phi(:, 1) = y
            w%phi(:, 2) = w%h * yp
            w%k = 1
            w%kold = 0
            w%hold = 0.0_wp
            w%psi = 0.0_wp
            w%psi(1) = w%h
            w%cj = 1.0_wp / w%h
            w%cjold = w%cj
            w%cjlast = w%cj
            w%s = s_fresh
            w%jcalc = -1
            w%iphase = 0
            w%ns = 0
            w%nef = 0
            w%ncf = 0
            w%nsf = 0
            w%knew = 1
            w%est = 0.0_wp
            w%erkm1 = 0.0_wp
            w%terkm1 = 0.0_wp
            w%terk = 0.0_wp
            w%alpha = 0.0_wp; w%beta = 0.0_wp; w%gamma = 0.0_wp; w%sigma = 0.0_wp
            if (self%fixed_step .and. allocated(self%start_history)) then
                if (size(self%start_history, 1) /= w%n .or. &
                    size(self%start_history, 2) /= w%pmax + 1) then
                    call bad(status, 'start_history must have shape (n, pmax + 1)')
                    return
                end if
                call history_from_values(self)
            end if
        end associate
    end subroutine first_history

    !> Constant-step history at order pmax: φ_{j+1} = ∇^j y_0 (§2.2 with
    !> ψ_i = i·h0), from the values y(t0 − j·h0).
    subroutine history_from_values(self)
        class(ddassl_engine_t), intent(inout) :: self
        integer :: i, j
        real(wp), allocatable :: table(:, :)
        associate (w => self%work)
            table = self%start_history
            w%phi(:, 1) = table(:, 1)
            do j = 1, w%pmax
                do i = 1, w%pmax + 1 - j
                    table(:, i) = table(:, i) - table(:, i + 1)
                end do
                w%phi(:, j + 1) = table(:, 1)
            end do
            w%h = w%h_fixed
            w%hold = w%h
            w%k = w%pmax
            w%kold = w%pmax
            do i = 1, mx
                w%psi(i) = real(i, wp) * w%h
            end do
            w%cj = real(w%pmax, wp) / w%h
            w%cjold = w%cj
            w%cjlast = w%cj
            w%iphase = 1
        end associate
    end subroutine history_from_values

    !> §2.8 DDAINI: one damped backward-Euler step from (t0, y0) with y0'
    !> as the guess; advances tn to t0 + h and leaves (y, yp) there.
    subroutine initial_step(self, res, y, yp, st)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:)
        type(status_t), intent(out) :: st
        integer :: nefi, ncfi, nsfi
        real(wp) :: ynorm, err, r
        logical :: converged, singular
        associate (w => self%work)
            w%ysave = y
            w%ypsave = yp
            ynorm = vnorm(w, y)
            call w%model_failure%clear()
            nefi = 0
            ncfi = 0
            nsfi = 0
            do
                w%cj = 1.0_wp / w%h
                w%tn = w%t0 + w%h
                y = w%ysave + w%h * w%ypsave
                yp = w%ypsave
                call initial_newton(self, res, y, yp, ynorm, converged, singular)
                if (w%ires_stop) then
                    call st%set(status_interrupted, 'ddassl: the residual asked to stop ' // &
                        'in DDAINI at t = ' // real_text(w%tn))
                    exit
                else if (converged) then
                    w%delta = y - w%ysave
                    err = vnorm(w, w%delta)
                    if (err <= 1.0_wp) return
                    nefi = nefi + 1
                    r = min(max(fail_safety / (2.0_wp * err + est_offset), ini_r_min), ini_r_max)
                    w%h = w%h * r
                    if (nefi >= ini_max_nef .or. abs(w%h) < w%hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI) failed the error test at t = ' // real_text(w%t0), &
                            reason_step_too_small)
                        exit
                    end if
                else if (singular) then
                    nsfi = nsfi + 1
                    w%h = w%h * fail_quarter
                    if (nsfi >= max_nsf .or. abs(w%h) < w%hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI): iteration matrix singular at t = ' // real_text(w%t0), &
                            reason_singular_matrix)
                        exit
                    end if
                else
                    ncfi = ncfi + 1
                    w%h = w%h * fail_quarter
                    if (ncfi >= max_ncf .or. abs(w%h) < w%hmin) then
                        call st%set(status_solver_failure, 'ddassl: initial derivative ' // &
                            '(DDAINI): Newton iteration failed at t = ' // real_text(w%t0), &
                            reason_newton_failure)
                        if (w%model_failure%reason == reason_det_f) call st%set( &
                            status_solver_failure, st%message // ': ' // &
                            w%model_failure%text(), reason_det_f)
                        exit
                    end if
                end if
            end do
            y = w%ysave
            yp = w%ypsave
            w%tn = w%t0
        end associate
    end subroutine initial_step

    !> DDAINI's damped Newton iteration at t0 + h from (y, yp), with a new
    !> PD every ini_jac_every iterations.
    subroutine initial_newton(self, res, y, yp, ynorm, converged, singular)
        class(ddassl_engine_t), intent(inout) :: self
        class(residual_problem_t), intent(inout) :: res
        real(wp), intent(inout) :: y(:), yp(:)
        real(wp), intent(in) :: ynorm           !! ‖y0‖, the round-off scale
        logical, intent(out) :: converged, singular
        integer :: m, mb
        real(wp) :: d, d0
        logical :: refused, diverged
        converged = .false.
        singular = .false.
        m = 0
        mb = 0
        d0 = 0.0_wp
        associate (w => self%work)
            do
                if (.not. residual_ok(self, res, y, yp)) return
                if (mod(m, ini_jac_every) == 0) then
                    self%native%nje = self%native%nje + 1
                    call form_pd(self, res, y, yp, singular, refused)
                    if (singular) return
                    w%s = ini_s
                    mb = 0
                end if
                w%delta = ini_damp * w%delta
                call w%ls%solve_real(w%delta)
                self%nsol = self%nsol + 1
                y = y - w%delta
                yp = yp - w%cj * w%delta
                if (self%nonnegative) then
                    ! Clip y and keep y' = (y − y0)/h consistent with it.
                    where (y < 0.0_wp) yp = yp - w%cj * y
                    y = max(y, 0.0_wp)
                end if
                d = vnorm(w, w%delta)
                if (.not. ieee_is_finite(d)) return
                if (d <= roundoff_conv * w%uround * ynorm) then
                    converged = .true.
                    return
                end if
                call rate_test(mb, d, d0, w%s, converged, diverged)
                if (converged .or. diverged) return
                m = m + 1
                mb = mb + 1
                if (m >= ini_max_iter) return
            end do
        end associate
    end subroutine initial_newton
end module flexmbs_dae_ddassl_start
