!> The flexmbs text mesh format, for meshes made elsewhere.
!>
!> Whitespace-separated tokens, free layout over lines; `#` starts a comment
!> to the end of the line; keywords are case-insensitive:
!>
!>     flexmbs-mesh 1
!>     nodes N
!>       1 x y z            (ids 1..N in this order)
!>       ...
!>     elements hex8|hex27 E
!>       1 n1 ... n8|n27    (ids 1..E in order; nodes in VTK order, see
!>       ...                 flexmbs_fe_hexahedron)
!>     node_set NAME K      (any number of sets, in any order after the
!>       id id ...           elements; K ids follow)
!>     element_set NAME K
!>       id id ...
!>
!> Every error names the file, the line and the reason; on error the mesh
!> is left empty. Elements must not be inverted: det J at the element
!> centre must be positive. `write_mesh` writes reals in es24.16e3, so a
!> round trip is exact.
module flexmbs_fe_mesh_file
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_text, only: int_text, lower, excerpt
    use flexmbs_fe_mesh_tokens, only: token_cursor_t, open_tokens
    use flexmbs_fe_hexahedron, only: shape_functions
    use flexmbs_fe_tensor, only: det3
    use flexmbs_fe_mesh, only: mesh_t, node_set_t, element_set_t
    implicit none
    private

    public :: read_mesh, write_mesh

    character(len=*), parameter :: magic = 'flexmbs-mesh'

