!> Eigen-analysis of a scene (`flexmbs modes`, docs/modes.md): the finite
!> eigenvalues λ of the pencil (J, M), J = ∂F/∂y, of the DAE M y' = F(t, y)
!> that DDASSL integrates for the scene, linearised at t_start or at a later
!> time; frequencies and damping ratios; and for each BDF order k whether
!> h·λ of the stiff modes lies in the A(α_k) sector at the step sizes that
!> a DDASSL run of the same scene and settings took at that order.
!>
!> Which formulation: the scene's own, as DDASSL integrates it (projection
!> off: DDASSL refuses it), so that the check speaks of the matrices the
!> run factors. Its finite eigenvalues are the motion on the constraint
!> manifold, 2 (n_v − n_c) of them, plus eigenvalues that belong to the
!> formulation and not to the mechanics (docs/modes.md): one per unit
!> quaternion (its length, an invariant of q' = T v: 0 at rest), n_c for
!> index 2 (the values of g, which G v = 0 keeps: 0 at rest) and 2 n_c for
!> index 1 (those of g and ġ; the Baumgarte roots of s² + 2ζωs + ω² when
!> on). Index 3 and GGL have none. Their infinite eigenvalues (the
!> algebraic components) are recognised by QZ's β and counted.
!>
!> Dense pencils (n ≤ modes_dense_limit, or asked for) go to LAPACK's QZ
!> (linalg/generalized_eigen) and give every eigenvalue; larger ones to
!> ARPACK in shift-invert form around a real shift σ (linalg/arpack),
!> which gives the ones nearest σ.
module flexmbs_run_modes
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_linalg_matrix, only: matrix_t, storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_linalg_generalized_eigen, only: pencil_eigenvalues
    use flexmbs_linalg_arpack, only: shift_invert_eigenvalues
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_linearisation, only: linearise
    use flexmbs_dae_bdf_stability, only: bdf_stability_angle, sector_angle
    use flexmbs_problems_pendulum, only: pendulum_t, pendulum_index1, pendulum_index2
    use flexmbs_mbs_formulation, only: formulation_t, formulation_index1, formulation_index2, &
        block_q, block_v, block_lambda
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_run_catalogue, only: pmax_grid_solver
    use flexmbs_run_plan, only: run_plan_t, make_plan, scene_stab
    use flexmbs_run_step_sink, only: step_sink_t
    implicit none
    private

    !> Largest order for which `method = 'auto'` uses dense QZ. LAPACK's
    !> dggev3 (OpenBLAS, one thread, shared 2-core machine) took 13 s on the
    !> hex8 cantilever pencil of order 1920 (test/test_modes.f90); the
    !> older dggev 97 s. The cost grows like n³.
    integer, parameter, public :: modes_dense_limit = 2000
    !> BDF orders checked (DDASSL's largest).
    integer, parameter, public :: max_bdf_order = 5
    !> A QZ eigenvalue is infinite when |λ| ‖M‖ / ‖J‖ (max norms) exceeds
    !> ε^(−1/4) ≈ 8.2e3: below ε^(−1/3) ≈ 1.6e5, the size to which round-off
    !> lifts a Jordan block of length 3 at infinity (index 3), far above the
    !> mechanics. Measured at t_start: the five-body scene in all four
    !> formulations has its finite ones at ≤ 0.03 and its infinite ones at
    !> ≥ 3e6 (index 3; ≥ 2e11 in the others) or β = 0; the four-bar's at
    !> ≥ 1.7e15.
    real(wp), parameter :: infinite_ratio = epsilon(1.0_wp)**(-0.25_wp)
    !> |λ| ≤ zero_factor sqrt(ε max(‖J‖/‖M‖, 1)) counts as λ = 0: a double
    !> zero (a neutral direction: a free slider, a pendulum at 90°) perturbed
    !> by round-off δ ~ ε ‖J‖/‖M‖ splits into ±sqrt(δ). Measured: the
    !> five-body scene's zeros at ≤ 6e-5 (bound 1.4e-4), its lowest mode at
    !> 1.6; the horizontal pendulum's double zero at 2.5e-8 (bound 1.5e-7).
    real(wp), parameter :: zero_factor = 10.0_wp
    !> A mode is stiff at step size h when |h λ| ≥ 1: the step does not
    !> resolve it, and the method's stability, not its accuracy, decides
    !> what becomes of it.
    real(wp), parameter, public :: stiff_bound = 1.0_wp

    !> What to compute.
    type, public :: modes_options_t
        logical :: at_time = .false.        !! linearise at `time` (else t_start)
        real(wp) :: time = 0.0_wp
        integer :: count = 10               !! modes listed (ARPACK: computed)
        real(wp) :: shift = -1.0_wp         !! ARPACK's σ [1/s]
        character(len=6) :: method = 'auto' !! 'auto' | 'dense' | 'arpack'
        logical :: run_bdf = .true.         !! the DDASSL run and the sector check
    end type modes_options_t

    !> The spectrum and the check.
    type, public :: modes_result_t
        character(len=:), allocatable :: title, path, formulation, method
        character(len=:), allocatable :: solver   !! the BDF code run (DDASSL)
        real(wp) :: t = 0.0_wp               !! linearised at
        integer :: n = 0                     !! unknowns
        integer :: finite = 0                !! finite eigenvalues found
        integer :: infinite = -1             !! infinite ones (QZ only)
        !> expected finite ones (−1: unknown problem), and their parts
        integer :: expected = -1, dof = 0, quaternions = 0, constraint_values = 0
        real(wp) :: zero_bound = 0.0_wp      !! |λ| below it counts as 0
        !> finite eigenvalues by |λ| (conjugates: + first), and the mode of
        !> each (a pair shares one; 0 for λ = 0)
        complex(wp), allocatable :: lambda(:)
        integer, allocatable :: mode(:)
        integer :: modes = 0
        !> the DDASSL run: statistics, accepted steps and their orders
        logical :: has_run = .false.
        type(status_t) :: run_status
        character(len=:), allocatable :: run_settings
        type(dae_stats_t) :: stats
        real(wp), allocatable :: h(:)
        integer, allocatable :: order(:)
        real(wp) :: alpha(max_bdf_order) = 0.0_wp   !! A(α) angles [deg]
    contains
        procedure :: mode_index => result_mode_index
    end type modes_result_t

    public :: analyse_modes, stiff_outside, median, sort_by_modulus

contains

    !> The analysis of `scene` (validated) as `options` say. Bad input
    !> (status bad_input) names the file or the option; a failure of the
    !> linearisation or of the eigensolver is a solver failure. A DDASSL run
    !> that fails leaves its steps so far and its reason in `result`
    !> (run_status); only a run that fails before `--time` fails here.
    subroutine analyse_modes(scene, options, result, status)
        type(scene_input_t), intent(in) :: scene
        type(modes_options_t), intent(in) :: options
        type(modes_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        type(scene_input_t) :: bdf_scene
        type(run_plan_t), target :: plan
        type(step_sink_t) :: steps
        real(wp), allocatable :: y(:), yp(:)
        integer :: k

        call check_options(scene, options, status)
        if (.not. status%ok()) return
        call bdf_scene_of(scene, bdf_scene)
        call make_plan(bdf_scene, plan, status)
        if (.not. status%ok()) return
        result%solver = pmax_grid_solver()
        result%title = trim(scene%title)
        result%path = scene%path
        result%formulation = scene_stab(bdf_scene)
        result%n = plan%problem%n
        result%run_settings = 'rtol ' // real_text(scene%rtol) // ', atol ' // &
            real_text(scene%atol) // ', p_max ' // int_text(scene%pmax)
        do k = 1, max_bdf_order
            result%alpha(k) = bdf_stability_angle(k)
        end do
        result%t = scene%t_start
        y = plan%y0
        if (options%at_time .and. options%time /= scene%t_start) then
            steps%wants_state = .true.
            steps%t_state = options%time
            call run_bdf(plan, scene, steps, result)
            if (.not. steps%has_state) then
                status = result%run_status
                status%message = scene%path // ': ' // result%solver // ' did not reach &
                    &--time ' // real_text(options%time) // ': ' // status%text()
                return
            end if
            result%t = options%time
            y = steps%state
            select type (p => plan%problem)
            type is (formulation_t)
                allocate (yp(size(y)), source=0.0_wp)
                call p%consistent_initial(result%t, y, yp, status)
                if (.not. status%ok()) then
                    status%message = scene%path // ': the state at t = ' // &
                        real_text(result%t) // ' could not be made consistent: ' // &
                        status%text()
                    return
                end if
            end select
        end if
        call expected_counts(plan, result)
        call spectrum(plan, y, options, result, status)
        if (.not. status%ok()) then
            status%message = scene%path // ': ' // status%message
            return
        end if
        if (options%run_bdf .and. .not. result%has_run) &
            call run_bdf(plan, scene, steps, result)
    end subroutine analyse_modes

    subroutine check_options(scene, options, status)
        type(scene_input_t), intent(in) :: scene
        type(modes_options_t), intent(in) :: options
        type(status_t), intent(out) :: status
        if (options%count < 1) then
            call status%set(status_bad_input, '--count ' // int_text(options%count) // &
                ': needs a whole number >= 1')
        else if (all(options%method /= [character(len=6) :: 'auto', 'dense', 'arpack'])) then
            call status%set(status_bad_input, '--method ''' // trim(options%method) // &
                ''': use auto, dense or arpack')
        else if (options%at_time .and. .not. (options%time >= scene%t_start .and. &
                 options%time <= scene%t_end)) then
            call status%set(status_bad_input, scene%path // ': --time ' // &
                real_text(options%time) // ': outside the scene''s [t_start, t_end] = [' // &
                real_text(scene%t_start) // ', ' // real_text(scene%t_end) // ']')
        else if (options%at_time .and. .not. options%run_bdf .and. &
                 options%time /= scene%t_start) then
            call status%set(status_bad_input, '--time needs the BDF run to get there: drop &
                &--no-run')
        end if
    end subroutine check_options

    !> The scene with the catalogue's p_max-grid solver (DDASSL) and no
    !> outputs; without projection, which DDASSL refuses (docs/theory.md §3.5).
    subroutine bdf_scene_of(scene, bdf)
        type(scene_input_t), intent(in) :: scene
        type(scene_input_t), intent(out) :: bdf
        bdf = scene
        bdf%solver_name = pmax_grid_solver()
        bdf%output_file = ''
        bdf%table = ''
        bdf%vtk = ''
        bdf%multibody%projection = .false.
        bdf%pendulum_projection = .false.
    end subroutine bdf_scene_of

    !> DDASSL from t_start to t_end with the step sink; its statistics and
    !> steps (also after a failure) into `result`.
    subroutine run_bdf(plan, scene, steps, result)
        type(run_plan_t), intent(inout) :: plan
        type(scene_input_t), intent(in) :: scene
        type(step_sink_t), intent(inout) :: steps
        type(modes_result_t), intent(inout) :: result
        real(wp), allocatable :: y(:)
        real(wp) :: t
        t = scene%t_start
        y = plan%y0
        call plan%integrate(t, y, scene%t_end, result%stats, result%run_status, steps)
        result%has_run = .true.
        allocate (result%h(steps%steps), result%order(steps%steps))
        if (steps%steps > 0) then
            result%h = steps%h(1:steps%steps)
            result%order = steps%order(1:steps%steps)
        end if
    end subroutine run_bdf

    !> The finite eigenvalues a mechanical formulation should have
    !> (module header), constraints assumed independent.
    subroutine expected_counts(plan, result)
        type(run_plan_t), intent(in) :: plan
        type(modes_result_t), intent(inout) :: result
        integer :: nq, nv, nc, form
        select type (p => plan%problem)
        type is (formulation_t)
            nq = p%block_size(block_q)
            nv = p%block_size(block_v)
            nc = p%block_size(block_lambda)
            form = p%form_kind()
            result%constraint_values = merge(nc, 0, form == formulation_index2) + &
                merge(2 * nc, 0, form == formulation_index1)
        type is (pendulum_t)
            nq = 2
            nv = 2
            nc = 1
            result%constraint_values = merge(nc, 0, p%formulation == pendulum_index2) + &
                merge(2 * nc, 0, p%formulation == pendulum_index1)
        class default
            result%expected = -1
            return
        end select
        result%dof = nv - nc
        result%quaternions = nq - nv
        result%expected = 2 * result%dof + result%quaternions + result%constraint_values
    end subroutine expected_counts

    !> Linearise at (result%t, y) and compute the spectrum.
    subroutine spectrum(plan, y, options, result, status)
        type(run_plan_t), intent(inout) :: plan
        real(wp), intent(in) :: y(:)
        type(modes_options_t), intent(in) :: options
        type(modes_result_t), intent(inout) :: result
        type(status_t), intent(out) :: status
        type(matrix_t) :: jac, mass
        real(wp) :: scale
        logical :: dense
        call linearise(plan%problem, result%t, y, jac, mass, status)
        if (.not. status%ok()) then
            status%message = 'linearisation at t = ' // real_text(result%t) // ': ' // &
                status%message
            return
        end if
        scale = max_norm(jac) / max(max_norm(mass), tiny(1.0_wp))
        result%zero_bound = zero_factor * sqrt(epsilon(1.0_wp) * max(scale, 1.0_wp))
        select case (trim(options%method))
        case ('dense')
            dense = .true.
        case ('arpack')
            dense = .false.
        case default
            dense = result%n <= modes_dense_limit
        end select
        if (dense) then
            result%method = 'dense QZ (LAPACK dggev3), every eigenvalue'
            call dense_spectrum(jac, mass, scale, result, status)
        else
            call arpack_spectrum(jac, mass, plan, options, result, status)
        end if
        if (.not. status%ok()) return
        call sort_by_modulus(result%lambda)
        call number_modes(result)
    end subroutine spectrum

    !> Every eigenvalue by QZ; the infinite ones counted and dropped.
    subroutine dense_spectrum(jac, mass, scale, result, status)
        type(matrix_t), intent(in) :: jac, mass
        real(wp), intent(in) :: scale                !! ‖J‖ / ‖M‖
        type(modes_result_t), intent(inout) :: result
        type(status_t), intent(out) :: status
        real(wp), allocatable :: a(:, :), b(:, :), beta(:)
        complex(wp), allocatable :: alpha(:)
        logical, allocatable :: finite(:)
        integer :: stat
        allocate (a(jac%n, jac%n), b(jac%n, jac%n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'dense J and M for QZ (--method arpack needs less)', &
                               2_i8 * jac%n * jac%n, 8)
            return
        end if
        call jac%to_dense(a)
        call mass%to_dense(b)
        call pencil_eigenvalues(a, b, alpha, beta, status)
        if (.not. status%ok()) return
        deallocate (a, b)
        ! |λ| / scale = |α| / (β scale) > infinite_ratio, without dividing by β
        finite = abs(alpha) < infinite_ratio * scale * beta
        result%finite = count(finite)
        result%infinite = size(beta) - result%finite
        result%lambda = pack(alpha, finite) / pack(beta, finite)
    end subroutine dense_spectrum

    !> The eigenvalues nearest σ by ARPACK, with the scene's linear solver:
    !> 2 count of them (a pair per mode) and room for the formulation's own.
    subroutine arpack_spectrum(jac, mass, plan, options, result, status)
        type(matrix_t), intent(in) :: jac, mass
        type(run_plan_t), intent(inout) :: plan
        type(modes_options_t), intent(in) :: options
        type(modes_result_t), intent(inout) :: result
        type(status_t), intent(out) :: status
        class(linear_solver_t), allocatable :: solver
        integer :: wanted
        wanted = 2 * options%count + max(result%quaternions + result%constraint_values, 0)
        wanted = min(wanted, result%n - 2)
        ! the formulation's condensed Newton system factors σ M − J as it
        ! factors the integrators' matrices (docs/theory.md §3.7), or ours
        if (jac%storage == storage_sparse) &
            call plan%problem%iteration_solver(plan%options, solver, status)
        if (.not. status%ok()) return
        if (.not. allocated(solver)) call new_linear_solver(plan%options%linear_solver, &
            jac%n, jac%storage, solver, status, ordering=plan%options%sparse_ordering, &
            mass=mass, jac=jac)
        if (.not. status%ok()) return
        call shift_invert_eigenvalues(jac, mass, options%shift, wanted, solver, &
                                      result%lambda, status)
        if (.not. status%ok()) return
        result%method = 'ARPACK shift-invert around sigma = ' // real_text(options%shift) // &
            ' (' // solver%name() // ' LU), the ' // int_text(size(result%lambda)) // &
            ' eigenvalues nearest sigma'
        result%finite = size(result%lambda)
    end subroutine arpack_spectrum

    !> Largest |entry| of a matrix_t (1 for the identity).
    pure real(wp) function max_norm(a)
        type(matrix_t), intent(in) :: a
        select case (a%storage)
        case (storage_dense)
            max_norm = maxval(abs(a%dense))
        case (storage_sparse)
            max_norm = maxval(abs(a%csc%values))
        case default
            max_norm = 1.0_wp
        end select
    end function max_norm

    !> By |λ|, then + imaginary part before − (conjugate pairs adjacent).
    subroutine sort_by_modulus(lambda)
        complex(wp), intent(inout) :: lambda(:)
        complex(wp) :: swap
        integer :: i, j
        do i = 2, size(lambda)
            j = i
            do while (j > 1)
                if (.not. before(lambda(j), lambda(j - 1))) exit
                swap = lambda(j)
                lambda(j) = lambda(j - 1)
                lambda(j - 1) = swap
                j = j - 1
            end do
        end do
    contains
        pure logical function before(a, b)
            complex(wp), intent(in) :: a, b
            before = abs(a) < abs(b) .or. (abs(a) == abs(b) .and. aimag(a) > aimag(b))
        end function before
    end subroutine sort_by_modulus

    !> The modes: each eigenvalue with Im λ ≥ 0 above the zero bound, in order;
    !> one with Im λ < 0 takes the number of its conjugate (equal to
    !> round-off), or a number of its own when the conjugate is missing (an
    !> ARPACK list cut between the two).
    subroutine number_modes(result)
        type(modes_result_t), intent(inout) :: result
        real(wp), parameter :: conjugate_tolerance = 64.0_wp * epsilon(1.0_wp)
        logical, allocatable :: partnered(:)
        integer :: i, j
        associate (lambda => result%lambda)
            allocate (result%mode(size(lambda)), source=0)
            allocate (partnered(size(lambda)), source=.false.)
            result%modes = 0
            do i = 1, size(lambda)
                if (abs(lambda(i)) <= result%zero_bound) cycle
                if (aimag(lambda(i)) >= 0.0_wp) then
                    result%modes = result%modes + 1
                    result%mode(i) = result%modes
                    cycle
                end if
                do j = 1, size(lambda)
                    if (partnered(j) .or. result%mode(j) == 0 .or. aimag(lambda(j)) <= 0.0_wp) &
                        cycle
                    if (abs(lambda(j) - conjg(lambda(i))) > conjugate_tolerance * &
                        abs(lambda(i))) cycle
                    result%mode(i) = result%mode(j)
                    partnered(j) = .true.
                    exit
                end do
                if (result%mode(i) /= 0) cycle
                result%modes = result%modes + 1
                result%mode(i) = result%modes
            end do
        end associate
    end subroutine number_modes

    !> Position in `lambda` of mode m: its eigenvalue with Im λ ≥ 0, or its
    !> only one.
    pure integer function result_mode_index(self, m) result(i)
        class(modes_result_t), intent(in) :: self
        integer, intent(in) :: m
        integer :: j
        i = 0
        do j = 1, size(self%lambda)
            if (self%mode(j) /= m) cycle
            if (i == 0 .or. aimag(self%lambda(j)) >= 0.0_wp) i = j
            if (aimag(self%lambda(j)) >= 0.0_wp) return
        end do
    end function result_mode_index

    !> The modes that are stiff at step size h (|h λ| ≥ stiff_bound) and lie
    !> outside BDF-k's sector (|arg(−h λ)| > α_k): where BDF-k with this h
    !> is not guaranteed stable. By decreasing |λ|.
    function stiff_outside(result, k, h) result(modes)
        type(modes_result_t), intent(in) :: result
        integer, intent(in) :: k           !! BDF order, 1..max_bdf_order
        real(wp), intent(in) :: h          !! step size, > 0
        integer, allocatable :: modes(:)
        integer :: i, m
        allocate (modes(0))
        do m = result%modes, 1, -1
            i = result%mode_index(m)
            if (h * abs(result%lambda(i)) < stiff_bound) cycle
            if (sector_angle(result%lambda(i)) > result%alpha(k)) modes = [modes, m]
        end do
    end function stiff_outside

    !> Median of x (not empty), by heapsort of a copy (runs keep up to
    !> millions of steps).
    real(wp) function median(x)
        real(wp), intent(in) :: x(:)
        real(wp), allocatable :: s(:)
        real(wp) :: top
        integer :: i, n
        s = x
        n = size(s)
        do i = n / 2, 1, -1
            call sift(i, n)
        end do
        do i = n, 2, -1
            top = s(1)
            s(1) = s(i)
            s(i) = top
            call sift(1, i - 1)
        end do
        median = s((n + 1) / 2)
        if (mod(n, 2) == 0) median = 0.5_wp * (s(n / 2) + s(n / 2 + 1))
    contains
        !> Restore the max-heap below `root` within s(1:last).
        subroutine sift(root, last)
            integer, intent(in) :: root, last
            integer :: parent, child
            real(wp) :: value
            parent = root
            value = s(parent)
            do
                child = 2 * parent
                if (child > last) exit
                if (child < last) then
                    if (s(child + 1) > s(child)) child = child + 1
                end if
                if (s(child) <= value) exit
                s(parent) = s(child)
                parent = child
            end do
            s(parent) = value
        end subroutine sift
    end function median

end module flexmbs_run_modes
