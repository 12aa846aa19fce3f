!> Explicit interfaces of the classic DDASSL face for modern callers.
!>
!> `use flexmbs_legacy_ddassl_interface` gives `DDASSL` and the abstract
!> interfaces of the user routines RES and JAC (docs/solvers.md, DDASSL). As in
!> the original, RES and JAC do not receive NEQ: their arrays are
!> assumed-size. Fixed-form programs call the same external procedure
!> without this module.
module flexmbs_legacy_ddassl_interface
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    public :: ddassl_res_i, ddassl_jac_i, ddassl

    abstract interface
        !> `RES`: delta = G(t, y, y'). Set ires = -1 for an illegal y (the step
        !> is retried smaller), ires = -2 to stop the integration (IDID -11).
        subroutine ddassl_res_i(t, y, yprime, delta, ires, rpar, ipar)
            import :: wp
            real(wp), intent(in) :: t            !! time
            real(wp), intent(in) :: y(*)         !! state
            real(wp), intent(in) :: yprime(*)    !! its derivative
            real(wp), intent(out) :: delta(*)    !! residual G(t, y, y')
            integer, intent(inout) :: ires       !! 0 on entry; -1 or -2, see above
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
        end subroutine ddassl_res_i

        !> `JAC`: pd = ∂G/∂y + cj ∂G/∂y', zeroed before the call; full
        !> pd(i, j) with leading dimension NEQ, or banded pd(i - j + ML + MU + 1, j)
        !> with leading dimension 2 ML + MU + 1.
        subroutine ddassl_jac_i(t, y, yprime, pd, cj, rpar, ipar)
            import :: wp
            real(wp), intent(in) :: t            !! time
            real(wp), intent(in) :: y(*)         !! state
            real(wp), intent(in) :: yprime(*)    !! its derivative
            real(wp), intent(inout) :: pd(*)     !! iteration matrix, classic storage
            real(wp), intent(in) :: cj           !! the BDF coefficient
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
        end subroutine ddassl_jac_i
    end interface

    interface
        !> The classic DDASSL calling sequence (docs/solvers.md, DDASSL).
        subroutine ddassl(res, neq, t, y, yprime, tout, info, rtol, atol, idid, rwork, lrw, &
            iwork, liw, rpar, ipar, jac)
            import :: wp, ddassl_res_i, ddassl_jac_i
            include 'ddassl_arguments.inc'
        end subroutine ddassl
    end interface
end module flexmbs_legacy_ddassl_interface
