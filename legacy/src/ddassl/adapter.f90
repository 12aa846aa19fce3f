!> The classic DDASSL face over the modern core `flexmbs_dae_ddassl`.
!>
!> `ddassl_classic` reads INFO, RTOL/ATOL and the option slots
!> (docs/solvers.md, DDASSL), validates them (IDID -33), wraps RES, JAC and
!> RPAR/IPAR in a `residual_problem_t`, and plays the driver of §2.7 over
!> the core's begin/step/interpolate: output at TOUT by interpolation or
!> after every step (INFO(3)), TSTOP (INFO(4)), 500 steps a call (IDID -1)
!> and continuation calls. The core's state between calls (the original kept
!> it in RWORK/IWORK) is a session of this module, found again through two
!> internal IWORK slots; the published RWORK/IWORK slots are written on every
!> return. A differenced banded PD is formed column by column (NRE does not
!> count those calls, so the counters are the original's) and factored in
!> band storage. Only T, Y, YPRIME, INFO(1), RTOL/ATOL (on IDID -2), IDID,
!> RWORK and IWORK are ever written.
module flexmbs_legacy_ddassl_adapter
    use, intrinsic :: iso_fortran_env, only: error_unit
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense
    use flexmbs_dae_residual_problem, only: residual_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_ddassl, only: ddassl_t, ddassl_max_order, ddassl_fail_none, &
        ddassl_fail_tolerances, ddassl_fail_initial
    use flexmbs_legacy_ddassl_interface, only: ddassl_res_i, ddassl_jac_i
    implicit none
    private

    public :: ddassl_classic

    integer, parameter :: max_steps_per_call = 500   !! §2.7: IDID -1 after 500 steps
    real(wp), parameter :: tstop_tol = 100.0_wp      !! §2.7: |T_N - TSTOP| ≤ 100 uround (...)
    real(wp), parameter :: hmin_factor = 4.0_wp      !! §2.7: hmin = 4 uround max(|T|, |TOUT|)
    integer, parameter :: lrw_fixed = 40, liw_fixed = 20 !! §2.11 workspace
    ! Internal IWORK slots that find the session again (§2.11: 16..20 internal).
    integer, parameter :: slot_session = 16, slot_token = 17
    integer, parameter :: idid_illegal = -33, idid_fatal = -999, idid_no_action = -998

    !> G(t, y, y') = 0 given by the classic RES and JAC.
    type, extends(residual_problem_t) :: classic_residual_t
        procedure(ddassl_res_i), pointer, nopass :: res => null()
        procedure(ddassl_jac_i), pointer, nopass :: jac => null()
        real(wp), pointer, contiguous :: rpar(:) => null()
        integer, pointer, contiguous :: ipar(:) => null()
        logical :: analytic = .false.     !! INFO(5) = 1
        logical :: banded = .false.       !! INFO(6) = 1
        integer :: ml = 0, mu = 0
        real(wp), allocatable :: pdband(:, :) !! JAC's banded array
    contains
        procedure :: residual => classic_residual
        procedure :: setup_partials => classic_setup
        procedure :: partials => classic_partials
        procedure :: has_iteration_matrix => classic_has_pd
        procedure :: iteration_matrix => classic_pd
    end type classic_residual_t

    !> One integration's state between DDASSL calls.
    type :: session_t
        logical :: in_use = .false.
        integer :: token = 0
        integer :: last_idid = 0
        type(ddassl_t) :: solver
        type(classic_residual_t) :: problem
    end type session_t

    !> What a call's arguments say, once checked (check_call, §2.11).
    type :: classic_call_t
        logical :: first = .false.           !! INFO(1) = 0: a new problem
        logical :: have_tstop = .false.      !! INFO(4) = 1
        integer :: maxord = ddassl_max_order !! INFO(9): IWORK(3)
        integer :: ml = 0, mu = 0            !! INFO(6): IWORK(1), IWORK(2)
        integer :: ntol = 1                  !! INFO(2): NEQ tolerances, else 1
        real(wp) :: tstop = 0.0_wp           !! RWORK(1)
        real(wp) :: hmax = huge(1.0_wp)      !! INFO(7): RWORK(2)
        real(wp) :: uround = epsilon(1.0_wp)
        real(wp) :: dir = 1.0_wp             !! the direction of integration
        real(wp), allocatable :: rt(:), at(:) !! first call: the tolerances as vectors
    end type classic_call_t

    type(session_t), allocatable, target, save :: sessions(:)
    integer, save :: token_counter = 0
    integer, save :: last_idid = 0   !! of the latest call, for -998/-999 without a session

contains

    !> The body of the external DDASSL: same arguments, same meanings.
    subroutine ddassl_classic(res, neq, t, y, yprime, tout, info, rtol, atol, idid, rwork, lrw, &
        iwork, liw, rpar, ipar, jac)
        include 'ddassl_arguments.inc'

        type(session_t), pointer :: ses
        type(dae_options_t) :: options
        type(status_t) :: status
        type(classic_call_t) :: args
        real(wp), allocatable :: rt(:), at(:)
        integer :: nst_start, illegal

        ! ---- a failure not acknowledged (§2.11, INFO(1)) ----
        if (info(1) == -1) then
            call refuse_unacknowledged(iwork, liw, idid)
            return
        end if

        ! ---- illegal input (IDID -33, §2.11) ----
        call check_call(neq, t, y, tout, info, rtol, atol, lrw, rwork, liw, iwork, args, illegal)
        if (illegal /= 0) then
            call illegal_input(illegal)
            return
        end if

        ! ---- first call: a session and the core's begin (§2.7) ----
        if (args%first) then
            ses => new_session(iwork, liw)
            call attach()
            call configure_session(ses, args, neq, info, rwork, options)
            if (args%have_tstop) then
                call ses%solver%begin(ses%problem, t, y(1:neq), yprime(1:neq), tout, options, &
                    status, initial_derivative=info(11) == 1, tstop=args%tstop)
            else
                call ses%solver%begin(ses%problem, t, y(1:neq), yprime(1:neq), tout, options, &
                    status, initial_derivative=info(11) == 1)
            end if
            if (.not. status%ok()) then
                if (ses%solver%work%failure /= ddassl_fail_none) then
                    call failed(ses%solver%work%failure, status%message)
                else
                    ! Input the checks above let through (e.g. a bad band).
                    call message(status%message)
                    call illegal_input(1)
                end if
                return
            end if
            info(1) = 1  ! the code has been initialised: later calls continue
        else
            ses => find_session(iwork, liw)   ! check_call found it
            call attach()
            ses%solver%work%hmax = args%hmax
            allocate (rt(neq), at(neq))
            call expand_tolerances(info, neq, rtol, atol, rt, at)
            ses%solver%work%rtol = rt
            ses%solver%work%atol = at
        end if

        ! ---- the driver (§2.7) ----
        associate (w => ses%solver%work, solver => ses%solver)
            nst_start = solver%native%nst
            ! A continuation call makes the output tests before stepping.
            if (.not. args%first) then
                if (output_reached(ses, args, .true., info, neq, tout, t, y, yprime, idid)) then
                    call finish()
                    return
                end if
            end if
            do
                if (solver%native%nst - nst_start >= max_steps_per_call) then
                    call give_back_tn()
                    call failed(-1, 'at T = ' // real_text(w%tn) // ', 500 steps were taken ' &
                        // 'on this call before reaching TOUT')
                    return
                end if
                if (args%have_tstop) then
                    call solver%step(ses%problem, y(1:neq), yprime(1:neq), tout, status, &
                        .false., args%tstop)
                else
                    call solver%step(ses%problem, y(1:neq), yprime(1:neq), tout, status, &
                        .false.)
                end if
                if (.not. status%ok()) then
                    call give_back_tn()
                    if (w%failure == ddassl_fail_tolerances) then
                        rtol(1:args%ntol) = rtol(1:args%ntol) * w%tol_scale
                        atol(1:args%ntol) = atol(1:args%ntol) * w%tol_scale
                    end if
                    call failed(w%failure, status%message)
                    return
                end if
                if (output_reached(ses, args, .false., info, neq, tout, t, y, yprime, idid)) exit
                if (info(3) == 1) then
                    call give_back_tn()
                    idid = 1
                    exit
                end if
            end do
        end associate
        call finish()

    contains

        !> Point the wrapper at this call's user routines and data.
        subroutine attach()
            ses%problem%res => res
            ses%problem%jac => jac
            ses%problem%rpar(1:1) => rpar(1:1)
            ses%problem%ipar(1:1) => ipar(1:1)
        end subroutine attach

        !> T = T_N and (Y, YPRIME) there.
        subroutine give_back_tn()
            t = ses%solver%work%tn
            call ses%solver%interpolate(t, y(1:neq), yprime(1:neq))
        end subroutine give_back_tn

        !> A failure return: IDID, INFO(1) = -1, the slots, and the message.
        subroutine failed(code, why)
            integer, intent(in) :: code
            character(len=*), intent(in) :: why
            idid = code
            if (code /= -1) call message(why)
            call finish()
        end subroutine failed

        subroutine illegal_input(number)
            integer, intent(in) :: number
            type(session_t), pointer :: old
            idid = idid_illegal
            info(1) = -1
            call message('illegal input ' // int_text(number) // ': ' // illegal_text(number))
            old => find_session(iwork, liw)
            if (associated(old)) old%last_idid = idid
            last_idid = idid
        end subroutine illegal_input

        !> The published slots (§2.11) and INFO(1) on every return.
        subroutine finish()
            call publish_slots(ses, neq, idid, info, rwork, iwork)
        end subroutine finish
    end subroutine ddassl_classic

    !> INFO(1) = -1 on entry: the last failure was not acknowledged. IDID
    !> -999 after an illegal input (repeated: the run is terminated), else
    !> -998 (no action taken).
    subroutine refuse_unacknowledged(iwork, liw, idid)
        integer, intent(in) :: liw, iwork(liw)
        integer, intent(out) :: idid
        type(session_t), pointer :: ses
        ses => find_session(iwork, liw)
        if (associated(ses)) last_idid = ses%last_idid
        if (last_idid == idid_illegal .or. last_idid == idid_fatal) then
            idid = idid_fatal
            last_idid = idid
            call message('repeated illegal input: run terminated')
            return
        end if
        idid = idid_no_action
        last_idid = idid
        call message('the last call ended with IDID < 0 and no action was taken ' // &
            '(set INFO(1) = 1 to continue, 0 to start again): run terminated')
    end subroutine refuse_unacknowledged

    !> §2.7 "Output": TOUT reached (IDID 3) or TSTOP reached (IDID 2)? Then
    !> T, Y and YPRIME there. On a continuation call with INFO(3) = 1 "TOUT
    !> passed" is strict.
    logical function output_reached(ses, args, continuation, info, neq, tout, t, y, yprime, &
                                    idid) result(reached)
        type(session_t), intent(inout) :: ses
        type(classic_call_t), intent(in) :: args
        logical, intent(in) :: continuation
        integer, intent(in) :: info(15), neq
        real(wp), intent(in) :: tout
        real(wp), intent(inout) :: t, y(*), yprime(*)
        integer, intent(inout) :: idid
        real(wp) :: passed
        associate (w => ses%solver%work)
            reached = .false.
            ! TSTOP first: TOUT may not lie beyond it, so reaching it
            ! (stepping exactly there) is IDID 2 even when TOUT = TSTOP.
            if (args%have_tstop) then
                if (abs(w%tn - args%tstop) <= tstop_tol * w%uround * (abs(w%tn) + abs(w%h))) then
                    call ses%solver%interpolate(args%tstop, y(1:neq), yprime(1:neq))
                    t = args%tstop
                    idid = 2
                    reached = .true.
                    return
                end if
            end if
            passed = (w%tn - tout) * w%h
            if ((continuation .and. info(3) == 1 .and. passed > 0.0_wp) .or. &
                ((.not. continuation .or. info(3) == 0) .and. passed >= 0.0_wp)) then
                call ses%solver%interpolate(tout, y(1:neq), yprime(1:neq))
                t = tout
                idid = 3
                reached = .true.
            end if
        end associate
    end function output_reached

    !> A new session's problem and solver settings, and the core's options,
    !> from INFO, the checked arguments and RWORK(3) (docs/solvers.md, DDASSL).
    subroutine configure_session(ses, args, neq, info, rwork, options)
        type(session_t), intent(inout) :: ses
        type(classic_call_t), intent(in) :: args
        integer, intent(in) :: neq, info(15)
        real(wp), intent(in) :: rwork(*)
        type(dae_options_t), intent(out) :: options
        ses%problem%n = neq
        ses%problem%analytic = info(5) == 1
        ses%problem%banded = info(6) == 1
        ses%problem%ml = args%ml
        ses%problem%mu = args%mu
        ses%solver%netlib = .false.
        ses%solver%fixed_step = .false.
        ses%solver%tstop = .false.           ! TSTOP is handled here
        ses%solver%h0_from_first_output = .false.
        ses%solver%exclude_index23 = .false.  ! §2.10: no mask in the classic code
        ses%solver%nonnegative = info(10) == 1
        ses%solver%uround = args%uround
        options%pmax = args%maxord
        options%rtol_vector = args%rt
        options%atol_vector = args%at
        options%max_steps = huge(1)
        if (info(7) == 1) options%hmax = args%hmax
        if (info(8) == 1) options%h0 = abs(rwork(3))
        options%jacobian = 'analytic'
        if (info(5) == 0) options%jacobian = 'fd'
        options%linear_solver = 'dense'
        options%classic_lu = .true.
        if (info(6) == 1) then
            options%linear_solver = 'band'
            options%band_lower = args%ml
            options%band_upper = args%mu
        end if
    end subroutine configure_session

    !> The published slots (§2.11), INFO(1) on a failure and the last IDID,
    !> on every return.
    subroutine publish_slots(ses, neq, idid, info, rwork, iwork)
        type(session_t), intent(inout) :: ses
        integer, intent(in) :: neq, idid
        integer, intent(inout) :: info(15), iwork(*)
        real(wp), intent(inout) :: rwork(*)
        integer :: k, base, nphi
        associate (w => ses%solver%work, nat => ses%solver%native)
            iwork(7) = w%k
            iwork(8) = w%kold
            iwork(11) = nat%nst
            iwork(12) = nat%nre
            iwork(13) = nat%nje
            iwork(14) = nat%netf
            iwork(15) = nat%ncfn
            rwork(3) = w%h
            rwork(4) = w%tn
            rwork(5) = w%cj
            rwork(6) = w%cjold
            rwork(7) = w%hold
            rwork(9) = w%uround
            rwork(11:16) = w%alpha
            rwork(17:22) = w%beta
            rwork(23:28) = w%gamma
            rwork(29:34) = w%psi
            rwork(35:40) = w%sigma
            if (allocated(w%phi)) then
                ! δ, e and wt, then φ (NEQ x (MAXORD + 1)).
                base = lrw_fixed
                rwork(base + 1:base + neq) = w%delta
                rwork(base + neq + 1:base + 2 * neq) = w%e
                rwork(base + 2 * neq + 1:base + 3 * neq) = w%wt
                nphi = size(w%phi, 2)
                do k = 1, nphi
                    rwork(base + (2 + k) * neq + 1:base + (3 + k) * neq) = w%phi(:, k)
                end do
            end if
        end associate
        if (idid < 0) info(1) = -1
        ses%last_idid = idid
        last_idid = idid
    end subroutine publish_slots

    !> §2.11's checks of a call's arguments, in the original's order: the
    !> number of the first illegal input (0: none) and what the arguments
    !> say (`args`); the tolerances as vectors on a first call.
    subroutine check_call(neq, t, y, tout, info, rtol, atol, lrw, rwork, liw, iwork, args, &
                          illegal)
        integer, intent(in) :: neq, lrw, liw
        real(wp), intent(in) :: t, y(*), tout, rtol(*), atol(*), rwork(lrw)
        integer, intent(in) :: info(15), iwork(liw)
        type(classic_call_t), intent(out) :: args
        integer, intent(out) :: illegal
        type(session_t), pointer :: ses
        real(wp), allocatable :: wt(:)
        real(wp) :: h0, hmin
        illegal = 0
        args%first = info(1) == 0
        if (any(info(1:11) /= 0 .and. info(1:11) /= 1)) illegal = 1
        if (illegal == 0 .and. neq <= 0) illegal = 2
        if (illegal == 0 .and. info(9) == 1) then
            args%maxord = iwork(3)
            if (args%maxord < 1 .or. args%maxord > ddassl_max_order) illegal = 3
        end if
        if (illegal == 0 .and. info(6) == 1) then
            args%ml = iwork(1)
            args%mu = iwork(2)
            if (args%ml < 0 .or. args%ml >= neq) illegal = 17
            if (illegal == 0 .and. (args%mu < 0 .or. args%mu >= neq)) illegal = 18
        end if
        if (illegal == 0) then
            if (lrw < required_lrw(neq, args%maxord, info(6) == 1, info(5) == 0, args%ml, &
                                   args%mu)) illegal = 4
            if (illegal == 0 .and. liw < liw_fixed + neq) illegal = 5
        end if
        if (info(2) == 1) args%ntol = max(neq, 1)
        if (illegal == 0) then
            associate (ntol => args%ntol)
                if (any(rtol(1:ntol) < 0.0_wp)) illegal = 6
                if (illegal == 0 .and. any(atol(1:ntol) < 0.0_wp)) illegal = 7
                if (illegal == 0 .and. all(rtol(1:ntol) == 0.0_wp) .and. &
                    all(atol(1:ntol) == 0.0_wp)) illegal = 8
            end associate
        end if
        ! The direction of integration: towards TOUT, or that of the steps.
        args%dir = sign(1.0_wp, tout - t)
        if (.not. args%first) then
            ses => find_session(iwork, liw)
            if (associated(ses)) args%dir = sign(1.0_wp, ses%solver%work%h)
        end if
        args%have_tstop = info(4) == 1
        if (illegal == 0 .and. args%have_tstop) then
            args%tstop = rwork(1)
            if ((args%tstop - tout) * args%dir < 0.0_wp) illegal = 9
        end if
        if (illegal == 0 .and. info(7) == 1) then
            args%hmax = rwork(2)
            if (args%hmax < 0.0_wp) illegal = 10
        end if
        if (illegal == 0 .and. args%first) then
            if (tout == t) then
                illegal = 19
            else if (info(8) == 1) then
                h0 = rwork(3)
                if (h0 == 0.0_wp) then
                    illegal = 12
                else if ((tout - t) * h0 < 0.0_wp) then
                    illegal = 11
                end if
            end if
            if (illegal == 0 .and. args%have_tstop) then
                if ((args%tstop - t) * args%dir < 0.0_wp) illegal = 15
            end if
            if (illegal == 0) then
                allocate (args%rt(neq), args%at(neq), wt(neq))
                call expand_tolerances(info, neq, rtol, atol, args%rt, args%at)
                wt = args%rt * abs(y(1:neq)) + args%at
                if (any(.not. wt > 0.0_wp)) illegal = 13
            end if
            if (illegal == 0) then
                hmin = hmin_factor * args%uround * max(abs(t), abs(tout))
                if (abs(tout - t) < hmin) illegal = 14
            end if
        end if
        if (illegal == 0 .and. .not. args%first) then
            ses => find_session(iwork, liw)
            if (.not. associated(ses)) then
                illegal = 1
                call message('INFO(1) = 1 but IWORK holds no integration to continue')
            else if (.not. ses%solver%work%ready) then
                illegal = 1
                call message('INFO(1) = 1 but the integration never started (DDAINI ' // &
                    'failed): start again with INFO(1) = 0')
            end if
            if (illegal == 0) then
                if ((tout - t) * args%dir < 0.0_wp) illegal = 11
                if (illegal == 0 .and. tout == t) illegal = 19
                if (illegal == 0 .and. args%have_tstop) then
                    if ((args%tstop - ses%solver%work%tn) * args%dir < 0.0_wp) illegal = 15
                end if
            end if
        end if
    end subroutine check_call

    !> INFO(2): scalar or vector tolerances as vectors of length NEQ.
    subroutine expand_tolerances(info, neq, rtol, atol, rt, at)
        integer, intent(in) :: info(15), neq
        real(wp), intent(in) :: rtol(*), atol(*)
        real(wp), intent(inout) :: rt(:), at(:)
        if (info(2) == 1) then
            rt = rtol(1:neq)
            at = atol(1:neq)
        else
            rt = rtol(1)
            at = atol(1)
        end if
    end subroutine expand_tolerances

    !> The session IWORK names, if it is one of ours.
    function find_session(iwork, liw) result(found)
        integer, intent(in) :: liw, iwork(liw)
        type(session_t), pointer :: found
        integer :: isession
        found => null()
        if (liw < slot_token .or. .not. allocated(sessions)) return
        isession = iwork(slot_session)
        if (isession < 1 .or. isession > size(sessions)) return
        if (.not. sessions(isession)%in_use) return
        if (sessions(isession)%token /= iwork(slot_token)) return
        found => sessions(isession)
    end function find_session

    !> A session for a new problem: the one IWORK names, else a free one;
    !> IWORK's internal slots name it.
    function new_session(iwork, liw) result(fresh)
        integer, intent(in) :: liw
        integer, intent(inout) :: iwork(liw)
        type(session_t), pointer :: fresh
        type(session_t), allocatable :: grown(:)
        integer :: isession, i
        fresh => find_session(iwork, liw)
        if (associated(fresh)) then
            isession = iwork(slot_session)
        else
            if (.not. allocated(sessions)) allocate (sessions(4))
            isession = 0
            do i = 1, size(sessions)
                if (.not. sessions(i)%in_use) then
                    isession = i
                    exit
                end if
            end do
            if (isession == 0) then
                allocate (grown(2 * size(sessions)))
                grown(1:size(sessions)) = sessions
                isession = size(sessions) + 1
                call move_alloc(grown, sessions)
            end if
            fresh => sessions(isession)
        end if
        token_counter = token_counter + 1
        fresh%in_use = .true.
        fresh%token = token_counter
        fresh%last_idid = 0
        iwork(slot_session) = isession
        iwork(slot_token) = fresh%token
    end function new_session

    !> §2.11 workspace: dense, or banded (+ the differenced band's extra).
    pure integer function required_lrw(neq, maxord, banded, differenced, ml, mu) result(lrw)
        integer, intent(in) :: neq, maxord, ml, mu
        logical, intent(in) :: banded, differenced
        if (banded) then
            lrw = lrw_fixed + (maxord + 4) * neq + (2 * ml + mu + 1) * neq
            if (differenced) lrw = lrw + 2 * (neq / (ml + mu + 1) + 1)
        else
            lrw = lrw_fixed + (maxord + 4) * neq + neq * neq
        end if
    end function required_lrw

    pure function illegal_text(number) result(text)
        integer, intent(in) :: number
        character(len=:), allocatable :: text
        select case (number)
        case (1); text = 'some INFO(1..11) is neither 0 nor 1'
        case (2); text = 'NEQ <= 0'
        case (3); text = 'MAXORD = IWORK(3) not in 1..5'
        case (4); text = 'LRW too small'
        case (5); text = 'LIW too small'
        case (6); text = 'some RTOL < 0'
        case (7); text = 'some ATOL < 0'
        case (8); text = 'all RTOL and ATOL are zero'
        case (9); text = 'TSTOP = RWORK(1) lies behind TOUT'
        case (10); text = 'HMAX = RWORK(2) < 0'
        case (11); text = 'TOUT lies behind T'
        case (12); text = 'H0 = RWORK(3) is zero'
        case (13); text = 'some weight RTOL*|Y| + ATOL is not positive'
        case (14); text = 'TOUT too close to T to start'
        case (15); text = 'TSTOP lies behind T'
        case (17); text = 'ML = IWORK(1) not in 0..NEQ-1'
        case (18); text = 'MU = IWORK(2) not in 0..NEQ-1'
        case (19); text = 'TOUT = T'
        case default; text = 'see docs/solvers.md, DDASSL'
        end select
    end function illegal_text

    subroutine message(text)
        character(len=*), intent(in) :: text
        write (error_unit, '(a)') 'DDASSL: ' // text
    end subroutine message

    subroutine classic_residual(self, t, y, yp, g, status)
        class(classic_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
        integer :: ires
        ires = 0
        call self%res(t, y, yp, g, ires, self%rpar, self%ipar)
        if (ires == -2) then
            call status%set(status_interrupted, 'DDASSL: RES set IRES = -2 at T = ' // &
                real_text(t))
        else if (ires < 0) then
            call status%set(status_bad_input, 'DDASSL: RES set IRES = -1 (illegal Y) at T = ' &
                // real_text(t))
        end if
    end subroutine classic_residual

    !> A is unused (PD is factored as it stands); B holds −PD, dense.
    subroutine classic_setup(self, differenced, a, b, status)
        class(classic_residual_t), intent(inout) :: self
        logical, intent(in) :: differenced
        type(matrix_t), intent(inout) :: a, b
        type(status_t), intent(inout) :: status
        a%n = self%n
        a%storage = storage_identity
        b%n = self%n
        if (differenced .or. .not. self%analytic) then
            b%storage = storage_none
        else
            b%storage = storage_dense
            if (allocated(b%dense)) deallocate (b%dense)
            allocate (b%dense(self%n, self%n))
            b%dense = 0.0_wp
            if (self%banded) then
                if (allocated(self%pdband)) deallocate (self%pdband)
                allocate (self%pdband(2 * self%ml + self%mu + 1, self%n))
            end if
        end if
    end subroutine classic_setup

    subroutine classic_partials(self, t, y, yp, a, b, status)
        class(classic_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:)
        type(matrix_t), intent(inout) :: a, b
        type(status_t), intent(inout) :: status
        call status%set(status_bad_input, 'DDASSL: the classic JAC gives PD, not its parts')
    end subroutine classic_partials

    logical function classic_has_pd(self)
        class(classic_residual_t), intent(in) :: self
        classic_has_pd = self%analytic
    end function classic_has_pd

    !> PD from JAC, zeroed before the call; banded storage expanded.
    subroutine classic_pd(self, t, y, yp, cj, pd, status)
        class(classic_residual_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:), yp(:), cj
        real(wp), intent(out) :: pd(:, :)
        type(status_t), intent(inout) :: status
        integer :: i, j, m
        if (self%banded) then
            self%pdband = 0.0_wp
            call self%jac(t, y, yp, self%pdband, cj, self%rpar, self%ipar)
            pd = 0.0_wp
            m = self%ml + self%mu + 1
            do j = 1, self%n
                do i = max(1, j - self%mu), min(self%n, j + self%ml)
                    pd(i, j) = self%pdband(i - j + m, j)
                end do
            end do
        else
            pd = 0.0_wp
            call self%jac(t, y, yp, pd, cj, self%rpar, self%ipar)
        end if
    end subroutine classic_pd
end module flexmbs_legacy_ddassl_adapter
