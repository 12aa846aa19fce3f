!> A solid mesh: reference nodal positions, hexahedral connectivity (VTK node
!> order, see flexmbs_fe_hexahedron), named node sets (faces, edges, ...) and
!> named element sets (material regions such as the paper's tip layers).
module flexmbs_fe_mesh
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text, excerpt, nearest
    implicit none
    private

    !> A named set of node numbers.
    type, public :: node_set_t
        character(len=:), allocatable :: name
        integer, allocatable :: nodes(:)
    end type node_set_t

    !> A named set of element numbers.
    type, public :: element_set_t
        character(len=:), allocatable :: name
        integer, allocatable :: elements(:)
    end type element_set_t

    !> A hexahedral mesh (hex8 or hex27, nodes in VTK order): reference nodal
    !> positions, connectivity and named node and element sets.
    type, public :: mesh_t
        integer :: nnode_element = 0                 !! 8 or 27
        real(wp), allocatable :: x(:, :)             !! (3, nodes) reference positions
        integer, allocatable :: connectivity(:, :)   !! (nnode_element, elements)
        type(node_set_t), allocatable :: node_sets(:)
        type(element_set_t), allocatable :: element_sets(:)
    contains
        procedure :: node_count => mesh_node_count
        procedure :: element_count => mesh_element_count
        procedure :: node_set => mesh_node_set
        procedure :: element_set => mesh_element_set
        procedure :: check => mesh_check
        procedure :: nodes_per_element => mesh_nodes_per_element
        procedure :: reference_positions => mesh_reference_positions
        procedure :: reference_position => mesh_reference_position
        procedure :: centroid => mesh_centroid
        procedure :: element_nodes => mesh_element_nodes
        procedure :: node_set_count => mesh_node_set_count
        procedure :: node_set_name => mesh_node_set_name
        procedure :: node_set_nodes => mesh_node_set_nodes
        procedure :: element_set_count => mesh_element_set_count
        procedure :: element_set_name => mesh_element_set_name
        procedure :: element_set_elements => mesh_element_set_elements
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

    !> 8 or 27.
    pure integer function mesh_nodes_per_element(self) result(n)
        class(mesh_t), intent(in) :: self
        n = self%nnode_element
    end function mesh_nodes_per_element

    !> Every node's reference position (3, nodes).
    pure function mesh_reference_positions(self) result(x)
        class(mesh_t), intent(in) :: self
        real(wp), allocatable :: x(:, :)
        x = self%x
    end function mesh_reference_positions

    !> Node `node`'s reference position.
    pure function mesh_reference_position(self, node) result(x)
        class(mesh_t), intent(in) :: self
        integer, intent(in) :: node
        real(wp) :: x(3)
        x = self%x(:, node)
    end function mesh_reference_position

    !> The mean of the reference positions (every node weighted alike).
    pure function mesh_centroid(self) result(c)
        class(mesh_t), intent(in) :: self
        real(wp) :: c(3)
        c = sum(self%x, dim=2) / real(self%node_count(), wp)
    end function mesh_centroid

    !> The nodes of each element (nodes_per_element, elements).
    pure function mesh_element_nodes(self) result(nodes)
        class(mesh_t), intent(in) :: self
        integer, allocatable :: nodes(:, :)
        nodes = self%connectivity
    end function mesh_element_nodes

    !> The number of named node sets.
    pure integer function mesh_node_set_count(self) result(n)
        class(mesh_t), intent(in) :: self
        n = 0
        if (allocated(self%node_sets)) n = size(self%node_sets)
    end function mesh_node_set_count

    !> The name of node set k (1..node_set_count).
    pure function mesh_node_set_name(self, k) result(name)
        class(mesh_t), intent(in) :: self
        integer, intent(in) :: k
        character(len=:), allocatable :: name
        name = self%node_sets(k)%name
    end function mesh_node_set_name

    !> The nodes of node set k (1..node_set_count).
    pure function mesh_node_set_nodes(self, k) result(nodes)
        class(mesh_t), intent(in) :: self
        integer, intent(in) :: k
        integer, allocatable :: nodes(:)
        nodes = self%node_sets(k)%nodes
    end function mesh_node_set_nodes

    !> The number of named element sets.
    pure integer function mesh_element_set_count(self) result(n)
        class(mesh_t), intent(in) :: self
        n = 0
        if (allocated(self%element_sets)) n = size(self%element_sets)
    end function mesh_element_set_count

    !> The name of element set k (1..element_set_count).
    pure function mesh_element_set_name(self, k) result(name)
        class(mesh_t), intent(in) :: self
        integer, intent(in) :: k
        character(len=:), allocatable :: name
        name = self%element_sets(k)%name
    end function mesh_element_set_name

    !> The elements of element set k (1..element_set_count).
    pure function mesh_element_set_elements(self, k) result(elements)
        class(mesh_t), intent(in) :: self
        integer, intent(in) :: k
        integer, allocatable :: elements(:)
        elements = self%element_sets(k)%elements
    end function mesh_element_set_elements

    !> The nodes of the set called `name`; bad input naming the set if absent.
    subroutine mesh_node_set(self, name, nodes, status)
        class(mesh_t), intent(in) :: self
        character(len=*), intent(in) :: name
        integer, allocatable, intent(out) :: nodes(:)
        type(status_t), intent(out) :: status
        character(len=64), allocatable :: names(:)
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
        names = [character(len=64) ::]
        if (allocated(self%node_sets)) names = [character(len=64) :: &
            (self%node_sets(i)%name, i = 1, size(self%node_sets))]
        call status%set(status_bad_input, 'mesh: no node set named ''' // excerpt(name) // &
            '''' // known_sets(names, name))
    end subroutine mesh_node_set

    !> The elements of the set called `name`; bad input naming the set if absent.
    subroutine mesh_element_set(self, name, elements, status)
        class(mesh_t), intent(in) :: self
        character(len=*), intent(in) :: name
        integer, allocatable, intent(out) :: elements(:)
        type(status_t), intent(out) :: status
        character(len=64), allocatable :: names(:)
        integer :: i
        if (allocated(self%element_sets)) then
            do i = 1, size(self%element_sets)
                if (self%element_sets(i)%name == name) then
                    elements = self%element_sets(i)%elements
                    return
                end if
            end do
        end if
        allocate (elements(0))
        names = [character(len=64) ::]
        if (allocated(self%element_sets)) names = [character(len=64) :: &
            (self%element_sets(i)%name, i = 1, size(self%element_sets))]
        call status%set(status_bad_input, 'mesh: no element set named ''' // excerpt(name) // &
            '''' // known_sets(names, name))
    end subroutine mesh_element_set

    !> ' (did you mean ''x''?) (known: a, b, ...)', at most ~80 characters
    !> of names; ' (the mesh has none)' without sets.
    function known_sets(names, name) result(text)
        character(len=*), intent(in) :: names(:), name
        character(len=:), allocatable :: text, list, best
        integer :: i
        if (size(names) == 0) then
            text = ' (the mesh has none)'
            return
        end if
        list = ''
        do i = 1, size(names)
            if (i > 1) list = list // ', '
            list = list // trim(names(i))
        end do
        best = nearest(name, names)
        text = ''
        if (len(best) > 0) text = ' (did you mean ''' // best // '''?)'
        text = text // ' (known: ' // excerpt(list) // ')'
    end function known_sets

    !> Consistency checks: 8 or 27 nodes per element, connectivity within the nodes
    !> and without repeats, set members in range, set names unique per kind.
    subroutine mesh_check(self, status)
        class(mesh_t), intent(in) :: self
        type(status_t), intent(out) :: status
        integer :: e, a, i, j, n, ne
        if (self%nnode_element /= 8 .and. self%nnode_element /= 27) then
            call status%set(status_bad_input, 'mesh: ' // int_text(self%nnode_element) // &
                            ' nodes per element; 8 or 27 expected')
            return
        end if
        n = self%node_count()
        ne = self%element_count()
        if (.not. allocated(self%connectivity)) then
            call status%set(status_bad_input, 'mesh: no elements')
            return
        end if
        if (size(self%connectivity, 1) /= self%nnode_element) then
            call status%set(status_bad_input, 'mesh: connectivity rows differ from nodes per element')
            return
        end if
        do e = 1, ne
            do a = 1, self%nnode_element
                if (self%connectivity(a, e) < 1 .or. self%connectivity(a, e) > n) then
                    call status%set(status_bad_input, 'mesh: element ' // int_text(e) // &
                        ' names node ' // int_text(self%connectivity(a, e)) // &
                        ', outside 1..' // int_text(n))
                    return
                end if
                if (any(self%connectivity(a + 1:, e) == self%connectivity(a, e))) then
                    call status%set(status_bad_input, 'mesh: element ' // int_text(e) // &
                        ' names node ' // int_text(self%connectivity(a, e)) // ' twice')
                    return
                end if
            end do
        end do
        if (allocated(self%node_sets)) then
            do i = 1, size(self%node_sets)
                if (any(self%node_sets(i)%nodes < 1 .or. self%node_sets(i)%nodes > n)) then
                    call status%set(status_bad_input, 'mesh: node set ''' // &
                        self%node_sets(i)%name // ''' has a node outside 1..' // int_text(n))
                    return
                end if
                do j = i + 1, size(self%node_sets)
                    if (self%node_sets(j)%name == self%node_sets(i)%name) then
                        call status%set(status_bad_input, 'mesh: two node sets named ''' // &
                                        self%node_sets(i)%name // '''')
                        return
                    end if
                end do
            end do
        end if
        if (allocated(self%element_sets)) then
            do i = 1, size(self%element_sets)
                if (any(self%element_sets(i)%elements < 1 .or. &
                        self%element_sets(i)%elements > ne)) then
                    call status%set(status_bad_input, 'mesh: element set ''' // &
                        self%element_sets(i)%name // ''' has an element outside 1..' // &
                        int_text(ne))
                    return
                end if
                do j = i + 1, size(self%element_sets)
                    if (self%element_sets(j)%name == self%element_sets(i)%name) then
                        call status%set(status_bad_input, 'mesh: two element sets named ''' &
                                        // self%element_sets(i)%name // '''')
                        return
                    end if
                end do
            end do
        end if
    end subroutine mesh_check
end module flexmbs_fe_mesh
