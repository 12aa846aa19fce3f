!> The joint types: one table, the one place a joint type is declared. Each
!> entry gives the type's name (as a scene's `&joint type` names it), the
!> constraint primitives it is made of between marker i and marker j (Haug
!> 1989, sec. 3.4; Nikravesh 1988, ch. 7), and which joint coordinates it
!> has: the angle of x_j from x_i about z_i, the displacement x_j - x_i
!> along some of marker i's axes. The builder, the scene schema's choices,
!> the named output, the run summary and the VTK writer ask this table.
!> Convention: the joint axis is the z axis (3) of both markers; x (1) and
!> y (2) span the plane normal to it.
!>
!>   spherical    origins coincide                                    3 rows
!>   revolute     spherical; z_j normal to x_i and y_i (z axes parallel)  5 rows
!>   cylindrical  z axes parallel; x_j - x_i normal to x_i and y_i       4 rows
!>   prismatic    cylindrical; x_i normal to y_j (no rotation about z)   5 rows
!>   universal    spherical; z_i normal to z_j (the cross's two pins)    4 rows
!>   fixed        spherical; z axes parallel; x_i normal to y_j          6 rows
!>   planar       z axes parallel; x_j - x_i normal to z_i               3 rows
!>
!> Entry `joint_primitive` is the joint of one primitive given when it is
!> built (a driver, a distance): it has no rows of its own and is no choice
!> of `&joint`. The kind of a joint is its index in the table (also the
!> VTK files' `joint_type`, docs/output.md).
module flexmbs_mbs_joint_types
    use flexmbs_mbs_primitive_kinds, only: primitive_rows, primitive_dot1, primitive_dot2, &
        primitive_spherical
    implicit none
    private

    !> The most primitives a joint is built from.
    integer, parameter, public :: max_joint_primitives = 6

    !> One primitive of a joint: its kind and the axes of marker i and j it
    !> uses (0: none).
    type, public :: joint_primitive_t
        integer :: kind = 0
        integer :: axis_i = 0
        integer :: axis_j = 0
    end type joint_primitive_t

    !> A joint type (module header).
    type, public :: joint_type_t
        character(len=12) :: name = ''
        !> its primitives, in row order; kind 0 ends the list
        type(joint_primitive_t) :: primitives(max_joint_primitives) = joint_primitive_t()
        !> reports the angle of x_j from x_i about z_i
        logical :: angle = .false.
        !> reports x_j - x_i along marker i's axis k where displaced(k)
        logical :: displaced(3) = .false.
    end type joint_type_t

    integer, parameter, public :: joint_spherical = 1
    integer, parameter, public :: joint_revolute = 2
    integer, parameter, public :: joint_cylindrical = 3
    integer, parameter, public :: joint_prismatic = 4
    integer, parameter, public :: joint_universal = 5
    integer, parameter, public :: joint_fixed = 6
    !> A joint of one primitive (new_primitive_joint).
    integer, parameter, public :: joint_primitive = 7
    integer, parameter, public :: joint_planar = 8

    type(joint_primitive_t), parameter :: none = joint_primitive_t()
    type(joint_primitive_t), parameter :: spherical = joint_primitive_t(primitive_spherical)
    !> z_j normal to x_i, to y_i: together the z axes parallel
    type(joint_primitive_t), parameter :: z_j_normal_x_i = joint_primitive_t(primitive_dot1, 1, 3)
    type(joint_primitive_t), parameter :: z_j_normal_y_i = joint_primitive_t(primitive_dot1, 2, 3)
    !> x_i normal to y_j: no rotation about z
    type(joint_primitive_t), parameter :: x_i_normal_y_j = joint_primitive_t(primitive_dot1, 1, 2)
    !> z_i normal to z_j
    type(joint_primitive_t), parameter :: z_i_normal_z_j = joint_primitive_t(primitive_dot1, 3, 3)
    !> x_j - x_i normal to x_i, y_i, z_i
    type(joint_primitive_t), parameter :: offset_normal_x_i = joint_primitive_t(primitive_dot2, 1)
    type(joint_primitive_t), parameter :: offset_normal_y_i = joint_primitive_t(primitive_dot2, 2)
    type(joint_primitive_t), parameter :: offset_normal_z_i = joint_primitive_t(primitive_dot2, 3)

    !> The table (module header), indexed by joint kind.
    type(joint_type_t), parameter, public :: joint_types(8) = [ &
        joint_type_t('spherical', [spherical, none, none, none, none, none]), &
        joint_type_t('revolute', [spherical, z_j_normal_x_i, z_j_normal_y_i, none, none, &
            none], angle=.true.), &
        joint_type_t('cylindrical', [z_j_normal_x_i, z_j_normal_y_i, offset_normal_x_i, &
            offset_normal_y_i, none, none], angle=.true., &
            displaced=[.false., .false., .true.]), &
        joint_type_t('prismatic', [z_j_normal_x_i, z_j_normal_y_i, offset_normal_x_i, &
            offset_normal_y_i, x_i_normal_y_j, none], displaced=[.false., .false., .true.]), &
        joint_type_t('universal', [spherical, z_i_normal_z_j, none, none, none, none]), &
        joint_type_t('fixed', [spherical, z_j_normal_x_i, z_j_normal_y_i, x_i_normal_y_j, none, &
            none]), &
        joint_type_t('primitive'), &
        joint_type_t('planar', [z_j_normal_x_i, z_j_normal_y_i, offset_normal_z_i, none, none, &
            none], angle=.true., displaced=[.true., .true., .false.])]

    !> The names of the joint types a scene's `&joint` may give, as the
    !> scene schema lists choices (test/layers.py checks it against the table).
    character(len=*), parameter, public :: joint_choices = &
        'spherical|revolute|cylindrical|prismatic|universal|fixed|planar'

    public :: joint_kind, joint_name, joint_type_rows, joint_type_of, joint_has_angle, &
        joint_displaced_axes

contains

    !> The kind of the joint type named `name` (trailing blanks ignored);
    !> 0 when no `&joint` type has that name.
    pure integer function joint_kind(name) result(kind)
        character(len=*), intent(in) :: name
        do kind = 1, size(joint_types)
            if (joint_types(kind)%primitives(1)%kind == 0) cycle
            if (trim(joint_types(kind)%name) == trim(name)) return
        end do
        kind = 0
    end function joint_kind

    !> The name of joint kind `kind`; 'unknown' outside the table.
    pure function joint_name(kind) result(name)
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        name = 'unknown'
        if (kind >= 1 .and. kind <= size(joint_types)) name = trim(joint_types(kind)%name)
    end function joint_name

    !> The table's entry of kind `kind`; an empty entry (no rows, no
    !> coordinates) outside the table.
    pure function joint_type_of(kind) result(entry)
        integer, intent(in) :: kind
        type(joint_type_t) :: entry
        if (kind >= 1 .and. kind <= size(joint_types)) entry = joint_types(kind)
    end function joint_type_of

    !> Whether joint kind `kind` reports the angle of x_j from x_i about z_i
    !> (false outside the table).
    pure logical function joint_has_angle(kind)
        integer, intent(in) :: kind
        type(joint_type_t) :: entry
        entry = joint_type_of(kind)
        joint_has_angle = entry%angle
    end function joint_has_angle

    !> The axes k of marker i along which joint kind `kind` reports x_j - x_i
    !> (none outside the table).
    pure function joint_displaced_axes(kind) result(displaced)
        integer, intent(in) :: kind
        logical :: displaced(3)
        type(joint_type_t) :: entry
        entry = joint_type_of(kind)
        displaced = entry%displaced
    end function joint_displaced_axes

    !> The constraint rows of joint kind `kind` (0 outside the table and for
    !> joint_primitive, whose rows its one primitive gives).
    pure integer function joint_type_rows(kind) result(rows)
        integer, intent(in) :: kind
        integer :: k
        rows = 0
        if (kind < 1 .or. kind > size(joint_types)) return
        do k = 1, max_joint_primitives
            rows = rows + primitive_rows(joint_types(kind)%primitives(k)%kind)
        end do
    end function joint_type_rows
end module flexmbs_mbs_joint_types
