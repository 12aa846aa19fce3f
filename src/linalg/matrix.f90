!> A matrix held as identity, dense array or CSC values on a fixed pattern.
!>
!> Problems report their Jacobian and mass matrix in this form; linear
!> solvers read it to build iteration matrices c*M - J.
module flexmbs_linalg_matrix
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    integer, parameter, public :: storage_none = -1     !! not provided (e.g. difference Jacobian)
    integer, parameter, public :: storage_identity = 0
    integer, parameter, public :: storage_dense = 1
    integer, parameter, public :: storage_sparse = 2

    !> Square matrix of order n in one of the storages.
    type, public :: matrix_t
        integer :: storage = storage_identity
        integer :: n = 0
        real(wp), allocatable :: dense(:, :)
        type(csc_matrix_t) :: csc
    contains
        procedure :: matvec => matrix_matvec
        procedure :: to_dense => matrix_to_dense
    end type matrix_t

contains

    !> y = A x.
    pure subroutine matrix_matvec(self, x, y)
        class(matrix_t), intent(in) :: self
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: y(:)
        select case (self%storage)
        case (storage_dense)
            y = matmul(self%dense, x)
        case (storage_sparse)
            call self%csc%matvec(x, y)
        case default
            y = x
        end select
    end subroutine matrix_matvec

    !> Dense copy (n x n).
    pure subroutine matrix_to_dense(self, a)
        class(matrix_t), intent(in) :: self
        real(wp), intent(out) :: a(:, :)
        integer :: i
        select case (self%storage)
        case (storage_dense)
            a = self%dense
        case (storage_sparse)
            call self%csc%to_dense(a)
        case default
            a = 0.0_wp
            do i = 1, self%n
                a(i, i) = 1.0_wp
            end do
        end select
    end subroutine matrix_to_dense
end module flexmbs_linalg_matrix
