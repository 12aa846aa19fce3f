!> Band LU (LAPACK gbtrf/gbtrs): agreement with dense LU for identity,
!> banded-dense and sparse masses, both factorisations alive together,
!> singular matrices, bandwidth detection and checks, the factory, and a
!> RADAU5 run that equals the dense one.
module test_band
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    use flexmbs_core_kinds, only: wp, i8, uround_wp
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, &
        status_solver_failure, reason_singular_matrix
    use flexmbs_linalg_matrix, only: matrix_t, storage_identity, storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_band, only: band_solver_t, matrix_bandwidths
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    use flexmbs_problems_van_der_pol, only: van_der_pol_t, new_van_der_pol
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_band

    !> Band and dense LU pivot alike on these well-conditioned systems: a few
    !> hundred units of round-off at most.
    real(wp), parameter :: agree_tol = 500 * uround_wp

    !> Park–Miller minimal standard generator (CACM 31, 1988): the same
    !> numbers with every compiler, unlike random_number.
    integer(i8), parameter :: lehmer_a = 16807_i8, lehmer_m = 2147483647_i8

contains

    function collect_band() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('matches_dense_identity_mass', test_identity_mass), &
                 new_test('matches_dense_banded_dense_mass', test_dense_mass), &
                 new_test('matches_dense_sparse_mass', test_sparse_mass), &
                 new_test('real_factor_survives_complex', test_both_alive), &
                 new_test('singular_matrix_status', test_singular), &
                 new_test('bandwidth_detection_and_checks', test_bandwidths), &
                 new_test('factory_choice', test_factory), &
                 new_test('radau5_band_equals_dense_brusselator', test_radau5_brusselator), &
                 new_test('radau5_band_options_checked', test_radau5_options)]
    end function collect_band

    ! ---------------------------------------------------------------- helpers

    real(wp) function uniform(seed)
        integer(i8), intent(inout) :: seed
        seed = mod(lehmer_a * seed, lehmer_m)
        uniform = real(seed, wp) / real(lehmer_m, wp)
    end function uniform

    !> A random n x n CSC matrix filling the band (ml, mu) with values in
    !> (-1, 1), plus `diag` on the diagonal.
    subroutine random_band(n, ml, mu, diag, seed, a)
        integer, intent(in) :: n, ml, mu
        real(wp), intent(in) :: diag
        integer(i8), intent(inout) :: seed
        type(matrix_t), intent(out) :: a
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: vals(:)
        integer :: i, j, t
        type(status_t) :: status
        allocate (rows(n * (ml + mu + 1)), cols(n * (ml + mu + 1)), vals(n * (ml + mu + 1)))
        t = 0
        do j = 1, n
            do i = max(1, j - mu), min(n, j + ml)
                t = t + 1
                rows(t) = i
                cols(t) = j
                vals(t) = 2 * uniform(seed) - 1
                if (i == j) vals(t) = vals(t) + diag
            end do
        end do
        a%storage = storage_sparse
        a%n = n
        call a%csc%build(n, n, rows(:t), cols(:t), status)
        call a%csc%fill(vals(:t))
    end subroutine random_band

    !> The same matrix in dense storage.
    subroutine as_dense(a, d)
        type(matrix_t), intent(in) :: a
        type(matrix_t), intent(out) :: d
        d%storage = storage_dense
        d%n = a%n
        allocate (d%dense(a%n, a%n))
        call a%to_dense(d%dense)
    end subroutine as_dense

    subroutine identity(n, a)
        integer, intent(in) :: n
        type(matrix_t), intent(out) :: a
        a%storage = storage_identity
        a%n = n
    end subroutine identity

    pure real(wp) function rel_diff(x, y)
        real(wp), intent(in) :: x(:), y(:)
        rel_diff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function rel_diff

    pure real(wp) function zrel_diff(x, y)
        complex(wp), intent(in) :: x(:), y(:)
        zrel_diff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function zrel_diff

    !> Factor c*M - J (real and complex shifts) with band and dense LU and
    !> compare solutions of random right-hand sides. The band solver holds
    !> both factorisations: the real solve comes after the complex factor.
    subroutine compare_with_dense(error, mass, jac, c, zc, seed, label)
        type(error_t), allocatable, intent(inout) :: error
        type(matrix_t), intent(in) :: mass, jac
        real(wp), intent(in) :: c
        complex(wp), intent(in) :: zc
        integer(i8), intent(inout) :: seed
        character(len=*), intent(in) :: label
        type(band_solver_t) :: band
        type(dense_solver_t) :: dense, zdense
        type(status_t) :: status
        real(wp), allocatable :: b(:), x(:)
        complex(wp), allocatable :: zb(:), zx(:)
        integer :: i, n

        n = jac%n
        allocate (b(n), x(n), zb(n), zx(n))
        call band%init(mass, jac, status)
        call check(error, status%ok(), label // ': band init: ' // status%text())
        call band%factor_real(c, mass, jac, status)
        call check(error, status%ok(), label // ': band real factor: ' // status%text())
        call band%factor_complex(zc, mass, jac, status)
        call check(error, status%ok(), label // ': band complex factor: ' // status%text())
        ! Separate dense solvers: dense_solver_t builds its complex matrix
        ! from the real array's storage.
        call dense%init(mass, jac, status)
        call zdense%init(mass, jac, status)
        call dense%factor_real(c, mass, jac, status)
        call zdense%factor_complex(zc, mass, jac, status)
        if (allocated(error)) return
        do i = 1, n
            b(i) = 2 * uniform(seed) - 1
            zb(i) = cmplx(2 * uniform(seed) - 1, 2 * uniform(seed) - 1, kind=wp)
        end do
        x = b
        call band%solve_real(x)
        call dense%solve_real(b)
        call check_close(error, rel_diff(x, b), 0.0_wp, agree_tol, label // ': real solves')
        zx = zb
        call band%solve_complex(zx)
        call zdense%solve_complex(zb)
        call check_close(error, zrel_diff(zx, zb), 0.0_wp, agree_tol, &
            label // ': complex solves')
    end subroutine compare_with_dense

    ! ------------------------------------------------------------------ tests

    subroutine test_identity_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac, dense_j
        integer(i8) :: seed
        seed = 2024
        call random_band(60, 3, 2, 0.0_wp, seed, jac)
        call identity(60, mass)
        call compare_with_dense(error, mass, jac, 3.0_wp, cmplx(2.0_wp, 4.0_wp, wp), seed, &
            'identity M, sparse J')
        ! A dense J: the band is read from its nonzero entries.
        call as_dense(jac, dense_j)
        call compare_with_dense(error, mass, dense_j, 1.5_wp, cmplx(0.5_wp, -3.0_wp, wp), &
            seed, 'identity M, dense J')
    end subroutine test_identity_mass

    !> A tridiagonal mass held as a dense array, J wider in the upper band.
    subroutine test_dense_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass_sparse, mass, jac
        integer(i8) :: seed
        seed = 31337
        call random_band(50, 2, 4, 0.0_wp, seed, jac)
        call random_band(50, 1, 1, 3.0_wp, seed, mass_sparse)
        call as_dense(mass_sparse, mass)
        call compare_with_dense(error, mass, jac, 2.0_wp, cmplx(1.5_wp, -2.5_wp, wp), seed, &
            'banded dense M')
    end subroutine test_dense_mass

    !> A sparse mass wider below than J: the band is the union of both.
    subroutine test_sparse_mass(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        type(band_solver_t) :: band
        type(status_t) :: status
        integer(i8) :: seed
        seed = 97
        call random_band(70, 1, 2, 0.0_wp, seed, jac)
        call random_band(70, 3, 0, 4.0_wp, seed, mass)
        call compare_with_dense(error, mass, jac, 2.0_wp, cmplx(1.0_wp, 1.0_wp, wp), seed, &
            'sparse M')
        call band%init(mass, jac, status)
        call check(error, all(band%bandwidths() == [3, 2]), 'union of the bands of M and J')
    end subroutine test_sparse_mass

    !> The real factorisation survives a complex one, and a failed
    !> factorisation is not used: the solve then returns NaN.
    subroutine test_both_alive(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        type(band_solver_t) :: band
        type(status_t) :: status
        real(wp) :: b(40), x1(40), x2(40)
        complex(wp) :: zb(40)
        integer(i8) :: seed
        integer :: i
        seed = 5
        call random_band(40, 2, 2, 0.0_wp, seed, jac)
        call identity(40, mass)
        do i = 1, 40
            b(i) = 2 * uniform(seed) - 1
        end do
        call band%init(mass, jac, status)
        x1 = b
        call band%solve_real(x1)
        call check(error, all(ieee_is_nan(x1)), 'solve before any factor must give NaN')
        call band%factor_real(4.0_wp, mass, jac, status)
        x1 = b
        call band%solve_real(x1)
        call band%factor_complex(cmplx(3.0_wp, 5.0_wp, wp), mass, jac, status)
        x2 = b
        call band%solve_real(x2)
        call check(error, all(x1 == x2), 'real solution changed by the complex factor')
        zb = cmplx(b, -b, kind=wp)
        call band%solve_complex(zb)
        call check(error, .not. any(ieee_is_nan(zb%re)), 'complex factor missing')
    end subroutine test_both_alive

    subroutine test_singular(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac
        type(band_solver_t) :: band
        type(status_t) :: status
        real(wp) :: b(10)
        complex(wp) :: zb(10)
        integer :: i
        integer(i8) :: p
        integer(i8) :: seed
        seed = 11
        call random_band(10, 1, 1, 0.0_wp, seed, jac)
        ! Column 4 of J zero and c = 0: A = -J has a zero column.
        do p = jac%csc%colptr(4) + 1, jac%csc%colptr(5)
            jac%csc%values(p) = 0.0_wp
        end do
        call identity(10, mass)
        call band%init(mass, jac, status)
        call check(error, status%ok(), 'init: ' // status%text())
        call band%factor_real(0.0_wp, mass, jac, status)
        call check(error, status%code == status_solver_failure .and. &
            status%reason == reason_singular_matrix, 'real singular: ' // status%text())
        call band%factor_complex((0.0_wp, 0.0_wp), mass, jac, status)
        call check(error, status%code == status_solver_failure .and. &
            status%reason == reason_singular_matrix, 'complex singular: ' // status%text())
        b = [(real(i, wp), i = 1, 10)]
        call band%solve_real(b)
        call check(error, all(ieee_is_nan(b)), 'solve after a singular factor must give NaN')
        zb = (1.0_wp, 0.0_wp)
        call band%solve_complex(zb)
        call check(error, all(ieee_is_nan(zb%re)), 'complex solve after a singular factor')
        ! A nonzero shift makes it regular again.
        call band%factor_real(1.0_wp, mass, jac, status)
        call check(error, status%ok(), 'regular after shift: ' // status%text())
    end subroutine test_singular

    subroutine test_bandwidths(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: mass, jac, dense_j, tri
        type(band_solver_t) :: band
        type(status_t) :: status
        integer(i8) :: seed
        integer :: i
        seed = 1234
        call random_band(30, 3, 1, 0.0_wp, seed, jac)
        call identity(30, mass)
        call check(error, all(matrix_bandwidths(jac) == [3, 1]), 'CSC pattern')
        call check(error, all(matrix_bandwidths(mass) == [0, 0]), 'identity')
        call as_dense(jac, dense_j)
        call check(error, all(matrix_bandwidths(dense_j) == [3, 1]), 'dense nonzeros')
        ! Zeros do not count in a dense array: clear the third subdiagonal.
        do i = 4, 30
            dense_j%dense(i, i - 3) = 0.0_wp
        end do
        call check(error, all(matrix_bandwidths(dense_j) == [2, 1]), 'dense zeros ignored')
        dense_j%dense(1, 30) = 0.5_wp
        call check(error, all(matrix_bandwidths(dense_j) == [2, 29]), 'dense corner')
        call band%init(mass, jac, status)
        call check(error, status%ok() .and. all(band%bandwidths() == [3, 1]), 'detected')

        ! Given bandwidths: wider is fine (capped at n - 1), narrower is not.
        band%lower = 5
        band%upper = 40
        call band%init(mass, jac, status)
        call check(error, status%ok() .and. all(band%bandwidths() == [5, 29]), &
            'given bandwidths used: ' // status%text())
        call compare_given(error, band, mass, jac)
        band%lower = 2
        band%upper = 1
        call band%init(mass, jac, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'outside the bandwidths given') > 0, &
            'pattern outside given band: ' // status%text())
        band%lower = 2
        band%upper = -1
        call band%init(mass, jac, status)
        call check(error, status%code == status_bad_input, 'only one bandwidth given')

        ! A dense J whose values leave the band found at init is reported,
        ! never silently cut.
        band%lower = -1
        band%upper = -1
        call random_band(30, 1, 1, 0.0_wp, seed, tri)
        call as_dense(tri, dense_j)
        call band%init(mass, dense_j, status)
        call check(error, status%ok() .and. all(band%bandwidths() == [1, 1]), 'dense J band')
        dense_j%dense(7, 2) = 1.0_wp
        call band%factor_real(1.0_wp, mass, dense_j, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), '(7, 2)') > 0, 'entry outside the band: ' // status%text())
        call band%factor_complex((1.0_wp, 1.0_wp), mass, dense_j, status)
        call check(error, status%code == status_bad_input, 'complex: entry outside the band')
        ! Changed storage since init.
        call band%factor_real(1.0_wp, mass, tri, status)
        call check(error, status%code == status_bad_input, 'storage changed since init')
    contains
        !> A band wider than needed gives the dense solution all the same.
        subroutine compare_given(error, band, mass, jac)
            type(error_t), allocatable, intent(inout) :: error
            type(band_solver_t), intent(inout) :: band
            type(matrix_t), intent(in) :: mass, jac
            type(dense_solver_t) :: dense
            real(wp) :: b(30), x(30)
            integer :: i
            b = [(sin(real(i, wp)), i = 1, 30)]
            x = b
            call band%factor_real(5.0_wp, mass, jac, status)
            call band%solve_real(x)
            call dense%init(mass, jac, status)
            call dense%factor_real(5.0_wp, mass, jac, status)
            call dense%solve_real(b)
            call check_close(error, rel_diff(x, b), 0.0_wp, agree_tol, 'wide band solve')
        end subroutine compare_given
    end subroutine test_bandwidths

    subroutine test_factory(error)
        type(error_t), allocatable, intent(out) :: error
        class(linear_solver_t), allocatable :: solver
        type(status_t) :: status
        type(matrix_t) :: mass, jac
        integer(i8) :: seed
        call new_linear_solver('band', 100, storage_sparse, solver, status)
        call check(error, status%code == status_ok .and. allocated(solver), &
            "'band': " // status%text())
        if (allocated(error)) return
        call check(error, solver%name() == 'band', "'band' chose " // solver%name())
        call new_linear_solver('band', 100, storage_dense, solver, status, lower=2, upper=3)
        call check(error, status%code == status_ok .and. allocated(solver), &
            'band with bandwidths: ' // status%text())
        if (allocated(error)) return
        seed = 8
        call random_band(100, 1, 1, 0.0_wp, seed, jac)
        call identity(100, mass)
        call solver%init(mass, jac, status)
        select type (solver)
        type is (band_solver_t)
            call check(error, all(solver%bandwidths() == [2, 3]), 'bandwidths passed through')
        class default
            call check(error, .false., 'factory did not make a band_solver_t')
        end select
        ! 'auto' never picks band (bench: KLU is as fast on banded problems).
        call new_linear_solver('auto', 1000, storage_sparse, solver, status)
        call check(error, solver%name() == 'klu', "'auto' chose " // solver%name())
        call new_linear_solver('banded', 100, storage_sparse, solver, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), "'band'") > 0, 'unknown name lists band: ' // status%text())
    end subroutine test_factory

    subroutine run(problem, y0, t_end, options, y, stats, native, status)
        class(reaction_diffusion_t), intent(inout) :: problem
        real(wp), intent(in) :: y0(:), t_end
        type(dae_options_t), intent(in) :: options
        real(wp), intent(out) :: y(:)
        type(dae_stats_t), intent(out) :: stats
        integer, intent(out) :: native(7)
        type(status_t), intent(out) :: status
        type(radau5_t) :: solver
        real(wp) :: t
        t = 0.0_wp
        y = y0
        call solver%integrate(problem, t, y, t_end, options, stats, status)
        native = [solver%native%nfcn, solver%native%njac, solver%native%nstep, &
                  solver%native%naccpt, solver%native%nrejct, solver%native%ndec, &
                  solver%native%nsol]
    end subroutine run

    !> 1-D Brusselator, N = 200 (400 unknowns, bandwidths 2, 2), t in [0, 1]:
    !> the same steps and counters, states equal to round-off.
    subroutine test_radau5_brusselator(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(dae_options_t) :: options
        type(dae_stats_t) :: s_dense, s_band
        type(status_t) :: status
        real(wp), allocatable :: y0(:), y_dense(:), y_band(:)
        integer :: n_dense(7), n_band(7)
        character(len=120) :: msg
        problem = new_reaction_diffusion(1, 200)
        allocate (y0(problem%n), y_dense(problem%n), y_band(problem%n))
        call reaction_diffusion_initial(problem, y0)
        options%rtol = 1.0e-6_wp
        options%atol = 1.0e-6_wp
        options%linear_solver = 'dense'
        call run(problem, y0, 1.0_wp, options, y_dense, s_dense, n_dense, status)
        call check(error, status%ok(), 'dense run: ' // status%text())
        options%linear_solver = 'band'
        call run(problem, y0, 1.0_wp, options, y_band, s_band, n_band, status)
        call check(error, status%ok(), 'band run: ' // status%text())
        write (msg, '(a,es10.3)') 'trajectories differ: ', &
            maxval(abs(y_dense - y_band) / (1.0_wp + abs(y_dense)))
        call check(error, maxval(abs(y_dense - y_band) / (1.0_wp + abs(y_dense))) <= 1.0e-10_wp, &
            trim(msg))
        call check(error, all(n_dense == n_band), 'RADAU5 counters differ between dense and band')
        call check(error, s_dense%nst == s_band%nst .and. s_dense%nfe == s_band%nfe .and. &
            s_dense%nsol == s_band%nsol, 'statistics differ between dense and band')
        ! The same with the bandwidths given.
        options%band_lower = 2
        options%band_upper = 2
        call run(problem, y0, 1.0_wp, options, y_band, s_band, n_band, status)
        call check(error, status%ok() .and. all(n_dense == n_band), 'given bandwidths')
    end subroutine test_radau5_brusselator

    !> Bandwidths narrower than the pattern, one of two, or a dense Jacobian
    !> without them: bad input, said before any step.
    subroutine test_radau5_options(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(van_der_pol_t) :: vdp
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: y(:)
        real(wp) :: t
        problem = new_reaction_diffusion(1, 20)
        allocate (y(problem%n))
        call reaction_diffusion_initial(problem, y)
        options%linear_solver = 'band'
        options%band_lower = 1
        options%band_upper = 1
        t = 0.0_wp
        call solver%integrate(problem, t, y, 1.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input .and. stats%nst == 0, &
            'band narrower than J: ' // status%text())
        options%band_upper = -1
        call solver%integrate(problem, t, y, 1.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'band_lower') > 0, 'one bandwidth: ' // status%text())
        vdp = new_van_der_pol(1.0e-6_wp)
        options%band_lower = -1
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(vdp, t, y(1:2), 1.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'dense or difference Jacobian') > 0, &
            'dense J without bandwidths: ' // status%text())
        options%band_lower = 1
        options%band_upper = 1
        t = 0.0_wp
        call solver%integrate(vdp, t, y(1:2), 0.1_wp, options, stats, status)
        call check(error, status%ok(), 'dense J with bandwidths: ' // status%text())
    end subroutine test_radau5_options
end module test_band
