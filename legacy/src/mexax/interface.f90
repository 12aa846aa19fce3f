!> Explicit interfaces of the classic MEXAX face for modern callers.
!>
!> `use flexmbs_legacy_mexax_interface` gives `MEXAX`, its alias `MEXX`, and
!> the abstract interfaces of the user routines FPROB and SOLOUT
!> (docs/solvers.md, MEXAX). DENOUT and FSWIT are passed but never called (the
!> face rejects dense output and root finding), so they have no interface
!> here: any external subroutine will do. Fixed-form programs call the same
!> external procedures without this module.
module flexmbs_legacy_mexax_interface
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    public :: mexax_fprob_i, mexax_solout_i, mexax_i, mexax, mexx

    abstract interface
        !> `FPROB`: evaluate exactly the items whose flag is set (§3.9):
        !> QFLAG(1) AM = M; (2) GP = G (LDG = NL); (3) GP = C = g_p T (LDG = NG);
        !> (4) F = f; (5) PDOT = T(t, p) v; (6) UDOT = d; (7) G = g; (8) GI = g_I;
        !> (9) FL = ∂f/∂λ. Set IFAIL ≠ 0 to stop the run (IERR −17 / −18).
        subroutine mexax_fprob_i(np, nv, nl, ng, nu, ldg, t, p, v, u, rlam, am, gp, f, pdot, &
            udot, g, gi, fl, qflag, ifail)
            import :: wp
            integer, intent(in) :: np, nv, nl, ng, nu !! dimensions
            integer, intent(in) :: ldg                !! leading dimension of GP
            real(wp), intent(in) :: t                 !! time
            real(wp), intent(in) :: p(*), v(*), u(*)  !! positions, velocities, extra states
            real(wp), intent(in) :: rlam(*)           !! multipliers
            real(wp), intent(inout) :: am(nv, *)      !! mass matrix M (NV x NV)
            real(wp), intent(inout) :: gp(ldg, *)     !! G or C (LDG x NV)
            real(wp), intent(inout) :: f(*)           !! forces f
            real(wp), intent(inout) :: pdot(*)        !! T v
            real(wp), intent(inout) :: udot(*)        !! d
            real(wp), intent(inout) :: g(*)           !! position constraints g
            real(wp), intent(inout) :: gi(*)          !! g_I
            real(wp), intent(inout) :: fl(nv, *)      !! ∂f/∂λ (MDISC = 1 only)
            logical, intent(in) :: qflag(9)           !! which items to evaluate
            integer, intent(inout) :: ifail           !! 0 on entry; ≠ 0 stops the run
        end subroutine mexax_fprob_i

        !> `SOLOUT`: called at T0 and after every accepted step when MXJOB(30) = 1.
        !> INFO(1) is the number of the output (1 at T0); set IRTRN < 0 to stop
        !> the integration (IERR 1).
        subroutine mexax_solout_i(np, nv, nu, nl, t, p, v, u, a, rlam, info, irtrn)
            import :: wp
            integer, intent(in) :: np, nv, nu, nl
            real(wp), intent(in) :: t                    !! time reached
            real(wp), intent(in) :: p(np), v(nv), u(*)   !! state at t
            real(wp), intent(in) :: a(nv), rlam(*)       !! accelerations and multipliers
            integer, intent(inout) :: info(50)           !! INFO(1): output number
            integer, intent(inout) :: irtrn              !! < 0: stop
        end subroutine mexax_solout_i
    end interface

    abstract interface
        !> The classic MEXAX calling sequence (docs/solvers.md, MEXAX).
        subroutine mexax_i(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
            atol, h, mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
            import :: wp, mexax_fprob_i, mexax_solout_i
            include 'mexax_arguments.inc'
        end subroutine mexax_i
    end interface

    !> MEXAX and MEXX, the original's two names of one routine.
    procedure(mexax_i) :: mexax, mexx
end module flexmbs_legacy_mexax_interface
