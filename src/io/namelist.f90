!> Scene input: the namelist groups `&simulation`, `&solver`, `&output`, and
!> for a flexible body `&flexible_body` with one or more `&material` groups.
!>
!> The text is checked before Fortran namelist I/O reads it, because the
!> compiler's own namelist errors name neither the variable nor the value.
!> A small tokeniser walks every group, rejects unknown groups and
!> variables and values of the wrong type; the validated text of each group
!> is then read with `read(..., nml=...)`, and ranges are checked on the
!> typed values. Every problem yields one `status_t` whose message names
!> file, group, variable, value and reason, e.g.
!> `inputs/x.nml: &solver: rtol = -1e-6: must be positive (line 7)`.
module flexmbs_io_namelist
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_files, only: read_text_file, same_file
    use flexmbs_core_text, only: lower, int_text, real_text
    use flexmbs_core_resources, only: physical_memory, bytes_text
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_linalg_linear_solver, only: linear_solver_names, linear_solver_names_text
    implicit none
    private

    integer, parameter :: kind_string = 1, kind_real = 2, kind_integer = 3, kind_logical = 4
    integer, parameter :: len_title = 256, len_name = 32, len_path = 512
    !> Longest lists of a study (`&study`).
    integer, parameter, public :: max_study_solvers = 4, max_study_tolerances = 16

    !> At most this many node-set names in `&flexible_body fixed`.
    integer, parameter, public :: max_fixed_sets = 6

    !> One variable of the schema.
    type :: var_spec_t
        character(len=16) :: group
        character(len=24) :: name
        integer :: kind
        !> values: 1 for a scalar; an array of reals or integers takes
        !> exactly `count`, an array of strings 1..count
        integer :: count = 1
        !> a list: 1..count values of any kind
        logical :: list = .false.
    end type var_spec_t

    type(var_spec_t), parameter :: schema(*) = [ &
        var_spec_t('simulation', 'title', kind_string), &
        var_spec_t('simulation', 'problem', kind_string), &
        var_spec_t('simulation', 't_start', kind_real), &
        var_spec_t('simulation', 't_end', kind_real), &
        var_spec_t('simulation', 'vdp_eps', kind_real), &
        var_spec_t('simulation', 'vdp_y1', kind_real), &
        var_spec_t('simulation', 'vdp_y2', kind_real), &
        var_spec_t('simulation', 'pendulum_formulation', kind_string), &
        var_spec_t('simulation', 'pendulum_length', kind_real), &
        var_spec_t('simulation', 'pendulum_mass', kind_real), &
        var_spec_t('simulation', 'pendulum_angle', kind_real), &
        var_spec_t('simulation', 'pendulum_projection', kind_logical), &
        var_spec_t('simulation', 'gravity', kind_real), &
        var_spec_t('simulation', 'npoints', kind_integer), &
        var_spec_t('solver', 'name', kind_string), &
        var_spec_t('solver', 'rtol', kind_real), &
        var_spec_t('solver', 'atol', kind_real), &
        var_spec_t('solver', 'h0', kind_real), &
        var_spec_t('solver', 'hmax', kind_real), &
        var_spec_t('solver', 'max_steps', kind_integer), &
        var_spec_t('solver', 'linear_solver', kind_string), &
        var_spec_t('solver', 'sparse_ordering', kind_string), &
        var_spec_t('solver', 'jacobian', kind_string), &
        var_spec_t('solver', 'nit', kind_integer), &
        var_spec_t('solver', 'thet', kind_real), &
        var_spec_t('solver', 'fnewt', kind_real), &
        var_spec_t('solver', 'quot1', kind_real), &
        var_spec_t('solver', 'quot2', kind_real), &
        var_spec_t('solver', 'safe', kind_real), &
        var_spec_t('solver', 'fac_min', kind_real), &
        var_spec_t('solver', 'fac_max', kind_real), &
        var_spec_t('solver', 'controller', kind_string), &
        var_spec_t('solver', 'zero_start', kind_logical), &
        var_spec_t('solver', 'pmax', kind_integer), &
        var_spec_t('solver', 'initial_derivative', kind_logical), &
        var_spec_t('solver', 'exclude_index23', kind_logical), &
        var_spec_t('solver', 'netlib', kind_logical), &
        var_spec_t('solver', 'max_extrapolation', kind_integer), &
        var_spec_t('solver', 'mexax_base', kind_string), &
        var_spec_t('output', 'file', kind_string), &
        var_spec_t('output', 'n_output', kind_integer), &
        var_spec_t('output', 'every_step', kind_logical), &
        var_spec_t('output', 'table', kind_string), &
        var_spec_t('output', 'progress', kind_logical), &
        var_spec_t('output', 'vtk', kind_string), &
        var_spec_t('flexible_body', 'name', kind_string), &
        var_spec_t('flexible_body', 'element', kind_string), &
        var_spec_t('flexible_body', 'mesh_file', kind_string), &
        var_spec_t('flexible_body', 'divisions', kind_integer, 3), &
        var_spec_t('flexible_body', 'lengths', kind_real, 3), &
        var_spec_t('flexible_body', 'origin', kind_real, 3), &
        var_spec_t('flexible_body', 'fixed', kind_string, max_fixed_sets), &
        var_spec_t('flexible_body', 'load_set', kind_string), &
        var_spec_t('flexible_body', 'load', kind_real, 3), &
        var_spec_t('flexible_body', 'gravity', kind_real, 3), &
        var_spec_t('flexible_body', 'initial_velocity', kind_real, 3), &
        var_spec_t('flexible_body', 'initial_angular_velocity', kind_real, 3), &
        var_spec_t('flexible_body', 'formulation', kind_string), &
        var_spec_t('material', 'name', kind_string), &
        var_spec_t('material', 'youngs_modulus', kind_real), &
        var_spec_t('material', 'poisson_ratio', kind_real), &
        var_spec_t('material', 'density', kind_real), &
        var_spec_t('material', 'viscosity', kind_real), &
        var_spec_t('material', 'elements', kind_string), &
        var_spec_t('multibody', 'formulation', kind_string), &
        var_spec_t('multibody', 'gravity', kind_real, 3), &
        var_spec_t('multibody', 'constraint_derivatives', kind_string), &
        var_spec_t('multibody', 'projection', kind_logical), &
        var_spec_t('rigid_body', 'name', kind_string), &
        var_spec_t('rigid_body', 'mass', kind_real), &
        var_spec_t('rigid_body', 'inertia', kind_real, 3), &
        var_spec_t('rigid_body', 'inertia_products', kind_real, 3), &
        var_spec_t('rigid_body', 'position', kind_real, 3), &
        var_spec_t('rigid_body', 'rotation_axis', kind_real, 3), &
        var_spec_t('rigid_body', 'rotation_angle', kind_real), &
        var_spec_t('rigid_body', 'velocity', kind_real, 3), &
        var_spec_t('rigid_body', 'angular_velocity', kind_real, 3), &
        var_spec_t('marker', 'name', kind_string), &
        var_spec_t('marker', 'body', kind_string), &
        var_spec_t('marker', 'position', kind_real, 3), &
        var_spec_t('marker', 'z_axis', kind_real, 3), &
        var_spec_t('marker', 'x_axis', kind_real, 3), &
        var_spec_t('marker', 'node_set', kind_string), &
        var_spec_t('joint', 'name', kind_string), &
        var_spec_t('joint', 'type', kind_string), &
        var_spec_t('joint', 'marker_i', kind_string), &
        var_spec_t('joint', 'marker_j', kind_string), &
        var_spec_t('driver', 'name', kind_string), &
        var_spec_t('driver', 'type', kind_string), &
        var_spec_t('driver', 'marker_i', kind_string), &
        var_spec_t('driver', 'marker_j', kind_string), &
        var_spec_t('driver', 'axis_i', kind_integer), &
        var_spec_t('driver', 'axis_j', kind_integer), &
        var_spec_t('driver', 'coefficients', kind_real, 4), &
        var_spec_t('driver', 'amplitude', kind_real), &
        var_spec_t('driver', 'frequency', kind_real), &
        var_spec_t('driver', 'phase', kind_real), &
        var_spec_t('rigid_chain', 'name', kind_string), &
        var_spec_t('rigid_chain', 'parent', kind_string), &
        var_spec_t('rigid_chain', 'joint', kind_string), &
        var_spec_t('rigid_chain', 'joint_position', kind_real, 3), &
        var_spec_t('rigid_chain', 'joint_axis', kind_real, 3), &
        var_spec_t('rigid_chain', 'centre', kind_real, 3), &
        var_spec_t('rigid_chain', 'mass', kind_real), &
        var_spec_t('rigid_chain', 'inertia', kind_real, 3), &
        var_spec_t('rigid_chain', 'inertia_products', kind_real, 3), &
        var_spec_t('rigid_chain', 'coordinate', kind_real), &
        var_spec_t('rigid_chain', 'rate', kind_real), &
        var_spec_t('rigid_chain', 'rotation_axis', kind_real, 3), &
        var_spec_t('rigid_chain', 'rotation_angle', kind_real), &
        var_spec_t('rigid_chain', 'angular_rate', kind_real, 3), &
        var_spec_t('study', 'scene', kind_string), &
        var_spec_t('study', 'reference_file', kind_string), &
        var_spec_t('study', 'reference_solver', kind_string), &
        var_spec_t('study', 'reference_tolerance', kind_real), &
        var_spec_t('study', 'check_solver', kind_string), &
        var_spec_t('study', 'check_tolerance', kind_real), &
        var_spec_t('study', 'solvers', kind_string, max_study_solvers), &
        var_spec_t('study', 'stabilisations', kind_string, 3), &
        var_spec_t('study', 'tolerances', kind_real, max_study_tolerances, .true.), &
        var_spec_t('study', 'pmax', kind_integer, 5, .true.), &
        var_spec_t('study', 'derivatives', kind_string, 3), &
        var_spec_t('study', 'table', kind_string), &
        var_spec_t('study', 'cpu_reference', kind_integer), &
        var_spec_t('study', 't_end', kind_real), &
        var_spec_t('study', 'max_steps', kind_integer), &
        var_spec_t('study', 'layout', kind_string)]

    character(len=16), parameter :: group_names(*) = [character(len=16) :: &
        'simulation', 'solver', 'output', 'flexible_body', 'material', 'multibody', &
        'rigid_body', 'marker', 'joint', 'driver', 'rigid_chain', 'study']
    !> The groups that may be given several times (one item each).
    character(len=16), parameter :: repeatable_groups(*) = [character(len=16) :: &
        'material', 'rigid_body', 'marker', 'joint', 'driver', 'rigid_chain']

    !> Problem names the schema accepts (the scene builder says which exist).
    character(len=16), parameter, public :: problem_names(*) = [character(len=16) :: &
        'van_der_pol', 'pendulum', 'robertson', 'brusselator_1d', 'brusselator_2d', &
        'flexible_body', 'multibody', 'rigid_chain']
    character(len=8), parameter, public :: formulation_names(*) = [character(len=8) :: &
        'index3', 'index2', 'index1', 'ggl']

    !> π/2: the pendulum starts horizontal by default.
    real(wp), parameter :: half_pi = 1.5707963267948966_wp

    !> One `&material`: the paper's neo-Hookean law with damping, on an
    !> element set of the body's mesh.
    type, public :: material_input_t
        character(len=len_name) :: name = ''     !! for messages ('' = 'material N')
        real(wp) :: youngs_modulus = 0.0_wp      !! E [Pa], required, > 0
        real(wp) :: poisson_ratio = 0.3_wp       !! ν, in (−1, 0.5)
        real(wp) :: density = 0.0_wp             !! ρ [kg/m³], required, > 0
        real(wp) :: viscosity = 0.0_wp           !! η [Pa·s], ≥ 0 (0: undamped)
        !> element set it covers; '' = every element no other material names
        character(len=len_name) :: elements = ''
        integer :: line = 0                      !! where the group starts
    end type material_input_t

    !> The `&flexible_body` group: mesh, supports, loads, initial velocity.
    type, public :: body_input_t
        character(len=len_name) :: name = 'body'
        character(len=len_name) :: element = 'hex8'       !! 'hex8' | 'hex27'
        character(len=len_path) :: mesh_file = ''         !! '' = a box mesh
        integer :: divisions(3) = 1                       !! box: elements per direction
        real(wp) :: lengths(3) = 0.0_wp                   !! box: edge lengths [m], required
        real(wp) :: origin(3) = 0.0_wp                    !! box: lower corner [m]
        character(len=len_name) :: fixed(max_fixed_sets) = '' !! node sets held at X
        character(len=len_name) :: load_set = ''          !! node set carrying `load`
        real(wp) :: load(3) = 0.0_wp                      !! total force on load_set [N]
        real(wp) :: gravity(3) = 0.0_wp                   !! [m/s²]
        real(wp) :: initial_velocity(3) = 0.0_wp          !! [m/s], rigid field
        real(wp) :: initial_angular_velocity(3) = 0.0_wp  !! [rad/s] about the centroid
        character(len=len_name) :: formulation = 'index2'
        integer :: line = 0                               !! where the group starts
    end type body_input_t

    !> The `&multibody` group: how rigid bodies and joints are integrated.
    type, public :: multibody_input_t
        character(len=len_name) :: formulation = 'ggl'
        real(wp) :: gravity(3) = [0.0_wp, -9.81_wp, 0.0_wp]  !! [m/s²]
        character(len=len_name) :: constraint_derivatives = 'analytic'
        logical :: projection = .false.   !! coordinate projection after each step
        integer :: line = 0
    end type multibody_input_t

    !> One `&rigid_body`: mass, inertia about the centre of mass (body
    !> frame), initial pose and velocities (world).
    type, public :: rigid_body_input_t
        character(len=len_name) :: name = ''
        real(wp) :: mass = 0.0_wp                   !! [kg], required
        real(wp) :: inertia(3) = 0.0_wp             !! Jxx, Jyy, Jzz [kg m²], required
        real(wp) :: inertia_products(3) = 0.0_wp    !! Jxy, Jyz, Jxz
        real(wp) :: position(3) = 0.0_wp            !! centre of mass [m]
        real(wp) :: rotation_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]
        real(wp) :: rotation_angle = 0.0_wp         !! [rad]
        real(wp) :: velocity(3) = 0.0_wp            !! [m/s]
        real(wp) :: angular_velocity(3) = 0.0_wp    !! [rad/s], world frame
        integer :: line = 0
    end type rigid_body_input_t

    !> One `&marker`: a frame on a rigid body or the ground.
    type, public :: marker_input_t
        character(len=len_name) :: name = ''
        character(len=len_name) :: body = 'ground'
        real(wp) :: position(3) = 0.0_wp            !! in the body's frame [m]
        real(wp) :: z_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]
        real(wp) :: x_axis(3) = 0.0_wp              !! 0: any normal to z
        character(len=len_name) :: node_set = ''    !! on the flexible body: its nodes
        logical :: position_given = .false.         !! (node-set markers default to the centroid)
        integer :: line = 0
    end type marker_input_t

    !> One `&joint` between two markers.
    type, public :: joint_input_t
        character(len=len_name) :: name = ''
        character(len=len_name) :: type = ''
        character(len=len_name) :: marker_i = '', marker_j = ''
        integer :: line = 0
    end type joint_input_t

    !> One `&driver`: an angle, translation or distance following s(t).
    !> A study file (`flexmbs reference`, `flexmbs sweep`): one `&study`
    !> naming a scene and the grid of runs over it.
    type, public :: study_input_t
        character(len=:), allocatable :: path            !! the study file
        character(len=:), allocatable :: scene           !! scene file, resolved
        character(len=:), allocatable :: reference_file  !! HDF5 reference, resolved
        character(len=len_name) :: reference_solver = 'radau5'
        real(wp) :: reference_tolerance = 1.0e-10_wp
        character(len=len_name) :: check_solver = 'ddassl' !! '' or 'none': no check
        real(wp) :: check_tolerance = 0.0_wp  !! 0: the reference tolerance
        character(len=len_name), allocatable :: solvers(:)
        character(len=len_name), allocatable :: stabilisations(:)
        real(wp), allocatable :: tolerances(:)
        integer, allocatable :: pmax(:)
        character(len=len_name), allocatable :: derivatives(:)
        character(len=:), allocatable :: table            !! '' = no file, resolved
        integer :: cpu_reference = 1  !! the row whose CPU is 1 in the table
        real(wp) :: t_end = 0.0_wp    !! > 0: the scene's t_end for every run
        integer :: max_steps = 0      !! > 0: every run's step limit
        character(len=len_name) :: layout = 'table3' !! 'table3' or 'table2' (the table's)
    end type study_input_t

    type, public :: driver_input_t
        character(len=len_name) :: name = ''
        character(len=len_name) :: type = ''        !! 'angle' | 'translation' | 'distance'
        character(len=len_name) :: marker_i = '', marker_j = ''
        integer :: axis_i = 1, axis_j = 1
        real(wp) :: coefficients(4) = 0.0_wp        !! s = c0 + c1 t + c2 t² + c3 t³
        real(wp) :: amplitude = 0.0_wp              !! + a sin(ω t + φ)
        real(wp) :: frequency = 0.0_wp              !! ω [rad/s]
        real(wp) :: phase = 0.0_wp                  !! φ [rad]
        integer :: line = 0
    end type driver_input_t

    !> One `&rigid_chain` group: a body of a loop-free chain in relative
    !> coordinates and the joint to its parent (flexmbs_mbs_rigid_chain).
    type, public :: chain_body_input_t
        character(len=len_name) :: name = ''
        character(len=len_name) :: parent = 'ground'  !! 'ground' or an earlier body
        character(len=len_name) :: joint = 'revolute' !! 'revolute' | 'prismatic'
        real(wp) :: joint_position(3) = 0.0_wp        !! in the parent's frame [m]
        real(wp) :: joint_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp] !! parent's frame
        real(wp) :: centre(3) = 0.0_wp                !! centre of mass, own frame [m]
        real(wp) :: mass = 0.0_wp                     !! [kg], required
        real(wp) :: inertia(3) = 0.0_wp               !! about the centre of mass, required
        real(wp) :: inertia_products(3) = 0.0_wp
        real(wp) :: coordinate = 0.0_wp               !! initial q [rad or m]
        real(wp) :: rate = 0.0_wp                     !! initial q' [rad/s or m/s]
        !> spherical: initial relative rotation and angular velocity (own frame)
        real(wp) :: rotation_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]
        real(wp) :: rotation_angle = 0.0_wp
        real(wp) :: angular_rate(3) = 0.0_wp
        integer :: line = 0
    end type chain_body_input_t

    !> Everything a scene file says, with defaults for what it leaves out.
    type, public :: scene_input_t
        character(len=:), allocatable :: path !! the file read
        character(len=:), allocatable :: text !! its full text (stored in the HDF5 file)
        ! &simulation
        character(len=len_title) :: title = ''
        character(len=len_name) :: problem = ''
        real(wp) :: t_start = 0.0_wp          !! s
        real(wp) :: t_end = 0.0_wp            !! s, required, > t_start
        real(wp) :: vdp_eps = 1.0e-6_wp
        real(wp) :: vdp_y1 = 2.0_wp
        real(wp) :: vdp_y2 = -0.66_wp
        character(len=len_name) :: pendulum_formulation = 'index2'
        real(wp) :: pendulum_length = 1.0_wp  !! m
        real(wp) :: pendulum_mass = 1.0_wp    !! kg
        real(wp) :: pendulum_angle = half_pi  !! rad from the downward vertical, at rest
        logical :: pendulum_projection = .false. !! project onto both constraints
        real(wp) :: gravity = 9.81_wp         !! m/s²
        integer :: npoints = 100              !! grid points per direction (Brusselator)
        ! &solver
        character(len=len_name) :: solver_name = 'radau5'
        real(wp) :: rtol = 1.0e-6_wp
        real(wp) :: atol = 1.0e-6_wp
        real(wp) :: h0 = 0.0_wp               !! s, 0 = automatic
        real(wp) :: hmax = 0.0_wp             !! s, 0 = |t_end - t_start|
        integer :: max_steps = 100000
        character(len=len_name) :: linear_solver = 'auto'
        character(len=len_name) :: sparse_ordering = 'auto' !! KLU: 'auto' | 'amd' | 'nd'
        character(len=len_name) :: jacobian = 'analytic'
        integer :: nit = 7
        real(wp) :: thet = 0.001_wp
        real(wp) :: fnewt = 0.0_wp            !! 0 = the solver's default
        real(wp) :: quot1 = 1.0_wp
        real(wp) :: quot2 = 1.2_wp
        real(wp) :: safe = 0.9_wp
        real(wp) :: fac_min = 0.2_wp
        real(wp) :: fac_max = 8.0_wp
        character(len=len_name) :: controller = 'predictive'
        logical :: zero_start = .false.
        integer :: pmax = 5
        logical :: initial_derivative = .false. !! DDASSL: y' by DDAINI
        logical :: exclude_index23 = .true.     !! DDASSL: index-2/3 out of the error test
        logical :: netlib = .false.             !! DDASSL: later netlib revision
        integer :: max_extrapolation = 12       !! MEXAX: extrapolation columns (KDMAX), 2..12
        character(len=len_name) :: mexax_base = 'midpoint' !! MEXAX: 'midpoint' | 'euler'
        ! &output
        !> HDF5 file; '' = none. Derived from the input name when not given.
        character(len=:), allocatable :: output_file
        integer :: n_output = 101
        logical :: every_step = .false.
        character(len=len_path) :: table = ''
        logical :: progress = .true.
        !> ParaView files PREFIX_NNNN.vtu and PREFIX.pvd ('' = none)
        character(len=len_path) :: vtk = ''
        ! &flexible_body and &material
        logical :: has_body = .false.                 !! a &flexible_body group was given
        type(body_input_t) :: body
        type(material_input_t), allocatable :: materials(:) !! in the order given
        ! &multibody, &rigid_body, &marker, &joint, &driver
        logical :: has_multibody = .false.
        type(multibody_input_t) :: multibody
        type(rigid_body_input_t), allocatable :: rigid_bodies(:)
        type(marker_input_t), allocatable :: markers(:)
        type(joint_input_t), allocatable :: joints(:)
        type(driver_input_t), allocatable :: drivers(:)
        ! &rigid_chain
        type(chain_body_input_t), allocatable :: chain(:)
    end type scene_input_t

    !> One value of a variable's list.
    type :: item_t
        character(len=:), allocatable :: text
        logical :: quoted = .false.
    end type item_t

    !> One `name = value[, value ...]` of the text; `value` is the list as
    !> written (for messages), `items` its values.
    type :: entry_t
        character(len=:), allocatable :: group, name, value
        integer :: line = 0
        logical :: quoted = .false.
        integer :: instance = 1  !! which occurrence of a repeatable group
        type(item_t), allocatable :: items(:)
    end type entry_t

    !> Text span [first, last] of one group, from '&name' to its closing '/'.
    type :: span_t
        integer :: group = 0     !! index in group_names
        integer :: instance = 1  !! occurrence of that group
        integer :: first = 0, last = 0
        integer :: line = 0      !! line of '&name'
    end type span_t

    public :: read_scene, parse_scene, scene_dae_options, controller_code, read_study, &
        parse_study

