!> What a scene file says, typed: one derived type per group, filled by
!> flexmbs_io_scene_reader with the file's values and the schema's
!> defaults (flexmbs_io_scene_schema) for the rest.
module flexmbs_io_scene_input
    use flexmbs_core_kinds, only: wp
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_io_scene_schema, only: len_title, len_name, len_path, max_fixed_sets, &
        max_interfaces
    implicit none
    private

    !> One `&material`: the paper's neo-Hookean law with damping, on an
    !> element set of the body's mesh.
    type, public :: material_input_t
        character(len=len_name) :: name !! for messages ('' = 'material N')
        real(wp) :: youngs_modulus !! E [Pa], required, > 0
        real(wp) :: poisson_ratio !! ν, in (−1, 0.5)
        real(wp) :: density !! ρ [kg/m³], required, > 0
        real(wp) :: viscosity !! η [Pa·s], ≥ 0 (0: undamped)
        !> element set it covers; '' = every element no other material names
        character(len=len_name) :: elements
        !> the &flexible_body it belongs to; '' = the scene's only one
        character(len=len_name) :: body
        integer :: line = 0                      !! where the group starts
    end type material_input_t

    !> One `&flexible_body` group: mesh, supports, loads, initial velocity.
    type, public :: body_input_t
        character(len=len_name) :: name
        character(len=len_name) :: element !! 'hex8' | 'hex27'
        character(len=len_path) :: mesh_file !! '' = a box mesh
        integer :: divisions(3) !! box: elements per direction
        real(wp) :: lengths(3) !! box: edge lengths [m], required
        real(wp) :: origin(3) !! box: lower corner [m]
        character(len=len_name) :: fixed(max_fixed_sets) !! node sets held at X
        character(len=len_name) :: load_set !! node set carrying `load`
        real(wp) :: load(3) !! total force on load_set [N]
        real(wp) :: gravity(3) !! [m/s²]
        real(wp) :: initial_velocity(3) !! [m/s], rigid field
        real(wp) :: initial_angular_velocity(3) !! [rad/s] about the centroid
        character(len=len_name) :: formulation
        character(len=len_name) :: model = 'nonlinear' !! 'nonlinear' | 'modal'
        integer :: modes = 8 !! modal: fixed-interface modes
        character(len=len_name) :: interfaces(max_interfaces) = '' !! modal: interface sets
        character(len=len_name) :: modes_method = 'auto' !! modal: 'auto' | 'dense' | 'arpack'
        character(len=len_path) :: modes_cache = '' !! modal: HDF5 cache of the basis
        integer :: line = 0                               !! where the group starts
    end type body_input_t

    !> The `&multibody` group: how rigid bodies and joints are integrated.
    type, public :: multibody_input_t
        character(len=len_name) :: formulation
        real(wp) :: gravity(3) !! [m/s²]
        character(len=len_name) :: constraint_derivatives
        logical :: projection !! coordinate projection after each step
        !> largest move of a body by the consistent initial assembly [m]
        real(wp) :: assembly_tolerance
        integer :: line = 0
    end type multibody_input_t

    !> One `&rigid_body`: mass, inertia about the centre of mass (body
    !> frame), initial pose and velocities (world).
    type, public :: rigid_body_input_t
        character(len=len_name) :: name
        real(wp) :: mass !! [kg], required
        real(wp) :: inertia(3) !! Jxx, Jyy, Jzz [kg m²], required
        real(wp) :: inertia_products(3) !! Jxy, Jyz, Jxz
        real(wp) :: position(3) !! centre of mass [m]
        real(wp) :: rotation_axis(3)
        real(wp) :: rotation_angle !! [rad]
        real(wp) :: velocity(3) !! [m/s]
        real(wp) :: angular_velocity(3) !! [rad/s], world frame
        integer :: line = 0
    end type rigid_body_input_t

    !> One `&marker`: a frame on a rigid body or the ground.
    type, public :: marker_input_t
        character(len=len_name) :: name
        character(len=len_name) :: body
        real(wp) :: position(3) !! in the body's frame [m]
        real(wp) :: z_axis(3)
        real(wp) :: x_axis(3) !! 0: any normal to z
        character(len=len_name) :: node_set !! on the flexible body: its nodes
        logical :: position_given = .false.         !! (node-set markers default to the centroid)
        integer :: line = 0
    end type marker_input_t

    !> One `&joint` between two markers.
    type, public :: joint_input_t
        character(len=len_name) :: name
        character(len=len_name) :: type
        character(len=len_name) :: marker_i, marker_j
        integer :: line = 0
    end type joint_input_t


    !> One `&driver`: an angle, translation or distance following s(t).
    type, public :: driver_input_t
        character(len=len_name) :: name
        character(len=len_name) :: type !! 'angle' | 'translation' | 'distance'
        character(len=len_name) :: marker_i, marker_j
        integer :: axis_i, axis_j
        real(wp) :: coefficients(4) !! s = c0 + c1 t + c2 t² + c3 t³
        real(wp) :: amplitude !! + a sin(ω t + φ)
        real(wp) :: frequency !! ω [rad/s]
        real(wp) :: phase !! φ [rad]
        real(wp) :: ramp_rate = 0.0_wp !! + a ramp to this rate, then held
        real(wp) :: ramp_time = 0.0_wp !! the ramp's duration [s]
        integer :: line = 0
    end type driver_input_t

    !> One `&force`: a force element between two markers or a load on one.
    type, public :: force_input_t
        character(len=len_name) :: name
        !> 'spring_damper' | 'rotational' | 'bushing' | 'applied'
        character(len=len_name) :: type
        character(len=len_name) :: marker_i, marker_j
        real(wp) :: free_length !! ℓ₀ [m]
        real(wp) :: free_angle !! φ₀ [rad]
        real(wp), allocatable :: stiffness(:), damping(:) !! as given, 0 .. 6 values
        real(wp) :: stiffness_matrix(36), damping_matrix(36) !! rows of K and C
        logical :: has_stiffness_matrix = .false., has_damping_matrix = .false.
        real(wp) :: force(3), torque(3) !! applied [N], [N m]
        character(len=len_name) :: frame !! 'world' | 'marker'
        real(wp) :: coefficients(4), amplitude, frequency, phase !! s(t) as a driver's
        integer :: line = 0
    end type force_input_t

    !> One `&rigid_chain` group: a body of a loop-free chain in relative
    !> coordinates and the joint to its parent (flexmbs_mbs_rigid_chain).
    type, public :: chain_body_input_t
        character(len=len_name) :: name
        character(len=len_name) :: parent !! 'ground' or an earlier body
        character(len=len_name) :: joint !! 'revolute' | 'prismatic'
        real(wp) :: joint_position(3) !! in the parent's frame [m]
        real(wp) :: joint_axis(3) !! parent's frame
        real(wp) :: centre(3) !! centre of mass, own frame [m]
        real(wp) :: mass !! [kg], required
        real(wp) :: inertia(3) !! about the centre of mass, required
        real(wp) :: inertia_products(3)
        real(wp) :: coordinate !! initial q [rad or m]
        real(wp) :: rate !! initial q' [rad/s or m/s]
        !> For spherical, initial relative rotation and angular velocity (own frame)
        real(wp) :: rotation_axis(3)
        real(wp) :: rotation_angle
        real(wp) :: angular_rate(3)
        integer :: line = 0
    end type chain_body_input_t

    !> Everything a scene file says, with defaults for what it leaves out.
    type, public :: scene_input_t
        character(len=:), allocatable :: path !! the file read
        character(len=:), allocatable :: text !! its full text (stored in the HDF5 file)
        ! &simulation
        character(len=len_title) :: title
        character(len=len_name) :: problem
        real(wp) :: t_start !! s
        real(wp) :: t_end !! s, required, > t_start
        real(wp) :: vdp_eps
        real(wp) :: vdp_y1
        real(wp) :: vdp_y2
        character(len=len_name) :: pendulum_formulation
        real(wp) :: pendulum_length !! m
        real(wp) :: pendulum_mass !! kg
        real(wp) :: pendulum_angle !! rad from the downward vertical, at rest
        logical :: pendulum_projection !! project onto both constraints
        real(wp) :: gravity !! m/s²
        integer :: npoints !! grid points per direction (Brusselator)
        ! &solver
        character(len=len_name) :: solver_name
        real(wp) :: rtol
        real(wp) :: atol
        real(wp) :: h0 !! s, 0 = automatic
        real(wp) :: hmax !! s, 0 = |t_end - t_start|
        integer :: max_steps
        character(len=len_name) :: linear_solver
        character(len=len_name) :: sparse_ordering !! KLU: 'auto' | 'amd' | 'nd'
        character(len=len_name) :: newton_system   !! 'condensed' | 'full'
        character(len=len_name) :: jacobian
        integer :: pmax
        !> The solvers' own settings the scene gives (the schema's &solver
        !> variables without a default), in the schema's order: the solver
        !> factory hands them to the solver, and every other keeps the
        !> solver type's default, which is kept nowhere else.
        type(solver_setting_t), allocatable :: solver_settings(:)
        ! &output
        !> HDF5 file; '' = none. Derived from the input name when not given.
        character(len=:), allocatable :: output_file
        integer :: n_output
        logical :: every_step
        character(len=len_path) :: table
        logical :: reasons !! the table also counts the rejected steps by cause
        logical :: progress
        !> ParaView files PREFIX_NNNN.vtu, PREFIX_bodies_NNNN.vtu, PREFIX_joints_NNNN.vtu and
        !> PREFIX.pvd ('' = none; flexmbs_io_vtk_sink)
        character(len=len_path) :: vtk
        !> 'binary' (the .vtu arrays as base64 appended data) or 'ascii' (text)
        character(len=len_name) :: vtk_format
        ! &flexible_body and &material
        type(body_input_t), allocatable :: bodies(:)  !! the &flexible_body groups, in order
        type(material_input_t), allocatable :: materials(:) !! in the order given
        ! &multibody, &rigid_body, &marker, &joint, &driver
        logical :: has_multibody = .false.
        type(multibody_input_t) :: multibody
        type(rigid_body_input_t), allocatable :: rigid_bodies(:)
        type(marker_input_t), allocatable :: markers(:)
        type(joint_input_t), allocatable :: joints(:)
        type(driver_input_t), allocatable :: drivers(:)
        type(force_input_t), allocatable :: forces(:) !! &force
        ! &rigid_chain
        type(chain_body_input_t), allocatable :: chain(:)
    contains
        procedure :: has_body => scene_has_body
    end type scene_input_t

    public :: setting_given, given_setting, marker_index, flexible_index, material_of, nonlinear_body, &
        modal_body

