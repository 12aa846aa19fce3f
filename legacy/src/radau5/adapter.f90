!> The classic RADAU5 face over the modern core `flexmbs_dae_radau5`.
!>
!> `radau5_classic` reads the classic arguments and option slots
!> (docs/solvers.md, RADAU5), validates them (IDID = -1), wraps FCN/JAC/MAS and
!> RPAR/IPAR in a `dae_problem_t` and SOLOUT in a `sink_t`, runs the core,
!> and writes back X, Y, H, IDID and the statistics IWORK(14..20). Banded
!> Jacobians and masses become CSC matrices; the M1/M2 structure is expanded
!> to full size (§1.3): J(i, i+M2) = 1 for i ≤ M1 and M = diag(I, M_lower).
!> With a banded Jacobian and M1 = 0, c*M - J is factored in band storage
!> with the bandwidths MLJAC, MUJAC, as the original does; its round-off,
!> and so the step statistics, come closer to the original's than dense
!> LU's. With M1 > 0 the expanded matrix is not banded: dense or KLU.
!> Only X, Y, H, IDID, WORK and IWORK are ever written.
module flexmbs_legacy_radau5_adapter
    use, intrinsic :: iso_fortran_env, only: error_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: int_text
    use flexmbs_core_rules, only: rule_reason, safety_factor_rule
    use flexmbs_core_status, only: status_t, status_ok, status_bad_input, status_interrupted, &
        reason_max_steps, reason_step_too_small, reason_singular_matrix
    use flexmbs_linalg_matrix, only: storage_none, storage_identity, storage_dense, storage_sparse
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: dense_output_t
    use flexmbs_dae_radau5, only: radau5_t, radau5_dense_t
    use flexmbs_legacy_radau5_interface, only: radau5_fcn_i, radau5_jac_i, radau5_mas_i, &
        radau5_solout_i
    use flexmbs_legacy_common_solout_sink, only: solout_sink_t
    implicit none
    private

    public :: radau5_classic, contr5_value

    ! Defaults of the option slots (docs/solvers.md, RADAU5) that are not
    ! RADAU5's own settings; those (a zero slot) come from radau5_t.
    real(wp), parameter :: uround_default = 1.0e-16_wp
    integer, parameter :: nmax_default = 100000
    ! §1.12: δ_j = sqrt(uround · max(1e-5, |y_j|)).
    real(wp), parameter :: delta_floor = 1.0e-5_wp
    ! Option slots read: WORK(1..9), IWORK(1..10); statistics IWORK(14..20).
    integer, parameter :: min_slots = 20

    !> M y' = f(x, y) given by the classic FCN, JAC and MAS.
    type, extends(dae_problem_t) :: classic_problem_t
        procedure(radau5_fcn_i), pointer, nopass :: fcn => null()
        procedure(radau5_jac_i), pointer, nopass :: jac => null()
        procedure(radau5_mas_i), pointer, nopass :: mas => null()
        !> The caller's RPAR/IPAR (first element; the callee sees the whole array).
        real(wp), pointer, contiguous :: rpar(:) => null()
        integer, pointer, contiguous :: ipar(:) => null()
        integer :: m1 = 0, m2 = 0, nm1 = 0    !! M1/M2 structure; nm1 = n - M1
        logical :: analytic = .true.          !! IJAC /= 0
        logical :: banded = .false.           !! MLJAC < n - M1
        integer :: mljac = 0, mujac = 0, ldjac = 0
        logical :: has_mass = .false.         !! IMAS /= 0
        logical :: mass_banded = .false.      !! MLMAS < n - M1
        integer :: mlmas = 0, mumas = 0, ldmas = 0
        integer :: nind(3) = 0                !! NIND1, NIND2, NIND3
        real(wp) :: uround = uround_default
        !> JAC's array in classic layout. Kept between calls and zeroed once,
        !> as the original's work area: JACs that set only nonzeros still work.
        real(wp), allocatable :: dfy(:, :)
        !> Banded/M1 pattern: triplet k sits at (trow, tcol), takes dfy's
        !> element tsrc (column-major; 0: the constant 1 of the M1 rows) and
        !> lands in CSC slot tslot.
        integer, allocatable :: trow(:), tcol(:), tsrc(:)
        integer(i8), allocatable :: tslot(:)
        !> The last f(x, y) evaluated, reused as f0 by the difference Jacobian.
        logical :: cache_on = .false., cache_valid = .false.
        real(wp) :: cache_x = 0.0_wp
        real(wp), allocatable :: cache_y(:), cache_f(:), ywork(:), fwork(:)
    contains
        procedure :: rhs => classic_rhs
        procedure :: jacobian_storage => classic_jacobian_storage
        procedure :: jacobian_pattern => classic_jacobian_pattern
        procedure :: jacobian_dense => classic_jacobian_dense
        procedure :: jacobian_sparse => classic_jacobian_sparse
        procedure :: mass_storage => classic_mass_storage
        procedure :: mass_dense => classic_mass_dense
        procedure :: mass_sparse => classic_mass_sparse
        procedure :: index_classes => classic_index_classes
    end type classic_problem_t

    !> SOLOUT as a step sink; CONTR5 reads the state it stores.
    type, extends(solout_sink_t) :: classic_sink_t
        procedure(radau5_solout_i), pointer, nopass :: solout => null()
        real(wp), pointer, contiguous :: rpar(:) => null()
        integer, pointer, contiguous :: ipar(:) => null()
        integer :: n = 0
        real(wp), allocatable :: y(:), cont(:)  !! copies handed to SOLOUT
    contains
        procedure :: call_solout => sink_solout
    end type classic_sink_t

    ! Dense output of the latest SOLOUT call, read by CONTR5 (the original's
    ! COMMON block played this part).
    type(radau5_dense_t), save :: last_dense
    logical, save :: last_dense_valid = .false.

