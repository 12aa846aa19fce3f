!> IDA's memory and the SUNDIALS objects of one integration (docs/theory.md
!> §8): the context, the vectors over the work arrays, IDA created and set
!> (callbacks, tolerances, order, steps, stop time, the observed Newton
!> solver), the iteration matrix with its linear solver, the initial
!> values made consistent, and every object freed at the end. Every
!> SUNDIALS flag is checked.
module flexmbs_dae_ida_sundials
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_null_ptr, c_associated, &
        c_loc, c_funloc
    use fsundials_context_mod, only: FSUNContext_Create, FSUNContext_Free
    use fsundials_nvector_mod, only: FN_VDestroy
    use fsundials_matrix_mod, only: FSUNMatDestroy
    use fsundials_linearsolver_mod, only: FSUNLinSolFree
    use fnvector_serial_mod, only: FN_VMake_Serial
    use fsunmatrix_dense_mod, only: FSUNDenseMatrix
    use fsunmatrix_sparse_mod, only: FSUNSparseMatrix, CSC_MAT
    use fsunlinsol_dense_mod, only: FSUNLinSol_Dense
    use fsunlinsol_klu_mod, only: FSUNLinSol_KLU
    use fida_mod, only: FIDACreate, FIDAInit, FIDAFree, FIDASStolerances, FIDASVtolerances, &
        FIDAWFtolerances, FIDASetUserData, FIDASetErrHandlerFn, FIDASetMaxOrd, &
        FIDASetInitStep, FIDASetMaxStep, FIDASetStopTime, FIDASetId, FIDASetSuppressAlg, &
        FIDASetLinearSolver, FIDASetJacFn, FIDACalcIC, FIDAGetConsistentIC, IDA_YA_YDP_INIT
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_ida_callbacks, only: ida_residual, ida_jacobian, ida_weights, &
        ida_error_handler, jac_quotients, jac_sparse, jac_own
    use flexmbs_dae_ida_linear_solver, only: own_linear_solver
    use flexmbs_dae_ida_observer, only: observer_attach, observer_free
    use flexmbs_dae_ida_state, only: ida_engine_t, ida_work_t, ida_max_order, check, &
        sundials_failure, map_failure
    implicit none
    private
    public :: create_ida, consistent_start, free_all

