!> IDA's state (docs/theory.md §8): IDA's counters, the part of the solver
!> the phases of an integration read and write (`ida_engine_t`: settings
!> and results, which `ida_t` extends), IDA's interpolant as a dense
!> output, the state of one integration (`ida_work_t`: the callbacks' data,
!> the vectors IDA works on and the SUNDIALS objects), and how IDA's return
!> flags and counters become flexmbs' status and statistics.
module flexmbs_dae_ida_state
    use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_ptr, c_null_ptr, &
        c_associated
    use fsundials_nvector_mod, only: N_Vector
    use fsundials_matrix_mod, only: SUNMatrix
    use fsundials_linearsolver_mod, only: SUNLinearSolver
    use fida_mod, only: FIDAGetDky, FIDAGetNumSteps, FIDAGetNumResEvals, &
        FIDAGetNumLinResEvals, FIDAGetNumJacEvals, FIDAGetNumLinSolvSetups, &
        FIDAGetNumNonlinSolvIters, FIDAGetNumErrTestFails, FIDAGetNumNonlinSolvConvFails, &
        FIDAGetNumStepSolveFails, FIDAGetLastStep, FIDAGetLastOrder, IDA_TOO_MUCH_WORK, &
        IDA_TOO_MUCH_ACC, IDA_ERR_FAIL, IDA_CONV_FAIL, IDA_LINIT_FAIL, IDA_LSETUP_FAIL, &
        IDA_LSOLVE_FAIL, IDA_RES_FAIL, IDA_REP_RES_ERR, IDA_FIRST_RES_FAIL, &
        IDA_LINESEARCH_FAIL, IDA_NO_RECOVERY, IDA_BAD_EWT
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_step_too_small, reason_max_steps, reason_singular_matrix, &
        reason_newton_failure, reason_user_function
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_model_refused
    use flexmbs_dae_ida_callbacks, only: callback_data_t, jac_own, jac_sparse
    use flexmbs_dae_ida_observer, only: observed_rejections
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private
    public :: check, sundials_failure, map_failure, collect_statistics, ieee_nan

    integer, parameter, public :: ida_max_order = 5    !! IDA's BDF orders are 1…5

    !> IDA's own counters after the last integration.
    type, public :: ida_native_t
        integer :: nst = 0      !! accepted steps (IDAGetNumSteps)
        integer :: nre = 0      !! residual evaluations (IDAGetNumResEvals)
        integer :: nre_ls = 0   !! residual evaluations for difference Jacobians
        integer :: nje = 0      !! Jacobian evaluations
        integer :: nsetups = 0  !! linear solver setups (factorisations)
        integer :: nni = 0      !! nonlinear (Newton) iterations
        integer :: netf = 0     !! error test failures
        integer :: ncfn = 0     !! steps failed in the nonlinear solver (IDAGetNumStepSolveFails)
        !> nonlinear solver failures, those a new Jacobian recovered within the
        !> step included (IDAGetNumNonlinSolvConvFails since SUNDIALS 6.2)
        integer :: nnf = 0
        integer :: last_order = 0
        real(wp) :: last_step = 0.0_wp
    end type ida_native_t

    !> SUNDIALS IDA. `calc_ic` runs IDACalcIC (IDA_YA_YDP_INIT: algebraic y
    !> and differential y' from the given differential y) before stepping;
    !> `suppress_alg` removes index-2/3 components from the error test.
    !> What the phases of an integration (the modules flexmbs_dae_ida_*)
    !> read and write; `ida_t` extends it with the driver.
    type, extends(dae_solver_t), abstract, public :: ida_engine_t
        logical :: calc_ic = .false.
        logical :: suppress_alg = .true.
        type(ida_native_t) :: native
        !> Linear solver used by the last integration: 'dense', 'klu' (SUNDIALS'),
        !> 'mumps', or the problem's ('condensed klu', 'condensed mumps').
        character(len=16) :: linear_solver_used = ''
    end type ida_engine_t

    !> IDA's interpolant of the last step, through IDAGetDky.
    type, extends(dense_output_t), public :: ida_dense_t
        type(c_ptr) :: mem = c_null_ptr
        type(N_Vector), pointer :: vector => null()
        real(wp), pointer :: values(:) => null()
    contains
        procedure :: evaluate => ida_dense_evaluate
    end type ida_dense_t

    !> Everything one integration works on: the callbacks' data (IDA's user
    !> data points at `data`), the arrays IDA's vectors wrap (y, y', atol,
    !> the id vector, the interpolant's), the SUNDIALS objects and the
    !> position in the output times. Local to the driver, and a target
    !> there: IDA keeps the addresses of `data` and of the arrays.
    type, public :: ida_work_t
        type(callback_data_t) :: data
        type(ida_dense_t) :: dense
        type(c_ptr) :: ctx = c_null_ptr, mem = c_null_ptr
        type(N_Vector), pointer :: nv_y => null(), nv_yp => null(), nv_atol => null(), &
            nv_id => null(), nv_dky => null()
        type(SUNMatrix), pointer :: a_mat => null()
        type(SUNLinearSolver), pointer :: lin_solver => null()
        real(wp), allocatable :: yw(:), ypw(:), atolw(:), idw(:), dkyw(:)
        integer, allocatable :: classes(:)
        logical, allocatable :: flags(:)  !! the differential components (IDA's id)
        integer :: n = 0
        integer :: nout = 0, iout = 1      !! requested output times, the next one
        real(wp) :: x = 0.0_wp             !! time reached
        real(wp) :: posneg = 1.0_wp        !! direction of the integration
        logical :: want_steps = .false., stop_requested = .false.
        logical :: use_klu = .false.
        logical :: suppress = .false.      !! index-2/3 components out of the error test
        logical :: annotated = .false.     !! the failure message names the rejection causes
    end type ida_work_t

contains

    subroutine ida_dense_evaluate(self, s, y)
        class(ida_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        if (FIDAGetDky(self%mem, s, 0_c_int, self%vector) == 0) then
            y = self%values
        else
            y = ieee_nan()
        end if
    end subroutine ida_dense_evaluate

    !> True when a SUNDIALS call returned 0; otherwise records the failure.
    logical function check(w, status, flag, what)
        type(ida_work_t), intent(in) :: w
        type(status_t), intent(inout) :: status
        integer(c_int), intent(in) :: flag
        character(len=*), intent(in) :: what
        check = flag == 0
        if (.not. check) call sundials_failure(w, status, what, int(flag))
    end function check

    !> Report a failed SUNDIALS call `what` (its flag when given, and the last
    !> message IDA's error handler left in the run's data) as status_bad_input.
    subroutine sundials_failure(w, status, what, flag)
        type(ida_work_t), intent(in) :: w
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: what
        integer, intent(in), optional :: flag
        character(len=:), allocatable :: text
        text = 'ida: ' // what // ' failed'
        if (present(flag)) text = text // ' with flag ' // int_text(flag)
        if (allocated(w%data%message)) text = text // ': ' // w%data%message
        call status%set(status_bad_input, text)
    end subroutine sundials_failure

    !> IDA's return flags as status_t, with the time reached and IDA's words.
    subroutine map_failure(self, w, flag, what, options, stats, status)
        class(ida_engine_t), intent(inout) :: self
        type(ida_work_t), intent(inout) :: w
        integer, intent(in) :: flag
        character(len=*), intent(in) :: what
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        integer :: reason
        character(len=:), allocatable :: text
        select case (flag)
        case (IDA_TOO_MUCH_WORK)
            reason = reason_max_steps
            text = 'more than ' // int_text(options%max_steps) // ' steps needed'
        case (IDA_TOO_MUCH_ACC, IDA_ERR_FAIL, IDA_BAD_EWT)
            reason = reason_step_too_small
            text = 'step size too small (error test failed repeatedly or accuracy ' // &
                'unattainable)'
        case (IDA_CONV_FAIL, IDA_LINESEARCH_FAIL, IDA_NO_RECOVERY)
            reason = reason_newton_failure
            text = 'Newton iteration failed repeatedly'
        case (IDA_LINIT_FAIL, IDA_LSETUP_FAIL, IDA_LSOLVE_FAIL)
            reason = reason_singular_matrix
            text = 'linear solver failed (singular iteration matrix)'
        case (IDA_RES_FAIL, IDA_REP_RES_ERR, IDA_FIRST_RES_FAIL)
            reason = reason_user_function
            text = 'residual failed repeatedly'
        case default
            reason = reason_newton_failure
            text = what
        end select
        ! A failing callback says more than IDA's flag (the last refusal
        ! closes the rejection causes).
        call collect_statistics(self, w, stats)
        if (.not. w%data%failure%ok()) then
            if (w%data%failure%reason /= 0 .and. reason /= reason_max_steps) &
                reason = w%data%failure%reason
            if (stats%rejections%count_of(cause_model_refused) == 0) &
                text = text // '; first callback failure: ' // w%data%failure%text()
        end if
        text = 'ida: ' // text // '; stopped at t = ' // real_text(w%x) // &
            stats%rejections%failure_text() // ' (IDA flag ' // int_text(flag) // ')'
        w%annotated = .true.
        if (allocated(w%data%message)) text = text // ': ' // w%data%message
        call status%set(status_solver_failure, text, reason)
    end subroutine map_failure

    !> IDA's counters into self%native and, as docs/solvers.md maps them,
    !> into stats.
    subroutine collect_statistics(self, w, stats)
        class(ida_engine_t), intent(inout) :: self
        type(ida_work_t), intent(in) :: w
        type(dae_stats_t), intent(inout) :: stats
        integer(c_long) :: v(1)
        integer(c_int) :: order(1)
        real(c_double) :: h(1)
        if (.not. c_associated(w%mem)) return
        v = 0
        if (FIDAGetNumSteps(w%mem, v) == 0) self%native%nst = int(v(1))
        if (FIDAGetNumResEvals(w%mem, v) == 0) self%native%nre = int(v(1))
        if (FIDAGetNumLinResEvals(w%mem, v) == 0) self%native%nre_ls = int(v(1))
        if (FIDAGetNumJacEvals(w%mem, v) == 0) self%native%nje = int(v(1))
        if (FIDAGetNumLinSolvSetups(w%mem, v) == 0) self%native%nsetups = int(v(1))
        if (FIDAGetNumNonlinSolvIters(w%mem, v) == 0) self%native%nni = int(v(1))
        if (FIDAGetNumErrTestFails(w%mem, v) == 0) self%native%netf = int(v(1))
        if (FIDAGetNumStepSolveFails(w%mem, v) == 0) self%native%ncfn = int(v(1))
        if (FIDAGetNumNonlinSolvConvFails(w%mem, v) == 0) self%native%nnf = int(v(1))
        order = 0
        if (FIDAGetLastOrder(w%mem, order) == 0) self%native%last_order = int(order(1))
        h = 0.0_wp
        if (FIDAGetLastStep(w%mem, h) == 0) self%native%last_step = h(1)
        ! docs/architecture.md, the DAE contract.
        stats%nst = self%native%nst + self%native%netf + self%native%ncfn
        stats%nac = self%native%nst
        stats%nrj = stats%nst - stats%nac
        stats%nfe = self%native%nre
        stats%nfe_jac = self%native%nre_ls
        stats%nje = self%native%nje
        stats%ndec = self%native%nsetups
        stats%nsol = self%native%nni
        ! netf by the error test, the ncfn failed solves by the observer's causes
        stats%rejections = observed_rejections(w%data%observer, self%native%netf, &
            w%data%refusal)
        ! ours behind the SUNLinearSolver, else SUNDIALS' own
        if (w%data%jac_mode == jac_own .and. allocated(w%data%ls)) then
            stats%linear_solver = w%data%ls%description()
            stats%linear_solver_report = w%data%ls%report()
        else if (w%data%jac_mode == jac_sparse) then
            stats%linear_solver = 'klu (SUNDIALS)'
        else
            stats%linear_solver = 'dense (SUNDIALS)'
        end if
    end subroutine collect_statistics

    !> A quiet NaN: what the dense output returns when IDAGetDky fails, so that
    !> a bad interpolation cannot pass for a value.
    real(wp) function ieee_nan()
        use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
        ieee_nan = ieee_value(1.0_wp, ieee_quiet_nan)
    end function ieee_nan
end module flexmbs_dae_ida_state
