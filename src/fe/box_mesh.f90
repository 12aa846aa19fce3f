!> Structured meshes of a box [origin, origin + lengths] by nx × ny × nz
!> hexahedra of either type, with the six faces as node sets
!> 'xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax'.
module flexmbs_fe_box_mesh
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_fe_hexahedron, only: hex8, hex27, hex_node_xi
    use flexmbs_fe_mesh, only: mesh_t, node_set_t
    implicit none
    private

    public :: box_mesh

contains

    !> Box mesh: nodes on a regular grid of p·n + 1 points per direction
    !> (p = 1 for hex8, 2 for hex27), numbered x fastest, then y, then z.
    subroutine box_mesh(mesh, nnode_element, divisions, lengths, status, origin)
        type(mesh_t), intent(out) :: mesh
        integer, intent(in) :: nnode_element  !! hex8 or hex27
        integer, intent(in) :: divisions(3)   !! elements per direction
        real(wp), intent(in) :: lengths(3)    !! box edge lengths
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: origin(3) !! lower corner (default 0)
        integer :: p, grid(3), i, j, k, e, a, ex, ey, ez, idx(3), d
        real(wp) :: x0(3)
        character(len=120) :: msg
        character(len=4), parameter :: face_names(2, 3) = reshape( &
            ['xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax'], [2, 3])
        if (nnode_element /= hex8 .and. nnode_element /= hex27) then
            write (msg, '(a,i0,a)') 'box mesh: nodes per element = ', nnode_element, &
                ': must be 8 or 27'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (any(divisions < 1) .or. any(.not. (lengths > 0.0_wp))) then
            write (msg, '(a,3(1x,i0),a,3(1x,es10.3),a)') 'box mesh: divisions =', divisions, &
                ', lengths =', lengths, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        x0 = 0.0_wp
        if (present(origin)) x0 = origin
        p = merge(1, 2, nnode_element == hex8)
        grid = p * divisions + 1
        mesh%nnode_element = nnode_element
        allocate (mesh%x(3, product(grid)), mesh%connectivity(nnode_element, product(divisions)))
        do k = 0, grid(3) - 1
            do j = 0, grid(2) - 1
                do i = 0, grid(1) - 1
                    mesh%x(:, grid_node(i, j, k)) = x0 + lengths * [i, j, k] / real(grid - 1, wp)
                end do
            end do
        end do
        e = 0
        do ez = 0, divisions(3) - 1
            do ey = 0, divisions(2) - 1
                do ex = 0, divisions(1) - 1
                    e = e + 1
                    do a = 1, nnode_element
                        ! natural coordinate −1, 0, 1 → grid offset 0, p/2, p
                        idx = p * [ex, ey, ez] + nint((hex_node_xi(:, a) + 1.0_wp) * p / 2)
                        mesh%connectivity(a, e) = grid_node(idx(1), idx(2), idx(3))
                    end do
                end do
            end do
        end do
        allocate (mesh%node_sets(6))
        do d = 1, 3
            do a = 1, 2
                mesh%node_sets(2 * (d - 1) + a) = face_set(face_names(a, d), d, &
                                                           merge(0, grid(d) - 1, a == 1))
            end do
        end do

    contains

        pure integer function grid_node(i, j, k)
            integer, intent(in) :: i, j, k
            grid_node = 1 + i + grid(1) * (j + grid(2) * k)
        end function grid_node

        !> Nodes whose grid index in direction d equals level.
        function face_set(name, d, level) result(set)
            character(len=*), intent(in) :: name
            integer, intent(in) :: d, level
            type(node_set_t) :: set
            integer :: i, j, k, n, ijk(3)
            set%name = name
            allocate (set%nodes(product(grid) / grid(d)))
            n = 0
            do k = 0, grid(3) - 1
                do j = 0, grid(2) - 1
                    do i = 0, grid(1) - 1
                        ijk = [i, j, k]
                        if (ijk(d) == level) then
                            n = n + 1
                            set%nodes(n) = grid_node(i, j, k)
                        end if
                    end do
                end do
            end do
        end function face_set
    end subroutine box_mesh
end module flexmbs_fe_box_mesh
