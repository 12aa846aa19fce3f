!> RADAU5 with KLU and with MUMPS: the sparse path gives the dense
!> trajectory to round-off, on a problem of more than 2000 unknowns.
module test_radau5_sparse
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, pendulum_ggl
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_radau5_sparse

contains

    function collect_radau5_sparse() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('klu_mumps_equal_dense_brusselator_2000', test_brusselator), &
                 new_test('klu_mumps_equal_dense_pendulum_ggl', test_pendulum), &
                 new_test('nested_dissection_equals_amd_brusselator_2d', test_orderings)]
    end function collect_radau5_sparse

    subroutine run(problem, y0, t_end, linear_solver, y, stats, status, ordering)
        class(dae_problem_t), intent(inout) :: problem
        real(wp), intent(in) :: y0(:), t_end
        character(len=*), intent(in) :: linear_solver
        character(len=*), intent(in), optional :: ordering !! KLU's sparse_ordering
        real(wp), intent(out) :: y(:)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        real(wp) :: t
        options%rtol = 1.0e-6_wp
        options%atol = 1.0e-6_wp
        options%linear_solver = linear_solver
        if (present(ordering)) options%sparse_ordering = ordering
        t = 0.0_wp
        y = y0
        call solver%integrate(problem, t, y, t_end, options, stats, status)
    end subroutine run

    !> 1-D Brusselator, N = 1000: 2000 unknowns, t in [0, 0.5].
    subroutine test_brusselator(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(dae_stats_t) :: s_dense, s_klu
        type(status_t) :: status
        real(wp), allocatable :: y0(:), y_dense(:), y_klu(:)
        problem = new_reaction_diffusion(1, 1000)
        allocate (y0(problem%n), y_dense(problem%n), y_klu(problem%n))
        call check(error, problem%n >= 2000, 'problem too small')
        call reaction_diffusion_initial(problem, y0)
        call run(problem, y0, 0.5_wp, 'dense', y_dense, s_dense, status)
        call check(error, status%ok(), 'dense run: ' // status%text())
        call run(problem, y0, 0.5_wp, 'klu', y_klu, s_klu, status)
        call check(error, status%ok(), 'klu run: ' // status%text())
        call compare(error, y_dense, y_klu, s_dense, s_klu)
        call run(problem, y0, 0.5_wp, 'mumps', y_klu, s_klu, status)
        call check(error, status%ok(), 'mumps run: ' // status%text())
        call compare(error, y_dense, y_klu, s_dense, s_klu)
    end subroutine test_brusselator

    !> Sparse Jacobian and mass (CSC) through KLU versus dense LU.
    subroutine test_pendulum(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_t) :: problem
        type(dae_stats_t) :: s_dense, s_klu
        type(status_t) :: status
        real(wp) :: y0(6), y_dense(6), y_klu(6)
        problem = new_pendulum(pendulum_ggl, 1.0_wp, sparse=.true., sparse_mass=.true.)
        call pendulum_initial(problem, y0)
        call run(problem, y0, 3.0_wp, 'dense', y_dense, s_dense, status)
        call check(error, status%ok(), 'dense run: ' // status%text())
        call run(problem, y0, 3.0_wp, 'klu', y_klu, s_klu, status)
        call check(error, status%ok(), 'klu run: ' // status%text())
        call compare(error, y_dense, y_klu, s_dense, s_klu)
        call run(problem, y0, 3.0_wp, 'mumps', y_klu, s_klu, status)
        call check(error, status%ok(), 'mumps run: ' // status%text())
        call compare(error, y_dense, y_klu, s_dense, s_klu)
    end subroutine test_pendulum

    !> 2-D Brusselator on a 32 x 32 periodic grid (2048 unknowns): KLU with
    !> nested dissection and with AMD give one trajectory.
    subroutine test_orderings(error)
        type(error_t), allocatable, intent(out) :: error
        type(reaction_diffusion_t) :: problem
        type(dae_stats_t) :: s_amd, s_nd
        type(status_t) :: status
        real(wp), allocatable :: y0(:), y_amd(:), y_nd(:)
        problem = new_reaction_diffusion(2, 32)
        allocate (y0(problem%n), y_amd(problem%n), y_nd(problem%n))
        call reaction_diffusion_initial(problem, y0)
        call run(problem, y0, 0.2_wp, 'klu', y_amd, s_amd, status, 'amd')
        call check(error, status%ok(), 'amd run: ' // status%text())
        call run(problem, y0, 0.2_wp, 'klu', y_nd, s_nd, status, 'nd')
        call check(error, status%ok(), 'nd run: ' // status%text())
        call compare(error, y_amd, y_nd, s_amd, s_nd)
    end subroutine test_orderings

    !> Same steps and counters; states equal to round-off (1e-10 relative,
    !> far below the tolerance 1e-6: pivoting differs, the method does not).
    subroutine compare(error, y_dense, y_klu, s_dense, s_klu)
        type(error_t), allocatable, intent(inout) :: error
        real(wp), intent(in) :: y_dense(:), y_klu(:)
        type(dae_stats_t), intent(in) :: s_dense, s_klu
        character(len=120) :: msg
        write (msg, '(a,es10.3)') 'trajectories differ: ', &
            maxval(abs(y_dense - y_klu) / (1.0_wp + abs(y_dense)))
        call check(error, maxval(abs(y_dense - y_klu) / (1.0_wp + abs(y_dense))) <= 1.0e-10_wp, &
            trim(msg))
        call check(error, s_dense%nst == s_klu%nst .and. s_dense%nac == s_klu%nac .and. &
            s_dense%nfe == s_klu%nfe .and. s_dense%nje == s_klu%nje .and. &
            s_dense%ndec == s_klu%ndec, 'counters differ between dense and sparse')
    end subroutine compare
end module test_radau5_sparse