contains

    !> The body of the external RADAU5: same arguments, same meanings.
    subroutine radau5_classic(n, fcn, x, y, xend, h, rtol, atol, itol, jac, ijac, mljac, mujac, &
        mas, imas, mlmas, mumas, solout, iout, work, lwork, iwork, liwork, rpar, ipar, idid)
        include 'radau5_arguments.inc'

        type(classic_problem_t) :: problem
        type(classic_sink_t) :: sink
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        character(len=:), allocatable :: why
        integer :: nmax, nind(3), m1, m2, nm1

        idid = -1
        ! Sizes first: the option slots are read only from large enough arrays.
        if (n <= 0) then
            call reject('N = ' // int_text(n) // ': must be positive')
            return
        end if
        if (liwork < 3 * n + 20) then
            call reject('LIWORK = ' // int_text(liwork) // ': must be at least 3N+20 = ' &
                // int_text(3 * n + 20))
            return
        end if
        if (lwork < min_slots) then
            call reject('LWORK = ' // int_text(lwork) // ': too small')
            return
        end if
        call read_option_slots(n, rtol, atol, itol, work, iwork, solver, nmax, nind, m1, m2, why)
        if (len(why) == 0) call check_structure(n, m1, m2, mljac, mujac, imas, mlmas, mumas, &
                                                iwork(1), lwork, problem, why)
        if (len(why) > 0) then
            call reject(why)
            return
        end if
        nm1 = n - m1

        ! ---- the problem, the sink and the core ----
        problem%n = n
        problem%fcn => fcn
        problem%jac => jac
        problem%mas => mas
        problem%rpar => rpar(1:1)
        problem%ipar => ipar(1:1)
        problem%m1 = m1
        problem%m2 = m2
        problem%nm1 = nm1
        problem%analytic = ijac /= 0
        problem%mljac = mljac
        problem%mujac = mujac
        problem%ldjac = merge(mljac + mujac + 1, nm1, problem%banded)
        problem%mlmas = mlmas
        problem%mumas = mumas
        problem%ldmas = merge(mlmas + mumas + 1, nm1, problem%mass_banded)
        problem%nind = nind
        problem%uround = solver%uround
        allocate (problem%dfy(problem%ldjac, n), source=0.0_wp)
        if (.not. problem%analytic .and. (problem%banded .or. m1 > 0)) then
            ! The face differences these itself (§1.12); the core does the plain full case.
            problem%cache_on = .true.
            allocate (problem%cache_y(n), problem%cache_f(n), problem%ywork(n), problem%fwork(n))
        end if

        sink%solout => solout
        sink%rpar => rpar(1:1)
        sink%ipar => ipar(1:1)
        sink%n = n
        allocate (sink%y(n), sink%cont(4 * n))
        last_dense_valid = .false.

        if (itol == 0) then
            options%rtol = rtol(1)
            options%atol = atol(1)
        else
            options%rtol_vector = rtol(1:n)
            options%atol_vector = atol(1:n)
        end if
        options%h0 = h
        options%hmax = abs(work(7))
        options%max_steps = nmax
        if (problem%banded .and. m1 == 0) then
            options%linear_solver = 'band'
            options%band_lower = mljac
            options%band_upper = mujac
        end if

        if (iout /= 0) then
            call solver%integrate(problem, x, y, xend, options, stats, status, sink)
        else
            call solver%integrate(problem, x, y, xend, options, stats, status)
        end if

        if (status%code == status_bad_input) then
            call reject(status%text())
            return
        end if
        call write_back(solver, status, iwork, h, idid)

    contains

        subroutine reject(reason)
            character(len=*), intent(in) :: reason
            idid = -1
            write (error_unit, '(a)') 'RADAU5: IDID = -1: ' // reason
        end subroutine reject
    end subroutine radau5_classic

    !> The option slots WORK(1..9) and IWORK(2..10) (0 selects the default)
    !> into the solver's settings, NMAX, NIND1..3 and M1, M2; `why` says what
    !> is illegal ('' if nothing).
    subroutine read_option_slots(n, rtol, atol, itol, work, iwork, solver, nmax, nind, m1, m2, &
                                 why)
        integer, intent(in) :: n, itol, iwork(*)
        real(wp), intent(in) :: rtol(*), atol(*), work(*)
        type(radau5_t), intent(inout) :: solver
        integer, intent(out) :: nmax, nind(3), m1, m2
        character(len=:), allocatable, intent(out) :: why
        type(radau5_t) :: defaults !! its settings' defaults, for zero slots
        real(wp) :: uround, rtol1
        integer :: i
        why = ''
        uround = merge(uround_default, work(1), work(1) == 0.0_wp)
        if (uround <= 1.0e-19_wp .or. uround >= 1.0_wp) then
            why = 'WORK(1) = uround = ' // rtoa(uround) // ': must lie in (1e-19, 1)'
            return
        end if
        solver%uround = uround
        if (itol == 0) then
            if (atol(1) <= 0.0_wp .or. rtol(1) <= 10.0_wp * uround) then
                why = 'tolerances RTOL = ' // rtoa(rtol(1)) // ', ATOL = ' // &
                    rtoa(atol(1)) // ': need ATOL > 0 and RTOL > 10*uround'
                return
            end if
        else
            do i = 1, n
                if (atol(i) <= 0.0_wp .or. rtol(i) <= 10.0_wp * uround) then
                    why = 'tolerances RTOL(' // int_text(i) // ') = ' // rtoa(rtol(i)) // &
                        ', ATOL(' // int_text(i) // ') = ' // rtoa(atol(i)) // &
                        ': need ATOL > 0 and RTOL > 10*uround'
                    return
                end if
            end do
        end if
        nmax = merge(nmax_default, iwork(2), iwork(2) == 0)
        if (nmax <= 0) then
            why = 'IWORK(2) = NMAX = ' // int_text(nmax) // ': must be positive'
            return
        end if
        solver%nit = merge(defaults%nit, iwork(3), iwork(3) == 0)
        if (solver%nit <= 0) then
            why = 'IWORK(3) = NIT = ' // int_text(solver%nit) // ': must be positive'
            return
        end if
        nind = [merge(n, iwork(5), iwork(5) == 0), iwork(6), iwork(7)]
        if (any(nind < 0) .or. sum(nind) /= n) then
            why = 'IWORK(5..7) = NIND1..3 = ' // int_text(nind(1)) // ', ' // &
                int_text(nind(2)) // ', ' // int_text(nind(3)) // &
                ': must be non-negative and add up to N'
            return
        end if
        m1 = iwork(9)
        m2 = merge(m1, iwork(10), iwork(10) == 0)
        if (m1 < 0 .or. m2 < 0 .or. m1 + m2 > n) then
            why = 'IWORK(9..10) = M1, M2 = ' // int_text(m1) // ', ' // int_text(m2) // &
                ': need M1 >= 0, M2 >= 0 and M1 + M2 <= N'
            return
        end if
        solver%safe = merge(defaults%safe, work(2), work(2) == 0.0_wp)
        if (len(rule_reason(safety_factor_rule, solver%safe, .false.)) > 0) then
            why = 'WORK(2) = SAFE = ' // rtoa(solver%safe) // ': ' // &
                rule_reason(safety_factor_rule, solver%safe, .false.)
            return
        end if
        solver%thet = merge(defaults%thet, work(3), work(3) == 0.0_wp)
        if (solver%thet >= 1.0_wp) then
            why = 'WORK(3) = THET = ' // rtoa(solver%thet) // ': must be below 1'
            return
        end if
        ! §1.4: FNEWT is checked against the first transformed rtol.
        rtol1 = 0.1_wp * rtol(1)**(2.0_wp / 3.0_wp)
        solver%fnewt = work(4)
        if (solver%fnewt /= 0.0_wp .and. solver%fnewt <= uround / rtol1) then
            why = 'WORK(4) = FNEWT = ' // rtoa(solver%fnewt) // &
                ': must exceed uround/rtol'' = ' // rtoa(uround / rtol1)
            return
        end if
        solver%quot1 = merge(defaults%quot1, work(5), work(5) == 0.0_wp)
        solver%quot2 = merge(defaults%quot2, work(6), work(6) == 0.0_wp)
        if (solver%quot1 > 1.0_wp .or. solver%quot2 < 1.0_wp) then
            why = 'WORK(5..6) = QUOT1, QUOT2 = ' // rtoa(solver%quot1) // ', ' // &
                rtoa(solver%quot2) // ': need QUOT1 <= 1 <= QUOT2'
            return
        end if
        solver%fac_min = merge(defaults%fac_min, work(8), work(8) == 0.0_wp)
        solver%fac_max = merge(defaults%fac_max, work(9), work(9) == 0.0_wp)
        if (solver%fac_min > 1.0_wp .or. solver%fac_max < 1.0_wp) then
            why = 'WORK(8..9) = ' // rtoa(solver%fac_min) // ', ' // rtoa(solver%fac_max) // &
                ': need WORK(8) <= 1 <= WORK(9)'
            return
        end if
        solver%controller = iwork(8)
        solver%zero_start = iwork(4) /= 0
    end subroutine read_option_slots

    !> The Jacobian's and mass's structure (full or banded, M1/M2) and
    !> LWORK against it; `why` says what is illegal ('' if nothing).
    subroutine check_structure(n, m1, m2, mljac, mujac, imas, mlmas, mumas, hessenberg, lwork, &
                               problem, why)
        integer, intent(in) :: n, m1, m2, mljac, mujac, imas, mlmas, mumas, hessenberg, lwork
        type(classic_problem_t), intent(inout) :: problem
        character(len=:), allocatable, intent(out) :: why
        integer :: nm1, ljac, lmas, le
        integer(i8) :: need
        why = ''
        nm1 = n - m1
        problem%banded = mljac < nm1
        if (problem%banded .and. (mljac < 0 .or. mujac < 0)) then
            why = 'MLJAC, MUJAC = ' // int_text(mljac) // ', ' // int_text(mujac) // &
                ': bandwidths must not be negative'
            return
        end if
        ! Banded blocks ∂f_lower/∂y_(j+k·M2) need the lower part to be the last M2
        ! components, M1 a multiple of M2.
        if (problem%banded .and. m1 > 0) then
            if (m1 + m2 /= n .or. mod(m1, max(m2, 1)) /= 0) then
                why = 'banded Jacobian with M1 > 0 needs M1 + M2 = N and M1 a ' // &
                    'multiple of M2; got M1, M2 = ' // int_text(m1) // ', ' // int_text(m2)
                return
            end if
        end if
        problem%has_mass = imas /= 0
        if (problem%has_mass) then
            problem%mass_banded = mlmas < nm1
            if (problem%mass_banded .and. (mlmas < 0 .or. mumas < 0)) then
                why = 'MLMAS, MUMAS = ' // int_text(mlmas) // ', ' // int_text(mumas) // &
                    ': bandwidths must not be negative'
                return
            end if
            if (problem%banded) then
                if (.not. problem%mass_banded .or. mlmas > mljac .or. mumas > mujac) then
                    why = 'mass bandwidths MLMAS, MUMAS = ' // int_text(mlmas) // ', ' // &
                        int_text(mumas) // ' exceed the Jacobian''s ' // int_text(mljac) // &
                        ', ' // int_text(mujac)
                    return
                end if
            end if
        end if
        ! Hessenberg reduction (plain LU here) is ignored for n <= 2 (§1.13).
        if (hessenberg /= 0 .and. n > 2 .and. (problem%banded .or. problem%has_mass)) then
            why = 'IWORK(1) /= 0 (Hessenberg) needs a full Jacobian and IMAS = 0'
            return
        end if
        ! LWORK >= N(LJAC + LMAS + 3LE + 12) + 20 (widths n - M1 when full).
        if (problem%banded) then
            ljac = mljac + mujac + 1
            le = 2 * mljac + mujac + 1
        else
            ljac = nm1
            le = nm1
        end if
        lmas = 0
        if (problem%has_mass) lmas = merge(mlmas + mumas + 1, nm1, problem%mass_banded)
        need = int(n, i8) * (int(ljac, i8) + lmas + 3_i8 * le + 12) + 20
        if (lwork < need) why = 'LWORK = ' // int_text(lwork) // ': must be at least ' // &
            int_text(need)
    end subroutine check_structure

    !> The statistics IWORK(14..20), H and IDID after the core's run.
    subroutine write_back(solver, status, iwork, h, idid)
        type(radau5_t), intent(in) :: solver
        type(status_t), intent(in) :: status
        integer, intent(inout) :: iwork(*)
        real(wp), intent(inout) :: h
        integer, intent(out) :: idid
        iwork(14) = solver%native%nfcn
        iwork(15) = solver%native%njac
        iwork(16) = solver%native%nstep
        iwork(17) = solver%native%naccpt
        iwork(18) = solver%native%nrejct
        iwork(19) = solver%native%ndec
        iwork(20) = solver%native%nsol
        h = solver%h_opt
        select case (status%code)
        case (status_ok)
            idid = 1
        case (status_interrupted)
            idid = 2
        case default
            select case (status%reason)
            case (reason_max_steps)
                idid = -2
            case (reason_singular_matrix)
                idid = -4
            case default
                ! Step too small, and non-finite values that end there (§0).
                idid = -3
            end select
            write (error_unit, '(a,i0,a)') 'RADAU5: IDID = ', idid, ': ' // status%text()
        end select
    end subroutine write_back

    !> `CONTR5`: component i at s of the dense output of the latest SOLOUT
    !> call; NaN when there is none or i is out of range.
    real(wp) function contr5_value(i, s) result(value)
        integer, intent(in) :: i
        real(wp), intent(in) :: s
        if (.not. last_dense_valid) then
            value = ieee_value(1.0_wp, ieee_quiet_nan)
        else if (i < 1 .or. i > size(last_dense%cont, 1)) then
            value = ieee_value(1.0_wp, ieee_quiet_nan)
        else
            value = last_dense%component(i, s)
        end if
    end function contr5_value

    ! ---------------------------------------------------------------- problem

    subroutine classic_rhs(self, t, y, f, status)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        call evaluate_f(self, t, y, f)
        if (self%cache_on) then
            self%cache_x = t
            self%cache_y = y
            self%cache_f = f
            self%cache_valid = .true.
        end if
    end subroutine classic_rhs

    !> f = FCN(x, y); the M1 rows are y_(i+M2) by definition (§1.1), so a FCN
    !> that fills only the lower rows works as well.
    subroutine evaluate_f(self, t, y, f)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: f(:)
        integer :: nloc, i
        real(wp) :: xloc
        ! Copies: FCN gets variables of its own, never the core's.
        nloc = self%n
        xloc = t
        call self%fcn(nloc, xloc, y, f, self%rpar, self%ipar)
        do i = 1, self%m1
            f(i) = y(i + self%m2)
        end do
    end subroutine evaluate_f

    integer function classic_jacobian_storage(self) result(storage)
        class(classic_problem_t), intent(in) :: self
        if (self%banded) then
            storage = storage_sparse
        else if (.not. self%analytic .and. self%m1 == 0) then
            storage = storage_none
        else
            storage = storage_dense
        end if
    end function classic_jacobian_storage

    !> Band (and M1) pattern, column by column.
    subroutine classic_jacobian_pattern(self, pattern, status)
        class(classic_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer :: pass, nt, jj, i, j, ioff
        type(status_t) :: st
        ! Pass 1 counts, pass 2 fills.
        do pass = 1, 2
            nt = 0
            do jj = 1, self%n
                i = jj - self%m2
                if (self%m1 > 0 .and. i >= 1 .and. i <= self%m1) call add(i, jj, 0)
                call lower_block_column(self, jj, j)
                do i = max(1, j - self%mujac), min(self%nm1, j + self%mljac)
                    ioff = i - j + self%mujac + 1
                    call add(self%m1 + i, jj, ioff + (jj - 1) * self%ldjac)
                end do
            end do
            if (pass == 1) then
                if (allocated(self%trow)) deallocate (self%trow, self%tcol, self%tsrc)
                allocate (self%trow(nt), self%tcol(nt), self%tsrc(nt))
            end if
        end do
        call pattern%build(self%n, self%n, self%trow, self%tcol, st)
        if (.not. st%ok()) then
            status = st
            return
        end if
        self%tslot = pattern%triplet_map
    contains
        subroutine add(row, col, src)
            integer, intent(in) :: row, col, src
            nt = nt + 1
            if (pass == 2) then
                self%trow(nt) = row
                self%tcol(nt) = col
                self%tsrc(nt) = src
            end if
        end subroutine add
    end subroutine classic_jacobian_pattern

    !> Column jj of y seen by the banded lower block: j = jj - k·M2 (§1.13).
    pure subroutine lower_block_column(self, jj, j)
        class(classic_problem_t), intent(in) :: self
        integer, intent(in) :: jj
        integer, intent(out) :: j
        if (self%m1 > 0) then
            j = jj - ((jj - 1) / self%m2) * self%m2
        else
            j = jj
        end if
    end subroutine lower_block_column

    subroutine classic_jacobian_dense(self, t, y, jac, status)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        integer :: i
        call fill_dfy(self, t, y)
        jac(1:self%m1, :) = 0.0_wp
        do i = 1, self%m1
            jac(i, i + self%m2) = 1.0_wp
        end do
        jac(self%m1 + 1:self%n, :) = self%dfy(1:self%nm1, :)
    end subroutine classic_jacobian_dense

    subroutine classic_jacobian_sparse(self, t, y, values, status)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: k, src, ld
        call fill_dfy(self, t, y)
        ld = self%ldjac
        values = 0.0_wp
        do k = 1, size(self%trow)
            src = self%tsrc(k)
            if (src == 0) then
                values(self%tslot(k)) = values(self%tslot(k)) + 1.0_wp
            else
                values(self%tslot(k)) = values(self%tslot(k)) &
                    + self%dfy(mod(src - 1, ld) + 1, (src - 1) / ld + 1)
            end if
        end do
    end subroutine classic_jacobian_sparse

    !> dfy from JAC, or by differences of FCN (§1.12; not counted in NFCN).
    subroutine fill_dfy(self, t, y)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        integer :: nloc, ldloc
        real(wp) :: xloc
        if (self%analytic) then
            nloc = self%n
            ldloc = self%ldjac
            xloc = t
            call self%jac(nloc, xloc, y, self%dfy, ldloc, self%rpar, self%ipar)
        else if (self%banded) then
            call banded_differences(self, t, y)
        else
            call full_differences(self, t, y)
        end if
    end subroutine fill_dfy

    !> f0 = f(x, y): the core evaluated it just before, in most cases.
    subroutine current_f0(self, t, y)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        if (self%cache_valid) then
            if (self%cache_x == t .and. all(self%cache_y == y)) return
        end if
        call evaluate_f(self, t, y, self%cache_f)
        self%cache_x = t
        self%cache_y = y
        self%cache_valid = .true.
    end subroutine current_f0

    !> Full lower rows with M1 > 0: one FCN call per column.
    subroutine full_differences(self, t, y)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        integer :: j, m1
        real(wp) :: delt, ysafe
        call current_f0(self, t, y)
        m1 = self%m1
        self%ywork = y
        do j = 1, self%n
            ysafe = self%ywork(j)
            delt = sqrt(self%uround * max(delta_floor, abs(ysafe)))
            self%ywork(j) = ysafe + delt
            call evaluate_f(self, t, self%ywork, self%fwork)
            self%dfy(1:self%nm1, j) = (self%fwork(m1 + 1:self%n) - self%cache_f(m1 + 1:self%n)) &
                / delt
            self%ywork(j) = ysafe
        end do
    end subroutine full_differences

    !> Banded Jacobian: columns j ≡ g (mod MLJAC+MUJAC+1) of one block perturbed
    !> together, one FCN call per group; only in-band entries kept.
    subroutine banded_differences(self, t, y)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        integer :: mbb, nblocks, width, k, g, j, jj, i, off
        real(wp) :: delt
        call current_f0(self, t, y)
        mbb = self%mljac + self%mujac + 1
        if (self%m1 > 0) then
            nblocks = self%m1 / self%m2 + 1
            width = self%m2
        else
            nblocks = 1
            width = self%n
        end if
        self%ywork = y
        do k = 0, nblocks - 1
            off = k * width
            do g = 1, min(mbb, width)
                do j = g, width, mbb
                    jj = j + off
                    self%ywork(jj) = y(jj) + sqrt(self%uround * max(delta_floor, abs(y(jj))))
                end do
                call evaluate_f(self, t, self%ywork, self%fwork)
                do j = g, width, mbb
                    jj = j + off
                    delt = sqrt(self%uround * max(delta_floor, abs(y(jj))))
                    self%ywork(jj) = y(jj)
                    do i = max(1, j - self%mujac), min(self%nm1, j + self%mljac)
                        self%dfy(i - j + self%mujac + 1, jj) = &
                            (self%fwork(self%m1 + i) - self%cache_f(self%m1 + i)) / delt
                    end do
                end do
            end do
        end do
    end subroutine banded_differences

    integer function classic_mass_storage(self) result(storage)
        class(classic_problem_t), intent(in) :: self
        if (.not. self%has_mass) then
            storage = storage_identity
        else if (self%mass_banded) then
            storage = storage_sparse
        else
            storage = storage_dense
        end if
    end function classic_mass_storage

    !> MAS, called once, for the block of order n - M1 in classic storage.
    subroutine call_mas(self, am)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(out) :: am(:, :)
        integer :: nloc, ldloc
        nloc = self%nm1
        ldloc = self%ldmas
        am = 0.0_wp
        call self%mas(nloc, am, ldloc, self%rpar, self%ipar)
    end subroutine call_mas

    subroutine classic_mass_dense(self, m)
        class(classic_problem_t), intent(inout) :: self
        real(wp), intent(out) :: m(:, :)
        real(wp), allocatable :: am(:, :)
        integer :: i
        allocate (am(self%ldmas, self%nm1))
        call call_mas(self, am)
        m = 0.0_wp
        do i = 1, self%m1
            m(i, i) = 1.0_wp
        end do
        m(self%m1 + 1:self%n, self%m1 + 1:self%n) = am(1:self%nm1, 1:self%nm1)
    end subroutine classic_mass_dense

    subroutine classic_mass_sparse(self, m, status)
        class(classic_problem_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: m
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: am(:, :), vals(:)
        integer, allocatable :: rows(:), cols(:)
        integer :: nt, i, j, k
        type(status_t) :: st
        allocate (am(self%ldmas, self%nm1))
        call call_mas(self, am)
        nt = self%m1
        do j = 1, self%nm1
            nt = nt + min(self%nm1, j + self%mlmas) - max(1, j - self%mumas) + 1
        end do
        allocate (rows(nt), cols(nt), vals(nt))
        k = 0
        do i = 1, self%m1
            k = k + 1
            rows(k) = i
            cols(k) = i
            vals(k) = 1.0_wp
        end do
        do j = 1, self%nm1
            do i = max(1, j - self%mumas), min(self%nm1, j + self%mlmas)
                k = k + 1
                rows(k) = self%m1 + i
                cols(k) = self%m1 + j
                vals(k) = am(i - j + self%mumas + 1, j)
            end do
        end do
        call m%build(self%n, self%n, rows, cols, st)
        if (.not. st%ok()) then
            status = st
            return
        end if
        call m%fill(vals)
    end subroutine classic_mass_sparse

    subroutine classic_index_classes(self, classes)
        class(classic_problem_t), intent(in) :: self
        integer, intent(out) :: classes(:)
        classes(1:self%nind(1)) = 1
        classes(self%nind(1) + 1:self%nind(1) + self%nind(2)) = 2
        classes(self%nind(1) + self%nind(2) + 1:) = 3
    end subroutine classic_index_classes

    ! ------------------------------------------------------------------- sink

    !> Store the step's dense output for CONTR5, then call SOLOUT with
    !> CONT = (y⁺, q1, q2, q3) and copies of x, xold and y.
    subroutine sink_solout(self, nr, t_old, t, y, dense, irtrn)
        class(classic_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        integer, intent(inout) :: irtrn
        integer :: k, n, nrloc, nloc, lrc
        real(wp) :: xold, x
        n = self%n
        select type (dense)
        type is (radau5_dense_t)
            if (allocated(last_dense%cont)) then
                if (size(last_dense%cont, 1) /= n) deallocate (last_dense%cont)
            end if
            if (.not. allocated(last_dense%cont)) allocate (last_dense%cont(n, 0:3))
            last_dense%x = dense%x
            last_dense%h = dense%h
            last_dense%cont = dense%cont
            do k = 0, 3
                self%cont(k * n + 1:(k + 1) * n) = dense%cont(:, k)
            end do
            last_dense_valid = .true.
        class default
            self%cont(1:n) = y
            self%cont(n + 1:) = 0.0_wp
            last_dense_valid = .false.
        end select
        self%y = y
        nrloc = nr
        xold = t_old
        x = t
        nloc = n
        lrc = 4 * n
        call self%solout(nrloc, xold, x, self%y, self%cont, lrc, nloc, self%rpar, self%ipar, irtrn)
    end subroutine sink_solout

    ! ---------------------------------------------------------------- helpers



    pure function rtoa(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf
        write (buf, '(es12.4)') x
        text = trim(adjustl(buf))
    end function rtoa
end module flexmbs_legacy_radau5_adapter
