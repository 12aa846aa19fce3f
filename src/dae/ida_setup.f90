!> The problem's side of an IDA integration (docs/theory.md §8): the
!> callbacks' data and the vectors (allocated once, here), the tolerances
!> and the components out of the error test, M and the storage of ∂F/∂y
!> with the pattern of c_j M − ∂F/∂y, the initial y' and the estimate of
!> IDA's first step.
module flexmbs_dae_ida_setup
    use, intrinsic :: iso_c_binding, only: c_null_ptr
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: real_text
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_user_function, reason_det_f
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_none, storage_identity, storage_dense, &
        storage_sparse
    use flexmbs_linalg_linear_solver, only: auto_sparse_threshold
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t, problem_mass_matrix
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t, index3_warning
    use flexmbs_dae_multiplier_scaling, only: multiplier_kappa
    use flexmbs_dae_ida_callbacks, only: jac_quotients, jac_dense, jac_scatter, jac_sparse, &
        jac_own
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_ida_state, only: ida_engine_t, ida_work_t
    implicit none
    private
    public :: prepare, setup_matrices, initial_derivative, first_step_estimate

contains

    !> The callbacks' data and the vectors, the tolerances, the index classes
    !> with the components out of the error test and their Newton weights,
    !> and the output position. On failure (memory) `status` says so.
    subroutine prepare(self, w, problem, t, y, t_end, options, stats, status, sink)
        class(ida_engine_t), intent(in) :: self
        type(ida_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout), target :: problem
        real(wp), intent(in) :: t, y(:), t_end
        type(dae_options_t), intent(in) :: options
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        integer :: n, stat
        n = problem%n
        w%n = n
        w%ctx = c_null_ptr
        w%mem = c_null_ptr
        w%annotated = .false.
        w%x = t
        w%posneg = sign(1.0_wp, t_end - t)
        w%want_steps = .false.
        if (present(sink)) w%want_steps = sink%wants_steps()
        w%stop_requested = .false.
        w%nout = 0
        if (allocated(options%output_times)) w%nout = size(options%output_times)
        w%iout = 1

        w%data%problem => problem
        w%data%n = n
        allocate (w%data%f(n), w%data%rtol(n), w%data%atol(n), w%yw(n), w%ypw(n), w%atolw(n), &
            w%idw(n), w%dkyw(n), w%classes(n), w%flags(n), w%data%newton_power(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'ida vectors', 11_i8 * n, 8)
            return
        end if
        call options%tolerances(w%data%rtol, w%data%atol)
        w%yw = y
        call problem%index_classes(w%classes)
        w%suppress = self%suppress_alg .and. any(w%classes > 1)
        call problem%multiplier_flags(w%flags)
        w%data%newton_power = 0
        if (w%suppress) where (w%flags .and. w%classes > 1) w%data%newton_power = w%classes - 1
        w%data%kappa = multiplier_kappa(minval(w%data%rtol))
        call problem%differential_flags(w%flags)
        if (any(w%classes >= 3)) stats%warning = index3_warning('ida')
    end subroutine prepare

    !> M and the storage of ∂F/∂y, and the pattern of c_j M − ∂F/∂y.
    subroutine setup_matrices(w, problem, options, st)
        type(ida_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: st
        integer :: storage
        call problem_mass_matrix(problem, w%data%mass, st, 'ida')
        if (.not. st%ok()) return
        storage = problem%jacobian_storage()
        if (options%jacobian == 'fd') storage = storage_none
        select case (storage)
        case (storage_dense)
            w%data%jac_mode = jac_dense
        case (storage_sparse)
            call problem%jacobian_pattern(w%data%jac, st)
            if (.not. st%ok()) return
            w%data%jac_mode = jac_scatter
        case default
            w%data%jac_mode = jac_quotients
        end select
        if (w%data%jac_mode == jac_scatter) then
            call own_solver(w, problem, options, st)
            if (.not. st%ok() .or. w%data%jac_mode == jac_own) return
        end if
        select case (options%linear_solver)
        case ('klu')
            w%use_klu = .true.
        case ('dense')
            w%use_klu = .false.
        case ('band', 'mumps')
            call st%set(status_bad_input, "ida: linear_solver = '" &
                // trim(options%linear_solver) // "' needs an analytic sparse " &
                // "Jacobian with IDA (jacobian_storage = storage_sparse, jacobian = " &
                // "'analytic'); 'band' is not offered; use 'dense', 'klu' or 'auto'")
            return
        case default
            w%use_klu = w%data%jac_mode == jac_scatter .and. w%n >= auto_sparse_threshold
        end select
        if (w%use_klu .and. w%data%jac_mode /= jac_scatter) then
            call st%set(status_bad_input, "ida: linear_solver = 'klu' needs an analytic " &
                // "sparse Jacobian (jacobian_storage = storage_sparse, jacobian = " &
                // "'analytic'); use 'dense' or 'auto'")
            return
        end if
        if (w%use_klu) then
            w%data%jac_mode = jac_sparse
            call build_iteration_pattern(w, st)
        end if
    end subroutine setup_matrices

    !> With a sparse analytic ∂F/∂y: the problem's solver of c_j M − ∂F/∂y
    !> (condensed Newton systems), or MUMPS when asked for, behind our
    !> SUNLinearSolver (mode jac_own, flexmbs_dae_ida_linear_solver);
    !> otherwise none, and SUNDIALS' own solvers follow.
    subroutine own_solver(w, problem, options, st)
        type(ida_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(dae_options_t), intent(in) :: options
        type(status_t), intent(inout) :: st
        call problem%iteration_solver(options, w%data%ls, st)
        if (.not. st%ok()) return
        if (.not. allocated(w%data%ls) .and. options%linear_solver == 'mumps') &
            call new_linear_solver('mumps', w%n, storage_sparse, w%data%ls, st, &
                ordering=options%sparse_ordering)
        if (.not. st%ok() .or. .not. allocated(w%data%ls)) return
        w%data%jac_matrix%n = w%n
        w%data%jac_matrix%storage = storage_sparse
        w%data%jac_matrix%csc = w%data%jac
        call w%data%ls%init(w%data%mass, w%data%jac_matrix, st)
        if (.not. st%ok()) then
            st%message = 'ida: ' // st%message
            return
        end if
        w%data%jac_mode = jac_own
    end subroutine own_solver

    !> Union of the patterns of ∂F/∂y and M; slot maps for both.
    subroutine build_iteration_pattern(w, st)
        type(ida_work_t), intent(inout) :: w
        type(status_t), intent(inout) :: st
        type(csc_matrix_t) :: union
        integer, allocatable :: rows(:), cols(:), mrows(:), mcols(:)
        integer :: i, j, nj, nm, k, n, stat
        integer(i8) :: filled !! positions listed so far
        n = w%n
        associate (data => w%data)
            select case (data%mass%storage)
            case (storage_sparse)
                data%mass_csc = data%mass%csc
            case (storage_dense)
                ! Structural non-zeros of the dense M.
                nm = count(data%mass%dense /= 0.0_wp)
                allocate (mrows(nm), mcols(nm), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(st, 'ida mass pattern positions', 2_i8 * nm, 4)
                    return
                end if
                k = 0
                do j = 1, n
                    do i = 1, n
                        if (data%mass%dense(i, j) /= 0.0_wp) then
                            k = k + 1
                            mrows(k) = i
                            mcols(k) = j
                        end if
                    end do
                end do
                call data%mass_csc%build(n, n, mrows, mcols, st)
                if (.not. st%ok()) return
                do k = 1, nm
                    data%mass_csc%values(data%mass_csc%triplet_map(k)) = &
                        data%mass%dense(mrows(k), mcols(k))
                end do
            case default
                call data%mass_csc%build(n, n, [(k, k=1, n)], [(k, k=1, n)], st)
                if (.not. st%ok()) return
                data%mass_csc%values = 1.0_wp
            end select
            nj = int(data%jac%nnz)
            nm = int(data%mass_csc%nnz)
            allocate (rows(nj + nm), cols(nj + nm), stat=stat)
            if (stat /= 0) then
                call out_of_memory(st, 'ida iteration pattern positions', 2_i8 * (nj + nm), 4)
                return
            end if
            filled = 0
            call data%jac%append_positions(rows, cols, filled)
            call data%mass_csc%append_positions(rows, cols, filled)
            call union%build(n, n, rows, cols, st)
            if (.not. st%ok()) return
            data%nnz = union%nnz
            data%colptr = union%colptr
            data%rowind = union%rowind
            data%jac_slot = union%triplet_map(1:nj)
            data%mass_slot = union%triplet_map(nj + 1:nj + nm)
        end associate
    end subroutine build_iteration_pattern

    !> y'0: given, F (M = I), guessed for IDACalcIC, or the problem's.
    subroutine initial_derivative(self, w, problem, st, yp)
        class(ida_engine_t), intent(in) :: self
        type(ida_work_t), intent(inout) :: w
        class(dae_problem_t), intent(inout) :: problem
        type(status_t), intent(inout) :: st
        real(wp), intent(in), optional :: yp(:)
        type(status_t) :: fst
        if (present(yp)) then
            w%ypw = yp
            return
        end if
        if (w%data%mass%storage == storage_identity) then
            call problem%rhs(w%x, w%yw, w%ypw, fst)
            if (.not. fst%ok()) call st%set(status_solver_failure, &
                'ida: right-hand side failed at t = ' // real_text(w%x) // ': ' // &
                fst%text(), reason_user_function)
        else if (self%calc_ic) then
            ! IDACalcIC computes the differential y' from this guess.
            w%ypw = 0.0_wp
        else
            call problem%consistent_initial(w%x, w%yw, w%ypw, fst)
            if (fst%reason == reason_det_f) then
                call st%set(status_solver_failure, 'ida: the initial state is refused ' // &
                    'at t = ' // real_text(w%x) // ': ' // fst%text(), reason_det_f)
            else if (.not. fst%ok()) then
                call st%set(status_bad_input, 'ida: no initial y'': ' // &
                    fst%text() // '; pass yp or set calc_ic = .true.')
            end if
        end if
    end subroutine initial_derivative

    !> |h| of IDA's first step, which the weights of the correction
    !> components need before IDA has one: the one asked for, or IDA's
    !> rule min(0.001 |t_out - t0|, 0.5/‖y0'‖), the norm over the
    !> components in the error test.
    subroutine first_step_estimate(w, t_end, options)
        type(ida_work_t), intent(inout) :: w
        real(wp), intent(in) :: t_end
        type(dae_options_t), intent(in) :: options
        real(wp) :: tfirst, ypnorm
        integer :: k
        if (options%h0 > 0.0_wp) then
            w%data%h_start = options%h0
            return
        end if
        tfirst = t_end
        if (allocated(options%output_times)) then
            do k = 1, size(options%output_times)
                if ((options%output_times(k) - w%x) * w%posneg > 0.0_wp) then
                    if ((options%output_times(k) - tfirst) * w%posneg < 0.0_wp) &
                        tfirst = options%output_times(k)
                    exit
                end if
            end do
        end if
        w%data%h_start = 0.001_wp * abs(tfirst - w%x)
        ypnorm = sqrt(sum(merge((w%ypw / (w%data%rtol * abs(w%yw) + w%data%atol))**2, &
            0.0_wp, w%classes == 1 .or. .not. w%suppress)) / real(w%n, wp))
        if (ypnorm > 0.5_wp / w%data%h_start) w%data%h_start = 0.5_wp / ypnorm
    end subroutine first_step_estimate
end module flexmbs_dae_ida_setup
