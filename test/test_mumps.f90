!> Multifrontal sparse LU through MUMPS: agreement with KLU and dense LU on
!> real and complex shifted systems c*M - J (a small matrix with a known
!> solution, the node graph of a 3-D hex8 block, a slender one),
!> refactorisation, singular matrices, orderings, several right-hand sides,
!> MUMPS's error analysis and the choice of `linear_solver = 'auto'`.
module test_mumps
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    use flexmbs_core_kinds, only: wp, i8, uround_wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t, auto_mumps_min_order, &
        auto_mumps_min_fill
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_klu_solver, only: klu_solver_t
    use flexmbs_linalg_mumps, only: mumps_real_t, mumps_complex_t, mumps_accuracy_t, &
        mumps_ordering_amd, mumps_ordering_amf, mumps_ordering_scotch, mumps_ordering_pord, &
        mumps_ordering_qamd, mumps_ordering_auto, mumps_ordering_code, mumps_ordering_name
    use flexmbs_linalg_mumps_solver, only: mumps_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver, predicted_fill_ratio
    use flexmbs_problems_node_graph, only: node_graph_jacobian, node_graph_mass
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_mumps

    !> Agreement of MUMPS, KLU and LAPACK on diagonally dominant systems.
    real(wp), parameter :: agree_tol = 1.0e-10_wp
    !> The shifts of the tests: RADAU5-like real and complex values.
    real(wp), parameter :: shift = 2.5_wp
    complex(wp), parameter :: zshift = (1.5_wp, 3.0_wp)

