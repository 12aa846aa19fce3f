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
    use flexmbs_core_files, only: read_text_file
    use flexmbs_fe_hexahedron, only: shape_functions
    use flexmbs_fe_tensor, only: det3
    use flexmbs_fe_mesh, only: mesh_t, node_set_t, element_set_t
    implicit none
    private

    public :: read_mesh, write_mesh

    character(len=*), parameter :: magic = 'flexmbs-mesh'

    !> The file as tokens: start and end offsets and the line of each.
    type :: tokens_t
        integer, allocatable :: first(:), last(:), line(:)
        integer :: n = 0
    end type tokens_t

contains

    !> Read a mesh in the flexmbs text format (the module's grammar) from `path`;
    !> an error names the file, the line and the reason and leaves `mesh` empty.
    subroutine read_mesh(path, mesh, status)
        character(len=*), intent(in) :: path
        type(mesh_t), intent(out) :: mesh
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        type(tokens_t) :: tok
        type(mesh_t) :: work
        integer :: pos, nnode, nelem, i, a, k, id, nset, stat
        character(len=:), allocatable :: word, name
        real(wp) :: x(3)
        call read_text_file(path, text, status)
        if (.not. status%ok()) return
        call tokenise(text, tok, status)
        if (.not. status%ok()) return
        pos = 0
        call expect_word(magic)
        if (.not. status%ok()) return
        call next_int(k, 'format version')
        if (.not. status%ok()) return
        if (k /= 1) then
            call fail('format version ' // int_text(k) // ' is not supported (1 is)')
            return
        end if
        call expect_word('nodes')
        if (.not. status%ok()) return
        call next_int(nnode, 'node count')
        if (.not. status%ok()) return
        if (nnode < 1) then
            call fail('node count must be positive')
            return
        end if
        ! counts beyond what the text can hold are refused before allocating
        if (.not. fits(nnode, 4, 'nodes')) return
        allocate (work%x(3, nnode), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': node coordinates', 3_i8 * nnode, 8)
            return
        end if
        do i = 1, nnode
            call next_int(id, 'node id')
            if (.not. status%ok()) return
            if (id /= i) then
                call fail('node id ' // int_text(id) // ' where ' // int_text(i) // &
                          ' is expected (ids run 1..N in order)')
                return
            end if
            do k = 1, 3
                call next_real(x(k), 'node coordinate')
                if (.not. status%ok()) return
            end do
            work%x(:, i) = x
        end do
        call expect_word('elements')
        if (.not. status%ok()) return
        call next_word(word, 'element type')
        if (.not. status%ok()) return
        select case (lower(word))
        case ('hex8')
            work%nnode_element = 8
        case ('hex27')
            work%nnode_element = 27
        case default
            call fail('element type ''' // excerpt(word) // ''': hex8 or hex27 expected')
            return
        end select
        call next_int(nelem, 'element count')
        if (.not. status%ok()) return
        if (nelem < 1) then
            call fail('element count must be positive')
            return
        end if
        if (.not. fits(nelem, work%nnode_element + 1, 'elements')) return
        allocate (work%connectivity(work%nnode_element, nelem), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': connectivity', &
                int(work%nnode_element, i8) * nelem, 4)
            return
        end if
        allocate (work%node_sets(0), work%element_sets(0))
        do i = 1, nelem
            call next_int(id, 'element id')
            if (.not. status%ok()) return
            if (id /= i) then
                call fail('element id ' // int_text(id) // ' where ' // int_text(i) // &
                          ' is expected (ids run 1..E in order)')
                return
            end if
            do a = 1, work%nnode_element
                call next_int(k, 'element node')
                if (.not. status%ok()) return
                if (k < 1 .or. k > nnode) then
                    call fail('element ' // int_text(i) // ' names node ' // int_text(k) // &
                              ', outside 1..' // int_text(nnode))
                    return
                end if
                work%connectivity(a, i) = k
            end do
            if (.not. positive_centre_jacobian(work, i)) then
                call fail('element ' // int_text(i) // ' is inverted or degenerate ' // &
                          '(det J <= 0 at its centre; check the VTK node order)')
                return
            end if
        end do
        do while (pos < tok%n)
            call next_word(word, 'set keyword')
            if (.not. status%ok()) return
            select case (lower(word))
            case ('node_set', 'element_set')
                call next_word(name, 'set name')
                if (.not. status%ok()) return
                call next_int(nset, 'set size')
                if (.not. status%ok()) return
                if (nset < 0) then
                    call fail('set ''' // excerpt(name) // ''': negative size')
                    return
                end if
                if (lower(word) == 'node_set') then
                    call read_node_set(name, nset)
                else
                    call read_element_set(name, nset)
                end if
                if (.not. status%ok()) return
            case default
                call fail('''' // excerpt(word) // ''': node_set or element_set expected')
                return
            end select
        end do
        call work%check(status)
        if (.not. status%ok()) then
            call status%set(status_bad_input, path // ': ' // status%text())
            return
        end if
        mesh = work

    contains

        subroutine read_node_set(name, nset)
            character(len=*), intent(in) :: name
            integer, intent(in) :: nset
            type(node_set_t) :: set
            integer :: j
            if (any([(work%node_sets(j)%name == name, j = 1, size(work%node_sets))])) then
                call fail('a second node set named ''' // excerpt(name) // '''')
                return
            end if
            set%name = name
            if (.not. fits(nset, 1, 'set members')) return
            allocate (set%nodes(nset), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, path // ': node set', int(nset, i8), 4)
                return
            end if
            do j = 1, nset
                call next_int(set%nodes(j), 'node id of set ''' // excerpt(name) // '''')
                if (.not. status%ok()) return
                if (set%nodes(j) < 1 .or. set%nodes(j) > nnode) then
                    call fail('node set ''' // excerpt(name) // ''' names node ' // &
                              int_text(set%nodes(j)) // ', outside 1..' // int_text(nnode))
                    return
                end if
            end do
            work%node_sets = [work%node_sets, set]
        end subroutine read_node_set

        subroutine read_element_set(name, nset)
            character(len=*), intent(in) :: name
            integer, intent(in) :: nset
            type(element_set_t) :: set
            integer :: j
            if (any([(work%element_sets(j)%name == name, j = 1, size(work%element_sets))])) then
                call fail('a second element set named ''' // excerpt(name) // '''')
                return
            end if
            set%name = name
            if (.not. fits(nset, 1, 'set members')) return
            allocate (set%elements(nset), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, path // ': element set', int(nset, i8), 4)
                return
            end if
            do j = 1, nset
                call next_int(set%elements(j), 'element id of set ''' // excerpt(name) // '''')
                if (.not. status%ok()) return
                if (set%elements(j) < 1 .or. set%elements(j) > nelem) then
                    call fail('element set ''' // excerpt(name) // ''' names element ' // &
                              int_text(set%elements(j)) // ', outside 1..' // int_text(nelem))
                    return
                end if
            end do
            work%element_sets = [work%element_sets, set]
        end subroutine read_element_set

        !> Whether `count` items of `per_item` values each fit in the values
        !> the file has left; bad input (before any allocation) if not, so
        !> that a declared count of 2e9 cannot exhaust the memory.
        logical function fits(count, per_item, what)
            integer, intent(in) :: count, per_item
            character(len=*), intent(in) :: what
            fits = count <= (tok%n - pos) / per_item
            if (.not. fits) call fail(int_text(count) // ' ' // what // ' declared, but the &
                &file holds only ' // int_text(tok%n - pos) // ' more values (' // &
                int_text(per_item) // ' per item)')
        end function fits

        !> Bad input at the current token's line (the last line at the end).
        subroutine fail(reason)
            character(len=*), intent(in) :: reason
            integer :: line
            line = 1
            if (tok%n > 0) line = tok%line(max(1, min(pos, tok%n)))
            call status%set(status_bad_input, path // ':' // int_text(line) // ': ' // reason)
        end subroutine fail

        subroutine next_word(word, what)
            character(len=:), allocatable, intent(out) :: word
            character(len=*), intent(in) :: what
            if (pos >= tok%n) then
                pos = tok%n
                word = ''
                call fail('file ends where a ' // what // ' is expected')
                return
            end if
            pos = pos + 1
            word = text(tok%first(pos):tok%last(pos))
        end subroutine next_word

        subroutine expect_word(keyword)
            character(len=*), intent(in) :: keyword
            character(len=:), allocatable :: word
            call next_word(word, '''' // keyword // '''')
            if (.not. status%ok()) return
            if (lower(word) /= keyword) call fail('''' // excerpt(word) // ''' where ''' // keyword // &
                                                  ''' is expected')
        end subroutine expect_word

        subroutine next_int(value, what)
            integer, intent(out) :: value
            character(len=*), intent(in) :: what
            character(len=:), allocatable :: word
            integer :: ios
            value = 0
            call next_word(word, what)
            if (.not. status%ok()) return
            if (verify(word, '+-0123456789') /= 0) then
                ios = 1
            else
                read (word, *, iostat=ios) value
            end if
            if (ios /= 0) call fail('''' // excerpt(word) // ''' is not an integer (' // what // ')')
        end subroutine next_int

        subroutine next_real(value, what)
            real(wp), intent(out) :: value
            character(len=*), intent(in) :: what
            character(len=:), allocatable :: word
            integer :: ios
            value = 0.0_wp
            call next_word(word, what)
            if (.not. status%ok()) return
            if (verify(word, '+-.0123456789eEdD') /= 0) then
                ios = 1
            else
                read (word, *, iostat=ios) value
            end if
            if (ios /= 0) call fail('''' // excerpt(word) // ''' is not a number (' // what // ')')
        end subroutine next_real
    end subroutine read_mesh

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

    !> Split text into whitespace-separated tokens, dropping # comments.
    subroutine tokenise(text, tok, status)
        character(len=*), intent(in) :: text
        type(tokens_t), intent(out) :: tok
        type(status_t), intent(inout) :: status
        integer :: i, line, start, capacity
        logical :: comment
        character :: c
        capacity = 1024
        allocate (tok%first(capacity), tok%last(capacity), tok%line(capacity))
        line = 1
        start = 0
        comment = .false.
        do i = 1, len(text) + 1
            if (i <= len(text)) then
                c = text(i:i)
            else
                c = new_line('a')
            end if
            if (c == new_line('a') .or. c == char(13) .or. c == ' ' .or. c == char(9) &
                .or. (c == '#' .and. .not. comment)) then
                if (start > 0) call push(start, i - 1)
                if (.not. status%ok()) return
                start = 0
                if (c == '#') comment = .true.
                if (c == new_line('a')) then
                    line = line + 1
                    comment = .false.
                end if
            else if (.not. comment .and. start == 0) then
                start = i
            end if
        end do

    contains

        subroutine push(first, last)
            integer, intent(in) :: first, last
            integer, allocatable :: tmp_first(:), tmp_last(:), tmp_line(:)
            integer :: stat
            if (tok%n == capacity) then
                ! a token takes at least 2 characters: len(text) bounds the count
                capacity = int(min(2_i8 * capacity, len(text, i8) / 2 + 1, int(huge(1), i8)))
                allocate (tmp_first(capacity), tmp_last(capacity), tmp_line(capacity), &
                    stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'mesh file tokens', 3_i8 * capacity, 4)
                    return
                end if
                tmp_first(1:tok%n) = tok%first(1:tok%n)
                call move_alloc(tmp_first, tok%first)
                tmp_last(1:tok%n) = tok%last(1:tok%n)
                call move_alloc(tmp_last, tok%last)
                tmp_line(1:tok%n) = tok%line(1:tok%n)
                call move_alloc(tmp_line, tok%line)
            end if
            tok%n = tok%n + 1
            tok%first(tok%n) = first
            tok%last(tok%n) = last
            tok%line(tok%n) = line
        end subroutine push
    end subroutine tokenise

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
