!> What a scene file says, typed: one derived type per group, filled by
!> flexmbs_io_scene_reader with the file's values and the schema's
!> defaults (flexmbs_io_scene_schema) for the rest.
module flexmbs_io_scene_input
    use flexmbs_core_kinds, only: wp
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_io_scene_records, only: scene_record_t, flexible_body_record_t, &
        material_record_t, multibody_record_t, rigid_body_record_t, marker_record_t, &
        joint_record_t, driver_record_t, force_record_t, rigid_chain_record_t
    implicit none
    private

    !> One `&material`: the paper's neo-Hookean law with damping, on an
    !> element set of a flexible body (its variables: io/scene_records).
    type, extends(material_record_t), public :: material_input_t
        integer :: line = 0 !! where the group starts
    end type material_input_t

    !> One `&flexible_body`: a box or a mesh file, nonlinear or modal.
    type, extends(flexible_body_record_t), public :: body_input_t
        integer :: line = 0 !! where the group starts
    end type body_input_t

    !> The `&multibody` group: formulation, gravity, derivatives, assembly.
    type, extends(multibody_record_t), public :: multibody_input_t
        integer :: line = 0 !! where the group starts
    end type multibody_input_t

    !> One `&rigid_body`.
    type, extends(rigid_body_record_t), public :: rigid_body_input_t
        integer :: line = 0 !! where the group starts
    end type rigid_body_input_t

    !> One `&marker`: a frame on a body, a node set or the ground.
    type, extends(marker_record_t), public :: marker_input_t
        !> whether `position` is given (node-set markers default to the centroid)
        logical :: position_given = .false.
        integer :: line = 0 !! where the group starts
    end type marker_input_t

    !> One `&joint` between two markers.
    type, extends(joint_record_t), public :: joint_input_t
        integer :: line = 0 !! where the group starts
    end type joint_input_t

    !> One `&driver`: s(t) = c0 + c1 t + c2 t² + c3 t³ + a sin(ω t + φ) + a ramp.
    type, extends(driver_record_t), public :: driver_input_t
        integer :: line = 0 !! where the group starts
    end type driver_input_t

    !> One `&force` element.
    type, extends(force_record_t), public :: force_input_t
        !> whether the full matrices are given (in place of the diagonals)
        logical :: has_stiffness_matrix = .false., has_damping_matrix = .false.
        integer :: line = 0 !! where the group starts
    end type force_input_t

    !> One link of a `&rigid_chain`.
    type, extends(rigid_chain_record_t), public :: chain_body_input_t
        integer :: line = 0 !! where the group starts
    end type chain_body_input_t

    !> Everything a scene file says, with defaults for what it leaves out:
    !> &simulation, &solver and &output in the record it extends
    !> (io/scene_records, generated from the schema), the other groups as
    !> lists of their records.
    type, extends(scene_record_t), public :: scene_input_t
        character(len=:), allocatable :: path !! the file read
        character(len=:), allocatable :: text !! its full text (stored in the HDF5 file)
        !> The solvers' own settings the scene gives (the schema's &solver
        !> variables without a default), in the schema's order: the solver
        !> factory hands them to the solver, and every other keeps the
        !> solver type's default, which is kept nowhere else.
        type(solver_setting_t), allocatable :: solver_settings(:)
        !> The HDF5 result: `file` resolved (io/scene_checks); '' = none.
        character(len=:), allocatable :: output_file
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

    public :: given_setting, marker_index, flexible_index, material_of, nonlinear_body, &
        modal_body

contains

    !> The solver setting `name` the scene gives, or one without a name when
    !> it gives none.
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