contains

    function collect_mumps() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('small_known_solution', test_small_known), &
                 new_test('hex8_node_graph_matches_klu_dense', test_hex8), &
                 new_test('slender_node_graph_matches_klu_dense', test_slender), &
                 new_test('refactor_new_values', test_refactor), &
                 new_test('singular_matrix_status', test_singular), &
                 new_test('orderings_reported', test_orderings), &
                 new_test('several_right_hand_sides', test_several_rhs), &
                 new_test('error_analysis_estimates', test_error_analysis), &
                 new_test('misuse_reported', test_misuse), &
                 new_test('small_workspace_grows', test_workspace), &
                 new_test('auto_picks_mumps_on_3d_klu_on_slender', test_auto)]
    end function collect_mumps

    ! ---------------------------------------------------------------- helpers

    !> Max-norm relative difference.
    pure real(wp) function reldiff(x, y)
        real(wp), intent(in) :: x(:), y(:)
        reldiff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function reldiff

    pure real(wp) function zreldiff(x, y)
        complex(wp), intent(in) :: x(:), y(:)
        zreldiff = maxval(abs(x - y)) / max(maxval(abs(y)), tiny(1.0_wp))
    end function zreldiff

    !> A deterministic right-hand side.
    pure function rhs(n, k) result(b)
        integer, intent(in) :: n, k
        real(wp) :: b(n)
        integer :: i
        b = [(cos(real(i * k, wp)), i = 1, n)]
    end function rhs

    !> Solve c*M - J x = b (real and complex shift) with MUMPS, KLU and dense
    !> LU; every pair agrees to agree_tol. The real factorisation must survive
    !> the complex one.
    subroutine check_agreement(error, label, mass, jac)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: label
        type(matrix_t), intent(in) :: mass, jac
        type(mumps_solver_t) :: mumps
        type(klu_solver_t) :: klu
        type(dense_solver_t) :: dense, zdense
        type(status_t) :: status
        real(wp), allocatable :: xm(:), xk(:), xd(:)
        complex(wp), allocatable :: zm(:), zk(:), zd(:)
        integer :: n

        n = jac%n
        call mumps%init(mass, jac, status)
        call check(error, status%ok(), label // ': mumps init: ' // status%text())
        call klu%init(mass, jac, status)
        call dense%init(mass, jac, status)
        call zdense%init(mass, jac, status)
        call mumps%factor_real(shift, mass, jac, status)
        call check(error, status%ok(), label // ': mumps real factor: ' // status%text())
        call mumps%factor_complex(zshift, mass, jac, status)
        call check(error, status%ok(), label // ': mumps complex factor: ' // status%text())
        call klu%factor_real(shift, mass, jac, status)
        call klu%factor_complex(zshift, mass, jac, status)
        call dense%factor_real(shift, mass, jac, status)
        call zdense%factor_complex(zshift, mass, jac, status)
        if (allocated(error)) return
        ! allocated first: gfortran's reallocation on assignment tests the
        ! bounds of a never-allocated array's descriptor (valgrind: a jump on
        ! uninitialised values)
        allocate (xm(n), xk(n), xd(n), zm(n), zk(n), zd(n))
        xm = rhs(n, 1)
        xk = xm
        xd = xm
        zm = cmplx(rhs(n, 2), rhs(n, 3), kind=wp)
        zk = zm
        zd = zm
        call mumps%solve_real(xm)
        call klu%solve_real(xk)
        call dense%solve_real(xd)
        call mumps%solve_complex(zm)
        call klu%solve_complex(zk)
        call zdense%solve_complex(zd)
        call check_close(error, reldiff(xm, xd), 0.0_wp, agree_tol, label // ': real mumps/dense')
        call check_close(error, reldiff(xk, xd), 0.0_wp, agree_tol, label // ': real klu/dense')
        call check_close(error, zreldiff(zm, zd), 0.0_wp, agree_tol, &
            label // ': complex mumps/dense')
        call check_close(error, zreldiff(zk, zd), 0.0_wp, agree_tol, &
            label // ': complex klu/dense')
        call check(error, mumps%name() == 'mumps', label // ': name ' // mumps%name())
        call check(error, mumps%factor_nonzeros() >= mumps%nonzeros(), &
            label // ': factors hold at least the pattern')
    end subroutine check_agreement

    !> A 5 x 5 unsymmetric sparse J (10 entries off the diagonal, no symmetric
    !> partner for most) and an identity M.
    subroutine small_jacobian(jac, status)
        type(matrix_t), intent(out) :: jac
        type(status_t), intent(out) :: status
        integer, parameter :: rows(15) = [1, 2, 3, 4, 5, 2, 4, 1, 5, 3, 1, 4, 2, 5, 3]
        integer, parameter :: cols(15) = [1, 2, 3, 4, 5, 1, 1, 2, 2, 4, 3, 3, 5, 4, 5]
        real(wp), parameter :: vals(15) = [-4.0_wp, -5.0_wp, -3.0_wp, -6.0_wp, -2.0_wp, &
            1.0_wp, 2.0_wp, -1.0_wp, 0.5_wp, 1.5_wp, 0.25_wp, -2.0_wp, 1.0_wp, 3.0_wp, -0.5_wp]
        jac%storage = storage_sparse
        jac%n = 5
        call jac%csc%build(5, 5, rows, cols, status)
        if (status%ok()) call jac%csc%fill(vals)
    end subroutine small_jacobian

    ! ---------------------------------------------------------------- tests

    !> x = (1, -2, 3, -4, 5): b = (c I - J) x by hand-free matvec, then every
    !> solver recovers x.
    subroutine test_small_known(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp), parameter :: x_true(5) = [1.0_wp, -2.0_wp, 3.0_wp, -4.0_wp, 5.0_wp]
        type(matrix_t) :: jac, mass
        type(mumps_solver_t) :: mumps
        type(status_t) :: status
        real(wp) :: jx(5), b(5)
        complex(wp) :: zb(5)

        call small_jacobian(jac, status)
        call check(error, status%ok(), 'build: ' // status%text())
        mass%storage = storage_identity
        mass%n = 5
        call jac%matvec(x_true, jx)
        b = shift * x_true - jx
        zb = zshift * x_true - jx
        call mumps%init(mass, jac, status)
        call mumps%factor_real(shift, mass, jac, status)
        call check(error, status%ok(), 'real factor: ' // status%text())
        call mumps%factor_complex(zshift, mass, jac, status)
        call check(error, status%ok(), 'complex factor: ' // status%text())
        if (allocated(error)) return
        call mumps%solve_real(b)
        call mumps%solve_complex(zb)
        call check_close(error, reldiff(b, x_true), 0.0_wp, agree_tol, 'real solution')
        call check_close(error, zreldiff(zb, cmplx(x_true, 0.0_wp, kind=wp)), 0.0_wp, &
            agree_tol, 'complex solution')
        call check_agreement(error, 'small', mass, jac)
    end subroutine test_small_known

    !> 6 x 6 x 6 nodes, 3 unknowns each (n = 648, 27-point coupling).
    subroutine test_hex8(error)
        type(error_t), allocatable, intent(out) :: error
        call check_node_graph(error, 6, 6, 6, 'hex8 6x6x6')
    end subroutine test_hex8

    !> 2 x 2 x 60 nodes, 3 unknowns each (n = 720).
    subroutine test_slender(error)
        type(error_t), allocatable, intent(out) :: error
        call check_node_graph(error, 2, 2, 60, 'slender 2x2x60')
    end subroutine test_slender

    subroutine check_node_graph(error, nx, ny, nz, label)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: nx, ny, nz
        character(len=*), intent(in) :: label
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        call node_graph_jacobian(nx, ny, nz, 3, jac, status)
        if (status%ok()) call node_graph_mass(jac%n, mass, status)
        call check(error, status%ok(), 'node graph: ' // status%text())
        if (allocated(error)) return
        call check_agreement(error, label, mass, jac)
    end subroutine check_node_graph

    !> New values on the same pattern give the new solution (against dense
    !> LU of the new values), for both the real and the complex factorisation.
    subroutine test_refactor(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: jac, jac2, mass
        type(mumps_solver_t) :: mumps
        type(dense_solver_t) :: dense, zdense
        type(status_t) :: status
        real(wp), allocatable :: x1(:), x2(:), xd(:)
        complex(wp), allocatable :: z2(:), zd(:)

        call node_graph_jacobian(4, 4, 4, 3, jac, status, seed=0)
        if (status%ok()) call node_graph_jacobian(4, 4, 4, 3, jac2, status, seed=7)
        if (status%ok()) call node_graph_mass(jac%n, mass, status)
        call check(error, status%ok(), 'node graph: ' // status%text())
        if (allocated(error)) return
        call mumps%init(mass, jac, status)
        call mumps%factor_real(shift, mass, jac, status)
        allocate (x1(jac%n), x2(jac%n), xd(jac%n)) ! see check_agreement
        x1 = rhs(jac%n, 1)
        call mumps%solve_real(x1)
        call mumps%factor_real(shift, mass, jac2, status)
        call check(error, status%ok(), 'refactor: ' // status%text())
        call mumps%factor_complex(zshift, mass, jac2, status)
        x2 = rhs(jac%n, 1)
        call mumps%solve_real(x2)
        z2 = cmplx(rhs(jac%n, 1), 0.0_wp, kind=wp)
        call mumps%solve_complex(z2)
        call dense%init(mass, jac2, status)
        call dense%factor_real(shift, mass, jac2, status)
        xd = rhs(jac%n, 1)
        call dense%solve_real(xd)
        call zdense%init(mass, jac2, status)
        call zdense%factor_complex(zshift, mass, jac2, status)
        zd = cmplx(rhs(jac%n, 1), 0.0_wp, kind=wp)
        call zdense%solve_complex(zd)
        call check_close(error, reldiff(x2, xd), 0.0_wp, agree_tol, 'new real solution')
        call check_close(error, zreldiff(z2, zd), 0.0_wp, agree_tol, 'new complex solution')
        call check(error, reldiff(x1, xd) > 1.0e-3_wp, 'the values did change the solution')
    end subroutine test_refactor

    !> J with two equal rows and no M: c*M - J = -J is singular. Reported as
    !> a solver failure with reason singular matrix and a message that says
    !> so; the solve then gives NaN, never a silent answer.
    subroutine test_singular(error)
        type(error_t), allocatable, intent(out) :: error
        ! column 4 holds slots but only zeros: a zero pivot whatever the scaling
        ! and pivot order (only exact zeros count as null pivots, as in KLU)
        integer, parameter :: rows(10) = [1, 2, 3, 4, 3, 4, 3, 4, 3, 4]
        integer, parameter :: cols(10) = [1, 2, 3, 4, 1, 1, 2, 2, 4, 3]
        real(wp), parameter :: vals(10) = [1.0_wp, 2.0_wp, 3.0_wp, 0.0_wp, 1.0_wp, 1.0_wp, &
            5.0_wp, 5.0_wp, 0.0_wp, 3.0_wp]
        type(matrix_t) :: jac, mass
        type(mumps_solver_t) :: mumps
        type(mumps_real_t) :: lu
        type(status_t) :: status
        real(wp) :: b(4)

        jac%storage = storage_sparse
        jac%n = 4
        call jac%csc%build(4, 4, rows, cols, status)
        call jac%csc%fill(vals)
        mass%storage = storage_none
        mass%n = 4
        call mumps%init(mass, jac, status)
        call check(error, status%ok(), 'init: ' // status%text())
        call mumps%factor_real(0.0_wp, mass, jac, status)
        call check(error, .not. status%ok(), 'singular matrix factored without complaint')
        call check(error, status%code == status_solver_failure .and. &
            status%reason == reason_singular_matrix, 'reason: ' // status%text())
        call check(error, index(status%text(), 'singular') > 0, 'message: ' // status%text())
        b = 1.0_wp
        call mumps%solve_real(b)
        call check(error, all(ieee_is_nan(b)), 'solve after a failed factorisation must give NaN')
        ! The binding alone: a structurally full 2 x 2 with a zero column.
        call lu%analyse(2, [0_i8, 2_i8, 4_i8], [0_i8, 1_i8, 0_i8, 1_i8], status)
        call check(error, status%ok(), 'analyse 2x2: ' // status%text())
        call lu%factor([1.0_wp, 2.0_wp, 0.0_wp, 0.0_wp], status)
        call check(error, status%reason == reason_singular_matrix, '2x2: ' // status%text())
        call check(error, lu%null_pivots() >= 1 .or. index(status%text(), '-10') > 0, &
            '2x2 null pivots reported: ' // status%text())
        call check(error, .not. lu%is_factored(), '2x2: no factorisation alive')
    end subroutine test_singular

    !> MUMPS reports the ordering it used; the ones asked for are honoured
    !> where Debian's sequential build has them (AMD, AMF, QAMD, SCOTCH, PORD);
    !> 'auto' picks one of them.
    subroutine test_orderings(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: asked(5) = [mumps_ordering_amd, mumps_ordering_amf, &
            mumps_ordering_qamd, mumps_ordering_scotch, mumps_ordering_pord]
        type(matrix_t) :: jac, mass
        type(mumps_solver_t) :: mumps
        type(status_t) :: status
        character(len=:), allocatable :: used
        integer :: k

        call node_graph_jacobian(5, 5, 5, 3, jac, status)
        mass%storage = storage_identity
        mass%n = jac%n
        do k = 1, size(asked)
            mumps%ordering = asked(k)
            call mumps%init(mass, jac, status)
            call check(error, status%ok(), 'init ' // mumps_ordering_name(asked(k)) // ': ' &
                // status%text())
            used = mumps%ordering_used()
            call check(error, used == mumps_ordering_name(asked(k)), 'asked ' // &
                mumps_ordering_name(asked(k)) // ', used ' // used)
            call check(error, mumps_ordering_code(used) == asked(k), 'code of ' // used)
        end do
        mumps%ordering = mumps_ordering_auto
        call mumps%init(mass, jac, status)
        used = mumps%ordering_used()
        call check(error, any(used == ['amd   ', 'amf   ', 'qamd  ', 'scotch', 'pord  ', &
            'metis ']), "'auto' used " // used)
        call check(error, mumps_ordering_code('nested') == -1, 'unknown ordering name')
    end subroutine test_orderings

    !> Three right-hand sides at once equal three single solves (real and
    !> complex binding).
    subroutine test_several_rhs(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: jac, mass
        type(mumps_real_t) :: lu
        type(mumps_complex_t) :: zlu
        type(dense_solver_t) :: dense
        type(status_t) :: status
        real(wp), allocatable :: b(:, :), x(:)
        complex(wp), allocatable :: zb(:, :)
        integer(i8), allocatable :: colptr(:), rowind(:)
        integer :: n, k

        call node_graph_jacobian(3, 3, 4, 3, jac, status)
        mass%storage = storage_none
        mass%n = jac%n
        n = jac%n
        ! -J itself on J's own pattern (it has the full diagonal)
        colptr = jac%csc%colptr
        rowind = jac%csc%rowind
        call lu%analyse(n, colptr, rowind, status)
        call zlu%analyse(n, colptr, rowind, status)
        call lu%factor(-jac%csc%values, status)
        call check(error, status%ok(), 'real factor: ' // status%text())
        call zlu%factor(cmplx(-jac%csc%values, 0.0_wp, kind=wp), status)
        call check(error, status%ok(), 'complex factor: ' // status%text())
        allocate (b(n, 3))
        do k = 1, 3
            b(:, k) = rhs(n, k)
        end do
        zb = cmplx(b, -b, kind=wp)
        call lu%solve(b, status)
        call check(error, status%ok(), 'real solve of 3: ' // status%text())
        call zlu%solve(zb, status)
        call check(error, status%ok(), 'complex solve of 3: ' // status%text())
        call dense%init(mass, jac, status)
        call dense%factor_real(0.0_wp, mass, jac, status)
        allocate (x(n)) ! see check_agreement
        do k = 1, 3
            x = rhs(n, k)
            call dense%solve_real(x)
            call check_close(error, reldiff(b(:, k), x), 0.0_wp, agree_tol, 'real column')
            call check_close(error, zreldiff(zb(:, k), cmplx(x, -x, kind=wp)), 0.0_wp, &
                agree_tol, 'complex column')
        end do
    end subroutine test_several_rhs

    !> With error analysis on, a well-conditioned system has backward errors
    !> near round-off and 0 < rcond <= 1; without it nothing is claimed.
    subroutine test_error_analysis(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: jac
        type(mumps_real_t) :: lu
        type(mumps_accuracy_t) :: acc
        type(status_t) :: status
        real(wp), allocatable :: x(:)

        call node_graph_jacobian(3, 3, 3, 3, jac, status)
        call lu%configure(status, error_analysis=.true.)
        call lu%analyse(jac%n, jac%csc%colptr, jac%csc%rowind, status)
        call lu%factor(-jac%csc%values, status)
        allocate (x(jac%n)) ! see check_agreement
        x = rhs(jac%n, 1)
        call lu%solve(x, status)
        call check(error, status%ok(), 'solve: ' // status%text())
        acc = lu%accuracy()
        call check(error, acc%available, 'estimates available')
        call check(error, acc%omega1 + acc%omega2 < 100 * uround_wp, 'backward error')
        call check(error, acc%rcond > 0.0_wp .and. acc%rcond <= 1.0_wp, 'rcond in (0, 1]')
        call check(error, acc%cond1 < 1.0e3_wp, 'a diagonally dominant matrix is well ' // &
            'conditioned')
        call lu%configure(status, error_analysis=.false.)
        call lu%analyse(jac%n, jac%csc%colptr, jac%csc%rowind, status)
        call lu%factor(-jac%csc%values, status)
        call lu%solve(x, status)
        acc = lu%accuracy()
        call check(error, .not. acc%available, 'no estimates without error analysis')
    end subroutine test_error_analysis

    !> A workspace WK_USER far below MUMPS's estimate grows on error -9 until
    !> the factorisation fits (real and complex), then stays: refactoring
    !> reuses it. The solutions agree with dense LU.
    subroutine test_workspace(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: jac, mass
        type(mumps_real_t) :: lu
        type(mumps_complex_t) :: zlu
        type(dense_solver_t) :: dense
        type(status_t) :: status
        real(wp), allocatable :: x(:), xd(:)
        complex(wp), allocatable :: z(:)
        complex(wp), parameter :: factor = (1.0_wp, 2.0_wp)
        integer(i8) :: grown
        character(len=120) :: msg

        call node_graph_jacobian(5, 5, 5, 3, jac, status, seed=3)
        if (status%ok()) call node_graph_mass(jac%n, mass, status)
        if (status%ok()) call dense%init(mass, jac, status)
        if (status%ok()) call dense%factor_real(0.0_wp, mass, jac, status)
        call check(error, status%ok(), 'node graph, dense LU of -J: ' // status%text())
        if (allocated(error)) return
        allocate (x(jac%n), xd(jac%n)) ! see check_agreement
        xd = rhs(jac%n, 2)
        call dense%solve_real(xd)

        call lu%configure(status, workspace=1000_i8)
        call lu%analyse(jac%n, jac%csc%colptr, jac%csc%rowind, status)
        call lu%factor(-jac%csc%values, status)
        call check(error, status%ok(), 'real factor from 1000 entries: ' // status%text())
        if (allocated(error)) return
        grown = lu%workspace_entries()
        write (msg, '(a,i0,a,i0)') 'workspace ', grown, ', factor entries ', &
            lu%factor_nonzeros()
        call check(error, grown > 1000 .and. grown >= lu%factor_nonzeros(), trim(msg))
        call lu%factor(-2.0_wp * jac%csc%values, status)
        call check(error, status%ok() .and. lu%workspace_entries() == grown, &
            'refactor keeps the workspace: ' // trim(msg))
        x = rhs(jac%n, 2)
        call lu%solve(x, status)
        call check_close(error, reldiff(2.0_wp * x, xd), 0.0_wp, agree_tol, 'real solution')

        call zlu%configure(status, workspace=1000_i8)
        call zlu%analyse(jac%n, jac%csc%colptr, jac%csc%rowind, status)
        call zlu%factor(-factor * jac%csc%values, status)
        call check(error, status%ok() .and. zlu%workspace_entries() > 1000, &
            'complex factor from 1000 entries: ' // status%text())
        z = cmplx(rhs(jac%n, 2), 0.0_wp, kind=wp)
        call zlu%solve(z, status)
        call check_close(error, zreldiff(factor * z, cmplx(xd, 0.0_wp, kind=wp)), 0.0_wp, &
            agree_tol, 'complex solution')
    end subroutine test_workspace

    !> Misuse gives bad-input statuses naming what is wrong.
    subroutine test_misuse(error)
        type(error_t), allocatable, intent(out) :: error
        type(mumps_real_t) :: lu, copy
        type(status_t) :: status
        real(wp) :: b(2)

        call lu%factor([1.0_wp], status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'analyse') > 0, 'factor before analyse: ' // status%text())
        call lu%analyse(2, [0_i8, 1_i8, 2_i8], [0_i8, 1_i8], status)
        call check(error, status%ok(), 'analyse: ' // status%text())
        b = 1.0_wp
        call lu%solve(b, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), 'factor') > 0, 'solve before factor: ' // status%text())
        call lu%factor([1.0_wp, 2.0_wp, 3.0_wp], status)
        call check(error, index(status%text(), '3 values') > 0, 'values: ' // status%text())
        call lu%configure(status, ordering=1)
        call check(error, status%code == status_bad_input, 'user ordering refused')
        call analyse_bad(error, lu, [0_i8, 1_i8, 2_i8], [0_i8, 5_i8], 'row 5 of 2')
        call lu%analyse(2, [0_i8, 1_i8, 2_i8], [0_i8, 1_i8], status)
        call lu%factor([2.0_wp, 4.0_wp], status)
        copy = lu
        call check(error, .not. copy%is_analysed(), 'a copy owns no MUMPS instance')
        b = [2.0_wp, 4.0_wp]
        call lu%solve(b, status)
        call check_close(error, maxval(abs(b - 1.0_wp)), 0.0_wp, agree_tol, &
            'the original still solves after being copied')
    end subroutine test_misuse

    subroutine analyse_bad(error, lu, colptr, rowind, label)
        type(error_t), allocatable, intent(inout) :: error
        type(mumps_real_t), intent(inout) :: lu
        integer(i8), intent(in) :: colptr(:), rowind(:)
        character(len=*), intent(in) :: label
        type(status_t) :: status
        call lu%analyse(size(colptr) - 1, colptr, rowind, status)
        call check(error, status%code == status_bad_input, label // ': ' // status%text())
    end subroutine analyse_bad

    !> 'auto' picks MUMPS on a 3-D node graph and KLU on a slender one of the
    !> same order; 'mumps' by name; the names listed in the message.
    subroutine test_auto(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: cube, slender, mass
        class(linear_solver_t), allocatable :: solver
        type(status_t) :: status
        real(wp) :: fill_cube, fill_slender
        character(len=80) :: msg

        ! 15 x 15 x 15 and 3 x 5 x 225 nodes: n = 10125 each
        call node_graph_jacobian(15, 15, 15, 3, cube, status)
        if (status%ok()) call node_graph_jacobian(3, 5, 225, 3, slender, status)
        call check(error, status%ok(), 'node graphs: ' // status%text())
        if (allocated(error)) return
        call check(error, cube%n == slender%n .and. cube%n >= auto_mumps_min_order, &
            'equal orders above auto_mumps_min_order')
        call predicted_fill_ratio(cube, fill_cube, status)
        call predicted_fill_ratio(slender, fill_slender, status)
        write (msg, '(a,f0.1,a,f0.1)') 'fill cube ', fill_cube, ', slender ', fill_slender
        call check(error, fill_cube >= auto_mumps_min_fill, trim(msg))
        call check(error, fill_slender < auto_mumps_min_fill, trim(msg))
        mass%storage = storage_identity
        mass%n = cube%n
        call new_linear_solver('auto', cube%n, storage_sparse, solver, status, mass=mass, &
            jac=cube)
        call check(error, status%ok() .and. solver%name() == 'mumps', "3-D: 'auto' chose " // &
            solver%name())
        call new_linear_solver('auto', slender%n, storage_sparse, solver, status, jac=slender)
        call check(error, status%ok() .and. solver%name() == 'klu', "slender: 'auto' chose " &
            // solver%name())
        ! without the pattern 'auto' keeps KLU
        call new_linear_solver('auto', cube%n, storage_sparse, solver, status)
        call check(error, solver%name() == 'klu', "no pattern: 'auto' chose " // solver%name())
        call new_linear_solver('mumps', 100, storage_sparse, solver, status)
        call check(error, status%ok() .and. solver%name() == 'mumps', "'mumps' by name")
        call new_linear_solver('mumps', 100, storage_none, solver, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), "'mumps'") > 0, 'mumps without J: ' // status%text())
        call new_linear_solver('superlu', 100, storage_sparse, solver, status)
        call check(error, index(status%text(), "'mumps'") > 0, 'names: ' // status%text())
    end subroutine test_auto
end module test_mumps
