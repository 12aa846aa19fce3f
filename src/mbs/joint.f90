!> A joint between marker i and marker j as its list of constraint
!> primitives, built from its type's entry in flexmbs_mbs_joint_types (the
!> table of joint types) or from one primitive (a driver, a distance). The
!> rows are evaluated for real and dual numbers by joint_value etc. in
!> flexmbs_mbs_constraint_primitives(_dual).
module flexmbs_mbs_joint
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_mbs_primitive_kinds, only: primitive_rows
    use flexmbs_mbs_joint_types, only: joint_types, joint_primitive_t, joint_choices, &
        joint_name, max_joint_primitives, joint_spherical, joint_revolute, joint_cylindrical, &
        joint_prismatic, joint_universal, joint_fixed, joint_primitive, joint_planar
    implicit none
    private

    ! the joint kinds, as the table numbers them, for the users of joints
    public :: max_joint_primitives, joint_spherical, joint_revolute, joint_cylindrical, &
        joint_prismatic, joint_universal, joint_fixed, joint_primitive, joint_planar

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

    !> The joint of the given kind (an entry of flexmbs_mbs_joint_types'
    !> table other than joint_primitive).
    subroutine new_joint(joint, kind, status)
        type(joint_t), intent(out) :: joint
        integer, intent(in) :: kind
        type(status_t), intent(inout) :: status
        type(joint_primitive_t) :: p
        integer :: k
        if (kind >= 1 .and. kind <= size(joint_types)) then
            ! (a copy: gfortran 12 misreads an associate name on an element of
            ! the parameter table indexed by variables)
            do k = 1, max_joint_primitives
                p = joint_types(kind)%primitives(k)
                if (p%kind == 0) exit
                call add(joint, p%kind, p%axis_i, p%axis_j)
            end do
        end if
        if (joint%nprimitives == 0) then
            call status%set(status_bad_input, 'joint kind ' // int_text(kind) // &
                            ' is unknown: use one of ' // joint_choices)
            return
        end if
        joint%kind = kind
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
