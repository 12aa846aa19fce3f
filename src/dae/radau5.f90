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
!>
!> This module holds the solver type and its driver, which runs the blocks
!> of §5.5; the constants, the state and F in flexmbs_dae_radau5_state, the
!> set-up (R0) in flexmbs_dae_radau5_start, the Jacobian, factorisations
!> and Newton iteration (R1, R2, R8) in flexmbs_dae_radau5_newton and the
!> attempt with its error estimate, acceptance and rejection (R3–R7) in
!> flexmbs_dae_radau5_step.
module flexmbs_dae_radau5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_singular_matrix
    use flexmbs_dae_sink, only: sink_t, finish_sink
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_dae_radau5_state, only: radau5_engine_t, radau5_work_t, radau5_dense_t, &
        radau5_native_t, radau5_controller_predictive, radau5_controller_classical, &
        blk_jacobian, blk_factor, blk_attempt
    use flexmbs_dae_radau5_start, only: begin_integration, output_start, start_step
    use flexmbs_dae_radau5_newton, only: jacobian_block, factor_block
    use flexmbs_dae_radau5_step, only: attempt_block
    implicit none
    private
    ! Defined with the state; part of this module's interface.
    public :: radau5_dense_t, radau5_native_t
    public :: radau5_controller_predictive, radau5_controller_classical

    !> The RADAU5 solver: the settings (a value of 0 selects the default, as in
    !> WORK/IWORK) and the results of the last integration are those of
    !> `radau5_engine_t`, which the phases read and write.
    type, extends(radau5_engine_t), public :: radau5_t
    contains
        procedure :: integrate_dae => radau5_integrate
        procedure :: name => radau5_name
        procedure :: step_counts => radau5_step_counts
        procedure :: apply_setting => radau5_apply_setting
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

    !> A scene's RADAU5 setting (scene schema, group &solver).
    subroutine radau5_apply_setting(self, setting, applied)
        class(radau5_t), intent(inout) :: self
        type(solver_setting_t), intent(in) :: setting
        logical, intent(out) :: applied
        applied = .true.
        select case (setting%name)
        case ('nit')
            self%nit = setting%integer_value
        case ('thet')
            self%thet = setting%real_value
        case ('fnewt')
            self%fnewt = setting%real_value
        case ('quot1')
            self%quot1 = setting%real_value
        case ('quot2')
            self%quot2 = setting%real_value
        case ('safe')
            self%safe = setting%real_value
        case ('fac_min')
            self%fac_min = setting%real_value
        case ('fac_max')
            self%fac_max = setting%real_value
        case ('controller')
            self%controller = merge(radau5_controller_classical, radau5_controller_predictive, &
                                    setting%string_value == 'classical')
        case ('zero_start')
            self%zero_start = setting%logical_value
        case default
            applied = .false.
        end select
    end subroutine radau5_apply_setting

    !> Integrate M y' = F(t, y) from (t, y) to t_end (docs/theory.md §5.5).
    subroutine radau5_integrate(self, problem, t, y, t_end, options, stats, status, sink, yp)
        class(radau5_t), intent(inout) :: self
        class(dae_problem_t), intent(inout) :: problem
        include 'integrate_arguments.inc'
        real(wp), intent(inout), optional :: yp(:)
        type(radau5_work_t) :: w  !! the integration's state and workspace

        call w%timer%start()
        stats%t_reached = t
        self%native = radau5_native_t()
        self%h_opt = 0.0_wp
        self%nsol_error = 0
        ! ---- R0 ----
        call begin_integration(self, w, problem, t, y, t_end, options, status)
        if (.not. status%ok()) return
        call output_start(self, w, y, options, status, sink)
        if (status%ok()) call start_step(self, w, problem, y, status)
        if (.not. status%ok()) then
            call finish(self, w, stats, status, sink)
            return
        end if

        main: do
            select case (w%block)
            case (blk_jacobian) ! ---- R1 ----
                call jacobian_block(self, w, problem, y, stats, status)
            case (blk_factor) ! ---- R2 ----
                call factor_block(self, w, stats, status)
            case (blk_attempt) ! ---- R3 to R8 ----
                call attempt_block(self, w, problem, y, options, stats, status, sink)
            end select
            if (w%done) exit main
        end do main

        t = w%x
        call finish(self, w, stats, status, sink)
    end subroutine radau5_integrate

    !> Common statistics from the native counters (docs/solvers.md): NST
    !> counts the attempts made, those that ended at R2 with a singular
    !> matrix included, the one R3 stopped on (native NSTEP) not.
    subroutine finish(self, w, stats, status, sink)
        class(radau5_t), intent(inout) :: self
        type(radau5_work_t), intent(in) :: w
        type(dae_stats_t), intent(inout) :: stats
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: sink
        stats%nst = self%native%nstep + stats%rejections%count_of(cause_singular_matrix)
        if (w%abandoned) stats%nst = stats%nst - 1
        stats%nac = self%native%naccpt
        stats%nrj = stats%nst - stats%nac
        stats%nfe = self%native%nfcn
        stats%nje = self%native%njac
        stats%ndec = self%native%ndec
        stats%nsol = self%native%nsol + self%nsol_error
        stats%t_reached = w%x
        if (allocated(w%ls)) stats%linear_solver = w%ls%description()
        if (allocated(w%ls)) stats%linear_solver_report = w%ls%report()
        if (self%h_opt == 0.0_wp) self%h_opt = w%hopt
        stats%cpu = w%timer%cpu()
        stats%wall = w%timer%wall()
        call stats%rejections%annotate(status)
        call finish_sink(sink, status)
    end subroutine finish
end module flexmbs_dae_radau5
