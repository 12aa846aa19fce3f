!> Linear algebra: CSC assembly, dense real and complex LU.
module test_linalg
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_identity, storage_sparse
    use flexmbs_linalg_dense, only: dense_solver_t, classic_lu_factor, classic_lu_solve
    use flexmbs_linalg_block_assembly, only: block_assembly_t, product_pattern, product_values, &
        transpose_pattern
    use flexmbs_linalg_accumulator, only: accumulator_t
    use flexmbs_core_threads, only: default_blas_threads, blas_threads
    use flexmbs_linalg_saddle_point, only: saddle_point_t
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_linalg

contains

    function collect_linalg() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('csc_duplicates_summed', test_csc_duplicates), &
                 new_test('csc_many_duplicates_rectangular', test_csc_many), &
                 new_test('dense_real_complex_shift', test_dense_shift), &
                 new_test('classic_lu', test_classic_lu), &
                 new_test('block_assembly', test_block_assembly), &
                 new_test('accumulator_dense_sparse', test_accumulator), &
                 new_test('blas_threads_default', test_blas_threads), &
                 new_test('saddle_point', test_saddle_point)]
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

    !> 4000 triplets in random order on 7 x 5 and 5 x 7 matrices, most of them
    !> duplicates: rows strictly ascending in every column, each triplet mapped
    !> to its slot, and the values equal to the dense sum of the triplets.
    subroutine test_csc_many(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: nt = 4000
        integer :: rows(nt), cols(nt), k, j, shape(2, 2), m
        integer(i8) :: p
        integer(i8) :: seed
        real(wp) :: v(nt)
        real(wp), allocatable :: d(:, :), ref(:, :)
        type(csc_matrix_t) :: a
        type(status_t) :: status
        logical :: sorted
        shape = reshape([7, 5, 5, 7], [2, 2])
        do m = 1, 2
            seed = 12345
            do k = 1, nt
                seed = mod(1103515245_i8 * seed + 12345_i8, 2147483648_i8)
                rows(k) = 1 + int(mod(seed, int(shape(1, m), i8)))
                seed = mod(1103515245_i8 * seed + 12345_i8, 2147483648_i8)
                cols(k) = 1 + int(mod(seed / 7, int(shape(2, m), i8)))
                v(k) = real(k, wp)
            end do
            call a%build(shape(1, m), shape(2, m), rows, cols, status)
            call check(error, status%ok(), 'build: ' // status%text())
            if (allocated(error)) return
            sorted = .true.
            do j = 1, shape(2, m)
                do p = a%colptr(j) + 2, a%colptr(j + 1)
                    sorted = sorted .and. a%rowind(p) > a%rowind(p - 1)
                end do
            end do
            call check(error, sorted, 'rows strictly ascending in each column')
            call a%fill(v)
            allocate (d(shape(1, m), shape(2, m)), ref(shape(1, m), shape(2, m)))
            call a%to_dense(d)
            ref = 0.0_wp
            do k = 1, nt
                ref(rows(k), cols(k)) = ref(rows(k), cols(k)) + v(k)
            end do
            call check(error, all(d == ref), 'values are the sums of the triplets')
            call check(error, a%nnz == count(ref /= 0.0_wp), 'one slot per position')
            deallocate (d, ref)
        end do
    end subroutine test_csc_many

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

    !> The classic-order LU: pivoting, a zero pivot named, an exact
    !> integer case, agreement with LAPACK on a dense 40 x 40, and the
    !> same numbers through dense_solver_t%classic_order.
    subroutine test_classic_lu(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: n = 40
        real(wp) :: a(n, n), f(n, n), x(n), b(n), bl(n), a2(2, 2), b2(2), a3(3, 3), b3(3)
        integer :: ipiv(n), ipiv2(2), ipiv3(3), info, i, j
        type(dense_solver_t) :: solver
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        ! A zero leading pivot needs the row swap.
        a2 = reshape([0.0_wp, 1.0_wp, 2.0_wp, 3.0_wp], [2, 2])
        call classic_lu_factor(a2, ipiv2, info)
        call check(error, info == 0 .and. ipiv2(1) == 2, 'pivot row 2 chosen')
        if (allocated(error)) return
        b2 = [4.0_wp, 5.0_wp]          ! 2 x2 = 4, x1 + 3 x2 = 5
        call classic_lu_solve(a2, ipiv2, b2)
        call check(error, all(b2 == [-1.0_wp, 2.0_wp]), 'swapped 2 x 2 solved exactly')
        if (allocated(error)) return
        ! Rank one: the second pivot vanishes and is named.
        a2 = reshape([1.0_wp, 2.0_wp, 2.0_wp, 4.0_wp], [2, 2])
        call classic_lu_factor(a2, ipiv2, info)
        call check(error, info == 2, 'singular matrix: info names pivot 2')
        if (allocated(error)) return
        ! Powers of two throughout: every operation is exact.
        a3 = reshape([2.0_wp, 4.0_wp, -2.0_wp, 1.0_wp, 4.0_wp, 1.0_wp, 1.0_wp, 2.0_wp, 8.0_wp], &
                     [3, 3])
        b3 = matmul(a3, [1.0_wp, -1.0_wp, 0.5_wp])
        call classic_lu_factor(a3, ipiv3, info)
        call classic_lu_solve(a3, ipiv3, b3)
        call check(error, info == 0 .and. all(b3 == [1.0_wp, -1.0_wp, 0.5_wp]), &
            'exact 3 x 3 solved exactly')
        if (allocated(error)) return
        ! A dense nonsymmetric matrix that needs pivoting in most columns.
        do j = 1, n
            do i = 1, n
                a(i, j) = sin(real(7 * i + 13 * j, wp)) + merge(0.5_wp, 0.0_wp, i == j)
            end do
            x(j) = cos(real(j, wp))
        end do
        b = matmul(a, x)
        f = a
        call classic_lu_factor(f, ipiv, info)
        call check(error, info == 0 .and. any(ipiv(1:n - 1) /= [(i, i = 1, n - 1)]), &
            'dense 40 x 40 factored, with row swaps')
        if (allocated(error)) return
        bl = b
        call classic_lu_solve(f, ipiv, bl)
        call check(error, maxval(abs(bl - x)) < 1e-11_wp, 'dense 40 x 40: x recovered')
        if (allocated(error)) return
        call check(error, maxval(abs(matmul(a, bl) - b)) < 1e-13_wp * n * maxval(abs(a)), &
            'dense 40 x 40: backward-stable residual')
        if (allocated(error)) return
        ! The solver object with classic_order gives the same numbers.
        jac%storage = storage_dense
        jac%n = n
        jac%dense = -a
        mass%storage = storage_identity
        mass%n = n
        solver%classic_order = .true.
        call solver%init(mass, jac, status)
        call solver%factor_real(0.0_wp, mass, jac, status)
        call check(error, status%ok(), 'classic_order factor')
        if (allocated(error)) return
        x = b
        call solver%solve_real(x)
        call check(error, all(x == bl), 'dense_solver_t%classic_order: the same bits')
    end subroutine test_classic_lu

    !> Blocks placed (one transposed) into a global matrix and scattered with
    !> scales equal the dense sum; a sparse product A B equals matmul.
    subroutine test_block_assembly(error)
        type(error_t), allocatable, intent(out) :: error
        type(block_assembly_t) :: asm
        type(csc_matrix_t) :: a, b, c, at
        type(status_t) :: status
        integer(i8), allocatable :: map(:)
        real(wp) :: da(3, 2), db(2, 3), g(5, 5), expect(5, 5)
        integer :: ia, ib, id
        call a%build(3, 2, [1, 3, 2, 3], [1, 1, 2, 2], status)
        a%values = [1.0_wp, 2.0_wp, 3.0_wp, 4.0_wp]
        call b%build(2, 3, [1, 2, 2], [1, 2, 3], status)
        b%values = [5.0_wp, 6.0_wp, 7.0_wp]
        call a%to_dense(da)
        call b%to_dense(db)
        call asm%add_block(a, 0, 0, ia)
        call asm%add_block(a, 3, 0, ib, transposed=.true.)
        call asm%add_diagonal(5, 0, 0, id)
        call asm%build(5, 5, status)
        call check(error, status%ok(), 'build: ' // status%text())
        if (allocated(error)) return
        call asm%zero()
        call asm%scatter(ia, a%values)
        call asm%scatter(ib, a%values, -2.0_wp)
        call asm%scatter_diagonal(id, 0.5_wp)
        expect = 0.0_wp
        expect(1:3, 1:2) = da
        expect(4:5, 1:3) = -2.0_wp * transpose(da)
        expect(1, 1) = expect(1, 1) + 0.5_wp
        expect(2, 2) = expect(2, 2) + 0.5_wp
        expect(3, 3) = expect(3, 3) + 0.5_wp
        expect(4, 4) = expect(4, 4) + 0.5_wp
        expect(5, 5) = expect(5, 5) + 0.5_wp
        call asm%matrix%to_dense(g)
        call check(error, maxval(abs(g - expect)) <= 0.0_wp, 'assembled blocks')
        call product_pattern(a, b, c, status)
        call product_values(a, b, c)
        block
            real(wp) :: dc(3, 3)
            call c%to_dense(dc)
            call check(error, all(abs(dc - matmul(da, db)) <= 1e-14_wp), 'sparse product')
        end block
        call transpose_pattern(a, at, map, status)
        at%values = a%values(map)
        block
            real(wp) :: dt(2, 3)
            call at%to_dense(dt)
            call check(error, maxval(abs(dt - transpose(da))) <= 0.0_wp, 'transpose and its map')
        end block
    end subroutine test_block_assembly

    !> The same contributions give the same matrix dense and sparse; one
    !> outside the sparse pattern is reported.
    subroutine test_accumulator(error)
        type(error_t), allocatable, intent(out) :: error
        type(accumulator_t) :: acc
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp) :: d(3, 3), s(3, 3), values(4)
        call pattern%build(3, 3, [1, 2, 3, 1], [1, 2, 3, 3], status)
        call acc%start_dense(3, 3)
        call contributions(acc)
        call acc%get_dense(d)
        call acc%start_sparse(pattern)
        call contributions(acc)
        call acc%get_values(values, 'test', status)
        call check(error, status%ok(), 'sparse: ' // status%text())
        pattern%values = values
        call pattern%to_dense(s)
        call check(error, maxval(abs(d - s)) <= 0.0_wp, 'dense and sparse agree')
        call acc%start_sparse(pattern)
        call acc%add(2, 1, 1.0_wp)
        call acc%get_values(values, 'test', status)
        call check(error, .not. status%ok(), 'a contribution outside the pattern is reported')
    contains
        subroutine contributions(a)
            type(accumulator_t), intent(inout) :: a
            call a%add(1, 1, 2.0_wp)
            call a%add(1, 1, 1.0_wp)
            call a%add(1, 3, -4.0_wp)
            call a%add_range(1, 1, reshape([5.0_wp, 0.0_wp, 0.0_wp, 6.0_wp], [2, 2]))
        end subroutine contributions
    end subroutine test_accumulator

    !> Without OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS and OMP_NUM_THREADS in
    !> the environment the solvers' set-up puts OpenBLAS on one thread; with
    !> one of them set, its count stays (docs/performance.md).
    subroutine test_blas_threads(error)
        type(error_t), allocatable, intent(out) :: error
        integer :: before, l1, l2, l3
        call get_environment_variable('OPENBLAS_NUM_THREADS', length=l1)
        call get_environment_variable('GOTO_NUM_THREADS', length=l2)
        call get_environment_variable('OMP_NUM_THREADS', length=l3)
        before = blas_threads()
        call default_blas_threads()
        if (before == 0) return ! not OpenBLAS: nothing is set
        if (l1 + l2 + l3 == 0) then
            call check(error, blas_threads() == 1, 'one BLAS thread by default')
        else
            call check(error, blas_threads() == before, 'the environment''s count stays')
        end if
    end subroutine test_blas_threads

    !> [M Bᵀ; A 0] x = b by the sparse saddle-point module against the
    !> dense matrix: M tridiagonal (4 x 4), A and B two constraint rows on
    !> one pattern with different values; refactoring with new values.
    subroutine test_saddle_point(error)
        type(error_t), allocatable, intent(out) :: error
        type(saddle_point_t) :: kkt
        type(csc_matrix_t) :: m, a
        type(status_t) :: status
        real(wp) :: k(6, 6), dm(4, 4), da(2, 4), db(2, 4), x(6), b(6), av(5), bv(5)
        integer :: pass
        call m%build(4, 4, [1, 2, 1, 2, 3, 2, 3, 4, 3, 4], [1, 1, 2, 2, 2, 3, 3, 3, 4, 4], status)
        m%values = [4.0_wp, -1.0_wp, -1.0_wp, 4.0_wp, -1.0_wp, -1.0_wp, 4.0_wp, -1.0_wp, &
                    -1.0_wp, 4.0_wp]
        call a%build(2, 4, [1, 1, 2, 2, 1], [1, 2, 3, 4, 4], status)
        call kkt%init(m, a, status)
        call check(error, status%ok(), 'init: ' // status%text())
        if (allocated(error)) return
        do pass = 1, 2
            av = [1.0_wp, 2.0_wp, -1.0_wp, 0.5_wp, 3.0_wp] * pass
            bv = av + [0.1_wp, -0.2_wp, 0.3_wp, 0.0_wp, 0.1_wp]
            a%values = av
            call a%to_dense(da)
            a%values = bv
            call a%to_dense(db)
            call m%to_dense(dm)
            k = 0.0_wp
            k(1:4, 1:4) = dm
            k(1:4, 5:6) = transpose(db)
            k(5:6, 1:4) = da
            x = [1.0_wp, -2.0_wp, 0.5_wp, 3.0_wp, -1.0_wp, 2.0_wp]
            b = matmul(k, x)
            call kkt%assemble(m%values, av, bv)
            call kkt%factor(status)
            call kkt%solve(b, status)
            call check(error, status%ok() .and. maxval(abs(b - x)) <= 1.0e-13_wp, &
                       'sparse saddle-point solve, pass ' // char(48 + pass))
        end do
    end subroutine test_saddle_point
end module test_linalg
