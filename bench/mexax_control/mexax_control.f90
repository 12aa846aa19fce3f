!> `flexmbs-bench-mexax-control`: MEXAX's two order and step-size controls
!> (ODEX/SEULEX's 'hairer' and 'deuflhard', docs/theory.md §7.3) side by
!> side on the planar bar chain of docs/solvers.md, from horizontal at rest
!> to t = 1, rtol = atol = TOL, H0 = 1e-3.
!>
!> Part 1, the work-precision table: for chains of 3, 5, 8, 12 and 16 bars
!> and TOL 1e-3 … 1e-9, per base and control, NSTEP, NACCPT, NREJCT, NFCN
!> and the largest relative error of the bars' angles at t = 1 over TOL
!> and as correct digits (−log10 of it),
!> against Radau IIA at 1e-12 (index-2 formulation; a reference from another
!> integrator). Lines 'wp BASE CONTROL NB TOL ...' are what
!> bench/mexax_control.py plots.
!> Part 2, the 8-bar anchor of docs/theory.md §7.7 (base (E), a and λ
!> extrapolated, the classic elimination order) per control: the counters
!> of one run at H0 = 1e-3 and the means over H0 = 1e-3 (1 + 1e-4 m), m =
!> 0 … 9, beside the original's; a member that fails is named and left out
!> of the means.
!> Part 3, the spread of part 1's accuracy: the same runs on the chains of
!> 8, 12 and 16 bars (the longer ones within the given lengths) from the
!> anchor's ten H0 (1e-3 (1 + 1e-4 m)) — a single run's largest angle error
!> moves by an order of magnitude under such a change (docs/theory.md §7.3)
!> — per base and control: runs, how many above 20 TOL, median and worst
!> over TOL.
!> Arguments: optional chain lengths (default 3 5 8 12 16). Never asserts.
program flexmbs_bench_mexax_control
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler, mexax_base_midpoint, &
        mexax_control_hairer, mexax_control_deuflhard
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_run_catalogue, only: solvers, solver_radau5
    use flexmbs_run_solver_factory, only: new_solver
    use flexmbs_mbs_formulation, only: block_q, block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_problems_pendulum_chain, only: pendulum_chain_t, new_pendulum_chain, &
        pendulum_chain_initial
    implicit none
    integer, parameter :: default_chains(5) = [3, 5, 8, 12, 16]
    integer, parameter :: bases(2) = [mexax_base_euler, mexax_base_midpoint]
    integer, parameter :: controls(2) = [mexax_control_hairer, mexax_control_deuflhard]
    character(len=*), parameter :: base_names(2) = ['euler   ', 'midpoint']
    character(len=*), parameter :: control_names(2) = ['hairer   ', 'deuflhard']
    ! the original's anchor: NSTEP, NACCPT, NREJCT at TOL 1e-3, 1e-5, 1e-7, 1e-9
    integer, parameter :: anchor(3, 4) = reshape([49, 38, 11, 58, 45, 13, 54, 45, 9, &
                                                  68, 60, 8], [3, 4])
    integer, allocatable :: chains(:)
    integer :: n, i
    character(len=32) :: arg
    n = command_argument_count()
    if (n == 0) then
        chains = default_chains
    else
        allocate (chains(n))
        do i = 1, n
            call get_command_argument(i, arg)
            read (arg, *) chains(i)
        end do
    end if
    call work_precision(chains)
    call anchor_ensembles()
    call accuracy_ensembles(pack(chains, chains >= 8))

contains

    subroutine work_precision(chains)
        integer, intent(in) :: chains(:)
        real(wp), allocatable :: ref(:), q(:)
        type(dae_stats_t) :: stats
        type(status_t) :: status
        integer :: b, ib, ic, e, counts(9)
        real(wp) :: tol, err
        print '(a)', 'wp base control NB TOL NSTEP NACCPT NREJCT NFCN max|dphi/phi|/TOL ' // &
            'digits (against ' // trim(solvers(solver_radau5)%name) // ' at 1e-12)'
        do b = 1, size(chains)
            if (.not. reference(chains(b), ref)) cycle
            print '(a,i3,a,es9.2)', 'NB', chains(b), ': smallest |phi| at t = 1', &
                minval(abs(ref(3::3)))
            do ib = 1, size(bases)
                do ic = 1, size(controls)
                    do e = 3, 9
                        tol = 10.0_wp**(-e)
                        call chain_run(chains(b), bases(ib), controls(ic), tol, 1.0e-3_wp, .false., &
                                       q, stats, status, counts)
                        if (.not. status%ok()) then
                            print '(a)', 'failed: ' // status%text()
                            cycle
                        end if
                        err = maxval(abs(q(3::3) - ref(3::3)) / abs(ref(3::3)))
                        print '(a,1x,a,1x,a,i4,es9.1,4i7,es11.3,f6.2)', 'wp', &
                            trim(base_names(ib)), trim(control_names(ic)), chains(b), tol, &
                            counts(1:3), counts(5), err / tol, -log10(err)
                    end do
                end do
            end do
        end do
    end subroutine work_precision

    subroutine anchor_ensembles()
        integer, parameter :: members = 10
        ! the original's cost counters at TOL 1e-3: NFPROB NFCN NGCN NMULT NDEC NSOL
        integer, parameter :: anchor_cost(6) = [2080, 871, 44, 1126, 1160, 1165]
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:)
        real(wp) :: tol, mean(9)
        integer :: ic, e, m, counts(9), failed
        print '(a)', 'anchor control TOL: one run NSTEP NACCPT NREJCT NFPROB NFCN NGCN NMULT ' // &
            'NDEC NSOL; ensemble means; original'
        do ic = 1, size(controls)
            do e = 1, 4
                tol = 10.0_wp**(-(2 * e + 1))
                mean = 0.0_wp
                failed = 0
                do m = 0, members - 1
                    call chain_run(8, mexax_base_euler, controls(ic), tol, &
                                   1.0e-3_wp * (1.0_wp + 1.0e-4_wp * m), .true., q, stats, status, &
                                   counts)
                    if (.not. status%ok()) then
                        ! a failed member's counters stop short: named, and left out of the means
                        failed = failed + 1
                        print '(a,1x,a,es8.0,a,i0,a)', 'anchor', trim(control_names(ic)), tol, &
                            ': member ', m, ' failed: ' // status%text()
                        cycle
                    end if
                    if (m == 0) print '(a,1x,a,es8.0,a,9i6)', 'anchor', trim(control_names(ic)), &
                        tol, ': one run', counts
                    mean = mean + real(counts, wp)
                end do
                if (failed == members) cycle
                mean = mean / (members - failed)
                if (failed > 0) print '(a,1x,a,es8.0,a,i0,a,i0,a)', 'anchor', &
                    trim(control_names(ic)), tol, ': means over ', members - failed, ' of ', &
                    members, ' members'
                if (e == 1) then
                    print '(a,1x,a,es8.0,a,9f8.1,a,9i6)', 'anchor', trim(control_names(ic)), tol, &
                        ': means', mean, '; original', anchor(:, e), anchor_cost
                else
                    print '(a,1x,a,es8.0,a,9f8.1,a,3i6)', 'anchor', trim(control_names(ic)), tol, &
                        ': means', mean, '; original', anchor(:, e)
                end if
            end do
        end do
    end subroutine anchor_ensembles

    subroutine accuracy_ensembles(chains)
        integer, intent(in) :: chains(:)
        integer, parameter :: members = 10, tols = 7
        real(wp), allocatable :: ref(:), q(:)
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: ratio(members * tols), tol
        integer :: b, ib, ic, e, m, n, failed, counts(9)
        print '(a)', 'ensemble base control NB: runs, above 20 TOL, median and worst ' // &
            'max|dphi/phi|/TOL over H0 = 1e-3 (1 + 1e-4 m), m = 0..9, and TOL 1e-3..1e-9'
        do b = 1, size(chains)
            if (.not. reference(chains(b), ref)) cycle
            do ib = 1, size(bases)
                do ic = 1, size(controls)
                    n = 0
                    failed = 0
                    do m = 0, members - 1
                        do e = 3, 2 + tols
                            tol = 10.0_wp**(-e)
                            call chain_run(chains(b), bases(ib), controls(ic), tol, &
                                           1.0e-3_wp * (1.0_wp + 1.0e-4_wp * m), .false., q, &
                                           stats, status, counts)
                            if (.not. status%ok()) then
                                failed = failed + 1
                                cycle
                            end if
                            n = n + 1
                            ratio(n) = maxval(abs(q(3::3) - ref(3::3)) / abs(ref(3::3))) / tol
                        end do
                    end do
                    if (n == 0) cycle
                    print '(a,1x,a,1x,a,i4,a,i4,a,i3,a,2f8.2,a,i0)', 'ensemble', &
                        trim(base_names(ib)), trim(control_names(ic)), chains(b), ':', n, &
                        ' runs,', count(ratio(1:n) > 20.0_wp), ' above 20 TOL, median, worst', &
                        median(ratio(1:n)), maxval(ratio(1:n)), '; failed ', failed
                end do
            end do
        end do
    end subroutine accuracy_ensembles

    !> The median of x (sorted by insertion: the ensembles are small).
    pure real(wp) function median(x)
        real(wp), intent(in) :: x(:)
        real(wp) :: s(size(x)), v
        integer :: i, j
        s = x
        do i = 2, size(s)
            v = s(i)
            j = i - 1
            do while (j >= 1)
                if (s(j) <= v) exit
                s(j + 1) = s(j)
                j = j - 1
            end do
            s(j + 1) = v
        end do
        i = size(s)
        median = 0.5_wp * (s((i + 1) / 2) + s(i / 2 + 1))
    end function median

    !> MEXAX on the chain from its start to t = 1; `classic`: the anchor's
    !> settings (a and λ extrapolated, the classic elimination order).
    subroutine chain_run(bodies, base, control, tol, h0, classic, q, stats, status, counts)
        integer, intent(in) :: bodies, base, control
        real(wp), intent(in) :: tol, h0
        logical, intent(in) :: classic
        real(wp), allocatable, intent(out) :: q(:)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        !> NSTEP NACCPT NREJCT NFPROB NFCN NGCN NMULT NDEC NSOL
        integer, intent(out) :: counts(9)
        type(pendulum_chain_t) :: chain
        type(mexax_t) :: solver
        type(dae_options_t) :: options
        real(wp), allocatable :: v(:), lam(:)
        real(wp) :: t
        chain = new_pendulum_chain(bodies)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        call pendulum_chain_initial(chain, q, v, lam)
        solver%base = base
        solver%control = control
        options%rtol = tol
        options%atol = tol
        options%h0 = h0
        if (classic) then
            solver%consistent_accelerations = .false.
            options%classic_lu = .true.
        end if
        t = 0.0_wp
        call solver%integrate_mechanical(chain, t, q, v, 1.0_wp, options, stats, status, &
                                         lambda=lam)
        associate (n => solver%native)
            counts = [n%nstep, n%naccpt, n%nrejct, n%nfprob, n%nfcn, n%ngcn, n%nmult, n%ndec, &
                      n%nsol]
        end associate
    end subroutine chain_run

    !> radau5_reference, its failure printed.
    logical function reference(bodies, q) result(ok)
        integer, intent(in) :: bodies
        real(wp), allocatable, intent(out) :: q(:)
        type(status_t) :: status
        call radau5_reference(bodies, q, status)
        ok = status%ok()
        if (.not. ok) print '(a)', 'reference failed: ' // status%text()
    end function reference

    !> The catalogue's Radau IIA solver at rtol = atol = 1e-12 on the index-2
    !> formulation: q at t = 1.
    subroutine radau5_reference(bodies, q, status)
        integer, intent(in) :: bodies
        real(wp), allocatable, intent(out) :: q(:)
        type(status_t), intent(out) :: status
        type(pendulum_chain_t), target :: chain
        type(formulation_t) :: gen
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        real(wp), allocatable :: v(:), lam(:), y(:), yp(:)
        real(wp) :: t
        chain = new_pendulum_chain(bodies)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        call pendulum_chain_initial(chain, q, v, lam)
        gen = new_formulation(chain, formulation_index2, q, constant_mass=.true., status=status)
        if (.not. status%ok()) return
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(gen%offset(block_q) + 1:gen%last(block_q)) = q
        y(gen%offset(block_v) + 1:gen%last(block_v)) = v
        call gen%consistent_initial(0.0_wp, y, yp, status)
        if (.not. status%ok()) return
        options%rtol = 1.0e-12_wp
        options%atol = 1.0e-12_wp
        call new_solver(solvers(solver_radau5)%name, solver, status)
        if (.not. status%ok()) return
        t = 0.0_wp
        call solver%integrate_system(chain, gen, t, y, 1.0_wp, options, stats, status)
        q = y(gen%offset(block_q) + 1:gen%last(block_q))
    end subroutine radau5_reference
end program flexmbs_bench_mexax_control
