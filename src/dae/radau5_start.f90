!> The start of a RADAU5 integration (docs/theory.md §5.5, block R0): the
!> input and settings checked, the internal tolerances and the index
!> classes (§5.3), the matrices and the linear solver fixed and the
!> workspace allocated (once, here), the first step size, the output at t0
!> and F at t0.
module flexmbs_dae_radau5_start
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: real_text
    use flexmbs_core_rules, only: rule_reason, safety_factor_rule
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        status_interrupted, reason_det_f, reason_user_function
    use flexmbs_linalg_matrix, only: storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t, problem_mass_matrix
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_radau5_state, only: radau5_engine_t, radau5_work_t, eval_f, compute_scal, &
        h_default, end_factor, blk_jacobian, radau5_controller_predictive
    implicit none
    private
    public :: begin_integration, output_start, start_step

contains

    !> R0 up to the first step: validate, fix the storages and the linear
    !> solver, allocate the workspace and choose the first h. On failure
    !> `status` says why (nothing has been output yet).
    subroutine begin_integration(self, w, problem, t, y, t_end, options, status)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: t, y(:), t_end
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        w%n = problem%n
        w%x = t
        w%xend = t_end

        ! ---- R0: set-up and validation (§1.13) ----
        if (size(y) /= w%n .or. w%n <= 0) then
            call status%set(status_bad_input, 'radau5: size of y differs from problem%n')
            return
        end if
        call options%validate(w%n, status)
        if (.not. status%ok()) return
        call check_settings(self, w, options, status)
        if (.not. status%ok()) return
        call set_error_control(self, w, problem, options, status)
        if (.not. status%ok()) return

        ! Matrices and the linear solver: patterns fixed here, once.
        call setup_matrices(w, problem, options, status)
        if (.not. status%ok()) return
        ! A dense J holds no values yet, so its band cannot be seen at init.
        if (options%linear_solver == 'band' .and. w%jac%storage == storage_dense .and. &
            options%band_lower < 0) then
            call bad(status, "linear_solver = 'band' with a dense or difference Jacobian needs " &
                // "options%band_lower and band_upper; or give J as a sparse pattern")
            return
        end if
        call setup_linear_solver(w, problem, options, status)
        if (.not. status%ok()) return
        call allocate_workspace(self, w, status)
        if (.not. status%ok()) return
        call first_step_size(self, w, options)
    end subroutine begin_integration

    subroutine bad(status, reason)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: reason
        call status%set(status_bad_input, 'radau5: ' // reason)
    end subroutine bad

    !> The settings of `self` against the ranges of §1.13.
    subroutine check_settings(self, w, options, status)
        class(radau5_engine_t), intent(in) :: self
        type(radau5_work_t), intent(inout) :: w
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        if (self%fixed_step .and. .not. options%h0 > 0.0_wp) then
            call bad(status, 'fixed_step needs a positive h0')
            return
        end if
        w%uround = self%uround
        if (w%uround <= 1.0e-19_wp .or. w%uround >= 1.0_wp) then
            call bad(status, 'uround must lie in (1e-19, 1)')
            return
        end if
        w%nit = self%nit
        if (w%nit <= 0) then
            call bad(status, 'nit must be positive')
            return
        end if
        if (len(rule_reason(safety_factor_rule, self%safe, .false.)) > 0) then
            call bad(status, 'safe ' // rule_reason(safety_factor_rule, self%safe, .false.))
            return
        end if
        w%thet = self%thet
        if (w%thet >= 1.0_wp) then
            call bad(status, 'thet must be below 1')
            return
        end if
        if (self%quot1 > 1.0_wp .or. self%quot2 < 1.0_wp) then
            call bad(status, 'need quot1 <= 1 <= quot2')
            return
        end if
        if (self%fac_min > 1.0_wp .or. self%fac_max < 1.0_wp) then
            call bad(status, 'need fac_min <= 1 <= fac_max')
            return
        end if
    end subroutine check_settings

    !> §1.4: the internal tolerances, the Newton tolerance (§1.6) and the
    !> index classes, ordered 1s, then 2s, then 3s.
    subroutine set_error_control(self, w, problem, options, status)
        class(radau5_engine_t), intent(in) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        real(wp) :: expm, qt
        integer :: i, n, stat
        n = w%n
        allocate (w%rtolt(n), w%atolt(n), w%classes(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'radau5 tolerances and index classes', 3_i8 * n, 8)
            return
        end if
        call options%tolerances(w%rtolt, w%atolt)
        if (any(w%atolt <= 0.0_wp) .or. any(w%rtolt <= 10.0_wp * w%uround)) then
            call bad(status, 'tolerances must satisfy atol > 0 and rtol > 10*uround')
            return
        end if
        ! §1.4: internal tolerances rtol' = 0.1 rtol^(2/3), atol' = rtol' atol/rtol.
        expm = 2.0_wp / 3.0_wp
        do i = 1, n
            qt = w%atolt(i) / w%rtolt(i)
            w%rtolt(i) = 0.1_wp * w%rtolt(i)**expm
            w%atolt(i) = w%rtolt(i) * qt
        end do
        if (self%fnewt == 0.0_wp) then
            w%fnewt = max(10.0_wp * w%uround / w%rtolt(1), min(0.03_wp, w%rtolt(1)**0.5_wp))
        else
            w%fnewt = self%fnewt
            if (w%fnewt <= w%uround / w%rtolt(1)) then
                call bad(status, 'fnewt must exceed uround/rtol''')
                return
            end if
        end if
        call problem%index_classes(w%classes)
        if (any(w%classes < 1 .or. w%classes > 3)) then
            call bad(status, 'index classes must be 1, 2 or 3')
            return
        end if
        do i = 2, n
            if (w%classes(i) < w%classes(i - 1)) then
                call bad(status, 'components must be ordered by index class (1s, then 2s, ' // &
                    'then 3s)')
                return
            end if
        end do
        w%nind1 = count(w%classes == 1)
        w%nind2 = count(w%classes == 2)
        w%nind3 = count(w%classes == 3)
    end subroutine set_error_control

    !> Storage of J and M fixed once for the integration.
    subroutine setup_matrices(w, problem, options, st)
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: st
        integer :: storage, n, stat
        n = w%n
        storage = problem%jacobian_storage()
        if (options%jacobian == 'fd') storage = storage_none
        w%jac%n = n
        select case (storage)
        case (storage_sparse)
            w%jac%storage = storage_sparse
            call problem%jacobian_pattern(w%jac%csc, st)
            if (.not. st%ok()) return
        case default
            ! A dense J, or a difference Jacobian held as dense values.
            w%fd_jacobian = storage /= storage_dense
            w%jac%storage = storage_dense
            allocate (w%jac%dense(n, n), stat=stat)
            if (stat /= 0) then
                call out_of_memory(st, 'radau5 dense Jacobian', int(n, i8) * n, 8)
                return
            end if
        end select
        call problem_mass_matrix(problem, w%mass, st, 'radau5')
    end subroutine setup_matrices

    !> The linear solver of E1 and E2 for the storages fixed above.
    subroutine setup_linear_solver(w, problem, options, status)
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        ! the problem's own solver of c M − J (condensed Newton systems), or ours
        if (w%jac%storage == storage_sparse) call problem%iteration_solver(options, w%ls, status)
        if (.not. status%ok()) return
        if (.not. allocated(w%ls)) call new_linear_solver(options%linear_solver, w%n, &
            w%jac%storage, w%ls, status, options%band_lower, options%band_upper, &
            options%sparse_ordering, mass=w%mass, jac=w%jac)
        if (.not. status%ok()) return
        call w%ls%init(w%mass, w%jac, status)
    end subroutine setup_linear_solver

    !> The stage, Newton and error-estimate vectors and the dense output.
    subroutine allocate_workspace(self, w, status)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        type(status_t), intent(inout) :: status
        integer :: n, stat
        n = w%n
        if (allocated(self%dense%cont)) deallocate (self%dense%cont)
        allocate (w%z1(n), w%z2(n), w%z3(n), w%w1(n), w%w2(n), w%w3(n), w%f1(n), w%f2(n), &
            w%f3(n), w%f0(n), w%scal(n), w%cont(n), w%ytmp(n), w%mw(n), w%zc(n), &
            self%dense%cont(n, 0:3), stat=stat)
        if (stat /= 0) then
            ! 14 real vectors, zc complex (2), the dense output's 4 columns
            call out_of_memory(status, 'radau5 workspace', 20_i8 * n, 8)
            return
        end if
    end subroutine allocate_workspace

    !> §1.10 R0: the first h and the controller's starting state.
    subroutine first_step_size(self, w, options)
        class(radau5_engine_t), intent(in) :: self
        type(radau5_work_t), intent(inout) :: w
        type(dae_options_t), intent(in) :: options
        w%posneg = sign(1.0_wp, w%xend - w%x)
        if (options%hmax > 0.0_wp) then
            w%hmaxn = min(abs(options%hmax), abs(w%xend - w%x))
        else
            w%hmaxn = abs(w%xend - w%x)
        end if
        w%h = options%h0
        if (abs(w%h) <= 10.0_wp * w%uround) w%h = h_default
        w%h = sign(min(abs(w%h), w%hmaxn), w%posneg)
        w%hold = w%h
        w%last = .false.
        if ((w%x + w%h * end_factor - w%xend) * w%posneg >= 0.0_wp) then
            w%h = w%xend - w%x
            w%last = .true.
        end if
        w%hopt = w%h
        w%faccon = 1.0_wp
        w%nsing = 0
        w%first = .true.
        w%reject = .false.
        w%caljac = .false.
        w%theta = abs(w%thet)
        w%thqold = 0.0_wp
        w%dynold = 0.0_wp
        w%hacc = 0.0_wp
        w%erracc = 0.0_wp
        w%hnew = w%h
        w%quot = 1.0_wp
        w%err = 0.0_wp
        w%newt = 0
        w%pred = self%controller <= radau5_controller_predictive
        w%facl = 1.0_wp / self%fac_min
        w%facr = 1.0_wp / self%fac_max
        w%mass_identity = w%mass%storage == storage_identity
    end subroutine first_step_size

    !> Output at t0: requested times equal to t0, and the step sink (NR = 1).
    !> On an interruption `status` says so.
    subroutine output_start(self, w, y, options, status, sink)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        real(wp), intent(in) :: y(:)
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        w%stop_requested = .false.
        w%want_steps = .false.
        if (present(sink)) w%want_steps = sink%wants_steps()
        w%nout = 0
        if (allocated(options%output_times)) w%nout = size(options%output_times)
        w%iout = 1

        self%dense%x = w%x
        self%dense%h = w%h
        self%dense%cont(:, 0) = y
        self%dense%cont(:, 1:3) = 0.0_wp
        if (.not. present(sink)) return
        do while (w%iout <= w%nout)
            if ((options%output_times(w%iout) - w%x) * w%posneg > 0.0_wp) exit
            if (options%output_times(w%iout) == w%x) call sink%output(w%x, y, status)
            w%iout = w%iout + 1
            if (.not. status%ok()) exit
        end do
        if (w%want_steps .and. status%ok()) &
            call sink%step(1, w%x, w%x, y, self%dense, w%stop_requested, status)
        if (status%ok() .and. w%stop_requested) call status%set(status_interrupted, &
            'radau5: interrupted by the output routine at t = ' // real_text(w%x))
    end subroutine output_start

    !> The weights at y0 and F(t0, y0); the first block is R1.
    subroutine start_step(self, w, problem, y, status)
        class(radau5_engine_t), intent(inout) :: self
        type(radau5_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: fstatus
        call compute_scal(w, y)
        w%hhfac = w%h
        call eval_f(problem, w%x, y, w%f0, fstatus)
        self%native%nfcn = self%native%nfcn + 1
        if (.not. fstatus%ok()) then
            call status%set(status_solver_failure, 'radau5: right-hand side failed at t = ' &
                // real_text(w%x) // ': ' // fstatus%text(), merge(reason_det_f, &
                reason_user_function, fstatus%reason == reason_det_f))
            return
        end if
        w%block = blk_jacobian
    end subroutine start_step
end module flexmbs_dae_radau5_start
