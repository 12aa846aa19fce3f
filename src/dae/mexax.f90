!> `MEXAX`: half-explicit extrapolation for constrained mechanical systems
!> (docs/theory.md §7; [Lub91], [LNPE95], [HW96 VII.6], ODEX control of
!> [HNW93 II.9]).
!>
!> For q' = T(t,q) v, M(t,q) v' = f(t,q,v) − G(t,q)ᵀλ, 0 = G v + g_I, with
!> the position invariant g(t,q) = 0. A macro step H is split into n_j
!> substeps of a half-explicit base method (explicit in the differential
!> equations, one solve of the augmented system [M Gᵀ; G 0] per substep);
!> the results are extrapolated (Aitken–Neville in h for the Euler base,
!> in h² for the midpoint base), the error of the diagonal is estimated from
!> the subdiagonal, and column and step size are chosen as in ODEX. After
!> every converged step the positions are projected onto g = 0 (simplified
!> Newton) and the velocities onto G v + g_I = 0. Errors are controlled on
!> q and v only; a = v' and λ are outputs.
!>
!> Only the mechanical form is integrated (`integrate_mechanical`); the
!> generic `integrate` of a `dae_problem_t` is refused (§6).
!>
!> The augmented matrix is factored densely (LAPACK LU), or, with
!> `options%linear_solver = 'klu'` (or 'auto' for a problem with sparse M and
!> G and nv + nc ≥ `mexax_auto_klu_order`), by KLU on the CSC pattern of
!> [M Gᵀ; G 0] built once from the patterns of M and G and analysed once;
!> each substep only refills its values and refactors.
!>
!> This module holds the solver type and its drivers; the constants, the
!> dense output and the state of an integration in flexmbs_dae_mexax_state,
!> the start (checks, workspace, H0, t0) in flexmbs_dae_mexax_start and one
!> macro step (attempt, projection, acceptance) in flexmbs_dae_mexax_step.
module flexmbs_dae_mexax
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_non_finite
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t, finish_sink
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_dae_mexax_control, only: mexax_base_midpoint, mexax_base_euler, &
        mexax_max_columns, mexax_control_hairer, mexax_control_deuflhard
    use flexmbs_dae_mexax_workspace, only: workspace_t, workspace_linear_solver, mexax_native_t, mexax_auto_klu_order, &
        setup_workspace, ev_ok
    use flexmbs_dae_mexax_tableau, only: start_point, base_column, extrapolate_column
    use flexmbs_dae_mexax_state, only: mexax_engine_t, mexax_run_t, mexax_dense_t, &
        mexax_failed_none, mexax_failed_step, mexax_failed_projection
    use flexmbs_dae_mexax_start, only: check_input, begin_integration, start
    use flexmbs_dae_mexax_step, only: macro_step
    implicit none
    private

    public :: mexax_base_midpoint, mexax_base_euler, mexax_max_columns, mexax_native_t, &
        mexax_auto_klu_order, mexax_control_hairer, mexax_control_deuflhard
    ! Defined with the state; part of this module's interface.
    public :: mexax_dense_t, mexax_failed_none, mexax_failed_step, mexax_failed_projection

    !> The MEXAX solver: the settings and the results of the last integration are
    !> those of `mexax_engine_t`, which the phases read and write.
    type, extends(mexax_engine_t), public :: mexax_t
    contains
        procedure :: integrate_dae => mexax_integrate
        procedure :: integrate_mechanical => mexax_integrate_mechanical
        procedure :: integrate_system => mexax_integrate_system
        procedure :: extrapolate => mexax_extrapolate
        procedure :: name => mexax_name
        procedure :: step_counts => mexax_step_counts
        procedure :: apply_setting => mexax_apply_setting
    end type mexax_t

