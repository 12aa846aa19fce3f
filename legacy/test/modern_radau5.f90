!> A modern caller of the classic face: callbacks are module procedures
!> checked against `flexmbs_legacy_radau5_interface`; the van der Pol
!> anchor (docs/solvers.md) must come out as from a fixed-form program.
module modern_radau5_callbacks
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: fvpol, jvpol, nomass, last_point

    real(wp), public :: max_gap = 0.0_wp !! |CONTR5(x) - y| over all steps

contains

    subroutine fvpol(n, x, y, f, rpar, ipar)
        integer, intent(in) :: n
        real(wp), intent(in) :: x
        real(wp), intent(in) :: y(n)
        real(wp), intent(out) :: f(n)
        real(wp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        f(1) = y(2)
        f(2) = ((1.0_wp - y(1)**2) * y(2) - y(1)) / rpar(1)
    end subroutine fvpol

    subroutine jvpol(n, x, y, dfy, ldfy, rpar, ipar)
        integer, intent(in) :: n
        real(wp), intent(in) :: x
        real(wp), intent(in) :: y(n)
        integer, intent(in) :: ldfy
        real(wp), intent(out) :: dfy(ldfy, n)
        real(wp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        dfy(1, 1) = 0.0_wp
        dfy(1, 2) = 1.0_wp
        dfy(2, 1) = (-2.0_wp * y(1) * y(2) - 1.0_wp) / rpar(1)
        dfy(2, 2) = (1.0_wp - y(1)**2) / rpar(1)
    end subroutine jvpol

    subroutine nomass(n, am, lmas, rpar, ipar)
        integer, intent(in) :: n
        integer, intent(in) :: lmas
        real(wp), intent(out) :: am(lmas, n)
        real(wp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        am = 0.0_wp
    end subroutine nomass

    subroutine last_point(nr, xold, x, y, cont, lrc, n, rpar, ipar, irtrn)
        use flexmbs_legacy_radau5_interface, only: contr5
        integer, intent(in) :: nr
        real(wp), intent(in) :: xold
        real(wp), intent(in) :: x
        integer, intent(in) :: n
        real(wp), intent(in) :: y(n)
        integer, intent(in) :: lrc
        real(wp), intent(in) :: cont(lrc)
        real(wp), intent(inout) :: rpar(*)
        integer, intent(inout) :: ipar(*)
        integer, intent(inout) :: irtrn
        integer :: i
        do i = 1, n
            max_gap = max(max_gap, abs(contr5(i, x, cont, lrc) - y(i)))
        end do
    end subroutine last_point
end module modern_radau5_callbacks

program modern_radau5
    use flexmbs_core_kinds, only: wp
    use flexmbs_legacy_radau5_interface, only: radau5
    use modern_radau5_callbacks, only: fvpol, jvpol, nomass, last_point, max_gap
    implicit none
    integer, parameter :: n = 2, lwork = 4 * n * n + 12 * n + 20, liwork = 3 * n + 20
    integer, parameter :: anchor(7) = [2218, 161, 275, 238, 8, 248, 660]
    real(wp) :: x, y(n), h, work(lwork), rpar(1)
    integer :: iwork(liwork), ipar(1), idid, npassed, nfailed

    npassed = 0
    nfailed = 0
    x = 0.0_wp
    y = [2.0_wp, -0.66_wp]
    h = 1.0e-6_wp
    work = 0.0_wp
    iwork = 0
    rpar(1) = 1.0e-6_wp
    ipar = 0
    call radau5(n, fvpol, x, y, 2.0_wp, h, [1.0e-4_wp], [1.0e-4_wp], 0, jvpol, 1, n, 0, &
        nomass, 0, n, 0, last_point, 1, work, lwork, iwork, liwork, rpar, ipar, idid)
    print '(a,7(1x,i0))', ' modern caller: fcn jac step accpt rejct dec sol =', iwork(14:20)
    call check(idid == 1, 'IDID = 1')
    call check(all(iwork(14:20) == anchor), 'anchor counters exact')
    call check(abs(y(1) - 1.706161101_wp) <= 2.0e-9_wp, 'y1(2)')
    call check(max_gap == 0.0_wp, 'CONTR5 at x equals y')
    print '(i0,a,i0,a)', npassed, ' passed, ', nfailed, ' failed'
    if (nfailed > 0) stop 1

contains

    subroutine check(ok, what)
        logical, intent(in) :: ok
        character(len=*), intent(in) :: what
        if (ok) then
            npassed = npassed + 1
        else
            nfailed = nfailed + 1
            print '(2a)', ' FAIL: ', what
        end if
    end subroutine check
end program modern_radau5
