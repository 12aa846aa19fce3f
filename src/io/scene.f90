!> From a validated scene to a finished run: the problem and solver the
!> scene names, its options, the output sinks, and the run itself.
!>
!> Everything that can be checked is checked before any output file is
!> created, so bad input never leaves a half-written file behind.
module flexmbs_io_scene
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted, status_signal
    use flexmbs_core_signals, only: signal_pending, caught_signal, signal_name
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_resources, only: physical_memory, free_space, bytes_text
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_midpoint, mexax_base_euler
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_problems_van_der_pol, only: new_van_der_pol
    use flexmbs_problems_robertson, only: robertson_t, new_robertson, robertson_initial
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_index1, pendulum_index2, pendulum_index3, pendulum_ggl, &
        new_pendulum_mechanical
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_index3, formulation_ggl
    use flexmbs_io_namelist, only: scene_input_t, scene_dae_options, controller_code
    use flexmbs_io_multibody_input, only: build_multibody
    use flexmbs_io_assembly_check, only: check_assembly
    use flexmbs_io_monitor_sink, only: monitor_sink_t
    use flexmbs_io_chain_input, only: build_rigid_chain
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_io_body_input, only: build_flexible_body, body_energies
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_progress, only: progress_t, new_progress
    use flexmbs_io_multi_sink, only: multi_sink_t
    use flexmbs_io_signal_sink, only: signal_sink_t
    use flexmbs_io_table, only: new_stats_row, write_table
    use flexmbs_io_vtk_sink, only: vtk_sink_t
    use flexmbs_io_output_files, only: named_path_t, named_path, check_output_paths, &
        output_hdf5, output_vtk, output_table
    implicit none
    private

    !> A named slice of y written as its own HDF5 dataset (/q, /v, /lambda).
    type, public :: block_spec_t
        character(len=:), allocatable :: name
        integer :: first = 0, last = 0
    end type block_spec_t

    !> What a run produced, successful or not.
    type, public :: run_result_t
        real(wp) :: t = 0.0_wp                !! last time reached
        real(wp), allocatable :: y(:)         !! state there
        type(dae_stats_t) :: stats
        character(len=:), allocatable :: solver_name
        logical :: hdf5_written = .false.     !! an HDF5 file was created (and kept)
        !> A flexible body: strain, kinetic and total energy (with the
        !> potential of gravity and loads) at the start and at the end [J].
        logical :: has_energy = .false.
        real(wp) :: energy_start(3) = 0.0_wp, energy_end(3) = 0.0_wp
        !> A formulated mechanical scene: ‖g‖∞ and ‖G v + g_I‖∞ at the end
        !> (the whole history is /monitor in the HDF5 file), constraint rows.
        logical :: has_drift = .false.
        real(wp) :: drift_end(2) = 0.0_wp
        integer :: constraints = 0
        !> a multibody scene: how far the initial assembly moved each body
        character(len=:), allocatable :: assembly
        !> the positions in y (block 'q'), all of y when there is none
        integer :: q_first = 0, q_last = 0
    end type run_result_t

    public :: build_problem, build_solver, scene_stab, run_scene

