!> `RADAU5`: the 3-stage Radau IIA method of order 5 for M y' = F(t, y).
!>
!> Implemented from the published algorithm [HW96 IV.8, HW99] as specified
!> in docs/theory.md §5: simplified Newton on the stage equations in the
!> variables W = (T⁻¹ ⊗ I) Z, which decouple into a real system with
!> E1 = (γ/h) M − J and a complex one with E2 = ((α + iβ)/h) M − J; the
!> embedded error estimate; Gustafsson's predictive step-size controller;
!> index-2/3 weight scaling; collocation dense output. The control flow
!> R0…R8 of the control flow (docs/theory.md §5.5) decides every counter and is followed
!> literally, so the native counters are those of the classic code.
module flexmbs_dae_radau5
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, &
        status_solver_failure, status_interrupted, reason_step_too_small, reason_max_steps, &
        reason_singular_matrix, reason_non_finite, reason_newton_failure, reason_projection, &
        reason_det_f, &
        reason_user_function
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t, problem_mass_matrix
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_newton_diverged, &
        cause_newton_slow, cause_singular_matrix, cause_model_refused, cause_projection
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private

    ! Method constants (docs/theory.md §5.1), r6 = sqrt(6).
    real(wp), parameter :: sq6 = sqrt(6.0_wp)
    real(wp), parameter :: c1 = (4.0_wp - sq6) / 10.0_wp
    real(wp), parameter :: c2 = (4.0_wp + sq6) / 10.0_wp
    real(wp), parameter :: c1m1 = c1 - 1.0_wp
    real(wp), parameter :: c2m1 = c2 - 1.0_wp
    real(wp), parameter :: c1mc2 = c1 - c2
    real(wp), parameter :: dd1 = -(13.0_wp + 7.0_wp * sq6) / 3.0_wp
    real(wp), parameter :: dd2 = (-13.0_wp + 7.0_wp * sq6) / 3.0_wp
    real(wp), parameter :: dd3 = -1.0_wp / 3.0_wp
    ! Eigenvalues of A⁻¹: γ (real) and α ± iβ.
    real(wp), parameter :: u1 = 3.637834252744495732208419_wp
    real(wp), parameter :: alph = 2.681082873627752133895791_wp
    real(wp), parameter :: beta = 3.050430199247410569426378_wp
    ! T and T⁻¹ exactly as normalised in §1.2 (the Newton norm depends on it).
    real(wp), parameter :: t11 = 0.09123239487089294279155_wp
    real(wp), parameter :: t12 = -0.1412552950209542084280_wp
    real(wp), parameter :: t13 = -0.03002919410514742449186_wp
    real(wp), parameter :: t21 = 0.2417179327071070189575_wp
    real(wp), parameter :: t22 = 0.2041293522937999319960_wp
    real(wp), parameter :: t23 = 0.3829421127572619377954_wp
    real(wp), parameter :: t31 = 0.9660481826150929361906_wp
    real(wp), parameter :: ti11 = 4.325579890063155351024_wp
    real(wp), parameter :: ti12 = 0.3391992518158098695428_wp
    real(wp), parameter :: ti13 = 0.5417705399358748711865_wp
    real(wp), parameter :: ti21 = -4.178718591551904727346_wp
    real(wp), parameter :: ti22 = -0.3276828207610623870825_wp
    real(wp), parameter :: ti23 = 0.4766235545005504519601_wp
    real(wp), parameter :: ti31 = -0.5028726349457868759512_wp
    real(wp), parameter :: ti32 = 2.571926949855605429187_wp
    real(wp), parameter :: ti33 = -0.5960392048282249249688_wp

    real(wp), parameter :: err_floor = 1.0e-10_wp     !! §1.7: err = max(err, 1e-10)
    real(wp), parameter :: theta_fail = 0.99_wp        !! §1.6: θ ≥ 0.99 is divergence
    real(wp), parameter :: first_reject_factor = 0.1_wp !! §1.10 R7: h/10 before any acceptance
    real(wp), parameter :: failure_factor = 0.5_wp     !! §1.10 R8: h/2
    real(wp), parameter :: h_default = 1.0e-6_wp       !! §1.10 R0: initial step guess
    integer, parameter :: max_singular = 5             !! §1.10 R8: nsing ≥ 5 gives up
    real(wp), parameter :: end_factor = 1.0001_wp      !! §1.10 R0: last-step detection

    ! Control-flow blocks of §1.10.
    integer, parameter :: blk_jacobian = 1, blk_factor = 2, blk_attempt = 3

    public :: radau5_controller_predictive, radau5_controller_classical
    integer, parameter :: radau5_controller_predictive = 1
    integer, parameter :: radau5_controller_classical = 2

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
    type, extends(dae_solver_t), public :: radau5_t
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
    contains
        procedure :: integrate_dae => radau5_integrate
        procedure :: name => radau5_name
        procedure :: step_counts => radau5_step_counts
    end type radau5_t

