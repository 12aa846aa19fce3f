!> MEXAX's state (docs/theory.md §7): the driver's constants, the dense
!> output, the part of the solver that the phases of an integration read
!> and write (`mexax_engine_t`: settings and results, which `mexax_t`
!> extends) and the state one integration carries from step to step
!> (`mexax_run_t`: the workspace, the step, column and outcome of the
!> attempt, the output position).
module flexmbs_dae_mexax_state
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_timer, only: timer_t
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_mexax_control, only: mexax_base_midpoint, mexax_max_columns, &
        mexax_control_deuflhard
    use flexmbs_dae_mexax_workspace, only: workspace_t, mexax_native_t
    implicit none
    private

    !> Where a stopping failure happened (mexax_t%failed_in): the classic face
    !> tells IERR −15/−17 (in a step) from −16/−18 (in the projection).
    integer, parameter, public :: mexax_failed_none = 0, mexax_failed_step = 1, &
        mexax_failed_projection = 2

    ! §3.5: the stability check runs in columns 1..2 (ODEX's JSTAB = 2).
    integer, parameter, public :: stability_columns = 2
    ! §3.3/§3.5/§3.8: divergence, instability and non-finite values halve H
    ! (ODEX's SAFE3 = 0.5); such a restart counts in NSTEP, not in NREJCT (ODEX).
    real(wp), parameter, public :: restart_factor = 0.5_wp
    ! §3.4: the step ends at TFIN when t + 1.01 H passes it (ODEX).
    real(wp), parameter, public :: end_factor = 1.01_wp
    ! §3.8 [R]: stop when |H| ≤ 10 EPMACH |t| (the original's EPMACH = 1e-17;
    ! the form is RADAU5's 0.1 |H| ≤ uround |t| [HW96 IV.8]); |t_end − t0|
    ! stands in for |t| near t = 0, where the rule never fires (own rule).
    real(wp), parameter, public :: epmach = 1.0e-17_wp, small_step_factor = 10.0_wp
    ! §4.2 [R]: automatic initial step 1e-3 |t_end − t0| (reconstructed).
    real(wp), parameter, public :: h0_fraction = 1.0e-3_wp
    ! §3.6: after a projection rejection H ← H max(0.45, 0.9/c) (reconstructed).
    real(wp), parameter, public :: projection_reject_min = 0.45_wp, &
        projection_reject_safe = 0.9_wp

    ! Outcomes of an attempt.
    integer, parameter, public :: undecided = 0, do_accept = 1, do_reject = 2, &
        do_restart = 3, do_stop = 4

    !> Cubic Hermite interpolation on the last accepted step (§3.7): q from
    !> (q, T v), v from (v, a) at both ends; λ linear.
    type, extends(dense_output_t), public :: mexax_dense_t
        real(wp) :: t_old = 0.0_wp, t = 0.0_wp
        real(wp), allocatable :: y0(:), y1(:), d0(:), d1(:) !! (q, v, λ) and derivatives
    contains
        procedure :: evaluate => dense_evaluate
    end type mexax_dense_t

    !> MEXAX settings and the results of the last integration: what the
    !> phases of an integration (the modules flexmbs_dae_mexax_*) read and
    !> write; `mexax_t` extends it with the drivers.
    type, extends(dae_solver_t), abstract, public :: mexax_engine_t
        integer :: max_extrapolation = mexax_max_columns !! KDMAX, 2..12
        integer :: base = mexax_base_midpoint            !! mexax_base_midpoint | _euler
        !> order and step-size control: mexax_control_deuflhard | _hairer
        integer :: control = mexax_control_deuflhard
        !> a and λ at every accepted point from the index-1 system
        !> [M Gᵀ; G 0][a; λ] = [f; −γ] (one more LU a step; needs
        !> constraint_curvature). False, or without γ: the extrapolated values
        !> of the last substeps (§3.7, the original's), which for the
        !> midpoint base lag by a substep.
        logical :: consistent_accelerations = .true.
        type(mexax_native_t) :: native
        integer :: nstab = 0        !! restarts by the stability check, divergence, NaN/Inf
        !> rejections by the projection test (the classic face counts 2 each)
        integer :: nprj_reject = 0
        real(wp) :: h_next = 0.0_wp !! proposed next step (classic H on return)
        integer :: column = 0       !! column used next (k)
        integer :: failed_in = mexax_failed_none !! mexax_failed_step | _projection
        type(mexax_dense_t) :: dense
    end type mexax_engine_t

    !> Everything one integration by `integrate_mechanical` carries from
    !> step to step: the workspace (allocated once, in the set-up), the time
    !> and step, the planned and the converged column, how the attempt
    !> ended, the step-size flags of ODEX and the output position. Local to
    !> the driver.
    type, public :: mexax_run_t
        !> Allocatable (allocated by begin_integration): gfortran 12's
        !> finalization wrapper of a type that holds a workspace_t component
        !> directly frees only the first entity of each component list such
        !> as `type(block_t) :: m0, g0, mm, gm, gn` (valgrind: g0, mm, gm, gn
        !> and gpat leaked on every integration); for an allocatable
        !> component it calls workspace_t's own wrapper, which frees them all.
        type(workspace_t), allocatable :: w
        type(timer_t) :: timer
        type(status_t) :: fst     !! the failure of the attempt's last column or projection
        type(status_t) :: refusal !! the model's last refusal since an accepted step
        real(wp), allocatable :: yout(:) !! (q, v, λ) at an output time
        integer :: k = 0          !! the planned column
        integer :: kc = 0         !! the column the attempt converged in
        integer :: km = 0         !! columns at most (max_extrapolation)
        integer :: decision = undecided !! outcome of the attempt (do_*)
        integer :: iout = 1, nout = 0 !! the next requested output time, their number
        integer :: nstab_nonfinite = 0 !! restarts by non-finite values
        integer :: cause = 0      !! why the attempt of a restart or a stop failed (cause_*)
        real(wp) :: t = 0.0_wp    !! the last accepted point
        real(wp) :: h = 0.0_wp, hmax = 0.0_wp, posneg = 1.0_wp, tscale = 0.0_wp
        real(wp) :: c = 0.0_wp    !! the projection's rejection measure (> 1 rejects)
        real(wp) :: t_old = 0.0_wp
        logical :: first = .true., last = .false., reject = .false.
        logical :: need_start = .false. !! start_point still to be evaluated at t
        logical :: basic_entry = .false. !! the next attempt follows ODEX's basic order
        logical :: want_steps = .false., stop_requested = .false.
        logical :: done = .false. !! the main loop ends
    end type mexax_run_t

contains

    subroutine dense_evaluate(self, s, y)
        class(mexax_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        real(wp) :: h, th, h00, h10, h01, h11
        h = self%t - self%t_old
        if (h == 0.0_wp) then
            y = self%y1
            return
        end if
        th = (s - self%t_old) / h
        h00 = (1.0_wp + 2.0_wp * th) * (1.0_wp - th)**2
        h10 = th * (1.0_wp - th)**2
        h01 = th**2 * (3.0_wp - 2.0_wp * th)
        h11 = th**2 * (th - 1.0_wp)
        y = h00 * self%y0 + h10 * h * self%d0 + h01 * self%y1 + h11 * h * self%d1
    end subroutine dense_evaluate
end module flexmbs_dae_mexax_state
