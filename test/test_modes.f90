!> Eigen-analysis (`flexmbs modes`): the finite eigenvalues of the pencil
!> (∂F/∂y, M) by dense QZ (linalg/generalized_eigen) and by ARPACK in
!> shift-invert form (linalg/arpack), on systems whose eigenvalues are
!> known: an undamped spring–mass chain (exact), the pendulum's small
!> oscillation, a hex8 cantilever against Euler–Bernoulli; and the analysis
!> of run/modes (infinite and zero eigenvalues, the counts the formulations
!> should give, the BDF sector check).
module test_modes
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_sparse
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_linalg_generalized_eigen, only: pencil_eigenvalues
    use flexmbs_linalg_arpack, only: shift_invert_eigenvalues
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_linearisation, only: linearise
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_index2
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_core_text, only: int_text
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene
    use flexmbs_run_modes, only: modes_options_t, modes_result_t, analyse_modes, &
        stiff_outside, median, sort_by_modulus
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_modes

    real(wp), parameter :: pi = acos(-1.0_wp)
    !> The cantilever: 1 m long, 5 cm square, E = 1 MPa, ρ = 1000 kg/m³, ν = 0
    real(wp), parameter :: beam_length = 1.0_wp, beam_width = 0.05_wp
    real(wp), parameter :: beam_youngs = 1.0e6_wp, beam_density = 1000.0_wp

    !> N equal masses m on a line joined by N + 1 equal springs k, both ends
    !> fixed, undamped: y = (x, v), M = diag(I, m I), F = (v, −K x) with K
    !> the tridiagonal (−k, 2k, −k). Its eigenvalues are ±i ω_j,
    !> ω_j = 2 sqrt(k/m) sin(jπ / (2(N + 1))), j = 1..N.
    type, extends(dae_problem_t) :: spring_chain_t
        integer :: masses = 0
        real(wp) :: mass = 1.0_wp, stiffness = 1.0_wp
        logical :: sparse = .false.
    contains
        procedure :: rhs => chain_rhs
        procedure :: jacobian_storage => chain_jacobian_storage
        procedure :: jacobian_dense => chain_jacobian_dense
        procedure :: jacobian_pattern => chain_jacobian_pattern
        procedure :: jacobian_sparse => chain_jacobian_sparse
        procedure :: mass_storage => chain_mass_storage
        procedure :: mass_dense => chain_mass_dense
        procedure :: mass_sparse => chain_mass_sparse
    end type spring_chain_t