contains

    !> Whether the scene gives the solver setting `name` (&solver).
    pure logical function setting_given(scene, name)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        setting_given = .false.
        if (allocated(scene%solver_settings)) &
            setting_given = any(scene%solver_settings%name == name)
    end function setting_given

    !> The solver setting `name` the scene gives (setting_given), or one
    !> without a name.
    pure function given_setting(scene, name) result(setting)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        type(solver_setting_t) :: setting
        integer :: k
        if (.not. allocated(scene%solver_settings)) return
        do k = 1, size(scene%solver_settings)
            if (scene%solver_settings(k)%name == name) setting = scene%solver_settings(k)
        end do
    end function given_setting

    !> The index of the first marker called `name` in scene, 0 if none.
    pure integer function marker_index(scene, name)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        do marker_index = 1, size(scene%markers)
            if (scene%markers(marker_index)%name == name) return
        end do
        marker_index = 0
    end function marker_index

    !> Whether the scene gives a &flexible_body group.
    pure logical function scene_has_body(self)
        class(scene_input_t), intent(in) :: self
        scene_has_body = .false.
        if (allocated(self%bodies)) scene_has_body = size(self%bodies) > 0
    end function scene_has_body

    !> The index of the &flexible_body called `name`, 0 if none.
    pure integer function flexible_index(scene, name)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        flexible_index = 0
        if (.not. allocated(scene%bodies)) return
        do flexible_index = 1, size(scene%bodies)
            if (scene%bodies(flexible_index)%name == name) return
        end do
        flexible_index = 0
    end function flexible_index

    !> The scene index of the i-th &flexible_body with model = 'nonlinear'
    !> (the system's flexible body i), 0 if there are fewer.
    pure integer function nonlinear_body(scene, i) result(ib)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: i
        ib = nth_body(scene, i, .false.)
    end function nonlinear_body

    !> The scene index of the j-th &flexible_body with model = 'modal' (the
    !> system's modal body j), 0 if there are fewer.
    pure integer function modal_body(scene, j) result(ib)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: j
        ib = nth_body(scene, j, .true.)
    end function modal_body

    pure integer function nth_body(scene, n, modal) result(ib)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: n
        logical, intent(in) :: modal
        integer :: k
        k = 0
        if (allocated(scene%bodies)) then
            do ib = 1, size(scene%bodies)
                if ((scene%bodies(ib)%model == 'modal') .eqv. modal) k = k + 1
                if (k == n) return
            end do
        end if
        ib = 0
    end function nth_body

    !> Whether &material `m` belongs to the &flexible_body numbered `body`
    !> (a material naming no body belongs to the only one).
    pure logical function material_of(scene, m, body)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: m, body
        if (len_trim(scene%materials(m)%body) == 0) then
            material_of = size(scene%bodies) == 1 .and. body == 1
        else
            material_of = scene%materials(m)%body == scene%bodies(body)%name
        end if
    end function material_of
end module flexmbs_io_scene_input
