!> Sparse LU through KLU: agreement with dense LU, refactorisation,
!> singular matrices, a large 2-D operator, and the solver factory.
module test_klu
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_value, ieee_quiet_nan, &
        ieee_positive_inf
    use flexmbs_core_kinds, only: wp, i8, uround_wp
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, &
        status_solver_failure, reason_singular_matrix, reason_non_finite
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t, auto_sparse_threshold
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_stats_t, klu_part_real, klu_part_complex, &
        klu_refactor_degrade_ratio, klu_ordering_auto, klu_ordering_amd, klu_ordering_nd
    use flexmbs_linalg_klu_solver, only: klu_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_klu

    !> Agreement of KLU and LAPACK on well-conditioned systems: a few hundred
    !> units of round-off.
    real(wp), parameter :: agree_tol = 500 * uround_wp

    !> Park–Miller minimal standard generator (CACM 31, 1988): the same
    !> numbers with every compiler, unlike random_number.
    integer(i8), parameter :: lehmer_a = 16807_i8, lehmer_m = 2147483647_i8

contains

    function collect_klu() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('matches_dense_sparse_mass', test_sparse_mass), &
                 new_test('matches_dense_identity_mass', test_identity_mass), &
                 new_test('matches_dense_full_pattern', test_full_pattern), &
                 new_test('refactor_new_values', test_refactor_values), &
                 new_test('refactor_degraded_pivots_refactored_afresh', test_refactor_degraded), &
                 new_test('singular_matrix_status', test_singular), &
                 new_test('laplacian_2d_residual', test_laplacian), &
                 new_test('copies_are_independent', test_copies), &
                 new_test('misuse_and_bad_values_reported', test_bad_use), &
                 new_test('factory_choice_and_bad_name', test_factory), &
                 new_test('orderings_auto_amd_nd', test_orderings)]
    end function collect_klu

    ! ---------------------------------------------------------------- helpers

    real(wp) function uniform(seed)
        integer(i8), intent(inout) :: seed
        seed = mod(lehmer_a * seed, lehmer_m)
        uniform = real(seed, wp) / real(lehmer_m, wp)
    end function uniform

    !> A random sparse nonsymmetric n x n matrix: `per_col` random rows per
    !> column (duplicates merged) with values in (-1, 1), plus `diag` on the
    !> diagonal.
    subroutine random_sparse(n, per_col, diag, seed, a)
        integer, intent(in) :: n, per_col
        real(wp), intent(in) :: diag
        integer(i8), intent(inout) :: seed
        type(matrix_t), intent(out) :: a
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: vals(:)
        integer :: j, k, t
        type(status_t) :: status
        allocate (rows(n * (per_col + 1)), cols(n * (per_col + 1)), vals(n * (per_col + 1)))
        t = 0
        do j = 1, n
            t = t + 1
            rows(t) = j
            cols(t) = j
            vals(t) = diag
            do k = 1, per_col
                t = t + 1
                rows(t) = 1 + min(n - 1, int(n * uniform(seed)))
                cols(t) = j
                vals(t) = 2 * uniform(seed) - 1
            end do
        end do
        a%storage = storage_sparse
        a%n = n
        call a%csc%build(n, n, rows, cols, status)
        call a%csc%fill(vals)
    end subroutine random_sparse

    subroutine identity(n, a)
        integer, intent(in) :: n
        type(matrix_t), intent(out) :: a
        a%storage = storage_identity
        a%n = n
    end subroutine identity

    !> Relative max-norm difference of two vectors.
    pure real(wp) function rel_diff(x, y)
        real(wp), intent(in) :: x(:), y(:)
        rel_diff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function rel_diff

    pure real(wp) function zrel_diff(x, y)
        complex(wp), intent(in) :: x(:), y(:)
        zrel_diff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function zrel_diff

    !> Factor c*M - J (real and complex shifts) with KLU and dense LU, both
    !> kept alive, and compare solutions of random right-hand sides.
    subroutine compare_with_dense(error, mass, jac, c, zc, seed, label)
        type(error_t), allocatable, intent(inout) :: error
        type(matrix_t), intent(in) :: mass, jac
        real(wp), intent(in) :: c
        complex(wp), intent(in) :: zc
        integer(i8), intent(inout) :: seed
        character(len=*), intent(in) :: label
        type(klu_solver_t) :: sparse
        type(dense_solver_t) :: dense, zdense
        type(status_t) :: status
        real(wp), allocatable :: b(:), x(:)
        complex(wp), allocatable :: zb(:), zx(:)
        integer :: i, n

        n = jac%n
        allocate (b(n), x(n), zb(n), zx(n))
        call sparse%init(mass, jac, status)
        call check(error, status%ok(), label // ': klu init: ' // status%text())
        call dense%init(mass, jac, status)
        call zdense%init(mass, jac, status)
        call sparse%factor_real(c, mass, jac, status)
        call check(error, status%ok(), label // ': klu real factor: ' // status%text())
        call sparse%factor_complex(zc, mass, jac, status)
        call check(error, status%ok(), label // ': klu complex factor: ' // status%text())
        ! Separate dense solvers: dense_solver_t%factor_complex overwrites the
        ! real LU (it builds its real part in the same array).
        call dense%factor_real(c, mass, jac, status)
        call zdense%factor_complex(zc, mass, jac, status)
        if (allocated(error)) return
        ! The real factor must survive the complex one.
        do i = 1, n
            b(i) = 2 * uniform(seed) - 1
            zb(i) = cmplx(2 * uniform(seed) - 1, 2 * uniform(seed) - 1, kind=wp)
        end do
        x = b
        call sparse%solve_real(x)
        call dense%solve_real(b)
        call check_close(error, rel_diff(x, b), 0.0_wp, agree_tol, label // ': real solves')
        zx = zb
        call sparse%solve_complex(zx)
        call zdense%solve_complex(zb)
        call check_close(error, zrel_diff(zx, zb), 0.0_wp, agree_tol, &
            label // ': complex solves')
        call sparse%destroy()
    end subroutine compare_with_dense

    ! ------------------------------------------------------------------ tests

    subroutine test_sparse_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        integer(i8) :: seed
        seed = 12345
        call random_sparse(80, 4, 0.0_wp, seed, jac)
        ! A nonsymmetric sparse mass with its own pattern (not inside J's).
        call random_sparse(80, 2, 3.0_wp, seed, mass)
        call compare_with_dense(error, mass, jac, 2.0_wp, cmplx(1.5_wp, -2.5_wp, wp), seed, &
            'sparse M')
    end subroutine test_sparse_mass

    subroutine test_identity_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        integer(i8) :: seed
        seed = 777
        call random_sparse(120, 3, 0.0_wp, seed, jac)
        call identity(120, mass)
        call compare_with_dense(error, mass, jac, 3.0_wp, cmplx(2.0_wp, 4.0_wp, wp), seed, &
            'identity M')
    end subroutine test_identity_mass

    !> A dense M or J makes the union pattern full.
    subroutine test_full_pattern(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac, dense_m, dense_j
        integer(i8) :: seed
        integer, parameter :: n = 30
        seed = 4242
        call random_sparse(n, 3, 0.0_wp, seed, jac)
        call random_sparse(n, 2, 3.0_wp, seed, mass)
        dense_m%storage = storage_dense
        dense_m%n = n
        allocate (dense_m%dense(n, n))
        call mass%to_dense(dense_m%dense)
        call compare_with_dense(error, dense_m, jac, 2.0_wp, cmplx(1.0_wp, 1.0_wp, wp), seed, &
            'dense M, sparse J')
        dense_j%storage = storage_dense
        dense_j%n = n
        allocate (dense_j%dense(n, n))
        call jac%to_dense(dense_j%dense)
        call identity(n, mass)
        call compare_with_dense(error, mass, dense_j, 3.0_wp, cmplx(0.5_wp, 3.0_wp, wp), seed, &
            'identity M, dense J')
    end subroutine test_full_pattern

    !> New values on the same pattern go through KLU's refactor and still
    !> solve to round-off.
    subroutine test_refactor_values(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        type(klu_solver_t) :: sparse
        type(dense_solver_t) :: dense, zdense
        type(status_t) :: status
        type(klu_stats_t) :: stats
        real(wp) :: b(60), x(60)
        complex(wp) :: zb(60), zx(60)
        integer(i8) :: seed
        integer :: i, round
        seed = 99
        call random_sparse(60, 4, 0.0_wp, seed, jac)
        call random_sparse(60, 2, 3.0_wp, seed, mass)
        call sparse%init(mass, jac, status)
        call dense%init(mass, jac, status)
        call zdense%init(mass, jac, status)
        do round = 1, 3
            ! Perturb every value by up to 10 %, as between Newton iterations.
            do i = 1, int(jac%csc%nnz)
                jac%csc%values(i) = jac%csc%values(i) * (0.9_wp + 0.2_wp * uniform(seed))
            end do
            call sparse%factor_real(2.0_wp + round, mass, jac, status)
            call check(error, status%ok(), 'real refactor: ' // status%text())
            call sparse%factor_complex(cmplx(2.0_wp, round, wp), mass, jac, status)
            call check(error, status%ok(), 'complex refactor: ' // status%text())
            call dense%factor_real(2.0_wp + round, mass, jac, status)
            call zdense%factor_complex(cmplx(2.0_wp, round, wp), mass, jac, status)
            do i = 1, 60
                b(i) = uniform(seed)
                zb(i) = cmplx(uniform(seed), -uniform(seed), wp)
            end do
            x = b
            zx = zb
            call sparse%solve_real(x)
            call dense%solve_real(b)
            call sparse%solve_complex(zx)
            call zdense%solve_complex(zb)
            call check(error, rel_diff(x, b) <= agree_tol, 'real solve after refactor')
            call check(error, zrel_diff(zx, zb) <= agree_tol, 'complex solve after refactor')
        end do
        stats = sparse%stats(klu_part_real)
        call check(error, stats%nfactor == 1 .and. stats%nrefactor == 2, &
            'real: expected 1 fresh factorisation and 2 refactorisations')
        stats = sparse%stats(klu_part_complex)
        call check(error, stats%nfactor == 1 .and. stats%nrefactor == 2, &
            'complex: expected 1 fresh factorisation and 2 refactorisations')
        call sparse%destroy()
    end subroutine test_refactor_values

    !> A reused pivot order that meets a zero or a tiny pivot is rejected
    !> and the matrix factored afresh. 2 x 2, full pattern, column-major
    !> values [a11, a21, a12, a22].
    subroutine test_refactor_degraded(error)
        type(error_t), allocatable, intent(out) :: error
        type(klu_factor_t) :: lu
        type(status_t) :: status
        type(klu_stats_t) :: stats
        integer(i8), parameter :: colptr(3) = [0_i8, 2_i8, 4_i8]
        integer(i8), parameter :: rowind(4) = [0_i8, 1_i8, 0_i8, 1_i8]
        real(wp), parameter :: tiny_pivot = 1.0e-10_wp
        complex(wp), parameter :: rot = (1.0_wp, 1.0_wp)

        call check(error, klu_refactor_degrade_ratio() > 0 .and. &
            klu_refactor_degrade_ratio() < 1, 'degrade ratio in (0, 1)')
        call lu%analyse(2, colptr, rowind, status)
        call check(error, status%ok(), 'analyse: ' // status%text())
        ! 1: first call factors afresh (diagonal pivots).
        call step(error, lu, [4.0_wp, 1.0_wp, 1.0_wp, 4.0_wp], 1_i8, 0_i8, 'diagonally dominant')
        ! 2: mild change: old pivot order kept.
        call step(error, lu, [3.0_wp, 1.0_wp, 1.0_wp, 5.0_wp], 1_i8, 1_i8, 'mild change')
        ! 3: tiny diagonal: the old order would grow pivots by 1/tiny_pivot².
        call step(error, lu, [tiny_pivot, 1.0_wp, 1.0_wp, tiny_pivot], 2_i8, 1_i8, 'tiny pivot')
        ! 4: zero off-diagonal: the now off-diagonal pivot order meets zeros.
        call step(error, lu, [2.0_wp, 0.0_wp, 0.0_wp, 3.0_wp], 3_i8, 1_i8, 'zero pivot')
        ! The complex part keeps its own pivot order and counters.
        call lu%refactor(rot * [4.0_wp, 1.0_wp, 1.0_wp, 4.0_wp], status)
        call lu%refactor(rot * [tiny_pivot, 1.0_wp, 1.0_wp, tiny_pivot], status)
        call check(error, status%ok(), 'complex refactor: ' // status%text())
        stats = lu%stats(klu_part_complex)
        call check(error, stats%nfactor == 2 .and. stats%nrefactor == 0, &
            'complex: tiny pivot must be factored afresh')
        stats = lu%stats(klu_part_real)
        call check(error, stats%nfactor == 3, 'complex work changed the real counters')
        call lu%destroy()
    contains
        subroutine step(error, lu, a, nfactor, nrefactor, label)
            type(error_t), allocatable, intent(inout) :: error
            type(klu_factor_t), intent(inout) :: lu
            real(wp), intent(in) :: a(4)
            integer(i8), intent(in) :: nfactor, nrefactor
            character(len=*), intent(in) :: label
            real(wp) :: x(2), b(2)
            type(status_t) :: status
            type(klu_stats_t) :: stats
            call lu%refactor(a, status)
            call check(error, status%ok(), label // ': ' // status%text())
            stats = lu%stats(klu_part_real)
            call check(error, stats%nfactor == nfactor .and. stats%nrefactor == nrefactor, &
                label // ': unexpected choice between refactor and fresh factor')
            x = [1.0_wp, -2.0_wp]
            b = [a(1) * x(1) + a(3) * x(2), a(2) * x(1) + a(4) * x(2)]
            call lu%solve(b, status)
            call check(error, rel_diff(b, x) <= agree_tol, label // ': solution')
        end subroutine step
    end subroutine test_refactor_degraded

    !> Exactly singular matrices report reason_singular_matrix.
    subroutine test_singular(error)
        type(error_t), allocatable, intent(out) :: error
        type(klu_factor_t) :: lu
        type(klu_solver_t) :: solver
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        real(wp) :: b(3)
        complex(wp) :: zb(3)
        ! [[1, 2], [2, 4]]: dependent columns.
        call lu%analyse(2, [0_i8, 2_i8, 4_i8], [0_i8, 1_i8, 0_i8, 1_i8], status)
        call lu%factor([1.0_wp, 2.0_wp, 2.0_wp, 4.0_wp], status)
        call check_singular(error, status, 'klu_factor_t real')
        call lu%factor(cmplx([1.0_wp, 2.0_wp, 2.0_wp, 4.0_wp], 0.0_wp, wp), status)
        call check_singular(error, status, 'klu_factor_t complex')
        call lu%destroy()
        ! J with a zero column and no shift: c*M - J = -J is singular.
        jac%storage = storage_sparse
        jac%n = 3
        call jac%csc%build(3, 3, [1, 2, 3, 1, 2], [1, 1, 2, 2, 3], status)
        call jac%csc%fill([1.0_wp, 2.0_wp, 1.0_wp, 0.0_wp, 0.0_wp])
        call identity(3, mass)
        call solver%init(mass, jac, status)
        call check(error, status%ok(), 'init: ' // status%text())
        call solver%factor_real(0.0_wp, mass, jac, status)
        call check_singular(error, status, 'klu_solver_t real')
        call solver%factor_complex((0.0_wp, 0.0_wp), mass, jac, status)
        call check_singular(error, status, 'klu_solver_t complex')
        ! A failed factorisation must not pass for a solution.
        b = 1.0_wp
        call solver%solve_real(b)
        call check(error, all(ieee_is_nan(b)), 'solve after a singular factor must give NaN')
        zb = (1.0_wp, 0.0_wp)
        call solver%solve_complex(zb)
        call check(error, all(ieee_is_nan(real(zb, wp))), &
            'complex solve after a singular factor must give NaN')
        ! A shift makes it regular again (a fresh factorisation).
        call solver%factor_real(2.0_wp, mass, jac, status)
        call check(error, status%ok(), 'shifted matrix is regular: ' // status%text())
        call solver%destroy()
    end subroutine test_singular

    subroutine check_singular(error, status, label)
        type(error_t), allocatable, intent(inout) :: error
        type(status_t), intent(in) :: status
        character(len=*), intent(in) :: label
        call check(error, status%code == status_solver_failure .and. &
            status%reason == reason_singular_matrix, label // ': expected singular, got ' // &
            status%text())
    end subroutine check_singular

    !> 5-point Laplacian with a convection term on a 60 x 60 grid (3600
    !> unknowns): backward error of the KLU solution ~ round-off.
    subroutine test_laplacian(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: m = 60, n = m * m
        real(wp), parameter :: peclet = 0.3_wp ! makes J nonsymmetric
        type(matrix_t) :: mass, jac
        type(klu_solver_t) :: solver
        type(status_t) :: status
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: vals(:), x(:), b(:), r(:), jx(:)
        complex(wp), allocatable :: zx(:), zb(:), zr(:)
        real(wp) :: norm_a, c
        complex(wp) :: zc
        integer :: i, j, k, t
        integer(i8) :: seed

        allocate (rows(5 * n), cols(5 * n), vals(5 * n))
        t = 0
        do j = 1, m
            do i = 1, m
                k = i + (j - 1) * m
                call add(k, k, -4.0_wp)
                if (i > 1) call add(k, k - 1, 1.0_wp + peclet)
                if (i < m) call add(k, k + 1, 1.0_wp - peclet)
                if (j > 1) call add(k, k - m, 1.0_wp)
                if (j < m) call add(k, k + m, 1.0_wp)
            end do
        end do
        jac%storage = storage_sparse
        jac%n = n
        call jac%csc%build(n, n, rows(:t), cols(:t), status)
        call jac%csc%fill(vals(:t))
        call identity(n, mass)
        call solver%init(mass, jac, status)
        call check(error, status%ok(), 'init: ' // status%text())
        call check(error, solver%nonzeros() == jac%csc%nnz, 'union pattern = pattern of J')
        c = 0.01_wp
        zc = cmplx(0.01_wp, 2.0_wp, wp)
        call solver%factor_real(c, mass, jac, status)
        call check(error, status%ok(), 'real factor: ' // status%text())
        call solver%factor_complex(zc, mass, jac, status)
        call check(error, status%ok(), 'complex factor: ' // status%text())
        if (allocated(error)) return

        allocate (x(n), b(n), r(n), jx(n), zx(n), zb(n), zr(n))
        seed = 2024
        do i = 1, n
            b(i) = uniform(seed)
            zb(i) = cmplx(uniform(seed), uniform(seed), wp)
        end do
        norm_a = abs(c) + 8.0_wp ! row sums of |c I - J|, bounded above
        x = b
        call solver%solve_real(x)
        call jac%csc%matvec(x, jx)
        r = b - (c * x - jx)
        call check(error, maxval(abs(r)) <= 50 * uround_wp * (norm_a * maxval(abs(x)) + &
            maxval(abs(b))), 'real residual not at round-off')
        zx = zb
        call solver%solve_complex(zx)
        call jac%csc%matvec(real(zx, wp), jx)
        zr = zb - zc * zx + jx
        call jac%csc%matvec(aimag(zx), jx)
        zr = zr + cmplx(0.0_wp, 1.0_wp, wp) * jx
        call check(error, maxval(abs(zr)) <= 50 * uround_wp * ((abs(zc) + 8.0_wp) * &
            maxval(abs(zx)) + maxval(abs(zb))), 'complex residual not at round-off')
        call solver%destroy()
    contains
        subroutine add(row, col, v)
            integer, intent(in) :: row, col
            real(wp), intent(in) :: v
            t = t + 1
            rows(t) = row
            cols(t) = col
            vals(t) = v
        end subroutine add
    end subroutine test_laplacian

    !> Nested dissection (METIS) and AMD solve the same 2-D system to
    !> round-off; 'auto' picks ND on the periodic 2-D grid of 10⁴ unknowns
    !> (AMD predicts much fill) and AMD on the 1-D chain of the same size.
    subroutine test_orderings(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: m = 100, n = m * m
        type(csc_matrix_t) :: a2, a1
        type(klu_factor_t) :: lu
        type(status_t) :: status
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: vals(:), b(:), x_amd(:), x_nd(:), r(:)
        integer :: i, j, k, t
        integer(i8) :: seed
        allocate (rows(5 * n), cols(5 * n), vals(5 * n), b(n), r(n))
        t = 0
        do j = 1, m
            do i = 1, m
                k = i + (j - 1) * m
                ! Periodic, as the Brusselator's grid: more fill than a box.
                call add(k, k, 4.5_wp)
                call add(k, modulo(i - 2, m) + 1 + (j - 1) * m, -1.3_wp)
                call add(k, modulo(i, m) + 1 + (j - 1) * m, -0.7_wp)
                call add(k, i + modulo(j - 2, m) * m, -1.0_wp)
                call add(k, i + modulo(j, m) * m, -1.0_wp)
            end do
        end do
        call a2%build(n, n, rows(:t), cols(:t), status)
        call a2%fill(vals(:t))
        seed = 7
        do i = 1, n
            b(i) = uniform(seed)
        end do
        call lu%analyse(n, a2%colptr, a2%rowind, status, klu_ordering_auto)
        call check(error, status%ok() .and. lu%ordering_used() == klu_ordering_nd, &
            "'auto' did not choose nested dissection on the 2-D grid: " // status%text())
        x_nd = b
        call lu%factor(a2%values, status)
        if (status%ok()) call lu%solve(x_nd, status)
        call check(error, status%ok(), 'nd: ' // status%text())
        call lu%analyse(n, a2%colptr, a2%rowind, status, klu_ordering_amd)
        call check(error, lu%ordering_used() == klu_ordering_amd, 'amd not used when asked')
        x_amd = b
        call lu%factor(a2%values, status)
        if (status%ok()) call lu%solve(x_amd, status)
        call check(error, status%ok(), 'amd: ' // status%text())
        if (allocated(error)) return
        call a2%matvec(x_nd, r)
        call check(error, maxval(abs(r - b)) <= 100 * uround_wp * 10.0_wp * maxval(abs(x_nd)), &
            'nd residual not at round-off')
        call check(error, maxval(abs(x_nd - x_amd)) <= 1.0e-12_wp * maxval(abs(x_amd)), &
            'nd and amd solutions differ')
        ! 1-D chain: little fill, 'auto' keeps AMD.
        t = 0
        do k = 1, n
            call add(k, k, 4.0_wp)
            if (k > 1) call add(k, k - 1, -1.0_wp)
            if (k < n) call add(k, k + 1, -1.0_wp)
        end do
        call a1%build(n, n, rows(:t), cols(:t), status)
        call lu%analyse(n, a1%colptr, a1%rowind, status)
        call check(error, status%ok() .and. lu%ordering_used() == klu_ordering_amd, &
            "'auto' left AMD on the 1-D chain")
        call lu%analyse(n, a1%colptr, a1%rowind, status, 5)
        call check(error, status%code == status_bad_input, 'unknown ordering accepted')
    contains
        subroutine add(r1, c1, v1)
            integer, intent(in) :: r1, c1
            real(wp), intent(in) :: v1
            t = t + 1
            rows(t) = r1
            cols(t) = c1
            vals(t) = v1
        end subroutine add
    end subroutine test_orderings

    !> A copy made by assignment owns no KLU objects: it reports 'not
    !> analysed' instead of sharing the original's, finalising it frees
    !> nothing, and the original keeps working.
    subroutine test_copies(error)
        type(error_t), allocatable, intent(out) :: error
        type(klu_factor_t) :: a
        type(klu_factor_t), allocatable :: b
        type(klu_solver_t) :: s1
        class(linear_solver_t), allocatable :: p1, p2
        type(matrix_t) :: mass, jac
        type(status_t) :: status
        real(wp) :: x(2), y(5)
        integer(i8) :: seed

        call a%analyse(2, [0_i8, 2_i8, 4_i8], [0_i8, 1_i8, 0_i8, 1_i8], status)
        call a%factor([2.0_wp, 0.0_wp, 0.0_wp, 4.0_wp], status)
        allocate (b)
        b = a
        call check(error, .not. b%is_analysed(), 'a copy must not hold the KLU objects')
        call b%factor([1.0_wp, 0.0_wp, 0.0_wp, 8.0_wp], status)
        call check(error, status%code == status_bad_input, 'factor of a copy accepted')
        x = [2.0_wp, 8.0_wp]
        call b%solve(x, status)
        call check(error, status%code == status_bad_input, 'solve with a copy accepted')
        deallocate (b) ! finalises the copy
        x = [2.0_wp, 8.0_wp]
        call a%solve(x, status)
        call check(error, status%ok() .and. rel_diff(x, [1.0_wp, 2.0_wp]) <= agree_tol, &
            'original spoiled by its copy')
        call a%destroy()

        seed = 5
        call random_sparse(5, 2, 3.0_wp, seed, jac)
        call identity(5, mass)
        call s1%init(mass, jac, status)
        call s1%factor_real(1.0_wp, mass, jac, status)
        allocate (p1, source=s1)
        p2 = p1
        call p2%factor_real(1.0_wp, mass, jac, status)
        call check(error, status%code == status_bad_input, 'factor of a solver copy accepted')
        deallocate (p1, p2)
        ! The original still solves (1 I - J) y = (1 I - J) 1.
        call jac%matvec([1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp], y)
        y = 1.0_wp - y
        call s1%solve_real(y)
        call check(error, rel_diff(y, [1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp]) <= agree_tol, &
            'original solver spoiled by its copies')
        ! A copy initialised again is a solver of its own.
        allocate (p2, source=s1)
        call p2%init(mass, jac, status)
        call p2%factor_real(2.0_wp, mass, jac, status)
        call check(error, status%ok(), 'copy initialised again: ' // status%text())
        call s1%destroy()
        deallocate (p2)
    end subroutine test_copies

    !> Wrong use and non-finite values are reported, not crashed on.
    subroutine test_bad_use(error)
        type(error_t), allocatable, intent(out) :: error
        type(klu_solver_t) :: solver
        type(klu_factor_t) :: lu
        type(matrix_t) :: mass, jac, other
        type(status_t) :: status
        integer(i8) :: seed
        real(wp) :: b(3)
        seed = 31
        call random_sparse(10, 2, 3.0_wp, seed, jac)
        call identity(10, mass)
        call solver%factor_real(1.0_wp, mass, jac, status)
        call check(error, status%code == status_bad_input, 'factor before init')
        call solver%init(mass, jac, status)
        call random_sparse(10, 4, 3.0_wp, seed, other)
        call solver%factor_real(1.0_wp, mass, other, status)
        call check(error, status%code == status_bad_input, 'changed pattern accepted')
        jac%storage = storage_none
        call solver%init(mass, jac, status)
        call check(error, status%code == status_bad_input, 'init without a Jacobian')
        call solver%destroy()
        call lu%analyse(2, [0_i8, 1_i8, 2_i8], [0_i8, 1_i8], status)
        call lu%factor([1.0_wp, 2.0_wp, 3.0_wp], status)
        call check(error, status%code == status_bad_input, 'wrong number of values')
        call lu%factor([1.0_wp, 2.0_wp], status)
        call lu%solve(b, status)
        call check(error, status%code == status_bad_input, 'wrong right-hand side size')
        call lu%factor([1.0_wp, ieee_value(1.0_wp, ieee_quiet_nan)], status)
        call check(error, status%reason == reason_non_finite, 'NaN not reported')
        call lu%factor([1.0_wp, 2.0_wp], status)
        call lu%refactor([ieee_value(1.0_wp, ieee_positive_inf), 2.0_wp], status)
        call check(error, status%reason == reason_non_finite, 'Inf not reported')
        call lu%refactor(cmplx([1.0_wp, ieee_value(1.0_wp, ieee_quiet_nan)], 0.0_wp, wp), &
            status)
        call check(error, status%reason == reason_non_finite, 'complex NaN not reported')
        call lu%analyse(2, [0_i8, 2_i8, 3_i8], [0_i8, 0_i8, 1_i8], status)
        call check(error, status%code == status_bad_input, 'duplicate entries accepted')
        call lu%destroy()
    end subroutine test_bad_use

    subroutine test_factory(error)
        type(error_t), allocatable, intent(out) :: error
        class(linear_solver_t), allocatable :: solver
        type(status_t) :: status
        call expect('auto', auto_sparse_threshold - 1, storage_sparse, 'dense')
        call expect('auto', auto_sparse_threshold, storage_sparse, 'klu')
        call expect('auto', 10 * auto_sparse_threshold, storage_dense, 'dense')
        call expect('auto', 10 * auto_sparse_threshold, storage_none, 'dense')
        call expect('dense', 10 * auto_sparse_threshold, storage_sparse, 'dense')
        call expect('klu', 3, storage_sparse, 'klu')
        call new_linear_solver('umfpack', 1000, storage_sparse, solver, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), "'umfpack'") > 0 .and. .not. allocated(solver), &
            'bad name must be rejected and named: ' // status%text())
        call new_linear_solver('klu', 1000, storage_none, solver, status)
        call check(error, status%code == status_bad_input, 'klu without a Jacobian')
        call new_linear_solver('auto', 0, storage_sparse, solver, status)
        call check(error, status%code == status_bad_input, 'n = 0 accepted')
    contains
        subroutine expect(choice, n, storage, chosen)
            character(len=*), intent(in) :: choice, chosen
            integer, intent(in) :: n, storage
            call new_linear_solver(choice, n, storage, solver, status)
            call check(error, status%code == status_ok, choice // ': ' // status%text())
            if (allocated(solver)) then
                call check(error, solver%name() == chosen, choice // ' chose ' // solver%name() &
                    // ', expected ' // chosen)
            else
                call check(error, .false., choice // ': no solver')
            end if
        end subroutine expect
    end subroutine test_factory
end module test_klu
