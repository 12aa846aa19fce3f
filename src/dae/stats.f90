!> Common solver statistics, one meaning for every solver (docs/solvers.md).
module flexmbs_dae_stats
    use flexmbs_core_kinds, only: wp
    use flexmbs_dae_rejections, only: rejections_t
    implicit none
    private

    public :: index3_warning, projection_refusal

    !> The statistics of one integration, filled alike by every solver: steps,
    !> evaluations, factorisations, solves, times and the causes of rejections.
    type, public :: dae_stats_t
        integer :: nst = 0     !! attempted steps (accepted + rejected + failed)
        integer :: nac = 0     !! accepted steps
        integer :: nrj = 0     !! nst - nac
        integer :: nfe = 0     !! F/G/f evaluations, difference-Jacobian calls excluded
        integer :: nfe_jac = 0 !! evaluations made for difference Jacobians
        integer :: nje = 0     !! Jacobian evaluations
        integer :: ndec = 0    !! factorisations (RADAU5's real+complex pair counts 1)
        integer :: nsol = 0    !! solves with a factorisation, error-estimate solves included
        integer :: nprj = 0    !! projections
        real(wp) :: cpu = 0.0_wp  !! CPU seconds
        real(wp) :: wall = 0.0_wp !! wall seconds
        real(wp) :: t_reached = 0.0_wp !! last time reached (t_end on success)
        real(wp) :: h_last = 0.0_wp    !! last accepted step size
        !> The NRJ failed or rejected attempts by cause (they add up to NRJ),
        !> with the last model refusal's reason (flexmbs_dae_rejections).
        type(rejections_t) :: rejections
        !> What the caller should know although the run succeeded (e.g. a
        !> formulation the solver is not made for); empty when none.
        character(len=:), allocatable :: warning
        !> What factored the iteration matrices, as the linear solver's
        !> description() gives it ('condensed mumps, ordering scotch', 'klu,
        !> ordering amd', 'dense'): what linear_solver = 'auto' chose.
        !> Empty when the solver factors nothing of ours.
        character(len=:), allocatable :: linear_solver
        !> What its factorisations cost, where the linear solver counts it
        !> (MUMPS: processes, seconds per factorisation, memory); empty
        !> otherwise. `flexmbs run --verbose` prints it.
        character(len=:), allocatable :: linear_solver_report
    contains
        procedure :: reset => stats_reset
        procedure :: summary => stats_summary
    end type dae_stats_t

contains

    pure subroutine stats_reset(self)
        class(dae_stats_t), intent(inout) :: self
        self%nst = 0; self%nac = 0; self%nrj = 0; self%nfe = 0; self%nfe_jac = 0
        self%nje = 0; self%ndec = 0; self%nsol = 0; self%nprj = 0
        self%cpu = 0.0_wp; self%wall = 0.0_wp; self%t_reached = 0.0_wp; self%h_last = 0.0_wp
        self%rejections = rejections_t()
        if (allocated(self%warning)) deallocate (self%warning)
        if (allocated(self%linear_solver)) deallocate (self%linear_solver)
        if (allocated(self%linear_solver_report)) deallocate (self%linear_solver_report)
    end subroutine stats_reset

    !> One line: 'NST=... NAC=... NRJ=... ...', NRJ followed by its causes
    !> when an attempt failed: 'NRJ=37 (error test 30, Newton slow 5,
    !> refused 2)'.
    function stats_summary(self) result(line)
        class(dae_stats_t), intent(in) :: self
        character(len=:), allocatable :: line, causes
        character(len=400) :: head, tail
        write (head, '(3(a,i0))') 'NST=', self%nst, ' NAC=', self%nac, ' NRJ=', self%nrj
        write (tail, '(6(a,i0),2(a,f0.4))') ' NFE=', self%nfe, ' NFE_JAC=', self%nfe_jac, &
            ' NJE=', self%nje, ' NDEC=', self%ndec, ' NSOL=', self%nsol, &
            ' NPRJ=', self%nprj, ' CPU=', self%cpu, ' WALL=', self%wall
        causes = self%rejections%summary()
        if (len(causes) > 0) causes = ' (' // causes // ')'
        line = trim(head) // causes // trim(tail)
    end function stats_summary

    !> The warning for index-3 components given to a BDF code (docs/theory.md §3).
    pure function index3_warning(solver) result(text)
        character(len=*), intent(in) :: solver
        character(len=:), allocatable :: text
        text = solver // ': the problem has index-3 components; BDF is not made for ' // &
            'index 3 (they are left out of the error test, else it fails at t = 0): ' // &
            'prefer the index-2 or GGL formulation'
    end function index3_warning

    !> Why a BDF code refuses a formulation with coordinate projection, and
    !> the solver that takes one.
    pure function projection_refusal(solver, instead) result(text)
        character(len=*), intent(in) :: solver, instead
        character(len=:), allocatable :: text
        text = solver // ': projection is refused, it disturbs the BDF history ' // &
            '(docs/theory.md, section 3.5); use ' // instead // ' or switch projection off'
    end function projection_refusal
end module flexmbs_dae_stats
