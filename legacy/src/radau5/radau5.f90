!> The classic external entry points RADAU5 and CONTR5 (docs/solvers.md, RADAU5).
!>
!> Not in a module, so that programs written for the original link
!> unchanged: `gfortran -std=legacy prog.f -lflexmbs-legacy -lflexmbs ...`.
!> Both forward to `flexmbs_legacy_radau5_adapter`; modern callers get the
!> explicit interfaces from `flexmbs_legacy_radau5_interface`.

!> Integrate M y' = f(x, y) from X to XEND with Radau IIA of order 5.
subroutine radau5(n, fcn, x, y, xend, h, rtol, atol, itol, jac, ijac, mljac, mujac, &
    mas, imas, mlmas, mumas, solout, iout, work, lwork, iwork, liwork, rpar, ipar, idid)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_radau5_interface, only: radau5_fcn_i, radau5_jac_i, radau5_mas_i, &
        radau5_solout_i
    use flexmbs_legacy_radau5_adapter, only: radau5_classic
    implicit none
    include 'radau5_arguments.inc'
    call radau5_classic(n, fcn, x, y, xend, h, rtol, atol, itol, jac, ijac, mljac, mujac, &
        mas, imas, mlmas, mumas, solout, iout, work, lwork, iwork, liwork, rpar, ipar, idid)
end subroutine radau5

!> Component i at s of the dense output; valid inside SOLOUT for s in
!> [XOLD, X]. CONT and LRC are accepted as published; the state of the
!> latest SOLOUT call is what is evaluated.
function contr5(i, s, cont, lrc) result(value)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_radau5_adapter, only: contr5_value
    implicit none
    integer, intent(in) :: i            !! component
    real(wp), intent(in) :: s           !! where to evaluate
    integer, intent(in) :: lrc          !! length of cont
    real(wp), intent(in) :: cont(*)     !! SOLOUT's CONT (unused, see above)
    real(wp) :: value
    value = contr5_value(i, s)
end function contr5
