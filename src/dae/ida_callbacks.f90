!> The bind(C) callbacks through which SUNDIALS IDA calls back into
!> flexmbs_dae_ida: the residual, the iteration matrix (dense or CSC), the
!> error weights and the error handler, and the data they share, to which
!> IDA's user data points (local to one integration; no module state).
module flexmbs_dae_ida_callbacks
    use, intrinsic :: iso_c_binding, only: c_int, c_double, c_int64_t, c_ptr, c_null_ptr, &
        c_associated, c_loc, c_f_pointer, c_char, c_null_char
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use fsundials_nvector_mod, only: N_Vector, FN_VGetArrayPointer
    use fsundials_matrix_mod, only: SUNMatrix
    use fsunmatrix_dense_mod, only: FSUNDenseMatrix_Data
    use fsunmatrix_sparse_mod, only: FSUNSparseMatrix_Data, FSUNSparseMatrix_IndexValues, &
        FSUNSparseMatrix_IndexPointers
    use fida_mod, only: FIDAGetCurrentStep
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_user_function, &
        reason_non_finite, reason_det_f
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_rejections, only: refusal_len
    use flexmbs_dae_ida_observer, only: observer_refused
    implicit none
    private
    public :: ida_residual, ida_jacobian, ida_weights, ida_error_handler, record

    integer, parameter :: max_message = 1000   !! longest IDA message kept

    ! How the iteration matrix is formed.
    integer, parameter, public :: jac_quotients = 0 !! IDA's difference quotients (dense)
    integer, parameter, public :: jac_dense = 1     !! problem dense, SUNDIALS dense
    integer, parameter, public :: jac_scatter = 2   !! problem CSC, SUNDIALS dense
    integer, parameter, public :: jac_sparse = 3    !! problem CSC, SUNDIALS CSC + KLU
    !> problem CSC, a linear_solver_t of ours (the problem's condensed Newton
    !> system, or MUMPS) behind a SUNLinearSolver (ida_linear_solver)
    integer, parameter, public :: jac_own = 4

    !> What the callbacks need; IDA's user data points here.
    type, public :: callback_data_t
        class(dae_problem_t), pointer :: problem => null()
        integer :: n = 0
        integer :: jac_mode = jac_quotients
        type(matrix_t) :: mass
        type(csc_matrix_t) :: jac               !! the problem's ∂F/∂y pattern and values
        type(csc_matrix_t) :: mass_csc          !! M as CSC (sparse mode)
        !> With jac_own, our solver of c_j M − ∂F/∂y, ∂F/∂y for it, and the c_j
        !> of the last Jacobian call (the one its setup factors with)
        class(linear_solver_t), allocatable :: ls
        type(matrix_t) :: jac_matrix
        real(wp) :: cj = 0.0_wp
        integer(i8) :: nnz = 0                  !! non-zeros of the iteration matrix
        integer(i8), allocatable :: colptr(:), rowind(:) !! its pattern
        integer(i8), allocatable :: jac_slot(:), mass_slot(:) !! entry -> its slot
        real(wp), allocatable :: f(:), rtol(:), atol(:)
        !> suppressed components of index k (out of the error test): weights
        !> multiplied by κ/|h|^(k-1), so that their Newton corrections count as
        !> h^(k-1) δ / κ (ida_weights)
        integer, allocatable :: newton_power(:)
        real(wp) :: kappa = 1.0_wp     !! κ for the run's smallest rtol (multiplier_kappa)
        real(wp) :: h_start = 0.0_wp   !! |h| before the first step (IDA's rule)
        type(c_ptr) :: mem = c_null_ptr
        type(c_ptr) :: observer = c_null_ptr    !! the observed Newton solver
        type(status_t) :: failure               !! first failing callback
        character(len=refusal_len) :: refusal = '' !! last failing callback (a refusal)
        character(len=:), allocatable :: message !! IDA's last error message
    end type callback_data_t

contains

    ! ---- bind(C) callbacks ----
    ! The N_Vector arguments are intent(inout) only because FN_VGetArrayPointer
    ! declares its argument so; y and y' are read, never written.

    !> `IDAResFn`: r = M y' − F(t, y). Failures and non-finite values are
    !> recoverable (1): IDA retries with a smaller step.
    integer(c_int) function ida_residual(t, nv_y, nv_yp, nv_r, user_data) result(ierr) &
        bind(C, name='flexmbs_ida_residual')
        real(c_double), value, intent(in) :: t
        type(N_Vector), target, intent(inout) :: nv_y, nv_yp
        type(N_Vector), target, intent(inout) :: nv_r
        type(c_ptr), value, intent(in) :: user_data
        type(callback_data_t), pointer :: data
        real(c_double), pointer :: y(:), yp(:), r(:)
        type(status_t) :: st
        integer :: i
        call c_f_pointer(user_data, data)
        y => FN_VGetArrayPointer(nv_y)
        yp => FN_VGetArrayPointer(nv_yp)
        r => FN_VGetArrayPointer(nv_r)
        ierr = 0
        call data%problem%rhs(t, y, data%f, st)
        if (.not. st%ok()) then
            call record(data, status_solver_failure, 'right-hand side failed at t = ' // &
                real_text(t) // ': ' // st%text(), callback_reason(st))
            ierr = 1
            return
        end if
        call data%mass%matvec(yp, r)
        r = r - data%f
        do i = 1, size(r)
            if (ieee_is_finite(r(i))) cycle
            call record(data, status_solver_failure, 'non-finite residual in component ' // &
                int_text(i) // ' at t = ' // real_text(t), reason_non_finite)
            ierr = 1
            return
        end do
    end function ida_residual

    !> As IDALsJacFn, J = c_j M − ∂F/∂y into the dense or CSC SUNMatrix.
    integer(c_int) function ida_jacobian(t, cj, nv_y, nv_yp, nv_r, a_mat, user_data, &
                                         tmp1, tmp2, tmp3) result(ierr) &
        bind(C, name='flexmbs_ida_jacobian')
        real(c_double), value, intent(in) :: t, cj
        type(N_Vector), target, intent(inout) :: nv_y, nv_yp, nv_r
        type(SUNMatrix), target, intent(inout) :: a_mat
        type(c_ptr), value, intent(in) :: user_data
        type(N_Vector), target, intent(inout) :: tmp1, tmp2, tmp3
        type(callback_data_t), pointer :: data
        real(c_double), pointer :: y(:), flat(:), jm(:, :)
        integer(c_int64_t), pointer :: colptr(:), rowind(:)
        type(status_t) :: st
        integer :: n, i, j
        integer(i8) :: p
        call c_f_pointer(user_data, data)
        n = data%n
        y => FN_VGetArrayPointer(nv_y)
        ierr = 0
        if (data%jac_mode == jac_own) then
            ! IDA's matrix is a placeholder: our solver's setup factors c_j M − J
            call data%problem%jacobian_sparse(t, y, data%jac_matrix%csc%values, st)
            if (.not. failed()) data%cj = cj
            return
        end if
        if (data%jac_mode == jac_sparse) then
            call data%problem%jacobian_sparse(t, y, data%jac%values, st)
            if (.not. failed()) then
                ! The accessors return one-element pointers: reshape to the full size.
                flat => FSUNSparseMatrix_Data(a_mat)
                call c_f_pointer(c_loc(flat(1)), flat, [data%nnz])
                colptr => FSUNSparseMatrix_IndexPointers(a_mat)
                call c_f_pointer(c_loc(colptr(1)), colptr, [n + 1])
                rowind => FSUNSparseMatrix_IndexValues(a_mat)
                call c_f_pointer(c_loc(rowind(1)), rowind, [data%nnz])
                ! IDA zeroes the whole matrix, pattern included, before each call.
                colptr(1:n + 1) = data%colptr
                rowind(1:data%nnz) = data%rowind
                flat(1:data%nnz) = 0.0_wp
                do p = 1, data%jac%nnz
                    flat(data%jac_slot(p)) = flat(data%jac_slot(p)) - data%jac%values(p)
                end do
                do p = 1, data%mass_csc%nnz
                    flat(data%mass_slot(p)) = flat(data%mass_slot(p)) &
                        + cj * data%mass_csc%values(p)
                end do
            end if
            return
        end if
        flat => FSUNDenseMatrix_Data(a_mat)
        call c_f_pointer(c_loc(flat(1)), jm, [n, n])
        if (data%jac_mode == jac_dense) then
            call data%problem%jacobian_dense(t, y, jm, st)
        else
            call data%problem%jacobian_sparse(t, y, data%jac%values, st)
            jm = 0.0_wp
            do j = 1, n
                do p = data%jac%colptr(j) + 1, data%jac%colptr(j + 1)
                    i = int(data%jac%rowind(p)) + 1
                    jm(i, j) = jm(i, j) + data%jac%values(p)
                end do
            end do
        end if
        if (failed()) return
        jm = -jm
        select case (data%mass%storage)
        case (storage_dense)
            jm = jm + cj * data%mass%dense
        case (storage_sparse)
            do j = 1, n
                do p = data%mass%csc%colptr(j) + 1, data%mass%csc%colptr(j + 1)
                    i = int(data%mass%csc%rowind(p)) + 1
                    jm(i, j) = jm(i, j) + cj * data%mass%csc%values(p)
                end do
            end do
        case default
            do j = 1, n
                jm(j, j) = jm(j, j) + cj
            end do
        end select
    contains
        !> Records a failing or non-finite Jacobian; IDA then retries (flag 1).
        logical function failed()
            logical :: finite
            failed = .true.
            ierr = 1
            if (.not. st%ok()) then
                call record(data, status_solver_failure, 'Jacobian failed at t = ' // &
                    real_text(t) // ': ' // st%text(), callback_reason(st))
                return
            end if
            if (data%jac_mode == jac_dense) then
                finite = all(ieee_is_finite(jm))
            else if (data%jac_mode == jac_own) then
                finite = all(ieee_is_finite(data%jac_matrix%csc%values))
            else
                finite = all(ieee_is_finite(data%jac%values))
            end if
            if (.not. finite) then
                call record(data, status_solver_failure, 'non-finite Jacobian at t = ' // &
                    real_text(t), reason_non_finite)
                return
            end if
            failed = .false.
            ierr = 0
        end function failed
    end function ida_jacobian

    !> IDAEwtFn for per-component rtol: w_i = 1 / (rtol_i |y_i| + atol_i).
    integer(c_int) function ida_weights(nv_y, nv_w, user_data) result(ierr) &
        bind(C, name='flexmbs_ida_weights')
        type(N_Vector), target, intent(inout) :: nv_y
        type(N_Vector), target, intent(inout) :: nv_w
        type(c_ptr), value, intent(in) :: user_data
        type(callback_data_t), pointer :: data
        real(c_double), pointer :: y(:), w(:)
        real(c_double) :: hcur(1)
        call c_f_pointer(user_data, data)
        y => FN_VGetArrayPointer(nv_y)
        w => FN_VGetArrayPointer(nv_w)
        w = data%rtol * abs(y) + data%atol
        if (.not. all(w > 0.0_wp)) then
            ierr = -1
            return
        end if
        ! multipliers out of the error test (index k = 2, 3) count as
        ! h^(k-1) δ / κ in the Newton test, as in DDASSL's newton_norm: with
        ! them out of the error test, these weights serve the Newton test alone
        if (allocated(data%newton_power) .and. c_associated(data%mem)) then
            if (any(data%newton_power > 0)) then
                if (FIDAGetCurrentStep(data%mem, hcur) /= 0) hcur = 0.0_wp
                if (hcur(1) == 0.0_wp) hcur = data%h_start
                if (hcur(1) /= 0.0_wp) where (data%newton_power > 0) &
                    w = data%kappa * w / abs(hcur(1))**data%newton_power
            end if
        end if
        w = 1.0_wp / w
        ierr = 0
    end function ida_weights

    !> As IDAErrHandlerFn, keep IDA's message for the status instead of printing it.
    subroutine ida_error_handler(error_code, module, function, msg, eh_data) &
        bind(C, name='flexmbs_ida_error_handler')
        integer(c_int), value, intent(in) :: error_code
        type(c_ptr), value, intent(in) :: module, function, msg, eh_data
        type(callback_data_t), pointer :: data
        character(kind=c_char), pointer :: chars(:)
        integer :: length, i
        if (.not. (c_associated(eh_data) .and. c_associated(msg))) return
        if (error_code > 0) return   ! warnings
        call c_f_pointer(eh_data, data)
        call c_f_pointer(msg, chars, [max_message])
        length = 0
        do while (length < max_message)
            if (chars(length + 1) == c_null_char) exit
            length = length + 1
        end do
        if (allocated(data%message)) deallocate (data%message)
        allocate (character(len=length) :: data%message)
        do i = 1, length
            data%message(i:i) = chars(i)
        end do
    end subroutine ida_error_handler

    !> Keep the first callback failure (later ones are its consequences) and
    !> the last as the refusal that makes IDA's current solve fail.
    subroutine record(data, code, message, reason)
        type(callback_data_t), intent(inout) :: data
        integer, intent(in) :: code, reason
        character(len=*), intent(in) :: message
        if (data%failure%ok()) call data%failure%set(code, message, reason)
        data%refusal = message
        call observer_refused(data%observer)
    end subroutine record

    !> The reason a failed callback is recorded with: det F <= 0 stays itself
    !> (the model refusing the trial state), anything else is the user's.
    pure integer function callback_reason(st)
        type(status_t), intent(in) :: st
        callback_reason = reason_user_function
        if (st%reason == reason_det_f) callback_reason = reason_det_f
    end function callback_reason
end module flexmbs_dae_ida_callbacks