contains

    !> Read and validate a scene file. A missing file is bad input; a file
    !> that exists but cannot be read is an I/O error.
    subroutine read_scene(path, scene, status)
        character(len=*), intent(in) :: path      !! scene file
        type(scene_input_t), intent(out) :: scene !! defaults plus the file's values
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        call read_text_file(path, text, status)
        if (.not. status%ok()) return
        call parse_scene(text, path, scene, status)
    end subroutine read_scene

    !> Validate and read scene text; `path` is used in messages and for the
    !> default output name.
    subroutine parse_scene(text, path, scene, status)
        character(len=*), intent(in) :: text      !! the whole file
        character(len=*), intent(in) :: path      !! where it came from
        type(scene_input_t), intent(out) :: scene
        type(status_t), intent(out) :: status
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        character(len=:), allocatable :: clean
        integer :: i, g

        scene%path = path
        scene%text = text
        call tokenise(text, path, entries, spans, clean, status)
        if (.not. status%ok()) return
        call check_types(entries, path, status)
        if (.not. status%ok()) return
        if (any(spans%group == find_group('study'))) then
            call status%set(status_bad_input, path // ': &study: belongs in a study file ' // &
                '(flexmbs reference, flexmbs sweep), not in a scene' // &
                at(spans(findloc(spans%group, find_group('study'), dim=1))%line))
            return
        end if
        allocate (scene%materials(count(spans%group == find_group('material'))), &
                  scene%rigid_bodies(count(spans%group == find_group('rigid_body'))), &
                  scene%markers(count(spans%group == find_group('marker'))), &
                  scene%joints(count(spans%group == find_group('joint'))), &
                  scene%drivers(count(spans%group == find_group('driver'))), &
                  scene%chain(count(spans%group == find_group('rigid_chain'))))
        do i = 1, size(spans)
            g = spans(i)%group
            associate (group_text => clean(spans(i)%first:spans(i)%last))
                select case (trim(group_names(g)))
                case ('flexible_body')
                    scene%has_body = .true.
                    scene%body%line = spans(i)%line
                    call read_body_group(group_text, path, scene%body, status)
                case ('material')
                    scene%materials(spans(i)%instance)%line = spans(i)%line
                    call read_material_group(group_text, path, &
                                             scene%materials(spans(i)%instance), status)
                case ('multibody')
                    scene%has_multibody = .true.
                    scene%multibody%line = spans(i)%line
                    call read_multibody_group(group_text, path, scene%multibody, status)
                case ('rigid_body')
                    scene%rigid_bodies(spans(i)%instance)%line = spans(i)%line
                    call read_rigid_body_group(group_text, path, &
                                               scene%rigid_bodies(spans(i)%instance), status)
                case ('marker')
                    scene%markers(spans(i)%instance)%line = spans(i)%line
                    call read_marker_group(group_text, path, scene%markers(spans(i)%instance), &
                                           status)
                case ('joint')
                    scene%joints(spans(i)%instance)%line = spans(i)%line
                    call read_joint_group(group_text, path, scene%joints(spans(i)%instance), &
                                          status)
                case ('rigid_chain')
                    scene%chain(spans(i)%instance)%line = spans(i)%line
                    call read_chain_group(group_text, path, scene%chain(spans(i)%instance), &
                                          status)
                case ('driver')
                    scene%drivers(spans(i)%instance)%line = spans(i)%line
                    call read_driver_group(group_text, path, scene%drivers(spans(i)%instance), &
                                           status)
                case default
                    call read_group(group_text, trim(group_names(g)), path, scene, status)
                end select
            end associate
            if (.not. status%ok()) return
        end do
        call normalise(scene, entries)
        call check_ranges(scene, entries, path, status)
        if (.not. status%ok()) return
        call check_body(scene, entries, path, status)
        if (.not. status%ok()) return
        call check_multibody(scene, entries, path, status)
        if (.not. status%ok()) return
        call check_chain(scene, entries, path, status)
        if (.not. status%ok()) return
        call resolve_output(scene, entries, path, status)
    end subroutine parse_scene

    !> Read a study file (see study_input_t).
    subroutine read_study(path, study, status)
        character(len=*), intent(in) :: path
        type(study_input_t), intent(out) :: study
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        call read_text_file(path, text, status)
        if (.not. status%ok()) return
        call parse_study(text, path, study, status)
    end subroutine read_study

    !> Validate and read a study's text: exactly one `&study` group; paths
    !> in it are relative to the study file's folder.
    subroutine parse_study(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(study_input_t), intent(out) :: input
        type(status_t), intent(out) :: status
        character(len=8), parameter :: solver_choices(4) = [character(len=8) :: 'radau5', &
            'ddassl', 'ida', 'mexax']
        character(len=10), parameter :: stab_choices(3) = [character(len=10) :: 'none', &
            'ggl', 'projection']
        character(len=8), parameter :: derivative_choices(3) = [character(len=8) :: &
            'analytic', 'ad', 'ad_full']
        type(entry_t), allocatable :: entries(:)
        type(span_t), allocatable :: spans(:)
        character(len=:), allocatable :: clean, lines(:), dir, where
        character(len=len_path) :: scene, reference_file, table
        character(len=len_name) :: reference_solver, check_solver, &
            solvers(max_study_solvers), stabilisations(3), derivatives(3), layout
        real(wp) :: reference_tolerance, check_tolerance, tolerances(max_study_tolerances), t_end
        integer :: pmax(5), cpu_reference, max_steps, ios, i
        character(len=256) :: msg
        namelist /study/ scene, reference_file, reference_solver, reference_tolerance, &
            check_solver, check_tolerance, solvers, stabilisations, tolerances, pmax, &
            derivatives, table, cpu_reference, t_end, max_steps, layout

        input%path = path
        call tokenise(text, path, entries, spans, clean, status)
        if (.not. status%ok()) return
        call check_types(entries, path, status)
        if (.not. status%ok()) return
        do i = 1, size(spans)
            if (group_names(spans(i)%group) /= 'study') then
                call status%set(status_bad_input, path // ': &' // &
                    trim(group_names(spans(i)%group)) // ': a study file holds only &study &
                    &(its scene = names the scene file)' // at(spans(i)%line))
                return
            end if
        end do
        if (size(spans) /= 1) then
            call status%set(status_bad_input, path // ': needs one &study group')
            return
        end if
        where = path // ': &study: '
        scene = ''
        reference_file = ''
        table = ''
        reference_solver = input%reference_solver
        reference_tolerance = input%reference_tolerance
        check_solver = input%check_solver
        check_tolerance = 0.0_wp
        t_end = 0.0_wp
        max_steps = 0
        layout = input%layout
        solvers = ''
        stabilisations = ''
        derivatives = ''
        tolerances = -1.0_wp
        pmax = 0
        cpu_reference = input%cpu_reference
        lines = split_lines(clean(spans(1)%first:spans(1)%last))
        msg = ''
        read (lines, nml=study, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call status%set(status_bad_input, path // ': &study: ' // trim(msg))
            return
        end if
        input%reference_solver = reference_solver
        input%reference_tolerance = reference_tolerance
        input%check_solver = check_solver
        if (input%check_solver == 'none') input%check_solver = ''
        input%check_tolerance = check_tolerance
        input%t_end = t_end
        input%max_steps = max_steps
        input%layout = layout
        if (input%check_tolerance == 0.0_wp) input%check_tolerance = reference_tolerance
        input%cpu_reference = cpu_reference
        input%solvers = pack(solvers, solvers /= '')
        if (size(input%solvers) == 0) input%solvers = [character(len=len_name) :: 'radau5', &
            'ddassl', 'ida', 'mexax']
        input%stabilisations = pack(stabilisations, stabilisations /= '')
        if (size(input%stabilisations) == 0) input%stabilisations = &
            [character(len=len_name) :: 'none', 'ggl']
        input%derivatives = pack(derivatives, derivatives /= '')
        if (size(input%derivatives) == 0) input%derivatives = [character(len=len_name) :: &
            'analytic']
        input%tolerances = pack(tolerances, tolerances /= -1.0_wp)
        if (size(input%tolerances) == 0) input%tolerances = [1.0e-6_wp]
        input%pmax = pack(pmax, pmax /= 0)
        if (size(input%pmax) == 0) input%pmax = [5]

        if (len_trim(scene) == 0) then
            call status%set(status_bad_input, where // 'scene: required (the scene file)')
        else if (.not. any(solver_choices == input%reference_solver)) then
            call status%set(status_bad_input, where // 'reference_solver = ''' // &
                trim(input%reference_solver) // ''': must be one of ' // choices(solver_choices))
        else if (len_trim(input%check_solver) > 0 .and. &
                 .not. any(solver_choices == input%check_solver)) then
            call status%set(status_bad_input, where // 'check_solver = ''' // &
                trim(input%check_solver) // ''': must be one of ' // &
                choices(solver_choices) // ', or ''none''')
        else if (.not. (input%reference_tolerance > 0.0_wp .and. &
                        input%reference_tolerance < 1.0_wp)) then
            call status%set(status_bad_input, where // 'reference_tolerance: must lie in (0, 1)')
        else if (.not. (input%check_tolerance > 0.0_wp .and. input%check_tolerance < 1.0_wp)) &
            then
            call status%set(status_bad_input, where // 'check_tolerance: must lie in (0, 1)')
        else if (input%layout /= 'table3' .and. input%layout /= 'table2') then
            call status%set(status_bad_input, where // 'layout = ''' // trim(input%layout) // &
                ''': must be ''table3'' or ''table2''')
        else if (input%max_steps < 0) then
            call status%set(status_bad_input, where // 'max_steps: must be positive (0: the &
                &scene''s)')
        else if (input%t_end < 0.0_wp) then
            call status%set(status_bad_input, where // 't_end: must be positive (0: the scene''s)')
        else if (input%cpu_reference < 1) then
            call status%set(status_bad_input, where // 'cpu_reference: must be a row, >= 1')
        end if
        if (.not. status%ok()) return
        do i = 1, size(input%solvers)
            if (.not. any(solver_choices == input%solvers(i))) then
                call status%set(status_bad_input, where // 'solvers: ''' // &
                    trim(input%solvers(i)) // ''': must be one of ' // choices(solver_choices))
                return
            end if
        end do
        do i = 1, size(input%stabilisations)
            if (.not. any(stab_choices == input%stabilisations(i))) then
                call status%set(status_bad_input, where // 'stabilisations: ''' // &
                    trim(input%stabilisations(i)) // ''': must be one of ' // &
                    choices(stab_choices))
                return
            end if
        end do
        do i = 1, size(input%derivatives)
            if (.not. any(derivative_choices == input%derivatives(i))) then
                call status%set(status_bad_input, where // 'derivatives: ''' // &
                    trim(input%derivatives(i)) // ''': must be one of ' // &
                    choices(derivative_choices))
                return
            end if
        end do
        if (any(.not. (input%tolerances > 0.0_wp .and. input%tolerances < 1.0_wp))) then
            call status%set(status_bad_input, where // 'tolerances: each must lie in (0, 1)')
            return
        end if
        if (any(input%pmax < 1 .or. input%pmax > 5)) then
            call status%set(status_bad_input, where // 'pmax: each must be 1 .. 5')
            return
        end if
        ! paths relative to the study's folder
        dir = ''
        if (index(path, '/', back=.true.) > 0) dir = path(1:index(path, '/', back=.true.))
        input%scene = relative(trim(scene))
        if (len_trim(reference_file) > 0) then
            input%reference_file = relative(trim(reference_file))
        else
            i = index(path, '.', back=.true.)
            if (i <= index(path, '/', back=.true.)) i = len(path) + 1
            input%reference_file = path(1:i - 1) // '_reference.h5'
        end if
        input%table = ''
        if (len_trim(table) > 0) then
            input%table = relative(trim(table))
            i = index(input%table, '.', back=.true.)
            if (i == 0) i = len(input%table)
            if (all([character(len=4) :: 'md', 'csv', 'tex'] /= input%table(i + 1:))) then
                call status%set(status_bad_input, where // 'table = ''' // trim(table) // &
                    ''': the name must end in .md, .csv or .tex (the format)')
                return
            end if
        end if

    contains

        function relative(name) result(full)
            character(len=*), intent(in) :: name
            character(len=:), allocatable :: full
            full = name
            if (name(1:1) /= '/') full = dir // name
        end function relative
    end subroutine parse_study

    ! ------------------------------------------------------------------
    ! Tokenising: find groups, names and raw values, with line numbers.
    ! ------------------------------------------------------------------

    !> Walk the text; return the `name = value` entries, each group's span
    !> in `clean` (the text with comments blanked, same length).
    subroutine tokenise(text, path, entries, spans, clean, status)
        character(len=*), intent(in) :: text, path
        type(entry_t), allocatable, intent(out) :: entries(:)
        type(span_t), allocatable, intent(out) :: spans(:)
        character(len=:), allocatable, intent(out) :: clean
        type(status_t), intent(inout) :: status
        integer :: pos, line, g, n, first, first_line, vline, instance, spec
        character(len=:), allocatable :: word, group, name, value, previous
        logical :: quoted
        type(item_t), allocatable :: items(:)

        allocate (entries(0), spans(0))
        clean = blank_comments(text)
        n = len(clean)
        pos = 1
        line = 1
        do
            ! outside any group
            call skip_blank(clean, pos, line)
            if (pos > n) exit
            if (clean(pos:pos) /= '&') then
                word = bare_word(clean, pos)
                call status%set(status_bad_input, path // ': unexpected text ''' // word // &
                    ''' outside a group (groups start with &name and end with /)' // at(line))
                return
            end if
            first = pos
            first_line = line
            pos = pos + 1
            group = lower(name_word(clean, pos))
            g = find_group(group)
            if (g == 0) then
                call status%set(status_bad_input, path // ': &' // group // &
                    ': unknown group (expected &simulation, &solver, &output, &
                    &&flexible_body, &material, &multibody, &rigid_body, &marker, &joint, &
                    &&driver or &rigid_chain)' // at(line))
                return
            end if
            instance = count(spans%group == g) + 1
            if (instance > 1 .and. group == 'flexible_body') then
                call status%set(status_bad_input, path // ': &' // group // &
                    ': group given more than once (one flexible body per scene for now)' &
                    // at(line))
                return
            else if (instance > 1 .and. all(repeatable_groups /= group)) then
                call status%set(status_bad_input, path // ': &' // group // &
                    ': group given more than once' // at(line))
                return
            end if
            previous = ''
            do
                ! inside group `group`
                call skip_blank(clean, pos, line)
                if (pos > n) then
                    call status%set(status_bad_input, path // ': &' // group // &
                        ': not closed by ''/''' // at(line))
                    return
                end if
                if (clean(pos:pos) == '/') then
                    pos = pos + 1
                    exit
                end if
                if (clean(pos:pos) == '&') then
                    pos = pos + 1
                    word = lower(name_word(clean, pos))
                    if (word == 'end') exit
                    call status%set(status_bad_input, path // ': &' // group // &
                        ': not closed by ''/'' before &' // word // at(line))
                    return
                end if
                if (clean(pos:pos) == ',' .and. len(previous) > 0) then
                    pos = pos + 1
                    cycle
                end if
                if (.not. is_letter(clean(pos:pos))) then
                    word = bare_word(clean, pos)
                    if (len(previous) > 0) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            previous // ': unexpected ''' // word // &
                            ''' after its value (one value per variable)' // at(line))
                    else
                        call status%set(status_bad_input, path // ': &' // group // &
                            ': unexpected ''' // word // ''' (expected name = value)' // at(line))
                    end if
                    return
                end if
                name = lower(variable_word(clean, pos))
                if (find_var(group, name) == 0) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': unknown variable (known: ' // known_vars(group) // ')' // at(line))
                    return
                end if
                if (has_entry(entries, group, name, instance)) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': given more than once' // at(line))
                    return
                end if
                call skip_blank(clean, pos, line)
                if (pos > n) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': expected ''='' after the name' // at(line))
                    return
                end if
                if (clean(pos:pos) /= '=') then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': expected ''='' after the name' // at(line))
                    return
                end if
                pos = pos + 1
                call skip_blank(clean, pos, line)
                vline = line
                if (pos > n) then
                    value = ''
                else if (scan(clean(pos:pos), ',/&') > 0) then
                    value = ''
                else
                    call value_word(clean, pos, value, quoted, status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ' = ' // value // ': unterminated string' // at(vline))
                        return
                    end if
                end if
                if (len(value) == 0) then
                    call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                        ': has no value' // at(vline))
                    return
                end if
                items = [item_t(value, quoted)]
                spec = find_var(group, name)
                if (schema(spec)%count > 1) then
                    call more_values(clean, pos, line, items, status)
                    value = joined(items)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ' = ' // value // ': unterminated string' // at(vline))
                        return
                    end if
                    if (schema(spec)%kind /= kind_string .and. .not. schema(spec)%list .and. &
                        size(items) /= schema(spec)%count) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ' = ' // value // ': needs ' // itoa(schema(spec)%count) &
                            // ' values' // at(vline))
                        return
                    else if (size(items) > schema(spec)%count) then
                        call status%set(status_bad_input, path // ': &' // group // ': ' // &
                            name // ' = ' // value // ': at most ' // &
                            itoa(schema(spec)%count) // ' values' // at(vline))
                        return
                    end if
                end if
                entries = [entries, entry_t(group, name, value, vline, &
                                            all(items%quoted), instance, items)]
                previous = name
            end do
            spans = [spans, span_t(g, instance, first, pos - 1, first_line)]
        end do
    end subroutine tokenise

    !> Further values of an array variable: each a quoted string or a token
    !> starting like a number, after blanks or a comma. Stops (leaving pos
    !> at the comma) before anything else, e.g. the next `name =`.
    subroutine more_values(text, pos, line, items, status)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line
        type(item_t), allocatable, intent(inout) :: items(:)
        type(status_t), intent(inout) :: status
        integer :: p, l
        character(len=:), allocatable :: value
        logical :: quoted
        do
            p = pos
            l = line
            call skip_blank(text, p, l)
            if (p <= len(text)) then
                if (text(p:p) == ',') then
                    p = p + 1
                    call skip_blank(text, p, l)
                end if
            end if
            if (p > len(text)) return
            if (scan(text(p:p), '0123456789+-.''"') == 0) return
            pos = p
            line = l
            call value_word(text, pos, value, quoted, status)
            items = [items, item_t(value, quoted)]
            if (.not. status%ok()) return
        end do
    end subroutine more_values

    !> The values of a list as one text, for messages.
    pure function joined(items) result(text)
        type(item_t), intent(in) :: items(:)
        character(len=:), allocatable :: text
        integer :: i
        text = items(1)%text
        do i = 2, size(items)
            text = text // ', ' // items(i)%text
        end do
    end function joined

    !> The text with every comment ('!' outside a string, to the end of
    !> its line) replaced by blanks; positions and newlines are kept.
    pure function blank_comments(text) result(clean)
        character(len=*), intent(in) :: text
        character(len=len(text)) :: clean
        integer :: i
        character :: quote
        logical :: comment
        clean = text
        quote = ' '
        comment = .false.
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                comment = .false.
                quote = ' '
            else if (comment) then
                clean(i:i) = ' '
            else if (quote /= ' ') then
                if (text(i:i) == quote) quote = ' '
            else if (text(i:i) == '''' .or. text(i:i) == '"') then
                quote = text(i:i)
            else if (text(i:i) == '!') then
                comment = .true.
                clean(i:i) = ' '
            end if
        end do
    end function blank_comments

    !> Skip blanks, tabs, carriage returns and newlines, counting lines.
    pure subroutine skip_blank(text, pos, line)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos, line
        do while (pos <= len(text))
            if (text(pos:pos) == new_line('a')) then
                line = line + 1
            else if (.not. is_space(text(pos:pos))) then
                exit
            end if
            pos = pos + 1
        end do
    end subroutine skip_blank

    !> A Fortran name (letters, digits, '_') starting at pos.
    function name_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable :: word
        integer :: start
        start = pos
        do while (pos <= len(text))
            if (.not. (is_letter(text(pos:pos)) .or. is_digit(text(pos:pos)) &
                       .or. text(pos:pos) == '_')) exit
            pos = pos + 1
        end do
        word = text(start:pos - 1)
    end function name_word

    !> A variable designator: a name, possibly with a subscript or
    !> component, so that `y0(1)` is reported whole as unknown.
    function variable_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable :: word
        integer :: start
        start = pos
        do while (pos <= len(text))
            if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
            if (scan(text(pos:pos), '=,/&''"') > 0) exit
            pos = pos + 1
        end do
        word = text(start:pos - 1)
    end function variable_word

    !> Anything up to the next separator (for messages about stray text).
    function bare_word(text, pos) result(word)
        character(len=*), intent(in) :: text
        integer, intent(in) :: pos
        character(len=:), allocatable :: word
        integer :: last
        last = pos
        do while (last < len(text))
            if (is_space(text(last + 1:last + 1)) .or. text(last + 1:last + 1) == new_line('a') &
                .or. scan(text(last + 1:last + 1), ',/=') > 0) exit
            last = last + 1
        end do
        word = text(pos:last)
    end function bare_word

    !> One value: a quoted string (quotes doubled inside) or a bare token
    !> ending at a blank, ',', '/' or end of line. Sets status (message
    !> filled by the caller) when a string is not closed on its line.
    subroutine value_word(text, pos, value, quoted, status)
        character(len=*), intent(in) :: text
        integer, intent(inout) :: pos
        character(len=:), allocatable, intent(out) :: value
        logical, intent(out) :: quoted
        type(status_t), intent(inout) :: status
        integer :: start
        character :: quote
        start = pos
        quoted = text(pos:pos) == '''' .or. text(pos:pos) == '"'
        if (quoted) then
            quote = text(pos:pos)
            pos = pos + 1
            do
                if (pos > len(text)) exit
                if (text(pos:pos) == new_line('a')) exit
                if (text(pos:pos) == quote) then
                    if (pos < len(text)) then
                        if (text(pos + 1:pos + 1) == quote) then
                            pos = pos + 2
                            cycle
                        end if
                    end if
                    pos = pos + 1
                    value = text(start:pos - 1)
                    return
                end if
                pos = pos + 1
            end do
            value = text(start:pos - 1)
            call status%set(status_bad_input, 'unterminated string')
            return
        end if
        do while (pos <= len(text))
            if (is_space(text(pos:pos)) .or. text(pos:pos) == new_line('a')) exit
            if (scan(text(pos:pos), ',/') > 0) exit
            pos = pos + 1
        end do
        value = text(start:pos - 1)
    end subroutine value_word

    ! ------------------------------------------------------------------
    ! Types: check each raw value against its variable's kind.
    ! ------------------------------------------------------------------

    subroutine check_types(entries, path, status)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: i, j, k
        character(len=:), allocatable :: reason

        do i = 1, size(entries)
            associate (e => entries(i))
                k = schema(find_var(e%group, e%name))%kind
                do j = 1, size(e%items)
                    reason = type_reason(k, e%name, e%items(j))
                    if (len(reason) == 0) cycle
                    ! in a list, say which value is wrong
                    if (size(e%items) > 1) reason = 'value ' // itoa(j) // ' (' // &
                        e%items(j)%text // ') ' // reason
                    call fail(status, path, e, reason)
                    return
                end do
            end associate
        end do
    end subroutine check_types

    !> Why one value does not fit the kind of variable `name` ('' if it does).
    function type_reason(kind, name, item) result(reason)
        integer, intent(in) :: kind
        character(len=*), intent(in) :: name
        type(item_t), intent(in) :: item
        character(len=:), allocatable :: reason
        integer :: ios, m
        real(wp) :: x
        type(ieee_status_type) :: fp_status
        reason = ''
        select case (kind)
        case (kind_string)
            if (.not. item%quoted) then
                reason = 'must be a quoted string, e.g. ' // name // ' = ''' // item%text // ''''
            else if (len(unquote(item%text)) > string_length(name)) then
                reason = 'longer than ' // itoa(string_length(name)) // ' characters'
            end if
        case (kind_real)
            if (item%quoted .or. .not. is_real_text(item%text)) then
                reason = 'must be a real number'
            else
                ! an overflowing value must not leave the overflow flag raised
                call ieee_get_status(fp_status)
                read (item%text, *, iostat=ios) x
                call ieee_set_status(fp_status)
                if (ios /= 0) then
                    reason = 'is out of the range of real numbers'
                else if (.not. ieee_is_finite(x)) then
                    reason = 'is out of the range of real numbers'
                end if
            end if
        case (kind_integer)
            if (item%quoted .or. .not. is_integer_text(item%text)) then
                reason = 'must be an integer'
            else
                read (item%text, *, iostat=ios) m
                if (ios /= 0) reason = 'is out of the range of integers'
            end if
        case (kind_logical)
            if (item%quoted .or. .not. is_logical_text(item%text)) then
                reason = 'must be .true. or .false.'
            end if
        end select
    end function type_reason

    pure logical function is_integer_text(s)
        character(len=*), intent(in) :: s
        integer :: i, start
        is_integer_text = .false.
        start = 1
        if (len(s) == 0) return
        if (s(1:1) == '+' .or. s(1:1) == '-') start = 2
        if (start > len(s)) return
        do i = start, len(s)
            if (.not. is_digit(s(i:i))) return
        end do
        is_integer_text = .true.
    end function is_integer_text

    !> [sign] digits [. digits] [e|d [sign] digits], at least one mantissa digit.
    pure logical function is_real_text(s)
        character(len=*), intent(in) :: s
        integer :: i, ndig
        is_real_text = .false.
        i = 1
        ndig = 0
        if (len(s) == 0) return
        if (s(1:1) == '+' .or. s(1:1) == '-') i = 2
        do while (i <= len(s))
            if (.not. is_digit(s(i:i))) exit
            ndig = ndig + 1
            i = i + 1
        end do
        if (i <= len(s)) then
            if (s(i:i) == '.') then
                i = i + 1
                do while (i <= len(s))
                    if (.not. is_digit(s(i:i))) exit
                    ndig = ndig + 1
                    i = i + 1
                end do
            end if
        end if
        if (ndig == 0) return
        if (i <= len(s)) then
            if (index('eEdD', s(i:i)) == 0) return
            i = i + 1
            if (i <= len(s)) then
                if (s(i:i) == '+' .or. s(i:i) == '-') i = i + 1
            end if
            if (i > len(s)) return
            do while (i <= len(s))
                if (.not. is_digit(s(i:i))) return
                i = i + 1
            end do
        end if
        is_real_text = .true.
    end function is_real_text

    pure logical function is_logical_text(s)
        character(len=*), intent(in) :: s
        character(len=8), parameter :: forms(*) = [character(len=8) :: '.true.', '.false.', &
            '.t.', '.f.', '.t', '.f', 't', 'f', 'true', 'false']
        is_logical_text = any(forms == lower(s))
    end function is_logical_text

    !> Declared length of a string variable.
    pure integer function string_length(name)
        character(len=*), intent(in) :: name
        select case (name)
        case ('title'); string_length = len_title
        case ('file', 'table', 'mesh_file', 'scene', 'reference_file', 'vtk')
            string_length = len_path
        case default; string_length = len_name
        end select
    end function string_length

    ! ------------------------------------------------------------------
    ! Reading: the validated text of one group through namelist I/O.
    ! ------------------------------------------------------------------

    subroutine read_group(text, group, path, scene, status)
        character(len=*), intent(in) :: text  !! '&group ... /', comments blanked
        character(len=*), intent(in) :: group, path
        type(scene_input_t), intent(inout) :: scene
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        ! Namelist variables carry the schema's names, so they are local.
        character(len=len_title) :: title
        character(len=len_name) :: problem, pendulum_formulation, name, linear_solver, &
            jacobian, controller, mexax_base, sparse_ordering
        character(len=len_path) :: file, table, vtk
        real(wp) :: t_start, t_end, vdp_eps, vdp_y1, vdp_y2, pendulum_length, pendulum_mass, &
            pendulum_angle, gravity, rtol, atol, h0, hmax, thet, fnewt, &
            quot1, quot2, safe, fac_min, fac_max
        integer :: npoints, max_steps, nit, pmax, n_output, max_extrapolation
        logical :: pendulum_projection, zero_start, every_step, progress
        logical :: initial_derivative, exclude_index23, netlib
        namelist /simulation/ title, problem, t_start, t_end, vdp_eps, vdp_y1, vdp_y2, &
            pendulum_formulation, pendulum_length, pendulum_mass, pendulum_angle, &
            pendulum_projection, gravity, npoints
        namelist /solver/ name, rtol, atol, h0, hmax, max_steps, linear_solver, &
            sparse_ordering, jacobian, &
            nit, thet, fnewt, quot1, quot2, safe, fac_min, fac_max, controller, zero_start, pmax, &
            initial_derivative, exclude_index23, netlib, max_extrapolation, mexax_base
        namelist /output/ file, n_output, every_step, table, progress, vtk

        lines = split_lines(text)
        ios = 0
        msg = ''
        select case (group)
        case ('simulation')
            title = scene%title
            problem = scene%problem
            t_start = scene%t_start
            t_end = scene%t_end
            vdp_eps = scene%vdp_eps
            vdp_y1 = scene%vdp_y1
            vdp_y2 = scene%vdp_y2
            pendulum_formulation = scene%pendulum_formulation
            pendulum_length = scene%pendulum_length
            pendulum_mass = scene%pendulum_mass
            pendulum_angle = scene%pendulum_angle
            pendulum_projection = scene%pendulum_projection
            gravity = scene%gravity
            npoints = scene%npoints
            read (lines, nml=simulation, iostat=ios, iomsg=msg)
            scene%title = title
            scene%problem = problem
            scene%t_start = t_start
            scene%t_end = t_end
            scene%vdp_eps = vdp_eps
            scene%vdp_y1 = vdp_y1
            scene%vdp_y2 = vdp_y2
            scene%pendulum_formulation = pendulum_formulation
            scene%pendulum_length = pendulum_length
            scene%pendulum_mass = pendulum_mass
            scene%pendulum_angle = pendulum_angle
            scene%pendulum_projection = pendulum_projection
            scene%gravity = gravity
            scene%npoints = npoints
        case ('solver')
            name = scene%solver_name
            rtol = scene%rtol
            atol = scene%atol
            h0 = scene%h0
            hmax = scene%hmax
            max_steps = scene%max_steps
            linear_solver = scene%linear_solver
            sparse_ordering = scene%sparse_ordering
            jacobian = scene%jacobian
            nit = scene%nit
            thet = scene%thet
            fnewt = scene%fnewt
            quot1 = scene%quot1
            quot2 = scene%quot2
            safe = scene%safe
            fac_min = scene%fac_min
            fac_max = scene%fac_max
            controller = scene%controller
            zero_start = scene%zero_start
            pmax = scene%pmax
            initial_derivative = scene%initial_derivative
            exclude_index23 = scene%exclude_index23
            netlib = scene%netlib
            max_extrapolation = scene%max_extrapolation
            mexax_base = scene%mexax_base
            read (lines, nml=solver, iostat=ios, iomsg=msg)
            scene%solver_name = name
            scene%rtol = rtol
            scene%atol = atol
            scene%h0 = h0
            scene%hmax = hmax
            scene%max_steps = max_steps
            scene%linear_solver = linear_solver
            scene%sparse_ordering = sparse_ordering
            scene%jacobian = jacobian
            scene%nit = nit
            scene%thet = thet
            scene%fnewt = fnewt
            scene%quot1 = quot1
            scene%quot2 = quot2
            scene%safe = safe
            scene%fac_min = fac_min
            scene%fac_max = fac_max
            scene%controller = controller
            scene%zero_start = zero_start
            scene%pmax = pmax
            scene%initial_derivative = initial_derivative
            scene%exclude_index23 = exclude_index23
            scene%netlib = netlib
            scene%max_extrapolation = max_extrapolation
            scene%mexax_base = mexax_base
        case ('output')
            file = ''
            n_output = scene%n_output
            every_step = scene%every_step
            table = scene%table
            progress = scene%progress
            vtk = scene%vtk
            read (lines, nml=output, iostat=ios, iomsg=msg)
            scene%output_file = trim(file)
            scene%n_output = n_output
            scene%every_step = every_step
            scene%table = table
            scene%progress = progress
            scene%vtk = vtk
        end select
        if (ios /= 0) then
            ! Not expected after validation; report what the compiler says.
            call status%set(status_bad_input, path // ': &' // group // ': ' // trim(msg))
        end if
    end subroutine read_group

    !> `&flexible_body` through namelist I/O; defaults are the current values.
    subroutine read_body_group(text, path, body, status)
        character(len=*), intent(in) :: text  !! '&flexible_body ... /', comments blanked
        character(len=*), intent(in) :: path
        type(body_input_t), intent(inout) :: body
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, element, load_set, formulation
        character(len=len_name) :: fixed(max_fixed_sets)
        character(len=len_path) :: mesh_file
        integer :: divisions(3)
        real(wp), dimension(3) :: lengths, origin, load, gravity, initial_velocity, &
            initial_angular_velocity
        namelist /flexible_body/ name, element, mesh_file, divisions, lengths, origin, fixed, &
            load_set, load, gravity, initial_velocity, initial_angular_velocity, formulation

        name = body%name
        element = body%element
        mesh_file = body%mesh_file
        divisions = body%divisions
        lengths = body%lengths
        origin = body%origin
        fixed = body%fixed
        load_set = body%load_set
        load = body%load
        gravity = body%gravity
        initial_velocity = body%initial_velocity
        initial_angular_velocity = body%initial_angular_velocity
        formulation = body%formulation
        msg = ''
        lines = split_lines(text)
        read (lines, nml=flexible_body, iostat=ios, iomsg=msg)
        body%name = name
        body%element = element
        body%mesh_file = mesh_file
        body%divisions = divisions
        body%lengths = lengths
        body%origin = origin
        body%fixed = fixed
        body%load_set = load_set
        body%load = load
        body%gravity = gravity
        body%initial_velocity = initial_velocity
        body%initial_angular_velocity = initial_angular_velocity
        body%formulation = formulation
        ! Not expected after validation; report what the compiler says.
        if (ios /= 0) call status%set(status_bad_input, path // ': &flexible_body: ' // trim(msg))
    end subroutine read_body_group

    !> One `&material` through namelist I/O.
    subroutine read_material_group(text, path, input, status)
        character(len=*), intent(in) :: text  !! '&material ... /', comments blanked
        character(len=*), intent(in) :: path
        type(material_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, elements
        real(wp) :: youngs_modulus, poisson_ratio, density, viscosity
        namelist /material/ name, youngs_modulus, poisson_ratio, density, viscosity, elements

        name = input%name
        youngs_modulus = input%youngs_modulus
        poisson_ratio = input%poisson_ratio
        density = input%density
        viscosity = input%viscosity
        elements = input%elements
        msg = ''
        lines = split_lines(text)
        read (lines, nml=material, iostat=ios, iomsg=msg)
        input%name = name
        input%youngs_modulus = youngs_modulus
        input%poisson_ratio = poisson_ratio
        input%density = density
        input%viscosity = viscosity
        input%elements = elements
        if (ios /= 0) call status%set(status_bad_input, path // ': &material: ' // trim(msg))
    end subroutine read_material_group

    !> `&multibody` through namelist I/O.
    subroutine read_multibody_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(multibody_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: formulation, constraint_derivatives
        real(wp) :: gravity(3)
        logical :: projection
        namelist /multibody/ formulation, gravity, constraint_derivatives, projection
        formulation = input%formulation
        gravity = input%gravity
        constraint_derivatives = input%constraint_derivatives
        projection = input%projection
        msg = ''
        lines = split_lines(text)
        read (lines, nml=multibody, iostat=ios, iomsg=msg)
        input%formulation = formulation
        input%gravity = gravity
        input%constraint_derivatives = constraint_derivatives
        input%projection = projection
        if (ios /= 0) call status%set(status_bad_input, path // ': &multibody: ' // trim(msg))
    end subroutine read_multibody_group

    !> One `&rigid_body` through namelist I/O.
    subroutine read_rigid_body_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(rigid_body_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name
        real(wp) :: mass, rotation_angle
        real(wp), dimension(3) :: inertia, inertia_products, position, rotation_axis, velocity, &
            angular_velocity
        namelist /rigid_body/ name, mass, inertia, inertia_products, position, rotation_axis, &
            rotation_angle, velocity, angular_velocity
        name = input%name
        mass = input%mass
        inertia = input%inertia
        inertia_products = input%inertia_products
        position = input%position
        rotation_axis = input%rotation_axis
        rotation_angle = input%rotation_angle
        velocity = input%velocity
        angular_velocity = input%angular_velocity
        msg = ''
        lines = split_lines(text)
        read (lines, nml=rigid_body, iostat=ios, iomsg=msg)
        input%name = name
        input%mass = mass
        input%inertia = inertia
        input%inertia_products = inertia_products
        input%position = position
        input%rotation_axis = rotation_axis
        input%rotation_angle = rotation_angle
        input%velocity = velocity
        input%angular_velocity = angular_velocity
        if (ios /= 0) call status%set(status_bad_input, path // ': &rigid_body: ' // trim(msg))
    end subroutine read_rigid_body_group

    !> One `&marker` through namelist I/O.
    subroutine read_marker_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(marker_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, body, node_set
        real(wp), dimension(3) :: position, z_axis, x_axis
        namelist /marker/ name, body, position, z_axis, x_axis, node_set
        name = input%name
        body = input%body
        position = huge(1.0_wp)   ! tells whether the group sets it
        z_axis = input%z_axis
        x_axis = input%x_axis
        node_set = input%node_set
        msg = ''
        lines = split_lines(text)
        read (lines, nml=marker, iostat=ios, iomsg=msg)
        input%name = name
        input%body = body
        input%position_given = any(position /= huge(1.0_wp))
        input%position = merge(position, input%position, position /= huge(1.0_wp))
        input%z_axis = z_axis
        input%x_axis = x_axis
        input%node_set = node_set
        if (ios /= 0) call status%set(status_bad_input, path // ': &marker: ' // trim(msg))
    end subroutine read_marker_group

    !> One `&joint` through namelist I/O.
    subroutine read_joint_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(joint_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, type, marker_i, marker_j
        namelist /joint/ name, type, marker_i, marker_j
        name = input%name
        type = input%type
        marker_i = input%marker_i
        marker_j = input%marker_j
        msg = ''
        lines = split_lines(text)
        read (lines, nml=joint, iostat=ios, iomsg=msg)
        input%name = name
        input%type = type
        input%marker_i = marker_i
        input%marker_j = marker_j
        if (ios /= 0) call status%set(status_bad_input, path // ': &joint: ' // trim(msg))
    end subroutine read_joint_group

    !> One `&driver` through namelist I/O.
    subroutine read_driver_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(driver_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, type, marker_i, marker_j
        integer :: axis_i, axis_j
        real(wp) :: coefficients(4), amplitude, frequency, phase
        namelist /driver/ name, type, marker_i, marker_j, axis_i, axis_j, coefficients, &
            amplitude, frequency, phase
        name = input%name
        type = input%type
        marker_i = input%marker_i
        marker_j = input%marker_j
        axis_i = input%axis_i
        axis_j = input%axis_j
        coefficients = input%coefficients
        amplitude = input%amplitude
        frequency = input%frequency
        phase = input%phase
        msg = ''
        lines = split_lines(text)
        read (lines, nml=driver, iostat=ios, iomsg=msg)
        input%name = name
        input%type = type
        input%marker_i = marker_i
        input%marker_j = marker_j
        input%axis_i = axis_i
        input%axis_j = axis_j
        input%coefficients = coefficients
        input%amplitude = amplitude
        input%frequency = frequency
        input%phase = phase
        if (ios /= 0) call status%set(status_bad_input, path // ': &driver: ' // trim(msg))
    end subroutine read_driver_group

    !> One `&rigid_chain` through namelist I/O.
    subroutine read_chain_group(text, path, input, status)
        character(len=*), intent(in) :: text, path
        type(chain_body_input_t), intent(inout) :: input
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: lines(:)
        integer :: ios
        character(len=256) :: msg
        character(len=len_name) :: name, parent, joint
        real(wp), dimension(3) :: joint_position, joint_axis, centre, inertia, inertia_products
        real(wp) :: mass, coordinate, rate, rotation_angle
        real(wp), dimension(3) :: rotation_axis, angular_rate
        namelist /rigid_chain/ name, parent, joint, joint_position, joint_axis, centre, mass, &
            inertia, inertia_products, coordinate, rate, rotation_axis, rotation_angle, &
            angular_rate
        name = input%name
        parent = input%parent
        joint = input%joint
        joint_position = input%joint_position
        joint_axis = input%joint_axis
        centre = input%centre
        mass = input%mass
        inertia = input%inertia
        inertia_products = input%inertia_products
        coordinate = input%coordinate
        rate = input%rate
        rotation_axis = input%rotation_axis
        rotation_angle = input%rotation_angle
        angular_rate = input%angular_rate
        msg = ''
        lines = split_lines(text)
        read (lines, nml=rigid_chain, iostat=ios, iomsg=msg)
        input%name = name
        input%parent = parent
        input%joint = joint
        input%joint_position = joint_position
        input%joint_axis = joint_axis
        input%centre = centre
        input%mass = mass
        input%inertia = inertia
        input%inertia_products = inertia_products
        input%coordinate = coordinate
        input%rate = rate
        input%rotation_axis = rotation_axis
        input%rotation_angle = rotation_angle
        input%angular_rate = angular_rate
        if (ios /= 0) call status%set(status_bad_input, path // ': &rigid_chain: ' // trim(msg))
    end subroutine read_chain_group

    !> Split text at newlines into records of equal length.
    pure function split_lines(text) result(lines)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: lines(:)
        integer :: i, k, nl, width, start
        nl = 1
        width = 1
        start = 1
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                nl = nl + 1
                width = max(width, i - start)
                start = i + 1
            end if
        end do
        width = max(width, len(text) - start + 1)
        allocate (character(len=width) :: lines(nl))
        k = 1
        start = 1
        do i = 1, len(text)
            if (text(i:i) == new_line('a')) then
                lines(k) = text(start:i - 1)
                k = k + 1
                start = i + 1
            end if
        end do
        lines(k) = text(start:)
    end function split_lines

    ! ------------------------------------------------------------------
    ! Ranges: check the typed values, quoting the text they came from.
    ! ------------------------------------------------------------------

    !> Lower-case the choice variables (names compare case-insensitively);
    !> a `&flexible_body` without `problem` selects it.
    subroutine normalise(scene, entries)
        type(scene_input_t), intent(inout) :: scene
        type(entry_t), intent(in) :: entries(:)
        integer :: i
        if (scene%has_body .and. .not. has_entry(entries, 'simulation', 'problem')) &
            scene%problem = 'flexible_body'
        if (size(scene%rigid_bodies) > 0 .and. &
            .not. has_entry(entries, 'simulation', 'problem')) scene%problem = 'multibody'
        scene%multibody%formulation = lower(scene%multibody%formulation)
        scene%multibody%constraint_derivatives = lower(scene%multibody%constraint_derivatives)
        do i = 1, size(scene%rigid_bodies)
            if (len_trim(scene%rigid_bodies(i)%name) == 0) &
                scene%rigid_bodies(i)%name = 'body ' // itoa(i)
        end do
        do i = 1, size(scene%markers)
            if (len_trim(scene%markers(i)%name) == 0) &
                scene%markers(i)%name = 'marker ' // itoa(i)
        end do
        do i = 1, size(scene%joints)
            if (len_trim(scene%joints(i)%name) == 0) scene%joints(i)%name = 'joint ' // itoa(i)
            scene%joints(i)%type = lower(scene%joints(i)%type)
        end do
        do i = 1, size(scene%drivers)
            if (len_trim(scene%drivers(i)%name) == 0) &
                scene%drivers(i)%name = 'driver ' // itoa(i)
            scene%drivers(i)%type = lower(scene%drivers(i)%type)
        end do
        do i = 1, size(scene%chain)
            if (len_trim(scene%chain(i)%name) == 0) scene%chain(i)%name = 'link ' // itoa(i)
            scene%chain(i)%joint = lower(scene%chain(i)%joint)
        end do
        scene%body%element = lower(scene%body%element)
        scene%body%formulation = lower(scene%body%formulation)
        do i = 1, size(scene%materials)
            if (len_trim(scene%materials(i)%name) == 0) &
                scene%materials(i)%name = 'material ' // itoa(i)
        end do
        scene%problem = lower(scene%problem)
        scene%pendulum_formulation = lower(scene%pendulum_formulation)
        scene%solver_name = lower(scene%solver_name)
        scene%linear_solver = lower(scene%linear_solver)
        scene%sparse_ordering = lower(scene%sparse_ordering)
        scene%jacobian = lower(scene%jacobian)
        scene%controller = lower(scene%controller)
        scene%mexax_base = lower(scene%mexax_base)
    end subroutine normalise

    subroutine check_ranges(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=*), parameter :: sim = 'simulation', sol = 'solver', out = 'output'
        character(len=:), allocatable :: ext

        ! &simulation
        if (.not. has_entry(entries, sim, 'problem') .and. .not. scene%has_body) then
            call missing(sim, 'problem', 'one of ' // choices(problem_names))
        else if (all(problem_names /= scene%problem)) then
            call bad(sim, 'problem', 'must be one of ' // choices(problem_names))
        else if (.not. has_entry(entries, sim, 't_end')) then
            call missing(sim, 't_end', 'the end time in s, greater than t_start')
        else if (.not. scene%t_end > scene%t_start) then
            call bad(sim, 't_end', 'must be greater than t_start = ' // &
                     raw_value(entries, sim, 't_start', '0'))
        else if (.not. scene%vdp_eps > 0.0_wp) then
            call bad(sim, 'vdp_eps', 'must be positive')
        else if (all(formulation_names /= scene%pendulum_formulation)) then
            call bad(sim, 'pendulum_formulation', 'must be one of ' // choices(formulation_names))
        else if (.not. scene%pendulum_length > 0.0_wp) then
            call bad(sim, 'pendulum_length', 'must be positive')
        else if (.not. scene%pendulum_mass > 0.0_wp) then
            call bad(sim, 'pendulum_mass', 'must be positive')
        else if (scene%gravity < 0.0_wp) then
            call bad(sim, 'gravity', 'must not be negative (it acts downwards)')
        else if (scene%npoints < 1) then
            call bad(sim, 'npoints', 'must be positive')
        ! &solver
        else if (all([character(len=8) :: 'radau5', 'ddassl', 'ida', 'mexax'] &
                     /= scene%solver_name)) then
            call bad(sol, 'name', 'must be ''radau5'', ''ddassl'', ''ida'' or ''mexax''')
        else if (scene%solver_name == 'mexax' .and. scene%problem /= 'pendulum' .and. &
                 scene%problem /= 'flexible_body' .and. scene%problem /= 'multibody' .and. &
                 scene%problem /= 'rigid_chain') then
            ! ALGORITHMS.md §6: MEXAX integrates the mechanical form only.
            call bad(sol, 'name', '''mexax'' integrates mechanical problems only: &
                &problem must be ''pendulum'', ''flexible_body'', ''multibody'' or &
                &''rigid_chain''')
        else if (.not. scene%rtol > 0.0_wp) then
            call bad(sol, 'rtol', 'must be positive')
        else if (.not. scene%rtol < 1.0_wp) then
            call bad(sol, 'rtol', 'must be less than 1')
        else if (.not. scene%atol > 0.0_wp) then
            call bad(sol, 'atol', 'must be positive')
        else if (scene%h0 < 0.0_wp) then
            call bad(sol, 'h0', 'must not be negative (0 = automatic)')
        else if (scene%hmax < 0.0_wp) then
            call bad(sol, 'hmax', 'must not be negative (0 = the whole interval)')
        else if (scene%max_steps < 1) then
            call bad(sol, 'max_steps', 'must be positive')
        else if (all(linear_solver_names /= scene%linear_solver)) then
            call bad(sol, 'linear_solver', 'must be ' // linear_solver_names_text)
        else if (all([character(len=8) :: 'auto', 'amd', 'nd'] /= scene%sparse_ordering)) then
            call bad(sol, 'sparse_ordering', 'must be ''auto'', ''amd'' or ''nd''')
        else if (all([character(len=8) :: 'analytic', 'fd'] /= scene%jacobian)) then
            call bad(sol, 'jacobian', 'must be ''analytic'' or ''fd''')
        else if (scene%nit < 1) then
            call bad(sol, 'nit', 'must be positive')
        else if (.not. scene%thet < 1.0_wp) then
            call bad(sol, 'thet', 'must be less than 1')
        else if (scene%fnewt < 0.0_wp) then
            call bad(sol, 'fnewt', 'must not be negative (0 = the solver''s default)')
        else if (.not. (scene%quot1 > 0.0_wp .and. scene%quot1 <= 1.0_wp)) then
            call bad(sol, 'quot1', 'must lie in (0, 1]')
        else if (scene%quot2 < 1.0_wp) then
            call bad(sol, 'quot2', 'must be at least 1')
        else if (.not. (scene%safe > 0.001_wp .and. scene%safe < 1.0_wp)) then
            call bad(sol, 'safe', 'must lie in (0.001, 1)')
        else if (.not. (scene%fac_min > 0.0_wp .and. scene%fac_min <= 1.0_wp)) then
            call bad(sol, 'fac_min', 'must lie in (0, 1]')
        else if (scene%fac_max < 1.0_wp) then
            call bad(sol, 'fac_max', 'must be at least 1')
        else if (controller_code(scene%controller) == 0) then
            call bad(sol, 'controller', 'must be ''predictive'' or ''classical''')
        else if (scene%pmax < 1 .or. scene%pmax > 12) then
            call bad(sol, 'pmax', 'must lie in 1..12')
        else if (scene%solver_name == 'ddassl' .and. scene%pmax > 5) then
            ! ALGORITHMS.md §2.2: MAXORD ≤ 5.
            call bad(sol, 'pmax', 'must lie in 1..5 for ddassl (its maximal BDF order)')
        else if (scene%max_extrapolation < 2 .or. scene%max_extrapolation > 12) then
            call bad(sol, 'max_extrapolation', 'must lie in 2..12')
        else if (all([character(len=8) :: 'midpoint', 'euler'] /= scene%mexax_base)) then
            call bad(sol, 'mexax_base', 'must be ''midpoint'' or ''euler''')
        ! &output
        else if (scene%n_output < 2) then
            call bad(out, 'n_output', 'must be at least 2 (t_start and t_end)')
        else if (len_trim(scene%table) > 0) then
            ext = lower(extension(trim(scene%table)))
            if (all([character(len=4) :: 'md', 'csv', 'tex'] /= ext)) then
                call bad(out, 'table', 'must end in .md, .csv or .tex')
            end if
        end if

    contains

        subroutine bad(group, name, reason)
            character(len=*), intent(in) :: group, name, reason
            integer :: i
            do i = 1, size(entries)
                if (entries(i)%group == group .and. entries(i)%name == name) then
                    call fail(status, path, entries(i), reason)
                    return
                end if
            end do
            ! a default out of range relative to a value that was given
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ' (default): ' // reason)
        end subroutine bad

        subroutine missing(group, name, what)
            character(len=*), intent(in) :: group, name, what
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ': required (' // what // ')')
        end subroutine missing
    end subroutine check_ranges

    !> &rigid_chain groups: present exactly for problem = 'rigid_chain', each
    !> body's parent the ground or an earlier body, values in range.
    subroutine check_chain(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: i, j
        logical :: found
        if (scene%problem /= 'rigid_chain' .and. &
            .not. (scene%problem == 'multibody' .and. size(scene%chain) > 0)) then
            if (size(scene%chain) > 0) call status%set(status_bad_input, path // &
                ': &rigid_chain: given, but problem = ''' // trim(scene%problem) // &
                ''' (a scene builds only what it declares)' // at(scene%chain(1)%line))
            return
        end if
        if (size(scene%chain) == 0) then
            call status%set(status_bad_input, path // ': &simulation: problem = &
                &''rigid_chain'': needs at least one &rigid_chain group (one per body)')
            return
        end if
        if (all(formulation_names /= scene%multibody%formulation)) then
            call status%set(status_bad_input, path // ': &multibody: formulation = ''' // &
                trim(scene%multibody%formulation) // ''': must be one of ' // &
                choices(formulation_names))
            return
        end if
        do i = 1, size(scene%chain)
            associate (b => scene%chain(i))
                found = b%parent == 'ground'
                do j = 1, i - 1
                    if (scene%chain(j)%name == b%parent) found = .true.
                    if (scene%chain(j)%name == b%name) then
                        call bad('name', i, 'also the name of the &rigid_chain' // &
                                 at(scene%chain(j)%line))
                        return
                    end if
                end do
                if (.not. found) then
                    call bad('parent', i, 'must be ''ground'' or a body of an earlier &
                        &&rigid_chain group')
                else if (all([character(len=12) :: 'revolute', 'prismatic', 'spherical'] /= &
                              b%joint)) then
                    call bad('joint', i, 'must be ''revolute'', ''prismatic'' or ''spherical''')
                else if (b%joint == 'spherical' .and. .not. norm2(b%rotation_axis) > 0.0_wp) then
                    call bad('rotation_axis', i, 'must not be zero')
                else if (.not. norm2(b%joint_axis) > 0.0_wp) then
                    call bad('joint_axis', i, 'must not be zero')
                else if (.not. b%mass > 0.0_wp) then
                    call bad('mass', i, 'must be positive (required)')
                else if (any(.not. b%inertia > 0.0_wp)) then
                    call bad('inertia', i, 'must be positive (required: Jxx, Jyy, Jzz)')
                end if
                if (.not. status%ok()) return
            end associate
        end do

    contains

        subroutine bad(name, instance, reason)
            character(len=*), intent(in) :: name, reason
            integer, intent(in) :: instance
            integer :: e
            do e = 1, size(entries)
                if (entries(e)%group == 'rigid_chain' .and. entries(e)%name == name .and. &
                    entries(e)%instance == instance) then
                    call fail(status, path, entries(e), reason)
                    return
                end if
            end do
            call status%set(status_bad_input, path // ': &rigid_chain ''' // &
                trim(scene%chain(instance)%name) // ''': ' // name // ' (default): ' // reason &
                // at(scene%chain(instance)%line))
        end subroutine bad
    end subroutine check_chain

    !> &multibody, &rigid_body, &marker, &joint and &driver: present exactly
    !> for problem = 'multibody'; values in range; names unique and known.
    !> (Constraint rank and the initial assembly are checked by the builder.)
    subroutine check_multibody(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=16), parameter :: mb_groups(5) = [character(len=16) :: 'multibody', &
            'rigid_body', 'marker', 'joint', 'driver']
        character(len=12), parameter :: joint_types(7) = [character(len=12) :: 'spherical', &
            'revolute', 'cylindrical', 'prismatic', 'universal', 'fixed', 'attach']
        character(len=12), parameter :: driver_types(3) = [character(len=12) :: 'angle', &
            'translation', 'distance']
        integer :: i, j, g
        if (scene%problem /= 'multibody') then
            do g = 1, size(mb_groups)
                ! a chain takes gravity and formulation from &multibody
                if (g == 1 .and. scene%problem == 'rigid_chain') cycle
                if (given(mb_groups(g)) .or. (g == 1 .and. scene%has_multibody)) then
                    call status%set(status_bad_input, path // ': &' // trim(mb_groups(g)) // &
                        ': given, but problem = ''' // trim(scene%problem) // ''' (a scene &
                        &builds only what it declares)')
                    return
                end if
            end do
            return
        end if
        associate (mb => scene%multibody)
            if (all(formulation_names /= mb%formulation)) then
                call bad('multibody', 'formulation', 1, 'must be one of ' // &
                         choices(formulation_names))
            else if (all([character(len=8) :: 'analytic', 'ad', 'ad_full'] /= &
                          mb%constraint_derivatives)) then
                call bad('multibody', 'constraint_derivatives', 1, 'must be ''analytic'', ''ad'' &
                         &or ''ad_full''')
            else if (size(scene%rigid_bodies) + size(scene%chain) == 0) then
                call status%set(status_bad_input, path // ': &simulation: problem = &
                    &''multibody'': needs at least one &rigid_body or &rigid_chain group')
            end if
        end associate
        if (.not. status%ok()) return
        do i = 1, size(scene%rigid_bodies)
            associate (b => scene%rigid_bodies(i))
                if (.not. has_entry(entries, 'rigid_body', 'mass', i)) then
                    call required('rigid_body', b%name, 'mass', 'in kg', b%line)
                else if (.not. b%mass > 0.0_wp) then
                    call bad('rigid_body', 'mass', i, 'must be positive')
                else if (.not. has_entry(entries, 'rigid_body', 'inertia', i)) then
                    call required('rigid_body', b%name, 'inertia', 'Jxx, Jyy, Jzz in kg m^2 &
                        &about the centre of mass', b%line)
                else if (any(.not. b%inertia > 0.0_wp)) then
                    call bad('rigid_body', 'inertia', i, 'must be positive')
                else if (.not. norm2(b%rotation_axis) > 0.0_wp) then
                    call bad('rigid_body', 'rotation_axis', i, 'must not be zero')
                end if
                if (.not. status%ok()) return
                do j = 1, i - 1
                    if (scene%rigid_bodies(j)%name == b%name) then
                        call bad('rigid_body', 'name', i, 'also the name of the &rigid_body' // &
                                 at(scene%rigid_bodies(j)%line))
                        return
                    end if
                end do
                if (b%name == 'ground') then
                    call bad('rigid_body', 'name', i, '''ground'' is reserved')
                    return
                end if
            end associate
        end do
        do i = 1, size(scene%markers)
            associate (m => scene%markers(i))
                if (scene%has_body .and. m%body == scene%body%name) then
                    if (len_trim(m%node_set) == 0) call bad('marker', 'body', i, 'a marker &
                        &on the flexible body needs node_set (the nodes a joint attaches)')
                else if (len_trim(m%node_set) > 0) then
                    call bad('marker', 'node_set', i, 'only for markers on the &flexible_body')
                else if (m%body /= 'ground' .and. .not. any([(scene%rigid_bodies(j)%name == &
                         m%body, j = 1, size(scene%rigid_bodies))]) .and. &
                         .not. any([(scene%chain(j)%name == m%body, &
                                     j = 1, size(scene%chain))])) then
                    call bad('marker', 'body', i, 'no &rigid_body or &rigid_chain body of &
                        &that name (nor ''ground'')')
                else if (.not. norm2(m%z_axis) > 0.0_wp) then
                    call bad('marker', 'z_axis', i, 'must not be zero')
                else if (norm2(cross3(m%x_axis, m%z_axis)) <= 1.0e-12_wp * norm2(m%z_axis) * &
                         norm2(m%x_axis)) then
                    if (has_entry(entries, 'marker', 'x_axis', i)) &
                        call bad('marker', 'x_axis', i, 'must not be parallel to z_axis')
                end if
                if (.not. status%ok()) return
                do j = 1, i - 1
                    if (scene%markers(j)%name == m%name) then
                        call bad('marker', 'name', i, 'also the name of the &marker' // &
                                 at(scene%markers(j)%line))
                        return
                    end if
                end do
            end associate
        end do
        do i = 1, size(scene%joints)
            associate (jt => scene%joints(i))
                if (all(joint_types /= jt%type)) then
                    call bad('joint', 'type', i, 'must be one of ' // choices(joint_types))
                else
                    call check_markers('joint', i, jt%marker_i, jt%marker_j)
                end if
                if (status%ok() .and. jt%type == 'attach') then
                    if (.not. (on_flexible(jt%marker_j) .and. .not. on_flexible(jt%marker_i))) &
                        call bad('joint', 'type', i, '''attach'' joins a marker of a rigid &
                        &body or the ground (marker_i) to a node-set marker of the flexible &
                        &body (marker_j)')
                end if
                if (.not. status%ok()) return
            end associate
        end do
        do i = 1, size(scene%drivers)
            associate (d => scene%drivers(i))
                if (all(driver_types /= d%type)) then
                    call bad('driver', 'type', i, 'must be one of ' // choices(driver_types))
                else if (d%axis_i < 1 .or. d%axis_i > 3) then
                    call bad('driver', 'axis_i', i, 'must be 1, 2 or 3 (x, y, z of marker_i)')
                else if (d%axis_j < 1 .or. d%axis_j > 3) then
                    call bad('driver', 'axis_j', i, 'must be 1, 2 or 3 (x, y, z of marker_j)')
                else
                    call check_markers('driver', i, d%marker_i, d%marker_j)
                end if
                if (.not. status%ok()) return
            end associate
        end do

    contains

        !> Some entry of the group was given (empty groups count via the scene).
        logical function given(group)
            character(len=*), intent(in) :: group
            integer :: e
            given = .false.
            do e = 1, size(entries)
                if (entries(e)%group == group) given = .true.
            end do
            select case (group)
            case ('rigid_body'); given = given .or. size(scene%rigid_bodies) > 0
            case ('marker'); given = given .or. size(scene%markers) > 0
            case ('joint'); given = given .or. size(scene%joints) > 0
            case ('driver'); given = given .or. size(scene%drivers) > 0
            end select
        end function given

        !> The marker of that name sits on the flexible body.
        logical function on_flexible(name)
            character(len=*), intent(in) :: name
            integer :: k
            on_flexible = .false.
            if (.not. scene%has_body) return
            do k = 1, size(scene%markers)
                if (scene%markers(k)%name == name) on_flexible = scene%markers(k)%body == &
                                                                 scene%body%name
            end do
        end function on_flexible

        !> Both markers exist and sit on different bodies.
        subroutine check_markers(group, instance, mi, mj)
            character(len=*), intent(in) :: group, mi, mj
            integer, intent(in) :: instance
            integer :: ki, kj, k
            ki = 0
            kj = 0
            do k = size(scene%markers), 1, -1
                if (scene%markers(k)%name == mi) ki = k
                if (scene%markers(k)%name == mj) kj = k
            end do
            if (ki == 0) then
                call bad(group, 'marker_i', instance, 'no &marker of that name')
            else if (kj == 0) then
                call bad(group, 'marker_j', instance, 'no &marker of that name')
            else if (scene%markers(ki)%body == scene%markers(kj)%body) then
                call bad(group, 'marker_j', instance, 'on the same body as marker_i (''' // &
                         trim(scene%markers(ki)%body) // ''')')
            end if
        end subroutine check_markers

        subroutine bad(group, name, instance, reason)
            character(len=*), intent(in) :: group, name, reason
            integer, intent(in) :: instance
            integer :: e
            do e = 1, size(entries)
                if (entries(e)%group == group .and. entries(e)%name == name .and. &
                    entries(e)%instance == instance) then
                    call fail(status, path, entries(e), reason)
                    return
                end if
            end do
            call status%set(status_bad_input, path // ': &' // group // ' #' // itoa(instance) &
                // ': ' // name // ' (default): ' // reason)
        end subroutine bad

        subroutine required(group, label, name, what, line)
            character(len=*), intent(in) :: group, label, name, what
            integer, intent(in) :: line
            call status%set(status_bad_input, path // ': &' // group // ' ''' // trim(label) // &
                ''': ' // name // ': required (' // what // ')' // at(line))
        end subroutine required

        pure function cross3(a, b) result(c)
            real(wp), intent(in) :: a(3), b(3)
            real(wp) :: c(3)
            c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
        end function cross3
    end subroutine check_multibody

    !> The `&flexible_body` and `&material` groups: presence, choices and
    !> ranges. Set names are checked against the mesh when the body is built.
    subroutine check_body(scene, entries, path, status)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=*), parameter :: fb = 'flexible_body', mat = 'material'
        integer :: i, j

        if (scene%problem /= 'flexible_body' .and. &
            .not. (scene%problem == 'multibody' .and. scene%has_body)) then
            if (scene%has_body) then
                call status%set(status_bad_input, path // ': &flexible_body: given, but &
                    &problem = ''' // trim(scene%problem) // ''' (a scene builds only what &
                    &it declares)' // at(scene%body%line))
            else if (size(scene%materials) > 0) then
                call status%set(status_bad_input, path // ': &material: given without &
                    &&flexible_body' // at(scene%materials(1)%line))
            end if
            return
        end if
        associate (b => scene%body)
            if (.not. scene%has_body) then
                call status%set(status_bad_input, path // ': &simulation: problem = &
                    &''flexible_body'': needs a &flexible_body group')
            else if (all([character(len=8) :: 'hex8', 'hex27'] /= b%element)) then
                call bad(fb, 'element', 1, 'must be ''hex8'' or ''hex27''')
            else if (all(formulation_names /= b%formulation)) then
                call bad(fb, 'formulation', 1, 'must be one of ' // choices(formulation_names))
            else if (len_trim(b%mesh_file) > 0 .and. has_entry(entries, fb, 'divisions')) then
                call bad(fb, 'divisions', 1, 'not used with mesh_file (the file gives the mesh)')
            else if (len_trim(b%mesh_file) > 0 .and. has_entry(entries, fb, 'lengths')) then
                call bad(fb, 'lengths', 1, 'not used with mesh_file (the file gives the mesh)')
            else if (len_trim(b%mesh_file) > 0 .and. has_entry(entries, fb, 'origin')) then
                call bad(fb, 'origin', 1, 'not used with mesh_file (the file gives the mesh)')
            else if (len_trim(b%mesh_file) == 0 .and. .not. has_entry(entries, fb, 'lengths')) &
                then
                call status%set(status_bad_input, path // ': &flexible_body: lengths: required &
                    &(the box edge lengths in m), or mesh_file' // at(b%line))
            else if (len_trim(b%mesh_file) == 0 .and. any(.not. b%lengths > 0.0_wp)) then
                call bad(fb, 'lengths', 1, 'must be positive')
            else if (len_trim(b%mesh_file) == 0 .and. any(b%divisions < 1)) then
                call bad(fb, 'divisions', 1, 'must be at least 1 in every direction')
            else if (len_trim(b%mesh_file) == 0 .and. len(box_size_problem(b%divisions, &
                     b%element)) > 0) then
                call bad(fb, 'divisions', 1, box_size_problem(b%divisions, b%element))
            else if (has_entry(entries, fb, 'fixed') .and. &
                     any(b%fixed(1:count_values(fb, 'fixed')) == '')) then
                call bad(fb, 'fixed', 1, 'node-set names must not be empty')
            else if (has_entry(entries, fb, 'load') .and. len_trim(b%load_set) == 0) then
                call bad(fb, 'load', 1, 'needs load_set (the node set that carries it)')
            else if (has_entry(entries, fb, 'load_set') .and. .not. has_entry(entries, fb, &
                     'load')) then
                call bad(fb, 'load_set', 1, 'needs load = fx, fy, fz (the total force in N)')
            else if (size(scene%materials) == 0) then
                call status%set(status_bad_input, path // ': &flexible_body: needs a &
                    &&material group (youngs_modulus, density, ...)' // at(b%line))
            end if
        end associate
        if (.not. status%ok()) return
        do i = 1, size(scene%materials)
            associate (m => scene%materials(i))
                if (.not. has_entry(entries, mat, 'youngs_modulus', i)) then
                    call missing_in(i, 'youngs_modulus', 'Young''s modulus E in Pa')
                else if (.not. m%youngs_modulus > 0.0_wp) then
                    call bad(mat, 'youngs_modulus', i, 'must be positive')
                else if (.not. (m%poisson_ratio > -1.0_wp .and. m%poisson_ratio < 0.5_wp)) then
                    call bad(mat, 'poisson_ratio', i, 'must lie in (-1, 0.5)')
                else if (.not. has_entry(entries, mat, 'density', i)) then
                    call missing_in(i, 'density', 'the mass density in kg/m^3')
                else if (.not. m%density > 0.0_wp) then
                    call bad(mat, 'density', i, 'must be positive')
                else if (.not. m%viscosity >= 0.0_wp) then
                    call bad(mat, 'viscosity', i, 'must not be negative (0: undamped)')
                else if (has_entry(entries, mat, 'elements', i) .and. &
                         len_trim(m%elements) == 0) then
                    call bad(mat, 'elements', i, 'must name an element set (leave it out &
                        &for the elements no other material names)')
                end if
                if (.not. status%ok()) return
                do j = 1, i - 1
                    if (scene%materials(j)%name == m%name) then
                        call bad(mat, 'name', i, 'also the name of the &material' // &
                                 at(scene%materials(j)%line))
                    else if (scene%materials(j)%elements == m%elements .and. &
                             len_trim(m%elements) > 0) then
                        call bad(mat, 'elements', i, 'the same set as &material ''' // &
                            trim(scene%materials(j)%name) // '''' // at(scene%materials(j)%line))
                    else if (scene%materials(j)%elements == m%elements) then
                        call status%set(status_bad_input, path // ': &material ''' // &
                            trim(m%name) // ''': elements: not given here nor in &material ''' &
                            // trim(scene%materials(j)%name) // ''': only one material may &
                            &cover the elements no other names' // at(m%line))
                    end if
                    if (.not. status%ok()) return
                end do
            end associate
        end do

    contains

        !> 'path: &group: name = value: reason (line n)' for occurrence
        !> `instance`, or '(default)' in place of the value when not given.
        subroutine bad(group, name, instance, reason)
            character(len=*), intent(in) :: group, name, reason
            integer, intent(in) :: instance
            integer :: e
            do e = 1, size(entries)
                if (entries(e)%group == group .and. entries(e)%name == name .and. &
                    entries(e)%instance == instance) then
                    call fail(status, path, entries(e), reason)
                    return
                end if
            end do
            call status%set(status_bad_input, path // ': &' // group // ': ' // name // &
                ' (default): ' // reason)
        end subroutine bad

        subroutine missing_in(instance, name, what)
            integer, intent(in) :: instance
            character(len=*), intent(in) :: name, what
            call status%set(status_bad_input, path // ': &material ''' // &
                trim(scene%materials(instance)%name) // ''': ' // name // ': required (' // &
                what // ')' // at(scene%materials(instance)%line))
        end subroutine missing_in

        integer function count_values(group, name)
            character(len=*), intent(in) :: group, name
            integer :: e
            count_values = 0
            do e = 1, size(entries)
                if (entries(e)%group == group .and. entries(e)%name == name) &
                    count_values = size(entries(e)%items)
            end do
        end function count_values
    end subroutine check_body

    !> RADAU5's controller switch: 1 predictive (Gustafsson), 2 classical; 0 unknown.
    pure integer function controller_code(name)
        character(len=*), intent(in) :: name
        select case (lower(trim(name)))
        case ('predictive'); controller_code = 1
        case ('classical'); controller_code = 2
        case default; controller_code = 0
        end select
    end function controller_code

    !> The HDF5 file: as given ('' or 'none' = no file), or the input's
    !> base name with `.h5` in the working directory.
    subroutine resolve_output(scene, entries, path, status)
        type(scene_input_t), intent(inout) :: scene
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: i
        if (.not. has_entry(entries, 'output', 'file')) then
            scene%output_file = stem(basename(path)) // '.h5'
        else if (lower(scene%output_file) == 'none') then
            scene%output_file = ''
        end if
        if (len(scene%output_file) == 0) return
        ! the same file by any spelling (./s.nml, ../in/s.nml, a link)
        if (scene%output_file /= path .and. .not. same_file(scene%output_file, path)) return
        do i = 1, size(entries)
            if (entries(i)%group == 'output' .and. entries(i)%name == 'file') then
                call fail(status, path, entries(i), 'would overwrite the input file')
                return
            end if
        end do
        call status%set(status_bad_input, path // ': &output: file (default ''' // &
            scene%output_file // '''): would overwrite the input file')
    end subroutine resolve_output

    !> Common options of the scene: tolerances, steps, output times.
    function scene_dae_options(scene) result(options)
        type(scene_input_t), intent(in) :: scene
        type(dae_options_t) :: options
        integer :: i, m
        options%rtol = scene%rtol
        options%atol = scene%atol
        options%h0 = scene%h0
        options%hmax = scene%hmax
        options%max_steps = scene%max_steps
        options%pmax = min(scene%pmax, 12)
        options%linear_solver = trim(scene%linear_solver)
        options%sparse_ordering = trim(scene%sparse_ordering)
        options%jacobian = trim(scene%jacobian)
        options%output_steps = scene%every_step
        m = max(scene%n_output, 2)
        allocate (options%output_times(m))
        do i = 1, m
            options%output_times(i) = scene%t_start + (scene%t_end - scene%t_start) * &
                real(i - 1, wp) / real(m - 1, wp)
        end do
        options%output_times(m) = scene%t_end
    end function scene_dae_options

    ! ------------------------------------------------------------------
    ! Small helpers.
    ! ------------------------------------------------------------------

    !> Record a bad value: 'path: &group: name = value: reason (line n)'.
    subroutine fail(status, path, e, reason)
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: path
        type(entry_t), intent(in) :: e
        character(len=*), intent(in) :: reason
        call status%set(status_bad_input, path // ': &' // e%group // ': ' // e%name // &
            ' = ' // e%value // ': ' // reason // at(e%line))
    end subroutine fail

    pure function at(line) result(text)
        integer, intent(in) :: line
        character(len=:), allocatable :: text
        text = ' (line ' // itoa(line) // ')'
    end function at

    pure integer function find_group(name)
        character(len=*), intent(in) :: name
        integer :: g
        find_group = 0
        do g = 1, size(group_names)
            if (group_names(g) == name) find_group = g
        end do
    end function find_group

    pure integer function find_var(group, name)
        character(len=*), intent(in) :: group, name
        integer :: i
        find_var = 0
        do i = 1, size(schema)
            if (schema(i)%group == group .and. schema(i)%name == name) find_var = i
        end do
    end function find_var

    pure function known_vars(group) result(list)
        character(len=*), intent(in) :: group
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        do i = 1, size(schema)
            if (schema(i)%group /= group) cycle
            if (len(list) > 0) list = list // ', '
            list = list // trim(schema(i)%name)
        end do
    end function known_vars

    !> Whether `name` is given in `group` (in occurrence `instance` if present).
    pure logical function has_entry(entries, group, name, instance)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name
        integer, intent(in), optional :: instance
        integer :: i
        has_entry = .false.
        do i = 1, size(entries)
            if (entries(i)%group /= group .or. entries(i)%name /= name) cycle
            if (present(instance)) then
                if (entries(i)%instance /= instance) cycle
            end if
            has_entry = .true.
        end do
    end function has_entry

    pure function choices(names) result(list)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        do i = 1, size(names)
            if (i == size(names) .and. i > 1) then
                list = list // ' or '
            else if (i > 1) then
                list = list // ', '
            end if
            list = list // '''' // trim(names(i)) // ''''
        end do
    end function choices

    !> Contents of a quoted value, doubled quotes made single.
    pure function unquote(value) result(text)
        character(len=*), intent(in) :: value
        character(len=:), allocatable :: text
        integer :: i
        character :: quote
        text = ''
        if (len(value) < 2) return
        quote = value(1:1)
        i = 2
        do while (i < len(value))
            text = text // value(i:i)
            if (value(i:i) == quote) i = i + 1
            i = i + 1
        end do
    end function unquote

    pure logical function is_letter(c)
        character, intent(in) :: c
        is_letter = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z')
    end function is_letter

    pure logical function is_digit(c)
        character, intent(in) :: c
        is_digit = c >= '0' .and. c <= '9'
    end function is_digit

    pure logical function is_space(c)
        character, intent(in) :: c
        is_space = c == ' ' .or. c == achar(9) .or. c == achar(13)
    end function is_space

    pure function itoa(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write (buf, '(i0)') i
        s = trim(buf)
    end function itoa

    !> The value as written in the file, or `default` when not given.
    pure function raw_value(entries, group, name, default) result(text)
        type(entry_t), intent(in) :: entries(:)
        character(len=*), intent(in) :: group, name, default
        character(len=:), allocatable :: text
        integer :: i
        text = default
        do i = 1, size(entries)
            if (entries(i)%group == group .and. entries(i)%name == name) text = entries(i)%value
        end do
    end function raw_value

    pure function basename(path) result(name)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: name
        name = path(index(path, '/', back=.true.) + 1:)
    end function basename

    !> File name without its last extension.
    pure function stem(name) result(s)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: s
        integer :: dot
        dot = index(name, '.', back=.true.)
        if (dot > 1) then
            s = name(1:dot - 1)
        else
            s = name
        end if
    end function stem

    pure function extension(name) result(ext)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: ext
        integer :: dot
        dot = index(name, '.', back=.true.)
        if (dot > index(name, '/', back=.true.) .and. dot > 0) then
            ext = name(dot + 1:)
        else
            ext = ''
        end if
    end function extension

    !> Why a box mesh of `divisions` elements of type `element` cannot be
    !> made here, or '': its node and element counts must fit the default
    !> integers that number them, and a lower estimate of the memory the run
    !> needs (the tangent pattern: per node 3 rows of 81 (hex8) or 375
    !> (hex27) entries of about 40 bytes each, values, damping, index and
    !> maps) must fit the machine. Counted in 64 bits: 2000³ elements
    !> overflow a default integer.
    function box_size_problem(divisions, element) result(why)
        integer, intent(in) :: divisions(3)
        character(len=*), intent(in) :: element
        character(len=:), allocatable :: why
        integer(i8) :: nodes, elements, p, machine
        real(wp) :: bytes, per_node
        why = ''
        p = merge(1_i8, 2_i8, element == 'hex8')
        per_node = merge(3.0_wp * 81.0_wp, 3.0_wp * 375.0_wp, element == 'hex8') * 40.0_wp
        nodes = product(p * int(divisions, i8) + 1_i8)
        elements = product(int(divisions, i8))
        bytes = real(nodes, wp) * per_node
        if (3_i8 * nodes > int(huge(1), i8) .or. elements > int(huge(1), i8)) then
            why = real_text(real(nodes, wp)) // ' nodes (' // real_text(3.0_wp * real(nodes, &
                wp)) // ' coordinates) and ' // real_text(real(elements, wp)) // &
                ' elements: more than the ' // int_text(huge(1)) // ' a mesh can number'
            return
        end if
        machine = physical_memory()
        if (machine > 0 .and. bytes > real(machine, wp)) why = real_text(real(nodes, wp)) // &
            ' nodes, needs at least ~' // bytes_text(bytes) // '; this machine has ' // &
            bytes_text(real(machine, wp))
    end function box_size_problem
end module flexmbs_io_namelist
