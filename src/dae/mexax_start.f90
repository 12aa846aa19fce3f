!> The start of a MEXAX integration (docs/theory.md §7; §3.4, §3.6, §4.2 of
!> the reconstruction): the input checked, the workspace and the output
!> vectors allocated (once, here), H0 and the start column, and at t0 the
!> projection, a and λ, the dense output's start and the outputs.
module flexmbs_dae_mexax_start
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_mexax_control, only: mexax_control_hairer, mexax_control_deuflhard, &
        mexax_base_midpoint, mexax_base_euler, &
        mexax_max_columns
    use flexmbs_dae_mexax_workspace, only: setup_workspace
    use flexmbs_dae_mexax_tableau, only: start_point
    use flexmbs_dae_mexax_projection, only: project
    use flexmbs_dae_mexax_state, only: mexax_engine_t, mexax_run_t, mexax_dense_t, &
        mexax_failed_step, mexax_failed_projection, h0_fraction
    implicit none
    private
    public :: check_input, begin_integration, start, interrupted

contains

    !> The problem, the arrays and the settings fit (sets r%km); else bad input.
    subroutine check_input(self, r, problem, t, q, v, t_end, options, status, lambda, accel)
        class(mexax_engine_t), intent(in) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(in) :: problem
        real(wp), intent(in) :: t, q(:), v(:), t_end
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        real(wp), intent(in), optional :: lambda(:), accel(:)
        logical :: lambda_ok, accel_ok
        r%km = self%max_extrapolation
        lambda_ok = .true.
        accel_ok = .true.
        if (present(lambda)) lambda_ok = size(lambda) == problem%nc
        if (present(accel)) accel_ok = size(accel) == problem%nv
        if (problem%nq <= 0 .or. problem%nv <= 0 .or. problem%nc < 0) then
            call bad(status, 'the problem needs nq > 0, nv > 0 and nc >= 0')
        else if (size(q) /= problem%nq .or. size(v) /= problem%nv) then
            call bad(status, 'sizes of q and v differ from problem%nq and problem%nv')
        else if (.not. lambda_ok) then
            call bad(status, 'size of lambda differs from problem%nc')
        else if (.not. accel_ok) then
            call bad(status, 'size of accel differs from problem%nv')
        else if (r%km < 2 .or. r%km > mexax_max_columns) then
            call bad(status, 'max_extrapolation = ' // int_text(r%km) // ': must lie in 2..12')
        else if (self%base /= mexax_base_midpoint .and. self%base /= mexax_base_euler) then
            call bad(status, 'base must be mexax_base_midpoint or mexax_base_euler')
        else if (self%control /= mexax_control_hairer .and. &
                 self%control /= mexax_control_deuflhard) then
            call bad(status, 'control must be mexax_control_hairer or mexax_control_deuflhard')
        else
            call options%validate(problem%nq + problem%nv, status)
            if (.not. status%ok()) then
                status%message = 'mexax: ' // status%message // ' (tolerances cover q and v)'
            else if (t_end == t) then
                call bad(status, 't_end equals t')
            end if
        end if
    end subroutine check_input

    subroutine bad(status, reason)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: reason
        call status%set(status_bad_input, 'mexax: ' // reason)
    end subroutine bad

    !> The run stopped at the request of the output routine: status_interrupted
    !> with the time reached.
    subroutine interrupted(r, status)
        type(mexax_run_t), intent(in) :: r
        type(status_t), intent(inout) :: status
        call status%set(status_interrupted, &
            'mexax: interrupted by the output routine at t = ' // real_text(r%t))
    end subroutine interrupted

    !> The workspace for km columns with the linear solver of the augmented
    !> system, the tolerances, the output vectors, the initial values, H0
    !> (§4.2) and the start column (§3.4).
    subroutine begin_integration(self, r, problem, q, v, t_end, options, status, lambda)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: q(:), v(:), t_end
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        real(wp), intent(in), optional :: lambda(:)
        integer :: stat
        allocate (r%w, stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'mexax workspace', 1_i8, storage_size(r%w) / 8)
            return
        end if
        call setup_workspace(r%w, problem, self%base, self%control, r%km, &
            options%linear_solver, status, options%sparse_ordering, options%classic_lu, &
            options%newton_system == 'condensed')
        if (.not. status%ok()) return
        call options%tolerances(r%w%rtol, r%w%atol)
        self%dense = mexax_dense_t()  ! drops the last run's arrays
        associate (m => r%w%nq + r%w%nv + r%w%nc)
            allocate (r%yout(m), self%dense%y0(m), self%dense%y1(m), self%dense%d0(m), &
                self%dense%d1(m), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'mexax output vectors', 5_i8 * m, 8)
                self%dense = mexax_dense_t()
                return
            end if
        end associate
        r%w%p0 = q
        r%w%v0 = v
        r%w%a0 = 0.0_wp
        r%w%lam0 = 0.0_wp
        if (present(lambda)) r%w%lam0 = lambda

        r%posneg = sign(1.0_wp, t_end - r%t)
        r%tscale = abs(t_end - r%t)
        r%hmax = r%tscale
        if (options%hmax > 0.0_wp) r%hmax = min(options%hmax, r%tscale)
        r%h = options%h0
        if (r%h == 0.0_wp) r%h = h0_fraction * r%tscale
        r%h = r%posneg * min(abs(r%h), r%hmax)
        ! §3.4 start column.
        r%k = r%w%ctl%start_column(r%w%rtol, r%w%atol)
        r%kc = r%k
        r%first = .true.
        r%last = .false.
        r%reject = .false.
        r%basic_entry = .false.
    end subroutine begin_integration

    !> At t0: project (no rejection test), a and λ from the index-1 system,
    !> the dense output's start and the outputs at t0. On a failure or an
    !> interruption `status` says so.
    subroutine start(self, r, problem, options, stats, status, sink)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(inout) :: r
        class(mechanical_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        associate (w => r%w)
            w%wt(1:w%nq) = w%rtol(1:w%nq) * abs(w%p0) + w%atol(1:w%nq)
            w%wt(w%nq + 1:) = w%rtol(w%nq + 1:) * abs(w%v0) + w%atol(w%nq + 1:)
            w%p = w%p0
            w%v = w%v0
            call project(self%native, problem, w, r%t, r%c, status)
            stats%nprj = 1
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_projection
                status%message = 'mexax: ' // status%message // ' at t0 = ' // real_text(r%t)
                return
            end if
            w%p0 = w%p
            w%v0 = w%v
            call start_point(self%native, problem, w, r%t, status, accelerations=.true.)
            if (.not. status%ok()) then
                self%failed_in = mexax_failed_step
                return
            end if
        end associate
        r%need_start = .false.

        ! Output at t0.
        call set_dense_start(self, r)
        r%want_steps = .false.
        r%nout = 0
        r%iout = 1
        if (present(sink)) then
            r%want_steps = sink%wants_steps()
            if (allocated(options%output_times)) r%nout = size(options%output_times)
            do while (r%iout <= r%nout)
                if ((options%output_times(r%iout) - r%t) * r%posneg > 0.0_wp) exit
                if (options%output_times(r%iout) == r%t) &
                    call sink%output(r%t, self%dense%y1, status)
                r%iout = r%iout + 1
                if (.not. status%ok()) exit
            end do
            if (r%want_steps .and. status%ok()) &
                call sink%step(1, r%t, r%t, self%dense%y1, self%dense, r%stop_requested, status)
            if (status%ok() .and. r%stop_requested) call interrupted(r, status)
        end if
    end subroutine start

    subroutine set_dense_start(self, r)
        class(mexax_engine_t), intent(inout) :: self
        type(mexax_run_t), intent(in) :: r
        integer :: nq, nv
        nq = r%w%nq
        nv = r%w%nv
        self%dense%t_old = r%t
        self%dense%t = r%t
        self%dense%y1(1:nq) = r%w%p0
        self%dense%y1(nq + 1:nq + nv) = r%w%v0
        self%dense%y1(nq + nv + 1:) = r%w%lam0
        self%dense%d1(1:nq) = r%w%pdot0
        self%dense%d1(nq + 1:nq + nv) = r%w%a0
        self%dense%d1(nq + nv + 1:) = 0.0_wp
        self%dense%y0 = self%dense%y1
        self%dense%d0 = self%dense%d1
    end subroutine set_dense_start
end module flexmbs_dae_mexax_start
