!> The constraint primitives between two markers, by name, and their row counts.
!> Shared by the real and dual instances of the primitives (constraint_primitives.inc).
module flexmbs_mbs_primitive_kinds
    implicit none
    private

    !> a_i . a_j = 0: two marker axes stay perpendicular.
    integer, parameter, public :: primitive_dot1 = 1
    !> a_i . (x_j - x_i) = 0: the marker offset stays perpendicular to an axis of i.
    integer, parameter, public :: primitive_dot2 = 2
    !> x_j - x_i = 0: the marker origins coincide (3 rows).
    integer, parameter, public :: primitive_spherical = 3
    !> |x_j - x_i|^2 - s(t)^2 = 0: prescribed (or constant) distance.
    integer, parameter, public :: primitive_distance = 4
    !> sin(theta - s(t)) = 0: the angle theta from axis k of marker i to axis k of
    !> marker j, about the axis k+2 (cyclic) of marker i, follows s(t).
    integer, parameter, public :: primitive_angle_driver = 5
    !> a_i . (x_j - x_i) - s(t) = 0: the offset along an axis of i follows s(t).
    integer, parameter, public :: primitive_translation_driver = 6

    public :: primitive_rows, primitive_name

contains

    !> Rows the primitive contributes to c; 0 for an unknown kind.
    pure integer function primitive_rows(kind)
        integer, intent(in) :: kind
        select case (kind)
        case (primitive_dot1, primitive_dot2, primitive_distance, primitive_angle_driver, &
              primitive_translation_driver)
            primitive_rows = 1
        case (primitive_spherical)
            primitive_rows = 3
        case default
            primitive_rows = 0
        end select
    end function primitive_rows

    !> A primitive kind as words for messages ('dot-1', 'spherical', 'angle
    !> driver', ...; 'unknown' otherwise).
    pure function primitive_name(kind) result(name)
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        select case (kind)
        case (primitive_dot1)
            name = 'dot-1'
        case (primitive_dot2)
            name = 'dot-2'
        case (primitive_spherical)
            name = 'spherical'
        case (primitive_distance)
            name = 'distance'
        case (primitive_angle_driver)
            name = 'angle driver'
        case (primitive_translation_driver)
            name = 'translation driver'
        case default
            name = 'unknown'
        end select
    end function primitive_name
end module flexmbs_mbs_primitive_kinds
