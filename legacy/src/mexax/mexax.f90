!> The classic external entry points MEXAX and MEXX (docs/solvers.md, MEXAX).
!>
!> Not in a module, so that programs written for the original link
!> unchanged: `gfortran -std=legacy prog.f -lflexmbs-legacy -lflexmbs ...`.
!> Both forward to `flexmbs_legacy_mexax_adapter`; modern callers get the
!> explicit interfaces from `flexmbs_legacy_mexax_interface`.

!> Integrate the constrained mechanical system of FPROB from T to TFIN.
subroutine mexax(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, atol, h, &
    mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_mexax_interface, only: mexax_fprob_i, mexax_solout_i
    use flexmbs_legacy_mexax_adapter, only: mexax_classic
    implicit none
    integer, intent(in) :: np, nv, nl, ng, nu   !! positions, velocities, multipliers, g, u
    procedure(mexax_fprob_i) :: fprob           !! the model (§3.9 flags)
    real(wp), intent(inout) :: t                !! in: t0; out: time reached
    real(wp), intent(in) :: tfin                !! end point, > t
    real(wp), intent(inout) :: p(*), v(*), u(*) !! state at t
    real(wp), intent(inout) :: a(*), rlam(*)    !! accelerations, multipliers at t
    integer, intent(in) :: itol                 !! 0: scalar, else vector tolerances
    real(wp), intent(in) :: rtol(*), atol(*)    !! on (p, v, u)
    real(wp), intent(inout) :: h                !! in: initial step (0: auto); out: next
    integer, intent(inout) :: mxjob(*)          !! options 1..40, statistics 41..74
    integer, intent(out) :: ierr                !! 0 success, 1 SOLOUT stop, < 0 failure
    integer, intent(in) :: liwk, lrwk           !! workspace lengths (checked, §3.9)
    integer, intent(inout) :: iwk(liwk)         !! integer workspace
    real(wp), intent(inout) :: rwk(lrwk)        !! real workspace
    procedure(mexax_solout_i) :: solout         !! called when MXJOB(30) = 1
    external :: denout, fswit                   !! never called (MDOUT = MSWIT = 0)
    call mexax_classic(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
        atol, h, mxjob, ierr, liwk, lrwk, solout)
end subroutine mexax

!> MEXX, the original's name of the same routine.
subroutine mexx(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, atol, h, &
    mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_mexax_interface, only: mexax_fprob_i, mexax_solout_i
    use flexmbs_legacy_mexax_adapter, only: mexax_classic
    implicit none
    integer, intent(in) :: np, nv, nl, ng, nu
    procedure(mexax_fprob_i) :: fprob
    real(wp), intent(inout) :: t
    real(wp), intent(in) :: tfin
    real(wp), intent(inout) :: p(*), v(*), u(*)
    real(wp), intent(inout) :: a(*), rlam(*)
    integer, intent(in) :: itol
    real(wp), intent(in) :: rtol(*), atol(*)
    real(wp), intent(inout) :: h
    integer, intent(inout) :: mxjob(*)
    integer, intent(out) :: ierr
    integer, intent(in) :: liwk, lrwk
    integer, intent(inout) :: iwk(liwk)
    real(wp), intent(inout) :: rwk(lrwk)
    procedure(mexax_solout_i) :: solout
    external :: denout, fswit
    call mexax_classic(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
        atol, h, mxjob, ierr, liwk, lrwk, solout)
end subroutine mexx
