!> ParaView output: at every output time, the flexible bodies' meshes as an
!> XML unstructured grid (`PREFIX_NNNN.vtu`, one piece, the flexible bodies
!> one after the other: current node positions, the hexahedra in VTK order
!> — hex8 cell type 12, hex27 type 29 —, point data displacement, velocity
!> and node_id (flexmbs's node number in its body, from 1: with one body
!> point k - 1 is node k), cell data Cauchy stress (xx, yy, zz, xy, yz,
!> xz), its von Mises value, element_id (in its body) and flexible_id, the
!> body's number in field data flexible_names), the rigid bodies (`PREFIX_bodies_NNNN.vtu`:
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
!> the data set, before its piece: VTK reads none inside a piece. The names
!> are UInt8 arrays of their bytes, each name followed by a 0, as meshio
!> reads no String arrays. The arrays are binary (base64 appended data)
!> unless `binary` is false (text); flexmbs_io_vtu_file writes either.
!> The files are listed with their times in `PREFIX.pvd` (part 0 the mesh, part
!> 1 the bodies, part 2 the joints). The .pvd is rewritten after every
!> record, so a run that stops keeps a collection ParaView opens. Every
!> file's second line is the comment '<!-- written by flexmbs 0.1.0 -->'
!> (flexmbs_io_vtu_file's xml_file_ours).
module flexmbs_io_vtk_sink
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_version, only: written_by
    use flexmbs_io_vtu_file, only: vtu_file_t, open_vtu, comment_opening, comment_closing
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_mbs_rotation, only: rotation_matrix
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t
    use flexmbs_mbs_system, only: mbs_system_t, part_chain
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_mbs_joint_types, only: joint_primitive, joint_name
    use flexmbs_mbs_primitive_kinds, only: primitive_name, primitive_angle_driver, &
        primitive_translation_driver, primitive_dot2
    implicit none
    private

    !> A flexible body to draw: its free q and v after y(oq) and y(ov); or
    !> a modal body (`modal`; body => its FE body), its (r, p, η) after
    !> y(oq) and (ṙ, ω′, η̇) after y(ov), its nodes reconstructed.
    type, public :: vtk_flexible_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
        character(len=32) :: name = ''
        type(modal_body_t), pointer :: modal => null()
    end type vtk_flexible_t

    !> The ParaView sink (the module's files): the file prefix and what it draws,
    !> flexible bodies, rigid bodies, chains and a system's joints.
    type, extends(sink_t), public :: vtk_sink_t
        character(len=:), allocatable :: prefix
        type(vtk_flexible_t), allocatable :: flexible(:) !! none: no mesh files
        integer :: bodies = 0         !! rigid bodies: (r, p) at y(7 b − 6 : 7 b)
        !> the names of the rigid bodies, then of the chains' links (a point
        !> each in the bodies' files: field data body_names, point data body_id)
        character(len=32), allocatable :: names(:)
        !> a multibody system: its chains' links (after the rigid bodies) and
        !> its joints and drivers (a point each in the joints' files), its q
        !> after y(system_q); the reactions from its formulation's consistent
        !> multipliers (none: no reactions)
        type(mbs_system_t), pointer :: system => null()
        type(formulation_t), pointer :: formulation => null()
        integer :: system_q = 0
        character(len=80), allocatable :: joint_names(:) !! 'joints/NAME', 'drivers/NAME'
        integer :: records = 0
        real(wp), allocatable :: times(:)
        !> the .vtu arrays binary (base64 appended data), else text
        logical :: binary = .true.
    contains
        procedure :: output => vtk_output
        procedure :: pieces => vtk_pieces
    end type vtk_sink_t

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
        include '../dae/sink_output_arguments.inc'
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

    !> The mesh file: the flexible bodies one after the other in one piece
    !> (meshio 5.3.5 keeps the cells of a file's last piece only), the
    !> names as field data.
    subroutine write_meshes(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        type(vtu_file_t) :: file
        character(len=32) :: names(size(self%flexible))
        real(wp), allocatable :: x(:, :), v(:, :), sigma(:, :), mises(:)
        integer, allocatable :: points(:), ends(:), types(:), node_id(:), element_id(:), &
            flexible_id(:)
        integer :: b, n, ne, nc, stat
        names = self%flexible%name
        n = 0
        ne = 0
        nc = 0
        do b = 1, size(self%flexible)
            associate (body => self%flexible(b)%body)
                n = n + body%node_count()
                ne = ne + body%element_count()
                nc = nc + body%nodes_per_element() * body%element_count()
            end associate
        end do
        allocate (x(3, n), v(3, n), sigma(6, ne), mises(ne), points(nc), ends(ne), &
                  types(ne), node_id(n), element_id(ne), flexible_id(ne), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, path // ': node and element fields', &
                8_i8 * n + 11_i8 * ne + nc, 8)
            return
        end if
        n = 0
        ne = 0
        nc = 0
        do b = 1, size(self%flexible)
            call body_fields(self%flexible(b), b, y)
        end do
        call open_vtu(file, path, self%binary, status)
        if (.not. status%ok()) return
        call file%line('<FieldData>')
        call file%names('flexible_names', names)
        call file%line('</FieldData>')
        call file%begin_piece(x, ne)
        call file%cells(points, ends, types)
        call file%line('<PointData Vectors="displacement">')
        call file%reals('displacement', x - reference())
        call file%reals('velocity', v)
        ! flexmbs's node and element numbers in their body (from 1), beside
        ! VTK's ids (from 0, over all bodies)
        call file%integers('node_id', node_id)
        call file%line('</PointData>')
        call file%line('<CellData Scalars="von_mises">')
        call file%reals('stress', sigma)
        call file%reals('von_mises', reshape(mises, [1, ne]))
        call file%integers('element_id', element_id)
        call file%integers('flexible_id', flexible_id)
        call file%line('</CellData>')
        call file%line('</Piece>')
        call file%close(status)

    contains

        !> Body `id`'s points, cells and fields after the n nodes, ne
        !> elements and nc connectivity entries of the bodies before it.
        subroutine body_fields(flexible, id, y)
            type(vtk_flexible_t), intent(in) :: flexible
            integer, intent(in) :: id
            real(wp), intent(in) :: y(:)
            type(status_t) :: stress_status
            integer :: i, j, k, nn, m, me, dofs(3)
            associate (body => flexible%body, oq => flexible%oq, ov => flexible%ov)
                m = body%node_count()
                me = body%element_count()
                nn = body%nodes_per_element()
                call body%reference_nodes(x(:, n + 1:n + m))
                v(:, n + 1:n + m) = 0.0_wp
                if (associated(flexible%modal)) then
                    call modal_fields(flexible%modal, y(oq + 1:oq + flexible%modal%nq), &
                        y(ov + 1:ov + flexible%modal%nv), x(:, n + 1:n + m), v(:, n + 1:n + m), &
                        stress_status)
                else
                    do i = 1, m
                        dofs = body%node_dofs(i)
                        do j = 1, 3
                            if (dofs(j) == 0) cycle
                            x(j, n + i) = y(oq + dofs(j))
                            v(j, n + i) = y(ov + dofs(j))
                        end do
                    end do
                    call body%element_stress(y(oq + 1:oq + body%nq), y(ov + 1:ov + body%nv), &
                        sigma(:, ne + 1:ne + me), mises(ne + 1:ne + me), stress_status)
                end if
                if (.not. stress_status%ok()) then
                    sigma(:, ne + 1:ne + me) = 0.0_wp
                    mises(ne + 1:ne + me) = 0.0_wp
                end if
                do k = 1, me
                    points(nc + 1:nc + nn) = body%element_nodes(k) + n
                    nc = nc + nn
                    ends(ne + k) = nc
                end do
                ! hex8: VTK_HEXAHEDRON (12), hex27: VTK_TRIQUADRATIC_HEXAHEDRON (29)
                types(ne + 1:ne + me) = merge(12, 29, nn == 8)
                node_id(n + 1:n + m) = [(i, i=1, m)]
                element_id(ne + 1:ne + me) = [(k, k=1, me)]
                flexible_id(ne + 1:ne + me) = id
                n = n + m
                ne = ne + me
            end associate
        end subroutine body_fields

        !> A modal body's nodes and element stresses (into sigma, mises at
        !> ne + 1 ...) from its coordinates.
        subroutine modal_fields(modal, qm, vm, xb, vb, stress_status)
            type(modal_body_t), intent(inout), target :: modal
            real(wp), intent(in) :: qm(:), vm(:)
            real(wp), intent(out) :: xb(:, :), vb(:, :)
            type(status_t), intent(out) :: stress_status
            real(wp) :: xf(size(xb)), vf(size(vb))
            type(flexible_body_t), pointer :: fe
            integer :: me
            fe => modal%fe_body()
            me = fe%element_count()
            call modal%node_positions(qm, xf)
            call modal%node_velocities(qm, vm, vf)
            xb = reshape(xf, shape(xb))
            vb = reshape(vf, shape(vb))
            call fe%element_stress(xf, vf, sigma(:, ne + 1:ne + me), mises(ne + 1:ne + me), &
                                   stress_status)
        end subroutine modal_fields

        !> The bodies' reference positions, as x.
        function reference() result(x0)
            real(wp) :: x0(3, size(x, 2))
            integer :: b, m
            m = 0
            do b = 1, size(self%flexible)
                associate (body => self%flexible(b)%body)
                    call body%reference_nodes(x0(:, m + 1:m + body%node_count()))
                    m = m + body%node_count()
                end associate
            end do
        end function reference
    end subroutine write_meshes

    subroutine write_bodies(self, y, path, status)
        class(vtk_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        character(len=*), intent(in) :: path
        type(status_t), intent(inout) :: status
        real(wp) :: a(3, 3), centre(3, self%bodies + links(self)), &
            axes(3, 3, self%bodies + links(self))
        type(vtu_file_t) :: file
        type(rigid_chain_t), pointer :: chain
        integer :: b, k, n, f, oq, ov
        n = self%bodies + links(self)
        do b = 1, self%bodies
            centre(:, b) = y(7 * b - 6:7 * b - 4)
            axes(:, :, b) = rotation_matrix(y(7 * b - 3:7 * b))
        end do
        n = self%bodies
        if (associated(self%system)) then
            do f = 1, self%system%chain_count()
                chain => self%system%chain_of(f)
                call self%system%part_offsets(part_chain, f, oq, ov)
                do b = 1, chain%link_count()
                    n = n + 1
                    associate (c => centre(:, n))
                        call chain%body_frame(y(oq + 1:oq + chain%nq), b, c, a)
                        c = c + matmul(a, chain%link_centre(b))
                        axes(:, :, n) = a
                    end associate
                end do
            end do
        end if
        call open_vtu(file, path, self%binary, status)
        if (.not. status%ok()) return
        ! the names: field data of the data set (VTK reads none in a piece)
        if (allocated(self%names)) then
            if (size(self%names) >= n) then
                call file%line('<FieldData>')
                call file%names('body_names', self%names(1:n))
                call file%line('</FieldData>')
            end if
        end if
        call file%begin_piece(centre, n)
        call file%cells([(b, b=1, n)], [(b, b=1, n)], [(1, b=1, n)])
        call file%line('<PointData>')
        do k = 1, 3
            call file%reals('axis_' // achar(iachar('x') + k - 1), axes(:, k, :))
        end do
        ! which body a point is: its number, and the names in the field data
        call file%integers('body_id', [(b, b=1, n)])
        call file%line('</PointData></Piece>')
        call file%close(status)
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
        type(vtu_file_t) :: file
        integer :: k, n, kind_k, first, markers(2)
        logical :: reactions
        n = joints(self)
        reactions = associated(self%formulation)
        if (reactions) then
            call self%formulation%consistent_multipliers(t, y, lambda, status)
            if (.not. status%ok()) return
        end if
        associate (sys => self%system, q => y(self%system_q + 1:self%system_q + self%system%nq))
            do k = 1, n
                markers = sys%joint_markers(k)
                call sys%marker_pose(markers(1), q, xi(:, k), ai)
                call sys%marker_pose(markers(2), q, xj, aj)
                offset(:, k) = xj - xi(:, k)
                kind_k = sys%joint_kind(k)
                first = 0
                if (sys%joint_primitive_count(k) > 0) first = sys%joint_primitive(k, 1)
                axis(:, k) = ai(:, joint_axis(kind_k, first, sys%joint_axis(k)))
                types(k) = joint_name(kind_k)
                if (kind_k == joint_primitive) types(k) = primitive_name(first)
                if (reactions) call sys%joint_reaction(k, t, q, lambda, force(:, :, k), &
                                                       torque(:, :, k))
                names(k) = 'joint ' // int_text(k)
                if (allocated(self%joint_names)) then
                    if (k <= size(self%joint_names)) names(k) = self%joint_names(k)
                end if
            end do
        end associate
        call open_vtu(file, path, self%binary, status)
        if (.not. status%ok()) return
        call file%line('<FieldData>')
        call file%names('joint_names', names)
        call file%names('joint_types', types)
        call file%line('</FieldData>')
        call file%begin_piece(xi, n)
        ! a vertex (VTK_VERTEX) per joint
        call file%cells([(k, k=1, n)], [(k, k=1, n)], [(1, k=1, n)])
        call file%line('<PointData Vectors="axis">')
        call file%integers('joint_id', [(k, k=1, n)])
        call file%integers('joint_type', [(self%system%joint_kind(k), k=1, n)])
        call file%reals('axis', axis)
        call file%reals('marker_j_offset', offset)
        if (reactions) then
            call file%reals('reaction_force', force(:, 1, :))
            call file%reals('reaction_torque', torque(:, 1, :))
            call file%reals('reaction_force_j', force(:, 2, :))
            call file%reals('reaction_torque_j', torque(:, 2, :))
        end if
        call file%line('</PointData></Piece>')
        call file%close(status)
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
        if (associated(self%system)) joints = self%system%joint_count()
    end function joints

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
        if (.not. associated(self%system)) return
        do f = 1, self%system%chain_count()
            links = links + self%system%link_count(f)
        end do
    end function links

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
