!> The problem factories of the catalogue (run/catalogue): the problem a
!> scene names, built from its input, with its initial value, its named
!> blocks of y and, for a mechanical problem, the mechanical form.
!>
!> The formulation and the layout of y follow the solver's capabilities:
!> a solver that integrates the mechanical form itself (MEXAX) gets the
!> index-2 formulation with constant mass, whose y = (q, v, λ) is the
!> layout it integrates; every other solver the formulation the scene asks
!> for.
module flexmbs_run_problem_factory
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: real_text
    use flexmbs_core_resources, only: physical_memory, bytes_text
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_problems_van_der_pol, only: new_van_der_pol
    use flexmbs_problems_robertson, only: robertson_t, new_robertson, robertson_initial
    use flexmbs_problems_pendulum, only: pendulum_t, new_pendulum, pendulum_initial, &
        pendulum_index1, pendulum_index2, pendulum_index3, pendulum_ggl, &
        new_pendulum_mechanical
    use flexmbs_problems_reaction_diffusion, only: reaction_diffusion_t, &
        new_reaction_diffusion, reaction_diffusion_initial
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_index3, formulation_ggl, block_q, block_v, block_lambda
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    use flexmbs_mbs_system, only: mbs_system_t, part_frame
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_run_catalogue, only: problem_id, problem_van_der_pol, problem_pendulum, &
        problem_robertson, problem_brusselator_1d, problem_brusselator_2d, &
        problem_flexible_body, problem_multibody, problem_rigid_chain, solver_mechanical_only
    use flexmbs_run_multibody_builder, only: build_multibody
    use flexmbs_run_assembly_check, only: check_assembly
    use flexmbs_run_chain_builder, only: build_rigid_chain
    use flexmbs_run_body_builder, only: build_flexible_body
    implicit none
    private

    !> A named slice of y written as its own HDF5 dataset (/q, /v, /lambda).
    type, public :: block_spec_t
        character(len=:), allocatable :: name
        integer :: first = 0, last = 0
    end type block_spec_t

    public :: build_problem

