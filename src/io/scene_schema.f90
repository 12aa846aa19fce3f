!> The schema of scene and study files: every group, every variable with
!> its kind, number of values, default, admissible range or choices, unit
!> and a one-line description. Reading (defaults), the type and range
!> checks and the scene reference all come from this one table.
module flexmbs_io_scene_schema
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: lower, nearest
    use flexmbs_core_rules, only: min_tolerance, safety_factor_rule
    use flexmbs_run_catalogue, only: solver_choices, problem_choices
    use flexmbs_mbs_joint_types, only: joint_choices
    implicit none
    private

    integer, parameter, public :: kind_string = 1, kind_real = 2, kind_integer = 3, &
        kind_logical = 4
    !> Declared lengths of string values.
    integer, parameter, public :: len_title = 256, len_name = 32, len_path = 512
    !> Longest lists of a study (`&study`).
    integer, parameter, public :: max_study_solvers = 4, max_study_tolerances = 16
    !> At most this many node-set names in `&flexible_body fixed`.
    integer, parameter, public :: max_fixed_sets = 6
    !> At most this many node-set names in `&flexible_body interfaces`.
    integer, parameter, public :: max_interfaces = 8
    ! core/rules: the rules' evaluation and the ranges the solvers share
    public :: min_tolerance

    !> One variable. `rule` is '' (any value), 'positive', 'nonnegative',
    !> 'tolerance' ([1e-14, 1)) or an interval such as '(0,1]' or '[2,12]'
    !> (`inf` for no bound); it applies to each value. `choices` lists the
    !> admissible strings, separated by '|' (compared case-insensitively).
    type, public :: var_spec_t
        character(len=16) :: group = ''
        character(len=24) :: name = ''
        integer :: kind = kind_real
        !> Number of values: 1 for a scalar; an array of reals or integers takes
        !> exactly `count`, an array of strings 1..count
        integer :: count = 1
        !> a list: 1..count values of any kind
        logical :: list = .false.
        character(len=40) :: default = ''
        character(len=16) :: rule = ''
        character(len=96) :: choices = ''
        character(len=8) :: unit = ''
        character(len=80) :: doc = ''
    end type var_spec_t

    type(var_spec_t), parameter, public :: schema(*) = [ &
        var_spec_t('simulation', 'title', kind_string, doc='free text, stored with the result'), &
        var_spec_t('simulation', 'problem', kind_string, choices=problem_choices, &
            doc='what to integrate (default: from the groups given)'), &
        var_spec_t('simulation', 't_start', kind_real, default='0', unit='s', &
            doc='start time'), &
        var_spec_t('simulation', 't_end', kind_real, unit='s', &
            doc='end time, required, greater than t_start'), &
        var_spec_t('simulation', 'vdp_eps', kind_real, default='1e-6', rule='positive', &
            doc='van der Pol: stiffness parameter'), &
        var_spec_t('simulation', 'vdp_y1', kind_real, default='2', doc='van der Pol: y1(0)'), &
        var_spec_t('simulation', 'vdp_y2', kind_real, default='-0.66', &
            doc='van der Pol: y2(0)'), &
        var_spec_t('simulation', 'pendulum_formulation', kind_string, default='index2', &
            choices='index3|index2|index1|ggl', doc='pendulum: DAE formulation'), &
        var_spec_t('simulation', 'pendulum_length', kind_real, default='1', rule='positive', &
            unit='m', doc='pendulum: length'), &
        var_spec_t('simulation', 'pendulum_mass', kind_real, default='1', rule='positive', &
            unit='kg', doc='pendulum: mass'), &
        var_spec_t('simulation', 'pendulum_angle', kind_real, default='1.5707963267948966', &
            unit='rad', doc='pendulum: initial angle from the downward vertical, at rest'), &
        var_spec_t('simulation', 'pendulum_projection', kind_logical, default='.false.', &
            doc='pendulum: project onto both constraints after each step'), &
        var_spec_t('simulation', 'gravity', kind_real, default='9.81', rule='nonnegative', &
            unit='m/s^2', doc='pendulum: gravity, acting downwards'), &
        var_spec_t('simulation', 'npoints', kind_integer, default='100', rule='[1,inf)', &
            doc='Brusselator: grid points per direction'), &
        var_spec_t('solver', 'name', kind_string, default='radau5', &
            choices=solver_choices, doc='the integrator'), &
        var_spec_t('solver', 'rtol', kind_real, default='1e-6', rule='tolerance', &
            doc='relative tolerance'), &
        var_spec_t('solver', 'atol', kind_real, default='1e-6', rule='tolerance', &
            doc='absolute tolerance'), &
        var_spec_t('solver', 'h0', kind_real, default='0', rule='nonnegative', unit='s', &
            doc='initial step (0: automatic)'), &
        var_spec_t('solver', 'hmax', kind_real, default='0', rule='nonnegative', unit='s', &
            doc='largest step (0: the whole interval)'), &
        var_spec_t('solver', 'max_steps', kind_integer, default='100000', rule='[1,inf)', &
            doc='most steps before the run stops'), &
        var_spec_t('solver', 'linear_solver', kind_string, default='auto', &
            doc='linear algebra of the Newton matrices: auto, dense, klu, band or mumps'), &
        var_spec_t('solver', 'sparse_ordering', kind_string, default='auto', &
            choices='auto|amd|nd', doc='KLU fill-reducing ordering'), &
        var_spec_t('solver', 'newton_system', kind_string, default='condensed', &
            choices='condensed|full', doc='mechanical scenes: factor the Newton matrix ' // &
            'condensed to velocities and multipliers, or the full first-order one'), &
        var_spec_t('solver', 'jacobian', kind_string, default='analytic', &
            choices='analytic|fd', doc='Jacobian: analytic or finite differences'), &
        var_spec_t('solver', 'nit', kind_integer, rule='[1,inf)', &
            doc='RADAU5: most Newton iterations per step'), &
        var_spec_t('solver', 'thet', kind_real, rule='(-inf,1)', &
            doc='RADAU5: Jacobian reuse threshold'), &
        var_spec_t('solver', 'fnewt', kind_real, rule='nonnegative', &
            doc='RADAU5: Newton stopping criterion (0: from rtol)'), &
        var_spec_t('solver', 'quot1', kind_real, rule='(0,1]', &
            doc='RADAU5: keep the step when h_new/h lies in [quot1, quot2]'), &
        var_spec_t('solver', 'quot2', kind_real, rule='[1,inf)', &
            doc='RADAU5: see quot1'), &
        var_spec_t('solver', 'safe', kind_real, rule=safety_factor_rule, &
            doc='safety factor of the step size control'), &
        var_spec_t('solver', 'fac_min', kind_real, rule='(0,1]', &
            doc='smallest step size ratio'), &
        var_spec_t('solver', 'fac_max', kind_real, rule='[1,inf)', &
            doc='largest step size ratio'), &
        var_spec_t('solver', 'controller', kind_string, &
            choices='predictive|classical', doc='RADAU5: step size controller'), &
        var_spec_t('solver', 'zero_start', kind_logical, &
            doc='RADAU5: start Newton from zero'), &
        var_spec_t('solver', 'pmax', kind_integer, default='5', rule='[1,12]', &
            doc='largest order (BDF: 1..5)'), &
        var_spec_t('solver', 'initial_derivative', kind_logical, &
            doc='DDASSL: compute consistent y'' at t_start'), &
        var_spec_t('solver', 'exclude_index23', kind_logical, &
            doc='DDASSL: index-2/3 variables out of the error test'), &
        var_spec_t('solver', 'netlib', kind_logical, &
            doc='DDASSL: the later netlib revision'), &
        var_spec_t('solver', 'max_extrapolation', kind_integer, rule='[2,12]', &
            doc='MEXAX: extrapolation columns'), &
        var_spec_t('solver', 'mexax_base', kind_string, &
            choices='midpoint|euler', doc='MEXAX: basic step'), &
        var_spec_t('solver', 'mexax_control', kind_string, &
            choices='hairer|deuflhard', doc='MEXAX: order and step-size control'), &
        var_spec_t('output', 'file', kind_string, &
            doc='HDF5 result (default: the scene''s name with .h5; ''none'': no file)'), &
        var_spec_t('output', 'n_output', kind_integer, default='101', rule='[2,inf)', &
            doc='equidistant output times, t_start and t_end included'), &
        var_spec_t('output', 'every_step', kind_logical, default='.false.', &
            doc='also record every accepted step'), &
        var_spec_t('output', 'table', kind_string, doc='a table of the outputs (.md, .csv, .tex)'), &
        var_spec_t('output', 'reasons', kind_logical, default='.false.', &
            doc='the table also counts the rejected steps by cause'), &
        var_spec_t('output', 'progress', kind_logical, default='.true.', &
            doc='progress display on standard error'), &
        var_spec_t('output', 'checkpoint_interval', kind_real, default='60', &
            rule='nonnegative', unit='s', doc='wall time between the checkpoints &
            &a run keeps in its HDF5 file for --resume (0: every accepted step)'), &
        var_spec_t('output', 'vtk', kind_string, &
            doc='ParaView files PREFIX.pvd, PREFIX_NNNN.vtu, PREFIX_bodies|joints_NNNN.vtu'), &
        var_spec_t('output', 'vtk_format', kind_string, default='binary', &
            choices='binary|ascii', &
            doc='the .vtu files'' arrays: binary (appended, base64) or text'), &
        var_spec_t('flexible_body', 'name', kind_string, default='body', &
            doc='unique name (default: body; body N when there are several)'), &
        var_spec_t('flexible_body', 'element', kind_string, default='hex8', &
            choices='hex8|hex27', doc='element type of a box mesh'), &
        var_spec_t('flexible_body', 'mesh_file', kind_string, &
            doc='mesh file (default: a box mesh)'), &
        var_spec_t('flexible_body', 'divisions', kind_integer, 3, default='1, 1, 1', &
            rule='[1,inf)', doc='box: elements per direction'), &
        var_spec_t('flexible_body', 'lengths', kind_real, 3, default='0, 0, 0', &
            rule='positive', unit='m', doc='box: edge lengths, required'), &
        var_spec_t('flexible_body', 'origin', kind_real, 3, default='0, 0, 0', unit='m', &
            doc='box: lower corner'), &
        var_spec_t('flexible_body', 'fixed', kind_string, max_fixed_sets, &
            doc='node sets held at their reference position'), &
        var_spec_t('flexible_body', 'load_set', kind_string, doc='node set carrying load'), &
        var_spec_t('flexible_body', 'load', kind_real, 3, default='0, 0, 0', unit='N', &
            doc='total force on load_set'), &
        var_spec_t('flexible_body', 'gravity', kind_real, 3, default='0, 0, 0', &
            unit='m/s^2', doc='gravity on the body'), &
        var_spec_t('flexible_body', 'initial_velocity', kind_real, 3, default='0, 0, 0', &
            unit='m/s', doc='initial velocity (a rigid field)'), &
        var_spec_t('flexible_body', 'initial_angular_velocity', kind_real, 3, &
            default='0, 0, 0', unit='rad/s', doc='initial angular velocity about the centroid'), &
        var_spec_t('flexible_body', 'formulation', kind_string, default='index2', &
            choices='index3|index2|index1|ggl', doc='DAE formulation (problem = flexible_body)'), &
        var_spec_t('flexible_body', 'model', kind_string, default='nonlinear', &
            choices='nonlinear|modal', doc='nonlinear finite elements, or modal: a floating &
            &frame with Craig-Bampton modes of the same mesh (problem = multibody)'), &
        var_spec_t('flexible_body', 'modes', kind_integer, default='8', rule='[0,inf)', &
            doc='modal: fixed-interface normal modes k (6 static modes per interface come &
            &with them)'), &
        var_spec_t('flexible_body', 'interfaces', kind_string, max_interfaces, &
            doc='modal: the node sets joints and markers use, each moving rigidly (default: &
            &the node sets of its markers)'), &
        var_spec_t('flexible_body', 'modes_method', kind_string, default='auto', &
            choices='auto|dense|arpack', doc='modal: eigen-solver of the fixed-interface &
            &modes (auto: dense up to 1200 interior coordinates)'), &
        var_spec_t('flexible_body', 'modes_cache', kind_string, &
            doc='modal: HDF5 file keeping the basis, reused when mesh, materials, interfaces &
            &and modes match (default: none)'), &
        var_spec_t('material', 'name', kind_string, doc='for messages (default: material N)'), &
        var_spec_t('material', 'youngs_modulus', kind_real, rule='positive', unit='Pa', &
            doc='Young''s modulus E, required'), &
        var_spec_t('material', 'poisson_ratio', kind_real, default='0.3', rule='(-1,0.5)', &
            doc='Poisson''s ratio'), &
        var_spec_t('material', 'density', kind_real, rule='positive', unit='kg/m^3', &
            doc='mass density, required'), &
        var_spec_t('material', 'viscosity', kind_real, default='0', rule='[0,1e20]', &
            unit='Pa s', doc='viscosity (0: undamped; above 1e20 its stresses overflow)'), &
        var_spec_t('material', 'elements', kind_string, &
            doc='element set (default: the elements no other material names)'), &
        var_spec_t('material', 'body', kind_string, &
            doc='its &flexible_body (default: the only one; required with several)'), &
        var_spec_t('multibody', 'formulation', kind_string, default='ggl', &
            choices='index3|index2|index1|ggl', doc='DAE formulation of the joints'), &
        var_spec_t('multibody', 'gravity', kind_real, 3, default='0, -9.81, 0', &
            unit='m/s^2', doc='gravity'), &
        var_spec_t('multibody', 'constraint_derivatives', kind_string, default='analytic', &
            choices='analytic|ad|ad_full', &
            doc='joint and force-element derivatives: hand-coded or AD'), &
        var_spec_t('multibody', 'projection', kind_logical, default='.false.', &
            doc='coordinate projection after each step'), &
        var_spec_t('multibody', 'assembly_tolerance', kind_real, default='1e-3', &
            rule='positive', unit='m', &
            doc='largest move of a body by the initial assembly'), &
        var_spec_t('rigid_body', 'name', kind_string, doc='unique name (default: body N)'), &
        var_spec_t('rigid_body', 'mass', kind_real, rule='positive', unit='kg', &
            doc='mass, required'), &
        var_spec_t('rigid_body', 'inertia', kind_real, 3, rule='positive', unit='kg m^2', &
            doc='Jxx, Jyy, Jzz about the centre of mass, required'), &
        var_spec_t('rigid_body', 'inertia_products', kind_real, 3, default='0, 0, 0', &
            unit='kg m^2', doc='Jxy, Jyz, Jxz'), &
        var_spec_t('rigid_body', 'position', kind_real, 3, default='0, 0, 0', unit='m', &
            doc='centre of mass'), &
        var_spec_t('rigid_body', 'rotation_axis', kind_real, 3, default='0, 0, 1', &
            doc='initial rotation: axis'), &
        var_spec_t('rigid_body', 'rotation_angle', kind_real, default='0', unit='rad', &
            doc='initial rotation: angle'), &
        var_spec_t('rigid_body', 'velocity', kind_real, 3, default='0, 0, 0', unit='m/s', &
            doc='initial velocity'), &
        var_spec_t('rigid_body', 'angular_velocity', kind_real, 3, default='0, 0, 0', &
            unit='rad/s', doc='initial angular velocity, world frame'), &
        var_spec_t('marker', 'name', kind_string, doc='unique name (default: marker N)'), &
        var_spec_t('marker', 'body', kind_string, default='ground', &
            doc='the body it sits on'), &
        var_spec_t('marker', 'position', kind_real, 3, default='0, 0, 0', unit='m', &
            doc='in the body''s frame (node sets: their centroid; given, a node frame)'), &
        var_spec_t('marker', 'z_axis', kind_real, 3, default='0, 0, 1', doc='z axis'), &
        var_spec_t('marker', 'x_axis', kind_real, 3, default='0, 0, 0', &
            doc='x axis (0: any normal to z)'), &
        var_spec_t('marker', 'node_set', kind_string, &
            doc='the flexible body''s nodes it follows: centroid, or if needed a fitted frame'), &
        var_spec_t('joint', 'name', kind_string, doc='unique name (default: joint N)'), &
        var_spec_t('joint', 'type', kind_string, choices=joint_choices // '|attach', &
            doc='joint type, required'), &
        var_spec_t('joint', 'marker_i', kind_string, doc='first marker'), &
        var_spec_t('joint', 'marker_j', kind_string, doc='second marker'), &
        var_spec_t('driver', 'name', kind_string, doc='unique name (default: driver N)'), &
        var_spec_t('driver', 'type', kind_string, choices='angle|translation|distance', &
            doc='what it drives, required'), &
        var_spec_t('driver', 'marker_i', kind_string, doc='first marker'), &
        var_spec_t('driver', 'marker_j', kind_string, doc='second marker'), &
        var_spec_t('driver', 'axis_i', kind_integer, default='1', rule='[1,3]', &
            doc='axis of marker_i (1, 2, 3: x, y, z)'), &
        var_spec_t('driver', 'axis_j', kind_integer, default='1', rule='[1,3]', &
            doc='axis of marker_j'), &
        var_spec_t('driver', 'coefficients', kind_real, 4, default='0, 0, 0, 0', &
            doc='s = c0 + c1 t + c2 t^2 + c3 t^3 ...'), &
        var_spec_t('driver', 'amplitude', kind_real, default='0', doc='... + a sin(w t + phi)'), &
        var_spec_t('driver', 'frequency', kind_real, default='0', unit='rad/s', doc='w'), &
        var_spec_t('driver', 'phase', kind_real, default='0', unit='rad', doc='phi'), &
        var_spec_t('driver', 'ramp_rate', kind_real, default='0', doc='... + a ramp then &
            &hold: the rate rises smoothly from 0 to ramp_rate over ramp_time, then holds &
            &(rad/s for angle drivers, m/s else)'), &
        var_spec_t('driver', 'ramp_time', kind_real, default='0', rule='[0,inf)', unit='s', &
            doc='the ramp''s duration, positive with ramp_rate'), &
        var_spec_t('force', 'name', kind_string, doc='unique name (default: force N)'), &
        var_spec_t('force', 'type', kind_string, &
            choices='spring_damper|rotational|bushing|applied', doc='the element, required'), &
        var_spec_t('force', 'marker_i', kind_string, doc='first marker (applied: the one)'), &
        var_spec_t('force', 'marker_j', kind_string, doc='second marker (not for applied)'), &
        var_spec_t('force', 'free_length', kind_real, default='0', rule='nonnegative', &
            unit='m', doc='spring_damper: unstretched length'), &
        var_spec_t('force', 'free_angle', kind_real, default='0', unit='rad', &
            doc='rotational: angle of zero torque'), &
        var_spec_t('force', 'stiffness', kind_real, 6, .true., &
            doc='k1..k5 of k1 e + k2 e^2 ..., rotational k, bushing diag K (6)'), &
        var_spec_t('force', 'damping', kind_real, 6, .true., rule='nonnegative', &
            doc='c (spring_damper, rotational), bushing diag C (6)'), &
        var_spec_t('force', 'stiffness_matrix', kind_real, 36, &
            doc='bushing: full K, row by row (in place of stiffness)'), &
        var_spec_t('force', 'damping_matrix', kind_real, 36, &
            doc='bushing: full C, row by row (in place of damping)'), &
        var_spec_t('force', 'force', kind_real, 3, default='0, 0, 0', unit='N', &
            doc='applied: F, times s(t)'), &
        var_spec_t('force', 'torque', kind_real, 3, default='0, 0, 0', unit='N m', &
            doc='applied: n, times s(t)'), &
        var_spec_t('force', 'frame', kind_string, default='world', choices='world|marker', &
            doc='applied: axes of force and torque'), &
        var_spec_t('force', 'coefficients', kind_real, 4, default='0, 0, 0, 0', &
            doc='applied: s = c0 + c1 t + c2 t^2 + c3 t^3 ...'), &
        var_spec_t('force', 'amplitude', kind_real, default='0', &
            doc='applied: ... + a sin(w t + phi)'), &
        var_spec_t('force', 'frequency', kind_real, default='0', unit='rad/s', &
            doc='applied: w'), &
        var_spec_t('force', 'phase', kind_real, default='0', unit='rad', doc='applied: phi'), &
        var_spec_t('rigid_chain', 'name', kind_string, doc='unique name (default: link N)'), &
        var_spec_t('rigid_chain', 'parent', kind_string, default='ground', &
            doc='''ground'' or an earlier link'), &
        var_spec_t('rigid_chain', 'joint', kind_string, default='revolute', &
            choices='revolute|prismatic|spherical', doc='joint to the parent'), &
        var_spec_t('rigid_chain', 'joint_position', kind_real, 3, default='0, 0, 0', &
            unit='m', doc='joint in the parent''s frame'), &
        var_spec_t('rigid_chain', 'joint_axis', kind_real, 3, default='0, 0, 1', &
            doc='joint axis, parent''s frame'), &
        var_spec_t('rigid_chain', 'centre', kind_real, 3, default='0, 0, 0', unit='m', &
            doc='centre of mass, own frame'), &
        var_spec_t('rigid_chain', 'mass', kind_real, unit='kg', doc='mass, required'), &
        var_spec_t('rigid_chain', 'inertia', kind_real, 3, unit='kg m^2', &
            doc='about the centre of mass, required'), &
        var_spec_t('rigid_chain', 'inertia_products', kind_real, 3, default='0, 0, 0', &
            unit='kg m^2', doc='Jxy, Jyz, Jxz'), &
        var_spec_t('rigid_chain', 'coordinate', kind_real, default='0', &
            doc='initial joint coordinate (rad or m)'), &
        var_spec_t('rigid_chain', 'rate', kind_real, default='0', &
            doc='initial joint rate (rad/s or m/s)'), &
        var_spec_t('rigid_chain', 'rotation_axis', kind_real, 3, default='0, 0, 1', &
            doc='spherical: initial relative rotation axis'), &
        var_spec_t('rigid_chain', 'rotation_angle', kind_real, default='0', unit='rad', &
            doc='spherical: initial relative rotation angle'), &
        var_spec_t('rigid_chain', 'angular_rate', kind_real, 3, default='0, 0, 0', &
            unit='rad/s', doc='spherical: initial angular velocity, own frame'), &
        var_spec_t('study', 'scene', kind_string, doc='the scene file, required'), &
        var_spec_t('study', 'reference_file', kind_string, &
            doc='HDF5 reference (default: STUDY_reference.h5)'), &
        var_spec_t('study', 'reference_solver', kind_string, default='radau5', &
            choices=solver_choices, doc='solver of the reference'), &
        var_spec_t('study', 'reference_tolerance', kind_real, default='1e-10', &
            rule='tolerance', doc='tolerance of the reference'), &
        var_spec_t('study', 'check_solver', kind_string, default='ddassl', &
            choices=solver_choices // '|none', doc='second solver checking the reference'), &
        var_spec_t('study', 'check_tolerance', kind_real, default='0', &
            doc='its tolerance (0: the reference tolerance)'), &
        var_spec_t('study', 'solvers', kind_string, max_study_solvers, &
            choices=solver_choices, doc='solvers of the grid (default: all four)'), &
        var_spec_t('study', 'stabilisations', kind_string, 3, choices='none|ggl|projection', &
            doc='stabilisations of the grid (default: none, ggl)'), &
        var_spec_t('study', 'tolerances', kind_real, max_study_tolerances, .true., &
            rule='tolerance', doc='tolerances of the grid (default: 1e-6)'), &
        var_spec_t('study', 'pmax', kind_integer, 5, .true., rule='[1,5]', &
            doc='largest BDF orders of the grid (default: 5)'), &
        var_spec_t('study', 'derivatives', kind_string, 3, choices='analytic|ad|ad_full', &
            doc='joint derivatives of the grid (default: analytic)'), &
        var_spec_t('study', 'table', kind_string, doc='the table (.md, .csv, .tex)'), &
        var_spec_t('study', 'cpu_reference', kind_integer, default='1', rule='[1,inf)', &
            doc='the row whose CPU time is 1 in the table'), &
        var_spec_t('study', 't_end', kind_real, default='0', rule='nonnegative', unit='s', &
            doc='end time of every run (0: the scene''s)'), &
        var_spec_t('study', 'max_steps', kind_integer, default='0', rule='[0,inf)', &
            doc='step limit of every run (0: the scene''s)'), &
        var_spec_t('study', 'layout', kind_string, default='table3', choices='table3|table2', &
            doc='the table''s layout'), &
        var_spec_t('study', 'reasons', kind_logical, default='.false.', &
            doc='the table also counts the rejected steps by cause (table2: as rows)')]

    character(len=16), parameter, public :: group_names(*) = [character(len=16) :: &
        'simulation', 'solver', 'output', 'flexible_body', 'material', 'multibody', &
        'rigid_body', 'marker', 'joint', 'driver', 'force', 'rigid_chain', 'study']
    !> The groups that may be given several times (one item each).
    character(len=16), parameter, public :: repeatable_groups(*) = [character(len=16) :: &
        'flexible_body', 'material', 'rigid_body', 'marker', 'joint', 'driver', 'force', 'rigid_chain']

    public :: find_group, find_var, known_vars, group_vars, string_length, choice_list, &
        is_choice, did_you_mean, split_choices

contains

    !> The index of group `name` in group_names, 0 when there is none.
    pure integer function find_group(name)
        character(len=*), intent(in) :: name
        integer :: g
        find_group = 0
        do g = 1, size(group_names)
            if (group_names(g) == name) find_group = g
        end do
    end function find_group

    !> The index of variable `name` of `group` in the schema table, 0 when the
    !> schema has no such variable.
    pure integer function find_var(group, name)
        character(len=*), intent(in) :: group, name
        integer :: i
        find_var = 0
        if (len(name) > len(schema(1)%name)) return
        do i = 1, size(schema)
            if (schema(i)%group == group .and. schema(i)%name == name) find_var = i
        end do
    end function find_var

    !> The variables of a group, 'a, b, c'.
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

    !> The names of a group's variables.
    pure function group_vars(group) result(names)
        character(len=*), intent(in) :: group
        character(len=24), allocatable :: names(:)
        names = pack(schema%name, schema%group == group)
    end function group_vars

    !> Declared length of a string variable.
    pure integer function string_length(name)
        character(len=*), intent(in) :: name
        select case (name)
        case ('title'); string_length = len_title
        case ('file', 'table', 'mesh_file', 'scene', 'reference_file', 'vtk', 'modes_cache')
            string_length = len_path
        case default; string_length = len_name
        end select
    end function string_length

    !> The choices of a variable as separate words.
    pure function split_choices(choices) result(words)
        character(len=*), intent(in) :: choices
        character(len=24), allocatable :: words(:)
        integer :: i, start, n
        n = count([(choices(i:i) == '|', i = 1, len_trim(choices))]) + 1
        allocate (words(n))
        start = 1
        n = 0
        do i = 1, len_trim(choices) + 1
            if (i > len_trim(choices)) then
                n = n + 1
                words(n) = choices(start:i - 1)
            else if (choices(i:i) == '|') then
                n = n + 1
                words(n) = choices(start:i - 1)
                start = i + 1
            end if
        end do
    end function split_choices

    !> Whether `value` is one of the '|'-separated `choices` (any case).
    pure logical function is_choice(value, choices)
        character(len=*), intent(in) :: value, choices
        character(len=24), allocatable :: words(:)
        words = split_choices(choices)
        is_choice = any(words == lower(value)) .and. len(value) <= len(words)
    end function is_choice

    !> "'a' or 'b'", "'a', 'b' or 'c'" (≤ 3 choices) or "one of 'a', ... or 'z'".
    pure function choice_list(names) result(list)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        if (size(names) > 3) list = 'one of '
        do i = 1, size(names)
            if (i == size(names) .and. i > 1) then
                list = list // ' or '
            else if (i > 1) then
                list = list // ', '
            end if
            list = list // '''' // trim(names(i)) // ''''
        end do
    end function choice_list

    !> ' (did you mean ''x''?)' or ''.
    pure function did_you_mean(word, candidates) result(hint)
        character(len=*), intent(in) :: word, candidates(:)
        character(len=:), allocatable :: hint, best
        best = nearest(word, candidates)
        hint = ''
        if (len(best) > 0 .and. best /= word) hint = ' (did you mean ''' // best // '''?)'
    end function did_you_mean

end module flexmbs_io_scene_schema
