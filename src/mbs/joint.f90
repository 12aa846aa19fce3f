!> Joints as lists of constraint primitives between marker i and marker j
!> (Haug 1989, sec. 3.4; Nikravesh 1988, ch. 7). Convention: the joint axis is the
!> z axis (3) of both markers; x (1) and y (2) span the plane normal to it.
!>
!>   spherical    origins coincide                                    3 rows
!>   revolute     spherical; z_j normal to x_i and y_i (z axes parallel)  5 rows
!>   cylindrical  z axes parallel; x_j - x_i normal to x_i and y_i       4 rows
!>   prismatic    cylindrical; x_i normal to y_j (no rotation about z)   5 rows
!>   universal    spherical; z_i normal to z_j (the cross's two pins)    4 rows
!>   fixed        spherical; z axes parallel; x_i normal to y_j          6 rows
!>
!> A single primitive (a driver, a distance) is a joint of one primitive. The rows
!> are evaluated for real and dual numbers by joint_value etc. in
!> flexmbs_mbs_constraint_primitives(_dual).
module flexmbs_mbs_joint
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_mbs_primitive_kinds, only: primitive_rows, primitive_dot1, primitive_dot2, &
        primitive_spherical
    implicit none
    private

    integer, parameter, public :: joint_spherical = 1
    integer, parameter, public :: joint_revolute = 2
    integer, parameter, public :: joint_cylindrical = 3
    integer, parameter, public :: joint_prismatic = 4
    integer, parameter, public :: joint_universal = 5
    integer, parameter, public :: joint_fixed = 6
    !> A joint of one primitive (new_primitive_joint).
    integer, parameter, public :: joint_primitive = 7
    !> The most primitives a joint is built from.
    integer, parameter, public :: max_joint_primitives = 6

    !> The parts of a joint evaluated by joint_rows.
    integer, parameter, public :: joint_part_time_derivative = 1 !! c_t
    integer, parameter, public :: joint_part_convective = 2 !! (C v)_q T v
    integer, parameter, public :: joint_part_time_terms = 3 !! 2 C_t v + c_tt

    !> A joint as a list of constraint primitives (see the module's table): its
    !> kind, its rows and, for each primitive, its kind and the marker axes it uses.
    type, public :: joint_t
        integer :: kind = 0
        integer :: nprimitives = 0
        integer :: nrows = 0
        integer :: primitive(max_joint_primitives) = 0 !! primitive kinds
        integer :: axis_i(max_joint_primitives) = 0 !! axis of marker i each uses
        integer :: axis_j(max_joint_primitives) = 0 !! axis of marker j each uses
    end type joint_t

    public :: new_joint, new_primitive_joint, joint_name

contains

    !> The joint of the given kind (joint_spherical ... joint_fixed).
    subroutine new_joint(joint, kind, status)
        type(joint_t), intent(out) :: joint
        integer, intent(in) :: kind
        type(status_t), intent(inout) :: status
        joint%kind = kind
        select case (kind)
        case (joint_spherical)
            call add(joint, primitive_spherical, 0, 0)
        case (joint_revolute)
            call add(joint, primitive_spherical, 0, 0)
            call add_parallel_z(joint)
        case (joint_cylindrical)
            call add_parallel_z(joint)
            call add(joint, primitive_dot2, 1, 0)
            call add(joint, primitive_dot2, 2, 0)
        case (joint_prismatic)
            call add_parallel_z(joint)
            call add(joint, primitive_dot2, 1, 0)
            call add(joint, primitive_dot2, 2, 0)
            call add(joint, primitive_dot1, 1, 2)
        case (joint_universal)
            call add(joint, primitive_spherical, 0, 0)
            call add(joint, primitive_dot1, 3, 3)
        case (joint_fixed)
            call add(joint, primitive_spherical, 0, 0)
            call add_parallel_z(joint)
            call add(joint, primitive_dot1, 1, 2)
        case default
            joint%kind = 0
            call status%set(status_bad_input, 'joint kind ' // int_text(kind) // &
                            ' is unknown: use spherical, revolute, cylindrical, ' // &
                            'prismatic, universal or fixed')
        end select
    end subroutine new_joint

    !> A joint of the one primitive `kind` on axis ki of marker i and kj of marker j.
    subroutine new_primitive_joint(joint, kind, ki, kj, status)
        type(joint_t), intent(out) :: joint
        integer, intent(in) :: kind, ki, kj
        type(status_t), intent(inout) :: status
        if (primitive_rows(kind) == 0 .or. ki < 1 .or. ki > 3 .or. kj < 1 .or. kj > 3) then
            call status%set(status_bad_input, 'constraint primitive ' // int_text(kind) // &
                            ' on axes ' // int_text(ki) // ', ' // int_text(kj) // &
                            ': unknown primitive or axis not in 1..3')
            return
        end if
        joint%kind = joint_primitive
        call add(joint, kind, ki, kj)
    end subroutine new_primitive_joint

    !> The scene's word for a joint kind ('spherical' ... 'fixed', 'primitive';
    !> 'unknown' otherwise), for messages and the VTK joints' files.
    pure function joint_name(kind) result(name)
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        select case (kind)
        case (joint_spherical)
            name = 'spherical'
        case (joint_revolute)
            name = 'revolute'
        case (joint_cylindrical)
            name = 'cylindrical'
        case (joint_prismatic)
            name = 'prismatic'
        case (joint_universal)
            name = 'universal'
        case (joint_fixed)
            name = 'fixed'
        case (joint_primitive)
            name = 'primitive'
        case default
            name = 'unknown'
        end select
    end function joint_name

    !> z_j normal to x_i and to y_i.
    subroutine add_parallel_z(joint)
        type(joint_t), intent(inout) :: joint
        call add(joint, primitive_dot1, 1, 3)
        call add(joint, primitive_dot1, 2, 3)
    end subroutine add_parallel_z

    subroutine add(joint, kind, ki, kj)
        type(joint_t), intent(inout) :: joint
        integer, intent(in) :: kind, ki, kj
        joint%nprimitives = joint%nprimitives + 1
        joint%primitive(joint%nprimitives) = kind
        ! Axis 0 (unused by the primitive) is stored as 1 to keep array indices valid.
        joint%axis_i(joint%nprimitives) = max(ki, 1)
        joint%axis_j(joint%nprimitives) = max(kj, 1)
        joint%nrows = joint%nrows + primitive_rows(kind)
    end subroutine add
end module flexmbs_mbs_joint