contains

    !> The context, the vectors over w's arrays and IDA with its settings,
    !> the linear solver and the differential components. `w` is the
    !> driver's target: IDA keeps the addresses of w%data and the arrays.
    subroutine create_ida(self, w, t_end, options, status)
        class(ida_engine_t), intent(inout) :: self
        type(ida_work_t), intent(inout), target :: w
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        integer(c_int64_t) :: n
        n = int(w%n, c_int64_t)
        if (FSUNContext_Create(c_null_ptr, w%ctx) /= 0) then
            call sundials_failure(w, status, 'SUNContext_Create')
            return
        end if
        w%nv_y => FN_VMake_Serial(n, w%yw, w%ctx)
        w%nv_yp => FN_VMake_Serial(n, w%ypw, w%ctx)
        w%nv_atol => FN_VMake_Serial(n, w%atolw, w%ctx)
        w%nv_id => FN_VMake_Serial(n, w%idw, w%ctx)
        w%nv_dky => FN_VMake_Serial(n, w%dkyw, w%ctx)
        if (.not. (associated(w%nv_y) .and. associated(w%nv_yp) .and. associated(w%nv_atol) &
            .and. associated(w%nv_id) .and. associated(w%nv_dky))) then
            call sundials_failure(w, status, 'N_VMake_Serial')
            return
        end if
        w%mem = FIDACreate(w%ctx)
        w%data%mem = w%mem
        if (.not. c_associated(w%mem)) then
            call sundials_failure(w, status, 'IDACreate')
            return
        end if
        if (.not. check(w, status, FIDASetErrHandlerFn(w%mem, c_funloc(ida_error_handler), &
            c_loc(w%data)), 'IDASetErrHandlerFn')) return
        if (.not. check(w, status, FIDAInit(w%mem, c_funloc(ida_residual), w%x, w%nv_y, &
            w%nv_yp), 'IDAInit')) return
        if (.not. check(w, status, FIDASetUserData(w%mem, c_loc(w%data)), 'IDASetUserData')) &
            return
        w%data%observer = observer_attach(w%mem, c_loc(w%nv_y), w%ctx)
        if (.not. c_associated(w%data%observer)) then
            call sundials_failure(w, status, 'attaching the observed Newton solver')
            return
        end if
        call set_tolerances(w, options, status)
        if (.not. status%ok()) return
        if (.not. check(w, status, FIDASetMaxOrd(w%mem, &
            int(min(options%pmax, ida_max_order), c_int)), 'IDASetMaxOrd')) return
        if (options%h0 > 0.0_wp) then
            if (.not. check(w, status, FIDASetInitStep(w%mem, w%posneg * options%h0), &
                'IDASetInitStep')) return
        end if
        if (options%hmax > 0.0_wp) then
            if (.not. check(w, status, FIDASetMaxStep(w%mem, options%hmax), 'IDASetMaxStep')) &
                return
        end if
        ! IDA must not step past t_end: F may be undefined there.
        if (.not. check(w, status, FIDASetStopTime(w%mem, t_end), 'IDASetStopTime')) return
        call attach_linear_solver(self, w, status)
        if (.not. status%ok()) return
        w%idw = merge(1.0_wp, 0.0_wp, w%flags)
        if (.not. check(w, status, FIDASetId(w%mem, w%nv_id), 'IDASetId')) return
    end subroutine create_ida

    !> Scalar or vector tolerances; per-component rtol needs IDA's weight hook.
    subroutine set_tolerances(w, options, st)
        type(ida_work_t), intent(inout) :: w
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: st
        logical :: ok
        if (.not. st%ok()) return
        if (any(w%data%newton_power > 0)) then
            ok = check(w, st, FIDAWFtolerances(w%mem, c_funloc(ida_weights)), 'IDAWFtolerances')
            return
        end if
        if (allocated(options%rtol_vector)) then
            if (any(options%rtol_vector /= options%rtol_vector(1))) then
                ok = check(w, st, FIDAWFtolerances(w%mem, c_funloc(ida_weights)), &
                    'IDAWFtolerances')
                return
            end if
        end if
        if (allocated(options%atol_vector)) then
            w%atolw = w%data%atol
            ok = check(w, st, FIDASVtolerances(w%mem, w%data%rtol(1), w%nv_atol), &
                'IDASVtolerances')
        else
            ok = check(w, st, FIDASStolerances(w%mem, w%data%rtol(1), w%data%atol(1)), &
                'IDASStolerances')
        end if
    end subroutine set_tolerances

    !> The iteration matrix, dense or CSC, with SUNDIALS' dense LU or KLU,
    !> or ours (jac_own); the Jacobian callback unless IDA forms difference
    !> quotients.
    subroutine attach_linear_solver(self, w, st)
        class(ida_engine_t), intent(inout) :: self
        type(ida_work_t), intent(inout) :: w
        type(status_t), intent(inout) :: st
        logical :: ok
        if (w%data%jac_mode == jac_own) then
            ! IDA's matrix is a placeholder; w%data%ls holds the real one
            w%a_mat => FSUNDenseMatrix(1_c_int64_t, 1_c_int64_t, w%ctx)
            if (.not. associated(w%a_mat)) then
                call out_of_memory(st, 'ida placeholder matrix', 1_i8, 8)
                return
            end if
            w%lin_solver => own_linear_solver(w%data, w%ctx)
            self%linear_solver_used = w%data%ls%name()
        else if (w%data%jac_mode == jac_sparse) then
            w%a_mat => FSUNSparseMatrix(int(w%n, c_int64_t), int(w%n, c_int64_t), &
                int(w%data%nnz, c_int64_t), CSC_MAT, w%ctx)
            if (.not. associated(w%a_mat)) then
                ! NULL only when its malloc failed: values and row indices
                call out_of_memory(st, 'ida sparse iteration matrix', 2 * w%data%nnz, 8)
                return
            end if
            w%lin_solver => FSUNLinSol_KLU(w%nv_y, w%a_mat, w%ctx)
            self%linear_solver_used = 'klu'
        else
            w%a_mat => FSUNDenseMatrix(int(w%n, c_int64_t), int(w%n, c_int64_t), w%ctx)
            if (.not. associated(w%a_mat)) then
                ! NULL only when its malloc failed
                call out_of_memory(st, 'ida dense iteration matrix', int(w%n, i8) * w%n, 8)
                return
            end if
            w%lin_solver => FSUNLinSol_Dense(w%nv_y, w%a_mat, w%ctx)
            self%linear_solver_used = 'dense'
        end if
        if (.not. associated(w%lin_solver)) then
            call sundials_failure(w, st, 'SUNLinSol_' // trim(self%linear_solver_used))
            return
        end if
        if (.not. check(w, st, FIDASetLinearSolver(w%mem, w%lin_solver, w%a_mat), &
            'IDASetLinearSolver')) return
        if (w%data%jac_mode /= jac_quotients) ok = check(w, st, FIDASetJacFn(w%mem, &
            c_funloc(ida_jacobian)), 'IDASetJacFn')
    end subroutine attach_linear_solver

    !> IDACalcIC when asked (toward the first output time), then the error
    !> test's exclusion: IDA masks the components with id = 0, so the id
    !> vector becomes "index 1" once the initial values are settled.
    subroutine consistent_start(self, w, t_end, options, stats, status)
        class(ida_engine_t), intent(inout) :: self
        type(ida_work_t), intent(inout) :: w
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        real(wp) :: tout
        integer(c_int) :: retval
        if (self%calc_ic) then
            tout = t_end
            if (w%nout > 0) then
                if (any((options%output_times - w%x) * w%posneg > 0.0_wp)) tout = &
                    minval(abs(options%output_times - w%x), &
                    mask=(options%output_times - w%x) * w%posneg > 0.0_wp) * w%posneg + w%x
            end if
            retval = FIDACalcIC(w%mem, IDA_YA_YDP_INIT, tout)
            if (retval < 0) then
                call map_failure(self, w, int(retval), 'initial-condition calculation failed', &
                    options, stats, status)
                return
            end if
            if (.not. check(w, status, FIDAGetConsistentIC(w%mem, w%nv_y, w%nv_yp), &
                'IDAGetConsistentIC')) return
        end if
        if (w%suppress) then
            w%idw = merge(1.0_wp, 0.0_wp, w%classes == 1)
            if (.not. check(w, status, FIDASetId(w%mem, w%nv_id), 'IDASetId')) return
            if (.not. check(w, status, FIDASetSuppressAlg(w%mem, 1_c_int), &
                'IDASetSuppressAlg')) return
        end if
    end subroutine consistent_start

    !> IDA memory first (it refers to the others), the context last.
    subroutine free_all(w)
        type(ida_work_t), intent(inout) :: w
        integer(c_int) :: ierr
        if (c_associated(w%mem)) call FIDAFree(w%mem)
        if (c_associated(w%data%observer)) call observer_free(w%data%observer)
        w%data%observer = c_null_ptr
        if (associated(w%lin_solver)) ierr = FSUNLinSolFree(w%lin_solver)
        if (associated(w%a_mat)) call FSUNMatDestroy(w%a_mat)
        if (associated(w%nv_y)) call FN_VDestroy(w%nv_y)
        if (associated(w%nv_yp)) call FN_VDestroy(w%nv_yp)
        if (associated(w%nv_atol)) call FN_VDestroy(w%nv_atol)
        if (associated(w%nv_id)) call FN_VDestroy(w%nv_id)
        if (associated(w%nv_dky)) call FN_VDestroy(w%nv_dky)
        if (c_associated(w%ctx)) ierr = FSUNContext_Free(w%ctx)
        w%mem = c_null_ptr
        w%ctx = c_null_ptr
        nullify (w%nv_y, w%nv_yp, w%nv_atol, w%nv_id, w%nv_dky, w%a_mat, w%lin_solver)
    end subroutine free_all
end module flexmbs_dae_ida_sundials
