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
    include 'ddassl_arguments.inc'
    call ddassl_classic(res, neq, t, y, yprime, tout, info, rtol, atol, idid, rwork, lrw, &
        iwork, liw, rpar, ipar, jac)
end subroutine ddassl
