!> The classic MEXAX face over the modern core `flexmbs_dae_mexax`.
!>
!> `mexax_classic` validates the dimensions, MXJOB options and workspace
!> lengths (docs/solvers.md, MEXAX, IERR −2 … −135), wraps FPROB in a
!> `mechanical_problem_t` (one FPROB call, one flag, per item the core
!> needs), runs the core from T to TFIN with the half-explicit Euler base
!> unless MXJOB(29) = 1 and under the default control (Deuflhard's; ODEX's
!> with MXJOB(28) = 1), and returns the state, the proposed step, the
!> statistics MXJOB(41..74) and IERR. Only T, P, V, A, RLAM, H, the output
!> slots of MXJOB and IERR are written; U, IWK and RWK are left as they are.
!>
!> Limits of the face, each reported through a published code with a message
!> on the standard error unit: NU > 0 (IERR −23) and NG < NL (−25) need
!> states and constraint classes the core does not integrate; MDISC = 1
!> (−101), sparse JOB = 10 (−102), MMODE ≠ 0 (−103), MGPFL ≠ 0 (−106),
!> MDOUT ≠ 0 (−131) and MSWIT ≠ 0 (−135) select features it does not have.
module flexmbs_legacy_mexax_adapter
    use, intrinsic :: iso_fortran_env, only: error_unit
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted, &
        reason_step_too_small, reason_max_steps, reason_singular_matrix, reason_non_finite, &
        reason_projection, reason_user_function
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler, mexax_base_midpoint, &
        mexax_dense_t, mexax_failed_projection, mexax_max_columns, mexax_control_hairer
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_legacy_mexax_interface, only: mexax_fprob_i, mexax_solout_i
    use flexmbs_legacy_common_solout_sink, only: solout_sink_t
    implicit none
    private

    public :: mexax_classic

    ! §3.9 IERR codes.
    integer, parameter :: ierr_ok = 0, ierr_solout = 1, ierr_tfin = -2, ierr_liwk = -3, &
        ierr_lrwk = -4, ierr_small_step = -9, ierr_max_steps = -10, ierr_projection = -11, &
        ierr_singular_step = -15, ierr_singular_projection = -16, ierr_fprob_step = -17, &
        ierr_fprob_projection = -18, ierr_np = -21, ierr_ng = -22, ierr_nu = -23, &
        ierr_ng_nl = -25, ierr_mxjob = -100
    ! §3.8: NMAX, fixed.
    integer, parameter :: nmax = 3000
    ! §3.9: workspace, LIWK ≥ NP + 4 NV + NL + NU + this, LRWK ≥ … + this.
    integer, parameter :: liwk_extra = 60, lrwk_extra = 50
    ! §3.9 MXJOB slots.
    integer, parameter :: slot_mdisc = 1, slot_job = 2, slot_mmode = 3, slot_mgpfl = 6, &
        slot_kdmax = 9, slot_ialam = 22, slot_control = 28, slot_base = 29, slot_mout = 30, &
        slot_mdout = 31, &
        slot_mswit = 35, slot_liwk_need = 41, slot_lrwk_need = 42, slot_liwk_used = 43, &
        slot_lrwk_used = 44, slot_nstep = 51, slot_ierr = 73, slot_failing_dec = 74
    ! JOB values the face solves with its one dense LU (§3.9).
    integer, parameter :: job_max_dense = 3

    ! FPROB request flags (§3.9).
    integer, parameter :: flag_mass = 1, flag_g_matrix = 2, flag_forces = 4, &
        flag_pdot = 5, flag_constraint = 7, flag_gi = 8, nflags = 9

    !> The mechanical problem of a classic FPROB.
    type, extends(mechanical_problem_t) :: classic_mechanical_t
        procedure(mexax_fprob_i), pointer, nopass :: fprob => null()
        integer :: nl = 0, ng = 0, nu = 0
        real(wp), allocatable :: u(:), rlam(:)               !! fixed arguments
        real(wp), allocatable :: am(:, :), gp(:, :), fl(:, :) !! FPROB output arrays
        real(wp), allocatable :: f(:), pdot(:), udot(:), g(:), gi(:)
    contains
        procedure :: kinematics => classic_kinematics
        procedure :: mass => classic_mass
        procedure :: forces => classic_forces
        procedure :: constraint => classic_constraint
        procedure :: constraint_jacobian => classic_constraint_jacobian
        procedure :: constraint_time_derivative => classic_constraint_time_derivative
    end type classic_mechanical_t

    !> SOLOUT after every accepted step (MXJOB(30) = 1).
    type, extends(solout_sink_t) :: classic_sink_t
        procedure(mexax_solout_i), pointer, nopass :: solout => null()
        integer :: np = 0, nv = 0, nl = 0, nu = 0
        real(wp), allocatable :: u(:)
        integer :: info(50) = 0
    contains
        procedure :: call_solout => classic_solout
    end type classic_sink_t

