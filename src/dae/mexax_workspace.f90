!> MEXAX workspace and linear algebra (docs/theory.md §7.1): the arrays of
!> one integration, allocated once; M and G dense or on their CSC patterns;
!> the augmented matrix [M Gᵀ; G 0] assembled, factored (LAPACK LU, the
!> classic elimination order, or KLU) and solved; the original's counters.
module flexmbs_dae_mexax_workspace
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix, reason_non_finite, reason_user_function, reason_det_f
    use flexmbs_core_text, only: int_text
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_linalg_csc, only: csc_matrix_t, pattern_matvec
    use flexmbs_linalg_klu, only: klu_ordering_auto
    use flexmbs_linalg_saddle_point, only: saddle_point_t
    use flexmbs_linalg_structured_saddle, only: structured_saddle_t
    use flexmbs_linalg_factory, only: klu_ordering_code
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_mexax_control, only: control_t
    implicit none
    private
    public :: workspace_linear_solver, setup_workspace, eval_block, copy_block, assemble, factor, &
        solve, factor_solve, user_failed, block_times, rms

    !> linear_solver = 'auto' factors [M Gᵀ; G 0] with KLU from this order
    !> nv + nc on (problems with sparse M and G), densely below. KLU is the
    !> faster from order 25 on (pendulum chain, release: about 0.2 against
    !> 0.6 ms a step at NB = 5, 0.3 against 1.6 ms at NB = 10), but below
    !> 50 both cost under 2 ms a step, and dense LU there keeps the original's
    !> full LU (JOB = 0) and so the §8 anchor (NB = 8, order 40) exactly: the
    !> round-off difference of KLU moves its TOL 1e-9 counters by ~3 %.
    integer, parameter, public :: mexax_auto_klu_order = 50

    !> Outcomes of a column (ev_restart: H/2 for an unstable column,
    !> ev_refused: H/2 when the model refused a substep).
    integer, parameter, public :: ev_ok = 0, ev_restart = 1, ev_stop = 2, ev_refused = 3
    !> Which matrix eval_block evaluates.
    integer, parameter, public :: block_mass = 1, block_jacobian = 2

    !> The original's counters, MXJOB(51..59).
    type, public :: mexax_native_t
        integer :: nstep = 0, naccpt = 0, nrejct = 0, nfprob = 0, nfcn = 0, ngcn = 0
        integer :: nmult = 0, ndec = 0, nsol = 0
    end type mexax_native_t

    !> M (nv x nv) or G (nc x nv) at one point: dense, or the values in the
    !> slots of the problem's fixed CSC pattern (KLU path).
    type, public :: block_t
        real(wp), allocatable :: dense(:, :)
        real(wp), allocatable :: values(:)
    end type block_t

    !> Workspace of one integration, allocated once.
    type, public :: workspace_t
        integer :: nq = 0, nv = 0, nc = 0, na = 0, ny = 0, ne = 0, km = 0
        integer :: base = 0 !! mexax_base_midpoint | mexax_base_euler
        integer :: klu_ordering = klu_ordering_auto !! KLU's fill-reducing ordering
        type(control_t) :: ctl !! sequence, err_j, H_j, W_j (flexmbs_dae_mexax_control)
        real(wp), allocatable :: rtol(:), atol(:), wt(:), wst(:)
        real(wp), allocatable :: p0(:), v0(:), a0(:), lam0(:), f0(:), pdot0(:)
        type(block_t) :: m0, g0, mm, gm, gn
        ! augmented matrix [M Gᵀ; G 0]: dense (LAPACK, or the classic elimination
        ! order) or sparse (KLU), flexmbs_linalg_saddle_point
        logical :: sparse = .false.
        logical :: classic_lu = .false. !! dense LU in the classic elimination order (options)
        type(csc_matrix_t) :: mpat, gpat
        type(saddle_point_t) :: kkt
        !> the sparse path by the structure of M (newton_system = 'condensed'):
        !> constant mass blocks factored once, massless frames in a small system
        logical :: structured = .false.
        type(structured_saddle_t), allocatable :: skkt !! allocatable: see formulation_sparse
        real(wp), allocatable :: p(:), pp(:), pn(:), v(:), vp(:), f(:), pdot(:), gt(:)
        real(wp), allocatable :: rhs(:), acc(:), lam(:), x(:), d(:), tab(:, :)
        real(wp), allocatable :: shift(:) !! the projection's accumulated correction (v space)
    end type workspace_t