contains

    function collect_modes() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('spring_chain_dense_exact', test_chain_dense), &
                 new_test('spring_chain_arpack_exact', test_chain_arpack), &
                 new_test('pendulum_index2_frequency', test_pendulum), &
                 new_test('arpack_large_chain', test_large_chain), &
                 new_test('cantilever_euler_bernoulli', test_cantilever), &
                 new_test('arpack_against_dense_1920', test_arpack_vs_dense), &
                 new_test('pendulum_formulations_counts', test_pendulum_formulations), &
                 new_test('sector_check', test_sector_check), &
                 new_test('five_body_counts_and_arpack', test_five_body)]
    end function collect_modes

    ! ---------------------------------------------------------------- chain

    function new_spring_chain(masses, mass, stiffness, sparse) result(chain)
        integer, intent(in) :: masses
        real(wp), intent(in) :: mass, stiffness
        logical, intent(in) :: sparse
        type(spring_chain_t) :: chain
        chain%masses = masses
        chain%n = 2 * masses
        chain%mass = mass
        chain%stiffness = stiffness
        chain%sparse = sparse
    end function new_spring_chain

    !> ω_j of the chain.
    pure real(wp) function chain_frequency(chain, j)
        type(spring_chain_t), intent(in) :: chain
        integer, intent(in) :: j
        chain_frequency = 2.0_wp * sqrt(chain%stiffness / chain%mass) * &
            sin(real(j, wp) * pi / real(2 * (chain%masses + 1), wp))
    end function chain_frequency

    subroutine chain_rhs(self, t, y, f, status)
        class(spring_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        integer :: i, n
        real(wp) :: left, right
        n = self%masses
        f(1:n) = y(n + 1:2 * n)
        do i = 1, n
            left = 0.0_wp
            right = 0.0_wp
            if (i > 1) left = y(i - 1)
            if (i < n) right = y(i + 1)
            f(n + i) = self%stiffness * (left - 2.0_wp * y(i) + right)
        end do
    end subroutine chain_rhs

    integer function chain_jacobian_storage(self)
        class(spring_chain_t), intent(in) :: self
        chain_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function chain_jacobian_storage

    subroutine chain_jacobian_dense(self, t, y, jac, status)
        class(spring_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        integer :: i, n
        n = self%masses
        jac = 0.0_wp
        do i = 1, n
            jac(i, n + i) = 1.0_wp
            jac(n + i, i) = -2.0_wp * self%stiffness
            if (i > 1) jac(n + i, i - 1) = self%stiffness
            if (i < n) jac(n + i, i + 1) = self%stiffness
        end do
    end subroutine chain_jacobian_dense

    !> Entries in the order chain_jacobian_sparse fills: per mass i the
    !> coupling to x(i-1), x(i), x(i+1) in row n + i, then row i's 1.
    subroutine chain_entries(self, rows, cols)
        class(spring_chain_t), intent(in) :: self
        integer, allocatable, intent(out) :: rows(:), cols(:)
        integer :: i, n, k
        n = self%masses
        allocate (rows(4 * n), cols(4 * n))
        k = 0
        do i = 1, n
            if (i > 1) call add(n + i, i - 1)
            call add(n + i, i)
            if (i < n) call add(n + i, i + 1)
            call add(i, n + i)
        end do
        rows = rows(1:k)
        cols = cols(1:k)
    contains
        subroutine add(r, c)
            integer, intent(in) :: r, c
            k = k + 1
            rows(k) = r
            cols(k) = c
        end subroutine add
    end subroutine chain_entries

    subroutine chain_jacobian_pattern(self, pattern, status)
        class(spring_chain_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        call chain_entries(self, rows, cols)
        call pattern%build(self%n, self%n, rows, cols, status)
    end subroutine chain_jacobian_pattern

    subroutine chain_jacobian_sparse(self, t, y, values, status)
        class(spring_chain_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        type(csc_matrix_t) :: pattern
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: triplets(:)
        integer :: k
        call chain_entries(self, rows, cols)
        call pattern%build(self%n, self%n, rows, cols, status)
        allocate (triplets(size(rows)))
        do k = 1, size(rows)
            if (rows(k) <= self%masses) then
                triplets(k) = 1.0_wp
            else if (cols(k) == rows(k) - self%masses) then
                triplets(k) = -2.0_wp * self%stiffness
            else
                triplets(k) = self%stiffness
            end if
        end do
        values = 0.0_wp
        do k = 1, size(rows)
            values(pattern%triplet_map(k)) = values(pattern%triplet_map(k)) + triplets(k)
        end do
    end subroutine chain_jacobian_sparse

    integer function chain_mass_storage(self)
        class(spring_chain_t), intent(in) :: self
        chain_mass_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function chain_mass_storage

    subroutine chain_mass_dense(self, m)
        class(spring_chain_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        integer :: i
        m = 0.0_wp
        do i = 1, self%masses
            m(i, i) = 1.0_wp
            m(self%masses + i, self%masses + i) = self%mass
        end do
    end subroutine chain_mass_dense

    subroutine chain_mass_sparse(self, m, status)
        class(spring_chain_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        integer :: i
        call m%build(self%n, self%n, [(i, i=1, self%n)], [(i, i=1, self%n)], status)
        if (.not. status%ok()) return
        m%values(1:self%masses) = 1.0_wp
        m%values(self%masses + 1:) = self%mass
    end subroutine chain_mass_sparse

    ! ------------------------------------------------------------- helpers

    !> Finite eigenvalues of the pencil by dense QZ (β above round-off),
    !> sorted by |λ|.
    subroutine dense_finite(jac, mass, lambda, status)
        type(matrix_t), intent(in) :: jac, mass
        complex(wp), allocatable, intent(out) :: lambda(:)
        type(status_t), intent(out) :: status
        real(wp), allocatable :: a(:, :), b(:, :), beta(:)
        complex(wp), allocatable :: alpha(:)
        allocate (a(jac%n, jac%n), b(jac%n, jac%n))
        call jac%to_dense(a)
        call mass%to_dense(b)
        call pencil_eigenvalues(a, b, alpha, beta, status)
        if (.not. status%ok()) return
        lambda = pack(alpha, beta > 1.0e-12_wp) / pack(beta, beta > 1.0e-12_wp)
        call sort_by_modulus(lambda)
    end subroutine dense_finite

    !> The chain's pencil at rest.
    subroutine chain_pencil(masses, mass, stiffness, sparse, chain, jac, mass_matrix, status)
        integer, intent(in) :: masses
        real(wp), intent(in) :: mass, stiffness
        logical, intent(in) :: sparse
        type(spring_chain_t), intent(out) :: chain
        type(matrix_t), intent(out) :: jac, mass_matrix
        type(status_t), intent(out) :: status
        real(wp), allocatable :: y(:)
        chain = new_spring_chain(masses, mass, stiffness, sparse)
        allocate (y(chain%n), source=0.0_wp)
        call linearise(chain, 0.0_wp, y, jac, mass_matrix, status)
    end subroutine chain_pencil

    !> ARPACK's `count` eigenvalues nearest σ with `solver_name`'s LU.
    subroutine arpack_nearest(jac, mass, sigma, count, solver_name, lambda, status)
        type(matrix_t), intent(in) :: jac, mass
        real(wp), intent(in) :: sigma
        integer, intent(in) :: count
        character(len=*), intent(in) :: solver_name
        complex(wp), allocatable, intent(out) :: lambda(:)
        type(status_t), intent(out) :: status
        class(linear_solver_t), allocatable :: solver
        call new_linear_solver(solver_name, jac%n, jac%storage, solver, status)
        if (.not. status%ok()) return
        call shift_invert_eigenvalues(jac, mass, sigma, count, solver, lambda, status)
        if (status%ok()) call sort_by_modulus(lambda)
    end subroutine arpack_nearest

    !> Every eigenvalue of the chain's list is ±i ω_j: compare the pairs
    !> (sorted by |λ|, the pair of ω_j at 2j − 1 and 2j) to 1e-8 relative.
    subroutine check_chain(error, chain, lambda, pairs, label)
        type(error_t), allocatable, intent(inout) :: error
        type(spring_chain_t), intent(in) :: chain
        complex(wp), intent(in) :: lambda(:)
        integer, intent(in) :: pairs
        character(len=*), intent(in) :: label
        integer :: j
        real(wp) :: omega
        character(len=80) :: what
        call check(error, size(lambda) >= 2 * pairs, label // ': too few eigenvalues')
        if (allocated(error)) return
        do j = 1, pairs
            omega = chain_frequency(chain, j)
            write (what, '(a,a,i0)') label, ': omega_', j
            call check_close(error, abs(aimag(lambda(2 * j - 1))), omega, 1.0e-8_wp, &
                trim(what), rel=.true.)
            call check_close(error, abs(aimag(lambda(2 * j))), omega, 1.0e-8_wp, &
                trim(what), rel=.true.)
            call check(error, abs(real(lambda(2 * j), wp)) <= 1.0e-8_wp * omega .and. &
                aimag(lambda(2 * j - 1)) * aimag(lambda(2 * j)) < 0.0_wp, trim(what) // &
                ': not an undamped conjugate pair')
        end do
    end subroutine check_chain

    ! --------------------------------------------------------------- tests

    !> 30 masses, dense QZ: all 60 eigenvalues ±i ω_j to 1e-8 relative.
    subroutine test_chain_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(spring_chain_t) :: chain
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:)
        call chain_pencil(30, 2.0_wp, 50.0_wp, .false., chain, jac, mass, status)
        if (status%ok()) call dense_finite(jac, mass, lambda, status)
        call check(error, status%ok(), 'dense: ' // status%text())
        if (allocated(error)) return
        call check(error, size(lambda) == chain%n, 'dense: all eigenvalues finite')
        call check_chain(error, chain, lambda, chain%masses, 'dense')
    end subroutine test_chain_dense

    !> 200 masses, sparse, ARPACK with KLU and with MUMPS around σ = 0: the
    !> 10 lowest pairs to 1e-8 relative.
    subroutine test_chain_arpack(error)
        type(error_t), allocatable, intent(out) :: error
        type(spring_chain_t) :: chain
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:)
        call chain_pencil(200, 0.5_wp, 8.0_wp, .true., chain, jac, mass, status)
        if (status%ok()) call arpack_nearest(jac, mass, 0.0_wp, 20, 'klu', lambda, status)
        call check(error, status%ok(), 'arpack klu: ' // status%text())
        if (allocated(error)) return
        call check_chain(error, chain, lambda, 10, 'arpack klu')
        if (allocated(error)) return
        call arpack_nearest(jac, mass, 0.0_wp, 20, 'mumps', lambda, status)
        call check(error, status%ok(), 'arpack mumps: ' // status%text())
        if (allocated(error)) return
        call check_chain(error, chain, lambda, 10, 'arpack mumps')
    end subroutine test_chain_arpack

    !> The index-2 pendulum at rest at its lowest point, L = 0.7 m: the one
    !> oscillating pair ±i sqrt(g/L) to 1e-8 relative, and one zero (the
    !> constant g(q) that G v = 0 keeps); dense and ARPACK (σ = −1).
    subroutine test_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: pendulum
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:)
        real(wp), allocatable :: y(:)
        real(wp) :: omega
        pendulum = new_pendulum(pendulum_index2, 0.0_wp, length=0.7_wp, gravity=9.81_wp, &
                                status=status)
        allocate (y(pendulum%n))
        call pendulum_initial(pendulum, y)
        omega = sqrt(9.81_wp / 0.7_wp)
        call linearise(pendulum, 0.0_wp, y, jac, mass, status)
        if (status%ok()) call dense_finite(jac, mass, lambda, status)
        call check(error, status%ok(), 'dense: ' // status%text())
        if (allocated(error)) return
        call check(error, size(lambda) == 3, 'dense: three finite eigenvalues')
        if (allocated(error)) return
        call check(error, abs(lambda(1)) <= 1.0e-12_wp, 'dense: the drift eigenvalue is 0')
        call check_close(error, abs(aimag(lambda(2))), omega, 1.0e-8_wp, 'dense: omega', &
                         rel=.true.)
        call check_close(error, abs(real(lambda(2), wp)), 0.0_wp, 1.0e-8_wp * omega, &
                         'dense: undamped')
        call arpack_nearest(jac, mass, -1.0_wp, 3, 'dense', lambda, status)
        call check(error, status%ok(), 'arpack: ' // status%text())
        if (allocated(error)) return
        call check(error, size(lambda) == 3, 'arpack: three eigenvalues')
        if (allocated(error)) return
        call check(error, abs(lambda(1)) <= 1.0e-12_wp, 'arpack: the drift eigenvalue is 0')
        call check_close(error, abs(aimag(lambda(3))), omega, 1.0e-8_wp, 'arpack: omega', &
                         rel=.true.)
    end subroutine test_pendulum

    !> ARPACK at n = 10⁴ (5000 masses, KLU, σ = 0): the 5 lowest pairs to
    !> 1e-8 relative.
    subroutine test_large_chain(error)
        type(error_t), allocatable, intent(out) :: error
        type(spring_chain_t) :: chain
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:)
        call chain_pencil(5000, 1.0_wp, 1.0e4_wp, .true., chain, jac, mass, status)
        if (status%ok()) call arpack_nearest(jac, mass, 0.0_wp, 10, 'klu', lambda, status)
        call check(error, status%ok(), 'arpack: ' // status%text())
        if (allocated(error)) return
        call check(error, chain%n >= 10000, 'n >= 1e4')
        call check_chain(error, chain, lambda, 5, 'arpack n = 1e4')
    end subroutine test_large_chain

    !> A hex8 cantilever L x b x b clamped at x = 0 (nodes of 'xmin' removed),
    !> undamped, at rest in its reference state: J and M of the index-2
    !> formulation (nc = 0: y = (q, v), M = diag(I, M_FE)).
    subroutine cantilever_pencil(divisions, jac, mass, status)
        integer, intent(in) :: divisions(3)
        type(matrix_t), intent(out) :: jac, mass
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        type(flexible_body_t), target :: body
        type(formulation_t) :: dae
        integer, allocatable :: fixed(:)
        real(wp), allocatable :: y(:)
        call box_mesh(mesh, hex8, divisions, [beam_length, beam_width, beam_width], status)
        if (status%ok()) call mesh%node_set('xmin', fixed, status)
        if (status%ok()) call new_neo_hooke(material, beam_youngs, 0.0_wp, beam_density, &
                                            0.0_wp, status)
        if (status%ok()) call new_flexible_body(body, mesh, [material], fixed, status)
        if (.not. status%ok()) return
        dae = new_formulation(body, formulation_index2, body%free_positions(), &
                              constant_mass=.true., status=status, sparse=.true.)
        if (.not. status%ok()) return
        allocate (y(dae%n), source=0.0_wp)
        y(1:body%nq) = body%free_positions()
        call linearise(dae, 0.0_wp, y, jac, mass, status)
    end subroutine cantilever_pencil

    !> The lowest bending frequency of three uniformly refined cantilevers
    !> (5 x 1 x 1, 10 x 2 x 2, 20 x 4 x 4 hex8; ARPACK, σ = 0) against
    !> Euler–Bernoulli's ω₁ = 1.875104² sqrt(EI / (ρ A L⁴)). Full-integration
    !> hex8 locks in bending, so coarse meshes are far too stiff; the error
    !> falls with h, by more than 2.5 per halving (measured 1.99, 0.728,
    !> 0.223: ratios 2.7 and 3.3, towards h²), and ends below 0.25.
    subroutine test_cantilever(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: meshes(3, 3) = reshape([5, 1, 1, 10, 2, 2, 20, 4, 4], [3, 3])
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:)
        real(wp) :: omega_eb, err(3)
        character(len=120) :: what
        integer :: m
        omega_eb = 1.875104_wp**2 * sqrt(beam_youngs * beam_width**4 / 12.0_wp / &
            (beam_density * beam_width**2 * beam_length**4))
        do m = 1, 3
            call cantilever_pencil(meshes(:, m), jac, mass, status)
            if (status%ok()) call arpack_nearest(jac, mass, 0.0_wp, 4, 'auto', lambda, status)
            call check(error, status%ok(), 'cantilever: ' // status%text())
            if (allocated(error)) return
            ! the two lowest pairs: bending in y and in z, equal by symmetry
            call check_close(error, abs(lambda(3)), abs(lambda(1)), 1.0e-8_wp, &
                'cantilever: bending in y and z alike', rel=.true.)
            call check(error, abs(real(lambda(1), wp)) <= 1.0e-8_wp * abs(lambda(1)), &
                'cantilever: undamped')
            err(m) = abs(lambda(1)) / omega_eb - 1.0_wp
        end do
        write (what, '(a,3es11.3)') 'cantilever: relative errors ', err
        call check(error, err(1) > 2.5_wp * err(2) .and. err(2) > 2.5_wp * err(3) .and. &
            err(3) > 0.0_wp .and. err(3) < 0.25_wp, trim(what))
    end subroutine test_cantilever

    !> ARPACK (KLU, σ = 0) against dense QZ on the 20 x 3 x 3 cantilever
    !> (1920 unknowns): the 8 lowest eigenvalues to 1e-8 relative.
    subroutine test_arpack_vs_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(matrix_t) :: jac, mass
        type(status_t) :: status
        complex(wp), allocatable :: lambda(:), dense(:)
        integer :: k
        call cantilever_pencil([20, 3, 3], jac, mass, status)
        call check(error, status%ok() .and. jac%n == 1920, 'cantilever 20 x 3 x 3: ' // &
            status%text())
        if (allocated(error)) return
        call arpack_nearest(jac, mass, 0.0_wp, 8, 'klu', lambda, status)
        call check(error, status%ok(), 'arpack: ' // status%text())
        if (allocated(error)) return
        call dense_finite(jac, mass, dense, status)
        call check(error, status%ok(), 'dense: ' // status%text())
        if (allocated(error)) return
        call check(error, size(dense) == jac%n, 'dense: every eigenvalue finite')
        do k = 1, 8
            call check_close(error, abs(lambda(k)), abs(dense(k)), 1.0e-8_wp, &
                'arpack against dense: |lambda| of ' // int_text(k), rel=.true.)
            call check_close(error, abs(aimag(lambda(k))), abs(aimag(dense(k))), &
                1.0e-8_wp * abs(dense(k)), 'arpack against dense: |Im lambda| of ' // &
                int_text(k))
        end do
    end subroutine test_arpack_vs_dense

    ! ------------------------------------------------------------ analysis

    !> The pendulum scene (L = 0.8 m) at rest at the bottom in each
    !> formulation: finite eigenvalues as run/modes expects them — the pair
    !> ±i sqrt(g/L), plus one 0 (index 2) or two (index 1); index 3 and GGL
    !> none — and the rest infinite.
    subroutine test_pendulum_formulations(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: forms(4) = [character(len=6) :: 'index1', 'index2', &
            'index3', 'ggl']
        integer, parameter :: finite(4) = [4, 3, 2, 2]
        type(modes_options_t) :: options
        type(modes_result_t) :: result
        type(status_t) :: status
        integer :: f, i
        options%run_bdf = .false.
        do f = 1, 4
            call analyse_modes(pendulum_scene(forms(f)), options, result, status)
            call check(error, status%ok(), trim(forms(f)) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, result%finite == finite(f) .and. result%expected == finite(f) &
                .and. result%finite + result%infinite == result%n, trim(forms(f)) // &
                ': finite and infinite eigenvalues as expected')
            call check(error, result%modes == 1 .and. count(result%mode == 0) == finite(f) - 2, &
                trim(forms(f)) // ': one mode and the zeros')
            if (allocated(error)) return
            i = result%mode_index(1)
            call check_close(error, aimag(result%lambda(i)), sqrt(9.81_wp / 0.8_wp), 1.0e-8_wp, &
                trim(forms(f)) // ': omega = sqrt(g/L)', rel=.true.)
        end do
    end subroutine test_pendulum_formulations

    !> The sector check on the index-2 pendulum with its DDASSL run: one
    !> entry per accepted step, orders 1..5; the undamped mode (90°) is
    !> outside the sectors of BDF-3..5 and inside those of BDF-1, 2, and
    !> counts only where |h λ| ≥ 1.
    subroutine test_sector_check(error)
        type(error_t), allocatable, intent(out) :: error
        type(modes_options_t) :: options
        type(modes_result_t) :: result
        type(status_t) :: status
        real(wp) :: omega
        integer :: k
        call analyse_modes(pendulum_scene('index2'), options, result, status)
        call check(error, status%ok() .and. result%run_status%ok(), 'analysis: ' // &
            status%text() // result%run_status%text())
        if (allocated(error)) return
        call check(error, result%has_run .and. size(result%h) == result%stats%nac .and. &
            all(result%order >= 1 .and. result%order <= 5) .and. all(result%h > 0.0_wp), &
            'the DDASSL run''s accepted steps and orders')
        omega = sqrt(9.81_wp / 0.8_wp)
        do k = 1, 2
            call check(error, size(stiff_outside(result, k, 10.0_wp / omega)) == 0, &
                'BDF-1, 2: the undamped mode inside the sector')
        end do
        do k = 3, 5
            call check(error, size(stiff_outside(result, k, 2.0_wp / omega)) == 1, &
                'BDF-3..5: stiff and outside at h = 2/omega')
            call check(error, size(stiff_outside(result, k, 0.5_wp / omega)) == 0, &
                'BDF-3..5: not stiff at h = 0.5/omega')
        end do
        call check_close(error, median([3.0_wp, 1.0_wp, 2.0_wp, 10.0_wp]), 2.5_wp, 0.0_wp, &
            'median')
    end subroutine test_sector_check

    !> The five-body scene at t_start in its four formulations (dense QZ):
    !> the finite eigenvalues number 2 x 131 (motion on the manifold) + 4
    !> (quaternion lengths) + n_c = 30 (index 2) or 2 n_c (index 1); ARPACK
    !> around σ = −1 finds the same lowest modes (GGL, 1e-8 relative or
    !> 2e-10 |λ − σ|², the shift-invert's accuracy far from σ).
    subroutine test_five_body(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: forms(4) = [character(len=6) :: 'ggl', 'index1', &
            'index2', 'index3']
        integer, parameter :: finite(4) = [266, 326, 296, 266]
        type(scene_input_t) :: scene
        type(modes_options_t) :: options
        type(modes_result_t) :: dense, arpack
        type(status_t) :: status
        integer :: f, m
        call read_scene('inputs/five_body.nml', scene, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        options%run_bdf = .false.
        do f = 1, 4
            scene%multibody%formulation = forms(f)
            call analyse_modes(scene, options, dense, status)
            call check(error, status%ok(), trim(forms(f)) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, dense%finite == finite(f) .and. dense%expected == finite(f), &
                trim(forms(f)) // ': finite eigenvalues ' // int_text(dense%finite) // &
                ', expected ' // int_text(finite(f)))
        end do
        scene%multibody%formulation = 'ggl'
        call analyse_modes(scene, options, dense, status)
        options%method = 'arpack'
        options%count = 8
        ! shift-invert resolves λ to about ε-relative in 1/(λ − σ): its error in
        ! λ grows like |λ − σ|², and at the default σ = −1 the LU's round-off
        ! decides it (mode 6, |λ − σ| = 137: 2.2e-6 with KLU on the full
        ! matrix, 2.5e-5 with the condensed Newton matrix in the debug build,
        ! 3.9e-6 in the release build); σ = −30 lies among the modes compared
        ! (every LU within 1.5e-7 of the dense QZ there, and 2e-9 of each other)
        options%shift = -30.0_wp
        if (status%ok()) call analyse_modes(scene, options, arpack, status)
        call check(error, status%ok(), 'ggl, arpack: ' // status%text())
        if (allocated(error)) return
        call check(error, arpack%modes >= 8, 'arpack: 8 modes')
        if (allocated(error)) return
        do m = 1, 8
            associate (ld => dense%lambda(dense%mode_index(m)))
                call check_close(error, abs(arpack%lambda(arpack%mode_index(m)) - ld), 0.0_wp, &
                    max(1.0e-8_wp * abs(ld), 2.0e-10_wp * abs(ld - options%shift)**2), &
                    'five-body: arpack against dense, mode ' // int_text(m))
            end associate
        end do
    end subroutine test_five_body

    !> The pendulum scene (DDASSL's settings), at rest at its lowest point.
    function pendulum_scene(formulation) result(scene)
        character(len=*), intent(in) :: formulation
        type(scene_input_t) :: scene
        type(status_t) :: status
        character(len=*), parameter :: nl = new_line('a')
        call parse_scene('&simulation problem = ''pendulum'', t_end = 2.0, ' // &
            'pendulum_formulation = ''' // formulation // ''', pendulum_length = 0.8, ' // &
            'pendulum_angle = 0.0, gravity = 9.81 /' // nl // '&solver name = ''radau5'', ' // &
            'rtol = 1e-6, atol = 1e-6 /' // nl, 'pendulum.nml', scene, status)
        if (.not. status%ok()) error stop 'pendulum_scene: ' // status%text()
    end function pendulum_scene
end module test_modes
