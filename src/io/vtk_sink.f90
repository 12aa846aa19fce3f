!> ParaView output: at every output time, the flexible body's mesh as an
!> XML unstructured grid (`PREFIX_NNNN.vtu`: current node positions, the
!> hexahedra in VTK order — hex8 cell type 12, hex27 type 29 —, point data
!> displacement and velocity, cell data Cauchy stress (xx, yy, zz, xy, yz,
!> xz) and its von Mises value) and the rigid bodies (`PREFIX_bodies_NNNN.vtu`:
!> one vertex per body at its centre of mass, the bodies in absolute
!> coordinates first, then a chain's links; point data the body's three
!> axes), listed with their times in `PREFIX.pvd` (part 0 the mesh, part 1
!> the bodies). The .pvd is rewritten after every record, so a run that
!> stops keeps a collection ParaView opens. Every file's second line is the
!> comment '<!-- written by flexmbs 0.1.0 -->' (vtk_file_ours).
module flexmbs_io_vtk_sink
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_version, only: written_by, is_written_by
    use flexmbs_core_files, only: read_first_lines
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_rotation, only: rotation_matrix
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    implicit none
    private

    type, extends(sink_t), public :: vtk_sink_t
        character(len=:), allocatable :: prefix
        type(flexible_body_t), pointer :: body => null() !! none: rigid bodies only
        integer :: oq = 0, ov = 0     !! the body's q and v in y
        integer :: bodies = 0         !! rigid bodies: (r, p) at y(7 b − 6 : 7 b)
        type(rigid_chain_t), pointer :: chain => null() !! its links after them
        integer :: chain_q = 0        !! the chain's coordinates in y
        !> the names of the rigid bodies, then of the chain's links (a point
        !> each in the bodies' files: field data body_names, point data body_id)
        character(len=32), allocatable :: names(:)
        integer :: records = 0
        real(wp), allocatable :: times(:)
    contains
        procedure :: output => vtk_output
        procedure :: pieces => vtk_pieces
    end type vtk_sink_t

    !> The XML comment that marks flexmbs's files.
    character(len=*), parameter :: comment_opening = '<!-- ', comment_closing = ' -->'

    public :: vtk_file_ours