contains

    !> The problem the scene names, its initial value and its named blocks.
    !> Small problems report a CSC Jacobian only when KLU is asked for; the
    !> Brusselator reports CSC unless the dense solver is forced.
    !> A mechanical scene (pendulum with MEXAX, flexible body) also returns
    !> its mechanical problem in `mechanical`, which the formulation in
    !> `problem` points to: it must stay in place while `problem` is used.
    !> Its y = (q, v, λ) is the layout MEXAX integrates.
    subroutine build_problem(scene, problem, y0, blocks, status, mechanical, assembly)
        type(scene_input_t), intent(in) :: scene
        class(dae_problem_t), allocatable, intent(out) :: problem
        real(wp), allocatable, intent(out) :: y0(:)
        type(block_spec_t), allocatable, intent(out) :: blocks(:)
        type(status_t), intent(out) :: status
        class(mechanical_problem_t), allocatable, target, intent(inout), optional :: mechanical
        !> a multibody scene: how far the initial assembly moved each body
        character(len=:), allocatable, intent(out), optional :: assembly
        character(len=:), allocatable :: labels(:), moves
        type(robertson_t) :: robertson
        type(pendulum_t) :: pendulum
        type(reaction_diffusion_t) :: bruss
        type(formulation_t) :: formulation
        real(wp), allocatable :: q0(:), v0(:), yp0(:)
        integer :: nq
        logical :: klu, massless
        klu = scene%linear_solver == 'klu' .or. scene%linear_solver == 'mumps'
        allocate (blocks(0))
        if (present(mechanical)) then
            if (allocated(mechanical)) deallocate (mechanical)
        end if
        select case (trim(scene%problem))
        case ('flexible_body', 'multibody', 'rigid_chain')
            if (.not. present(mechanical)) then
                call status%set(status_bad_input, scene%path // ': &simulation: problem = ''' &
                    // trim(scene%problem) // ''': build_problem needs its `mechanical` argument')
                return
            end if
        end select
        select case (trim(scene%problem))
        case ('van_der_pol')
            allocate (problem, source=new_van_der_pol(scene%vdp_eps, sparse=klu))
            y0 = [scene%vdp_y1, scene%vdp_y2]
        case ('robertson')
            robertson = new_robertson(sparse=klu, sparse_mass=klu)
            allocate (y0(robertson%n))
            call robertson_initial(robertson, y0)
            allocate (problem, source=robertson)
        case ('pendulum')
            ! MEXAX takes the mechanical form; its state y = (q, v, λ) has the
            ! layout and initial values of the index-2 formulation.
            pendulum = new_pendulum(merge(pendulum_index2, &
                formulation_code(scene%pendulum_formulation), scene%solver_name == 'mexax'), &
                scene%pendulum_angle, mass=scene%pendulum_mass, length=scene%pendulum_length, &
                gravity=scene%gravity, sparse=klu, sparse_mass=klu, &
                projection=scene%pendulum_projection, status=status)
            if (.not. status%ok()) then
                status%message = scene%path // ': &simulation: ' // status%message
                return
            end if
            allocate (y0(pendulum%n))
            call pendulum_initial(pendulum, y0)
            ! y = (x, y, u, v, λ[, μ])
            call append_block(blocks, 'q', 1, 2)
            call append_block(blocks, 'v', 3, 4)
            call append_block(blocks, 'lambda', 5, 5)
            allocate (problem, source=pendulum)
            if (scene%solver_name == 'mexax' .and. present(mechanical)) then
                allocate (mechanical, source=new_pendulum_mechanical(mass=scene%pendulum_mass, &
                    length=scene%pendulum_length, gravity=scene%gravity, status=status))
            end if
        case ('flexible_body')
            allocate (flexible_body_t :: mechanical)
            select type (body => mechanical)
            type is (flexible_body_t)
                call build_flexible_body(scene, body, q0, v0, status)
            end select
            if (.not. status%ok()) return
            call check_dense_size(scene, mechanical, status)
            if (.not. status%ok()) return
            ! M is constant in absolute nodal coordinates: y = (q, v[, λ]).
            formulation = new_formulation(mechanical, &
                mechanical_formulation(scene%body%formulation), q0, constant_mass=.true., &
                status=status, sparse=scene%linear_solver /= 'dense')
            if (.not. status%ok()) then
                status%message = scene%path // ': &flexible_body: ' // status%message
                return
            end if
            nq = size(q0)
            allocate (y0(formulation%n), source=0.0_wp)
            y0(1:nq) = q0
            y0(nq + 1:2 * nq) = v0
            call append_block(blocks, 'q', 1, nq)
            call append_block(blocks, 'v', nq + 1, 2 * nq)
            allocate (problem, source=formulation)
        case ('multibody')
            allocate (mbs_system_t :: mechanical)
            massless = .false.
            select type (sys => mechanical)
            type is (mbs_system_t)
                call build_multibody(scene, sys, q0, v0, status, labels)
                massless = size(sys%frames) > 0
            end select
            if (.not. status%ok()) return
            call check_dense_size(scene, mechanical, status)
            if (.not. status%ok()) return
            ! Rigid and flexible bodies have a constant M (body-fixed ω'):
            ! y = (q, v, λ[, μ]); a chain's M(q) and the zero M of node frames
            ! need the acceleration layout y = (q, v, a, λ[, μ]), where the
            ! constraints determine a through [M Gᵀ; G 0]. MEXAX integrates
            ! y = (q, v, λ) (index 2).
            formulation = new_formulation(mechanical, merge(formulation_index2, &
                mechanical_formulation(scene%multibody%formulation), &
                scene%solver_name == 'mexax'), q0, constant_mass=(size(scene%chain) == 0 &
                .and. .not. massless) .or. scene%solver_name == 'mexax', &
                projection=scene%multibody%projection, status=status, &
                sparse=scene%linear_solver /= 'dense')
            if (.not. status%ok()) then
                status%message = scene%path // ': &multibody: ' // status%message
                return
            end if
            allocate (y0(formulation%n), yp0(formulation%n), source=0.0_wp)
            y0(formulation%oq + 1:formulation%oq + formulation%nq) = q0
            y0(formulation%ov + 1:formulation%ov + formulation%nv) = v0
            call formulation%consistent_initial(scene%t_start, y0, yp0, status)
            if (.not. status%ok()) then
                call status%set(status_bad_input, scene%path // ': no consistent initial &
                    &state (the joints cannot be assembled from the given positions and &
                    &velocities): ' // status%text())
                return
            end if
            select type (sys => mechanical)
            type is (mbs_system_t)
                call check_assembly(scene, sys, labels, scene%t_start, q0, &
                    y0(formulation%oq + 1:formulation%oq + formulation%nq), moves, status)
                if (present(assembly)) assembly = moves
            end select
            if (.not. status%ok()) return
            call append_block(blocks, 'q', formulation%oq + 1, formulation%oq + formulation%nq)
            call append_block(blocks, 'v', formulation%ov + 1, formulation%ov + formulation%nv)
            if (formulation%nc > 0) call append_block(blocks, 'lambda', formulation%ol + 1, &
                formulation%ol + formulation%nc)
            allocate (problem, source=formulation)
        case ('rigid_chain')
            allocate (rigid_chain_t :: mechanical)
            select type (chain => mechanical)
            type is (rigid_chain_t)
                call build_rigid_chain(scene, chain, q0, v0, status)
            end select
            if (.not. status%ok()) return
            ! M(q) varies: the acceleration layout y = (q, v, a) (nc = 0). MEXAX
            ! integrates y = (q, v); its formulation only gives that layout.
            formulation = new_formulation(mechanical, merge(formulation_index2, &
                mechanical_formulation(scene%multibody%formulation), &
                scene%solver_name == 'mexax'), q0, &
                constant_mass=scene%solver_name == 'mexax', status=status)
            if (.not. status%ok()) then
                status%message = scene%path // ': &rigid_chain: ' // status%message
                return
            end if
            allocate (y0(formulation%n), yp0(formulation%n), source=0.0_wp)
            y0(formulation%oq + 1:formulation%oq + formulation%nq) = q0
            y0(formulation%ov + 1:formulation%ov + formulation%nv) = v0
            if (scene%solver_name /= 'mexax') then
                call formulation%consistent_initial(scene%t_start, y0, yp0, status)
                if (.not. status%ok()) return
            end if
            call append_block(blocks, 'q', formulation%oq + 1, formulation%oq + formulation%nq)
            call append_block(blocks, 'v', formulation%ov + 1, formulation%ov + formulation%nv)
            allocate (problem, source=formulation)
        case ('brusselator_1d', 'brusselator_2d')
            bruss = new_reaction_diffusion(merge(1, 2, scene%problem == 'brusselator_1d'), &
                scene%npoints, sparse=scene%linear_solver /= 'dense', status=status)
            if (.not. status%ok()) then
                status%message = scene%path // ': &simulation: ' // status%message
                return
            end if
            allocate (y0(bruss%n))
            call reaction_diffusion_initial(bruss, y0)
            allocate (problem, source=bruss)
        case default
            call status%set(status_bad_input, scene%path // ': &simulation: problem = ''' // &
                trim(scene%problem) // ''': not available in this build')
        end select
    end subroutine build_problem

    !> With linear_solver = 'dense' the formulation and the solvers hold a
    !> few n x n matrices (the Jacobian, the mass matrix, the iteration
    !> matrix and its factors: counted as 6); beyond the machine's memory
    !> that is bad input, named before anything is allocated.
    subroutine check_dense_size(scene, mechanical, status)
        type(scene_input_t), intent(in) :: scene
        class(mechanical_problem_t), intent(in) :: mechanical
        type(status_t), intent(inout) :: status
        real(wp) :: n, bytes
        integer(i8) :: machine
        if (scene%linear_solver /= 'dense') return
        n = real(mechanical%nq, wp) + real(mechanical%nv, wp) + 2.0_wp * real(mechanical%nc, wp)
        bytes = 6.0_wp * 8.0_wp * n**2
        machine = physical_memory()
        if (machine > 0 .and. bytes > real(machine, wp)) call status%set(status_bad_input, &
            scene%path // ': &solver: linear_solver = ''dense'': ' // real_text(n) // &
            ' unknowns need ~' // bytes_text(bytes) // ' of dense matrices; this machine has ' &
            // bytes_text(real(machine, wp)) // ' (''auto'', ''klu'' or ''mumps'' are sparse)')
    end subroutine check_dense_size

    !> The HDF5 file of n_output records (y, its blocks and the time) must
    !> fit in the free space of its folder: an output grid that cannot be
    !> written is bad input, said before the run (with every_step the
    !> number of records is not known in advance).
    subroutine check_output_size(scene, n, blocks, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: n
        type(block_spec_t), intent(in) :: blocks(:)
        type(status_t), intent(inout) :: status
        real(wp) :: bytes
        integer(i8) :: free
        integer :: i, per_record
        if (len(scene%output_file) == 0 .or. scene%every_step) return
        per_record = n + 1
        do i = 1, size(blocks)
            per_record = per_record + blocks(i)%last - blocks(i)%first + 1
        end do
        bytes = 8.0_wp * real(per_record, wp) * real(scene%n_output, wp)
        free = free_space(scene%output_file(1:index(scene%output_file, '/', back=.true.)))
        if (free >= 0 .and. bytes > real(free, wp)) call status%set(status_bad_input, &
            scene%path // ': &output: n_output = ' // int_text(scene%n_output) // ': the &
            &HDF5 file ''' // scene%output_file // ''' would need ~' // bytes_text(bytes) // &
            ' (' // int_text(per_record) // ' values a record); its file system has ' // &
            bytes_text(real(free, wp)) // ' free')
    end subroutine check_output_size

    !> Add the block y(first:last) named `name`. Through a named variable:
    !> gfortran 12 leaks the allocatable name of a structure constructor
    !> inside an array constructor (`[blocks, block_spec_t(...)]`).
    subroutine append_block(blocks, name, first, last)
        type(block_spec_t), allocatable, intent(inout) :: blocks(:)
        character(len=*), intent(in) :: name
        integer, intent(in) :: first, last
        type(block_spec_t) :: block
        block%name = name
        block%first = first
        block%last = last
        blocks = [blocks, block]
    end subroutine append_block

    pure integer function formulation_code(name)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ('index1'); formulation_code = pendulum_index1
        case ('index2'); formulation_code = pendulum_index2
        case ('index3'); formulation_code = pendulum_index3
        case ('ggl'); formulation_code = pendulum_ggl
        case default; formulation_code = 0
        end select
    end function formulation_code

    pure integer function mechanical_formulation(name)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ('index1'); mechanical_formulation = formulation_index1
        case ('index3'); mechanical_formulation = formulation_index3
        case ('ggl'); mechanical_formulation = formulation_ggl
        case default; mechanical_formulation = formulation_index2
        end select
    end function mechanical_formulation

    !> The solver the scene names, with its own settings.
    subroutine build_solver(scene, solver, status)
        type(scene_input_t), intent(in) :: scene
        class(dae_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        type(radau5_t) :: radau5
        type(ida_t) :: ida
        type(ddassl_t) :: ddassl
        type(mexax_t) :: mexax
        select case (trim(scene%solver_name))
        case ('radau5')
            radau5%nit = scene%nit
            radau5%thet = scene%thet
            radau5%fnewt = scene%fnewt
            radau5%quot1 = scene%quot1
            radau5%quot2 = scene%quot2
            radau5%safe = scene%safe
            radau5%fac_min = scene%fac_min
            radau5%fac_max = scene%fac_max
            radau5%controller = controller_code(scene%controller)
            radau5%zero_start = scene%zero_start
            allocate (solver, source=radau5)
        case ('ida')
            allocate (solver, source=ida)
        case ('ddassl')
            ! pmax reaches it through dae_options_t (MAXORD).
            ddassl%initial_derivative = scene%initial_derivative
            ddassl%exclude_index23 = scene%exclude_index23
            ddassl%netlib = scene%netlib
            allocate (solver, source=ddassl)
        case ('mexax')
            mexax%max_extrapolation = scene%max_extrapolation
            mexax%base = merge(mexax_base_euler, mexax_base_midpoint, &
                scene%mexax_base == 'euler')
            allocate (solver, source=mexax)
        case default
            call status%set(status_bad_input, scene%path // ': &solver: name = ''' // &
                trim(scene%solver_name) // ''': not available in this build yet')
        end select
    end subroutine build_solver

    !> The "stab." column of the tables: the formulation where there is one.
    function scene_stab(scene) result(stab)
        type(scene_input_t), intent(in) :: scene
        character(len=:), allocatable :: stab
        if (scene%solver_name == 'mexax') then
            stab = 'mech'
        else if (scene%problem == 'pendulum') then
            stab = trim(scene%pendulum_formulation)
        else if (scene%problem == 'flexible_body') then
            stab = trim(scene%body%formulation)
        else if (scene%problem == 'multibody' .or. scene%problem == 'rigid_chain') then
            stab = trim(scene%multibody%formulation)
        else
            stab = '-'
        end if
    end function scene_stab

    !> Run a validated scene: build, check, create the outputs, integrate,
    !> store the statistics. `status` is ok, bad_input (before any file is
    !> created), solver_failure or signal (SIGINT/SIGTERM, checked after
    !> every accepted step: outputs kept, `result` says how far it got) or
    !> io_error.
    subroutine run_scene(scene, quiet, result, status, record, force)
        type(scene_input_t), intent(in) :: scene
        logical, intent(in) :: quiet             !! no progress display
        type(run_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        !> also given the solution at every output time
        class(sink_t), intent(inout), target, optional :: record
        !> replace existing files that are not flexmbs's own (io/output_files)
        logical, intent(in), optional :: force
        class(dae_problem_t), allocatable, target :: problem
        type(monitor_sink_t), target :: monitor
        type(vtk_sink_t), target :: vtk
        class(mechanical_problem_t), allocatable, target :: mechanical
        class(dae_solver_t), allocatable, target :: solver
        type(block_spec_t), allocatable :: blocks(:)
        type(dae_options_t) :: options
        class(linear_solver_t), allocatable :: linear_solver
        type(hdf5_sink_t), target :: h5
        type(progress_t), target :: progress
        type(signal_sink_t), target :: signals
        type(multi_sink_t) :: sinks
        type(status_t) :: io_status
        integer :: i
        character(len=:), allocatable :: outcome
        real(wp), allocatable :: y_start(:)

        call build_problem(scene, problem, result%y, blocks, status, mechanical, result%assembly)
        if (.not. status%ok()) return
        result%q_first = 1
        result%q_last = size(result%y)
        do i = 1, size(blocks)
            if (blocks(i)%name /= 'q') cycle
            result%q_first = blocks(i)%first
            result%q_last = blocks(i)%last
        end do
        call build_solver(scene, solver, status)
        if (.not. status%ok()) return
        result%solver_name = solver%name()
        result%t = scene%t_start
        options = scene_dae_options(scene)
        call options%validate(problem%n, status)
        if (status%ok()) then
            ! the linear solver must exist before any file is created
            call new_linear_solver(options%linear_solver, problem%n, &
                                   problem%jacobian_storage(), linear_solver, status, &
                                   ordering=options%sparse_ordering)
        end if
        if (.not. status%ok()) then
            status%message = scene%path // ': &solver: ' // status%message
            return
        end if

        ! ParaView output is checked before any file is created
        if (len_trim(scene%vtk) > 0) then
            call setup_vtk()
            if (.not. status%ok()) return
        end if
        ! which files the run may write; checked before any file is created
        call check_outputs(scene, vtk, size(options%output_times), force_given(), status)
        if (.not. status%ok()) return
        call check_output_size(scene, problem%n, blocks, status)
        if (.not. status%ok()) return
        if (len(scene%output_file) > 0) then
            call h5%create(scene%output_file, problem%n, status, input_text=scene%text, &
                           every_step=scene%every_step)
            if (.not. status%ok()) then
                call h5%close(io_status)
                return
            end if
            result%hdf5_written = .true.
            do i = 1, size(blocks)
                call h5%add_block(blocks(i)%name, blocks(i)%first, blocks(i)%last, status)
                if (.not. status%ok()) return
            end do
            call h5%write_text('problem', trim(scene%problem), status)
            if (status%ok()) call h5%write_text('title', trim(scene%title), status)
            if (status%ok()) call h5%write_text('input_file', scene%path, status)
            if (status%ok() .and. allocated(result%assembly)) call h5%write_text('assembly', &
                'moves of the initial assembly from the given positions: ' // &
                result%assembly, status)
            if (.not. status%ok()) return
            call sinks%attach(h5)
        end if
        progress = new_progress(scene%t_start, scene%t_end, quiet .or. .not. scene%progress)
        call progress%watch(solver)
        call sinks%attach(progress)
        call sinks%attach(signals)
        if (present(record)) call sinks%attach(record)
        if (len_trim(scene%vtk) > 0) call sinks%attach(vtk)
        ! drift and energy of formulated mechanical scenes, at the output times
        select type (p => problem)
        type is (formulation_t)
            if (allocated(mechanical)) then
                monitor%formulation => p
                monitor%mechanical => mechanical
                monitor%every_step = scene%every_step
                monitor%q_start = result%y(p%oq + 1:p%oq + p%nq)
                call sinks%attach(monitor)
                result%constraints = p%nc
            end if
        end select

        y_start = result%y
        call record_energy(y_start, result%energy_start)
        select type (solver)
        type is (mexax_t)
            call integrate_mechanical(solver)
        class default
            call solver%integrate(problem, result%t, result%y, scene%t_end, options, &
                                  result%stats, status, sinks)
        end select
        ! a solver that refuses its options: say which file and group
        if (status%code == status_bad_input) then
            if (index(status%text(), scene%path // ':') /= 1) status%message = scene%path // &
                ': &solver: ' // status%text()
        end if
        if (status%code == status_interrupted .and. signal_pending()) call status%set( &
            status_signal, 'stopped by ' // signal_name(caught_signal()) // ' at t = ' // &
            real_text(result%t), caught_signal())
        if (status%ok()) call record_energy(result%y, result%energy_end)
        result%has_energy = result%has_energy .and. status%ok()

        if (monitor%records > 0) then
            result%has_drift = .true.
            result%drift_end = monitor%table(2:3, monitor%records)
        end if
        if (h5%is_open) then
            if (monitor%records > 0) then
                call h5%write_matrix('monitor', monitor%table(:, 1:monitor%records), io_status)
                if (io_status%ok()) call h5%write_text('monitor_columns', &
                    't, |g|_inf, |G v + g_I|_inf, energy [J]', io_status)
                if (io_status%ok() .and. size(monitor%reactions, 1) > 0) then
                    call h5%write_matrix('reactions', &
                        monitor%reactions(:, 1:monitor%records), io_status)
                    if (io_status%ok()) call h5%write_text('reactions_columns', 'per joint &
                        &of the system: force and torque on the body of marker i, then of &
                        &marker j (N, N m; global; torque about the marker)', io_status)
                end if
                if (status%ok() .and. .not. io_status%ok()) status = io_status
            end if
            outcome = 'ok'
            if (.not. status%ok()) outcome = status%text()
            call h5%write_statistics(result%stats, io_status, result%solver_name, outcome)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
            call h5%close(io_status)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
            ! A solver that refused its input computed nothing: leave no file.
            if (status%code == status_bad_input .and. h5%records == 0) then
                call delete_file(scene%output_file)
                result%hdf5_written = .false.
            end if
        end if
        if (len_trim(scene%table) > 0 .and. status%code /= status_bad_input) then
            call write_table(trim(scene%table), [new_stats_row(result%solver_name, &
                scene%rtol, scene_stab(scene), result%stats)], io_status)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
        end if

    contains

        !> ParaView output of the flexible body and the rigid bodies (y starts
        !> with q in every layout: the bodies' (r, p), then v behind q).
        subroutine setup_vtk()
            vtk%prefix = trim(scene%vtk)
            if (.not. allocated(mechanical)) then
                call status%set(status_bad_input, scene%path // ': &output: vtk: problem = ''' &
                    // trim(scene%problem) // ''' has no bodies to draw')
                return
            end if
            select type (m => mechanical)
            type is (flexible_body_t)
                vtk%body => m
                vtk%oq = 0
                vtk%ov = m%nq
            type is (mbs_system_t)
                vtk%bodies = size(m%rigid%bodies)
                if (size(m%chains) > 0) then
                    vtk%chain => m%chains(1)
                    vtk%chain_q = m%chain_q(1)
                end if
                if (size(m%flex) > 0) then
                    vtk%body => m%flex(1)
                    vtk%oq = m%flex_q(1)
                    vtk%ov = m%nq + m%flex_v(1)
                    select type (p => problem)
                    type is (formulation_t)
                        vtk%oq = p%oq + m%flex_q(1)
                        vtk%ov = p%ov + m%flex_v(1)
                    end select
                end if
            class default
                call status%set(status_bad_input, scene%path // ': &output: vtk: problem = ''' &
                    // trim(scene%problem) // ''' has no bodies to draw')
            end select
        end subroutine setup_vtk

        !> MEXAX on the mechanical problem; y = (q, v, λ) as built by
        !> build_problem (the namelist admits mechanical scenes only).
        subroutine integrate_mechanical(mexax)
            type(mexax_t), intent(inout) :: mexax
            integer :: nq, nv, nc
            if (.not. allocated(mechanical)) then
                call status%set(status_bad_input, scene%path // ': &solver: name = ''mexax'': &
                    &problem = ''' // trim(scene%problem) // ''' has no mechanical form')
                return
            end if
            nq = mechanical%nq
            nv = mechanical%nv
            nc = mechanical%nc
            call mexax%integrate_mechanical(mechanical, result%t, result%y(1:nq), &
                result%y(nq + 1:nq + nv), scene%t_end, options, result%stats, status, sinks, &
                lambda=result%y(nq + nv + 1:nq + nv + nc))
        end subroutine integrate_mechanical

        logical function force_given()
            force_given = .false.
            if (present(force)) force_given = force
        end function force_given

        !> Energies of a flexible body at y = (q, v, ...).
        subroutine record_energy(y, energies)
            real(wp), intent(in) :: y(:)
            real(wp), intent(out) :: energies(3)
            type(status_t) :: energy_status
            energies = 0.0_wp
            if (.not. allocated(mechanical)) return
            select type (body => mechanical)
            type is (flexible_body_t)
                associate (nq => body%nq)
                    call body_energies(body, y(1:nq), y(nq + 1:2 * nq), y_start(1:nq), &
                                       energies, energy_status)
                end associate
                result%has_energy = energy_status%ok()
            end select
        end subroutine record_energy
    end subroutine run_scene

    !> The run's outputs (the HDF5 file, the table, the ParaView collection
    !> and the pieces of its `records` records) against its inputs (the
    !> scene file, a mesh file) and each other, and what they would replace
    !> (io/output_files).
    subroutine check_outputs(scene, vtk, records, force, status)
        type(scene_input_t), intent(in) :: scene
        type(vtk_sink_t), intent(in) :: vtk
        integer, intent(in) :: records
        logical, intent(in) :: force
        type(status_t), intent(inout) :: status
        type(named_path_t), allocatable :: outputs(:), inputs(:)
        character(len=:), allocatable :: pieces(:)
        integer :: n, k
        allocate (inputs(merge(2, 1, len_trim(scene%body%mesh_file) > 0)))
        inputs(1) = named_path(scene%path, 'the scene file itself')
        if (size(inputs) > 1) inputs(2) = named_path(trim(scene%body%mesh_file), &
            'the mesh file ''' // trim(scene%body%mesh_file) // '''')
        allocate (character(len=0) :: pieces(0))
        if (len_trim(scene%vtk) > 0) pieces = vtk%pieces(records)
        allocate (outputs(3 + size(pieces)))
        n = 0
        if (len(scene%output_file) > 0) call add(scene%output_file, 'file', output_hdf5)
        if (len_trim(scene%table) > 0) call add(trim(scene%table), 'table', output_table)
        if (len_trim(scene%vtk) > 0) call add(trim(scene%vtk) // '.pvd', 'vtk', output_vtk)
        do k = 1, size(pieces)
            call add(trim(pieces(k)), 'vtk', output_vtk)
            outputs(n)%series = .true.
        end do
        call check_output_paths(scene%path // ': ', outputs(1:n), inputs, force, status)
    contains
        subroutine add(path, name, kind)
            character(len=*), intent(in) :: path, name
            integer, intent(in) :: kind
            n = n + 1
            outputs(n) = named_path(path, '&output: ' // name, kind)
        end subroutine add
    end subroutine check_outputs

    subroutine delete_file(path)
        character(len=*), intent(in) :: path
        integer :: unit, ios
        open (newunit=unit, file=path, status='old', iostat=ios)
        if (ios == 0) close (unit, status='delete')
    end subroutine delete_file
end module flexmbs_io_scene