contains

    !> What factors the augmented systems, as the statistics report it.
    function workspace_linear_solver(w) result(text)
        type(workspace_t), intent(in) :: w
        character(len=:), allocatable :: text
        if (w%structured) then
            text = 'structured [M Gt; G 0] (mass blocks, klu)'
        else if (w%sparse) then
            text = 'klu [M Gt; G 0]'
        else
            text = 'dense [M Gt; G 0]'
        end if
    end function workspace_linear_solver

    !> Allocate the workspace for `km` columns under the order and step-size
    !> control `control` and set up the linear solver of the augmented
    !> system ('auto' | 'dense' | 'klu').
    subroutine setup_workspace(w, problem, base, control, km, linear_solver, status, ordering, &
                               classic_lu, structured)
        type(workspace_t), intent(out) :: w
        class(mechanical_problem_t), intent(inout) :: problem
        integer, intent(in) :: base, km
        integer, intent(in) :: control !! mexax_control_hairer | _deuflhard
        character(len=*), intent(in) :: linear_solver
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: ordering !! 'auto' | 'amd' | 'nd'
        !> dense LU: the classic elimination order (options%classic_lu)
        logical, intent(in), optional :: classic_lu
        !> sparse LU: [M Gᵀ; G 0] by the structure of M (structured_saddle_t)
        !> instead of KLU on the whole matrix
        logical, intent(in), optional :: structured
        integer :: nq, nv, nc, stat
        integer(i8) :: entries
        call default_blas_threads()
        if (present(classic_lu)) w%classic_lu = classic_lu
        nq = problem%nq
        nv = problem%nv
        nc = problem%nc
        w%nq = nq
        w%nv = nv
        w%nc = nc
        w%na = nv + nc
        w%ne = nq + nv
        w%ny = nq + 2 * nv + nc
        w%km = km
        w%base = base
        call w%ctl%init(base, km, control)
        allocate (w%rtol(w%ne), w%atol(w%ne), w%wt(w%ne), w%wst(nv), w%p0(nq), w%v0(nv), &
            w%a0(nv), w%lam0(nc), w%f0(nv), w%pdot0(nq), w%rhs(w%na), w%p(nq), w%pp(nq), &
            w%pn(nq), w%v(nv), w%vp(nv), w%f(nv), w%pdot(nq), w%gt(nc), w%acc(nv), w%lam(nc), &
            w%x(w%ny), w%d(w%ny), w%tab(w%ny, km), w%shift(nv), stat=stat)
        if (stat /= 0) then
            entries = 3_i8 * w%ne + w%na + 6_i8 * nq + 9_i8 * nv + 3_i8 * nc + (2_i8 + km) * w%ny
            call out_of_memory(status, 'mexax workspace', entries, 8)
            return
        end if
        select case (trim(adjustl(linear_solver)))
        case ('auto')
            w%sparse = problem%has_sparse() .and. w%na >= mexax_auto_klu_order
        case ('dense')
            w%sparse = .false.
        case ('klu')
            if (.not. problem%has_sparse()) then
                call status%set(status_bad_input, "mexax: linear_solver = 'klu' needs M and " // &
                    'G in sparse form, which this mechanical problem does not provide ' // &
                    '(has_sparse, mass_pattern/mass_sparse, constraint_jacobian_pattern/' // &
                    "constraint_jacobian_sparse); use 'dense' or 'auto'")
                return
            end if
            w%sparse = .true.
        case default
            call status%set(status_bad_input, "mexax: linear_solver = '" // &
                trim(linear_solver) // "': the augmented matrix [M G^T; G 0] is " // &
                "factored by 'dense' (LAPACK) or 'klu'; use 'auto', 'dense' or 'klu'")
            return
        end select
        if (w%sparse) then
            if (present(ordering)) w%klu_ordering = klu_ordering_code(ordering)
            if (present(structured)) w%structured = structured
            call setup_sparse(w, problem, status)
        else
            allocate (w%m0%dense(nv, nv), w%g0%dense(nc, nv), w%mm%dense(nv, nv), &
                w%gm%dense(nc, nv), w%gn%dense(nc, nv), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'mexax dense M and G', &
                    int(nv, i8) * (2_i8 * nv + 3_i8 * nc), 8)
                return
            end if
            call w%kkt%init_dense(nv, nc, w%classic_lu, status)
        end if
    end subroutine setup_workspace

    !> KLU path: the patterns of M and G from the problem and the saddle-point
    !> matrix K = [M Gᵀ; G 0] on them (flexmbs_linalg_saddle_point).
    subroutine setup_sparse(w, problem, status)
        type(workspace_t), intent(inout) :: w
        class(mechanical_problem_t), intent(inout) :: problem
        type(status_t), intent(out) :: status
        integer :: nv, nc, stat
        nv = w%nv
        nc = w%nc
        call problem%mass_pattern(w%mpat, status)
        if (.not. pattern_ok(w%mpat, nv, nv, 'mass_pattern')) return
        call problem%constraint_jacobian_pattern(w%gpat, status)
        if (.not. pattern_ok(w%gpat, nc, nv, 'constraint_jacobian_pattern')) return
        if (w%structured) then
            allocate (w%skkt)
            call w%skkt%init(w%mpat, w%gpat, status)
        else
            call w%kkt%init(w%mpat, w%gpat, status, w%klu_ordering)
        end if
        if (.not. status%ok()) then
            status%message = 'mexax: ' // status%message
            return
        end if
        allocate (w%m0%values(w%mpat%nnz), w%mm%values(w%mpat%nnz), w%g0%values(w%gpat%nnz), &
            w%gm%values(w%gpat%nnz), w%gn%values(w%gpat%nnz), stat=stat)
        if (stat /= 0) call out_of_memory(status, 'mexax sparse M and G values', &
            2 * w%mpat%nnz + 3 * w%gpat%nnz, 8)
    contains
        logical function pattern_ok(pattern, nrow, ncol, what) result(ok)
            type(csc_matrix_t), intent(in) :: pattern
            integer, intent(in) :: nrow, ncol
            character(len=*), intent(in) :: what
            ok = .false.
            if (.not. status%ok()) then
                status%message = 'mexax: ' // what // ': ' // status%message
            else if (.not. pattern%is_built()) then
                call status%set(status_bad_input, 'mexax: ' // what // ' built no pattern')
            else if (pattern%nrow /= nrow .or. pattern%ncol /= ncol) then
                call status%set(status_bad_input, 'mexax: ' // what // ' is ' // &
                    int_text(pattern%nrow) // ' x ' // int_text(pattern%ncol) // &
                    ', expected ' // int_text(nrow) // ' x ' // int_text(ncol))
            else
                ok = .true.
            end if
        end function pattern_ok
    end subroutine setup_sparse

    !> M(t, q) (what = block_mass) or G(t, q) (block_jacobian) into blk,
    !> dense or as the values on its CSC pattern.
    subroutine eval_block(problem, w, what, t, q, blk, status)
        class(mechanical_problem_t), intent(inout) :: problem
        type(workspace_t), intent(in) :: w
        integer, intent(in) :: what
        real(wp), intent(in) :: t, q(:)
        type(block_t), intent(inout) :: blk
        type(status_t), intent(inout) :: status
        if (what == block_mass .and. w%sparse) then
            call problem%mass_sparse(t, q, blk%values, status)
        else if (what == block_mass) then
            call problem%mass(t, q, blk%dense, status)
        else if (w%sparse) then
            call problem%constraint_jacobian_sparse(t, q, blk%values, status)
        else
            call problem%constraint_jacobian(t, q, blk%dense, status)
        end if
    end subroutine eval_block

    !> dst = src without reallocation.
    pure subroutine copy_block(dst, src)
        type(block_t), intent(inout) :: dst
        type(block_t), intent(in) :: src
        if (allocated(src%dense)) dst%dense(:, :) = src%dense
        if (allocated(src%values)) dst%values(:) = src%values
    end subroutine copy_block

    !> K = [mtop gtopᵀ; gbot 0] into the saddle-point matrix (no allocation).
    subroutine assemble(w, mtop, gtop, gbot)
        type(workspace_t), intent(inout) :: w
        type(block_t), intent(in) :: mtop, gtop, gbot
        if (w%structured) then
            call w%skkt%assemble(mtop%values, gbot%values, gtop%values)
        else if (w%sparse) then
            call w%kkt%assemble(mtop%values, gbot%values, gtop%values)
        else
            call w%kkt%assemble(mtop%dense, gbot%dense, gtop%dense)
        end if
    end subroutine assemble

    !> LU of the assembled K: LAPACK or the classic order, or KLU reusing the
    !> last pivot order while it stays good (klu_factor_t%refactor).
    subroutine factor(w, status)
        type(workspace_t), intent(inout) :: w
        type(status_t), intent(out) :: status
        if (w%structured) then
            call w%skkt%factor(status)
        else
            call w%kkt%factor(status)
        end if
    end subroutine factor

    !> b ← K⁻¹ b with the factorisation of `factor`.
    subroutine solve(w, b)
        type(workspace_t), intent(inout) :: w
        real(wp), intent(inout) :: b(:)
        type(status_t) :: lst
        ! fails only without a factorisation, which `factor` excluded
        if (w%structured) then
            call w%skkt%solve(b, lst)
        else
            call w%kkt%solve(b, lst)
        end if
    end subroutine solve

    !> Factor the augmented matrix and solve for w%rhs; ev_stop on a singular matrix.
    subroutine factor_solve(native, w, where, ev, status)
        type(mexax_native_t), intent(inout) :: native
        type(workspace_t), intent(inout) :: w
        character(len=*), intent(in) :: where
        integer, intent(out) :: ev
        type(status_t), intent(inout) :: status
        type(status_t) :: lst
        ev = ev_ok
        call factor(w, lst)
        if (.not. lst%ok() .and. lst%reason == reason_non_finite) then
            ! KLU refuses Inf/NaN entries (of M or G: the model's), which LAPACK
            ! would pass on: restart
            call status%set(status_solver_failure, 'non-finite values in the augmented ' // &
                'matrix ' // where, reason_non_finite)
            ev = ev_refused
            return
        else if (.not. lst%ok()) then
            call status%set(status_solver_failure, 'augmented matrix [M G^T; G 0] is singular ' &
                // where, reason_singular_matrix)
            ev = ev_stop
            return
        end if
        native%ndec = native%ndec + 1
        call solve(w, w%rhs)
        native%nsol = native%nsol + 1
    end subroutine factor_solve

    !> A failed user call becomes a stop with the routine's name; non-finite
    !> `values` it returned fail it too (reason_non_finite: a refusal).
    logical function user_failed(status, what, values) result(failed)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: what
        real(wp), intent(in), optional :: values(:)
        integer :: i
        if (status%ok() .and. present(values)) then
            do i = 1, size(values)
                if (ieee_is_finite(values(i))) cycle
                call status%set(status_solver_failure, 'non-finite value in component ' // &
                    int_text(i), reason_non_finite)
                exit
            end do
        end if
        failed = .not. status%ok()
        if (failed) then
            status%message = 'user function ' // what // ' failed: ' // status%text()
            status%code = status_solver_failure
            ! det F <= 0 and non-finite values are the model refusing the
            ! trial state: a restart with H/2 (base_column), not a stop.
            if (status%reason /= reason_det_f .and. status%reason /= reason_non_finite) &
                status%reason = reason_user_function
        end if
    end function user_failed

    !> y = B x for a block B (M or G) stored dense or on its pattern `pat`.
    pure subroutine block_times(w, b, pat, x, y)
        type(workspace_t), intent(in) :: w
        type(block_t), intent(in) :: b
        type(csc_matrix_t), intent(in) :: pat !! w%mpat for M, w%gpat for G
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: y(:)
        if (w%sparse) then
            call pattern_matvec(pat, b%values, x, y)
        else
            call matvec(b%dense, x, y)
        end if
    end subroutine block_times

    !> y = a x without temporaries.
    pure subroutine matvec(a, x, y)
        real(wp), intent(in) :: a(:, :), x(:)
        real(wp), intent(out) :: y(:)
        integer :: j
        y = 0.0_wp
        do j = 1, size(x)
            y = y + a(:, j) * x(j)
        end do
    end subroutine matvec

    !> RMS norm of x/w.
    pure real(wp) function rms(x, w)
        real(wp), intent(in) :: x(:), w(:)
        if (size(x) == 0) then
            rms = 0.0_wp
        else
            rms = sqrt(sum((x / w)**2) / size(x))
        end if
    end function rms
end module flexmbs_dae_mexax_workspace
