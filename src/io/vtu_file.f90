!> One XML unstructured-grid file of VTK (.vtu), written as text or with
!> its arrays in binary: the XML part names every array with
!> format="appended" and its offset, the values follow in one
!> `<AppendedData encoding="base64">` section, each array as its byte
!> count (UInt64, header_type) and its bytes, each of the two base64-encoded
!> on its own as VTK writes them, in the machine's byte order (declared by
!> byte_order); no compression.
!>
!> Base64 rather than raw bytes: the file stays well-formed XML, and
!> meshio 5.3.5 reads raw appended data through a shortcut that takes one
!> array for another when an array's raw offset equals an earlier one's
!> base64 offset (it failed on the joints' files). The file is written
!> with stream access: the appended section is one line of any length.
!>
!> VTK, ParaView and meshio 5 read both forms. meshio reads no String
!> arrays, so names are UInt8 arrays of their bytes, each name followed by
!> a 0 (`names`). Every file's second line is the comment
!> '<!-- written by flexmbs 0.1.0 -->', whatever the form.
module flexmbs_io_vtu_file
    use, intrinsic :: iso_fortran_env, only: int8, int32, int64
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_version, only: written_by, is_written_by
    use flexmbs_core_files, only: read_first_lines
    implicit none
    private

    !> A .vtu file being written: open_vtu, its XML (pieces, arrays), close.
    type, public :: vtu_file_t
        private
        character(len=:), allocatable :: path
        integer :: unit = 0
        logical :: opened = .false.  !! (newunit's numbers are negative)
        logical :: binary = .true.
        !> the first failed write or allocation ('' while none failed)
        character(len=:), allocatable :: failure
        !> the appended section so far (binary), encoded(1:used)
        character(len=:), allocatable :: encoded
        integer(i8) :: used = 0
    contains
        procedure :: line => vtu_line
        procedure :: begin_piece => vtu_begin_piece
        procedure :: cells => vtu_cells
        procedure :: reals => vtu_reals
        procedure :: integers => vtu_integers
        procedure :: names => vtu_names
        procedure :: close => vtu_close
    end type vtu_file_t

    !> The XML comment that marks flexmbs's files (.vtu, .pvd, .xdmf) on
    !> their second line, after the XML declaration.
    character(len=*), parameter, public :: comment_opening = '<!-- ', comment_closing = ' -->'

    character(len=*), parameter :: real_format = 'es24.15e3'
    character(len=*), parameter :: alphabet = &
        'ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/'

    public :: open_vtu, xml_file_ours

contains

    !> Create (or replace) the file at `path` and write up to the opening of
    !> its UnstructuredGrid; field data or a piece follows.
    subroutine open_vtu(file, path, binary, status)
        type(vtu_file_t), intent(out) :: file
        character(len=*), intent(in) :: path
        logical, intent(in) :: binary  !! appended data, else text
        type(status_t), intent(inout) :: status
        integer :: ios
        file%path = path
        file%binary = binary
        file%failure = ''
        if (binary) then
            open (newunit=file%unit, file=path, access='stream', form='unformatted', &
                  action='write', status='replace', iostat=ios)
        else
            open (newunit=file%unit, file=path, action='write', status='replace', iostat=ios)
        end if
        file%opened = ios == 0
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot write the ParaView file')
            return
        end if
        call file%line('<?xml version="1.0"?>')
        call file%line(comment_opening // written_by // comment_closing)
        if (binary) then
            allocate (character(len=4096) :: file%encoded)
            call file%line('<VTKFile type="UnstructuredGrid" version="1.0" byte_order="' // &
                byte_order() // '" header_type="UInt64">')
        else
            call file%line('<VTKFile type="UnstructuredGrid" version="0.1" ' // &
                'byte_order="LittleEndian">')
        end if
        call file%line('<UnstructuredGrid>')
    end subroutine open_vtu

    !> Whether `path` is an XML file of flexmbs — a ParaView or XDMF file:
    !> its marking comment on the second line, after the XML declaration.
    logical function xml_file_ours(path)
        character(len=*), intent(in) :: path
        character(len=256) :: lines(2)
        integer :: count
        call read_first_lines(path, lines, count)
        xml_file_ours = .false.
        if (count == 2) xml_file_ours = is_written_by(lines(2), comment_opening)
    end function xml_file_ours

    !> 'LittleEndian' or 'BigEndian': how this machine stores numbers, so
    !> the bytes written as they are in memory.
    pure function byte_order() result(order)
        character(len=:), allocatable :: order
        order = 'BigEndian'
        if (transfer(1_int32, 0_int8) == 1_int8) order = 'LittleEndian'
    end function byte_order

    !> A line of XML.
    subroutine vtu_line(self, text)
        class(vtu_file_t), intent(inout) :: self
        character(len=*), intent(in) :: text
        integer :: ios
        if (.not. self%opened .or. len(self%failure) > 0) return
        if (self%binary) then
            write (self%unit, iostat=ios) text // new_line('a')
        else
            write (self%unit, '(a)', iostat=ios) text
        end if
        call check(self, ios)
    end subroutine vtu_line

    !> A piece's opening and its points (the columns of `x`).
    subroutine vtu_begin_piece(self, x, ncells)
        class(vtu_file_t), intent(inout) :: self
        real(wp), intent(in) :: x(:, :)
        integer, intent(in) :: ncells
        call self%line('<Piece NumberOfPoints="' // int_text(size(x, 2)) // &
            '" NumberOfCells="' // int_text(ncells) // '">')
        call self%line('<Points>')
        call self%reals('', x)
        call self%line('</Points>')
    end subroutine vtu_begin_piece

    !> The cells of a piece: cell k of VTK type types(k) has the points
    !> points(ends(k - 1) + 1:ends(k)) (ends(0) = 0), numbered from 1 as
    !> flexmbs numbers them (VTK from 0). Int32 (VTK converts to its ids):
    !> half the bytes of Int64.
    subroutine vtu_cells(self, points, ends, types)
        class(vtu_file_t), intent(inout) :: self
        integer, intent(in) :: points(:), ends(:), types(:)
        integer :: k, first
        call self%line('<Cells>')
        if (self%binary) then
            call self%line(array_tag('Int32', 'connectivity', 1, self%used))
            call append(self, transfer(int(points - 1, int32), 0_int8, 4 * size(points)))
            call self%line(array_tag('Int32', 'offsets', 1, self%used))
            call append(self, transfer(int(ends, int32), 0_int8, 4 * size(ends)))
            call self%line(array_tag('UInt8', 'types', 1, self%used))
            call append(self, int(types, int8))
        else
            call self%line(array_tag('Int32', 'connectivity', 1))
            first = 1
            do k = 1, size(ends)
                call text_integers(self, points(first:ends(k)) - 1)
                first = ends(k) + 1
            end do
            call self%line('</DataArray>')
            call self%line(array_tag('Int32', 'offsets', 1))
            call text_integers(self, ends)
            call self%line('</DataArray>')
            call self%line(array_tag('UInt8', 'types', 1))
            call text_integers(self, types)
            call self%line('</DataArray>')
        end if
        call self%line('</Cells>')
    end subroutine vtu_cells

    !> A Float64 array, a tuple per column of `values` (its rows the
    !> components); `name` '' for the points.
    subroutine vtu_reals(self, name, values)
        class(vtu_file_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: values(:, :)
        integer :: ios
        if (self%binary) then
            call self%line(array_tag('Float64', name, size(values, 1), self%used))
            call append(self, transfer(values, 0_int8, 8 * size(values)))
            return
        end if
        call self%line(array_tag('Float64', name, size(values, 1)))
        if (self%opened .and. len(self%failure) == 0 .and. size(values) > 0) then
            write (self%unit, '(' // int_text(size(values, 1)) // real_format // ')', &
                   iostat=ios) values
            call check(self, ios)
        end if
        call self%line('</DataArray>')
    end subroutine vtu_reals

    !> An Int32 array, a value per point or cell.
    subroutine vtu_integers(self, name, values)
        class(vtu_file_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        integer, intent(in) :: values(:)
        if (self%binary) then
            call self%line(array_tag('Int32', name, 1, self%used))
            call append(self, transfer(int(values, int32), 0_int8, 4 * size(values)))
            return
        end if
        call self%line(array_tag('Int32', name, 1))
        call text_integers(self, values)
        call self%line('</DataArray>')
    end subroutine vtu_integers

    !> Names as a UInt8 array (field data): each name's bytes (trailing
    !> blanks dropped), then a 0; in text a line per name. meshio reads no
    !> String arrays; in Python `bytes(a).decode().split('\0')[:-1]` gives
    !> the names back.
    subroutine vtu_names(self, name, names)
        class(vtu_file_t), intent(inout) :: self
        character(len=*), intent(in) :: name, names(:)
        integer(int8), allocatable :: codes(:)
        integer :: b, k, n
        allocate (codes(sum(len_trim(names)) + size(names)))
        k = 0
        do b = 1, size(names)
            n = len_trim(names(b))
            if (n > 0) codes(k + 1:k + n) = transfer(names(b)(1:n), 0_int8, n)
            codes(k + n + 1) = 0_int8
            k = k + n + 1
        end do
        if (self%binary) then
            call self%line(array_tag('UInt8', name, 1, self%used, size(codes)))
            call append(self, codes)
            return
        end if
        call self%line(array_tag('UInt8', name, 1, tuples=size(codes)))
        k = 0
        do b = 1, size(names)
            n = len_trim(names(b))
            ! bytes from 0 to 255 (int8 holds those above 127 as negative)
            call text_integers(self, modulo(int(codes(k + 1:k + n + 1)), 256))
            k = k + n + 1
        end do
        call self%line('</DataArray>')
    end subroutine vtu_names

    !> The end of the grid and of the file (the appended data in binary).
    subroutine vtu_close(self, status)
        class(vtu_file_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer :: ios
        if (.not. self%opened) return
        call self%line('</UnstructuredGrid>')
        if (self%binary) then
            call self%line('<AppendedData encoding="base64">')
            ! '_' opens the data, the offsets count from after it
            if (len(self%failure) == 0) then
                write (self%unit, iostat=ios) '_', self%encoded(1:self%used), new_line('a')
                call check(self, ios)
            end if
            call self%line('</AppendedData>')
            deallocate (self%encoded)
        end if
        call self%line('</VTKFile>')
        close (self%unit, iostat=ios)
        self%opened = .false.
        if (ios /= 0 .and. len(self%failure) == 0) self%failure = 'cannot close'
        if (len(self%failure) > 0 .and. status%ok()) &
            call status%set(status_io_error, self%path // ': ' // self%failure)
    end subroutine vtu_close

    !> A DataArray's opening tag: in text open (the values follow), in
    !> binary closed, its values at `offset` in the appended data.
    pure function array_tag(type, name, components, offset, tuples) result(tag)
        character(len=*), intent(in) :: type, name
        integer, intent(in) :: components
        integer(i8), intent(in), optional :: offset
        integer, intent(in), optional :: tuples
        character(len=:), allocatable :: tag
        tag = '<DataArray type="' // type // '"'
        if (len(name) > 0) tag = tag // ' Name="' // name // '"'
        if (components > 1) tag = tag // ' NumberOfComponents="' // int_text(components) // '"'
        if (present(tuples)) tag = tag // ' NumberOfTuples="' // int_text(tuples) // '"'
        if (present(offset)) then
            tag = tag // ' format="appended" offset="' // int_text(offset) // '"/>'
        else
            tag = tag // ' format="ascii">'
        end if
    end function array_tag

    !> Integers on one line of text.
    subroutine text_integers(self, values)
        type(vtu_file_t), intent(inout) :: self
        integer, intent(in) :: values(:)
        integer :: ios
        if (.not. self%opened .or. len(self%failure) > 0) return
        write (self%unit, '(*(1x,i0))', iostat=ios) values
        call check(self, ios)
    end subroutine text_integers

    !> Add an array to the appended data: its byte count (UInt64), then its
    !> bytes, each base64-encoded.
    subroutine append(self, data)
        type(vtu_file_t), intent(inout) :: self
        integer(int8), intent(in) :: data(:)
        character(len=:), allocatable :: grown
        integer(i8) :: need
        integer :: stat, n
        if (len(self%failure) > 0) return
        n = 4 * ((size(data) + 2) / 3)
        need = self%used + 12 + n
        if (need > len(self%encoded, kind=i8)) then
            allocate (character(len=max(need, 2 * len(self%encoded, kind=i8))) :: grown, &
                      stat=stat)
            if (stat /= 0) then
                self%failure = 'out of memory for ' // int_text(need) // ' characters of arrays'
                return
            end if
            grown(1:self%used) = self%encoded(1:self%used)
            call move_alloc(grown, self%encoded)
        end if
        self%encoded(self%used + 1:self%used + 12) = &
            base64(transfer(size(data, kind=int64), 0_int8, 8))
        self%encoded(self%used + 13:self%used + 12 + n) = base64(data)
        self%used = need
    end subroutine append

    !> The base64 encoding of `bytes` (RFC 4648, '=' padded).
    pure function base64(bytes) result(text)
        integer(int8), intent(in) :: bytes(:)
        character(len=4 * ((size(bytes) + 2) / 3)) :: text
        integer :: i, k, n, word, b(3)
        k = 0
        do i = 1, size(bytes), 3
            n = min(3, size(bytes) - i + 1)
            b = 0
            b(1:n) = modulo(int(bytes(i:i + n - 1)), 256)
            word = ior(ior(ishft(b(1), 16), ishft(b(2), 8)), b(3))
            text(k + 1:k + 1) = char64(ishft(word, -18))
            text(k + 2:k + 2) = char64(iand(ishft(word, -12), 63))
            text(k + 3:k + 3) = char64(iand(ishft(word, -6), 63))
            text(k + 4:k + 4) = char64(iand(word, 63))
            if (n < 3) text(k + 4:k + 4) = '='
            if (n < 2) text(k + 3:k + 3) = '='
            k = k + 4
        end do

    contains

        pure character function char64(six)
            integer, intent(in) :: six
            char64 = alphabet(six + 1:six + 1)
        end function char64
    end function base64

    !> Keep the first failed write.
    subroutine check(self, ios)
        type(vtu_file_t), intent(inout) :: self
        integer, intent(in) :: ios
        if (ios /= 0 .and. len(self%failure) == 0) self%failure = 'cannot write'
    end subroutine check
end module flexmbs_io_vtu_file
