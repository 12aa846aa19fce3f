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
    include 'mexax_arguments.inc'
    call mexax_classic(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
        atol, h, mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
end subroutine mexax

!> MEXX, the original's name of the same routine.
subroutine mexx(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, atol, h, &
    mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_mexax_interface, only: mexax_fprob_i, mexax_solout_i
    use flexmbs_legacy_mexax_adapter, only: mexax_classic
    implicit none
    include 'mexax_arguments.inc'
    call mexax_classic(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
        atol, h, mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
end subroutine mexx
