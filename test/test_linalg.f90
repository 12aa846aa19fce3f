!> Linear algebra: CSC assembly, dense real and complex LU.
module test_linalg
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_identity, storage_sparse
    use flexmbs_linalg_dense, only: dense_solver_t
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_linalg

contains

    function collect_linalg() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('csc_duplicates_summed', test_csc_duplicates), &
                 new_test('dense_real_complex_shift', test_dense_shift)]
    end function collect_linalg

    subroutine test_csc_duplicates(error)
        type(error_t), allocatable, intent(out) :: error
        type(csc_matrix_t) :: a
        type(status_t) :: status
        real(wp) :: d(3, 3), x(3), y(3)
        ! (2,1) appears twice; unsorted input
        call a%build(3, 3, [3, 2, 1, 2, 3], [3, 1, 1, 1, 2], status)
        call check(error, status%ok(), 'build failed')
        call check(error, a%nnz == 4_i8, 'duplicates not merged')
        call a%fill([5.0_wp, 1.0_wp, 2.0_wp, 10.0_wp, 7.0_wp])
        call a%to_dense(d)
        call check_close(error, d(2, 1), 11.0_wp, 0.0_wp, 'duplicate sum')
        call check_close(error, d(1, 1), 2.0_wp, 0.0_wp, 'a11')
        call check_close(error, d(3, 3), 5.0_wp, 0.0_wp, 'a33')
        call check_close(error, d(3, 2), 7.0_wp, 0.0_wp, 'a32')
        call check(error, a%find(2, 1) > 0 .and. a%find(1, 2) == 0, 'find')
        x = [1.0_wp, 2.0_wp, 3.0_wp]
        call a%matvec(x, y)
        call check(error, all(abs(y - matmul(d, x)) <= 1e-14_wp), 'matvec')
    end subroutine test_csc_duplicates

    subroutine test_dense_shift(error)
        type(error_t), allocatable, intent(out) :: error
        type(dense_solver_t) :: solver
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        real(wp) :: x(3), b(3), a(3, 3)
        complex(wp) :: zc, zx(3), zb(3), za(3, 3)
        integer :: i
        jac%storage = storage_dense
        jac%n = 3
        jac%dense = reshape([4.0_wp, -1.0_wp, 0.5_wp, 2.0_wp, 3.0_wp, -1.0_wp, &
                             0.0_wp, 1.0_wp, -2.0_wp], [3, 3])
        mass%storage = storage_identity
        mass%n = 3
        call solver%init(mass, jac, status)
        call solver%factor_real(2.5_wp, mass, jac, status)
        call check(error, status%ok(), 'factor real')
        x = [1.0_wp, -2.0_wp, 3.0_wp]
        a = -jac%dense
        do i = 1, 3
            a(i, i) = a(i, i) + 2.5_wp
        end do
        b = matmul(a, x)
        call solver%solve_real(b)
        call check(error, maxval(abs(b - x)) < 1e-13_wp, 'real solve')
        zc = cmplx(1.5_wp, -0.7_wp, wp)
        call solver%factor_complex(zc, mass, jac, status)
        call check(error, status%ok(), 'factor complex')
        za = -jac%dense
        do i = 1, 3
            za(i, i) = za(i, i) + zc
        end do
        zx = [cmplx(1, 2, wp), cmplx(-1, 0.5_wp, wp), cmplx(0, -3, wp)]
        zb = matmul(za, zx)
        call solver%solve_complex(zb)
        call check(error, maxval(abs(zb - zx)) < 1e-13_wp, 'complex solve')
        ! Both factorisations stay alive: the real one after the complex one.
        b = matmul(a, x)
        call solver%solve_real(b)
        call check(error, maxval(abs(b - x)) < 1e-13_wp, 'real solve after complex factor')
    end subroutine test_dense_shift
end module test_linalg
