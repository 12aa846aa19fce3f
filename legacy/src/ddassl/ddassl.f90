!> The classic external entry point DDASSL (docs/solvers.md, DDASSL).
!>
!> Not in a module, so that programs written for the original link
!> unchanged: `gfortran -std=legacy prog.f -lflexmbs-legacy -lflexmbs ...`.
!> It forwards to `flexmbs_legacy_ddassl_adapter`; modern callers get the
!> explicit interface from `flexmbs_legacy_ddassl_interface`.

!> Integrate G(t, y, y') = 0 from T towards TOUT with variable-order BDF.
subroutine ddassl(res, neq, t, y, yprime, tout, info, rtol, atol, idid, rwork, lrw, &
    iwork, liw, rpar, ipar, jac)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_ddassl_interface, only: ddassl_res_i, ddassl_jac_i
    use flexmbs_legacy_ddassl_adapter, only: ddassl_classic
    implicit none
    procedure(ddassl_res_i) :: res              !! residual G(t, y, y')
    integer, intent(in) :: neq                  !! number of equations
    real(wp), intent(inout) :: t                !! in: t (first call); out: time reached
    real(wp), intent(inout) :: y(*), yprime(*)  !! in: (y, y') at t; out: at the new t
    real(wp), intent(in) :: tout                !! next output time
    integer, intent(inout) :: info(15)          !! switches; INFO(1) set to -1 on failure
    real(wp), intent(inout) :: rtol(*), atol(*) !! scalars or vectors (INFO(2)); scaled on -2
    integer, intent(out) :: idid                !! 1, 2, 3 success; negative failure
    integer, intent(in) :: lrw, liw             !! lengths of rwork and iwork
    real(wp), intent(inout) :: rwork(lrw)       !! options in 1..3, state and statistics
    integer, intent(inout) :: iwork(liw)        !! options in 1..3, statistics in 7..15
    real(wp), intent(inout), target :: rpar(*)  !! user data, passed to res and jac
    integer, intent(inout), target :: ipar(*)   !! user data, passed to res and jac
    procedure(ddassl_jac_i) :: jac              !! iteration matrix (INFO(5) = 1)
    call ddassl_classic(res, neq, t, y, yprime, tout, info, rtol, atol, idid, rwork, lrw, &
        iwork, liw, rpar, ipar, jac)
end subroutine ddassl