contains

    !> The .vtu files of the first `records` records, as vtk_output names them.
    function vtk_pieces(self, records) result(paths)
        class(vtk_sink_t), intent(in) :: self
        integer, intent(in) :: records
        character(len=:), allocatable :: paths(:)
        integer :: k, n, width
        n = 0
        if (associated(self%body)) n = n + records
        if (self%bodies + links(self) > 0) n = n + records
        width = len(self%prefix) + len('_bodies_') + len(digits(records)) + len('.vtu')
        allocate (character(len=width) :: paths(n))
        n = 0
        do k = 1, records
            if (associated(self%body)) then
                n = n + 1
                paths(n) = mesh_piece(self%prefix, k)
            end if
            if (self%bodies + links(self) > 0) then
                n = n + 1
                paths(n) = bodies_piece(self%prefix, k)
            end if
        end do
    end function vtk_pieces

    !> Whether `path` is a ParaView file of flexmbs (its marking comment on
    !> the second line, after the XML declaration).
    logical function vtk_file_ours(path)
        character(len=*), intent(in) :: path
        character(len=256) :: lines(2)
        integer :: count
        call read_first_lines(path, lines, count)
        vtk_file_ours = .false.
        if (count == 2) vtk_file_ours = is_written_by(lines(2), comment_opening)
    end function vtk_file_ours

    !> PREFIX_NNNN.vtu, the mesh at record k
    pure function mesh_piece(prefix, k) result(path)
        character(len=*), intent(in) :: prefix
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = prefix // '_' // digits(k - 1) // '.vtu'
    end function mesh_piece

    !> PREFIX_bodies_NNNN.vtu, the rigid bodies at record k
    pure function bodies_piece(prefix, k) result(path)
        character(len=*), intent(in) :: prefix
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = prefix // '_bodies_' // digits(k - 1) // '.vtu'
    end function bodies_piece

    subroutine vtk_output(self, t, y, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: tt(:)
        if (.not. status%ok()) return
        self%records = self%records + 1
        if (associated(self%body)) call write_mesh(self, y, &
            mesh_piece(self%prefix, self%records), status)
        if (status%ok() .and. self%bodies + links(self) > 0) call write_bodies(self, y, &
            bodies_piece(self%prefix, self%records), status)
        if (.not. status%ok()) return
        if (.not. allocated(self%times)) allocate (self%times(0))
        tt = [self%times, t]
        call move_alloc(tt, self%times)
        call write_collection(self, status)
    end subroutine vtk_output

    !> 0042: four digits at least.
    pure function digits(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        s = int_text(k)
        if (len(s) < 4) s = repeat('0', 4 - len(s)) // s
    end function digits

    subroutine write_mesh(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: x(:, :), v(:, :), sigma(:, :), mises(:)
        type(status_t) :: stress_status
        integer :: unit, ios, n, ne, nn, i, j, celltype, stat
        associate (body => self%body, mesh => self%body%mesh)
            n = mesh%node_count()
            ne = mesh%element_count()
            nn = size(mesh%connectivity, 1)
            allocate (x(3, n), v(3, n), sigma(6, ne), mises(ne), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, path // ': node and element fields', &
                    6_i8 * n + 7_i8 * ne, 8)
                return
            end if
            x = mesh%x
            v = 0.0_wp
            do i = 1, n
                do j = 1, 3
                    if (body%dof(j, i) == 0) cycle
                    x(j, i) = y(self%oq + body%dof(j, i))
                    v(j, i) = y(self%ov + body%dof(j, i))
                end do
            end do
            call body%element_stress(y(self%oq + 1:self%oq + body%nq), &
                                     y(self%ov + 1:self%ov + body%nv), sigma, mises, &
                                     stress_status)
            if (.not. stress_status%ok()) then
                sigma = 0.0_wp
                mises = 0.0_wp
            end if
            celltype = merge(12, 29, nn == 8)
            call open_grid(path, n, ne, unit, status)
            if (.not. status%ok()) return
            write (unit, '(3es24.15e3)') x
            write (unit, '(a)') '</DataArray></Points>'
            write (unit, '(a)') '<Cells><DataArray type="Int64" Name="connectivity" ' // &
                'format="ascii">'
            do i = 1, ne
                write (unit, '(*(1x,i0))') mesh%connectivity(:, i) - 1
            end do
            write (unit, '(a)') '</DataArray><DataArray type="Int64" Name="offsets" ' // &
                'format="ascii">'
            write (unit, '(*(1x,i0))') (nn * i, i=1, ne)
            write (unit, '(a)') '</DataArray><DataArray type="UInt8" Name="types" ' // &
                'format="ascii">'
            write (unit, '(*(1x,i0))') (celltype, i=1, ne)
            write (unit, '(a)') '</DataArray></Cells>'
            write (unit, '(a)') '<PointData Vectors="displacement">'
            write (unit, '(a)') '<DataArray type="Float64" Name="displacement" ' // &
                'NumberOfComponents="3" format="ascii">'
            write (unit, '(3es24.15e3)') x - mesh%x
            write (unit, '(a)') '</DataArray>'
            write (unit, '(a)') '<DataArray type="Float64" Name="velocity" ' // &
                'NumberOfComponents="3" format="ascii">'
            write (unit, '(3es24.15e3)') v
            write (unit, '(a)') '</DataArray></PointData>'
            write (unit, '(a)') '<CellData Scalars="von_mises">'
            write (unit, '(a)') '<DataArray type="Float64" Name="stress" ' // &
                'NumberOfComponents="6" format="ascii">'
            write (unit, '(6es24.15e3)') sigma
            write (unit, '(a)') '</DataArray>'
            write (unit, '(a)') '<DataArray type="Float64" Name="von_mises" format="ascii">'
            write (unit, '(es24.15e3)') mises
            write (unit, '(a)') '</DataArray></CellData>'
            write (unit, '(a)') '</Piece></UnstructuredGrid></VTKFile>'
            close (unit, iostat=ios)
            if (ios /= 0) call status%set(status_io_error, path // ': cannot close')
        end associate
    end subroutine write_mesh

    subroutine write_bodies(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp) :: a(3, 3), centre(3, self%bodies + links(self)), &
            axes(3, 3, self%bodies + links(self))
        integer :: unit, ios, b, k, n
        n = self%bodies + links(self)
        do b = 1, self%bodies
            centre(:, b) = y(7 * b - 6:7 * b - 4)
            axes(:, :, b) = rotation_matrix(y(7 * b - 3:7 * b))
        end do
        do b = 1, links(self)
            associate (ch => self%chain, c => centre(:, self%bodies + b))
                call ch%body_frame(y(self%chain_q + 1:self%chain_q + ch%nq), b, c, a)
                c = c + matmul(a, ch%bodies(b)%centre)
                axes(:, :, self%bodies + b) = a
            end associate
        end do
        call open_grid(path, n, n, unit, status)
        if (.not. status%ok()) return
        write (unit, '(3es24.15e3)') centre
        write (unit, '(a)') '</DataArray></Points>'
        write (unit, '(a)') '<Cells><DataArray type="Int64" Name="connectivity" format="ascii">'
        write (unit, '(*(1x,i0))') (b - 1, b=1, n)
        write (unit, '(a)') '</DataArray><DataArray type="Int64" Name="offsets" format="ascii">'
        write (unit, '(*(1x,i0))') (b, b=1, n)
        write (unit, '(a)') '</DataArray><DataArray type="UInt8" Name="types" format="ascii">'
        write (unit, '(*(1x,i0))') (1, b=1, n)
        write (unit, '(a)') '</DataArray></Cells>'
        write (unit, '(a)') '<PointData>'
        do k = 1, 3
            write (unit, '(a)') '<DataArray type="Float64" Name="axis_' // &
                achar(iachar('x') + k - 1) // '" NumberOfComponents="3" format="ascii">'
            write (unit, '(3es24.15e3)') (axes(:, k, b), b=1, n)
            write (unit, '(a)') '</DataArray>'
        end do
        ! which body a point is: its number, and the names in the field data
        write (unit, '(a)') '<DataArray type="Int32" Name="body_id" format="ascii">'
        write (unit, '(*(1x,i0))') (b, b=1, n)
        write (unit, '(a)') '</DataArray>'
        write (unit, '(a)') '</PointData>'
        if (allocated(self%names)) then
            if (size(self%names) >= n) then
                ! a VTK string array in ASCII: each name's character codes, then 0
                write (unit, '(a)') '<FieldData><DataArray type="String" Name="body_names" ' &
                    // 'NumberOfTuples="' // int_text(n) // '" format="ascii">'
                do b = 1, n
                    write (unit, '(*(1x,i0))') (iachar(self%names(b)(k:k)), &
                        k=1, len_trim(self%names(b))), 0
                end do
                write (unit, '(a)') '</DataArray></FieldData>'
            end if
        end if
        write (unit, '(a)') '</Piece></UnstructuredGrid></VTKFile>'
        close (unit, iostat=ios)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot close')
    end subroutine write_bodies

    !> Links of the chain (none without one).
    pure integer function links(self)
        class(vtk_sink_t), intent(in) :: self
        links = 0
        if (associated(self%chain)) links = size(self%chain%bodies)
    end function links

    !> Open an unstructured-grid file and write up to its points' values.
    subroutine open_grid(path, npoints, ncells, unit, status)
        character(len=*), intent(in) :: path
        integer, intent(in) :: npoints, ncells
        integer, intent(out) :: unit
        type(status_t), intent(inout) :: status
        integer :: ios
        open (newunit=unit, file=path, action='write', status='replace', iostat=ios)
        if (ios /= 0) then
            call status%set(status_io_error, path // ': cannot write the ParaView file')
            return
        end if
        write (unit, '(a)') '<?xml version="1.0"?>'
        write (unit, '(a)') comment_opening // written_by // comment_closing
        write (unit, '(a)') '<VTKFile type="UnstructuredGrid" version="0.1" ' // &
            'byte_order="LittleEndian">'
        write (unit, '(a)') '<UnstructuredGrid>'
        write (unit, '(a)') '<Piece NumberOfPoints="' // int_text(npoints) // &
            '" NumberOfCells="' // int_text(ncells) // '">'
        write (unit, '(a)') '<Points><DataArray type="Float64" NumberOfComponents="3" ' // &
            'format="ascii">'
    end subroutine open_grid

    !> PREFIX.pvd: every record so far, file names relative to the .pvd.
    subroutine write_collection(self, status)
        class(vtk_sink_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        character(len=:), allocatable :: base
        character(len=32) :: tbuf
        integer :: unit, ios, k
        base = self%prefix(index(self%prefix, '/', back=.true.) + 1:)
        open (newunit=unit, file=self%prefix // '.pvd', action='write', status='replace', &
              iostat=ios)
        if (ios /= 0) then
            call status%set(status_io_error, self%prefix // '.pvd: cannot write')
            return
        end if
        write (unit, '(a)') '<?xml version="1.0"?>'
        write (unit, '(a)') comment_opening // written_by // comment_closing
        write (unit, '(a)') '<VTKFile type="Collection" version="0.1">'
        write (unit, '(a)') '<Collection>'
        do k = 1, self%records
            ! 17 significant digits: a reader gets back the HDF5 file's /time exactly
            write (tbuf, '(es25.16e3)') self%times(k)
            if (associated(self%body)) write (unit, '(a)') '<DataSet timestep="' // &
                trim(adjustl(tbuf)) // '" part="0" file="' // mesh_piece(base, k) // '"/>'
            if (self%bodies + links(self) > 0) write (unit, '(a)') '<DataSet timestep="' // &
                trim(adjustl(tbuf)) // '" part="1" file="' // bodies_piece(base, k) // '"/>'
        end do
        write (unit, '(a)') '</Collection>'
        write (unit, '(a)') '</VTKFile>'
        close (unit, iostat=ios)
        if (ios /= 0) call status%set(status_io_error, self%prefix // '.pvd: cannot close')
    end subroutine write_collection
end module flexmbs_io_vtk_sink
