!> Static equilibrium of a flexible body: k(q, 0) = λ g for the load factor
!> λ = 1, g the applied force (gravity and nodal loads) on the free dofs.
!>
!> Newton's method with the tangent stiffness ∂k/∂q in the body's fixed CSC
!> pattern, factorised by KLU (one symbolic analysis, a numeric factorisation
!> per iteration), and a backtracking line search on ‖r‖∞. In slender
!> bodies ‖r‖ is dominated by the stiff axial terms: a good Newton step that
!> bends a beam raises it (spurious stretch of O(θ²) times the axial
!> stiffness), and backtracking on ‖r‖ alone crawls (a cantilever at
!> δ/L = 0.27 took 146 iterations). Dead loads are conservative,
!> k − λg = ∇Π with Π = W − λ g·q, so a step is also accepted when it
!> satisfies Armijo on Π and Δq descends Π (Δq·r < 0): the same cantilever
!> then takes 13 iterations.
!>
!> Load stepping: λ rises from 0 to 1 in increments that halve when Newton
!> fails (no convergence, no descent, det F ≤ 0 at a quadrature point) and
!> double after quick convergence; each increment starts from the secant
!> predictor through the last two equilibria.
!>
!> Convergence of one load step: ‖Δq‖∞ ≤ increment_tolerance · (size of the
!> body) and either ‖r‖∞ ≤ residual_tolerance · λ ‖g‖∞ or ‖r‖∞ at the level
!> of round-off in k (100 ε (2μ + λ) times the largest element area, since
!> the stresses lose absolute, not relative, accuracy near C = I). When the
!> line search finds no descent, a negligible Newton correction also counts
!> as converged.
module flexmbs_fe_statics
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_newton_failure, reason_step_too_small
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_linalg_klu, only: klu_factor_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    implicit none
    private

    !> The tolerances and limits of a static solve: Newton's convergence
    !> tests, the load increments and the line search (see the module).
    type, public :: static_options_t
        real(wp) :: residual_tolerance = 1.0e-10_wp  !! on ‖r‖∞ / ‖g‖∞
        real(wp) :: increment_tolerance = 1.0e-10_wp !! on ‖Δq‖∞ / body size
        integer :: max_iterations = 20       !! Newton iterations per load step
        real(wp) :: initial_increment = 1.0_wp  !! first Δλ
        real(wp) :: min_increment = 1.0e-6_wp   !! smallest Δλ before giving up
        integer :: max_load_steps = 10000
        integer :: max_backtracks = 8        !! line-search halvings
    end type static_options_t

    !> What a solve cost and reached.
    type, public :: static_report_t
        integer :: load_steps = 0          !! accepted load increments
        integer :: failed_steps = 0        !! increments retried with half the size
        integer :: newton_iterations = 0   !! all iterations, failed steps included
        integer :: factorizations = 0
        real(wp) :: load_factor = 0.0_wp   !! λ reached (1 on success)
        real(wp) :: residual = 0.0_wp      !! final ‖r‖∞
        !> ‖r‖∞ before each iteration of the last accepted load step (then final).
        real(wp), allocatable :: residual_history(:)
        !> Newton decrement sqrt(Δqᵀ K Δq) = sqrt(|Δq·r|) of each iteration of
        !> that step: affine invariant, so it shows quadratic convergence even
        !> where ‖r‖ and ‖Δq‖ mix stiff and soft modes (slender bodies).
        real(wp), allocatable :: decrement_history(:)
    end type static_report_t

    !> A solve's workspace and the scales of its tests: the last two
    !> equilibria, the Newton iterate and its base, the residual r, the
    !> increment dq, the tangent values k, one load step's histories.
    type :: static_work_t
        type(static_options_t) :: opt
        type(static_report_t) :: rep
        type(klu_factor_t) :: klu
        real(wp), allocatable :: zero_v(:), q_last(:), q_prev(:), q_trial(:), q_base(:), &
            r(:), dq(:), k(:), history(:), decrements(:)
        real(wp) :: gnorm = 0.0_wp      !! ‖g‖∞
        real(wp) :: size_scale = 1.0_wp !! the body's extent
        real(wp) :: floor = 0.0_wp      !! round-off level of k
        integer :: nhist = 0            !! entries of history in this load step
    end type static_work_t

    public :: solve_static

