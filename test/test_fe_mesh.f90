!> Mesh sets and the text mesh format: box-mesh edges and element layers,
!> set lookup and checks, exact write/read round trips, a mesh file as a
!> flexible body, and the messages for malformed files.
module test_fe_mesh
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_mesh_file, only: read_mesh, write_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use test_problems, only: fill_random
    use test_fe, only: paper_material
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_fe_mesh

    character(len=*), parameter :: scratch = 'build/test-fe-mesh'
    integer, parameter :: divisions(3) = [3, 2, 2]
    real(wp), parameter :: lengths(3) = [0.6_wp, 0.2_wp, 0.3_wp]

contains

    function collect_fe_mesh() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('box_edges_and_layers', test_box_sets), &
                 new_test('set_lookup_and_check', test_lookup), &
                 new_test('round_trip_exact', test_round_trip), &
                 new_test('file_mesh_as_body', test_file_body), &
                 new_test('malformed_files', test_malformed)]
    end function collect_fe_mesh

    !> Edges: the nodes on both faces, ordered along the third axis; layers:
    !> the elements touching the face; 'all' every element.
    subroutine test_box_sets(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: kinds(2) = [hex8, hex27]
        type(mesh_t) :: mesh
        type(status_t) :: status
        integer, allocatable :: nodes(:), elements(:)
        integer :: k, p, grid(3), e
        do k = 1, 2
            call box_mesh(mesh, kinds(k), divisions, lengths, status)
            call check(error, status%ok(), 'box: ' // status%text())
            if (allocated(error)) return
            p = merge(1, 2, kinds(k) == hex8)
            grid = p * divisions + 1
            call mesh%check(status)
            call check(error, status%ok(), 'box: check: ' // status%text())
            call check(error, size(mesh%node_sets) == 24 .and. size(mesh%element_sets) == 7, &
                       'box: 6 faces + 12 edges + 6 layers, all + 6 layers expected')
            call mesh%node_set('xmax_layer', nodes, status)
            call check(error, status%ok() .and. size(nodes) == (p + 1) * grid(2) * grid(3) &
                       .and. all(mesh%x(1, nodes) >= lengths(1) * (1.0_wp - 1.0_wp / &
                       divisions(1)) - 1.0e-14_wp), 'box: xmax_layer nodes')
            call mesh%node_set('ymax_zmin', nodes, status)
            call check(error, status%ok() .and. size(nodes) == grid(1), 'box: ymax_zmin size')
            if (allocated(error)) return
            call check(error, all(mesh%x(2, nodes) == lengths(2)) .and. &
                       all(mesh%x(3, nodes) == 0.0_wp), 'box: ymax_zmin off its faces')
            call check(error, all(mesh%x(1, nodes(2:)) > mesh%x(1, nodes(:size(nodes) - 1))), &
                       'box: ymax_zmin not ordered along x')
            call mesh%node_set('xmin_zmax', nodes, status)
            call check(error, status%ok() .and. size(nodes) == grid(2) .and. &
                       all(mesh%x(1, nodes) == 0.0_wp) .and. &
                       all(abs(mesh%x(3, nodes) - lengths(3)) < 1.0e-15_wp), 'box: xmin_zmax')
            call mesh%element_set('xmax_layer', elements, status)
            call check(error, status%ok() .and. size(elements) == divisions(2) * divisions(3), &
                       'box: xmax_layer size')
            if (allocated(error)) return
            do e = 1, size(elements)
                call check(error, minval(mesh%x(1, mesh%connectivity(:, elements(e)))) > &
                           lengths(1) * (1.0_wp - 1.0_wp / divisions(1)) - 1.0e-14_wp, &
                           'box: xmax_layer element away from xmax')
            end do
            call mesh%element_set('zmin_layer', elements, status)
            call check(error, status%ok() .and. size(elements) == divisions(1) * divisions(2) &
                       .and. all(mesh%x(3, mesh%connectivity(1, elements)) == 0.0_wp), &
                       'box: zmin_layer')
            call mesh%element_set('all', elements, status)
            call check(error, status%ok() .and. size(elements) == product(divisions), 'box: all')
            if (allocated(error)) return
        end do
    end subroutine test_box_sets

    !> Missing sets name themselves; check catches a repeated node and a
    !> set member out of range.
    subroutine test_lookup(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh, bad
        type(status_t) :: status
        integer, allocatable :: elements(:)
        call box_mesh(mesh, hex8, divisions, lengths, status)
        call mesh%element_set('tip', elements, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'no element set named ''tip''') > 0, &
                   'lookup: ' // status%text())
        bad = mesh
        bad%connectivity(2, 1) = bad%connectivity(1, 1)
        call bad%check(status)
        call check(error, index(status%text(), 'twice') > 0, 'check: repeated node: ' // &
                   status%text())
        bad = mesh
        bad%element_sets(2)%elements(1) = 99
        call bad%check(status)
        call check(error, index(status%text(), 'outside 1..12') > 0, 'check: set range: ' // &
                   status%text())
    end subroutine test_lookup

    !> A distorted hex27 box with all its sets, written and read back: equal
    !> bit for bit.
    subroutine test_round_trip(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh, back
        type(status_t) :: status
        real(wp), allocatable :: p(:)
        integer(i8) :: seed
        integer :: i
        character(len=*), parameter :: path = scratch // '/round_trip.mesh'
        call execute_command_line('mkdir -p ' // scratch)
        call box_mesh(mesh, hex27, divisions, lengths, status)
        allocate (p(size(mesh%x)))
        seed = 17
        call fill_random(p, seed, -0.01_wp, 0.01_wp)
        mesh%x = mesh%x + reshape(p, shape(mesh%x)) * 1.0e-1_wp / 3
        call write_mesh(path, mesh, status)
        call check(error, status%ok(), 'round trip: write: ' // status%text())
        if (allocated(error)) return
        call read_mesh(path, back, status)
        call check(error, status%ok(), 'round trip: read: ' // status%text())
        if (allocated(error)) return
        call check(error, all(back%x == mesh%x), 'round trip: coordinates differ')
        call check(error, back%nnode_element == 27 .and. &
                   all(back%connectivity == mesh%connectivity), 'round trip: connectivity')
        call check(error, size(back%node_sets) == size(mesh%node_sets) .and. &
                   size(back%element_sets) == size(mesh%element_sets), 'round trip: set counts')
        if (allocated(error)) return
        do i = 1, size(mesh%node_sets)
            call check(error, back%node_sets(i)%name == mesh%node_sets(i)%name .and. &
                       all(back%node_sets(i)%nodes == mesh%node_sets(i)%nodes), &
                       'round trip: node set ' // mesh%node_sets(i)%name)
        end do
        do i = 1, size(mesh%element_sets)
            call check(error, back%element_sets(i)%name == mesh%element_sets(i)%name .and. &
                       all(back%element_sets(i)%elements == mesh%element_sets(i)%elements), &
                       'round trip: element set ' // mesh%element_sets(i)%name)
        end do
        open (newunit=i, file=path)
        close (i, status='delete')
    end subroutine test_round_trip

    !> inputs/meshes/bar_hex8.mesh as a clamped body with a denser tip
    !> element: mass = ρ V + Δρ V_tip, read from the momentum of a unit
    !> translation (fixed nodes at rest: the clamp's share is missing, so
    !> the free body is used for the mass, the clamped one for the dofs).
    subroutine test_file_body(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(status_t) :: status
        type(flexible_body_t) :: body
        type(neo_hooke_t) :: mats(2)
        integer, allocatable :: clamp(:), tip(:), material(:)
        real(wp) :: linear(3), angular(3)
        real(wp), allocatable :: v(:)
        call read_mesh('inputs/meshes/bar_hex8.mesh', mesh, status)
        call check(error, status%ok(), 'file body: ' // status%text())
        if (allocated(error)) return
        call check(error, mesh%node_count() == 20 .and. mesh%element_count() == 4, &
                   'file body: sizes')
        call paper_material(mats(1))
        mats(2) = mats(1)
        mats(2)%density = 2.0_wp * mats(1)%density
        call mesh%element_set('tip_layer', tip, status)
        if (status%ok()) call mesh%node_set('clamp', clamp, status)
        call check(error, status%ok(), 'file body: sets: ' // status%text())
        if (allocated(error)) return
        allocate (material(4), source=1)
        material(tip) = 2
        call new_flexible_body(body, mesh, mats, [integer ::], status, element_material=material)
        call check(error, status%ok(), 'file body: body: ' // status%text())
        if (allocated(error)) return
        allocate (v(body%nv))
        v = 0.0_wp
        v(1::3) = 1.0_wp
        call body%momenta(body%free_positions(), v, linear, angular)
        call check_close(error, linear(1), mats(1)%density * 0.01_wp * 1.25_wp, 1.0e-12_wp, &
                         'file body: mass', rel=.true.)
        call new_flexible_body(body, mesh, mats, clamp, status, element_material=material)
        call check(error, status%ok() .and. body%nq == 3 * 16, 'file body: clamped dofs')
    end subroutine test_file_body

    !> Each defect gives bad input naming the file, its line and the reason.
    subroutine test_malformed(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: nl = new_line('a')
        character(len=*), parameter :: head = 'flexmbs-mesh 1' // nl // 'nodes 8' // nl // &
            '1 0 0 0' // nl // '2 1 0 0' // nl // '3 1 1 0' // nl // '4 0 1 0' // nl // &
            '5 0 0 1' // nl // '6 1 0 1' // nl // '7 1 1 1' // nl // '8 0 1 1' // nl
        character(len=*), parameter :: good_element = 'elements hex8 1' // nl // &
            '1 1 2 3 4 5 6 7 8' // nl
        type(mesh_t) :: mesh
        type(status_t) :: status
        call read_text('ok', head // good_element // 'node_set base 4' // nl // '1 2 3 4' // nl)
        call check(error, status%ok() .and. mesh%element_count() == 1, 'malformed: the good ' &
                   // 'file fails: ' // status%text())
        call expect('version', 'flexmbs-mesh 2' // nl, ':1: format version 2')
        ! a count the rest of the file cannot hold: refused before allocating
        call expect('truncated', head(1:index(head, '8 0 1 1') - 1), &
                    ':2: 8 nodes declared, but the file holds only 28 more values')
        call expect('truncated_set', head // good_element // 'node_set base 4' // nl // &
                    '1 2 3' // nl, ':13: 4 set members declared, but the file holds only 3 more')
        ! a count sizes nothing beyond what the file holds (2e9 nodes were
        ! allocated first, 48 GB: a runtime error)
        call expect('node-count', 'flexmbs-mesh 1' // nl // 'nodes 2000000000' // nl // &
                    '1 0 0 0' // nl, ':2: 2000000000 nodes declared, but the file holds only 4')
        call expect('element-count', head // 'elements hex8 1000000000' // nl // &
                    '1 1 2 3 4 5 6 7 8' // nl, ':11: 1000000000 elements declared, but the file')
        call expect('set-size', head // good_element // 'node_set base 2147483647' // nl // &
                    '1 2 3 4' // nl, ':13: 2147483647 set members declared, but the file holds')
        call expect('number', head(1:index(head, '2 1 0 0') - 1) // '2 1 x0 0' // &
                    head(index(head, '2 1 0 0') + 7:), ':4: ''x0'' is not a number')
        call expect('range', head // 'elements hex8 1' // nl // '1 1 2 3 4 5 6 7 9' // nl, &
                    ':12: element 1 names node 9, outside 1..8')
        call expect('keyword', head // good_element // 'faces base 1' // nl // '1' // nl, &
                    ':13: ''faces'': node_set or element_set expected')
        call expect('duplicate', head // good_element // 'node_set a 1' // nl // '1' // nl // &
                    'node_set a 1' // nl // '2' // nl, ':15: a second node set named ''a''')
        call expect('inverted', head // 'elements hex8 1' // nl // '1 5 6 7 8 1 2 3 4' // nl, &
                    ':12: element 1 is inverted')
        call expect('type', head // 'elements tet4 1' // nl, ':11: element type ''tet4''')

    contains

        subroutine read_text(name, text)
            character(len=*), intent(in) :: name, text
            integer :: unit
            call execute_command_line('mkdir -p ' // scratch)
            open (newunit=unit, file=scratch // '/' // name // '.mesh', status='replace', &
                  access='stream', form='unformatted')
            write (unit) text
            close (unit)
            call read_mesh(scratch // '/' // name // '.mesh', mesh, status)
            open (newunit=unit, file=scratch // '/' // name // '.mesh')
            close (unit, status='delete')
        end subroutine read_text

        subroutine expect(name, text, message)
            character(len=*), intent(in) :: name, text, message
            call read_text(name, text)
            call check(error, status%code == status_bad_input .and. &
                       index(status%text(), scratch // '/' // name // '.mesh' // message) > 0, &
                       'malformed ' // name // ': got: ' // status%text())
            call check(error, mesh%node_count() == 0, 'malformed ' // name // ': mesh not empty')
        end subroutine expect
    end subroutine test_malformed
end module test_fe_mesh