contains

    function mexax_name(self) result(name)
        class(mexax_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'mexax'
    end function mexax_name

    !> Live counts for a display: the classic counters NSTEP and NACCPT.
    subroutine mexax_step_counts(self, attempted, accepted)
        class(mexax_t), intent(in) :: self
        integer, intent(out) :: attempted, accepted
        attempted = self%native%nstep
        accepted = self%native%naccpt
    end subroutine mexax_step_counts

    !> A scene's MEXAX setting (scene schema, group &solver).
    subroutine mexax_apply_setting(self, setting, applied)
        class(mexax_t), intent(inout) :: self
        type(solver_setting_t), intent(in) :: setting
        logical, intent(out) :: applied
        applied = .true.
        select case (setting%name)
        case ('max_extrapolation')
            self%max_extrapolation = setting%integer_value
        case ('mexax_base')
            self%base = merge(mexax_base_euler, mexax_base_midpoint, &
                              setting%string_value == 'euler')
        case ('mexax_control')
            self%control = merge(mexax_control_hairer, mexax_control_deuflhard, &
                                 setting%string_value == 'hairer')
        case default
            applied = .false.
        end select
    end subroutine mexax_apply_setting

    !> MEXAX takes mechanical problems only (docs/theory.md §3).
    subroutine mexax_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(mexax_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        include 'integrate_arguments.inc'
        real(wp), intent(inout), optional :: yp(:)
        stats%t_reached = t
        call status%set(status_bad_input, 'mexax: integrates mechanical problems only &
            &(q'' = T v, M v'' = f - G^T lambda, projection built in); give integrate &
            &a mechanical_problem_t with its formulation, not a formulation alone')
    end subroutine mexax_integrate

    !> The mechanical problem through the common interface: y = (q, v, λ)
    !> (the layout of `formulation`, the index-2 formulation with constant
    !> mass, which MEXAX itself does not need).
    subroutine mexax_integrate_system(self, mechanical, formulation, t, y, t_end, options, &
                                      stats, status, sink)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mechanical
        class(dae_problem_t), intent(inout) :: formulation
        include 'integrate_arguments.inc'
        integer :: nq, nv, nc
        nq = mechanical%nq
        nv = mechanical%nv
        nc = mechanical%nc
        if (size(y) /= nq + nv + nc) then
            stats%t_reached = t
            call status%set(status_bad_input, 'mexax: y has ' // int_text(size(y)) // &
                ' components; the mechanical problem''s (q, v, lambda) has ' // &
                int_text(nq + nv + nc) // ': give it the state of the index-2 formulation &
                &with constant mass (formulation_index2, constant_mass = .true.)')
            return
        end if
        call self%integrate_mechanical(mechanical, t, y(1:nq), y(nq + 1:nq + nv), t_end, &
            options, stats, status, sink, lambda=y(nq + nv + 1:nq + nv + nc))
    end subroutine mexax_integrate_system

    !> Integrate the mechanical problem from (t, q, v) to t_end. On return
    !> t, q, v hold the last accepted point (t_end on success), `lambda` and
    !> `accel` the multipliers and accelerations there (extrapolated). The
    !> sink sees y = (q, v, λ). `status` names what failed and when.
    subroutine mexax_integrate_mechanical(self, problem, t, q, v, t_end, options, stats, &
                                          status, sink, lambda, accel)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: q(:)            !! positions, size nq
        real(wp), intent(inout) :: v(:)            !! velocities, size nv
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options !! rtol/atol vectors have size nq + nv
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: lambda(:) !! on exit: λ at t (size nc)
        real(wp), intent(inout), optional :: accel(:)  !! on exit: a = v' at t (size nv)
        type(mexax_run_t) :: r  !! the integration's state and workspace

        call r%timer%start()
        self%native = mexax_native_t()
        self%nstab = 0
        self%nprj_reject = 0
        self%h_next = 0.0_wp
        self%failed_in = mexax_failed_none
        stats%t_reached = t
        r%t = t
        r%nstab_nonfinite = 0
        r%stop_requested = .false.

        call check_input(self, r, problem, t, q, v, t_end, options, status, lambda, accel)
        if (.not. status%ok()) return
        call begin_integration(self, r, problem, q, v, t_end, options, status, lambda)
        if (.not. status%ok()) return
        call start(self, r, problem, options, stats, status, sink)
        if (.not. status%ok()) then
            call finish(self, r, stats, status, sink)
            return
        end if

        main: do
            call macro_step(self, r, problem, t_end, options, stats, status, sink)
            if (r%done) exit main
        end do main

        t = r%t
        q = r%w%p0
        v = r%w%v0
        if (present(lambda)) lambda = r%w%lam0
        if (present(accel)) accel = r%w%a0
        call finish(self, r, stats, status, sink)
    end subroutine mexax_integrate_mechanical

    !> Common statistics from the native counters (docs/solvers.md).
    subroutine finish(self, r, stats, status, sink)
        class(mexax_t), intent(inout) :: self
        type(mexax_run_t), intent(in) :: r
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        stats%nst = self%native%nstep
        stats%nac = self%native%naccpt
        stats%nrj = stats%nst - stats%nac
        stats%nfe = self%native%nfcn
        stats%nje = 0
        stats%ndec = self%native%ndec
        stats%nsol = self%native%nsol
        stats%t_reached = r%t
        if (allocated(r%w)) stats%linear_solver = workspace_linear_solver(r%w)
        stats%cpu = r%timer%cpu()
        stats%wall = r%timer%wall()
        call stats%rejections%annotate(status)
        call finish_sink(sink, status)
    end subroutine finish

    !> One macro step of size big_h from (t, q, v) without projection or
    !> control: the diagonal T_{j,j} of columns j = 1..columns in q_out(:, j),
    !> v_out(:, j). For order studies (§8: local error of T_{j,j} in q is
    !> O(H^{j+1}) for (E), O(H^{2j+1}) for (M)).
    subroutine mexax_extrapolate(self, problem, t, q, v, big_h, columns, q_out, v_out, status)
        class(mexax_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, q(:), v(:), big_h
        integer, intent(in) :: columns          !! 1..12
        real(wp), intent(out) :: q_out(:, :)    !! (nq, columns)
        real(wp), intent(out) :: v_out(:, :)    !! (nv, columns)
        type(status_t), intent(out) :: status
        type(workspace_t) :: w
        integer :: j, ev
        self%native = mexax_native_t()
        if (columns < 1 .or. columns > mexax_max_columns) then
            call status%set(status_bad_input, 'mexax: columns must lie in 1..12')
            return
        end if
        call setup_workspace(w, problem, self%base, self%control, columns, 'auto', status)
        if (.not. status%ok()) return
        w%rtol = 1.0_wp
        w%atol = 1.0_wp
        w%p0 = q
        w%v0 = v
        call start_point(self%native, problem, w, t, status, accelerations=.false.)
        if (.not. status%ok()) return
        do j = 1, columns
            call base_column(self%native, problem, w, t, big_h, w%ctl%nj(j), .false., ev, status)
            if (ev /= ev_ok) then
                if (status%ok()) call status%set(status_solver_failure, &
                    'mexax: non-finite values in the base step', reason_non_finite)
                return
            end if
            call extrapolate_column(w, j)
            q_out(:, j) = w%tab(1:w%nq, j)
            v_out(:, j) = w%tab(w%nq + 1:w%nq + w%nv, j)
        end do
    end subroutine mexax_extrapolate
end module flexmbs_dae_mexax
