!> The XDMF file (XDMF 2, XML) beside an HDF5 result with flexible bodies,
!> so that ParaView and VisIt open the result itself: a temporal
!> collection with a grid per record, each a spatial collection of the
!> flexible bodies — the mesh (the HDF5 file's reference_nodes and
!> connectivity, numbered from 1: the function $0 - 1), the displacement and
!> velocity of every node, the stress (a symmetric tensor) and von Mises
!> stress of every element, each a hyperslab of the record's row in the
!> time series /flexible/<name>/... (docs/output.md). hex8 is Hexahedron,
!> hex27 Hexahedron_27 in flexmbs's node order, which is VTK's
!> (VTK_TRIQUADRATIC_HEXAHEDRON; ParaView's XDMF reader takes it as it is).
!> The stress series holds xx, yy, zz, xy, yz, xz; XDMF's Tensor6 is xx,
!> xy, xz, yy, yz, zz, so the components are joined in that order
!> (a JOIN function of six one-component hyperslabs).
!> The second line is the comment '<!-- written by flexmbs 0.1.0 -->'
!> (flexmbs_io_vtu_file's xml_file_ours).
module flexmbs_io_xdmf_file
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_version, only: written_by
    use flexmbs_io_vtu_file, only: comment_opening, comment_closing
    implicit none
    private

    !> A flexible body of the HDF5 result: its name, its HDF5 group
    !> ('flexible/NAME') and the size of its mesh.
    type, public :: xdmf_body_t
        character(len=:), allocatable :: name, group
        integer :: nodes = 0, elements = 0
        integer :: element_nodes = 8  !! 8 (hex8) or 27 (hex27)
    end type xdmf_body_t

    public :: xdmf_beside, write_xdmf

    !> The most records an XDMF file lists (about 3.4 kB of XML each per
    !> body): a longer run lists every k-th and the last, and says so in a
    !> comment; the HDF5 file keeps them all.
    integer, parameter, public :: xdmf_most_records = 10000

contains

    !> The XDMF file beside the HDF5 file `h5_path`: its name with .xdmf in
    !> place of .h5 or .hdf5 (after it for any other name).
    pure function xdmf_beside(h5_path) result(path)
        character(len=*), intent(in) :: h5_path
        character(len=:), allocatable :: path
        integer :: dot
        dot = index(h5_path, '.', back=.true.)
        path = h5_path // '.xdmf'
        if (dot <= index(h5_path, '/', back=.true.) + 1) return
        select case (h5_path(dot:))
        case ('.h5', '.H5', '.hdf5', '.HDF5')
            path = h5_path(1:dot - 1) // '.xdmf'
        end select
    end function xdmf_beside

    !> Write the XDMF file at `path` for the HDF5 file `h5_path` (in the same
    !> folder) holding `bodies` and `records` records, of which it lists
    !> `rows` at `times`. Without a record the meshes alone, at no time.
    subroutine write_xdmf(path, h5_path, bodies, rows, times, records, status)
        character(len=*), intent(in) :: path, h5_path
        type(xdmf_body_t), intent(in) :: bodies(:)
        integer, intent(in) :: rows(:)      !! the records listed (from 0)
        real(wp), intent(in) :: times(:)    !! their times
        integer, intent(in) :: records      !! the records in the HDF5 file
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: h5
        character(len=32) :: tbuf
        integer :: unit, ios, k, b
        h5 = xml_text(h5_path(index(h5_path, '/', back=.true.) + 1:))
        open (newunit=unit, file=path, action='write', status='replace', iostat=ios)
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot write the XDMF file')
            return
        end if
        write (unit, '(a)', iostat=ios) '<?xml version="1.0"?>'
        call put(comment_opening // written_by // comment_closing)
        call put('<Xdmf Version="2.0">')
        if (size(rows) < records) call put(comment_opening // int_text(size(rows)) // &
            ' of the ' // int_text(records) // ' records listed: one in ' // &
            int_text(rows(min(2, size(rows))) - rows(1)) // ' and the last' // comment_closing)
        call put('<Domain>')
        if (size(times) == 0) then
            call put('<Grid Name="flexible bodies" GridType="Collection" ' // &
                'CollectionType="Spatial">')
            do b = 1, size(bodies)
                call write_body(unit, h5, bodies(b), -1, 0, ios)
            end do
            call put('</Grid>')
        else
            call put('<Grid Name="flexible bodies" GridType="Collection" ' // &
                'CollectionType="Temporal">')
            do k = 1, size(times)
                ! 17 significant digits: the times of /time exactly
                write (tbuf, '(es25.16e3)') times(k)
                call put('<Grid Name="record ' // int_text(rows(k)) // '" GridType="Collection" ' &
                    // 'CollectionType="Spatial">')
                call put('<Time Value="' // trim(adjustl(tbuf)) // '"/>')
                do b = 1, size(bodies)
                    call write_body(unit, h5, bodies(b), rows(k), records, ios)
                end do
                call put('</Grid>')
            end do
            call put('</Grid>')
        end if
        call put('</Domain>')
        call put('</Xdmf>')
        if (ios == 0) then
            close (unit, iostat=ios)
        else
            close (unit)
        end if
        if (ios /= 0) call status%set(status_io_error, path // ': cannot write the XDMF file')

    contains

        subroutine put(line)
            character(len=*), intent(in) :: line
            if (ios == 0) write (unit, '(a)', iostat=ios) line
        end subroutine put
    end subroutine write_xdmf

    !> A body's grid at record `k` (from 0) of `records` (k < 0: the mesh
    !> alone).
    subroutine write_body(unit, h5, body, k, records, ios)
        integer, intent(in) :: unit, k, records
        character(len=*), intent(in) :: h5  !! the HDF5 file's name, XML-escaped
        type(xdmf_body_t), intent(in) :: body
        integer, intent(inout) :: ios
        character(len=:), allocatable :: group, ne, nn, ints
        character(len=*), parameter :: floats = ' NumberType="Float" Precision="8" Format="HDF">'
        group = h5 // ':/' // xml_text(body%group) // '/'
        ne = int_text(body%elements)
        nn = int_text(body%nodes)
        call put('<Grid Name="' // xml_text(trim(body%name)) // '" GridType="Uniform">')
        ! the nodes numbered from 0: a function rather than BaseOffset="1",
        ! which ParaView's Xdmf3 readers ignore
        ints = '" NumberType="Int" Precision="4"'
        call put('<Topology TopologyType="' // topology(body%element_nodes) // &
            '" NumberOfElements="' // ne // '">')
        call put('<DataItem ItemType="Function" Function="$0 - 1" Dimensions="' // ne // ' ' // &
            int_text(body%element_nodes) // ints // '>')
        call put('<DataItem Dimensions="' // ne // ' ' // int_text(body%element_nodes) // &
            ints // ' Format="HDF">' // group // 'connectivity' // '</DataItem>')
        call put('</DataItem>')
        call put('</Topology>')
        call put('<Geometry GeometryType="XYZ">')
        call put('<DataItem Dimensions="' // nn // ' 3"' // floats // group // 'reference_nodes' // &
            '</DataItem>')
        call put('</Geometry>')
        if (k >= 0) then
            call vector('displacement')
            call vector('velocity')
            call stress()
            call put('<Attribute Name="von_mises" AttributeType="Scalar" Center="Cell">')
            call slab(ne, int_text(k) // ' 0 1 1 1 ' // ne, '3 2', ne, 'von_mises')
            call put('</Attribute>')
        end if
        call put('</Grid>')

    contains

        subroutine put(line)
            character(len=*), intent(in) :: line
            if (ios == 0) write (unit, '(a)', iostat=ios) line
        end subroutine put

        !> A node vector: row k of the (records, nodes, 3) series.
        subroutine vector(name)
            character(len=*), intent(in) :: name
            call put('<Attribute Name="' // name // '" AttributeType="Vector" Center="Node">')
            call slab(nn // ' 3', int_text(k) // ' 0 0 1 1 1 1 ' // nn // ' 3', '3 3', &
                      nn // ' 3', name)
            call put('</Attribute>')
        end subroutine vector

        !> The stress tensor of every element: its six components of the
        !> (records, elements, 6) series in Tensor6's order (module header).
        subroutine stress()
            integer, parameter :: tensor6(6) = [0, 3, 5, 1, 4, 2]
            integer :: c
            call put('<Attribute Name="stress" AttributeType="Tensor6" Center="Cell">')
            call put('<DataItem ItemType="Function" Function="JOIN($0, $1, $2, $3, $4, $5)" ' &
                // 'Dimensions="' // ne // ' 6">')
            do c = 1, 6
                call slab(ne, int_text(k) // ' 0 ' // int_text(tensor6(c)) // ' 1 1 1 1 ' // &
                          ne // ' 1', '3 3', ne // ' 6', 'stress')
            end do
            call put('</DataItem>')
            call put('</Attribute>')
        end subroutine stress

        !> A hyperslab of `dimensions` from series `name` (records, `shape`):
        !> start, stride and count in `selection` (a `rows` matrix).
        subroutine slab(dimensions, selection, rows, shape, name)
            character(len=*), intent(in) :: dimensions, selection, rows, shape, name
            call put('<DataItem ItemType="HyperSlab" Dimensions="' // dimensions // &
                '" Type="HyperSlab">')
            call put('<DataItem Dimensions="' // rows // '" Format="XML">' // selection // &
                '</DataItem>')
            call put('<DataItem Dimensions="' // int_text(records) // ' ' // shape // '"' // &
                floats // group // name // '</DataItem>')
            call put('</DataItem>')
        end subroutine slab
    end subroutine write_body

    !> XDMF's name of the element: Hexahedron (hex8) or Hexahedron_27.
    pure function topology(nodes) result(name)
        integer, intent(in) :: nodes
        character(len=:), allocatable :: name
        name = 'Hexahedron_27'
        if (nodes == 8) name = 'Hexahedron'
    end function topology

    !> `text` with XML's special characters as entities.
    pure function xml_text(text) result(escaped)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: escaped
        integer :: i
        escaped = ''
        do i = 1, len(text)
            select case (text(i:i))
            case ('&'); escaped = escaped // '&amp;'
            case ('<'); escaped = escaped // '&lt;'
            case ('>'); escaped = escaped // '&gt;'
            case ('"'); escaped = escaped // '&quot;'
            case default; escaped = escaped // text(i:i)
            end select
        end do
    end function xml_text
end module flexmbs_io_xdmf_file
