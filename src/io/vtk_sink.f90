!> ParaView output: at every output time, the flexible bodies' meshes as an
!> XML unstructured grid (`PREFIX_NNNN.vtu`, a piece per flexible body:
!> current node positions, the hexahedra in VTK order — hex8 cell type 12,
!> hex27 type 29 —, point data displacement, velocity and node_id
!> (flexmbs's node number in its body, from 1: the piece's point k - 1 is
!> node k), cell data Cauchy stress (xx, yy, zz, xy, yz, xz), its von Mises
!> value, element_id and flexible_id, the body's number in field data
!> flexible_names), the rigid bodies (`PREFIX_bodies_NNNN.vtu`:
!> one vertex per body at its centre of mass, the bodies in absolute
!> coordinates first, then the chains' links; point data the body's three
!> axes and body_id, field data body_names) and a multibody system's joints
!> and drivers (`PREFIX_joints_NNNN.vtu`: one vertex per joint at its marker
!> i, wherever that sits — a body, a chain link, a node frame, a node, the
!> ground; point data joint_id, joint_type (flexmbs_mbs_joint: 1 spherical,
!> 2 revolute, 3 cylindrical, 4 prismatic, 5 universal, 6 fixed, 7 one
!> primitive: drivers, distances), axis (world: marker i's z axis, the joint
!> axis; an angle driver's turning axis, a translation driver's direction),
!> marker_j_offset x_j − x_i (zero for a satisfied spherical, revolute,
!> universal or fixed joint; a prismatic joint's stroke, a distance's rod)
!> and, with constraints in a formulation, reaction_force and
!> reaction_torque on marker i's body (from the multipliers consistent with
!> q and v), reaction_force_j and reaction_torque_j on marker j's
!> (as the HDF5 file's /joints; on the ground its bearing load); field data joint_names
!> — 'joints/NAME', 'joints/NAME (node N)' for an attached node, or
!> 'drivers/NAME', the HDF5 groups — and joint_types). Field data belongs to
!> the data set, before its piece: VTK reads none inside a piece.
!> The files are listed with their times in `PREFIX.pvd` (part 0 the mesh, part
!> 1 the bodies, part 2 the joints). The .pvd is rewritten after every
!> record, so a run that stops keeps a collection ParaView opens. Every
!> file's second line is the comment '<!-- written by flexmbs 0.1.0 -->'
!> (vtk_file_ours).
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
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_mbs_joint, only: joint_primitive, joint_name
    use flexmbs_mbs_primitive_kinds, only: primitive_name, primitive_angle_driver, &
        primitive_translation_driver, primitive_dot2
    implicit none
    private

    !> A flexible body to draw: its free q and v after y(oq) and y(ov).
    type, public :: vtk_flexible_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
        character(len=32) :: name = ''
    end type vtk_flexible_t

    type, extends(sink_t), public :: vtk_sink_t
        character(len=:), allocatable :: prefix
        type(vtk_flexible_t), allocatable :: flexible(:) !! none: no mesh files
        integer :: bodies = 0         !! rigid bodies: (r, p) at y(7 b − 6 : 7 b)
        !> chains (substructures), their links after them, chain c's
        !> coordinates after y(chain_q(c))
        type(rigid_chain_t), pointer :: chains(:) => null()
        integer, allocatable :: chain_q(:)
        !> the names of the rigid bodies, then of the chains' links (a point
        !> each in the bodies' files: field data body_names, point data body_id)
        character(len=32), allocatable :: names(:)
        !> a multibody system's joints and drivers (a point each in the
        !> joints' files): its q after y(system_q); the reactions from its
        !> formulation's consistent multipliers (none: no reactions)
        type(mbs_system_t), pointer :: system => null()
        type(formulation_t), pointer :: formulation => null()
        integer :: system_q = 0
        character(len=80), allocatable :: joint_names(:) !! 'joints/NAME', 'drivers/NAME'
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
        if (meshes(self)) n = n + records
        if (self%bodies + links(self) > 0) n = n + records
        if (joints(self) > 0) n = n + records
        ! '_joints_' is as long as '_bodies_'
        width = len(self%prefix) + len('_bodies_') + len(digits(records)) + len('.vtu')
        allocate (character(len=width) :: paths(n))
        n = 0
        do k = 1, records
            if (meshes(self)) then
                n = n + 1
                paths(n) = mesh_piece(self%prefix, k)
            end if
            if (self%bodies + links(self) > 0) then
                n = n + 1
                paths(n) = bodies_piece(self%prefix, k)
            end if
            if (joints(self) > 0) then
                n = n + 1
                paths(n) = joints_piece(self%prefix, k)
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

    !> PREFIX_joints_NNNN.vtu, the joints at record k
    pure function joints_piece(prefix, k) result(path)
        character(len=*), intent(in) :: prefix
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = prefix // '_joints_' // digits(k - 1) // '.vtu'
    end function joints_piece

    subroutine vtk_output(self, t, y, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: tt(:)
        if (.not. status%ok()) return
        self%records = self%records + 1
        if (meshes(self)) call write_meshes(self, y, mesh_piece(self%prefix, self%records), &
                                            status)
        if (status%ok() .and. self%bodies + links(self) > 0) call write_bodies(self, y, &
            bodies_piece(self%prefix, self%records), status)
        if (status%ok() .and. joints(self) > 0) call write_joints(self, t, y, &
            joints_piece(self%prefix, self%records), status)
        if (.not. status%ok()) return
        if (.not. allocated(self%times)) allocate (self%times(0))
        tt = [self%times, t]
        call move_alloc(tt, self%times)
        call write_collection(self, status)
    end subroutine vtk_output

    !> As 0042, four digits at least.
    pure function digits(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        s = int_text(k)
        if (len(s) < 4) s = repeat('0', 4 - len(s)) // s
    end function digits

    !> The mesh file: a piece per flexible body, the names as field data.
    subroutine write_meshes(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        character(len=32) :: names(size(self%flexible))
        integer :: unit, b
        call open_grid(path, unit, status)
        if (.not. status%ok()) return
        names = self%flexible%name
        write (unit, '(a)') '<FieldData>'
        call write_strings(unit, 'flexible_names', names)
        write (unit, '(a)') '</FieldData>'
        do b = 1, size(self%flexible)
            call write_mesh_piece(self%flexible(b), b, y, unit, path, status)
            if (.not. status%ok()) exit
        end do
        call close_grid(unit, path, status)
    end subroutine write_meshes

    !> Flexible body `id`'s piece of the mesh file.
    subroutine write_mesh_piece(flexible, id, y, unit, path, status)
        type(vtk_flexible_t), intent(in) :: flexible
        integer, intent(in) :: id, unit
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: x(:, :), v(:, :), sigma(:, :), mises(:)
        type(status_t) :: stress_status
        integer :: n, ne, nn, i, j, celltype, stat
        associate (body => flexible%body, mesh => flexible%body%mesh, oq => flexible%oq, &
                   ov => flexible%ov)
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
                    x(j, i) = y(oq + body%dof(j, i))
                    v(j, i) = y(ov + body%dof(j, i))
                end do
            end do
            call body%element_stress(y(oq + 1:oq + body%nq), &
                                     y(ov + 1:ov + body%nv), sigma, mises, &
                                     stress_status)
            if (.not. stress_status%ok()) then
                sigma = 0.0_wp
                mises = 0.0_wp
            end if
            celltype = merge(12, 29, nn == 8)
            call begin_piece(unit, n, ne)
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
            call write_vectors(unit, 'displacement', x - mesh%x)
            call write_vectors(unit, 'velocity', v)
            ! flexmbs's node and element numbers (from 1), beside VTK's ids (from 0)
            call write_integers(unit, 'node_id', [(i, i=1, n)])
            write (unit, '(a)') '</PointData>'
            write (unit, '(a)') '<CellData Scalars="von_mises">'
            write (unit, '(a)') '<DataArray type="Float64" Name="stress" ' // &
                'NumberOfComponents="6" format="ascii">'
            write (unit, '(6es24.15e3)') sigma
            write (unit, '(a)') '</DataArray>'
            write (unit, '(a)') '<DataArray type="Float64" Name="von_mises" format="ascii">'
            write (unit, '(es24.15e3)') mises
            write (unit, '(a)') '</DataArray>'
            call write_integers(unit, 'element_id', [(i, i=1, ne)])
            call write_integers(unit, 'flexible_id', [(id, i=1, ne)])
            write (unit, '(a)') '</CellData>'
            write (unit, '(a)') '</Piece>'
        end associate
    end subroutine write_mesh_piece

    subroutine write_bodies(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp) :: a(3, 3), centre(3, self%bodies + links(self)), &
            axes(3, 3, self%bodies + links(self))
        integer :: unit, b, k, n, f
        n = self%bodies + links(self)
        do b = 1, self%bodies
            centre(:, b) = y(7 * b - 6:7 * b - 4)
            axes(:, :, b) = rotation_matrix(y(7 * b - 3:7 * b))
        end do
        n = self%bodies
        if (associated(self%chains)) then
            do f = 1, size(self%chains)
                do b = 1, size(self%chains(f)%bodies)
                    n = n + 1
                    associate (ch => self%chains(f), c => centre(:, n), oq => self%chain_q(f))
                        call ch%body_frame(y(oq + 1:oq + ch%nq), b, c, a)
                        c = c + matmul(a, ch%bodies(b)%centre)
                        axes(:, :, n) = a
                    end associate
                end do
            end do
        end if
        call open_grid(path, unit, status)
        if (.not. status%ok()) return
        ! the names: field data of the data set (VTK reads none in a piece)
        if (allocated(self%names)) then
            if (size(self%names) >= n) then
                write (unit, '(a)') '<FieldData>'
                call write_strings(unit, 'body_names', self%names(1:n))
                write (unit, '(a)') '</FieldData>'
            end if
        end if
        call begin_piece(unit, n, n)
        write (unit, '(3es24.15e3)') centre
        call write_vertices(unit, n)
        write (unit, '(a)') '<PointData>'
        do k = 1, 3
            call write_vectors(unit, 'axis_' // achar(iachar('x') + k - 1), axes(:, k, :))
        end do
        ! which body a point is: its number, and the names in the field data
        call write_integers(unit, 'body_id', [(b, b=1, n)])
        write (unit, '(a)') '</PointData></Piece>'
        call close_grid(unit, path, status)
    end subroutine write_bodies

    !> The joints' file (module header): a vertex per joint at marker i.
    subroutine write_joints(self, t, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp) :: xi(3, joints(self)), offset(3, joints(self)), axis(3, joints(self)), &
            force(3, 2, joints(self)), torque(3, 2, joints(self)), xj(3), ai(3, 3), aj(3, 3), &
            lambda(self%system%nc)
        character(len=32) :: types(joints(self))
        character(len=80) :: names(joints(self))
        integer :: unit, k, n
        logical :: reactions
        n = joints(self)
        reactions = associated(self%formulation)
        if (reactions) then
            call self%formulation%consistent_multipliers(t, y, lambda, status)
            if (.not. status%ok()) return
        end if
        associate (sys => self%system, q => y(self%system_q + 1:self%system_q + self%system%nq))
            do k = 1, n
                associate (jt => sys%joints(k))
                    call sys%marker_pose(jt%marker_i, q, xi(:, k), ai)
                    call sys%marker_pose(jt%marker_j, q, xj, aj)
                    offset(:, k) = xj - xi(:, k)
                    axis(:, k) = ai(:, joint_axis(jt%joint%kind, jt%joint%primitive(1), &
                                                  jt%joint%axis_i(1)))
                    types(k) = joint_name(jt%joint%kind)
                    if (jt%joint%kind == joint_primitive) types(k) = &
                        primitive_name(jt%joint%primitive(1))
                    if (reactions) call sys%joint_reaction(k, t, q, lambda, force(:, :, k), &
                                                           torque(:, :, k))
                end associate
                names(k) = 'joint ' // int_text(k)
                if (allocated(self%joint_names)) then
                    if (k <= size(self%joint_names)) names(k) = self%joint_names(k)
                end if
            end do
        end associate
        call open_grid(path, unit, status)
        if (.not. status%ok()) return
        write (unit, '(a)') '<FieldData>'
        call write_strings(unit, 'joint_names', names)
        call write_strings(unit, 'joint_types', types)
        write (unit, '(a)') '</FieldData>'
        call begin_piece(unit, n, n)
        write (unit, '(3es24.15e3)') xi
        call write_vertices(unit, n)
        write (unit, '(a)') '<PointData Vectors="axis">'
        call write_integers(unit, 'joint_id', [(k, k=1, n)])
        call write_integers(unit, 'joint_type', [(self%system%joints(k)%joint%kind, k=1, n)])
        call write_vectors(unit, 'axis', axis)
        call write_vectors(unit, 'marker_j_offset', offset)
        if (reactions) then
            call write_vectors(unit, 'reaction_force', force(:, 1, :))
            call write_vectors(unit, 'reaction_torque', torque(:, 1, :))
            call write_vectors(unit, 'reaction_force_j', force(:, 2, :))
            call write_vectors(unit, 'reaction_torque_j', torque(:, 2, :))
        end if
        write (unit, '(a)') '</PointData></Piece>'
        call close_grid(unit, path, status)
    end subroutine write_joints

    !> Which of marker i's axes is a joint's axis: z (flexmbs_mbs_joint's
    !> convention), for a single primitive the axis it acts about or along.
    pure integer function joint_axis(kind, primitive, axis_i) result(k)
        integer, intent(in) :: kind, primitive, axis_i
        k = 3
        if (kind /= joint_primitive) return
        select case (primitive)
        case (primitive_angle_driver)
            k = mod(axis_i + 1, 3) + 1   ! about axis k + 2 (cyclic)
        case (primitive_translation_driver, primitive_dot2)
            k = axis_i
        end select
    end function joint_axis

    !> Joints of the system (none without one).
    pure integer function joints(self)
        class(vtk_sink_t), intent(in) :: self
        joints = 0
        if (associated(self%system)) joints = size(self%system%joints)
    end function joints

    !> The cells of n points, a vertex (type 1) each, after the points.
    subroutine write_vertices(unit, n)
        integer, intent(in) :: unit, n
        integer :: b
        write (unit, '(a)') '</DataArray></Points>'
        write (unit, '(a)') '<Cells><DataArray type="Int64" Name="connectivity" format="ascii">'
        write (unit, '(*(1x,i0))') (b - 1, b=1, n)
        write (unit, '(a)') '</DataArray><DataArray type="Int64" Name="offsets" format="ascii">'
        write (unit, '(*(1x,i0))') (b, b=1, n)
        write (unit, '(a)') '</DataArray><DataArray type="UInt8" Name="types" format="ascii">'
        write (unit, '(*(1x,i0))') (1, b=1, n)
        write (unit, '(a)') '</DataArray></Cells>'
    end subroutine write_vertices

    subroutine write_integers(unit, name, values)
        integer, intent(in) :: unit, values(:)
        character(len=*), intent(in) :: name
        write (unit, '(a)') '<DataArray type="Int32" Name="' // name // '" format="ascii">'
        write (unit, '(*(1x,i0))') values
        write (unit, '(a)') '</DataArray>'
    end subroutine write_integers

    !> A vector per point (the columns of `values`).
    subroutine write_vectors(unit, name, values)
        integer, intent(in) :: unit
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: values(:, :)
        write (unit, '(a)') '<DataArray type="Float64" Name="' // name // &
            '" NumberOfComponents="3" format="ascii">'
        write (unit, '(3es24.15e3)') values
        write (unit, '(a)') '</DataArray>'
    end subroutine write_vectors

    !> A VTK string array in ASCII: each name's character codes, then 0.
    subroutine write_strings(unit, name, names)
        integer, intent(in) :: unit
        character(len=*), intent(in) :: name, names(:)
        integer :: b, k
        write (unit, '(a)') '<DataArray type="String" Name="' // name // &
            '" NumberOfTuples="' // int_text(size(names)) // '" format="ascii">'
        do b = 1, size(names)
            write (unit, '(*(1x,i0))') (iachar(names(b)(k:k)), k=1, len_trim(names(b))), 0
        end do
        write (unit, '(a)') '</DataArray>'
    end subroutine write_strings

    !> The end of the file, after its pieces.
    subroutine close_grid(unit, path, status)
        integer, intent(in) :: unit
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        integer :: ios
        write (unit, '(a)') '</UnstructuredGrid></VTKFile>'
        close (unit, iostat=ios)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot close')
    end subroutine close_grid

    !> Whether there are flexible bodies to draw.
    pure logical function meshes(self)
        class(vtk_sink_t), intent(in) :: self
        meshes = .false.
        if (allocated(self%flexible)) meshes = size(self%flexible) > 0
    end function meshes

    !> Links of the chains (none without them).
    pure integer function links(self)
        class(vtk_sink_t), intent(in) :: self
        integer :: f
        links = 0
        if (.not. associated(self%chains)) return
        do f = 1, size(self%chains)
            links = links + size(self%chains(f)%bodies)
        end do
    end function links

    !> Open an unstructured-grid file and write up to its data set's field
    !> data (begin_piece follows).
    subroutine open_grid(path, unit, status)
        character(len=*), intent(in) :: path
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
    end subroutine open_grid

    !> The piece's opening, up to its points' values.
    subroutine begin_piece(unit, npoints, ncells)
        integer, intent(in) :: unit, npoints, ncells
        write (unit, '(a)') '<Piece NumberOfPoints="' // int_text(npoints) // &
            '" NumberOfCells="' // int_text(ncells) // '">'
        write (unit, '(a)') '<Points><DataArray type="Float64" NumberOfComponents="3" ' // &
            'format="ascii">'
    end subroutine begin_piece

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
            if (meshes(self)) write (unit, '(a)') '<DataSet timestep="' // &
                trim(adjustl(tbuf)) // '" part="0" file="' // mesh_piece(base, k) // '"/>'
            if (self%bodies + links(self) > 0) write (unit, '(a)') '<DataSet timestep="' // &
                trim(adjustl(tbuf)) // '" part="1" file="' // bodies_piece(base, k) // '"/>'
            if (joints(self) > 0) write (unit, '(a)') '<DataSet timestep="' // &
                trim(adjustl(tbuf)) // '" part="2" file="' // joints_piece(base, k) // '"/>'
        end do
        write (unit, '(a)') '</Collection>'
        write (unit, '(a)') '</VTKFile>'
        close (unit, iostat=ios)
        if (ios /= 0) call status%set(status_io_error, self%prefix // '.pvd: cannot close')
    end subroutine write_collection
end module flexmbs_io_vtk_sink
