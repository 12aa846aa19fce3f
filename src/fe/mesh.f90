!> A solid mesh: reference nodal positions, hexahedral connectivity (VTK node
!> order, see flexmbs_fe_hexahedron) and named node sets (faces, edges, ...).
module flexmbs_fe_mesh
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    implicit none
    private

    !> A named set of node numbers.
    type, public :: node_set_t
        character(len=:), allocatable :: name
        integer, allocatable :: nodes(:)
    end type node_set_t

    type, public :: mesh_t
        integer :: nnode_element = 0                 !! 8 or 27
        real(wp), allocatable :: x(:, :)             !! (3, nodes) reference positions
        integer, allocatable :: connectivity(:, :)   !! (nnode_element, elements)
        type(node_set_t), allocatable :: node_sets(:)
    contains
        procedure :: node_count => mesh_node_count
        procedure :: element_count => mesh_element_count
        procedure :: node_set => mesh_node_set
    end type mesh_t

contains

    pure integer function mesh_node_count(self)
        class(mesh_t), intent(in) :: self
        mesh_node_count = 0
        if (allocated(self%x)) mesh_node_count = size(self%x, 2)
    end function mesh_node_count

    pure integer function mesh_element_count(self)
        class(mesh_t), intent(in) :: self
        mesh_element_count = 0
        if (allocated(self%connectivity)) mesh_element_count = size(self%connectivity, 2)
    end function mesh_element_count

    !> The nodes of the set called `name`; bad input naming the set if absent.
    subroutine mesh_node_set(self, name, nodes, status)
        class(mesh_t), intent(in) :: self
        character(len=*), intent(in) :: name
        integer, allocatable, intent(out) :: nodes(:)
        type(status_t), intent(out) :: status
        integer :: i
        if (allocated(self%node_sets)) then
            do i = 1, size(self%node_sets)
                if (self%node_sets(i)%name == name) then
                    nodes = self%node_sets(i)%nodes
                    return
                end if
            end do
        end if
        allocate (nodes(0))
        call status%set(status_bad_input, 'mesh: no node set named ''' // name // '''')
    end subroutine mesh_node_set
end module flexmbs_fe_mesh