contains

    function radau5_name(self) result(name)
        class(radau5_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'radau5'
    end function radau5_name

    !> Live counts for a display: the classic counters NSTEP and NACCPT.
    subroutine radau5_step_counts(self, attempted, accepted)
        class(radau5_t), intent(in) :: self
        integer, intent(out) :: attempted, accepted
        attempted = self%native%nstep
        accepted = self%native%naccpt
    end subroutine radau5_step_counts

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

    !> Integrate M y' = F(t, y) from (t, y) to t_end (docs/theory.md §5.5).
    subroutine radau5_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(radau5_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(inout) :: t
        real(wp), intent(inout) :: y(:)
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        class(sink_t), intent(inout), optional :: sink
        real(wp), intent(inout), optional :: yp(:)

        ! Workspace, allocated once per integration.
        real(wp), allocatable :: z1(:), z2(:), z3(:), w1(:), w2(:), w3(:)
        real(wp), allocatable :: f1(:), f2(:), f3(:), f0(:), scal(:), cont(:), ytmp(:)
        real(wp), allocatable :: rtolt(:), atolt(:), mw(:)
        complex(wp), allocatable :: zc(:)
        integer, allocatable :: classes(:)
        type(matrix_t) :: jac, mass
        class(linear_solver_t), allocatable :: ls
        type(timer_t) :: timer
        type(status_t) :: fstatus
        type(status_t) :: rejection  !! the last refusal since an acceptance
        type(status_t) :: f0_status  !! a failed F at the step start (f0 is NaN then)

        integer :: n, nind1, nind2, nind3, nit, newt, block, i, nout, iout, stat, cause
        real(wp) :: x, h, xend, posneg, hmaxn, hhfac, faccon, theta, thet, thq, thqold
        real(wp) :: dyno, dynold, dyth, qnewt, fnewt, err, fac, quot, hnew, hacc, erracc
        real(wp) :: facgus, hopt, hold, xold, fac1, alphn, betan, c3q, sig1, sig2, sig3
        real(wp) :: facl, facr, expm, qt, uround, hee1, hee2, hee3, ak1, ak2, ak3, ak
        logical :: first, reject, last, caljac, mass_identity, stop_requested, want_steps
        logical :: singular, pred, fd_jacobian
        logical :: abandoned !! stopped at R3 before the attempt it counted (not in NST)
        real(wp) :: hold_saved
        integer :: nsing, naccpt_at_prj

        call timer%start()
        stats%t_reached = t
        fd_jacobian = .false.
        abandoned = .false.
        self%native = radau5_native_t()
        self%h_opt = 0.0_wp
        self%nsol_error = 0
        n = problem%n
        x = t
        xend = t_end

        ! ---- R0: set-up and validation (§1.13) ----
        if (size(y) /= n .or. n <= 0) then
            call status%set(status_bad_input, 'radau5: size of y differs from problem%n')
            return
        end if
        call options%validate(n, status)
        if (.not. status%ok()) return
        if (self%fixed_step .and. .not. options%h0 > 0.0_wp) then
            call bad('fixed_step needs a positive h0')
            return
        end if
        uround = self%uround
        if (uround <= 1.0e-19_wp .or. uround >= 1.0_wp) then
            call bad('uround must lie in (1e-19, 1)')
            return
        end if
        nit = self%nit
        if (nit <= 0) then
            call bad('nit must be positive')
            return
        end if
        if (self%safe <= 0.001_wp .or. self%safe >= 1.0_wp) then
            call bad('safe must lie in (0.001, 1)')
            return
        end if
        thet = self%thet
        if (thet >= 1.0_wp) then
            call bad('thet must be below 1')
            return
        end if
        if (self%quot1 > 1.0_wp .or. self%quot2 < 1.0_wp) then
            call bad('need quot1 <= 1 <= quot2')
            return
        end if
        if (self%fac_min > 1.0_wp .or. self%fac_max < 1.0_wp) then
            call bad('need fac_min <= 1 <= fac_max')
            return
        end if
        allocate (rtolt(n), atolt(n), classes(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'radau5 tolerances and index classes', 3_i8 * n, 8)
            return
        end if
        call options%tolerances(rtolt, atolt)
        if (any(atolt <= 0.0_wp) .or. any(rtolt <= 10.0_wp * uround)) then
            call bad('tolerances must satisfy atol > 0 and rtol > 10*uround')
            return
        end if
        ! §1.4: internal tolerances rtol' = 0.1 rtol^(2/3), atol' = rtol' atol/rtol.
        expm = 2.0_wp / 3.0_wp
        do i = 1, n
            qt = atolt(i) / rtolt(i)
            rtolt(i) = 0.1_wp * rtolt(i)**expm
            atolt(i) = rtolt(i) * qt
        end do
        if (self%fnewt == 0.0_wp) then
            fnewt = max(10.0_wp * uround / rtolt(1), min(0.03_wp, rtolt(1)**0.5_wp))
        else
            fnewt = self%fnewt
            if (fnewt <= uround / rtolt(1)) then
                call bad('fnewt must exceed uround/rtol''')
                return
            end if
        end if
        call problem%index_classes(classes)
        if (any(classes < 1 .or. classes > 3)) then
            call bad('index classes must be 1, 2 or 3')
            return
        end if
        do i = 2, n
            if (classes(i) < classes(i - 1)) then
                call bad('components must be ordered by index class (1s, then 2s, then 3s)')
                return
            end if
        end do
        nind1 = count(classes == 1)
        nind2 = count(classes == 2)
        nind3 = count(classes == 3)

        ! Matrices and the linear solver: patterns fixed here, once.
        call setup_matrices(status)
        if (.not. status%ok()) return
        ! A dense J holds no values yet, so its band cannot be seen at init.
        if (options%linear_solver == 'band' .and. jac%storage == storage_dense .and. &
            options%band_lower < 0) then
            call bad("linear_solver = 'band' with a dense or difference Jacobian needs " // &
                "options%band_lower and band_upper; or give J as a sparse pattern")
            return
        end if
        ! the problem's own solver of c M − J (condensed Newton systems), or ours
        if (jac%storage == storage_sparse) call problem%iteration_solver(options, ls, status)
        if (.not. status%ok()) return
        if (.not. allocated(ls)) call new_linear_solver(options%linear_solver, n, jac%storage, &
            ls, status, options%band_lower, options%band_upper, options%sparse_ordering, &
            mass=mass, jac=jac)
        if (.not. status%ok()) return
        call ls%init(mass, jac, status)
        if (.not. status%ok()) return

        if (allocated(self%dense%cont)) deallocate (self%dense%cont)
        allocate (z1(n), z2(n), z3(n), w1(n), w2(n), w3(n), f1(n), f2(n), f3(n), f0(n), &
            scal(n), cont(n), ytmp(n), mw(n), zc(n), self%dense%cont(n, 0:3), stat=stat)
        if (stat /= 0) then
            ! 14 real vectors, zc complex (2), the dense output's 4 columns
            call out_of_memory(status, 'radau5 workspace', 20_i8 * n, 8)
            return
        end if

        posneg = sign(1.0_wp, xend - x)
        if (options%hmax > 0.0_wp) then
            hmaxn = min(abs(options%hmax), abs(xend - x))
        else
            hmaxn = abs(xend - x)
        end if
        h = options%h0
        if (abs(h) <= 10.0_wp * uround) h = h_default
        h = sign(min(abs(h), hmaxn), posneg)
        hold = h
        last = .false.
        if ((x + h * end_factor - xend) * posneg >= 0.0_wp) then
            h = xend - x
            last = .true.
        end if
        hopt = h
        faccon = 1.0_wp
        nsing = 0
        first = .true.
        reject = .false.
        caljac = .false.
        theta = abs(thet)
        thqold = 0.0_wp
        dynold = 0.0_wp
        hacc = 0.0_wp
        erracc = 0.0_wp
        hnew = h
        quot = 1.0_wp
        err = 0.0_wp
        newt = 0
        pred = self%controller <= radau5_controller_predictive
        facl = 1.0_wp / self%fac_min
        facr = 1.0_wp / self%fac_max
        mass_identity = mass%storage == storage_identity
        stop_requested = .false.
        want_steps = .false.
        if (present(sink)) want_steps = sink%wants_steps()
        nout = 0
        if (allocated(options%output_times)) nout = size(options%output_times)
        iout = 1
        naccpt_at_prj = 0

        ! Output at t0: requested times equal to t0, and the step sink (NR = 1).
        self%dense%x = x
        self%dense%h = h
        self%dense%cont(:, 0) = y
        self%dense%cont(:, 1:3) = 0.0_wp
        if (present(sink)) then
            do while (iout <= nout)
                if ((options%output_times(iout) - x) * posneg > 0.0_wp) exit
                if (options%output_times(iout) == x) call sink%output(x, y, status)
                iout = iout + 1
                if (.not. status%ok()) exit
            end do
            if (want_steps .and. status%ok()) &
                call sink%step(1, x, x, y, self%dense, stop_requested, status)
            if (.not. status%ok()) then
                call finish()
                return
            end if
            if (stop_requested) then
                call interrupted()
                return
            end if
        end if

        call compute_scal()
        hhfac = h
        call eval_f(x, y, f0, fstatus)
        self%native%nfcn = self%native%nfcn + 1
        if (.not. fstatus%ok()) then
            call status%set(status_solver_failure, 'radau5: right-hand side failed at t = ' &
                // real_text(x) // ': ' // fstatus%text(), merge(reason_det_f, &
                reason_user_function, fstatus%reason == reason_det_f))
            call finish()
            return
        end if
        block = blk_jacobian

        main: do
            select case (block)

            case (blk_jacobian) ! ---- R1 ----
                self%native%njac = self%native%njac + 1
                call compute_jacobian(fstatus)
                if (.not. fstatus%ok()) then
                    call status%set(status_solver_failure, 'radau5: Jacobian failed at t = ' &
                        // real_text(x) // ': ' // fstatus%text(), fstatus%reason)
                    exit main
                end if
                caljac = .true.
                block = blk_factor

            case (blk_factor) ! ---- R2 ----
                fac1 = u1 / h
                alphn = alph / h
                betan = beta / h
                call ls%factor_real(fac1, mass, jac, fstatus)
                singular = .not. fstatus%ok()
                if (.not. singular) then
                    call ls%factor_complex(cmplx(alphn, betan, kind=wp), mass, jac, fstatus)
                    singular = .not. fstatus%ok()
                end if
                ! Misuse (e.g. J outside the band fixed at init) is no singularity.
                if (fstatus%code == status_bad_input) then
                    status = fstatus
                    exit main
                end if
                if (singular) then
                    ! an attempt at this h that failed before R3: counted in NST
                    nsing = nsing + 1
                    if (nsing >= max_singular) then
                        call stats%rejections%add(cause_singular_matrix)
                        call status%set(status_solver_failure, &
                            'radau5: matrix is repeatedly singular at t = ' // real_text(x), &
                            reason_singular_matrix)
                        exit main
                    end if
                    call unexpected_failure(cause_singular_matrix)
                    cycle main
                end if
                self%native%ndec = self%native%ndec + 1
                block = blk_attempt

            case (blk_attempt) ! ---- R3 ----
                self%native%nstep = self%native%nstep + 1
                if (self%native%nstep > options%max_steps) then
                    abandoned = .true.
                    call status%set(status_solver_failure, 'radau5: more than ' // &
                        int_text(options%max_steps) // ' steps needed; stopped at t = ' // &
                        real_text(x), reason_max_steps)
                    exit main
                end if
                if (0.1_wp * abs(h) <= abs(x) * uround) then
                    abandoned = .true.
                    ! A model refusal that forced the step down is the reason
                    ! (its text closes the message: finish).
                    call status%set(status_solver_failure, 'radau5: step size too small, h = ' &
                        // real_text(h) // ' at t = ' // real_text(x), merge(reason_det_f, &
                        reason_step_too_small, rejection%reason == reason_det_f))
                    exit main
                end if
                ! §1.4: cumulative index scaling of the weights.
                if (nind2 > 0) scal(nind1 + 1:nind1 + nind2) = scal(nind1 + 1:nind1 + nind2) / hhfac
                if (nind3 > 0) scal(nind1 + nind2 + 1:n) = scal(nind1 + nind2 + 1:n) / (hhfac * hhfac)
                ! §1.5: starting values.
                if (first .or. self%zero_start) then
                    z1 = 0.0_wp; z2 = 0.0_wp; z3 = 0.0_wp
                    w1 = 0.0_wp; w2 = 0.0_wp; w3 = 0.0_wp
                else
                    c3q = h / hold
                    sig1 = c1 * c3q
                    sig2 = c2 * c3q
                    sig3 = c3q
                    do i = 1, n
                        ak1 = self%dense%cont(i, 1)
                        ak2 = self%dense%cont(i, 2)
                        ak3 = self%dense%cont(i, 3)
                        z1(i) = sig1 * (ak1 + (sig1 - c2m1) * (ak2 + (sig1 - c1m1) * ak3))
                        z2(i) = sig2 * (ak1 + (sig2 - c2m1) * (ak2 + (sig2 - c1m1) * ak3))
                        z3(i) = sig3 * (ak1 + (sig3 - c2m1) * (ak2 + (sig3 - c1m1) * ak3))
                        w1(i) = ti11 * z1(i) + ti12 * z2(i) + ti13 * z3(i)
                        w2(i) = ti21 * z1(i) + ti22 * z2(i) + ti23 * z3(i)
                        w3(i) = ti31 * z1(i) + ti32 * z2(i) + ti33 * z3(i)
                    end do
                end if

                ! §1.6: simplified Newton iteration.
                faccon = max(faccon, uround)**0.8_wp
                theta = abs(thet)
                newt = 0
                newton: do
                    if (newt >= nit) then
                        call unexpected_failure(cause_newton_slow)
                        cycle main
                    end if
                    ytmp = y + z1
                    call eval_f(x + c1 * h, ytmp, f1, fstatus)
                    ytmp = y + z2
                    if (fstatus%ok()) call eval_f(x + c2 * h, ytmp, f2, fstatus)
                    ytmp = y + z3
                    if (fstatus%ok()) call eval_f(x + h, ytmp, f3, fstatus)
                    self%native%nfcn = self%native%nfcn + 3
                    if (.not. fstatus%ok()) then
                        call unexpected_failure(cause_model_refused)
                        cycle main
                    end if
                    ! G = (T⁻¹ ⊗ I) F, then the transformed residuals r1, r2 + i r3.
                    do i = 1, n
                        ak1 = f1(i); ak2 = f2(i); ak3 = f3(i)
                        f1(i) = ti11 * ak1 + ti12 * ak2 + ti13 * ak3
                        f2(i) = ti21 * ak1 + ti22 * ak2 + ti23 * ak3
                        f3(i) = ti31 * ak1 + ti32 * ak2 + ti33 * ak3
                    end do
                    call newton_residual()
                    call ls%solve_real(f1)
                    zc = cmplx(f2, f3, kind=wp)
                    call ls%solve_complex(zc)
                    f2 = real(zc, wp)
                    f3 = aimag(zc)
                    self%native%nsol = self%native%nsol + 1
                    newt = newt + 1
                    dyno = 0.0_wp
                    do i = 1, n
                        dyno = dyno + (f1(i) / scal(i))**2 + (f2(i) / scal(i))**2 &
                            + (f3(i) / scal(i))**2
                    end do
                    dyno = sqrt(dyno / real(3 * n, wp))
                    if (.not. ieee_is_finite(dyno)) then
                        call unexpected_failure(cause_newton_diverged)
                        cycle main
                    end if
                    if (newt > 1 .and. newt < nit) then
                        thq = dyno / dynold
                        if (newt == 2) then
                            theta = thq
                        else
                            theta = sqrt(thq * thqold)
                        end if
                        thqold = thq
                        if (theta < theta_fail) then
                            faccon = theta / (1.0_wp - theta)
                            dyth = faccon * dyno * theta**(nit - 1 - newt) / fnewt
                            if (dyth >= 1.0_wp) then
                                ! Convergence too slow: smaller h, same Jacobian.
                                qnewt = max(1.0e-4_wp, min(20.0_wp, dyth))
                                hhfac = 0.8_wp * qnewt**(-1.0_wp / real(4 + nit - 1 - newt, wp))
                                h = hhfac * h
                                call stats%rejections%add(cause_newton_slow)
                                reject = .true.
                                last = .false.
                                call retry_after_failure()
                                cycle main
                            end if
                        else
                            call unexpected_failure(cause_newton_diverged)
                            cycle main
                        end if
                    end if
                    dynold = max(dyno, uround)
                    do i = 1, n
                        w1(i) = w1(i) + f1(i)
                        w2(i) = w2(i) + f2(i)
                        w3(i) = w3(i) + f3(i)
                        z1(i) = t11 * w1(i) + t12 * w2(i) + t13 * w3(i)
                        z2(i) = t21 * w1(i) + t22 * w2(i) + t23 * w3(i)
                        z3(i) = t31 * w1(i) + w2(i)
                    end do
                    if (faccon * dyno <= fnewt) exit newton
                end do newton

                ! §1.7: error estimate.
                if (self%fixed_step) then
                    err = err_floor
                    fstatus%code = status_ok
                else
                    call estimate_error(fstatus, cause)
                end if
                if (.not. fstatus%ok()) then
                    ! a NaN f0 (F failed at the step start) is the model's refusal
                    if (cause == cause_error_test .and. .not. f0_status%ok()) then
                        fstatus = f0_status
                        cause = cause_model_refused
                    end if
                    call unexpected_failure(cause)
                    cycle main
                end if
                ! §1.9: step-size proposal.
                fac = min(self%safe, self%safe * real(1 + 2 * nit, wp) / real(newt + 2 * nit, wp))
                quot = max(facr, min(facl, err**0.25_wp / fac))
                hnew = h / quot
                if (self%fixed_step) hnew = h

                if (err < 1.0_wp) then
                    ! ---- R4: accept ----
                    first = .false.
                    self%native%naccpt = self%native%naccpt + 1
                    if (pred .and. .not. self%fixed_step) then
                        if (self%native%naccpt > 1) then
                            facgus = (hacc / h) * (err**2 / erracc)**0.25_wp / self%safe
                            facgus = max(facr, min(facl, facgus))
                            quot = max(quot, facgus)
                            hnew = h / quot
                        end if
                        hacc = h
                        erracc = max(1.0e-2_wp, err)
                    end if
                    xold = x
                    hold_saved = hold
                    hold = h
                    cont = y
                    x = x + h
                    if (last) x = xend
                    do i = 1, n
                        y(i) = y(i) + z3(i)
                        ak = (z1(i) - z2(i)) / c1mc2
                        self%dense%cont(i, 1) = (z2(i) - z3(i)) / c2m1
                        self%dense%cont(i, 2) = (ak - self%dense%cont(i, 1)) / c1m1
                        self%dense%cont(i, 3) = self%dense%cont(i, 2) - (ak - z1(i) / c1) / c2
                    end do
                    ! §6: projection hook on the accepted step.
                    if (problem%has_projection()) then
                        call problem%project(x, y, fstatus)
                        stats%nprj = stats%nprj + 1
                        if (.not. fstatus%ok() .or. .not. all(ieee_is_finite(y))) then
                            call undo_step(cause_projection)
                            cycle main
                        end if
                    end if
                    ! A state the model cannot hold (det F <= 0) is never accepted.
                    call problem%admissible(x, y, fstatus)
                    if (.not. fstatus%ok()) then
                        call undo_step(cause_model_refused)
                        cycle main
                    end if
                    call rejection%clear()
                    self%dense%cont(:, 0) = y
                    self%dense%x = x
                    self%dense%h = h
                    stats%t_reached = x
                    stats%h_last = h
                    call compute_scal()
                    if (present(sink)) then
                        call emit_outputs()
                        if (.not. status%ok()) exit main
                        if (stop_requested) then
                            call status%set(status_interrupted, &
                                'radau5: interrupted by the output routine at t = ' // real_text(x))
                            exit main
                        end if
                    end if
                    caljac = .false.
                    if (last) then
                        self%h_opt = hopt
                        exit main
                    end if
                    call eval_f(x, y, f0, fstatus)
                    self%native%nfcn = self%native%nfcn + 1
                    ! A failing f0 shows up as a non-finite error estimate next step.
                    f0_status = fstatus
                    if (.not. fstatus%ok()) f0 = ieee_nan()
                    ! ---- R5: next step ----
                    hnew = posneg * min(abs(hnew), hmaxn)
                    hopt = min(h, hnew)
                    if (reject) hnew = posneg * min(abs(hnew), abs(h))
                    reject = .false.
                    if ((x + hnew / self%quot1 - xend) * posneg >= 0.0_wp .or. (self%fixed_step &
                        .and. (x + hnew * end_factor - xend) * posneg >= 0.0_wp)) then
                        h = xend - x
                        last = .true.
                    else
                        qt = hnew / h
                        hhfac = h
                        if (theta <= thet .and. qt >= self%quot1 .and. qt <= self%quot2) then
                            block = blk_attempt
                            cycle main
                        end if
                        h = hnew
                    end if
                    ! ---- R6 ----
                    hhfac = h
                    if (theta <= thet) then
                        block = blk_factor
                    else
                        block = blk_jacobian
                    end if
                else
                    ! ---- R7: reject ----
                    reject = .true.
                    last = .false.
                    if (first) then
                        h = h * first_reject_factor
                        hhfac = first_reject_factor
                    else
                        hhfac = hnew / h
                        h = hnew
                    end if
                    if (self%native%naccpt >= 1) self%native%nrejct = self%native%nrejct + 1
                    call stats%rejections%add(cause_error_test)
                    call retry_after_failure()
                end if
            end select
        end do main

        t = x
        call finish()

    contains

        subroutine bad(reason)
            character(len=*), intent(in) :: reason
            call status%set(status_bad_input, 'radau5: ' // reason)
        end subroutine bad

        subroutine interrupted()
            call status%set(status_interrupted, &
                'radau5: interrupted by the output routine at t = ' // real_text(x))
            call finish()
        end subroutine interrupted

        !> Common statistics from the native counters (docs/solvers.md): NST
        !> counts the attempts made, those that ended at R2 with a singular
        !> matrix included, the one R3 stopped on (native NSTEP) not.
        subroutine finish()
            type(status_t) :: sink_status
            stats%nst = self%native%nstep + stats%rejections%count_of(cause_singular_matrix)
            if (abandoned) stats%nst = stats%nst - 1
            stats%nac = self%native%naccpt
            stats%nrj = stats%nst - stats%nac
            stats%nfe = self%native%nfcn
            stats%nje = self%native%njac
            stats%ndec = self%native%ndec
            stats%nsol = self%native%nsol + self%nsol_error
            stats%t_reached = x
            if (self%h_opt == 0.0_wp) self%h_opt = hopt
            stats%cpu = timer%cpu()
            stats%wall = timer%wall()
            call stats%rejections%annotate(status)
            if (present(sink)) then
                call sink%finish(sink_status)
                if (status%ok() .and. .not. sink_status%ok()) status = sink_status
            end if
        end subroutine finish

        !> F(tt, yy); a non-finite value fails as the model's (a refusal).
        subroutine eval_f(tt, yy, ff, st)
            real(wp), intent(in) :: tt, yy(:)
            real(wp), intent(out) :: ff(:)
            type(status_t), intent(out) :: st
            integer :: j
            call problem%rhs(tt, yy, ff, st)
            if (.not. st%ok()) return
            do j = 1, n
                if (ieee_is_finite(ff(j))) cycle
                call st%set(status_solver_failure, 'non-finite right-hand side in component ' &
                    // int_text(j) // ' at t = ' // real_text(tt), reason_non_finite)
                return
            end do
        end subroutine eval_f

        !> sc_i = atol'_i + rtol'_i |y_i| (§1.4).
        subroutine compute_scal()
            integer :: j
            do j = 1, n
                scal(j) = atolt(j) + rtolt(j) * abs(y(j))
            end do
        end subroutine compute_scal

        !> Take back the step just accepted and retry with h/2, counted like R8
        !> (`cause`: its projection failed, or the model refused its state).
        subroutine undo_step(cause)
            integer, intent(in) :: cause
            y = cont
            x = xold
            hold = hold_saved
            self%native%naccpt = self%native%naccpt - 1
            call unexpected_failure(cause)
        end subroutine undo_step

        !> §1.10 R8: h/2 after a Newton failure, a singular matrix, a refusal
        !> (fstatus says why) or a non-finite value, counted by `cause`.
        subroutine unexpected_failure(cause)
            integer, intent(in) :: cause
            if (cause == cause_model_refused) then
                rejection = fstatus
                call stats%rejections%refuse(fstatus%text())
            else
                call stats%rejections%add(cause)
            end if
            h = h * failure_factor
            hhfac = failure_factor
            reject = .true.
            last = .false.
            call retry_after_failure()
        end subroutine unexpected_failure

        !> Retry with the new h: refactor if J is fresh, else a new J first.
        subroutine retry_after_failure()
            if (caljac) then
                block = blk_factor
            else
                block = blk_jacobian
            end if
        end subroutine retry_after_failure

        !> r1 = G1 − (γ/h) M w1; r2 = G2 − (α/h) M w2 + (β/h) M w3;
        !> r3 = G3 − (β/h) M w2 − (α/h) M w3 (§1.3 step 2).
        subroutine newton_residual()
            integer :: j
            real(wp) :: s2, s3
            if (mass_identity) then
                do j = 1, n
                    s2 = -w2(j)
                    s3 = -w3(j)
                    f1(j) = f1(j) - w1(j) * fac1
                    f2(j) = f2(j) + s2 * alphn - s3 * betan
                    f3(j) = f3(j) + s3 * alphn + s2 * betan
                end do
            else
                call mass%matvec(w1, mw)
                f1 = f1 - fac1 * mw
                call mass%matvec(w2, mw)
                f2 = f2 - alphn * mw
                f3 = f3 - betan * mw
                call mass%matvec(w3, mw)
                f2 = f2 + betan * mw
                f3 = f3 - alphn * mw
            end if
        end subroutine newton_residual

        !> §1.7: err from ê = E1⁻¹(f0 + v), v = h⁻¹ M Σ e_i z_i; a second
        !> estimate from f(x, y + ê) on the first step or after a rejection.
        !> A failure's cause: a non-finite err fails the error test, a failed
        !> F is the model's refusal.
        subroutine estimate_error(st, cause)
            type(status_t), intent(out) :: st
            integer, intent(out) :: cause
            integer :: j
            cause = cause_error_test
            hee1 = dd1 / h
            hee2 = dd2 / h
            hee3 = dd3 / h
            do j = 1, n
                f1(j) = hee1 * z1(j) + hee2 * z2(j) + hee3 * z3(j)
            end do
            if (mass_identity) then
                f2 = f1
            else
                call mass%matvec(f1, f2)
            end if
            cont = f2 + f0
            call ls%solve_real(cont)
            self%nsol_error = self%nsol_error + 1
            call weighted_error()
            if (.not. ieee_is_finite(err)) then
                call st%set(status_solver_failure, 'non-finite error estimate', reason_non_finite)
                return
            end if
            if (err < 1.0_wp) return
            if (first .or. reject) then
                cont = y + cont
                call eval_f(x, cont, f1, st)
                self%native%nfcn = self%native%nfcn + 1
                if (.not. st%ok()) cause = cause_model_refused
                if (.not. st%ok()) return
                cont = f1 + f2
                call ls%solve_real(cont)
                self%nsol_error = self%nsol_error + 1
                call weighted_error()
                if (.not. ieee_is_finite(err)) call st%set(status_solver_failure, &
                    'non-finite error estimate', reason_non_finite)
            end if
        end subroutine estimate_error

        subroutine weighted_error()
            integer :: j
            err = 0.0_wp
            do j = 1, n
                err = err + (cont(j) / scal(j))**2
            end do
            err = sqrt(err / real(n, wp))
            if (ieee_is_finite(err)) err = max(err, err_floor)
        end subroutine weighted_error

        !> Storage of J and M fixed once for the integration.
        subroutine setup_matrices(st)
            type(status_t), intent(inout) :: st
            integer :: storage
            storage = problem%jacobian_storage()
            if (options%jacobian == 'fd') storage = storage_none
            jac%n = n
            select case (storage)
            case (storage_sparse)
                jac%storage = storage_sparse
                call problem%jacobian_pattern(jac%csc, st)
                if (.not. st%ok()) return
            case default
                ! A dense J, or a difference Jacobian held as dense values.
                fd_jacobian = storage /= storage_dense
                jac%storage = storage_dense
                allocate (jac%dense(n, n), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(st, 'radau5 dense Jacobian', int(n, i8) * n, 8)
                    return
                end if
            end select
            call problem_mass_matrix(problem, mass, st, 'radau5')
        end subroutine setup_matrices

        !> J at (x, y): analytic, or by forward differences (§1.12; these
        !> calls are not counted in NFCN).
        subroutine compute_jacobian(st)
            type(status_t), intent(out) :: st
            integer :: j
            real(wp) :: delt, ysafe
            if (fd_jacobian) then
                ytmp = y
                do j = 1, n
                    ysafe = ytmp(j)
                    delt = sqrt(uround * max(1.0e-5_wp, abs(ysafe)))
                    ytmp(j) = ysafe + delt
                    call eval_f(x, ytmp, cont, st)
                    stats%nfe_jac = stats%nfe_jac + 1
                    if (.not. st%ok()) return
                    jac%dense(:, j) = (cont - f0) / delt
                    ytmp(j) = ysafe
                end do
                if (.not. all(ieee_is_finite(jac%dense))) call st%set(status_solver_failure, &
                    'non-finite difference Jacobian', reason_non_finite)
                return
            end if
            select case (jac%storage)
            case (storage_sparse)
                call problem%jacobian_sparse(x, y, jac%csc%values, st)
                if (st%ok() .and. .not. all(ieee_is_finite(jac%csc%values))) &
                    call st%set(status_solver_failure, 'non-finite Jacobian', reason_non_finite)
            case (storage_dense)
                call problem%jacobian_dense(x, y, jac%dense, st)
                if (st%ok() .and. .not. all(ieee_is_finite(jac%dense))) &
                    call st%set(status_solver_failure, 'non-finite Jacobian', reason_non_finite)
            end select
        end subroutine compute_jacobian

        !> Dense output at requested times in (xold, x], then the step sink.
        subroutine emit_outputs()
            do while (iout <= nout)
                if ((options%output_times(iout) - x) * posneg > 0.0_wp) exit
                call self%dense%evaluate(options%output_times(iout), ytmp)
                call sink%output(options%output_times(iout), ytmp, status)
                iout = iout + 1
                if (.not. status%ok()) return
            end do
            if (want_steps) call sink%step(self%native%naccpt + 1, xold, x, y, self%dense, &
                stop_requested, status)
        end subroutine emit_outputs

        real(wp) function ieee_nan()
            use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
            ieee_nan = ieee_value(1.0_wp, ieee_quiet_nan)
        end function ieee_nan
    end subroutine radau5_integrate
end module flexmbs_dae_radau5
