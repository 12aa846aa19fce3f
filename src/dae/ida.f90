!> SUNDIALS IDA (variable-order BDF, orders 1–5) on G(t, y, y') = M y' − F(t, y) = 0
!> for any `dae_problem_t`, through SUNDIALS' Fortran 2003 modules.
!>
!> The problem reaches the bind(C) callbacks through IDA's user data: a
!> pointer to a callback-data object local to the integration (no module
!> state). The iteration matrix ∂G/∂y + c_j ∂G/∂y' = c_j M − ∂F/∂y is a
!> dense SUNMatrix (SUNDIALS' dense LU) or a CSC SUNMatrix with KLU, whose
!> pattern (the union of the patterns of ∂F/∂y and M) is built once.
!> Statistics map onto `dae_stats_t` as docs/solvers.md says: NST = nst + netf +
!> ncfn, NAC = nst, NFE = nre, NFE_JAC = nreLS, NJE = nje, NDEC = nsetups,
!> NSOL = nni. IDA's Newton solver is SUNDIALS' own, observed by a C shim
!> (ida_observer_shim.c) that counts its failed solves by cause.
!>
!> This module holds the solver type and its driver; the state, IDA's
!> flags and counters in flexmbs_dae_ida_state, the problem's side (vectors,
!> matrices and their pattern, y'0, the first step) in
!> flexmbs_dae_ida_setup, the SUNDIALS objects in flexmbs_dae_ida_sundials
!> and the steps and outputs in flexmbs_dae_ida_stepping.
module flexmbs_dae_ida
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_timer, only: timer_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t, projection_refusal
    use flexmbs_dae_sink, only: sink_t, finish_sink
    use flexmbs_dae_ida_state, only: ida_engine_t, ida_work_t, ida_native_t, collect_statistics
    use flexmbs_dae_ida_setup, only: prepare, setup_matrices, initial_derivative, &
        first_step_estimate
    use flexmbs_dae_ida_sundials, only: create_ida, consistent_start, free_all
    use flexmbs_dae_ida_stepping, only: output_start, to_output_times, step_by_step
    implicit none
    private
    ! Defined with the state; part of this module's interface.
    public :: ida_native_t

    !> SUNDIALS IDA: the settings (`calc_ic`, `suppress_alg`) and the results
    !> of the last integration are those of `ida_engine_t`.
    type, extends(ida_engine_t), public :: ida_t
    contains
        procedure :: integrate_dae => ida_integrate
        procedure :: name => ida_name
    end type ida_t

contains

    function ida_name(self) result(name)
        class(ida_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'ida'
    end function ida_name

    !> Integrate M y' = F(t, y) from (t, y) to t_end. `yp`, when given, is
    !> the initial y' (and receives the final one); otherwise y' comes from
    !> F (M = I), from IDACalcIC (`calc_ic`) or from the problem's
    !> `consistent_initial`.
    subroutine ida_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ida_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        include 'integrate_arguments.inc'
        real(wp), intent(inout), optional :: yp(:)
        type(timer_t) :: timer

        call timer%start()
        stats%t_reached = t
        self%native = ida_native_t()
        self%linear_solver_used = ''
        ! IDA has no hook after a step: a projection asked for would be
        ! silently left out (as for DDASSL, it would disturb the BDF history)
        if (problem%has_projection()) then
            call status%set(status_bad_input, projection_refusal('ida', 'radau5'))
            return
        end if
        if (size(y) /= problem%n .or. problem%n <= 0) then
            call status%set(status_bad_input, 'ida: size of y differs from problem%n')
            return
        end if
        if (present(yp)) then
            if (size(yp) /= problem%n) then
                call status%set(status_bad_input, 'ida: size of yp differs from problem%n')
                return
            end if
        end if
        call options%validate(problem%n, status)
        if (.not. status%ok()) return
        if (t_end == t) then
            call status%set(status_bad_input, 'ida: t_end equals t; nothing to integrate')
            return
        end if
        call solve(self, problem, t, y, t_end, options, stats, status, sink, yp)
        stats%cpu = timer%cpu()
        stats%wall = timer%wall()
        call finish_sink(sink, status)
    end subroutine ida_integrate

    !> The integration proper; `problem` is a target so that the callbacks
    !> can reach it during the call, and so is the state `w`, whose
    !> callback data and arrays IDA refers to. Every SUNDIALS object is
    !> freed at the end.
    subroutine solve(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ida_t), intent(inout) :: self
        class(dae_problem_t), intent(inout), target :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)
        type(ida_work_t), target :: w

        call prepare(self, w, problem, t, y, t_end, options, stats, status, sink)
        if (.not. status%ok()) return

        run: block
            call setup_matrices(w, problem, options, status)
            if (.not. status%ok()) exit run
            call initial_derivative(self, w, problem, status, yp)
            if (.not. status%ok()) exit run
            call first_step_estimate(w, t_end, options)
            call create_ida(self, w, t_end, options, status)
            if (.not. status%ok()) exit run
            call consistent_start(self, w, t_end, options, stats, status)
            if (.not. status%ok()) exit run
            call output_start(w, options, status, sink)
            if (.not. status%ok()) exit run
            if (w%want_steps) then
                call step_by_step(self, w, problem, t_end, options, stats, status, sink)
            else
                call to_output_times(self, w, problem, t_end, options, stats, status, sink)
            end if
        end block run

        call collect_statistics(self, w, stats)
        if (.not. w%annotated) call stats%rejections%annotate(status)
        call free_all(w)
        t = w%x
        y = w%yw
        if (present(yp)) yp = w%ypw
        stats%t_reached = w%x
        stats%h_last = self%native%last_step
    end subroutine solve
end module flexmbs_dae_ida