contains

    !> The problem the scene names, its initial value and its named blocks.
    !> Small problems report a CSC Jacobian only when KLU is asked for; the
    !> Brusselator reports CSC unless the dense solver is forced.
    !> A mechanical scene (pendulum with MEXAX, flexible body) also returns
    !> its mechanical problem in `mechanical`, which the formulation in
    !> `problem` points to: it must stay in place while `problem` is used.
    !> Its y = (q, v, λ) is the layout MEXAX integrates.
    subroutine build_problem(scene, problem, y0, blocks, status, mechanical, assembly, &
                             joint_names)
        type(scene_input_t), intent(in) :: scene
        class(dae_problem_t), allocatable, intent(out) :: problem
        real(wp), allocatable, intent(out) :: y0(:)
        type(block_spec_t), allocatable, intent(out) :: blocks(:)
        type(status_t), intent(out) :: status
        class(mechanical_problem_t), allocatable, target, intent(inout), optional :: mechanical
        !> a multibody scene: how far the initial assembly moved each body
        character(len=:), allocatable, intent(out), optional :: assembly
        !> a multibody scene: per joint of the system, its group and name
        !> ('joints/NAME', 'drivers/NAME'; run/multibody_builder)
        character(len=:), allocatable, intent(out), optional :: joint_names(:)
        type(robertson_t) :: robertson
        type(reaction_diffusion_t) :: bruss
        character(len=:), allocatable :: moves, names(:)
        logical :: klu, mech_core
        ! the solver integrates the mechanical form itself (MEXAX)
        mech_core = solver_mechanical_only(scene%solver_name)
        klu = scene%linear_solver == 'klu' .or. scene%linear_solver == 'mumps'
        allocate (blocks(0))
        if (present(mechanical)) then
            if (allocated(mechanical)) deallocate (mechanical)
        end if
        select case (problem_id(scene%problem))
        case (problem_flexible_body, problem_multibody, problem_rigid_chain)
            if (.not. present(mechanical)) then
                call status%set(status_bad_input, scene%path // ': &simulation: problem = ''' &
                    // trim(scene%problem) // ''': build_problem needs its `mechanical` argument')
                return
            end if
        end select
        select case (problem_id(scene%problem))
        case (problem_van_der_pol)
            allocate (problem, source=new_van_der_pol(scene%vdp_eps, sparse=klu))
            y0 = [scene%vdp_y1, scene%vdp_y2]
        case (problem_robertson)
            robertson = new_robertson(sparse=klu, sparse_mass=klu)
            allocate (y0(robertson%n))
            call robertson_initial(robertson, y0)
            allocate (problem, source=robertson)
        case (problem_pendulum)
            call build_pendulum(scene, mech_core, klu, problem, y0, blocks, status, mechanical)
        case (problem_flexible_body)
            call build_flexible_problem(scene, problem, y0, blocks, mechanical, status)
        case (problem_multibody)
            call build_multibody_problem(scene, mech_core, problem, y0, blocks, mechanical, &
                                         status, moves, names)
            ! (gfortran 12 loses a deferred length passed on through two
            ! optional dummies: the results come back in locals)
            if (present(assembly) .and. allocated(moves)) assembly = moves
            if (present(joint_names) .and. allocated(names)) joint_names = names
        case (problem_rigid_chain)
            call build_chain_problem(scene, mech_core, problem, y0, blocks, mechanical, status)
        case (problem_brusselator_1d, problem_brusselator_2d)
            bruss = new_reaction_diffusion(merge(1, 2, problem_id(scene%problem) == problem_brusselator_1d), &
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

    !> The pendulum in the scene's formulation; a mechanical core takes the
    !> mechanical form, its state y = (q, v, λ) with the layout and initial
    !> values of the index-2 formulation.
    subroutine build_pendulum(scene, mech_core, klu, problem, y0, blocks, status, mechanical)
        include 'problem_builder_arguments.inc'
        logical, intent(in) :: mech_core, klu
        class(mechanical_problem_t), allocatable, intent(inout), optional :: mechanical
        type(pendulum_t) :: pendulum
        pendulum = new_pendulum(merge(pendulum_index2, &
            formulation_code(scene%pendulum_formulation), mech_core), &
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
        if (mech_core .and. present(mechanical)) then
            allocate (mechanical, source=new_pendulum_mechanical(mass=scene%pendulum_mass, &
                length=scene%pendulum_length, gravity=scene%gravity, status=status))
        end if
    end subroutine build_pendulum

    !> One flexible body: M is constant in absolute nodal coordinates, so
    !> y = (q, v[, λ]).
    subroutine build_flexible_problem(scene, problem, y0, blocks, mechanical, status)
        include 'problem_builder_arguments.inc'
        class(mechanical_problem_t), allocatable, target, intent(inout) :: mechanical
        type(formulation_t) :: formulation
        real(wp), allocatable :: q0(:), v0(:)
        integer :: nq
        allocate (flexible_body_t :: mechanical)
        select type (body => mechanical)
        type is (flexible_body_t)
            call build_flexible_body(scene, 1, body, q0, v0, status)
        end select
        if (.not. status%ok()) return
        call check_dense_size(scene, mechanical, status)
        if (.not. status%ok()) return
        formulation = new_formulation(mechanical, &
            mechanical_formulation(scene%bodies(1)%formulation), q0, constant_mass=.true., &
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
    end subroutine build_flexible_problem

    !> A multibody system in its formulation, from consistent initial values
    !> (the initial assembly checked and reported).
    subroutine build_multibody_problem(scene, mech_core, problem, y0, blocks, mechanical, &
                                       status, moves, names)
        include 'problem_builder_arguments.inc'
        logical, intent(in) :: mech_core
        class(mechanical_problem_t), allocatable, target, intent(inout) :: mechanical
        !> how far the initial assembly moved each body; per joint its group and name
        character(len=:), allocatable, intent(out) :: moves, names(:)
        character(len=:), allocatable :: labels(:)
        type(formulation_t) :: formulation
        real(wp), allocatable :: q0(:), v0(:), yp0(:)
        logical :: massless
        allocate (mbs_system_t :: mechanical)
        massless = .false.
        select type (sys => mechanical)
        type is (mbs_system_t)
            call build_multibody(scene, sys, q0, v0, status, labels, names)
            massless = sys%part_count(part_frame) > 0
        end select
        if (.not. status%ok()) return
        call check_dense_size(scene, mechanical, status)
        if (.not. status%ok()) return
        ! Rigid and flexible bodies have a constant M (body-fixed ω'):
        ! y = (q, v, λ[, μ]); a chain's M(q) and the zero M of node frames
        ! need the acceleration layout y = (q, v, a, λ[, μ]), where the
        ! constraints determine a through [M Gᵀ; G 0]. A mechanical core integrates
        ! y = (q, v, λ) (index 2).
        formulation = new_formulation(mechanical, merge(formulation_index2, &
            mechanical_formulation(scene%multibody%formulation), &
            mech_core), q0, constant_mass=(size(scene%chain) == 0 &
            .and. .not. massless) .or. mech_core, &
            projection=scene%multibody%projection, status=status, &
            sparse=scene%linear_solver /= 'dense')
        if (.not. status%ok()) then
            status%message = scene%path // ': &multibody: ' // status%message
            return
        end if
        call start_state(formulation, q0, v0, y0, yp0)
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
                y0(formulation%offset(block_q) + 1:formulation%last(block_q)), moves, status)
        end select
        if (.not. status%ok()) return
        call append_layout(blocks, formulation)
        allocate (problem, source=formulation)
    end subroutine build_multibody_problem

    !> A rigid chain alone: M(q) varies, so the acceleration layout
    !> y = (q, v, a) (nc = 0). MEXAX integrates y = (q, v); its formulation
    !> only gives that layout.
    subroutine build_chain_problem(scene, mech_core, problem, y0, blocks, mechanical, status)
        include 'problem_builder_arguments.inc'
        logical, intent(in) :: mech_core
        class(mechanical_problem_t), allocatable, target, intent(inout) :: mechanical
        type(formulation_t) :: formulation
        real(wp), allocatable :: q0(:), v0(:), yp0(:)
        allocate (rigid_chain_t :: mechanical)
        select type (chain => mechanical)
        type is (rigid_chain_t)
            call build_rigid_chain(scene, chain, q0, v0, status)
        end select
        if (.not. status%ok()) return
        formulation = new_formulation(mechanical, merge(formulation_index2, &
            mechanical_formulation(scene%multibody%formulation), &
            mech_core), q0, constant_mass=mech_core, status=status)
        if (.not. status%ok()) then
            status%message = scene%path // ': &rigid_chain: ' // status%message
            return
        end if
        call start_state(formulation, q0, v0, y0, yp0)
        if (.not. mech_core) then
            call formulation%consistent_initial(scene%t_start, y0, yp0, status)
            if (.not. status%ok()) return
        end if
        call append_layout(blocks, formulation) ! nc = 0: q and v
        allocate (problem, source=formulation)
    end subroutine build_chain_problem

    !> y0 = (q0, v0, 0...) in the layout of `formulation`, yp0 = 0.
    subroutine start_state(formulation, q0, v0, y0, yp0)
        type(formulation_t), intent(in) :: formulation
        real(wp), intent(in) :: q0(:), v0(:)
        real(wp), allocatable, intent(out) :: y0(:), yp0(:)
        allocate (y0(formulation%n), yp0(formulation%n), source=0.0_wp)
        y0(formulation%offset(block_q) + 1:formulation%last(block_q)) = q0
        y0(formulation%offset(block_v) + 1:formulation%last(block_v)) = v0
    end subroutine start_state

    !> The blocks q, v and (when there are constraints) lambda of
    !> `formulation`'s y, appended to `blocks`.
    subroutine append_layout(blocks, formulation)
        type(block_spec_t), allocatable, intent(inout) :: blocks(:)
        type(formulation_t), intent(in) :: formulation
        call append_block(blocks, 'q', formulation%offset(block_q) + 1, formulation%last(block_q))
        call append_block(blocks, 'v', formulation%offset(block_v) + 1, formulation%last(block_v))
        if (formulation%block_size(block_lambda) > 0) call append_block(blocks, 'lambda', &
            formulation%offset(block_lambda) + 1, formulation%last(block_lambda))
    end subroutine append_layout

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
end module flexmbs_run_problem_factory
