!> RADAU5's state (docs/theory.md §5): the method's constants, the dense
!> output, the classic counters, the part of the solver that the phases of
!> an integration read and write (`radau5_engine_t`: settings and results,
!> which `radau5_t` extends), the state one integration carries from block
!> to block of the control flow §5.5 (`radau5_work_t`), and F with its
!> finiteness check and the weights of §5.3, which every phase uses.
module flexmbs_dae_radau5_state
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_non_finite
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_matrix, only: matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private
    public :: eval_f, compute_scal, ieee_nan

    ! Method constants (docs/theory.md §5.1), r6 = sqrt(6).
    real(wp), parameter :: sq6 = sqrt(6.0_wp)
    real(wp), parameter, public :: c1 = (4.0_wp - sq6) / 10.0_wp
    real(wp), parameter, public :: c2 = (4.0_wp + sq6) / 10.0_wp
    real(wp), parameter, public :: c1m1 = c1 - 1.0_wp
    real(wp), parameter, public :: c2m1 = c2 - 1.0_wp
    real(wp), parameter, public :: c1mc2 = c1 - c2
    real(wp), parameter, public :: dd1 = -(13.0_wp + 7.0_wp * sq6) / 3.0_wp
    real(wp), parameter, public :: dd2 = (-13.0_wp + 7.0_wp * sq6) / 3.0_wp
    real(wp), parameter, public :: dd3 = -1.0_wp / 3.0_wp
    ! Eigenvalues of A⁻¹: γ (real) and α ± iβ.
    real(wp), parameter, public :: u1 = 3.637834252744495732208419_wp
    real(wp), parameter, public :: alph = 2.681082873627752133895791_wp
    real(wp), parameter, public :: beta = 3.050430199247410569426378_wp
    ! T and T⁻¹ exactly as normalised in §1.2 (the Newton norm depends on it).
    real(wp), parameter, public :: t11 = 0.09123239487089294279155_wp
    real(wp), parameter, public :: t12 = -0.1412552950209542084280_wp
    real(wp), parameter, public :: t13 = -0.03002919410514742449186_wp
    real(wp), parameter, public :: t21 = 0.2417179327071070189575_wp
    real(wp), parameter, public :: t22 = 0.2041293522937999319960_wp
    real(wp), parameter, public :: t23 = 0.3829421127572619377954_wp
    real(wp), parameter, public :: t31 = 0.9660481826150929361906_wp
    real(wp), parameter, public :: ti11 = 4.325579890063155351024_wp
    real(wp), parameter, public :: ti12 = 0.3391992518158098695428_wp
    real(wp), parameter, public :: ti13 = 0.5417705399358748711865_wp
    real(wp), parameter, public :: ti21 = -4.178718591551904727346_wp
    real(wp), parameter, public :: ti22 = -0.3276828207610623870825_wp
    real(wp), parameter, public :: ti23 = 0.4766235545005504519601_wp
    real(wp), parameter, public :: ti31 = -0.5028726349457868759512_wp
    real(wp), parameter, public :: ti32 = 2.571926949855605429187_wp
    real(wp), parameter, public :: ti33 = -0.5960392048282249249688_wp

    real(wp), parameter, public :: err_floor = 1.0e-10_wp     !! §1.7: err = max(err, 1e-10)
    real(wp), parameter, public :: theta_fail = 0.99_wp        !! §1.6: θ ≥ 0.99 is divergence
    !> §1.10 R7: h/10 before any acceptance
    real(wp), parameter, public :: first_reject_factor = 0.1_wp
    real(wp), parameter, public :: failure_factor = 0.5_wp     !! §1.10 R8: h/2
    real(wp), parameter, public :: h_default = 1.0e-6_wp       !! §1.10 R0: initial step guess
    integer, parameter, public :: max_singular = 5             !! §1.10 R8: nsing ≥ 5 gives up
    real(wp), parameter, public :: end_factor = 1.0001_wp      !! §1.10 R0: last-step detection

    ! Control-flow blocks of §1.10.
    integer, parameter, public :: blk_jacobian = 1, blk_factor = 2, blk_attempt = 3

    integer, parameter, public :: radau5_controller_predictive = 1
    integer, parameter, public :: radau5_controller_classical = 2

    !> Collocation polynomial of the last accepted step (§1.8):
    !> u(σ) = y⁺ + σ(q1 + (σ − (c2−1))(q2 + (σ − (c1−1)) q3)), σ = (s − x)/h.
    type, extends(dense_output_t), public :: radau5_dense_t
        real(wp) :: x = 0.0_wp   !! end of the step (x⁺)
        real(wp) :: h = 1.0_wp   !! step size
        real(wp), allocatable :: cont(:, :) !! (n, 0:3): y⁺, q1, q2, q3
    contains
        procedure :: evaluate => dense_evaluate
        procedure :: component => dense_component
    end type radau5_dense_t

    !> The classic code's counters, IWORK(14..20).
    type, public :: radau5_native_t
        integer :: nfcn = 0, njac = 0, nstep = 0, naccpt = 0, nrejct = 0, ndec = 0, nsol = 0
    end type radau5_native_t

    !> RADAU5 settings; a value of 0 selects the default, as in WORK/IWORK.
    !> What the phases of an integration (the modules flexmbs_dae_radau5_*)
    !> read and write; `radau5_t` extends it with the driver.
    type, extends(dae_solver_t), abstract, public :: radau5_engine_t
        integer :: nit = 7                 !! max Newton iterations (IWORK(3))
        real(wp) :: thet = 0.001_wp        !! Jacobian reuse threshold (WORK(3)); < 0: always new
        real(wp) :: fnewt = 0.0_wp         !! Newton stopping tolerance (WORK(4)); 0: §1.6 default
        real(wp) :: quot1 = 1.0_wp         !! keep h and LU when quot1 ≤ h_new/h ≤ quot2 (WORK(5))
        real(wp) :: quot2 = 1.2_wp         !! (WORK(6))
        real(wp) :: safe = 0.9_wp          !! safety factor (WORK(2))
        real(wp) :: fac_min = 0.2_wp       !! h_new/h ≥ fac_min (WORK(8))
        real(wp) :: fac_max = 8.0_wp       !! h_new/h ≤ fac_max (WORK(9))
        real(wp) :: uround = 1.0e-16_wp    !! rounding unit (WORK(1))
        integer :: controller = radau5_controller_predictive !! IWORK(8)
        logical :: zero_start = .false.    !! zero Newton starting values (IWORK(4))
        !> Constant step h0, every converged step accepted (order studies).
        logical :: fixed_step = .false.
        ! Results of the last integration.
        type(radau5_native_t) :: native
        real(wp) :: h_opt = 0.0_wp         !! predicted next step (classic H on return)
        integer :: nsol_error = 0          !! error-estimate solves (not in native NSOL)
        type(radau5_dense_t) :: dense
    end type radau5_engine_t

    !> Everything one integration carries from block to block of §5.5
    !> (R0…R8), in the names of the classic code: the workspace (allocated
    !> once, in the set-up), the matrices and the linear solver, the step
    !> and Newton state, the step-size controller's memory and the output
    !> position. Local to `radau5_integrate`.
    type, public :: radau5_work_t
        integer :: n = 0
        integer :: nind1 = 0, nind2 = 0, nind3 = 0 !! components of index 1, 2, 3
        integer :: nit = 0                  !! max Newton iterations
        integer :: newt = 0                 !! Newton iterations of this attempt
        integer :: block = blk_jacobian     !! the next block of §1.10 (blk_*)
        integer :: nsing = 0                !! singular matrices in a row
        integer :: nout = 0, iout = 1       !! requested output times, the next one
        real(wp) :: x = 0.0_wp, h = 0.0_wp, xend = 0.0_wp, posneg = 1.0_wp
        real(wp) :: hmaxn = 0.0_wp          !! largest |h|
        real(wp) :: hhfac = 0.0_wp          !! index scaling factor of the weights (§1.4)
        real(wp) :: faccon = 1.0_wp, theta = 0.0_wp, thet = 0.0_wp, thqold = 0.0_wp
        real(wp) :: dynold = 0.0_wp, fnewt = 0.0_wp, err = 0.0_wp
        real(wp) :: quot = 1.0_wp, hnew = 0.0_wp, hacc = 0.0_wp, erracc = 0.0_wp
        real(wp) :: hopt = 0.0_wp, hold = 0.0_wp, xold = 0.0_wp
        real(wp) :: hold_saved = 0.0_wp     !! hold before the last acceptance (undo_step)
        real(wp) :: fac1 = 0.0_wp, alphn = 0.0_wp, betan = 0.0_wp !! γ/h, α/h, β/h
        real(wp) :: facl = 0.0_wp, facr = 0.0_wp, uround = 0.0_wp
        logical :: first = .true., reject = .false., last = .false., caljac = .false.
        logical :: mass_identity = .false., stop_requested = .false., want_steps = .false.
        logical :: pred = .true.            !! predictive controller (Gustafsson)
        logical :: fd_jacobian = .false.    !! J by differences (§1.12)
        !> stopped at R3 before the attempt it counted (not in NST)
        logical :: abandoned = .false.
        logical :: done = .false.           !! the main loop ends
        ! Workspace, allocated once per integration.
        real(wp), allocatable :: z1(:), z2(:), z3(:), w1(:), w2(:), w3(:)
        real(wp), allocatable :: f1(:), f2(:), f3(:), f0(:), scal(:), cont(:), ytmp(:)
        real(wp), allocatable :: rtolt(:), atolt(:), mw(:)
        complex(wp), allocatable :: zc(:)
        integer, allocatable :: classes(:)
        type(matrix_t) :: jac, mass
        class(linear_solver_t), allocatable :: ls
        type(timer_t) :: timer
        type(status_t) :: rejection  !! the last refusal since an acceptance
        type(status_t) :: f0_status  !! a failed F at the step start (f0 is NaN then)
    end type radau5_work_t

