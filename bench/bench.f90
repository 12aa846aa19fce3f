!> One benchmark run: integrate a problem with a solver of the catalogue
!> (run/catalogue), planned as `flexmbs run` plans a scene, and print one
!> line of figures (counters, CPU and wall time, time per step,
!> peak memory) and the accuracy reached at t_end.
!>
!>   flexmbs-bench INTEGRATOR PROBLEM N SOLVER [MAX_STEPS] [RTOL] [REFERENCE]
!>   flexmbs-bench reference PROBLEM N FILE [RTOL]
!>   flexmbs-bench assembly hex8|hex27 NDOF
!>   flexmbs-bench ad fourbar|slidercrank
!>   flexmbs-bench sparse_lu hex NX NY NZ | sparse_lu rd1d|rd2d N
!>   flexmbs-bench --help
!>
!> Wrong or missing arguments: a message and the usage on standard error,
!> exit 2; a run that cannot be set up: its reason there, exit 1.
!>
!> INTEGRATOR: a solver of the catalogue (radau5 | ddassl | ida | mexax),
!> or NAME-p2 (maximal BDF order 2) or NAME-euler (MEXAX's half-explicit
!> Euler base).
!> PROBLEM: vdp | rd1d | rd2d | pend3 | pend2 | pendggl | pendmech (the
!> index-2 pendulum, for MEXAX's mechanical form) (N: unknowns for rd1d,
!> grid points per side for rd2d, ignored otherwise); and chain (N bars,
!> the chain of MEXAX's published test (docs/solvers.md), no scene's problem: its index-2
!> formulation; ERR over (x1, y1, φ1) at t = 1 against the original's
!> TOL 1e-11 values for N = 8, none otherwise); SOLVER: dense |
!> klu | band | auto. ERR is eq. (13) of `paper_error` at t_end with
!> atol = rtol: van der Pol against its tight reference, the pendulum
!> (φ0 = 1, t_end = 3, index 3, index 2 or GGL) over the positions against
!> the exact solution, the Brusselator against the file REFERENCE written
!> by the `reference` mode (RADAU5 at rtol = atol = RTOL, default 1e-10).
!> ERR is '-' when the run stopped early or no reference is at hand.
!> The assembly mode builds a clamped cube of the element type with about
!> NDOF free dofs and prints the time of one internal-force + tangent
!> assembly (and of the force alone), per element, the nonzeros of the
!> tangent pattern, the growth of the peak resident memory (VmHWM) over
!> building the body and assembling once, per dof, and the thread count.
!> The ad mode compares constraint_derivatives = 'analytic' and 'ad' on a
!> driven closed-loop mechanism (flexmbs_problems_mechanisms): the time of
!> one set of constraint derivatives (G, c_q, c_t, γ) and of a whole RADAU5
!> run (GGL, rtol = atol = 1e-7, one crank revolution; best of 5 batches
!> and of 15 runs, the figures least disturbed by the machine), and
!> their ratios; 'ad' differentiates the vector relations on the marker
!> frames ('ad_full', through the body coordinates too, is the verification
!> path and is timed beside them).
!> The sparse_lu mode factors A = M - J on the node graph of NX × NY × NZ
!> hex8 nodes (3 unknowns each, 27-point coupling, flexmbs_problems_node_graph;
!> M positive diagonal), or A = I - J of the Brusselator (J at its initial
!> value, N as for the integrators), with KLU (AMD and nested-dissection orderings) and MUMPS (its automatic
!> ordering): one row each with the analysis time, the factorisation time
!> (best of 3, fresh pivoting), the solve time (best of 3), the nonzeros of
!> L+U (KLU: its analysis' count) and the ordering used; first the fill ratio
!> (nnz(L)+nnz(U))/nnz(A) KLU's AMD analysis predicts and what `linear_solver
!> = 'auto'` picks from it.
!> bench/run.sh runs the grid of configurations; these are figures, not tests.
program flexmbs_bench
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, reason_max_steps
    use flexmbs_core_text, only: int_text
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_pendulum_chain, only: pendulum_chain_t, new_pendulum_chain, &
        pendulum_chain_initial, chain_anchor_t1
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t
    use flexmbs_problems_pendulum, only: pendulum_t, pendulum_reference
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_run_catalogue, only: solvers, solver_radau5, solver_choices, solver_id
    use flexmbs_run_solver_factory, only: new_solver
    use flexmbs_run_plan, only: run_plan_t, make_plan
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_ggl, &
        formulation_index2
    use flexmbs_problems_mechanisms, only: new_mechanism, mechanism_slider_crank, &
        mechanism_four_bar
    use flexmbs_problems_node_graph, only: node_graph_jacobian, node_graph_mass
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse, storage_identity
    use flexmbs_linalg_shifted_pattern, only: shifted_pattern_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_amd, klu_ordering_nd, &
        klu_ordering_name, klu_part_real
    use flexmbs_linalg_mumps, only: mumps_real_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver, predicted_fill_ratio
    !$ use omp_lib, only: omp_get_max_threads
    implicit none

    !> van der Pol, ε = 1e-6, y(2) from y(0) = (2, −0.66): RADAU5 at
    !> rtol = atol = 1e-14, the reference of test/test_radau5.f90 (which
    !> confirms it by the independent Lobatto IIIC integrator to 1e-11).
    real(wp), parameter :: vdp_reference(2) = [1.70616743754319988_wp, &
        -0.892810016551103480_wp]

    character(len=32) :: integrator_name, problem_name, solver_name, arg
    character(len=256) :: reference_file
    integer :: npar, max_steps, ios, nargs, i
    real(wp) :: rtol, t, t_end, err
    real(wp), allocatable :: y(:), y_ref(:)
    logical, allocatable :: mask(:)
    !> the run as `flexmbs run` plans it (run/plan; `target`: a mechanical
    !> problem's formulation points into it)
    type(run_plan_t), target :: plan
    class(dae_solver_t), allocatable :: solver
    type(dae_options_t) :: options
    type(dae_stats_t) :: stats
    type(status_t) :: status
    character(len=16) :: outcome
    integer :: n_row   !! unknowns reported in the row

    nargs = command_argument_count()
    do i = 1, nargs
        call get_command_argument(i, arg)
        if (arg == '--help' .or. arg == '-h') then
            call usage(output_unit)
            stop
        end if
    end do
    if (nargs == 0) call bad_arguments('no arguments')
    call get_command_argument(1, integrator_name)
    select case (integrator_name)
    case ('assembly')
        if (nargs /= 3) call bad_arguments('assembly takes hex8|hex27 NDOF')
        call run_assembly()
        stop
    case ('sparse_lu')
        call run_sparse_lu()
        stop
    case ('ad')
        if (nargs /= 2) call bad_arguments('ad takes fourbar|slidercrank')
        call run_ad()
        stop
    case ('reference')
        if (nargs < 4 .or. nargs > 5) call bad_arguments('reference takes PROBLEM N FILE &
            &[RTOL]')
    case default
        if (nargs < 4 .or. nargs > 7) call bad_arguments('a run takes INTEGRATOR PROBLEM N &
            &SOLVER [MAX_STEPS] [RTOL] [REFERENCE]')
    end select
    call get_command_argument(2, problem_name)
    npar = whole_argument(3, 'N')
    call get_command_argument(4, solver_name)
    max_steps = 100000
    rtol = 1.0e-6_wp
    reference_file = ''
    if (integrator_name == 'reference') then
        reference_file = solver_name
        solver_name = 'auto'
        rtol = 1.0e-10_wp
        max_steps = 10000000
        if (nargs >= 5) rtol = tolerance_argument(5, 'RTOL')
    else
        if (nargs >= 5) max_steps = whole_argument(5, 'MAX_STEPS')
        if (nargs >= 6) rtol = tolerance_argument(6, 'RTOL')
        if (nargs >= 7) call get_command_argument(7, reference_file)
    end if

    if (problem_name == 'chain') then
        call run_chain()
        stop
    end if
    call make_plan_for(trim(problem_name))
    n_row = plan%problem%n
    y = plan%y0
    t = 0.0_wp
    call plan%integrate(t, y, t_end, stats, status)
    call set_outcome()
    if (integrator_name == 'reference') then
        call write_reference()
        stop
    end if
    err = ieee_value(err, ieee_quiet_nan)
    if (outcome == 'done' .and. allocated(y_ref)) then
        if (allocated(mask)) then
            err = paper_error(y, y_ref, rtol, rtol, mask)
        else
            err = paper_error(y, y_ref, rtol, rtol)
        end if
    end if
    call print_row(outcome)

contains

    !> The forms of the command line, on `unit`.
    subroutine usage(unit)
        integer, intent(in) :: unit
        write (unit, '(a)') 'usage: flexmbs-bench INTEGRATOR PROBLEM N SOLVER [MAX_STEPS] [RTOL] &
            &[REFERENCE]', &
            '       flexmbs-bench reference PROBLEM N FILE [RTOL]', &
            '       flexmbs-bench assembly hex8|hex27 NDOF', &
            '       flexmbs-bench ad fourbar|slidercrank', &
            '       flexmbs-bench sparse_lu hex NX NY NZ | sparse_lu rd1d|rd2d N', &
            '       flexmbs-bench --help', &
            'INTEGRATOR: ' // solver_choices // ', or NAME-p2 (maximal BDF order 2) or &
            &NAME-euler', &
            '  (the half-explicit Euler base step)', &
            'PROBLEM: vdp|rd1d|rd2d|pend3|pend2|pendggl|pendmech|chain; N: unknowns for rd1d,', &
            '  grid points per side for rd2d, bars for chain, ignored otherwise', &
            'SOLVER: the linear solver, dense|klu|band|auto', &
            'MAX_STEPS: default 100000; RTOL (= atol): default 1e-6, 1e-10 for reference;', &
            '  REFERENCE: a file that the reference form wrote', &
            'One row of figures on standard output (bench/bench.f90 says which);', &
            'bench/run.sh runs the grid of configurations.'
    end subroutine usage

    !> A wrong command line: `message` and the usage on standard error,
    !> exit 2 (quietly: no STOP line, no backtrace).
    subroutine bad_arguments(message)
        character(len=*), intent(in) :: message
        write (error_unit, '(a)') 'flexmbs-bench: ' // message
        call usage(error_unit)
        stop 2, quiet=.true.
    end subroutine bad_arguments

    !> A run that cannot be set up: why, on standard error, exit 1.
    subroutine give_up(message)
        character(len=*), intent(in) :: message
        write (error_unit, '(a)') 'flexmbs-bench: ' // message
        stop 1, quiet=.true.
    end subroutine give_up

    !> Argument `k`, a whole number >= 1 (`what` names it in the message).
    integer function whole_argument(k, what) result(value)
        integer, intent(in) :: k
        character(len=*), intent(in) :: what
        call get_command_argument(k, arg)
        read (arg, *, iostat=ios) value
        if (ios /= 0 .or. verify(trim(arg), '+0123456789') /= 0 .or. value < 1) &
            call bad_arguments(what // ' = ''' // trim(arg) // ''': needs a whole number >= 1')
    end function whole_argument

    !> Argument `k`, a positive number (`what` names it in the message).
    real(wp) function tolerance_argument(k, what) result(value)
        integer, intent(in) :: k
        character(len=*), intent(in) :: what
        call get_command_argument(k, arg)
        read (arg, *, iostat=ios) value
        if (ios /= 0 .or. len_trim(arg) == 0) then
            call bad_arguments(what // ' = ''' // trim(arg) // ''': needs a number')
        else if (.not. value > 0.0_wp) then
            call bad_arguments(what // ' = ''' // trim(arg) // ''': needs a number > 0')
        end if
    end function tolerance_argument

    !> The run's outcome from its status: done, capped (max_steps) or
    !> failed (the reason to standard error).
    subroutine set_outcome()
        if (status%ok()) then
            outcome = 'done'
        else if (status%reason == reason_max_steps) then
            outcome = 'capped'
        else
            outcome = 'failed'
            write (0, '(a)') trim(integrator_name) // ' ' // trim(problem_name) // ': ' // &
                status%text()
        end if
    end subroutine set_outcome

    !> INTEGRATOR as a catalogue solver and its settings (&solver entries):
    !> NAME, NAME-p2 (p_max = 2), NAME-euler (the half-explicit Euler basic
    !> step); 'reference' is RADAU5.
    subroutine solver_of(integrator, name, settings)
        character(len=*), intent(in) :: integrator
        character(len=:), allocatable, intent(out) :: name, settings
        integer :: dash
        settings = ''
        if (integrator == 'reference') then
            name = trim(solvers(solver_radau5)%name)
            return
        end if
        dash = index(integrator, '-')
        name = integrator
        if (dash > 0) name = integrator(1:dash - 1)
        if (solver_id(name) == 0) call bad_arguments('unknown integrator ''' // integrator // &
            '''')
        if (dash == 0) return
        select case (integrator(dash + 1:))
        case ('p2')
            settings = ', pmax = 2'
        case ('euler')
            settings = ', mexax_base = ''euler'''
        case default
            call bad_arguments('unknown variant ''' // integrator(dash:) // '''')
        end select
    end subroutine solver_of

    !> The run as a scene (problem, solver, tolerances, linear solver) and
    !> its plan, as `flexmbs run` makes it; t_end, and the reference at
    !> t_end when one is known. A combination the scene checks refuse
    !> (IDA or MEXAX with the band LU) is a row 'unsupported'.
    subroutine make_plan_for(name)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: simulation, solver, settings, text
        character(len=*), parameter :: nl = new_line('a')
        type(scene_input_t) :: scene
        type(status_t) :: st
        character(len=32) :: rtol_text
        write (rtol_text, '(es24.16e3)') rtol
        call solver_of(trim(integrator_name), solver, settings)
        select case (name)
        case ('vdp')
            simulation = 'problem = ''van_der_pol'', t_end = 2, vdp_eps = 1e-6, &
                &vdp_y1 = 2, vdp_y2 = -0.66'
            settings = settings // ', h0 = 1e-6'
            y_ref = vdp_reference
        case ('rd1d')
            simulation = 'problem = ''brusselator_1d'', t_end = 10, npoints = ' // &
                int_text(npar / 2)
        case ('rd2d')
            simulation = 'problem = ''brusselator_2d'', t_end = 1, npoints = ' // int_text(npar)
        case ('pend3', 'pend2', 'pendggl', 'pendmech')
            simulation = 'problem = ''pendulum'', t_end = 3, pendulum_angle = 1, &
                &pendulum_formulation = ''' // merge('index3', 'index2', name == 'pend3') // ''''
            if (name == 'pendggl') simulation = 'problem = ''pendulum'', t_end = 3, &
                &pendulum_angle = 1, pendulum_formulation = ''ggl'''
        case default
            call bad_arguments('unknown problem ''' // name // '''')
        end select
        text = '&simulation ' // simulation // ' /' // nl // '&solver name = ''' // solver // &
            ''', rtol = ' // trim(rtol_text) // ', atol = ' // trim(rtol_text) // &
            ', max_steps = ' // int_text(max_steps) // ', linear_solver = ''' // &
            trim(solver_name) // '''' // settings // ' /' // nl // &
            '&output file = ''none'', n_output = 2, progress = .false. /' // nl
        call parse_scene(text, 'bench.nml', scene, status)
        if (status%ok()) call make_plan(scene, plan, status)
        if (.not. status%ok()) then
            write (0, '(a)') trim(integrator_name) // ' ' // name // ': ' // status%text()
            t = 0.0_wp
            n_row = npar
            call print_row('unsupported')
            stop
        end if
        t_end = scene%t_end
        select type (problem => plan%problem)
        type is (reaction_diffusion_t)
            if (len_trim(reference_file) > 0 .and. integrator_name /= 'reference') &
                call read_reference()
        type is (pendulum_t)
            allocate (y_ref(problem%n), mask(problem%n))
            call pendulum_reference(problem, t_end, y_ref, st)
            if (.not. st%ok()) deallocate (y_ref)
            ! Positions only, as in test/: λ and μ are index-2/3 variables.
            mask = .false.
            mask(1:2) = .true.
        end select
    end subroutine make_plan_for

    !> The chain of N bars (MEXAX's published test, docs/solvers.md; no scene offers it) to t = 1,
    !> through the common interface: the catalogue's solver integrates the
    !> mechanical problem with its index-2 formulation (MEXAX the mechanical
    !> form itself); ERR over (x1, y1, φ1) against the original's values for
    !> N = 8.
    subroutine run_chain()
        type(pendulum_chain_t), target :: chain
        type(formulation_t) :: formulation
        real(wp), allocatable :: q(:), v(:), lam(:)
        character(len=:), allocatable :: name, settings
        type(status_t) :: st
        call solver_of(trim(integrator_name), name, settings)
        call new_solver(name, solver, st)
        if (.not. st%ok()) call give_up(st%text())
        select type (solver)
        type is (mexax_t)
            if (index(settings, 'euler') > 0) solver%base = mexax_base_euler
        end select
        chain = new_pendulum_chain(npar)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        call pendulum_chain_initial(chain, q, v, lam)
        formulation = new_formulation(chain, formulation_index2, q, constant_mass=.true., &
            status=st, sparse=solver_name /= 'dense')
        if (.not. st%ok()) call give_up('chain: ' // st%text())
        y = [q, v, lam]
        t_end = 1.0_wp
        if (npar == 8) y_ref = chain_anchor_t1
        n_row = size(y)
        options%rtol = rtol
        options%atol = rtol
        options%max_steps = max_steps
        options%linear_solver = solver_name
        t = 0.0_wp
        call solver%integrate(chain, formulation, t, y, t_end, options, stats, status)
        call set_outcome()
        err = ieee_value(err, ieee_quiet_nan)
        if (outcome == 'done' .and. allocated(y_ref)) err = paper_error(y(1:size(y_ref)), &
            y_ref, rtol, rtol)
        call print_row(outcome)
    end subroutine run_chain

    !> y(t_end) of the reference run, one value a line after n.
    subroutine write_reference()
        integer :: unit, i
        if (outcome /= 'done') call give_up('reference run did not reach t_end; no file written')
        open (newunit=unit, file=trim(reference_file), action='write', status='replace')
        write (unit, '(i0)') plan%problem%n
        write (unit, '(es25.17e3)') (y(i), i=1, size(y))
        close (unit)
        write (*, '(a,1x,a,1x,i0,a,es8.1,a,i0,a,es10.3,a)') 'reference', trim(problem_name), &
            plan%problem%n, ': ' // trim(solvers(solver_radau5)%name) // ' rtol = atol =', &
            rtol, ', NST ', stats%nst, ', CPU ', &
            stats%cpu, ' s'
    end subroutine write_reference

    !> Read the reference file if it exists and fits; otherwise no reference.
    subroutine read_reference()
        integer :: unit, n_file, i
        open (newunit=unit, file=trim(reference_file), action='read', status='old', iostat=ios)
        if (ios /= 0) return
        read (unit, *, iostat=ios) n_file
        if (ios == 0 .and. n_file == plan%problem%n) then
            allocate (y_ref(n_file))
            read (unit, *, iostat=ios) (y_ref(i), i=1, n_file)
            if (ios /= 0) deallocate (y_ref)
        end if
        close (unit)
    end subroutine read_reference

    !> integrator problem n solver outcome t_reached NST NAC NFE NJE NDEC CPU
    !> WALL CPU/step peakMiB ERR
    subroutine print_row(what)
        character(len=*), intent(in) :: what
        character(len=12) :: err_text
        err_text = '-'
        if (what == 'done' .and. allocated(y_ref)) then
            if (.not. ieee_is_nan(err)) write (err_text, '(es10.3)') err
        end if
        write (*, '(2(a,1x),i0,2(1x,a),1x,es10.3,5(1x,i0),3(1x,es10.3),1x,f0.1,1x,a)') &
            trim(integrator_name), trim(problem_name), n_row, trim(solver_name), &
            trim(what), t, stats%nst, stats%nac, stats%nfe, stats%nje, stats%ndec, &
            stats%cpu, stats%wall, stats%cpu / max(stats%nst, 1), peak_memory_mb(), &
            trim(adjustl(err_text))
    end subroutine print_row

    !> `assembly KIND NDOF`: one row of assembly figures (module header).
    subroutine run_assembly()
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: body
        integer, allocatable :: fixed(:)
        real(wp), allocatable :: q(:), v(:), k(:)
        real(wp) :: mem0, mem1, t_tangent, t_force
        integer :: kind, m, p, ndof, repeats, threads
        call get_command_argument(2, arg)
        if (arg /= 'hex8' .and. arg /= 'hex27') call bad_arguments('assembly ' // trim(arg) // &
            ': use hex8 or hex27')
        kind = merge(hex8, hex27, arg == 'hex8')
        ndof = whole_argument(3, 'NDOF')
        ! m³ elements, (p m + 1)² (p m) free nodes with the xmin face clamped
        p = merge(1, 2, kind == hex8)
        m = max(1, nint((ndof / 3.0_wp)**(1.0_wp / 3) / p))
        mem0 = peak_memory_mb()
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 1000.0_wp, status)
        if (status%ok()) call box_mesh(mesh, kind, [m, m, m], [1.0_wp, 1.0_wp, 1.0_wp], status)
        if (status%ok()) call mesh%node_set('xmin', fixed, status)
        if (status%ok()) call new_flexible_body(body, mesh, [mat], fixed, status)
        if (.not. status%ok()) call give_up('assembly: ' // status%text())
        q = body%free_positions()
        allocate (v(body%nv), source=0.01_wp, k(body%nv))
        q = q * 1.01_wp   ! a uniform stretch: every element works
        call body%tangents(q, v, k, status)
        mem1 = peak_memory_mb()
        ! repeat to about 0.5 s of assembly (at least twice)
        t_tangent = seconds_per_call(body, q, v, k, .true., 2)
        repeats = max(2, nint(0.5_wp / max(t_tangent, 1.0e-6_wp)))
        t_tangent = seconds_per_call(body, q, v, k, .true., repeats)
        t_force = seconds_per_call(body, q, v, k, .false., repeats)
        threads = 1
        !$ threads = omp_get_max_threads()
        write (*, '(a,1x,a,4(1x,i0),4(1x,es10.3),1x,f0.1,1x,i0)') 'assembly', &
            merge('hex8 ', 'hex27', kind == hex8), body%nv, mesh%element_count(), &
            body%stiffness%nnz, repeats, t_tangent, 1.0e6_wp * t_tangent / mesh%element_count(), &
            t_force, 1.0e6_wp * t_force / mesh%element_count(), &
            (mem1 - mem0) * 1048576.0_wp / body%nv, threads

    end subroutine run_assembly

    !> `sparse_lu hex NX NY NZ | rd1d N | rd2d N`: KLU (AMD, ND) and MUMPS on
    !> A = M - J of a node graph or of the Brusselator.
    subroutine run_sparse_lu()
        integer, parameter :: dofs = 3, repeats = 3
        type(matrix_t) :: jac, mass
        type(shifted_pattern_t) :: pattern
        class(linear_solver_t), allocatable :: auto
        real(wp), allocatable :: values(:)
        real(wp) :: fill
        integer :: nx, ny, nz, n, m
        character(len=24) :: mesh
        call get_command_argument(2, problem_name)
        if (.not. (problem_name == 'hex' .and. nargs == 5 .or. (problem_name == 'rd1d' .or. &
            problem_name == 'rd2d') .and. nargs == 3)) call bad_arguments('sparse_lu takes &
            &hex NX NY NZ, rd1d N or rd2d N')
        if (problem_name == 'hex') then
            nx = whole_argument(3, 'NX')
            ny = whole_argument(4, 'NY')
            nz = whole_argument(5, 'NZ')
            write (mesh, '("hex",i0,"x",i0,"x",i0)') nx, ny, nz
            call node_graph_jacobian(nx, ny, nz, dofs, jac, status)
            if (status%ok()) call node_graph_mass(jac%n, mass, status)
        else
            nx = whole_argument(3, 'N')
            write (mesh, '(a,"-",i0)') trim(problem_name), nx
            ! the Brusselator as a scene makes it, at its initial value
            integrator_name = 'reference'
            solver_name = 'klu'
            npar = nx
            max_steps = 1
            rtol = 1.0e-6_wp
            call make_plan_for(trim(problem_name))
            jac%storage = storage_sparse
            jac%n = plan%problem%n
            call plan%problem%jacobian_pattern(jac%csc, status)
            if (status%ok()) call plan%problem%jacobian_sparse(0.0_wp, plan%y0, &
                jac%csc%values, status)
            mass%storage = storage_identity
            mass%n = plan%problem%n
        end if
        n = jac%n
        if (status%ok()) call pattern%build(mass, jac, 'sparse_lu', status)
        if (status%ok()) call predicted_fill_ratio(jac, fill, status, mass)
        if (status%ok()) call new_linear_solver('auto', n, storage_sparse, auto, status, &
            mass=mass, jac=jac)
        if (.not. status%ok()) call give_up('sparse_lu: ' // status%text())
        allocate (values(pattern%nonzeros()))
        call pattern%gather(mass, jac)
        call pattern%real_values(1.0_wp, values)
        write (*, '(a,1x,i0,1x,i0,a,f0.1,a)') trim(mesh), n, pattern%nonzeros(), &
            ' predicted_fill(AMD) = ', fill, ' auto -> ' // auto%name()
        ! m = 1, 2: KLU with AMD and ND; m = 3: MUMPS with its automatic ordering
        do m = 1, 3
            call time_sparse_lu(m, trim(mesh), n, pattern, values, repeats)
        end do
    end subroutine run_sparse_lu

    !> One row of `sparse_lu`: KLU with AMD (m = 1) or ND (m = 2), MUMPS (m = 3).
    subroutine time_sparse_lu(m, mesh, n, pattern, values, repeats)
        integer, intent(in) :: m, n, repeats
        character(len=*), intent(in) :: mesh
        type(shifted_pattern_t), intent(in) :: pattern
        real(wp), intent(in) :: values(:)
        real(wp), parameter :: max_seconds = 10.0_wp
        type(klu_factor_t) :: klu
        type(mumps_real_t) :: mumps
        real(wp) :: t_analyse, t_factor, t_refactor, t_solve, lnz, unz, x(n)
        character(len=:), allocatable :: solver, ordering
        integer(8) :: c0, c1, rate
        integer :: r
        call system_clock(c0, rate)
        if (m < 3) then
            call klu%analyse(n, pattern%column_pointers(), pattern%row_indices(), status, &
                merge(klu_ordering_amd, klu_ordering_nd, m == 1))
        else
            call mumps%analyse(n, pattern%column_pointers(), pattern%row_indices(), status)
        end if
        call system_clock(c1)
        t_analyse = real(c1 - c0, wp) / rate
        t_factor = huge(1.0_wp)
        t_refactor = huge(1.0_wp)
        t_solve = huge(1.0_wp)
        do r = 1, repeats
            if (.not. status%ok()) exit
            call system_clock(c0)
            if (m < 3) then
                call klu%factor(values, status)
            else
                call mumps%factor(values, status)
            end if
            call system_clock(c1)
            t_factor = min(t_factor, real(c1 - c0, wp) / rate)
            ! what an integrator pays for new values: KLU's refactor keeps the
            ! pivot order, MUMPS factors numerically again (JOB = 2) each time
            call system_clock(c0)
            if (m < 3 .and. status%ok()) call klu%refactor(values, status)
            if (m == 3 .and. status%ok()) call mumps%factor(values, status)
            call system_clock(c1)
            t_refactor = min(t_refactor, real(c1 - c0, wp) / rate)
            x = 1.0_wp
            call system_clock(c0)
            if (m < 3 .and. status%ok()) call klu%solve(x, status)
            if (m == 3 .and. status%ok()) call mumps%solve(x, status)
            call system_clock(c1)
            t_solve = min(t_solve, real(c1 - c0, wp) / rate)
            if (t_factor > max_seconds) exit ! one factorisation of minutes says enough
        end do
        if (m < 3) then
            solver = 'klu'
            ordering = klu_ordering_name(klu%ordering_used())
            lnz = real(klu%factor_nonzeros(klu_part_real), wp)
            unz = 0.0_wp
        else
            solver = 'mumps'
            ordering = mumps%ordering_used()
            lnz = real(mumps%factor_nonzeros(), wp)
            unz = 0.0_wp
        end if
        if (.not. status%ok()) then
            write (*, '(a)') mesh // ' ' // solver // ' ' // ordering // ' failed: ' // &
                status%text()
            return
        end if
        write (*, '(a,1x,i0,1x,a,1x,a,4(1x,es9.2),1x,es9.2,1x,f0.1)') mesh, n, solver, &
            ordering, t_analyse, t_factor, t_refactor, t_solve, lnz + unz, &
            (lnz + unz) / real(pattern%nonzeros(), wp)
    end subroutine time_sparse_lu

    !> `ad MECHANISM`: derivative and whole-run cost, 'analytic' against 'ad'.
    subroutine run_ad()
        character(len=8), parameter :: modes(3) = ['analytic', 'ad      ', 'ad_full ']
        type(mbs_system_t), target :: sys
        type(formulation_t) :: dae
        class(dae_solver_t), allocatable :: radau5
        real(wp) :: q0(21), v0(18), t_deriv(3), t_run(3), tt
        real(wp), allocatable :: c(:), g(:, :), cq(:, :), ct(:), gam(:), y(:), yp(:), y0(:)
        integer :: mech, m, i, calls, runs, batch
        integer(8) :: c0, c1, rate
        call get_command_argument(2, problem_name)
        if (problem_name /= 'fourbar' .and. problem_name /= 'slidercrank') &
            call bad_arguments('ad ' // trim(problem_name) // ': use fourbar or slidercrank')
        mech = merge(mechanism_four_bar, mechanism_slider_crank, problem_name == 'fourbar')
        call new_solver(solvers(solver_radau5)%name, radau5, status)
        do m = 1, 3
            call new_mechanism(mech, sys, q0, status, trim(modes(m)))
            if (.not. status%ok()) call give_up('ad: ' // status%text())
            allocate (c(sys%nc), g(sys%nc, sys%nv), cq(sys%nc, sys%nq), ct(sys%nc), gam(sys%nc))
            v0 = 0.1_wp
            ! best of 5 batches (the least disturbed by the rest of the machine)
            calls = 4000
            t_deriv(m) = huge(1.0_wp)
            do batch = 1, 5
                call system_clock(c0, rate)
                do i = 1, calls
                    call sys%constraint_jacobian(0.1_wp, q0, g, status)
                    call sys%constraint_position_jacobian(0.1_wp, q0, cq, status)
                    call sys%constraint_time_derivative(0.1_wp, q0, ct, status)
                    call sys%constraint_curvature(0.1_wp, q0, v0, gam, status)
                end do
                call system_clock(c1)
                t_deriv(m) = min(t_deriv(m), real(c1 - c0, wp) / real(rate, wp) / calls)
            end do
            dae = new_formulation(sys, formulation_ggl, q0, status=status)
            allocate (y0(dae%n), yp(dae%n), source=0.0_wp)
            y0(1:21) = q0
            call dae%consistent_initial(0.0_wp, y0, yp, status)
            options%rtol = 1.0e-7_wp
            options%atol = 1.0e-7_wp
            runs = 15
            t_run(m) = huge(1.0_wp)
            do i = 1, runs
                y = y0
                tt = 0.0_wp
                call system_clock(c0)
                call radau5%integrate(dae, tt, y, 1.0_wp, options, stats, status)
                call system_clock(c1)
                t_run(m) = min(t_run(m), real(c1 - c0, wp) / real(rate, wp))
            end do
            write (*, '(a,1x,a,1x,a,1x,a,es10.3,a,es10.3,a,3(1x,i0),1x,a)') 'ad', &
                trim(problem_name), trim(modes(m)), 'derivatives[s]', t_deriv(m), &
                ' run[s]', t_run(m), ' NST NFE NJE', stats%nst, stats%nfe, stats%nje, &
                trim(merge('ok    ', 'failed', status%ok()))
            deallocate (c, g, cq, ct, gam, y0, yp)
        end do
        write (*, '(a,1x,a,a,f6.2,a,f6.2)') 'ad', trim(problem_name), &
            ' ratio ad/analytic: derivatives', t_deriv(2) / t_deriv(1), ', whole run', &
            t_run(2) / t_run(1)
        write (*, '(a,1x,a,a,f6.2,a,f6.2)') 'ad', trim(problem_name), &
            ' ratio ad_full/analytic: derivatives', t_deriv(3) / t_deriv(1), ', whole run', &
            t_run(3) / t_run(1)
    end subroutine run_ad

    !> Wall seconds per assembly of `body` (with tangents or the force alone).
    real(wp) function seconds_per_call(body, q, v, k, tangents, n)
        type(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(inout) :: k(:)
        logical, intent(in) :: tangents
        integer, intent(in) :: n
        integer(8) :: c0, c1, rate
        integer :: j
        call system_clock(c0, rate)
        do j = 1, n
            if (tangents) then
                call body%tangents(q, v, k, status)
            else
                call body%internal_forces(q, v, k, status)
            end if
        end do
        call system_clock(c1)
        seconds_per_call = real(c1 - c0, wp) / real(rate, wp) / n
    end function seconds_per_call

    !> Peak resident set size (VmHWM) of this process in MiB, Linux only.
    real(wp) function peak_memory_mb()
        character(len=256) :: line
        integer :: unit
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