contains

    !> Equilibrium under the body's applied force; q in: initial guess
    !> (usually body%free_positions()), out: the equilibrium, or on failure
    !> the last equilibrium reached (load factor in the report).
    subroutine solve_static(body, q, status, options, report)
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(inout) :: q(:)
        type(status_t), intent(out) :: status
        type(static_options_t), intent(in), optional :: options
        type(static_report_t), intent(out), optional :: report
        type(static_work_t) :: w
        if (present(options)) w%opt = options
        call check_input(body, q, w%opt, status)
        if (status%ok()) call prepare(w, body, q, status)
        if (.not. status%ok()) then
            if (present(report)) report = w%rep
            return
        end if
        if (body%nq == 0) then
            w%rep%load_factor = 1.0_wp
            if (present(report)) report = w%rep
            return
        end if
        call w%klu%analyse(body%nv, body%stiffness%colptr, body%stiffness%rowind, status)
        if (status%ok()) then
            call follow_load(w, body, status)
            q = w%q_last
        end if
        if (present(report)) report = w%rep
    end subroutine solve_static

    !> Bad input: q not of the body's size, options out of range, a guess
    !> or applied force that is not finite.
    subroutine check_input(body, q, opt, status)
        class(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: q(:)
        type(static_options_t), intent(in) :: opt
        type(status_t), intent(inout) :: status
        if (size(q) /= body%nq) then
            call status%set(status_bad_input, 'static equilibrium: q has ' // &
                            int_text(size(q)) // ' entries, the body ' // int_text(body%nq))
        else if (.not. (opt%min_increment > 0.0_wp .and. &
                        opt%initial_increment >= opt%min_increment .and. &
                        opt%residual_tolerance > 0.0_wp .and. opt%max_iterations > 0)) then
            call status%set(status_bad_input, 'static equilibrium: options need 0 < ' // &
                'min_increment <= initial_increment, residual_tolerance > 0, max_iterations > 0')
        else if (.not. (all(ieee_is_finite(q)) .and. all(ieee_is_finite(body%applied_force)))) then
            call status%set(status_bad_input, 'static equilibrium: the initial guess or ' // &
                            'the applied force is not finite')
        end if
    end subroutine check_input

    !> The workspace, and the scales of the convergence tests: ‖g‖∞, the
    !> body's size and the round-off level of k.
    subroutine prepare(w, body, q, status)
        type(static_work_t), intent(inout) :: w
        class(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: q(:)
        type(status_t), intent(inout) :: status
        integer :: e, stat
        allocate (w%zero_v(body%nv), w%history(w%opt%max_iterations + 1), &
            w%decrements(w%opt%max_iterations), stat=stat)
        if (stat == 0) allocate (w%q_last, w%q_prev, w%q_trial, w%q_base, w%r, w%dq, w%k, &
                                 source=q, stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'static equilibrium workspace', &
                body%nv + 2_i8 * w%opt%max_iterations + 1 + 7_i8 * size(q), 8)
            return
        end if
        w%zero_v = 0.0_wp
        w%gnorm = 0.0_wp
        if (body%nv > 0) w%gnorm = maxval(abs(body%applied_force))
        w%size_scale = maxval(body%mesh%x) - minval(body%mesh%x)
        if (w%size_scale <= 0.0_wp) w%size_scale = 1.0_wp
        ! Round-off level of k: the stresses carry absolute errors of about
        ! ε (2μ + λ) (from I − C⁻¹ and J − 1), times an element's area.
        w%floor = 0.0_wp
        do e = 1, body%mesh%element_count()
            associate (mat => body%materials(body%element_material(e)))
                w%floor = max(w%floor, (2.0_wp * mat%mu + mat%lambda) &
                                       * sum(body%wdv(:, e))**(2.0_wp / 3))
            end associate
        end do
        w%floor = 1.0e2_wp * epsilon(1.0_wp) * w%floor
    end subroutine prepare

    !> The load factor from 0 to 1 in increments (module header): the last
    !> equilibrium in w%q_last, its load factor in the report.
    subroutine follow_load(w, body, status)
        type(static_work_t), intent(inout) :: w
        class(flexible_body_t), intent(inout) :: body
        type(status_t), intent(inout) :: status
        real(wp) :: lambda_last, lambda_prev, dlambda, lambda
        logical :: converged
        character(len=:), allocatable :: why
        lambda_last = 0.0_wp
        lambda_prev = 0.0_wp
        dlambda = min(1.0_wp, w%opt%initial_increment)
        do while (lambda_last < 1.0_wp)
            if (w%rep%load_steps + w%rep%failed_steps >= w%opt%max_load_steps) then
                call status%set(status_solver_failure, 'static equilibrium: ' // &
                    int_text(w%opt%max_load_steps) // ' load steps reached at load factor ' // &
                    real_text(lambda_last), reason_step_too_small)
                exit
            end if
            lambda = min(1.0_wp, lambda_last + dlambda)
            ! Secant predictor through the last two equilibria.
            if (lambda_last > lambda_prev) then
                w%q_trial = w%q_last + (lambda - lambda_last) / (lambda_last - lambda_prev) &
                            * (w%q_last - w%q_prev)
            else
                w%q_trial = w%q_last
            end if
            call newton(w, body, lambda, converged, why)
            if (.not. converged) then
                ! The predictor may be what failed: retry from the last state.
                if (lambda_last > lambda_prev) then
                    w%q_trial = w%q_last
                    call newton(w, body, lambda, converged, why)
                end if
            end if
            if (converged) then
                w%rep%load_steps = w%rep%load_steps + 1
                w%q_prev = w%q_last
                lambda_prev = lambda_last
                w%q_last = w%q_trial
                lambda_last = lambda
                w%rep%residual_history = w%history(1:w%nhist)
                w%rep%decrement_history = w%decrements(1:w%nhist - 1)
                if (w%nhist <= 5) dlambda = min(1.0_wp, 2.0_wp * dlambda)
            else
                w%rep%failed_steps = w%rep%failed_steps + 1
                dlambda = 0.5_wp * dlambda
                if (dlambda < w%opt%min_increment) then
                    call status%set(status_solver_failure, 'static equilibrium: load ' // &
                        'increment below ' // real_text(w%opt%min_increment) // &
                        ' at load factor ' // real_text(lambda_last) // ' (the step to ' // &
                        real_text(lambda) // ' failed: ' // why // ')', reason_newton_failure)
                    exit
                end if
            end if
        end do
        w%rep%load_factor = lambda_last
    end subroutine follow_load

    !> Newton from w%q_trial for load factor lam; w%q_trial is the solution
    !> when converged, else why says what failed.
    subroutine newton(w, body, lam, converged, why)
        type(static_work_t), intent(inout) :: w
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: lam
        logical, intent(out) :: converged
        character(len=:), allocatable, intent(out) :: why
        type(status_t) :: st
        real(wp) :: rnorm, rtrial, alpha, dqnorm, slope
        integer :: it
        converged = .false.
        w%nhist = 0
        call residual(body, w%q_trial, lam, w%zero_v, w%r, rnorm, st)
        if (.not. st%ok()) then
            why = st%text()
            return
        end if
        do it = 1, w%opt%max_iterations
            w%nhist = w%nhist + 1
            w%history(w%nhist) = rnorm
            w%rep%newton_iterations = w%rep%newton_iterations + 1
            call body%tangents(w%q_trial, w%zero_v, w%k, st)
            if (.not. st%ok()) then
                why = st%text()
                return
            end if
            call w%klu%factor(body%stiffness%values, st)
            w%rep%factorizations = w%rep%factorizations + 1
            if (.not. st%ok()) then
                why = 'tangent stiffness: ' // st%text()
                return
            end if
            w%dq = -w%r
            call w%klu%solve(w%dq, st)
            if (.not. st%ok()) then
                why = 'tangent stiffness solve: ' // st%text()
                return
            end if
            dqnorm = maxval(abs(w%dq))
            w%q_base = w%q_trial
            slope = dot_product(w%dq, w%r)
            w%decrements(w%nhist) = sqrt(abs(slope))
            call line_search(w, body, lam, rnorm, slope, alpha, rtrial, why)
            if (alpha == 0.0_wp) then
                w%q_trial = w%q_base
                ! No descent: converged if r is at round-off level or the
                ! Newton correction itself is negligible.
                if (rnorm <= max(w%opt%residual_tolerance * lam * w%gnorm, w%floor) .or. &
                    dqnorm <= w%opt%increment_tolerance * w%size_scale) then
                    call residual(body, w%q_trial, lam, w%zero_v, w%r, rnorm, st)
                    converged = st%ok()
                    w%nhist = w%nhist + 1
                    w%history(w%nhist) = rnorm
                    w%rep%residual = rnorm
                    return
                end if
                if (.not. allocated(why)) why = 'no descent along the Newton direction'
                call residual(body, w%q_trial, lam, w%zero_v, w%r, rnorm, st)
                return
            end if
            rnorm = rtrial
            if ((rnorm <= w%opt%residual_tolerance * lam * w%gnorm .or. rnorm <= w%floor) .and. &
                alpha * dqnorm <= w%opt%increment_tolerance * w%size_scale) then
                converged = .true.
                w%nhist = w%nhist + 1
                w%history(w%nhist) = rnorm
                w%rep%residual = rnorm
                return
            end if
        end do
        why = 'no convergence in ' // int_text(w%opt%max_iterations) // ' iterations'
    end subroutine newton

    !> Backtracking along w%dq from w%q_base (Armijo, small slope factor) on
    !> ‖r‖∞, or else on the potential Π when dq descends it (module header):
    !> the step alpha taken (w%q_trial, its ‖r‖∞ rtrial), 0 when no step of
    !> max_backtracks halvings descends (why: a failed evaluation's reason).
    subroutine line_search(w, body, lam, rnorm, slope, alpha, rtrial, why)
        type(static_work_t), intent(inout) :: w
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: lam, rnorm, slope
        real(wp), intent(out) :: alpha, rtrial
        character(len=:), allocatable, intent(inout) :: why
        type(status_t) :: st
        real(wp) :: pi0, pi
        logical :: have_pi0
        integer :: ib
        have_pi0 = .false.
        alpha = 1.0_wp
        do ib = 0, w%opt%max_backtracks
            w%q_trial = w%q_base + alpha * w%dq
            call residual(body, w%q_trial, lam, w%zero_v, w%r, rtrial, st)
            if (st%ok()) then
                if (rtrial <= (1.0_wp - 1.0e-4_wp * alpha) * rnorm) return
                if (slope < 0.0_wp) then
                    if (.not. have_pi0) then
                        pi0 = potential(body, w%q_base, lam, st)
                        have_pi0 = st%ok()
                    end if
                    if (have_pi0) then
                        pi = potential(body, w%q_trial, lam, st)
                        if (st%ok() .and. pi <= pi0 + 1.0e-4_wp * alpha * slope) return
                    end if
                end if
            else
                why = st%text()
            end if
            alpha = 0.5_wp * alpha
        end do
        alpha = 0.0_wp
    end subroutine line_search

    !> Total potential Π = W(q) − lam g·q of the dead loads.
    real(wp) function potential(body, qq, lam, st)
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: qq(:), lam
        type(status_t), intent(out) :: st
        potential = body%strain_energy(qq, st) - lam * dot_product(body%applied_force, qq)
    end function potential

    !> r = k(q, 0) − lam g and its ∞-norm; st fails on det F ≤ 0.
    subroutine residual(body, qq, lam, zero_v, r, rnorm, st)
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: qq(:), lam, zero_v(:)
        real(wp), intent(inout) :: r(:)
        real(wp), intent(out) :: rnorm
        type(status_t), intent(out) :: st
        call body%internal_forces(qq, zero_v, r, st)
        if (.not. st%ok()) then
            rnorm = huge(1.0_wp)
            return
        end if
        r = r - lam * body%applied_force
        rnorm = maxval(abs(r))
    end subroutine residual
end module flexmbs_fe_statics
