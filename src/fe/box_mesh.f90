!> Structured meshes of a box [origin, origin + lengths] by nx × ny × nz
!> hexahedra of either type, with named sets:
!> - node sets: the six faces 'xmin', 'xmax', 'ymin', 'ymax', 'zmin', 'zmax';
!>   the twelve edges, named by their two faces in x, y, z order
!>   ('xmin_ymin', 'xmin_zmax', 'ymax_zmin', …), nodes ordered along the edge;
!>   and the nodes of each boundary element layer ('xmin_layer', …);
!> - element sets: 'all', and the boundary element layers 'xmin_layer',
!>   'xmax_layer', 'ymin_layer', … (the elements touching that face; for a
!>   bar along x the paper's stiffer tips are 'xmin_layer' and 'xmax_layer').
module flexmbs_fe_box_mesh
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_fe_hexahedron, only: hex8, hex27, hex_node_xi
    use flexmbs_fe_mesh, only: mesh_t, node_set_t, element_set_t
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
        integer :: p, grid(3), i, j, k, e, a, ex, ey, ez, idx(3), d, d2, b, n, level, lv(2)
        integer :: stat
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
        allocate (mesh%x(3, product(grid)), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'box mesh node coordinates', 3 * product(int(grid, i8)), 8)
            return
        end if
        allocate (mesh%connectivity(nnode_element, product(divisions)), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'box mesh connectivity', &
                nnode_element * product(int(divisions, i8)), 4)
            return
        end if
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
        allocate (mesh%node_sets(24), mesh%element_sets(7))
        do d = 1, 3
            do a = 1, 2
                level = merge(0, grid(d) - 1, a == 1)
                mesh%node_sets(2 * (d - 1) + a) = grid_set(face_names(a, d), [d], [level], &
                                                           [level])
                ! the nodes of the boundary element layer
                mesh%node_sets(18 + 2 * (d - 1) + a) = grid_set(face_names(a, d) // '_layer', &
                    [d], [merge(0, grid(d) - 1 - p, a == 1)], [merge(p, grid(d) - 1, a == 1)])
            end do
        end do
        n = 6
        do d = 1, 2
            do d2 = d + 1, 3
                do a = 1, 2
                    do b = 1, 2
                        n = n + 1
                        lv = [merge(0, grid(d) - 1, a == 1), merge(0, grid(d2) - 1, b == 1)]
                        mesh%node_sets(n) = grid_set(face_names(a, d) // '_' // &
                            face_names(b, d2), [d, d2], lv, lv)
                    end do
                end do
            end do
        end do
        mesh%element_sets(1)%name = 'all'
        mesh%element_sets(1)%elements = [(e, e = 1, product(divisions))]
        do d = 1, 3
            do a = 1, 2
                mesh%element_sets(1 + 2 * (d - 1) + a) = layer_set(face_names(a, d) // &
                    '_layer', d, merge(0, divisions(d) - 1, a == 1))
            end do
        end do

    contains

        pure integer function grid_node(i, j, k)
            integer, intent(in) :: i, j, k
            grid_node = 1 + i + grid(1) * (j + grid(2) * k)
        end function grid_node


        !> Nodes whose grid indices in the directions dirs lie in [lo, hi], in
        !> grid order (x fastest).
        function grid_set(name, dirs, lo, hi) result(set)
            character(len=*), intent(in) :: name
            integer, intent(in) :: dirs(:), lo(:), hi(:)
            type(node_set_t) :: set
            integer :: i, j, k, n, ijk(3), pass
            set%name = name
            allocate (set%nodes(0))
            do pass = 1, 2 ! count, then fill
                n = 0
                do k = 0, grid(3) - 1
                    do j = 0, grid(2) - 1
                        do i = 0, grid(1) - 1
                            ijk = [i, j, k]
                            if (all(ijk(dirs) >= lo .and. ijk(dirs) <= hi)) then
                                n = n + 1
                                if (pass == 2) set%nodes(n) = grid_node(i, j, k)
                            end if
                        end do
                    end do
                end do
                if (pass == 1) then
                    deallocate (set%nodes)
                    allocate (set%nodes(n))
                end if
            end do
        end function grid_set

        !> Elements whose index in direction d equals level.
        function layer_set(name, d, level) result(set)
            character(len=*), intent(in) :: name
            integer, intent(in) :: d, level
            type(element_set_t) :: set
            integer :: ex, ey, ez, e, n, exyz(3)
            set%name = name
            allocate (set%elements(product(divisions) / divisions(d)))
            n = 0
            e = 0
            do ez = 0, divisions(3) - 1
                do ey = 0, divisions(2) - 1
                    do ex = 0, divisions(1) - 1
                        e = e + 1
                        exyz = [ex, ey, ez]
                        if (exyz(d) == level) then
                            n = n + 1
                            set%elements(n) = e
                        end if
                    end do
                end do
            end do
        end function layer_set
    end subroutine box_mesh
end module flexmbs_fe_box_mesh