contains

    subroutine dense_evaluate(self, s, y)
        class(radau5_dense_t), intent(in) :: self
        real(wp), intent(in) :: s
        real(wp), intent(out) :: y(:)
        real(wp) :: sigma
        sigma = (s - self%x) / self%h
        y = self%cont(:, 0) + sigma * (self%cont(:, 1) + (sigma - c2m1) * (self%cont(:, 2) &
            + (sigma - c1m1) * self%cont(:, 3)))
    end subroutine dense_evaluate

    !> Component i of the dense output at s (CONTR5).
    pure real(wp) function dense_component(self, i, s) result(value)
        class(radau5_dense_t), intent(in) :: self
        integer, intent(in) :: i
        real(wp), intent(in) :: s
        real(wp) :: sigma
        sigma = (s - self%x) / self%h
        value = self%cont(i, 0) + sigma * (self%cont(i, 1) + (sigma - c2m1) * (self%cont(i, 2) &
            + (sigma - c1m1) * self%cont(i, 3)))
    end function dense_component

    !> F(tt, yy); a non-finite value fails as the model's (a refusal).
    subroutine eval_f(problem, tt, yy, ff, st)
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: tt, yy(:)
        real(wp), intent(out) :: ff(:)
        type(status_t), intent(out) :: st
        integer :: j
        call problem%rhs(tt, yy, ff, st)
        if (.not. st%ok()) return
        do j = 1, size(ff)
            if (ieee_is_finite(ff(j))) cycle
            call st%set(status_solver_failure, 'non-finite right-hand side in component ' &
                // int_text(j) // ' at t = ' // real_text(tt), reason_non_finite)
            return
        end do
    end subroutine eval_f

    !> sc_i = atol'_i + rtol'_i |y_i| (§1.4).
    subroutine compute_scal(w, y)
        type(radau5_work_t), intent(inout) :: w
        real(wp), intent(in) :: y(:)
        integer :: j
        do j = 1, w%n
            w%scal(j) = w%atolt(j) + w%rtolt(j) * abs(y(j))
        end do
    end subroutine compute_scal

    !> A quiet NaN: f0 after a failing evaluation, so that the next error
    !> estimate is non-finite and the step is rejected.
    real(wp) function ieee_nan()
        use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
        ieee_nan = ieee_value(1.0_wp, ieee_quiet_nan)
    end function ieee_nan
end module flexmbs_dae_radau5_state
