!> Explicit interfaces of the classic RADAU5 face for modern callers.
!>
!> `use flexmbs_legacy_radau5_interface` gives `RADAU5`, `CONTR5` and the
!> abstract interfaces of the user routines FCN, JAC, MAS and SOLOUT
!> (docs/solvers.md, RADAU5). A modern caller writes its callbacks with exactly
!> these characteristics (the intents included) and gets its call checked;
!> fixed-form programs call the same external procedures without it.
module flexmbs_legacy_radau5_interface
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    public :: radau5_fcn_i, radau5_jac_i, radau5_mas_i, radau5_solout_i
    public :: radau5, contr5

    abstract interface
        !> `FCN`: the right-hand side f(x, y) of M y' = f(x, y).
        subroutine radau5_fcn_i(n, x, y, f, rpar, ipar)
            import :: wp
            integer, intent(in) :: n             !! dimension
            real(wp), intent(in) :: x            !! independent variable
            real(wp), intent(in) :: y(n)         !! state
            real(wp), intent(out) :: f(n)        !! f(x, y)
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
        end subroutine radau5_fcn_i

        !> `JAC`: dfy(i, j) = ∂f_i/∂y_j (full), or dfy(i - j + mujac + 1, j)
        !> (banded); with M1 > 0 only the rows M1+1..n, as rows 1..n-M1.
        subroutine radau5_jac_i(n, x, y, dfy, ldfy, rpar, ipar)
            import :: wp
            integer, intent(in) :: n             !! dimension
            real(wp), intent(in) :: x            !! independent variable
            real(wp), intent(in) :: y(n)         !! state
            integer, intent(in) :: ldfy          !! leading dimension of dfy
            real(wp), intent(out) :: dfy(ldfy, n) !! Jacobian in classic storage
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
        end subroutine radau5_jac_i

        !> `MAS`: the constant mass matrix, full am(i, j) or banded
        !> am(i - j + mumas + 1, j); with M1 > 0 its lower-right block of
        !> order n - M1, which is then the `n` passed.
        subroutine radau5_mas_i(n, am, lmas, rpar, ipar)
            import :: wp
            integer, intent(in) :: n             !! order of the block described
            integer, intent(in) :: lmas          !! leading dimension of am
            real(wp), intent(out) :: am(lmas, n) !! mass matrix in classic storage
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
        end subroutine radau5_mas_i

        !> `SOLOUT`: called at x0 (nr = 1) and after every accepted step;
        !> CONTR5 evaluates the step's dense output on [xold, x].
        subroutine radau5_solout_i(nr, xold, x, y, cont, lrc, n, rpar, ipar, irtrn)
            import :: wp
            integer, intent(in) :: nr            !! 1 at x0, then accepted steps + 1
            real(wp), intent(in) :: xold         !! start of the step
            real(wp), intent(in) :: x            !! end of the step
            integer, intent(in) :: n             !! dimension
            real(wp), intent(in) :: y(n)         !! solution at x
            integer, intent(in) :: lrc           !! length of cont (4n)
            real(wp), intent(in) :: cont(lrc)    !! dense-output coefficients
            real(wp), intent(inout) :: rpar(*)   !! user data, passed through
            integer, intent(inout) :: ipar(*)    !! user data, passed through
            integer, intent(inout) :: irtrn      !! set < 0 to stop (IDID = 2)
        end subroutine radau5_solout_i
    end interface

    interface
        !> The classic RADAU5 calling sequence (docs/solvers.md, RADAU5).
        subroutine radau5(n, fcn, x, y, xend, h, rtol, atol, itol, jac, ijac, mljac, mujac, &
            mas, imas, mlmas, mumas, solout, iout, work, lwork, iwork, liwork, rpar, ipar, idid)
            import :: wp, radau5_fcn_i, radau5_jac_i, radau5_mas_i, radau5_solout_i
            include 'radau5_arguments.inc'
        end subroutine radau5

        !> Component i of the dense output of the latest SOLOUT call at s.
        function contr5(i, s, cont, lrc) result(value)
            import :: wp
            integer, intent(in) :: i, lrc
            real(wp), intent(in) :: s
            real(wp), intent(in) :: cont(*)
            real(wp) :: value
        end function contr5
    end interface
end module flexmbs_legacy_radau5_interface
