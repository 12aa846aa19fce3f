!> The paper's error measure, eq. (13):
!>   ERR = rtol · sqrt( (1/n) Σ_j ((x_j − x_ref,j) / (rtol·|x_ref,j| + atol))² ).
!> "Within k× tolerance" means ERR ≤ k·rtol.
module flexmbs_dae_error_measure
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: paper_error

contains

    !> ERR of eq. (13) over the components of x (or those flagged in mask).
    pure real(wp) function paper_error(x, x_ref, rtol, atol, mask) result(err)
        real(wp), intent(in) :: x(:), x_ref(:)
        real(wp), intent(in) :: rtol, atol
        logical, intent(in), optional :: mask(:)
        real(wp) :: s
        integer :: j, n
        s = 0.0_wp
        n = 0
        do j = 1, size(x)
            if (present(mask)) then
                if (.not. mask(j)) cycle
            end if
            s = s + ((x(j) - x_ref(j)) / (rtol * abs(x_ref(j)) + atol))**2
            n = n + 1
        end do
        err = rtol * sqrt(s / real(max(n, 1), wp))
    end function paper_error
end module flexmbs_dae_error_measure
