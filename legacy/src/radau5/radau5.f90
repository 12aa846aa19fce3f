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
    integer, intent(in) :: n                    !! dimension
    procedure(radau5_fcn_i) :: fcn              !! right-hand side
    real(wp), intent(inout) :: x                !! in: x0; out: last point reached
    real(wp), intent(inout) :: y(n)             !! in: y0; out: solution at x
    real(wp), intent(in) :: xend                !! end point (may lie below x)
    real(wp), intent(inout) :: h                !! in: initial guess; out: predicted step
    real(wp), intent(in) :: rtol(*), atol(*)    !! scalars (itol = 0) or vectors
    integer, intent(in) :: itol                 !! 0: scalar, 1: vector tolerances
    procedure(radau5_jac_i) :: jac              !! Jacobian (ijac = 1)
    integer, intent(in) :: ijac                 !! 0: differences, 1: jac
    integer, intent(in) :: mljac, mujac         !! Jacobian bandwidths (mljac = n: full)
    procedure(radau5_mas_i) :: mas              !! mass matrix (imas = 1)
    integer, intent(in) :: imas                 !! 0: M = I, 1: mas
    integer, intent(in) :: mlmas, mumas         !! mass bandwidths (mlmas = n: full)
    procedure(radau5_solout_i) :: solout        !! output routine (iout = 1)
    integer, intent(in) :: iout                 !! 0: no output, 1: solout after each step
    integer, intent(in) :: lwork, liwork        !! lengths of work and iwork
    real(wp), intent(inout) :: work(*)          !! options in 1..9
    integer, intent(inout) :: iwork(*)          !! options in 1..10, statistics in 14..20
    real(wp), intent(inout), target :: rpar(*)  !! user data, passed to the callbacks
    integer, intent(inout), target :: ipar(*)   !! user data, passed to the callbacks
    integer, intent(out) :: idid                !! 1, 2 success; -1..-4 failure
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