contains

    !> The body of the external MEXAX: same arguments, same meanings.
    subroutine mexax_classic(np, nv, nl, ng, nu, fprob, t, tfin, p, v, u, a, rlam, itol, rtol, &
        atol, h, mxjob, ierr, liwk, iwk, lrwk, rwk, solout, denout, fswit)
        include 'mexax_arguments.inc'

        type(classic_mechanical_t) :: problem
        type(classic_sink_t) :: sink
        type(mexax_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:), vel(:), lam(:), acc(:)
        real(wp) :: tt
        integer :: liwk_need, lrwk_need, kdmax, ntol, i

        ierr = check_input(np, nv, nl, ng, nu, t, tfin, mxjob, liwk, lrwk, kdmax, liwk_need, &
                           lrwk_need)
        call workspace_slots()
        if (ierr /= ierr_ok) then
            call finish_slots()
            return
        end if

        ! ---- the problem, the options, the solver ----
        call setup_problem(problem, fprob, np, nv, nl, ng, nu, u, rlam)

        ntol = np + nv + nu
        if (itol == 0) then
            options%rtol = rtol(1)
            options%atol = atol(1)
        else
            options%rtol_vector = [(rtol(i), i = 1, ntol)]
            options%atol_vector = [(atol(i), i = 1, ntol)]
        end if
        options%h0 = abs(h)
        options%max_steps = nmax
        options%classic_lu = .true.
        solver%max_extrapolation = kdmax
        solver%base = merge(mexax_base_midpoint, mexax_base_euler, mxjob(slot_base) == 1)
        ! our extension: MXJOB(28) = 1 selects ODEX/SEULEX's control
        if (mxjob(slot_control) == 1) solver%control = mexax_control_hairer
        ! the original's a and λ: extrapolated, no extra decomposition a step
        solver%consistent_accelerations = .false.

        q = [(p(i), i = 1, np)]
        vel = [(v(i), i = 1, nv)]
        allocate (lam(nl), acc(nv))
        if (nl > 0) lam = rlam(1:nl)
        acc = 0.0_wp
        tt = t
        if (mxjob(slot_mout) == 1) then
            sink%solout => solout
            sink%np = np
            sink%nv = nv
            sink%nl = nl
            sink%nu = nu
            sink%u = problem%u
            call solver%integrate_mechanical(problem, tt, q, vel, tfin, options, stats, status, &
                sink=sink, lambda=lam, accel=acc)
        else
            call solver%integrate_mechanical(problem, tt, q, vel, tfin, options, stats, status, &
                lambda=lam, accel=acc)
        end if

        t = tt
        p(1:np) = q
        v(1:nv) = vel
        a(1:nv) = acc
        if (nl > 0) rlam(1:nl) = lam
        if (solver%h_next /= 0.0_wp) h = solver%h_next
        ierr = status_ierr()
        if (ierr < 0) call message(status%text())
        associate (n => solver%native)
            mxjob(slot_nstep:slot_nstep + 8) = [n%nstep, n%naccpt, &
                n%nrejct + solver%nprj_reject, n%nfprob, n%nfcn, n%ngcn, n%nmult, n%ndec, n%nsol]
        end associate
        call finish_slots()

    contains

        subroutine workspace_slots()
            mxjob(slot_liwk_need) = liwk_need
            mxjob(slot_lrwk_need) = lrwk_need
            mxjob(slot_liwk_used) = liwk_need
            mxjob(slot_lrwk_used) = lrwk_need
        end subroutine workspace_slots

        subroutine finish_slots()
            mxjob(slot_ierr) = ierr
            mxjob(slot_failing_dec) = 0
            if (ierr == ierr_singular_step .or. ierr == ierr_singular_projection) &
                mxjob(slot_failing_dec) = 1
        end subroutine finish_slots

        !> The core's status as a §3.8/§3.9 IERR.
        integer function status_ierr() result(code)
            logical :: in_projection
            in_projection = solver%failed_in == mexax_failed_projection
            if (status%ok()) then
                code = ierr_ok
            else if (status%code == status_interrupted) then
                code = ierr_solout
            else
                select case (status%reason)
                case (reason_max_steps)
                    code = ierr_max_steps
                case (reason_projection)
                    code = ierr_projection
                case (reason_singular_matrix)
                    code = merge(ierr_singular_projection, ierr_singular_step, in_projection)
                case (reason_user_function)
                    code = merge(ierr_fprob_projection, ierr_fprob_step, in_projection)
                case default
                    ! step too small, persistent NaN/Inf, and tolerances the core
                    ! refuses (no published code of their own)
                    code = ierr_small_step
                end select
            end if
        end function status_ierr
    end subroutine mexax_classic

    !> §3.9 bad input, in the order of the list: the IERR (0 when all is
    !> well, with a message otherwise), the columns KDMAX and the workspace the
    !> run needs.
    integer function check_input(np, nv, nl, ng, nu, t, tfin, mxjob, liwk, lrwk, kdmax, &
                                 liwk_need, lrwk_need) result(code)
        integer, intent(in) :: np, nv, nl, ng, nu
        real(wp), intent(in) :: t, tfin
        integer, intent(in) :: mxjob(*)
        integer, intent(in) :: liwk, lrwk
        integer, intent(out) :: kdmax, liwk_need, lrwk_need
        integer :: k
        code = ierr_ok
        kdmax = mexax_max_columns
        liwk_need = 0
        lrwk_need = 0
        if (np <= 0) then
            code = ierr_np
            call message('NP = ' // int_text(np) // ': must be positive')
        else if (nv <= 0) then
            code = ierr_np
            call message('NV = ' // int_text(nv) // ': must be positive')
        else if (ng < 0) then
            code = ierr_ng
            call message('NG = ' // int_text(ng) // ': must not be negative')
        else if (nu < 0) then
            code = ierr_nu
            call message('NU = ' // int_text(nu) // ': must not be negative')
        else if (nu > 0) then
            code = ierr_nu
            call message('NU = ' // int_text(nu) // ': extra states u are not integrated &
                &by this face; use NU = 0')
        else if (ng > nl) then
            code = ierr_ng_nl
            call message('NG = ' // int_text(ng) // ' > NL = ' // int_text(nl))
        else if (ng < nl) then
            code = ierr_ng_nl
            call message('NG = ' // int_text(ng) // ' < NL = ' // int_text(nl) // &
                ': this face needs NG = NL (every velocity constraint a derivative of a &
                &position constraint)')
        else if (tfin <= t) then
            code = ierr_tfin
            call message('TFIN must be greater than T')
        end if
        if (code /= ierr_ok) return
        k = rejected_slot(mxjob)
        if (k /= 0) then
            code = ierr_mxjob - k
            call message('MXJOB(' // int_text(k) // ') = ' // int_text(mxjob(k)) // &
                ': not a value this face accepts (docs/solvers.md, MEXAX)')
            return
        end if
        kdmax = mxjob(slot_kdmax)
        if (kdmax == 0) kdmax = mexax_max_columns
        ! workspace (§3.9), empty dimensions counted as 1
        liwk_need = np + 4 * nv + max(1, nl) + max(1, nu) + liwk_extra
        lrwk_need = (nv + max(1, nl))**2 + np * (max(1, ng, nl) + 18) + nv * (nv + 45) &
            + 28 * max(1, nl) + max(1, ng) + 18 * max(1, nu) + lrwk_extra
        if (liwk < liwk_need) then
            code = ierr_liwk
            call message('LIWK = ' // int_text(liwk) // ': at least ' // &
                int_text(liwk_need) // ' needed')
        else if (lrwk < lrwk_need) then
            code = ierr_lrwk
            call message('LRWK = ' // int_text(lrwk) // ': at least ' // &
                int_text(lrwk_need) // ' needed')
        end if
    end function check_input

    !> The first MXJOB option slot whose value the face does not accept; 0
    !> when there is none.
    integer function rejected_slot(mxjob) result(k)
        integer, intent(in) :: mxjob(*)
        k = 0
        if (mxjob(slot_mdisc) /= 0) then
            k = slot_mdisc
        else if (mxjob(slot_job) < 0 .or. mxjob(slot_job) > job_max_dense) then
            k = slot_job
        else if (mxjob(slot_mmode) /= 0) then
            k = slot_mmode
        else if (mxjob(slot_mgpfl) /= 0) then
            k = slot_mgpfl
        else if (mxjob(slot_kdmax) /= 0 .and. (mxjob(slot_kdmax) < 2 .or. &
            mxjob(slot_kdmax) > mexax_max_columns)) then
            k = slot_kdmax
        else if (mxjob(slot_ialam) < 0 .or. mxjob(slot_ialam) > 1) then
            k = slot_ialam
        else if (mxjob(slot_base) < 0 .or. mxjob(slot_base) > 1) then
            k = slot_base
        else if (mxjob(slot_control) < 0 .or. mxjob(slot_control) > 1) then
            k = slot_control
        else if (mxjob(slot_mout) < 0 .or. mxjob(slot_mout) > 1) then
            k = slot_mout
        else if (mxjob(slot_mdout) /= 0) then
            k = slot_mdout
        else if (mxjob(slot_mswit) /= 0) then
            k = slot_mswit
        end if
    end function rejected_slot

    !> The classic FPROB as the core's mechanical problem, with U and RLAM as
    !> its fixed arguments and its output arrays allocated once.
    subroutine setup_problem(problem, fprob, np, nv, nl, ng, nu, u, rlam)
        type(classic_mechanical_t), intent(out) :: problem
        procedure(mexax_fprob_i) :: fprob
        integer, intent(in) :: np, nv, nl, ng, nu
        real(wp), intent(in) :: u(*), rlam(*)
        problem%fprob => fprob
        problem%nq = np
        problem%nv = nv
        problem%nc = nl
        problem%nl = nl
        problem%ng = ng
        problem%nu = nu
        allocate (problem%u(max(1, nu)), problem%rlam(max(1, nl)))
        problem%u = 0.0_wp
        if (nu > 0) problem%u(1:nu) = u(1:nu)
        problem%rlam = 0.0_wp
        if (nl > 0) problem%rlam(1:nl) = rlam(1:nl)
        allocate (problem%am(nv, nv), problem%gp(max(1, nl), nv), problem%fl(nv, max(1, nl)))
        allocate (problem%f(nv), problem%pdot(np), problem%udot(max(1, nu)), &
            problem%g(max(1, ng)), problem%gi(max(1, nl)))

    end subroutine setup_problem

    !> One line on the standard error unit (docs/theory.md §4).
    subroutine message(text)
        character(len=*), intent(in) :: text
        write (error_unit, '(a)') 'MEXAX: ' // text
    end subroutine message

    !> FPROB for one item; IFAIL ≠ 0 becomes a failed status.
    subroutine call_fprob(self, flag, t, q, w, ldg, status)
        class(classic_mechanical_t), intent(inout) :: self
        integer, intent(in) :: flag
        real(wp), intent(in) :: t, q(:), w(:)
        integer, intent(in) :: ldg
        type(status_t), intent(inout) :: status
        logical :: qflag(nflags)
        integer :: ifail
        qflag = .false.
        qflag(flag) = .true.
        ifail = 0
        call self%fprob(self%nq, self%nv, self%nl, self%ng, self%nu, ldg, t, q, w, self%u, &
            self%rlam, self%am, self%gp, self%f, self%pdot, self%udot, self%g, self%gi, &
            self%fl, qflag, ifail)
        if (ifail /= 0) call status%set(status_bad_input, 'FPROB returned IFAIL = ' // &
            int_text(ifail) // ' for flag ' // int_text(flag))
    end subroutine call_fprob

    subroutine classic_kinematics(self, t, q, w, qdot, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        call call_fprob(self, flag_pdot, t, q, w, max(1, self%nl), status)
        qdot = self%pdot
    end subroutine classic_kinematics

    subroutine classic_mass(self, t, q, m, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        self%am = 0.0_wp
        call call_fprob(self, flag_mass, t, q, self%f, max(1, self%nl), status)
        m = self%am
    end subroutine classic_mass

    subroutine classic_forces(self, t, q, v, f, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        call call_fprob(self, flag_forces, t, q, v, max(1, self%nl), status)
        f = self%f
    end subroutine classic_forces

    subroutine classic_constraint(self, t, q, g, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        call call_fprob(self, flag_constraint, t, q, self%f, max(1, self%nl), status)
        g = self%g(1:size(g))
    end subroutine classic_constraint

    !> G (flag 2, LDG = NL); with NG = NL and g_I = ∂g/∂t it is also C = g_p T.
    subroutine classic_constraint_jacobian(self, t, q, gmat, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
        self%gp = 0.0_wp
        call call_fprob(self, flag_g_matrix, t, q, self%f, max(1, self%nl), status)
        gmat = self%gp(1:size(gmat, 1), :)
    end subroutine classic_constraint_jacobian

    subroutine classic_constraint_time_derivative(self, t, q, gt, status)
        class(classic_mechanical_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gt(:)
        type(status_t), intent(inout) :: status
        self%gi = 0.0_wp
        call call_fprob(self, flag_gi, t, q, self%f, max(1, self%nl), status)
        gt = self%gi(1:size(gt))
    end subroutine classic_constraint_time_derivative

    !> SOLOUT with y = (p, v, λ) and a from the dense output of the step.
    subroutine classic_solout(self, nr, t_old, t, y, dense, irtrn)
        class(classic_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        integer, intent(inout) :: irtrn
        real(wp) :: acc(self%nv), lam(max(1, self%nl))
        integer :: np, nv
        np = self%np
        nv = self%nv
        acc = 0.0_wp
        select type (dense)
        type is (mexax_dense_t)
            acc = dense%d1(np + 1:np + nv)
        end select
        lam = 0.0_wp
        if (self%nl > 0) lam(1:self%nl) = y(np + nv + 1:np + nv + self%nl)
        self%info(1) = nr
        call self%solout(np, nv, self%nu, self%nl, t, y(1:np), y(np + 1:np + nv), self%u, acc, &
            lam, self%info, irtrn)
    end subroutine classic_solout
end module flexmbs_legacy_mexax_adapter
