!> One benchmark run: integrate a problem with RADAU5 and print one line of
!> figures (counters, CPU and wall time, time per step, peak memory).
!>
!>   flexmbs-bench PROBLEM N SOLVER [MAX_STEPS] [RTOL]
!>   PROBLEM: vdp | rd1d | rd2d (N: unknowns for rd1d, grid points per side
!>   for rd2d, ignored for vdp); SOLVER: dense | klu | band | auto.
!> bench/run.sh runs the grid of configurations; these are figures, not tests.
program flexmbs_bench
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, reason_max_steps
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_problems_van_der_pol, only: new_van_der_pol, van_der_pol_t
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    implicit none
    character(len=32) :: problem_name, solver_name, arg
    integer :: npar, max_steps
    real(wp) :: rtol, t, t_end
    real(wp), allocatable :: y(:)
    class(dae_problem_t), allocatable :: problem
    type(radau5_t) :: solver
    type(dae_options_t) :: options
    type(dae_stats_t) :: stats
    type(status_t) :: status
    character(len=16) :: outcome

    if (command_argument_count() < 3) then
        write (*, '(a)') 'usage: flexmbs-bench vdp|rd1d|rd2d N dense|klu|band|auto ' // &
            '[MAX_STEPS] [RTOL]'
        error stop 2
    end if
    call get_command_argument(1, problem_name)
    call get_command_argument(2, arg)
    read (arg, *) npar
    call get_command_argument(3, solver_name)
    max_steps = 100000
    rtol = 1.0e-6_wp
    if (command_argument_count() >= 4) then
        call get_command_argument(4, arg)
        read (arg, *) max_steps
    end if
    if (command_argument_count() >= 5) then
        call get_command_argument(5, arg)
        read (arg, *) rtol
    end if

    select case (trim(problem_name))
    case ('vdp')
        allocate (problem, source=new_van_der_pol(1.0e-6_wp))
        y = [2.0_wp, -0.66_wp]
        t_end = 2.0_wp
        options%h0 = 1.0e-6_wp
    case ('rd1d')
        allocate (problem, source=new_reaction_diffusion(1, npar / 2))
        t_end = 10.0_wp
    case ('rd2d')
        allocate (problem, source=new_reaction_diffusion(2, npar))
        t_end = 1.0_wp
    case default
        write (*, '(a)') 'unknown problem ' // trim(problem_name)
        error stop 2
    end select
    select type (problem)
    type is (reaction_diffusion_t)
        allocate (y(problem%n))
        call reaction_diffusion_initial(problem, y)
    end select

    options%rtol = rtol
    options%atol = rtol
    options%max_steps = max_steps
    options%linear_solver = solver_name
    t = 0.0_wp
    call solver%integrate(problem, t, y, t_end, options, stats, status)
    if (status%ok()) then
        outcome = 'done'
    else if (status%reason == reason_max_steps) then
        outcome = 'capped'
    else
        outcome = 'failed'
        write (0, '(a)') status%text()
    end if
    ! problem n solver outcome t_reached NST NAC NFE NJE NDEC CPU WALL CPU/step peakMB
    write (*, '(a,1x,i0,1x,a,1x,a,1x,es10.3,5(1x,i0),3(1x,es10.3),1x,f0.1)') &
        trim(problem_name), problem%n, trim(solver_name), trim(outcome), t, stats%nst, &
        stats%nac, stats%nfe, stats%nje, stats%ndec, stats%cpu, stats%wall, &
        stats%cpu / max(stats%nst, 1), peak_memory_mb()

contains

    !> Peak resident set size (VmHWM) of this process in MiB, Linux only.
    real(wp) function peak_memory_mb()
        character(len=256) :: line
        integer :: unit, ios
        real(wp) :: kb
        peak_memory_mb = -1.0_wp
        open (newunit=unit, file='/proc/self/status', action='read', iostat=ios)
        if (ios /= 0) return
        do
            read (unit, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:6) == 'VmHWM:') then
                read (line(7:), *) kb
                peak_memory_mb = kb / 1024.0_wp
                exit
            end if
        end do
        close (unit)
    end function peak_memory_mb
end program flexmbs_bench
