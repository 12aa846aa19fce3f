!> `DDASSL`: variable-order, variable-step BDF for G(t, y, y') = 0.
!>
!> Implemented from [BCP89, ch. 5] as specified in docs/theory.md §6:
!> fixed-leading-coefficient BDF of orders 1..pmax in modified divided
!> differences, a modified Newton corrector with iteration matrix
!> PD = ∂G/∂y + cj ∂G/∂y' reused across steps, error estimates at orders
!> k−2..k+1 deciding order and step, and the BDF interpolant for output.
!> The SLATEC revision 910624 is the default; `netlib` switches to the
!> later revision (§2.9). A `dae_problem_t` is integrated as G = M y' − F.
!>
!> This module holds the solver type and its drivers; the state and the
!> norms are in flexmbs_dae_ddassl_state, the start (validation, H0,
!> DDAINI) in flexmbs_dae_ddassl_start, one step in
!> flexmbs_dae_ddassl_stepper and the iteration matrix and corrector in
!> flexmbs_dae_ddassl_corrector.
module flexmbs_dae_ddassl
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_max_steps
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_matrix, only: storage_identity
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_residual_problem, only: residual_problem_t, dae_residual_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t, projection_refusal
    use flexmbs_dae_sink, only: sink_t, finish_sink, dense_output_t
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_dae_ddassl_state, only: ddassl_engine_t, ddassl_work_t, ddassl_native_t, &
        ddassl_max_order, mx, hmin_factor, tstop_tol, ddassl_fail_none, &
        ddassl_fail_tolerances, ddassl_fail_weights, ddassl_fail_error_test, &
        ddassl_fail_corrector, ddassl_fail_singular, ddassl_fail_after_error_test, &
        ddassl_fail_residual, ddassl_fail_stop, ddassl_fail_initial
    use flexmbs_dae_ddassl_start, only: begin_integration
    use flexmbs_dae_ddassl_stepper, only: before_step, take_step
    implicit none
    private
    ! Defined with the state; part of this module's interface.
    public :: ddassl_max_order, ddassl_native_t, ddassl_work_t
    public :: ddassl_fail_none, ddassl_fail_tolerances, ddassl_fail_weights, &
        ddassl_fail_error_test, ddassl_fail_corrector, ddassl_fail_singular, &
        ddassl_fail_after_error_test, ddassl_fail_residual, ddassl_fail_stop, &
        ddassl_fail_initial

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

    !> DDASSL settings (the INFO switches of the classic code that make
    !> sense in the modern core) and the results of the last integration:
    !> the drivers' own here, those the steps read and write (switches,
    !> counters, the state between steps) in `ddassl_engine_t`.
    type, extends(ddassl_engine_t), public :: ddassl_t
        logical :: initial_derivative = .false.  !! y' by DDAINI (§2.8, INFO(11) = 1)
        logical :: tstop = .false.               !! never step past t_end (INFO(4) = 1)
        !> H0 rule of §2.7 with TOUT = the first output time (as the classic
        !> driver called with that TOUT) instead of t_end.
        logical :: h0_from_first_output = .false.
        ! Results of the last integration.
        integer :: k_last = 0        !! order of the last step (IWORK(8))
        integer :: k_next = 0        !! order for the next step (IWORK(7))
        real(wp) :: h_next = 0.0_wp  !! next step size (RWORK(3))
        type(ddassl_dense_t) :: dense
    contains
        procedure :: integrate_dae => ddassl_integrate
        procedure :: integrate_residual => ddassl_integrate_residual
        procedure :: begin => ddassl_begin
        procedure :: step => ddassl_step
        procedure :: interpolate => ddassl_interpolate
        procedure :: name => ddassl_name
        procedure :: step_counts => ddassl_step_counts
        procedure :: apply_setting => ddassl_apply_setting
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

    !> A scene's DDASSL setting (scene schema, group &solver); p_max reaches
    !> DDASSL through dae_options_t (MAXORD).
    subroutine ddassl_apply_setting(self, setting, applied)
        class(ddassl_t), intent(inout) :: self
        type(solver_setting_t), intent(in) :: setting
        logical, intent(out) :: applied
        applied = .true.
        select case (setting%name)
        case ('initial_derivative')
            self%initial_derivative = setting%logical_value
        case ('exclude_index23')
            self%exclude_index23 = setting%logical_value
        case ('netlib')
            self%netlib = setting%logical_value
        case default
            applied = .false.
        end select
    end subroutine ddassl_apply_setting

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
        include 'integrate_arguments.inc'
        real(wp), intent(inout), optional :: yp(:)
        call run_dae(self, problem, t, y, t_end, options, stats, status, sink, yp)
    end subroutine ddassl_integrate

    !> `target` lets the wrapper point at the problem for this call.
    subroutine run_dae(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ddassl_t), intent(inout) :: self
        class(dae_problem_t), intent(inout), target :: problem
        include 'integrate_arguments.inc'
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
            call finish(self, t, timer, stats, status, sink)
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
            call finish(self, t, timer, stats, status, sink)
            return
        end if
        associate (w => self%work)
            if (want_steps) then
                call copy_dense(self)
                call sink%step(1, w%tn, w%tn, y, self%dense, stop_requested, status)
                if (.not. status%ok()) then
                    call finish(self, t, timer, stats, status, sink)
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
                    call copy_dense(self)
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
        call copy_dense(self)
        call finish(self, t, timer, stats, status, sink)
    end subroutine ddassl_integrate_residual

    !> Common statistics from the native counters (docs/solvers.md), and
    !> the sink finished.
    subroutine finish(self, t, timer, stats, status, sink)
        class(ddassl_t), intent(inout) :: self
        real(wp), intent(in) :: t            !! the last point reached
        type(timer_t), intent(in) :: timer   !! started with the integration
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
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
        if (allocated(self%work%ls)) stats%linear_solver = self%work%ls%description()
        if (allocated(self%work%ls)) stats%linear_solver_report = self%work%ls%report()
        if (allocated(self%warning)) stats%warning = self%warning
        self%k_last = self%work%kold
        self%k_next = self%work%k
        self%h_next = self%work%h
        stats%cpu = timer%cpu()
        stats%wall = timer%wall()
        call finish_sink(sink, status)
    end subroutine finish

    subroutine copy_dense(self)
        class(ddassl_t), intent(inout) :: self
        associate (w => self%work)
            ! allocated with its shape after begin, so nothing is allocated here
            self%dense%phi = w%phi
            self%dense%psi = w%psi
            self%dense%kold = w%kold
            self%dense%tn = w%tn
        end associate
    end subroutine copy_dense

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
        self%k_last = 0
        self%k_next = 0
        self%h_next = 0.0_wp
        call begin_integration(self, res, t, y, yp, tout, options, ddaini, status, tstop)
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
        real(wp) :: tlimit
        logical :: limited
        type(status_t) :: st
        if (.not. self%work%ready) then
            call status%set(status_bad_input, 'ddassl: step called before a successful begin')
            return
        end if
        limited = stop_at_tout .or. present(tstop)
        tlimit = tout
        if (present(tstop)) tlimit = tstop
        ! Both describe this step only.
        self%work%failure = ddassl_fail_none
        self%work%ires_stop = .false.
        call before_step(self, tout, limited, tlimit, status)
        if (status%ok()) then
            call take_step(self, res, y, yp, st)
            if (.not. st%ok()) status = st
        end if
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
end module flexmbs_dae_ddassl
