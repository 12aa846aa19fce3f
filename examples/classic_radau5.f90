!> A classic RADAU5 driver: the stiff van der Pol oscillator through the
!> published argument list (FCN, JAC, MAS, SOLOUT, WORK/IWORK, IDID), its
!> dense output by CONTR5 at x = 0.2, 0.4, ..., 2, against the reference
!> value of the Test Set for IVP Solvers (Mazzia & Magherini, problem VDPOL).
!>
!> The oscillator in its singularly perturbed form, the mass matrix given
!> by MAS (IMAS = 1), so that ε leaves the right-hand side:
!>   y1' = y2,   ε y2' = (1 - y1²) y2 - y1,   ε = 1e-6,  y(0) = (2, 0).
!> RPAR carries ε and the next output point (no COMMON blocks).
!>
!>   gfortran classic_radau5.f90 $(pkg-config --cflags --libs flexmbs-legacy)
!>
!> The interface module checks the call and the callbacks' characteristics;
!> a fixed-form program calls the same external RADAU5 and CONTR5 without
!> it. Exits non-zero when IDID or the value at x = 2 is off.

!> The user routines, with the characteristics of radau5_fcn_i, ...
module classic_radau5_callbacks
    use, intrinsic :: iso_fortran_env, only: dp => real64
    implicit none
    private
    public :: fvpol, jvpol, mvpol, solout

    !> RPAR(1) = ε, RPAR(2) = the next output point; IPAR(1) counts outputs.
    integer, parameter, public :: eps_slot = 1, xout_slot = 2, count_slot = 1
    real(dp), parameter, public :: dx_out = 0.2_dp

contains

    !> f(x, y) of M y' = f(x, y).
    subroutine fvpol(n, x, y, f, rpar, ipar)
        integer, intent(in) :: n
        real(dp), intent(in) :: x
        real(dp), intent(in) :: y(n)
        real(dp), intent(out) :: f(n)
        real(dp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        f(1) = y(2)
        f(2) = (1.0_dp - y(1)**2) * y(2) - y(1)
    end subroutine fvpol

    !> ∂f/∂y, full storage (IJAC = 1, MLJAC = N).
    subroutine jvpol(n, x, y, dfy, ldfy, rpar, ipar)
        integer, intent(in) :: n
        real(dp), intent(in) :: x
        real(dp), intent(in) :: y(n)
        integer, intent(in) :: ldfy
        real(dp), intent(out) :: dfy(ldfy, n)
        real(dp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        dfy(1, 1) = 0.0_dp
        dfy(1, 2) = 1.0_dp
        dfy(2, 1) = -2.0_dp * y(1) * y(2) - 1.0_dp
        dfy(2, 2) = 1.0_dp - y(1)**2
    end subroutine jvpol

    !> M = diag(1, ε), full storage (IMAS = 1, MLMAS = N).
    subroutine mvpol(n, am, lmas, rpar, ipar)
        integer, intent(in) :: n
        integer, intent(in) :: lmas
        real(dp), intent(out) :: am(lmas, n)
        real(dp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        am = 0.0_dp
        am(1, 1) = 1.0_dp
        am(2, 2) = rpar(eps_slot)
    end subroutine mvpol

    !> Print y at the output points the step [xold, x] passed (CONTR5).
    subroutine solout(nr, xold, x, y, cont, lrc, n, rpar, ipar, irtrn)
        use flexmbs_legacy_radau5_interface, only: contr5
        integer, intent(in) :: nr
        real(dp), intent(in) :: xold
        real(dp), intent(in) :: x
        integer, intent(in) :: n
        real(dp), intent(in) :: y(n)
        integer, intent(in) :: lrc
        real(dp), intent(in) :: cont(lrc)
        real(dp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        integer, intent(inout) :: irtrn
        if (nr == 1) then
            write (*, '(a,f4.1,a,2f14.10)') 'x = ', x, '  y =', y
            rpar(xout_slot) = x + dx_out
            return
        end if
        ! a half-step margin: the last point is x = 2 itself, not 2 - 1 ulp
        do while (rpar(xout_slot) <= x + 1.0e-9_dp)
            write (*, '(a,f4.1,a,2f14.10)') 'x = ', rpar(xout_slot), '  y =', &
                contr5(1, rpar(xout_slot), cont, lrc), contr5(2, rpar(xout_slot), cont, lrc)
            ipar(count_slot) = ipar(count_slot) + 1
            rpar(xout_slot) = rpar(xout_slot) + dx_out
        end do
    end subroutine solout
end module classic_radau5_callbacks

program classic_radau5
    use, intrinsic :: iso_fortran_env, only: dp => real64
    use flexmbs_legacy_radau5_interface, only: radau5
    use classic_radau5_callbacks, only: fvpol, jvpol, mvpol, solout, eps_slot, count_slot
    implicit none
    integer, parameter :: n = 2
    ! WORK and IWORK as RADAU5's documentation sizes them: N (LJAC + LMAS
    ! + 3 LE + 12) + 20 with LJAC = LMAS = LE = N (full matrices), 3 N + 20
    integer, parameter :: lwork = n * (5 * n + 12) + 20, liwork = 3 * n + 20
    ! VDPOL's reference solution at x = 2 (Test Set for IVP Solvers)
    real(dp), parameter :: y_ref(n) = [1.706167732170483_dp, -0.8928097010248125_dp]
    real(dp), parameter :: tol = 1.0e-6_dp
    real(dp) :: x, xend, y(n), h, rtol(1), atol(1), work(lwork), rpar(2), error
    integer :: iwork(liwork), ipar(1), idid

    x = 0.0_dp
    xend = 2.0_dp
    y = [2.0_dp, 0.0_dp]
    h = 1.0e-6_dp          ! initial step guess
    rtol = tol
    atol = tol
    work = 0.0_dp          ! zeros: every option at its default
    iwork = 0
    rpar(eps_slot) = 1.0e-6_dp
    ipar(count_slot) = 0
    ! ITOL = 0 (scalar tolerances), IJAC = 1, MLJAC = N (full), IMAS = 1,
    ! MLMAS = N (full), IOUT = 1 (SOLOUT after every step, CONTR5 usable)
    call radau5(n, fvpol, x, y, xend, h, rtol, atol, 0, jvpol, 1, n, 0, &
                mvpol, 1, n, 0, solout, 1, work, lwork, iwork, liwork, rpar, ipar, idid)

    error = maxval(abs(y - y_ref) / abs(y_ref))
    write (*, '(a,i0,a,es9.2,a,es9.2)') 'IDID = ', idid, ', relative error at x = 2: ', &
        error, ' for RTOL = ATOL = ', tol
    write (*, '(a,7(1x,i0))') 'fcn jac step accpt rejct dec sol:', iwork(14:20)
    if (idid /= 1) error stop 'RADAU5 failed'
    if (ipar(count_slot) /= 10) error stop 'SOLOUT did not reach every output point'
    if (error > 10.0_dp * tol) error stop 'y(2) differs from the reference'
end program classic_radau5
