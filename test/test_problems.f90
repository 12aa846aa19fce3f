!> Reference problems: analytic Jacobians against central differences,
!> sparse against dense, consistent initial values, invariants, and the
!> pendulum's reference solution.
module test_problems
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_problems_robertson, only: robertson_t, new_robertson, robertson_initial, &
        robertson_k2
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_reference, pendulum_position_residual, pendulum_velocity_residual, &
        pendulum_angle_exact, pendulum_angle_rk4, pendulum_mechanical_t, &
        new_pendulum_mechanical, pendulum_mechanical_initial, pendulum_index1, &
        pendulum_index2, pendulum_index3, pendulum_ggl
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_problems, fill_random

    ! Central differences of quadratic or cubic F are exact up to rounding;
    ! the tolerance covers the rounding of the difference quotient.
    real(wp), parameter :: fd_step = 1.0e-5_wp
    real(wp), parameter :: fd_rtol = 1.0e-6_wp
    integer, parameter :: formulations(4) = [pendulum_index3, pendulum_index2, &
                                             pendulum_index1, pendulum_ggl]
    character(len=*), parameter :: formulation_names(4) = ['index 3', 'index 2', &
                                                           'index 1', 'GGL    ']

contains

    function collect_problems() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('robertson_jacobian_fd', test_robertson_jacobian_fd), &
                 new_test('robertson_sparse_equals_dense', test_robertson_sparse_dense), &
                 new_test('robertson_conservation', test_robertson_conservation), &
                 new_test('pendulum_jacobian_fd', test_pendulum_jacobian_fd), &
                 new_test('pendulum_sparse_equals_dense', test_pendulum_sparse_dense), &
                 new_test('pendulum_structure', test_pendulum_structure), &
                 new_test('pendulum_initial_consistent', test_pendulum_initial), &
                 new_test('pendulum_consistent_initial_projects', test_pendulum_consistent), &
                 new_test('pendulum_mechanical_matches_dae', test_pendulum_mechanical), &
                 new_test('pendulum_reference_energy', test_pendulum_energy), &
                 new_test('pendulum_reference_vs_rk4', test_pendulum_rk4), &
                 new_test('pendulum_reference_solves_dae', test_pendulum_reference_dae), &
                 new_test('reaction_diffusion_jacobian_fd', test_rd_jacobian_fd), &
                 new_test('reaction_diffusion_sparse_equals_dense', test_rd_sparse_dense), &
                 new_test('reaction_diffusion_stencil', test_rd_stencil), &
                 new_test('reaction_diffusion_large_jv', test_rd_large), &
                 new_test('reaction_diffusion_bad_input', test_rd_bad_input)]
    end function collect_problems

    ! ------------------------------------------------------------------ helpers

    !> Uniform pseudo-random numbers in [lo, hi) (64-bit LCG, Knuth's MMIX
    !> constants), reproducible without touching the intrinsic generator.
    subroutine fill_random(x, seed, lo, hi)
        real(wp), intent(out) :: x(:)
        integer(i8), intent(inout) :: seed
        real(wp), intent(in) :: lo, hi
        integer :: i
        do i = 1, size(x)
            seed = seed * 6364136223846793005_i8 + 1442695040888963407_i8
            x(i) = lo + (hi - lo) * real(ishft(seed, -11), wp) / 2.0_wp**53
        end do
    end subroutine fill_random

    !> Central-difference Jacobian of F.
    subroutine fd_jacobian(problem, t, y, jac)
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        real(wp), allocatable :: yh(:), fp(:), fm(:)
        type(status_t) :: status
        real(wp) :: h
        integer :: j
        allocate (yh(size(y)), fp(size(y)), fm(size(y)))
        do j = 1, size(y)
            h = fd_step * max(1.0_wp, abs(y(j)))
            yh = y
            yh(j) = y(j) + h
            call problem%rhs(t, yh, fp, status)
            yh(j) = y(j) - h
            call problem%rhs(t, yh, fm, status)
            jac(:, j) = (fp - fm) / (2.0_wp * h)
        end do
    end subroutine fd_jacobian

    !> |a - b| <= rtol * (largest |b| in the row), entry by entry.
    subroutine check_rowwise(error, a, b, rtol, label)
        type(error_t), allocatable, intent(inout) :: error
        real(wp), intent(in) :: a(:, :), b(:, :), rtol
        character(len=*), intent(in) :: label
        integer :: i, j
        real(wp) :: scale
        character(len=200) :: msg
        do i = 1, size(a, 1)
            scale = max(maxval(abs(b(i, :))), tiny(1.0_wp))
            do j = 1, size(a, 2)
                if (.not. abs(a(i, j) - b(i, j)) <= rtol * scale) then
                    write (msg, '(a,i0,a,i0,a,es12.4,a,es12.4)') ': entry (', i, ',', j, &
                        ') analytic ', a(i, j), ' differences ', b(i, j)
                    call check(error, .false., label // trim(msg))
                    return
                end if
            end do
        end do
    end subroutine check_rowwise

    !> Dense and sparse analytic Jacobians against central differences.
    subroutine check_jacobian_fd(error, problem, t, y, label)
        type(error_t), allocatable, intent(inout) :: error
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, y(:)
        character(len=*), intent(in) :: label
        real(wp), allocatable :: jac(:, :), jfd(:, :), jsp(:, :)
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        integer :: n
        n = problem%n
        allocate (jac(n, n), jfd(n, n), jsp(n, n))
        call fd_jacobian(problem, t, y, jfd)
        call problem%jacobian_dense(t, y, jac, status)
        call check(error, status%ok(), label // ': dense Jacobian: ' // status%text())
        call check_rowwise(error, jac, jfd, fd_rtol, label // ' dense')
        call problem%jacobian_pattern(pattern, status)
        call check(error, status%ok(), label // ': pattern: ' // status%text())
        if (allocated(error)) return
        call problem%jacobian_sparse(t, y, pattern%values, status)
        call check(error, status%ok(), label // ': sparse Jacobian: ' // status%text())
        call pattern%to_dense(jsp)
        call check_rowwise(error, jsp, jfd, fd_rtol, label // ' sparse')
    end subroutine check_jacobian_fd

    !> The sparse Jacobian is bit for bit the dense one; M likewise.
    subroutine check_sparse_dense(error, problem, t, y, label, check_mass)
        type(error_t), allocatable, intent(inout) :: error
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, y(:)
        character(len=*), intent(in) :: label
        logical, intent(in) :: check_mass
        real(wp), allocatable :: jac(:, :), jsp(:, :)
        type(csc_matrix_t) :: pattern, mass
        type(status_t) :: status
        integer :: n
        n = problem%n
        allocate (jac(n, n), jsp(n, n))
        call problem%jacobian_dense(t, y, jac, status)
        call problem%jacobian_pattern(pattern, status)
        call check(error, status%ok(), label // ': pattern: ' // status%text())
        if (allocated(error)) return
        call check(error, pattern%nrow == n .and. pattern%ncol == n, label // ': pattern shape')
        call problem%jacobian_sparse(t, y, pattern%values, status)
        call pattern%to_dense(jsp)
        call check(error, all(jsp == jac), label // ': sparse and dense Jacobians differ')
        if (.not. check_mass) return
        call problem%mass_dense(jac)
        call problem%mass_sparse(mass, status)
        call check(error, status%ok(), label // ': sparse mass: ' // status%text())
        if (allocated(error)) return
        call mass%to_dense(jsp)
        call check(error, all(jsp == jac), label // ': sparse and dense mass matrices differ')
    end subroutine check_sparse_dense

    ! ---------------------------------------------------------------- Robertson

    subroutine test_robertson_jacobian_fd(error)
        type(error_t), allocatable, intent(out) :: error
        type(robertson_t) :: problem
        real(wp) :: y(3)
        integer(i8) :: seed
        integer :: trial
        problem = new_robertson(sparse=.true.)
        seed = 11
        do trial = 1, 5
            call fill_random(y, seed, 0.0_wp, 1.0_wp)
            call check_jacobian_fd(error, problem, 0.0_wp, y, 'robertson')
        end do
    end subroutine test_robertson_jacobian_fd

    subroutine test_robertson_sparse_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(robertson_t) :: problem
        real(wp) :: y(3), m(3, 3)
        logical :: flags(3)
        integer :: classes(3)
        integer(i8) :: seed
        integer :: trial
        type(status_t) :: status
        problem = new_robertson(sparse=.true., sparse_mass=.true.)
        call check(error, problem%jacobian_storage() == storage_sparse .and. &
                   problem%mass_storage() == storage_sparse, 'sparse storage requested')
        seed = 12
        do trial = 1, 5
            call fill_random(y, seed, -1.0_wp, 1.0_wp)
            call check_sparse_dense(error, problem, 0.0_wp, y, 'robertson', trial == 1)
        end do
        call problem%mass_dense(m)
        call check(error, all(m == reshape([1, 0, 0, 0, 1, 0, 0, 0, 0], [3, 3]) * 1.0_wp), &
                   'M = diag(1, 1, 0)')
        call problem%differential_flags(flags)
        call check(error, all(flags .eqv. [.true., .true., .false.]), 'differential flags')
        call problem%index_classes(classes)
        call check(error, all(classes == 1), 'index classes all 1')
        problem = new_robertson()
        call check(error, problem%jacobian_storage() == storage_dense .and. &
                   problem%mass_storage() == storage_dense, 'dense storage by default')
        call check(error, status%ok(), 'status')
    end subroutine test_robertson_sparse_dense

    !> Differentiating 0 = y1 + y2 + y3 - 1 gives y3' = -(y1' + y2'), which must
    !> be the ODE's y3' = k2 y2²: F1 + F2 + k2 y2² = 0 for every y.
    subroutine test_robertson_conservation(error)
        type(error_t), allocatable, intent(out) :: error
        type(robertson_t) :: problem
        type(status_t) :: status
        real(wp) :: y(3), yp(3), f(3), scale
        integer(i8) :: seed
        integer :: trial
        problem = new_robertson()
        seed = 13
        do trial = 1, 10
            call fill_random(y, seed, 0.0_wp, 1.0_wp)
            call problem%rhs(0.0_wp, y, f, status)
            scale = robertson_k2 * y(2)**2 + 1.0e4_wp * y(2) * y(3) + 1.0_wp
            call check_close(error, f(1) + f(2) + robertson_k2 * y(2)**2, 0.0_wp, &
                             1.0e-14_wp * scale, 'd/dt (y1 + y2 + y3) of the ODE form')
            ! completed to a consistent point: algebraic residual 0, Σ y' = 0
            call problem%consistent_initial(0.0_wp, y, yp, status)
            call check(error, status%ok(), 'consistent_initial')
            call problem%rhs(0.0_wp, y, f, status)
            call check_close(error, f(3), 0.0_wp, 1.0e-15_wp, 'algebraic residual')
            call check_close(error, sum(yp), 0.0_wp, 1.0e-15_wp * scale, 'sum of y''')
            call check(error, all(yp(1:2) == f(1:2)), 'y'' = F on the differential part')
        end do
        call robertson_initial(problem, y)
        call check(error, all(y == [1.0_wp, 0.0_wp, 0.0_wp]), 'y0 = (1, 0, 0)')
        call problem%rhs(0.0_wp, y, f, status)
        call check(error, all(f == [-0.04_wp, 0.04_wp, 0.0_wp]), 'F(y0) = (-k1, k1, 0)')
    end subroutine test_robertson_conservation

    ! ----------------------------------------------------------------- pendulum

    subroutine test_pendulum_jacobian_fd(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        real(wp) :: y(6)
        integer(i8) :: seed
        integer :: f, trial
        seed = 21
        do f = 1, size(formulations)
            problem = new_pendulum(formulations(f), 0.7_wp, mass=1.7_wp, length=0.8_wp, &
                                   gravity=9.81_wp, sparse=.true.)
            do trial = 1, 4
                call fill_random(y, seed, -2.0_wp, 2.0_wp)
                call check_jacobian_fd(error, problem, 0.0_wp, y(:problem%n), &
                                       'pendulum ' // trim(formulation_names(f)))
            end do
        end do
    end subroutine test_pendulum_jacobian_fd

    subroutine test_pendulum_sparse_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp) :: y(6)
        integer(i8) :: seed, k
        integer :: f, trial
        ! structural non-zeros of ∂F/∂y per formulation
        integer, parameter :: expected_nnz(4) = [8, 10, 11, 16]
        seed = 22
        do f = 1, size(formulations)
            problem = new_pendulum(formulations(f), 0.7_wp, mass=1.7_wp, length=0.8_wp, &
                                   sparse=.true., sparse_mass=.true.)
            do trial = 1, 4
                call fill_random(y, seed, -2.0_wp, 2.0_wp)
                call check_sparse_dense(error, problem, 0.0_wp, y(:problem%n), &
                                        'pendulum ' // trim(formulation_names(f)), trial == 1)
            end do
            call problem%jacobian_pattern(pattern, status)
            call check(error, pattern%nnz == expected_nnz(f), 'pendulum ' // &
                       trim(formulation_names(f)) // ': number of structural non-zeros')
            ! entries are emitted in slot order: the triplet map is the identity
            call check(error, all(pattern%triplet_map == [(k, k=1_i8, pattern%nnz)]), &
                       'pendulum ' // trim(formulation_names(f)) // ': entries not in CSC order')
        end do
    end subroutine test_pendulum_sparse_dense

    subroutine test_pendulum_structure(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(status_t) :: status
        integer :: classes(6), f
        logical :: flags(6)
        real(wp) :: m(6, 6)
        integer, parameter :: expected(6, 4) = reshape([1, 1, 2, 2, 3, 0, 1, 1, 1, 1, 2, 0, &
                                                        1, 1, 1, 1, 1, 0, 1, 1, 1, 1, 2, 2], &
                                                       [6, 4])
        integer, parameter :: sizes(4) = [5, 5, 5, 6]
        do f = 1, size(formulations)
            problem = new_pendulum(formulations(f), 0.3_wp, mass=2.5_wp, status=status)
            call check(error, status%ok(), 'construction: ' // status%text())
            call check(error, problem%n == sizes(f), trim(formulation_names(f)) // ': n')
            call problem%index_classes(classes(:problem%n))
            call check(error, all(classes(:problem%n) == expected(:problem%n, f)), &
                       trim(formulation_names(f)) // ': index classes')
            call problem%differential_flags(flags(:problem%n))
            call check(error, all(flags(:4)) .and. .not. any(flags(5:problem%n)), &
                       trim(formulation_names(f)) // ': differential flags')
            call problem%mass_dense(m(:problem%n, :problem%n))
            call check(error, m(1, 1) == 1.0_wp .and. m(2, 2) == 1.0_wp .and. &
                       m(3, 3) == 2.5_wp .and. m(4, 4) == 2.5_wp .and. &
                       count(m(:problem%n, :problem%n) /= 0.0_wp) == 4, &
                       trim(formulation_names(f)) // ': M = diag(1, 1, m, m, 0)')
            call check(error, problem%mass_storage() == storage_dense .and. &
                       problem%jacobian_storage() == storage_dense, 'dense by default')
        end do
        problem = new_pendulum(7, 0.3_wp, status=status)
        call check(error, .not. status%ok() .and. problem%n == 0, 'unknown formulation refused')
        problem = new_pendulum(pendulum_index3, 0.3_wp, length=-1.0_wp, status=status)
        call check(error, .not. status%ok(), 'negative length refused')
    end subroutine test_pendulum_structure

    !> pendulum_initial: every constraint of every formulation vanishes and λ
    !> is the acceleration-level multiplier (index-1 residual zero).
    subroutine test_pendulum_initial(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem, index1
        type(status_t) :: status
        real(wp) :: y(6), f(6), f1(5)
        real(wp), parameter :: angles(4) = [0.0_wp, 0.3_wp, -1.2_wp, 2.9_wp]
        integer :: a, k
        do a = 1, size(angles)
            index1 = new_pendulum(pendulum_index1, angles(a), mass=1.3_wp, length=2.0_wp)
            do k = 1, size(formulations)
                problem = new_pendulum(formulations(k), angles(a), mass=1.3_wp, length=2.0_wp)
                call pendulum_initial(problem, y(:problem%n))
                call problem%rhs(0.0_wp, y(:problem%n), f(:problem%n), status)
                call check(error, all(abs(f(5:problem%n)) <= 1.0e-13_wp), &
                           trim(formulation_names(k)) // ': algebraic residuals')
                call check_close(error, pendulum_position_residual(problem, y), 0.0_wp, &
                                 1.0e-14_wp, 'position constraint')
                call check_close(error, pendulum_velocity_residual(problem, y), 0.0_wp, &
                                 1.0e-14_wp, 'velocity constraint')
                call index1%rhs(0.0_wp, y(:5), f1, status)
                call check_close(error, f1(5), 0.0_wp, 1.0e-13_wp, &
                                 'acceleration-level constraint (λ consistent)')
                call check_close(error, y(5), 1.3_wp * 9.81_wp * cos(angles(a)) / 2.0_wp, &
                                 1.0e-14_wp, 'λ = m g cos φ0 / L', rel=.true.)
                if (problem%n == 6) call check(error, y(6) == 0.0_wp, 'μ = 0')
            end do
        end do
    end subroutine test_pendulum_initial

    !> consistent_initial projects a perturbed state onto both constraints,
    !> fixes λ, and returns y' with M y' = F on the differential part.
    subroutine test_pendulum_consistent(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(status_t) :: status
        real(wp) :: y(6), yp(6), f(6), m(6, 6), y2(6), yp2(6)
        integer(i8) :: seed
        integer :: k, n
        seed = 23
        do k = 1, size(formulations)
            problem = new_pendulum(formulations(k), 1.0_wp, mass=0.6_wp, length=1.5_wp)
            n = problem%n
            call fill_random(y, seed, -1.0_wp, 1.0_wp)
            call problem%consistent_initial(0.0_wp, y(:n), yp(:n), status)
            call check(error, status%ok(), 'consistent_initial: ' // status%text())
            call problem%rhs(0.0_wp, y(:n), f(:n), status)
            call check(error, all(abs(f(5:n)) <= 1.0e-13_wp), &
                       trim(formulation_names(k)) // ': algebraic residuals after projection')
            call problem%mass_dense(m(:n, :n))
            call check(error, all(abs(matmul(m(:4, :n), yp(:n)) - f(:4)) <= 1.0e-14_wp), &
                       trim(formulation_names(k)) // ': M y'' = F')
            ! a consistent state stays put
            y2(:n) = y(:n)
            call problem%consistent_initial(0.0_wp, y2(:n), yp2(:n), status)
            call check(error, all(abs(y2(:n) - y(:n)) <= 1.0e-14_wp), 'idempotent')
        end do
        y = 0.0_wp
        call problem%consistent_initial(0.0_wp, y(:n), yp(:n), status)
        call check(error, .not. status%ok(), 'q = 0 refused')
    end subroutine test_pendulum_consistent

    !> The mechanical form assembled by hand into each formulation gives the
    !> same F as the dae_problem_t written directly.
    subroutine test_pendulum_mechanical(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(pendulum_mechanical_t) :: mech
        type(status_t) :: status
        real(wp) :: y(6), f(6), expect(6), qdot(2), force(2), g(1), gmat(1, 2), gamma(1), &
                    mm(2, 2), acc(2), q(2), v(2), lambda(1)
        integer(i8) :: seed
        integer :: k, trial, n
        real(wp), parameter :: mass = 1.9_wp, length = 0.7_wp, gravity = 3.5_wp
        mech = new_pendulum_mechanical(mass, length, gravity, status)
        call check(error, status%ok() .and. mech%nq == 2 .and. mech%nv == 2 .and. &
                   mech%nc == 1, 'mechanical sizes')
        seed = 24
        do k = 1, size(formulations)
            problem = new_pendulum(formulations(k), 0.0_wp, mass, length, gravity)
            n = problem%n
            do trial = 1, 3
                call fill_random(y, seed, -1.5_wp, 1.5_wp)
                call problem%rhs(0.0_wp, y(:n), f(:n), status)
                q = y(1:2)
                v = y(3:4)
                call mech%kinematics(0.0_wp, q, v, qdot, status)
                call mech%mass(0.0_wp, q, mm, status)
                call mech%forces(0.0_wp, q, v, force, status)
                call mech%constraint(0.0_wp, q, g, status)
                call mech%constraint_jacobian(0.0_wp, q, gmat, status)
                call mech%constraint_curvature(0.0_wp, q, v, gamma, status)
                call check(error, status%ok(), 'mechanical callbacks')
                ! q' = T v [- Gᵀμ];  M v' = f - Gᵀλ  (DAE rows carry M v')
                expect(1:2) = qdot
                if (n == 6) expect(1:2) = qdot - gmat(1, :) * y(6)
                expect(3:4) = force - gmat(1, :) * y(5)
                select case (formulations(k))
                case (pendulum_index3)
                    expect(5) = g(1)
                case (pendulum_index2)
                    expect(5) = dot_product(gmat(1, :), v)
                case (pendulum_index1)
                    ! G a + γ with a = M⁻¹ (f - Gᵀλ), M = m I
                    acc = expect(3:4) / mm(1, 1)
                    expect(5) = dot_product(gmat(1, :), acc) + gamma(1)
                case (pendulum_ggl)
                    expect(5) = dot_product(gmat(1, :), v)
                    expect(6) = g(1)
                end select
                call check(error, all(abs(f(:n) - expect(:n)) <= 1.0e-13_wp), &
                           trim(formulation_names(k)) // ': mechanical and DAE forms differ')
                call check(error, mm(1, 2) == 0.0_wp .and. mm(2, 2) == mass, 'M = m I')
            end do
        end do
        ! consistent initial values agree too
        problem = new_pendulum(pendulum_index3, 0.8_wp, mass, length, gravity)
        call pendulum_initial(problem, y(:5))
        call pendulum_mechanical_initial(mech, 0.8_wp, q, v, lambda)
        call check(error, all(abs([q, v, lambda] - y(:5)) <= 1.0e-15_wp), 'initial values')
    end subroutine test_pendulum_mechanical

    !> The elliptic-function reference conserves energy and both constraints.
    subroutine test_pendulum_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(status_t) :: status
        real(wp) :: y(5), e0, e, t
        real(wp), parameter :: angles(4) = [0.2_wp, -1.0_wp, 2.0_wp, 3.0_wp]
        real(wp), parameter :: mass = 1.0_wp, length = 1.0_wp, gravity = 9.81_wp
        integer :: a, i
        do a = 1, size(angles)
            problem = new_pendulum(pendulum_index3, angles(a), mass, length, gravity)
            call pendulum_reference(problem, 0.0_wp, y, status)
            call check(error, status%ok(), 'reference: ' // status%text())
            call check_close(error, y(1), length * sin(angles(a)), 1.0e-15_wp, 'x(0)')
            call check_close(error, y(3), 0.0_wp, 1.0e-14_wp, 'u(0)')
            e0 = 0.5_wp * mass * (y(3)**2 + y(4)**2) + mass * gravity * y(2)
            do i = 1, 60
                t = 0.37_wp * i
                call pendulum_reference(problem, t, y, status)
                e = 0.5_wp * mass * (y(3)**2 + y(4)**2) + mass * gravity * y(2)
                call check_close(error, e, e0, 1.0e-12_wp * mass * gravity * length, &
                                 'energy conserved')
                call check_close(error, pendulum_position_residual(problem, y), 0.0_wp, &
                                 1.0e-15_wp, 'reference on the circle')
                call check_close(error, pendulum_velocity_residual(problem, y), 0.0_wp, &
                                 1.0e-14_wp, 'reference tangent to the circle')
            end do
        end do
        call pendulum_angle_exact(3.5_wp, 1.0_wp, 1.0_wp, e, e0, status)
        call check(error, .not. status%ok(), 'rotation (|phi0| >= pi) refused')
    end subroutine test_pendulum_energy

    !> The elliptic-function solution against fixed-step RK4 with small steps.
    subroutine test_pendulum_rk4(error)
        type(error_t), allocatable, intent(out) :: error
        type(status_t) :: status
        real(wp) :: phi, dphi, phi_rk, dphi_rk, omega
        real(wp), parameter :: angles(3) = [0.5_wp, -2.0_wp, 3.0_wp]
        real(wp), parameter :: times(3) = [0.7_wp, 2.3_wp, 5.0_wp]
        real(wp), parameter :: h = 2.0e-4_wp
        integer :: a, i
        omega = sqrt(9.81_wp)
        do a = 1, size(angles)
            do i = 1, size(times)
                call pendulum_angle_exact(angles(a), omega, times(i), phi, dphi, status)
                call check(error, status%ok(), 'exact: ' // status%text())
                call pendulum_angle_rk4(angles(a), 0.0_wp, omega, times(i), &
                                        nint(times(i) / h), phi_rk, dphi_rk)
                call check_close(error, phi, phi_rk, 1.0e-9_wp, 'φ exact vs RK4')
                call check_close(error, dphi, dphi_rk, 1.0e-9_wp * omega, 'φ'' exact vs RK4')
            end do
        end do
        ! negative time runs the motion backwards (even in t from rest)
        call pendulum_angle_exact(1.0_wp, omega, -1.1_wp, phi, dphi, status)
        call pendulum_angle_exact(1.0_wp, omega, 1.1_wp, phi_rk, dphi_rk, status)
        call check_close(error, phi, phi_rk, 1.0e-14_wp, 'φ(-t) = φ(t)')
        call check_close(error, dphi, -dphi_rk, 1.0e-13_wp, 'φ''(-t) = -φ''(t)')
    end subroutine test_pendulum_rk4

    !> The reference trajectory satisfies M y' = F (y' by central differences
    !> in time) and consistent_initial's λ' matches dλ/dt.
    subroutine test_pendulum_reference_dae(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(status_t) :: status
        real(wp) :: y(5), yp(5), yplus(5), yminus(5), ydot(5), f(5), m(5, 5)
        real(wp), parameter :: ht = 1.0e-4_wp
        real(wp), parameter :: times(3) = [0.3_wp, 1.7_wp, 4.4_wp]
        integer :: i
        problem = new_pendulum(pendulum_index3, 1.9_wp, mass=0.8_wp, length=1.2_wp)
        call problem%mass_dense(m)
        do i = 1, size(times)
            call pendulum_reference(problem, times(i), y, status)
            call pendulum_reference(problem, times(i) + ht, yplus, status)
            call pendulum_reference(problem, times(i) - ht, yminus, status)
            ! fourth-order central difference would be overkill: O(ht²) ~ 1e-7
            ydot = (yplus - yminus) / (2.0_wp * ht)
            call problem%rhs(times(i), y, f, status)
            call check(error, all(abs(matmul(m(:4, :), ydot) - f(:4)) <= 1.0e-6_wp), &
                       'reference solves M y'' = F')
            call problem%consistent_initial(times(i), y, yp, status)
            call check_close(error, yp(5), ydot(5), 1.0e-6_wp * max(1.0_wp, abs(ydot(5))), &
                             'λ'' of consistent_initial')
            call check(error, all(abs(yp(:4) - ydot(:4)) <= 1.0e-6_wp), 'y'' of q and v')
        end do
    end subroutine test_pendulum_reference_dae

    ! ------------------------------------------------------- reaction-diffusion

    subroutine test_rd_jacobian_fd(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(status_t) :: status
        real(wp), allocatable :: y(:)
        integer(i8) :: seed
        integer :: c
        integer, parameter :: dims(5) = [1, 1, 2, 2, 2], points(5) = [1, 5, 1, 2, 4]
        character(len=40) :: label
        seed = 31
        do c = 1, size(dims)
            problem = new_reaction_diffusion(dims(c), points(c), status=status)
            call check(error, status%ok(), 'construction: ' // status%text())
            write (label, '(a,i0,a,i0)') 'brusselator ', dims(c), '-D N=', points(c)
            if (allocated(y)) deallocate (y)
            allocate (y(problem%n))
            call fill_random(y, seed, 0.0_wp, 4.0_wp)
            call check_jacobian_fd(error, problem, 0.0_wp, y, trim(label))
            call reaction_diffusion_initial(problem, y)
            call check_jacobian_fd(error, problem, 0.0_wp, y, trim(label) // ' at y0')
        end do
    end subroutine test_rd_jacobian_fd

    subroutine test_rd_sparse_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), allocatable :: y(:)
        integer(i8) :: seed
        integer :: c
        integer, parameter :: dims(6) = [1, 1, 2, 2, 2, 2], points(6) = [1, 7, 1, 2, 3, 5]
        ! structural non-zeros: 1-D 4N + 4(N-1); 2-D periodic 12 N² for N >= 3,
        ! 8 N² for N = 2 (W = E and S = N share slots), 4 for N = 1
        integer, parameter :: expected_nnz(6) = [4, 52, 4, 32, 108, 300]
        character(len=40) :: label
        seed = 32
        do c = 1, size(dims)
            problem = new_reaction_diffusion(dims(c), points(c), sparse=.false.)
            call check(error, problem%jacobian_storage() == storage_dense, 'dense requested')
            write (label, '(a,i0,a,i0)') 'brusselator ', dims(c), '-D N=', points(c)
            if (allocated(y)) deallocate (y)
            allocate (y(problem%n))
            call fill_random(y, seed, -1.0_wp, 4.0_wp)
            call check_sparse_dense(error, problem, 0.0_wp, y, trim(label), .false.)
            call problem%jacobian_pattern(pattern, status)
            call check(error, pattern%nnz == expected_nnz(c), trim(label) // ': nnz')
        end do
        problem = new_reaction_diffusion(2, 3)
        call check(error, problem%jacobian_storage() == storage_sparse, 'sparse by default')
    end subroutine test_rd_sparse_dense

    !> Homogeneous steady state (A, B/A) gives F = 0 (the 1-D boundary values
    !> are that state); the stencil and initial values at chosen points.
    subroutine test_rd_stencil(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(status_t) :: status
        real(wp), allocatable :: y(:), f(:)
        integer :: p, dim, n
        real(wp) :: c, expected, u, v, x
        real(wp), parameter :: pi = acos(-1.0_wp)
        do dim = 1, 2
            problem = new_reaction_diffusion(dim, 6)
            y = [(problem%a, problem%b / problem%a, p=1, problem%n / 2)]
            allocate (f(problem%n))
            call problem%rhs(0.0_wp, y, f, status)
            call check(error, all(abs(f) <= 1.0e-12_wp), 'steady state')
            deallocate (f)
        end do
        ! 2-D, N = 4: u_p = p², v_p = 0; corner point p = 1 (i = j = 1) has
        ! neighbours W = 4, E = 2, S = 13, N = 5 (periodic)
        problem = new_reaction_diffusion(2, 4)
        n = problem%n
        y = [(real((p + 1) / 2, wp)**2 * merge(1.0_wp, 0.0_wp, mod(p, 2) == 1), p=1, n)]
        allocate (f(n))
        call problem%rhs(0.0_wp, y, f, status)
        c = 0.1_wp * 16.0_wp
        expected = 1.0_wp - 4.4_wp * 1.0_wp + c * (16.0_wp + 4.0_wp + 169.0_wp + 25.0_wp &
                                                   - 4.0_wp * 1.0_wp)
        call check_close(error, f(1), expected, 1.0e-13_wp, '2-D stencil at a corner', &
                         rel=.true.)
        call check_close(error, f(2), 3.4_wp, 1.0e-15_wp, '2-D v at a corner', rel=.true.)
        ! 1-D, N = 3, last point: right neighbour is the boundary u = 1, v = 3
        problem = new_reaction_diffusion(1, 3)
        y = [1.0_wp, 0.0_wp, 2.0_wp, 0.0_wp, 5.0_wp, 0.0_wp]
        deallocate (f)
        allocate (f(6))
        call problem%rhs(0.0_wp, y, f, status)
        c = 16.0_wp / 50.0_wp
        call check_close(error, f(5), 1.0_wp - 4.0_wp * 5.0_wp + c * (2.0_wp - 10.0_wp + &
                         1.0_wp), 1.0e-13_wp, '1-D stencil at the boundary', rel=.true.)
        call check_close(error, f(6), 15.0_wp + c * 3.0_wp, 1.0e-13_wp, &
                         '1-D v at the boundary', rel=.true.)
        ! initial values
        call reaction_diffusion_initial(problem, y)
        x = 2.0_wp / 4.0_wp
        call check_close(error, y(3), 1.0_wp + sin(2.0_wp * pi * x), 1.0e-15_wp, '1-D u0')
        call check(error, all(y(2::2) == 3.0_wp), '1-D v0 = 3')
        problem = new_reaction_diffusion(2, 4)
        deallocate (y)
        allocate (y(problem%n))
        call reaction_diffusion_initial(problem, y)
        ! point i = 2, j = 3: x = 1/4, y = 1/2
        p = 2 + 2 * 4
        u = 22.0_wp * 0.5_wp * 0.5_wp**1.5_wp
        v = 27.0_wp * 0.25_wp * 0.75_wp**1.5_wp
        call check_close(error, y(2 * p - 1), u, 1.0e-14_wp, '2-D u0', rel=.true.)
        call check_close(error, y(2 * p), v, 1.0e-14_wp, '2-D v0', rel=.true.)
    end subroutine test_rd_stencil

    !> Large sizes: the sparse Jacobian times a random vector against a
    !> central directional difference of F.
    subroutine test_rd_large(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), allocatable :: y(:), w(:), fp(:), fm(:), jw(:), fd(:)
        integer(i8) :: seed
        integer :: c, n
        integer, parameter :: dims(2) = [1, 2], points(2) = [2000, 60]
        real(wp), parameter :: h = 1.0e-6_wp
        seed = 33
        do c = 1, 2
            problem = new_reaction_diffusion(dims(c), points(c), status=status)
            call check(error, status%ok(), 'construction')
            n = problem%n
            if (allocated(y)) deallocate (y, w, fp, fm, jw, fd)
            allocate (y(n), w(n), fp(n), fm(n), jw(n), fd(n))
            call reaction_diffusion_initial(problem, y)
            call fill_random(w, seed, -1.0_wp, 1.0_wp)
            call problem%jacobian_pattern(pattern, status)
            call problem%jacobian_sparse(0.0_wp, y, pattern%values, status)
            call check(error, status%ok(), 'sparse Jacobian: ' // status%text())
            call pattern%matvec(w, jw)
            call problem%rhs(0.0_wp, y + h * w, fp, status)
            call problem%rhs(0.0_wp, y - h * w, fm, status)
            fd = (fp - fm) / (2.0_wp * h)
            call check(error, maxval(abs(jw - fd)) <= 1.0e-6_wp * maxval(abs(jw)), &
                       'J w against directional differences')
            ! refilling reuses the pattern's storage (no reallocation)
            call problem%jacobian_sparse(0.0_wp, y + w, pattern%values, status)
            call check(error, status%ok() .and. size(pattern%values, kind=i8) == &
                       pattern%nnz, 'refill')
        end do
    end subroutine test_rd_large

    subroutine test_rd_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(status_t) :: status
        real(wp) :: values(3)
        integer :: i
        problem = new_reaction_diffusion(3, 10, status=status)
        call check(error, .not. status%ok() .and. problem%n == 0, 'dim = 3 refused')
        problem = new_reaction_diffusion(1, 0, status=status)
        call check(error, .not. status%ok() .and. problem%n == 0, 'npoints = 0 refused')
        problem = new_reaction_diffusion(1, 4, status=status)
        call check(error, status%ok(), 'valid problem')
        call problem%jacobian_sparse(0.0_wp, [(1.0_wp, i=1, 8)], values, status)
        call check(error, .not. status%ok(), 'wrong values size refused')
    end subroutine test_rd_bad_input
end module test_problems