contains

    !> Read a mesh in the flexmbs text format (the module's grammar) from `path`;
    !> an error names the file, the line and the reason and leaves `mesh` empty.
    subroutine read_mesh(path, mesh, status)
        character(len=*), intent(in) :: path
        type(mesh_t), intent(out) :: mesh
        type(status_t), intent(out) :: status
        type(token_cursor_t) :: cur
        type(mesh_t) :: work
        integer :: k
        call open_tokens(path, cur, status)
        if (.not. status%ok()) return
        call cur%expect_word(magic, status)
        if (.not. status%ok()) return
        call cur%next_int(k, 'format version', status)
        if (.not. status%ok()) return
        if (k /= 1) then
            call cur%fail('format version ' // int_text(k) // ' is not supported (1 is)', status)
            return
        end if
        call read_nodes(cur, path, work, status)
        if (.not. status%ok()) return
        call read_elements(cur, path, work, status)
        if (.not. status%ok()) return
        call read_sets(cur, path, work, status)
        if (.not. status%ok()) return
        call work%check(status)
        if (.not. status%ok()) then
            call status%set(status_bad_input, path // ': ' // status%text())
            return
        end if
        mesh = work
    end subroutine read_mesh

    !> 'nodes N' and the N nodes, ids 1..N in order, into work%x.
    subroutine read_nodes(cur, path, work, status)
        type(token_cursor_t), intent(inout) :: cur
        character(len=*), intent(in) :: path
        type(mesh_t), intent(inout) :: work
        type(status_t), intent(inout) :: status
        integer :: nnode, i, k, id, stat
        real(wp) :: x(3)
        call cur%expect_word('nodes', status)
        if (.not. status%ok()) return
        call cur%next_int(nnode, 'node count', status)
        if (.not. status%ok()) return
        if (nnode < 1) then
            call cur%fail('node count must be positive', status)
            return
        end if
        ! counts beyond what the text can hold are refused before allocating
        if (.not. cur%fits(nnode, 4, 'nodes', status)) return
        allocate (work%x(3, nnode), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': node coordinates', 3_i8 * nnode, 8)
            return
        end if
        do i = 1, nnode
            call cur%next_int(id, 'node id', status)
            if (.not. status%ok()) return
            if (id /= i) then
                call cur%fail('node id ' // int_text(id) // ' where ' // int_text(i) // &
                              ' is expected (ids run 1..N in order)', status)
                return
            end if
            do k = 1, 3
                call cur%next_real(x(k), 'node coordinate', status)
                if (.not. status%ok()) return
            end do
            work%x(:, i) = x
        end do
    end subroutine read_nodes

    !> 'elements hex8|hex27 E' and the E elements, ids 1..E in order, into
    !> work%connectivity; an inverted element is bad input.
    subroutine read_elements(cur, path, work, status)
        type(token_cursor_t), intent(inout) :: cur
        character(len=*), intent(in) :: path
        type(mesh_t), intent(inout) :: work
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: word
        integer :: nnode, nelem, i, a, k, id, stat
        nnode = size(work%x, 2)
        call cur%expect_word('elements', status)
        if (.not. status%ok()) return
        call cur%next_word(word, 'element type', status)
        if (.not. status%ok()) return
        select case (lower(word))
        case ('hex8')
            work%nnode_element = 8
        case ('hex27')
            work%nnode_element = 27
        case default
            call cur%fail('element type ''' // excerpt(word) // ''': hex8 or hex27 expected', &
                          status)
            return
        end select
        call cur%next_int(nelem, 'element count', status)
        if (.not. status%ok()) return
        if (nelem < 1) then
            call cur%fail('element count must be positive', status)
            return
        end if
        if (.not. cur%fits(nelem, work%nnode_element + 1, 'elements', status)) return
        allocate (work%connectivity(work%nnode_element, nelem), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': connectivity', &
                int(work%nnode_element, i8) * nelem, 4)
            return
        end if
        do i = 1, nelem
            call cur%next_int(id, 'element id', status)
            if (.not. status%ok()) return
            if (id /= i) then
                call cur%fail('element id ' // int_text(id) // ' where ' // int_text(i) // &
                              ' is expected (ids run 1..E in order)', status)
                return
            end if
            do a = 1, work%nnode_element
                call cur%next_int(k, 'element node', status)
                if (.not. status%ok()) return
                if (k < 1 .or. k > nnode) then
                    call cur%fail('element ' // int_text(i) // ' names node ' // int_text(k) // &
                                  ', outside 1..' // int_text(nnode), status)
                    return
                end if
                work%connectivity(a, i) = k
            end do
            if (.not. positive_centre_jacobian(work, i)) then
                call cur%fail('element ' // int_text(i) // ' is inverted or degenerate ' // &
                              '(det J <= 0 at its centre; check the VTK node order)', status)
                return
            end if
        end do
    end subroutine read_elements

    !> The node and element sets, to the end of the file.
    subroutine read_sets(cur, path, work, status)
        type(token_cursor_t), intent(inout) :: cur
        character(len=*), intent(in) :: path
        type(mesh_t), intent(inout) :: work
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: word, name
        type(node_set_t) :: node_set
        type(element_set_t) :: element_set
        integer :: nset, j
        allocate (work%node_sets(0), work%element_sets(0))
        do while (.not. cur%at_end())
            call cur%next_word(word, 'set keyword', status)
            if (.not. status%ok()) return
            select case (lower(word))
            case ('node_set', 'element_set')
                call cur%next_word(name, 'set name', status)
                if (.not. status%ok()) return
                call cur%next_int(nset, 'set size', status)
                if (.not. status%ok()) return
                if (nset < 0) then
                    call cur%fail('set ''' // excerpt(name) // ''': negative size', status)
                    return
                end if
                if (lower(word) == 'node_set') then
                    if (any([(work%node_sets(j)%name == name, j = 1, size(work%node_sets))])) then
                        call cur%fail('a second node set named ''' // excerpt(name) // '''', &
                                      status)
                        return
                    end if
                    node_set%name = name
                    call read_set_ids(cur, path, 'node', name, nset, size(work%x, 2), &
                                      node_set%nodes, status)
                    if (.not. status%ok()) return
                    work%node_sets = [work%node_sets, node_set]
                else
                    if (any([(work%element_sets(j)%name == name, &
                              j = 1, size(work%element_sets))])) then
                        call cur%fail('a second element set named ''' // excerpt(name) // '''', &
                                      status)
                        return
                    end if
                    element_set%name = name
                    call read_set_ids(cur, path, 'element', name, nset, &
                                      size(work%connectivity, 2), element_set%elements, status)
                    if (.not. status%ok()) return
                    work%element_sets = [work%element_sets, element_set]
                end if
            case default
                call cur%fail('''' // excerpt(word) // ''': node_set or element_set expected', &
                              status)
                return
            end select
        end do
    end subroutine read_sets

    !> The nset ids of set `name` of `kind` ('node' or 'element'), each in
    !> 1..bound.
    subroutine read_set_ids(cur, path, kind, name, nset, bound, ids, status)
        type(token_cursor_t), intent(inout) :: cur
        character(len=*), intent(in) :: path, kind, name
        integer, intent(in) :: nset, bound
        integer, allocatable, intent(out) :: ids(:)
        type(status_t), intent(inout) :: status
        integer :: j, stat
        if (.not. cur%fits(nset, 1, 'set members', status)) return
        allocate (ids(nset), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': ' // kind // ' set', int(nset, i8), 4)
            return
        end if
        do j = 1, nset
            call cur%next_int(ids(j), kind // ' id of set ''' // excerpt(name) // '''', status)
            if (.not. status%ok()) return
            if (ids(j) < 1 .or. ids(j) > bound) then
                call cur%fail(kind // ' set ''' // excerpt(name) // ''' names ' // kind // ' ' &
                              // int_text(ids(j)) // ', outside 1..' // int_text(bound), status)
                return
            end if
        end do
    end subroutine read_set_ids

    !> Write `mesh` in the format above; an I/O error names the file.
    subroutine write_mesh(path, mesh, status)
        character(len=*), intent(in) :: path
        type(mesh_t), intent(in) :: mesh
        type(status_t), intent(out) :: status
        integer :: unit, ios, i
        character(len=256) :: msg
        call mesh%check(status)
        if (.not. status%ok()) return
        open (newunit=unit, file=path, status='replace', action='write', iostat=ios, &
              iomsg=msg)
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot open: ' // trim(msg))
            return
        end if
        write (unit, '(a,1x,i0)', iostat=ios) magic, 1
        write (unit, '(a,1x,i0)', iostat=ios) 'nodes', mesh%node_count()
        do i = 1, mesh%node_count()
            if (ios == 0) write (unit, '(i0,3(1x,es24.16e3))', iostat=ios) i, mesh%x(:, i)
        end do
        if (ios == 0) write (unit, '(a,1x,a,1x,i0)', iostat=ios) 'elements', &
            trim(merge('hex8 ', 'hex27', mesh%nnode_element == 8)), mesh%element_count()
        do i = 1, mesh%element_count()
            if (ios == 0) write (unit, '(i0,*(1x,i0))', iostat=ios) i, mesh%connectivity(:, i)
        end do
        if (allocated(mesh%node_sets)) then
            do i = 1, size(mesh%node_sets)
                if (ios == 0) write (unit, '(a,1x,a,1x,i0)', iostat=ios) 'node_set', &
                    mesh%node_sets(i)%name, size(mesh%node_sets(i)%nodes)
                if (ios == 0) call write_ids(mesh%node_sets(i)%nodes)
            end do
        end if
        if (allocated(mesh%element_sets)) then
            do i = 1, size(mesh%element_sets)
                if (ios == 0) write (unit, '(a,1x,a,1x,i0)', iostat=ios) 'element_set', &
                    mesh%element_sets(i)%name, size(mesh%element_sets(i)%elements)
                if (ios == 0) call write_ids(mesh%element_sets(i)%elements)
            end do
        end if
        close (unit)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot write')

    contains

        !> Ids, ten per line.
        subroutine write_ids(ids)
            integer, intent(in) :: ids(:)
            integer :: j
            do j = 1, size(ids), 10
                write (unit, '(*(i0,:,1x))', iostat=ios) ids(j:min(j + 9, size(ids)))
                if (ios /= 0) return
            end do
        end subroutine write_ids
    end subroutine write_mesh


    !> det J at the natural centre of element e is positive.
    logical function positive_centre_jacobian(mesh, e) result(ok)
        type(mesh_t), intent(in) :: mesh
        integer, intent(in) :: e
        real(wp) :: n(27), dn(3, 27)
        integer :: nn
        nn = mesh%nnode_element
        call shape_functions(nn, [0.0_wp, 0.0_wp, 0.0_wp], n(1:nn), dn(:, 1:nn))
        ok = det3(matmul(mesh%x(:, mesh%connectivity(:, e)), transpose(dn(:, 1:nn)))) > 0.0_wp
    end function positive_centre_jacobian
end module flexmbs_fe_mesh_file
