!> A SUNLinearSolver of ours for IDA: the iteration matrix c_j M − ∂F/∂y is
!> factored and solved by a `linear_solver_t` (the problem's condensed
!> Newton system, docs/theory.md §3.7, or MUMPS), which SUNDIALS has no
!> interface to.
!>
!> It presents itself as a direct, matrix-based solver
!> (SUNLINEARSOLVER_DIRECT), so IDA treats it as it treats its own KLU: it
!> calls the Jacobian function at every setup (ida_jacobian, which in mode
!> jac_own evaluates ∂F/∂y for our solver and keeps c_j; IDA's own matrix
!> is a 1 x 1 placeholder), then `setup`, and scales the solutions by
!> 2/(1 + c_j/c_j,setup) when c_j changed since. Its content is the
!> integration's callback data (not owned); freeing the solver frees only
!> the SUNLinearSolver itself.
module flexmbs_dae_ida_linear_solver
    use, intrinsic :: iso_c_binding, only: c_int, c_double, c_ptr, c_null_ptr, c_loc, &
        c_funloc, c_f_pointer
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use fsundials_nvector_mod, only: N_Vector, FN_VGetArrayPointer
    use fsundials_matrix_mod, only: SUNMatrix
    use fsundials_linearsolver_mod, only: SUNLinearSolver, SUNLinearSolver_Ops, &
        FSUNLinSolNewEmpty, FSUNLinSolFreeEmpty, SUNLINEARSOLVER_DIRECT
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_non_finite
    use flexmbs_dae_ida_callbacks, only: callback_data_t, record
    implicit none
    private
    public :: own_linear_solver

    ! SUNDIALS' return codes (sundials_linearsolver.h): success, an
    ! unrecoverable failure of the package, a singular matrix (recoverable:
    ! IDA retries with a smaller step)
    integer(c_int), parameter :: sunls_success = 0
    integer(c_int), parameter :: sunls_package_fail_unrec = -809
    integer(c_int), parameter :: sunls_lufact_fail = 808
    integer(c_int), parameter :: sunls_package_fail_rec = 806

contains

    !> A new SUNLinearSolver over data%ls (null when SUNDIALS' allocation fails).
    function own_linear_solver(data, ctx) result(ls)
        type(callback_data_t), target, intent(inout) :: data
        type(c_ptr), intent(in) :: ctx
        type(SUNLinearSolver), pointer :: ls
        type(SUNLinearSolver_Ops), pointer :: ops
        ls => FSUNLinSolNewEmpty(ctx)
        if (.not. associated(ls)) return
        ls%content = c_loc(data)
        call c_f_pointer(ls%ops, ops)
        ops%gettype = c_funloc(own_get_type)
        ops%setup = c_funloc(own_setup)
        ops%solve = c_funloc(own_solve)
        ops%free = c_funloc(own_free)
    end function own_linear_solver

    integer(c_int) function own_get_type(s) result(id) bind(C)
        type(SUNLinearSolver), intent(in) :: s
        id = SUNLINEARSOLVER_DIRECT
    end function own_get_type

    !> Factor c_j M − J with the J and c_j of the Jacobian call just made.
    integer(c_int) function own_setup(s, a) result(ierr) bind(C)
        type(SUNLinearSolver), intent(in) :: s
        type(SUNMatrix), intent(in) :: a
        type(callback_data_t), pointer :: data
        type(status_t) :: st
        call c_f_pointer(s%content, data)
        call data%ls%factor_real(data%cj, data%mass, data%jac_matrix, st)
        ierr = sunls_success
        if (st%ok()) return
        if (st%code == status_bad_input) then
            call record(data, st%code, 'iteration matrix: ' // st%text(), st%reason)
            ierr = sunls_package_fail_unrec
        else
            ierr = sunls_lufact_fail
        end if
    end function own_setup

    !> x = (c_j M − J)⁻¹ b with the factorisation of the last setup.
    integer(c_int) function own_solve(s, a, nv_x, nv_b, tol) result(ierr) bind(C)
        type(SUNLinearSolver), intent(in) :: s
        type(SUNMatrix), intent(in) :: a
        type(N_Vector), target, intent(inout) :: nv_x, nv_b
        real(c_double), value, intent(in) :: tol
        type(callback_data_t), pointer :: data
        real(c_double), pointer :: x(:), b(:)
        call c_f_pointer(s%content, data)
        x => FN_VGetArrayPointer(nv_x)
        b => FN_VGetArrayPointer(nv_b)
        x = b
        call data%ls%solve_real(x)
        ierr = sunls_success
        if (all(ieee_is_finite(x))) return
        call record(data, status_solver_failure, 'non-finite solution of the iteration ' // &
            'matrix at c_j = ' // real_text(data%cj), reason_non_finite)
        ierr = sunls_package_fail_rec
    end function own_solve

    !> The SUNLinearSolver alone: the callback data belongs to the integration.
    integer(c_int) function own_free(s) result(ierr) bind(C)
        type(SUNLinearSolver), target, intent(inout) :: s
        s%content = c_null_ptr
        call FSUNLinSolFreeEmpty(s)
        ierr = sunls_success
    end function own_free
end module flexmbs_dae_ida_linear_solver
