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
module flexmbs_dae_ida
    use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_int64_t, c_ptr, &
        c_null_ptr, c_associated, c_loc, c_funloc, c_f_pointer, c_char, c_null_char
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use fsundials_context_mod, only: FSUNContext_Create, FSUNContext_Free
    use fsundials_nvector_mod, only: N_Vector, FN_VDestroy, FN_VGetArrayPointer
    use fsundials_matrix_mod, only: SUNMatrix, FSUNMatDestroy
    use fsundials_linearsolver_mod, only: SUNLinearSolver, FSUNLinSolFree
    use fnvector_serial_mod, only: FN_VMake_Serial
    use fsunmatrix_dense_mod, only: FSUNDenseMatrix, FSUNDenseMatrix_Data
    use fsunmatrix_sparse_mod, only: FSUNSparseMatrix, FSUNSparseMatrix_Data, &
        FSUNSparseMatrix_IndexValues, FSUNSparseMatrix_IndexPointers, CSC_MAT
    use fsunlinsol_dense_mod, only: FSUNLinSol_Dense
    use fsunlinsol_klu_mod, only: FSUNLinSol_KLU
    use fida_mod, only: FIDACreate, FIDAInit, FIDAFree, FIDASStolerances, FIDASVtolerances, &
        FIDAWFtolerances, FIDASetUserData, FIDASetErrHandlerFn, FIDASetMaxOrd, &
        FIDASetMaxNumSteps, FIDASetInitStep, FIDASetMaxStep, FIDASetStopTime, FIDASetId, &
        FIDASetSuppressAlg, FIDASetLinearSolver, FIDASetJacFn, FIDACalcIC, &
        FIDAGetConsistentIC, FIDASolve, FIDAGetDky, FIDAGetNumSteps, FIDAGetNumResEvals, &
        FIDAGetNumLinResEvals, FIDAGetNumJacEvals, FIDAGetNumLinSolvSetups, &
        FIDAGetNumNonlinSolvIters, FIDAGetNumErrTestFails, FIDAGetNumNonlinSolvConvFails, &
        FIDAGetNumStepSolveFails, &
        FIDAGetLastStep, FIDAGetLastOrder, FIDAGetCurrentStep, IDA_NORMAL, IDA_ONE_STEP, IDA_YA_YDP_INIT, &
        IDA_TSTOP_RETURN, IDA_TOO_MUCH_WORK, IDA_TOO_MUCH_ACC, IDA_ERR_FAIL, IDA_CONV_FAIL, &
        IDA_LINIT_FAIL, IDA_LSETUP_FAIL, IDA_LSOLVE_FAIL, IDA_RES_FAIL, IDA_REP_RES_ERR, &
        IDA_FIRST_RES_FAIL, IDA_LINESEARCH_FAIL, IDA_NO_RECOVERY, IDA_BAD_EWT
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_step_too_small, reason_max_steps, reason_singular_matrix, &
        reason_newton_failure, reason_user_function, reason_non_finite, reason_det_f
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: auto_sparse_threshold
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t, problem_mass_matrix
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t, index3_warning, projection_refusal
    use flexmbs_dae_multiplier_scaling, only: multiplier_kappa
    use flexmbs_dae_rejections, only: refusal_len, cause_model_refused
    use flexmbs_dae_ida_callbacks, only: callback_data_t, ida_residual, ida_jacobian, &
        ida_weights, ida_error_handler, jac_quotients, jac_dense, jac_scatter, jac_sparse, &
        jac_own
    use flexmbs_dae_ida_linear_solver, only: own_linear_solver
    use flexmbs_dae_ida_observer, only: observer_attach, observer_free, &
        observed_rejections
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private

    integer, parameter :: ida_max_order = 5    !! IDA's BDF orders are 1…5

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
    type, extends(dae_solver_t), public :: ida_t
        logical :: calc_ic = .false.
        logical :: suppress_alg = .true.
        type(ida_native_t) :: native
        !> Linear solver used by the last integration: 'dense', 'klu' (SUNDIALS'),
        !> 'mumps', or the problem's ('condensed klu', 'condensed mumps').
        character(len=16) :: linear_solver_used = ''
    contains
        procedure :: integrate_dae => ida_integrate
        procedure :: name => ida_name
    end type ida_t


    !> IDA's interpolant of the last step, through IDAGetDky.
    type, extends(dense_output_t) :: ida_dense_t
        type(c_ptr) :: mem = c_null_ptr
        type(N_Vector), pointer :: vector => null()
        real(wp), pointer :: values(:) => null()
    contains
        procedure :: evaluate => ida_dense_evaluate
    end type ida_dense_t

contains

    function ida_name(self) result(name)
        class(ida_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'ida'
    end function ida_name

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

    !> Integrate M y' = F(t, y) from (t, y) to t_end. `yp`, when given, is
    !> the initial y' (and receives the final one); otherwise y' comes from
    !> F (M = I), from IDACalcIC (`calc_ic`) or from the problem's
    !> `consistent_initial`.
    subroutine ida_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(ida_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)
        type(timer_t) :: timer
        type(status_t) :: sink_status

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
        if (present(sink)) then
            call sink%finish(sink_status)
            if (status%ok() .and. .not. sink_status%ok()) status = sink_status
        end if
    end subroutine ida_integrate

    !> The integration proper; `problem` is a target so that the callbacks
    !> can reach it during the call. Every SUNDIALS object is freed at the end.
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

        type(callback_data_t), target :: data
        type(ida_dense_t) :: dense
        type(c_ptr), target :: ctx, mem
        type(N_Vector), pointer :: nv_y, nv_yp, nv_atol, nv_id, nv_dky
        type(SUNMatrix), pointer :: a_mat
        type(SUNLinearSolver), pointer :: lin_solver
        real(wp), allocatable, target :: yw(:), ypw(:), atolw(:), idw(:), dkyw(:)
        real(c_double) :: tret(1)
        integer(c_int) :: retval
        integer :: n, nout, iout, retval_solve, stat
        integer, allocatable :: classes(:)
        logical, allocatable :: flags(:)
        real(wp) :: x, x_old, tout, posneg
        logical :: want_steps, stop_requested, use_klu, suppress
        logical :: annotated !! the failure message names the rejection causes

        n = problem%n
        ctx = c_null_ptr
        mem = c_null_ptr
        annotated = .false.
        nullify (nv_y, nv_yp, nv_atol, nv_id, nv_dky, a_mat, lin_solver)
        x = t
        posneg = sign(1.0_wp, t_end - t)
        want_steps = .false.
        if (present(sink)) want_steps = sink%wants_steps()
        stop_requested = .false.
        nout = 0
        if (allocated(options%output_times)) nout = size(options%output_times)
        iout = 1

        data%problem => problem
        data%n = n
        allocate (data%f(n), data%rtol(n), data%atol(n), yw(n), ypw(n), atolw(n), idw(n), &
            dkyw(n), classes(n), flags(n), data%newton_power(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'ida vectors', 11_i8 * n, 8)
            return
        end if
        call options%tolerances(data%rtol, data%atol)
        yw = y
        call problem%index_classes(classes)
        suppress = self%suppress_alg .and. any(classes > 1)
        call problem%multiplier_flags(flags)
        data%newton_power = 0
        if (suppress) where (flags .and. classes > 1) data%newton_power = classes - 1
        data%kappa = multiplier_kappa(minval(data%rtol))
        call problem%differential_flags(flags)
        if (any(classes >= 3)) stats%warning = index3_warning('ida')

        run: block
            call setup_matrices(status)
            if (.not. status%ok()) exit run
            call initial_derivative(status)
            if (.not. status%ok()) exit run
            call first_step_estimate()

            if (FSUNContext_Create(c_null_ptr, ctx) /= 0) then
                call sundials_failure('SUNContext_Create')
                exit run
            end if
            nv_y => FN_VMake_Serial(int(n, c_int64_t), yw, ctx)
            nv_yp => FN_VMake_Serial(int(n, c_int64_t), ypw, ctx)
            nv_atol => FN_VMake_Serial(int(n, c_int64_t), atolw, ctx)
            nv_id => FN_VMake_Serial(int(n, c_int64_t), idw, ctx)
            nv_dky => FN_VMake_Serial(int(n, c_int64_t), dkyw, ctx)
            if (.not. (associated(nv_y) .and. associated(nv_yp) .and. associated(nv_atol) &
                .and. associated(nv_id) .and. associated(nv_dky))) then
                call sundials_failure('N_VMake_Serial')
                exit run
            end if
            mem = FIDACreate(ctx)
            data%mem = mem
            if (.not. c_associated(mem)) then
                call sundials_failure('IDACreate')
                exit run
            end if
            if (.not. check(FIDASetErrHandlerFn(mem, c_funloc(ida_error_handler), &
                c_loc(data)), 'IDASetErrHandlerFn')) exit run
            if (.not. check(FIDAInit(mem, c_funloc(ida_residual), x, nv_y, nv_yp), &
                'IDAInit')) exit run
            if (.not. check(FIDASetUserData(mem, c_loc(data)), 'IDASetUserData')) exit run
            data%observer = observer_attach(mem, c_loc(nv_y), ctx)
            if (.not. c_associated(data%observer)) then
                call sundials_failure('attaching the observed Newton solver')
                exit run
            end if
            call set_tolerances(status)
            if (.not. status%ok()) exit run
            if (.not. check(FIDASetMaxOrd(mem, int(min(options%pmax, ida_max_order), c_int)), &
                'IDASetMaxOrd')) exit run
            if (options%h0 > 0.0_wp) then
                if (.not. check(FIDASetInitStep(mem, posneg * options%h0), 'IDASetInitStep')) &
                    exit run
            end if
            if (options%hmax > 0.0_wp) then
                if (.not. check(FIDASetMaxStep(mem, options%hmax), 'IDASetMaxStep')) exit run
            end if
            ! IDA must not step past t_end: F may be undefined there.
            if (.not. check(FIDASetStopTime(mem, t_end), 'IDASetStopTime')) exit run
            call attach_linear_solver(status)
            if (.not. status%ok()) exit run
            idw = merge(1.0_wp, 0.0_wp, flags)
            if (.not. check(FIDASetId(mem, nv_id), 'IDASetId')) exit run

            if (self%calc_ic) then
                tout = t_end
                if (nout > 0) then
                    if (any((options%output_times - x) * posneg > 0.0_wp)) tout = &
                        minval(abs(options%output_times - x), &
                        mask=(options%output_times - x) * posneg > 0.0_wp) * posneg + x
                end if
                retval = FIDACalcIC(mem, IDA_YA_YDP_INIT, tout)
                if (retval < 0) then
                    call map_failure(int(retval), 'initial-condition calculation failed')
                    exit run
                end if
                if (.not. check(FIDAGetConsistentIC(mem, nv_y, nv_yp), 'IDAGetConsistentIC')) &
                    exit run
            end if
            ! Error-test exclusion: IDA masks the components with id = 0, so the
            ! id vector becomes "index 1" once the initial values are settled.
            if (suppress) then
                idw = merge(1.0_wp, 0.0_wp, classes == 1)
                if (.not. check(FIDASetId(mem, nv_id), 'IDASetId')) exit run
                if (.not. check(FIDASetSuppressAlg(mem, 1_c_int), 'IDASetSuppressAlg')) exit run
            end if

            dense%mem = mem
            dense%vector => nv_dky
            dense%values => dkyw
            ! Output at t0.
            if (present(sink)) then
                do while (iout <= nout)
                    if ((options%output_times(iout) - x) * posneg > 0.0_wp) exit
                    if (options%output_times(iout) == x) call sink%output(x, yw, status)
                    iout = iout + 1
                    if (.not. status%ok()) exit run
                end do
                if (want_steps) call sink%step(1, x, x, yw, dense, stop_requested, status)
                if (.not. status%ok()) exit run
                if (stop_requested) then
                    call interrupted()
                    exit run
                end if
            end if

            if (want_steps) then
                call step_by_step()
            else
                call to_output_times()
            end if
        end block run

        call collect_statistics()
        if (.not. annotated) call stats%rejections%annotate(status)
        call free_all()
        t = x
        y = yw
        if (present(yp)) yp = ypw
        stats%t_reached = x
        stats%h_last = self%native%last_step

    contains

        !> True when a SUNDIALS call returned 0; otherwise records the failure.
        logical function check(flag, what)
            integer(c_int), intent(in) :: flag
            character(len=*), intent(in) :: what
            check = flag == 0
            if (.not. check) call sundials_failure(what, int(flag))
        end function check

        subroutine sundials_failure(what, flag)
            character(len=*), intent(in) :: what
            integer, intent(in), optional :: flag
            character(len=:), allocatable :: text
            text = 'ida: ' // what // ' failed'
            if (present(flag)) text = text // ' with flag ' // int_text(flag)
            if (allocated(data%message)) text = text // ': ' // data%message
            call status%set(status_bad_input, text)
        end subroutine sundials_failure

        subroutine interrupted()
            call status%set(status_interrupted, &
                'ida: interrupted by the output routine at t = ' // real_text(x))
        end subroutine interrupted

        !> M and the storage of ∂F/∂y, and the pattern of c_j M − ∂F/∂y.
        subroutine setup_matrices(st)
            type(status_t), intent(inout) :: st
            integer :: storage
            call problem_mass_matrix(problem, data%mass, st, 'ida')
            if (.not. st%ok()) return
            storage = problem%jacobian_storage()
            if (options%jacobian == 'fd') storage = storage_none
            select case (storage)
            case (storage_dense)
                data%jac_mode = jac_dense
            case (storage_sparse)
                call problem%jacobian_pattern(data%jac, st)
                if (.not. st%ok()) return
                data%jac_mode = jac_scatter
            case default
                data%jac_mode = jac_quotients
            end select
            if (data%jac_mode == jac_scatter) then
                call own_solver(st)
                if (.not. st%ok() .or. data%jac_mode == jac_own) return
            end if
            select case (options%linear_solver)
            case ('klu')
                use_klu = .true.
            case ('dense')
                use_klu = .false.
            case ('band', 'mumps')
                call st%set(status_bad_input, "ida: linear_solver = '" &
                    // trim(options%linear_solver) // "' needs an analytic sparse " &
                    // "Jacobian with IDA (jacobian_storage = storage_sparse, jacobian = " &
                    // "'analytic'); 'band' is not offered; use 'dense', 'klu' or 'auto'")
                return
            case default
                use_klu = data%jac_mode == jac_scatter .and. n >= auto_sparse_threshold
            end select
            if (use_klu .and. data%jac_mode /= jac_scatter) then
                call st%set(status_bad_input, "ida: linear_solver = 'klu' needs an analytic " &
                    // "sparse Jacobian (jacobian_storage = storage_sparse, jacobian = " &
                    // "'analytic'); use 'dense' or 'auto'")
                return
            end if
            if (use_klu) then
                data%jac_mode = jac_sparse
                call build_iteration_pattern(st)
            end if
        end subroutine setup_matrices

        !> With a sparse analytic ∂F/∂y: the problem's solver of c_j M − ∂F/∂y
        !> (condensed Newton systems), or MUMPS when asked for, behind our
        !> SUNLinearSolver (mode jac_own); otherwise SUNDIALS' own solvers.
        subroutine own_solver(st)
            type(status_t), intent(inout) :: st
            call problem%iteration_solver(options, data%ls, st)
            if (.not. st%ok()) return
            if (.not. allocated(data%ls) .and. options%linear_solver == 'mumps') &
                call new_linear_solver('mumps', n, storage_sparse, data%ls, st, &
                    ordering=options%sparse_ordering)
            if (.not. st%ok() .or. .not. allocated(data%ls)) return
            data%jac_matrix%n = n
            data%jac_matrix%storage = storage_sparse
            data%jac_matrix%csc = data%jac
            call data%ls%init(data%mass, data%jac_matrix, st)
            if (.not. st%ok()) then
                st%message = 'ida: ' // st%message
                return
            end if
            data%jac_mode = jac_own
        end subroutine own_solver

        !> Union of the patterns of ∂F/∂y and M; slot maps for both.
        subroutine build_iteration_pattern(st)
            type(status_t), intent(inout) :: st
            type(csc_matrix_t) :: union
            integer, allocatable :: rows(:), cols(:), mrows(:), mcols(:)
            integer :: i, j, nj, nm, k
            select case (data%mass%storage)
            case (storage_sparse)
                data%mass_csc = data%mass%csc
            case (storage_dense)
                ! Structural non-zeros of the dense M.
                nm = count(data%mass%dense /= 0.0_wp)
                allocate (mrows(nm), mcols(nm), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(st, 'ida mass pattern positions', 2_i8 * nm, 4)
                    return
                end if
                k = 0
                do j = 1, n
                    do i = 1, n
                        if (data%mass%dense(i, j) /= 0.0_wp) then
                            k = k + 1
                            mrows(k) = i
                            mcols(k) = j
                        end if
                    end do
                end do
                call data%mass_csc%build(n, n, mrows, mcols, st)
                if (.not. st%ok()) return
                do k = 1, nm
                    data%mass_csc%values(data%mass_csc%triplet_map(k)) = &
                        data%mass%dense(mrows(k), mcols(k))
                end do
            case default
                call data%mass_csc%build(n, n, [(k, k=1, n)], [(k, k=1, n)], st)
                if (.not. st%ok()) return
                data%mass_csc%values = 1.0_wp
            end select
            nj = int(data%jac%nnz)
            nm = int(data%mass_csc%nnz)
            allocate (rows(nj + nm), cols(nj + nm), stat=stat)
            if (stat /= 0) then
                call out_of_memory(st, 'ida iteration pattern positions', 2_i8 * (nj + nm), 4)
                return
            end if
            k = 0
            call append_pattern(data%jac, rows, cols, k)
            call append_pattern(data%mass_csc, rows, cols, k)
            call union%build(n, n, rows, cols, st)
            if (.not. st%ok()) return
            data%nnz = union%nnz
            data%colptr = union%colptr
            data%rowind = union%rowind
            data%jac_slot = union%triplet_map(1:nj)
            data%mass_slot = union%triplet_map(nj + 1:nj + nm)
        end subroutine build_iteration_pattern

        !> y'0: given, F (M = I), guessed for IDACalcIC, or the problem's.
        !> |h| of IDA's first step, which the weights of the correction
        !> components need before IDA has one: the one asked for, or IDA's
        !> rule min(0.001 |t_out - t0|, 0.5/‖y0'‖), the norm over the
        !> components in the error test.
        subroutine first_step_estimate()
            real(wp) :: tfirst, ypnorm
            integer :: k
            if (options%h0 > 0.0_wp) then
                data%h_start = options%h0
                return
            end if
            tfirst = t_end
            if (allocated(options%output_times)) then
                do k = 1, size(options%output_times)
                    if ((options%output_times(k) - x) * posneg > 0.0_wp) then
                        if ((options%output_times(k) - tfirst) * posneg < 0.0_wp) &
                            tfirst = options%output_times(k)
                        exit
                    end if
                end do
            end if
            data%h_start = 0.001_wp * abs(tfirst - x)
            ypnorm = sqrt(sum(merge((ypw / (data%rtol * abs(yw) + data%atol))**2, 0.0_wp, &
                                    classes == 1 .or. .not. suppress)) / real(n, wp))
            if (ypnorm > 0.5_wp / data%h_start) data%h_start = 0.5_wp / ypnorm
        end subroutine first_step_estimate

        subroutine initial_derivative(st)
            type(status_t), intent(inout) :: st
            type(status_t) :: fst
            if (present(yp)) then
                ypw = yp
                return
            end if
            if (data%mass%storage == storage_identity) then
                call problem%rhs(x, yw, ypw, fst)
                if (.not. fst%ok()) call st%set(status_solver_failure, &
                    'ida: right-hand side failed at t = ' // real_text(x) // ': ' // &
                    fst%text(), reason_user_function)
            else if (self%calc_ic) then
                ! IDACalcIC computes the differential y' from this guess.
                ypw = 0.0_wp
            else
                call problem%consistent_initial(x, yw, ypw, fst)
                if (fst%reason == reason_det_f) then
                    call st%set(status_solver_failure, 'ida: the initial state is refused ' // &
                        'at t = ' // real_text(x) // ': ' // fst%text(), reason_det_f)
                else if (.not. fst%ok()) then
                    call st%set(status_bad_input, 'ida: no initial y'': ' // &
                        fst%text() // '; pass yp or set calc_ic = .true.')
                end if
            end if
        end subroutine initial_derivative

        !> Scalar or vector tolerances; per-component rtol needs IDA's weight hook.
        subroutine set_tolerances(st)
            type(status_t), intent(inout) :: st
            logical :: ok
            if (.not. st%ok()) return
            if (any(data%newton_power > 0)) then
                ok = check(FIDAWFtolerances(mem, c_funloc(ida_weights)), 'IDAWFtolerances')
                return
            end if
            if (allocated(options%rtol_vector)) then
                if (any(options%rtol_vector /= options%rtol_vector(1))) then
                    ok = check(FIDAWFtolerances(mem, c_funloc(ida_weights)), 'IDAWFtolerances')
                    return
                end if
            end if
            if (allocated(options%atol_vector)) then
                atolw = data%atol
                ok = check(FIDASVtolerances(mem, data%rtol(1), nv_atol), 'IDASVtolerances')
            else
                ok = check(FIDASStolerances(mem, data%rtol(1), data%atol(1)), &
                    'IDASStolerances')
            end if
        end subroutine set_tolerances

        subroutine attach_linear_solver(st)
            type(status_t), intent(inout) :: st
            logical :: ok
            if (data%jac_mode == jac_own) then
                ! IDA's matrix is a placeholder; data%ls holds the real one
                a_mat => FSUNDenseMatrix(1_c_int64_t, 1_c_int64_t, ctx)
                if (.not. associated(a_mat)) then
                    call out_of_memory(status, 'ida placeholder matrix', 1_i8, 8)
                    return
                end if
                lin_solver => own_linear_solver(data, ctx)
                self%linear_solver_used = data%ls%name()
            else if (data%jac_mode == jac_sparse) then
                a_mat => FSUNSparseMatrix(int(n, c_int64_t), int(n, c_int64_t), &
                    int(data%nnz, c_int64_t), CSC_MAT, ctx)
                if (.not. associated(a_mat)) then
                    ! NULL only when its malloc failed: values and row indices
                    call out_of_memory(status, 'ida sparse iteration matrix', 2 * data%nnz, 8)
                    return
                end if
                lin_solver => FSUNLinSol_KLU(nv_y, a_mat, ctx)
                self%linear_solver_used = 'klu'
            else
                a_mat => FSUNDenseMatrix(int(n, c_int64_t), int(n, c_int64_t), ctx)
                if (.not. associated(a_mat)) then
                    ! NULL only when its malloc failed
                    call out_of_memory(status, 'ida dense iteration matrix', int(n, i8) * n, 8)
                    return
                end if
                lin_solver => FSUNLinSol_Dense(nv_y, a_mat, ctx)
                self%linear_solver_used = 'dense'
            end if
            if (.not. associated(lin_solver)) then
                call sundials_failure('SUNLinSol_' // trim(self%linear_solver_used))
                return
            end if
            if (.not. check(FIDASetLinearSolver(mem, lin_solver, a_mat), &
                'IDASetLinearSolver')) return
            if (data%jac_mode /= jac_quotients) ok = check(FIDASetJacFn(mem, &
                c_funloc(ida_jacobian)), 'IDASetJacFn')
        end subroutine attach_linear_solver

        !> IDA_NORMAL to each output time, then to t_end (IDA interpolates).
        subroutine to_output_times()
            integer :: nst_now
            do while (iout <= nout)
                if ((options%output_times(iout) - x) * posneg > 0.0_wp) exit
                iout = iout + 1
            end do
            do
                tout = t_end
                if (iout <= nout) then
                    if ((options%output_times(iout) - t_end) * posneg < 0.0_wp) &
                        tout = options%output_times(iout)
                end if
                ! max_steps bounds the whole integration, IDA's limit each call.
                nst_now = accepted_steps()
                if (.not. check(FIDASetMaxNumSteps(mem, &
                    int(max(options%max_steps - nst_now, 1), c_long)), 'IDASetMaxNumSteps')) &
                    return
                retval_solve = FIDASolve(mem, tout, tret, nv_y, nv_yp, IDA_NORMAL)
                x = tret(1)
                if (retval_solve < 0) then
                    call map_failure(retval_solve, 'step failed')
                    return
                end if
                if (.not. admissible()) return
                ! past this output time whether or not a sink takes it (without
                ! one the loop would ask for the same time again forever)
                do while (iout <= nout)
                    if (options%output_times(iout) /= tout) exit
                    if (present(sink)) call sink%output(tout, yw, status)
                    iout = iout + 1
                    if (.not. status%ok()) return
                end do
                if (tout == t_end .or. retval_solve == IDA_TSTOP_RETURN) exit
            end do
        end subroutine to_output_times

        !> IDA_ONE_STEP, so that the sink sees every accepted step.
        subroutine step_by_step()
            integer :: nac
            x_old = x
            if (.not. check(FIDASetMaxNumSteps(mem, int(options%max_steps, c_long)), &
                'IDASetMaxNumSteps')) return
            do
                nac = accepted_steps()
                if (nac >= options%max_steps) then
                    call status%set(status_solver_failure, 'ida: more than ' // &
                        int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                        real_text(x), reason_max_steps)
                    return
                end if
                retval_solve = FIDASolve(mem, t_end, tret, nv_y, nv_yp, IDA_ONE_STEP)
                if (retval_solve < 0) then
                    x = tret(1)
                    call map_failure(retval_solve, 'step failed')
                    return
                end if
                x = tret(1)
                if (.not. admissible()) return
                do while (iout <= nout)
                    if ((options%output_times(iout) - x) * posneg > 0.0_wp) exit
                    if (options%output_times(iout) == x) then
                        call sink%output(x, yw, status)
                    else
                        call dense%evaluate(options%output_times(iout), dkyw)
                        call sink%output(options%output_times(iout), dkyw, status)
                    end if
                    iout = iout + 1
                    if (.not. status%ok()) return
                end do
                call sink%step(accepted_steps() + 1, x_old, x, yw, dense, stop_requested, &
                    status)
                if (.not. status%ok()) return
                if (stop_requested) then
                    call interrupted()
                    return
                end if
                if (retval_solve == IDA_TSTOP_RETURN .or. x == t_end) exit
                x_old = x
            end do
        end subroutine step_by_step

        !> IDA cannot take back a step: a state the model refuses (det F <= 0)
        !> ends the run there, with that reason, before it is output.
        logical function admissible()
            type(status_t) :: st
            call problem%admissible(x, yw, st)
            admissible = st%ok()
            if (.not. admissible) call status%set(status_solver_failure, 'ida: the model ' // &
                'refuses the state reached at t = ' // real_text(x) // ': ' // st%text(), &
                st%reason)
        end function admissible

        integer function accepted_steps()
            integer(c_long) :: count(1)
            count = 0
            if (FIDAGetNumSteps(mem, count) /= 0) count = 0
            accepted_steps = int(count(1))
        end function accepted_steps

        !> IDA's return flags as status_t, with the time reached and IDA's words.
        subroutine map_failure(flag, what)
            integer, intent(in) :: flag
            character(len=*), intent(in) :: what
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
            call collect_statistics()
            if (.not. data%failure%ok()) then
                if (data%failure%reason /= 0 .and. reason /= reason_max_steps) &
                    reason = data%failure%reason
                if (stats%rejections%count_of(cause_model_refused) == 0) &
                    text = text // '; first callback failure: ' // data%failure%text()
            end if
            text = 'ida: ' // text // '; stopped at t = ' // real_text(x) // &
                stats%rejections%failure_text() // ' (IDA flag ' // int_text(flag) // ')'
            annotated = .true.
            if (allocated(data%message)) text = text // ': ' // data%message
            call status%set(status_solver_failure, text, reason)
        end subroutine map_failure

        subroutine collect_statistics()
            integer(c_long) :: v(1)
            integer(c_int) :: order(1)
            real(c_double) :: h(1)
            if (.not. c_associated(mem)) return
            v = 0
            if (FIDAGetNumSteps(mem, v) == 0) self%native%nst = int(v(1))
            if (FIDAGetNumResEvals(mem, v) == 0) self%native%nre = int(v(1))
            if (FIDAGetNumLinResEvals(mem, v) == 0) self%native%nre_ls = int(v(1))
            if (FIDAGetNumJacEvals(mem, v) == 0) self%native%nje = int(v(1))
            if (FIDAGetNumLinSolvSetups(mem, v) == 0) self%native%nsetups = int(v(1))
            if (FIDAGetNumNonlinSolvIters(mem, v) == 0) self%native%nni = int(v(1))
            if (FIDAGetNumErrTestFails(mem, v) == 0) self%native%netf = int(v(1))
            if (FIDAGetNumStepSolveFails(mem, v) == 0) self%native%ncfn = int(v(1))
            if (FIDAGetNumNonlinSolvConvFails(mem, v) == 0) self%native%nnf = int(v(1))
            order = 0
            if (FIDAGetLastOrder(mem, order) == 0) self%native%last_order = int(order(1))
            h = 0.0_wp
            if (FIDAGetLastStep(mem, h) == 0) self%native%last_step = h(1)
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
            stats%rejections = observed_rejections(data%observer, self%native%netf, &
                data%refusal)
        end subroutine collect_statistics

        !> IDA memory first (it refers to the others), the context last.
        subroutine free_all()
            integer(c_int) :: ierr
            if (c_associated(mem)) call FIDAFree(mem)
            if (c_associated(data%observer)) call observer_free(data%observer)
            data%observer = c_null_ptr
            if (associated(lin_solver)) ierr = FSUNLinSolFree(lin_solver)
            if (associated(a_mat)) call FSUNMatDestroy(a_mat)
            if (associated(nv_y)) call FN_VDestroy(nv_y)
            if (associated(nv_yp)) call FN_VDestroy(nv_yp)
            if (associated(nv_atol)) call FN_VDestroy(nv_atol)
            if (associated(nv_id)) call FN_VDestroy(nv_id)
            if (associated(nv_dky)) call FN_VDestroy(nv_dky)
            if (c_associated(ctx)) ierr = FSUNContext_Free(ctx)
            mem = c_null_ptr
            ctx = c_null_ptr
            nullify (nv_y, nv_yp, nv_atol, nv_id, nv_dky, a_mat, lin_solver)
        end subroutine free_all
    end subroutine solve

    !> Append the 1-based positions of a's entries to (rows, cols) after k.
    pure subroutine append_pattern(a, rows, cols, k)
        type(csc_matrix_t), intent(in) :: a
        integer, intent(inout) :: rows(:), cols(:)
        integer, intent(inout) :: k
        integer :: j
        integer(i8) :: p
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                k = k + 1
                rows(k) = int(a%rowind(p)) + 1
                cols(k) = j
            end do
        end do
    end subroutine append_pattern

    real(wp) function ieee_nan()
        use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
        ieee_nan = ieee_value(1.0_wp, ieee_quiet_nan)
    end function ieee_nan
end module flexmbs_dae_ida
