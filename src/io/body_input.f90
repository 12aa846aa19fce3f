!> A flexible body from the `&flexible_body` and `&material` groups of a
!> validated scene: the mesh (box or file), the materials by element set,
!> supports, loads, gravity and the rigid initial velocity field.
!>
!> Materials: each element takes the last `&material` whose element set
!> contains it (so 'all' first, then the tip layers); every element must be
!> covered. The load is the total force on `load_set`, shared equally by
!> its free nodes. The initial velocity is rigid: v = velocity +
!> angular_velocity × (X − X̄), X̄ the centroid of the nodes.
!> Errors name the file, the group, the variable and the reason.
module flexmbs_io_body_input
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_mesh_file, only: read_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_mbs_rotation, only: cross
    implicit none
    private

    public :: build_flexible_body

contains

    !> The body of the scene and its initial free positions q0 and velocities v0.
    subroutine build_flexible_body(scene, body, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        type(flexible_body_t), intent(out) :: body
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t), allocatable :: materials(:)
        integer, allocatable :: element_material(:), set(:), fixed(:), loaded(:)
        real(wp) :: centroid(3), w(3)
        integer :: k, i, j, nfree
        character(len=:), allocatable :: where

        where = scene%path // ': &flexible_body: '
        associate (b => scene%body)
            if (len_trim(b%mesh_file) > 0) then
                call read_mesh(trim(b%mesh_file), mesh, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'mesh_file = ''' // &
                                    trim(b%mesh_file) // ''': ' // status%text())
                    return
                end if
                if (mesh%nnode_element /= merge(hex8, hex27, b%element == 'hex8')) then
                    call status%set(status_bad_input, where // 'element = ''' // &
                        trim(b%element) // ''': the mesh file has ' // &
                        int_text(mesh%nnode_element) // '-node elements')
                    return
                end if
            else
                call box_mesh(mesh, merge(hex8, hex27, b%element == 'hex8'), b%divisions, &
                              b%lengths, status, b%origin)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // status%text())
                    return
                end if
            end if

            allocate (materials(size(scene%materials)))
            allocate (element_material(mesh%element_count()), source=0)
            do k = 1, size(scene%materials)
                associate (m => scene%materials(k))
                    call new_neo_hooke(materials(k), m%young, m%poisson, m%density, &
                                       m%viscosity, status)
                    if (status%ok()) call mesh%element_set(trim(m%elements), set, status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, scene%path // ': &material #' // &
                            int_text(k) // ' (''' // trim(m%name) // '''): elements = ''' // &
                            trim(m%elements) // ''': ' // status%text() // known_sets(mesh, &
                            .false.))
                        return
                    end if
                    element_material(set) = k
                end associate
            end do
            if (any(element_material == 0)) then
                call status%set(status_bad_input, scene%path // ': &material: element ' // &
                    int_text(findloc(element_material, 0, dim=1)) // ' has no material ' // &
                    '(give a &material with elements = ''all'' or one covering it)')
                return
            end if

            allocate (fixed(0))
            if (len_trim(b%fixed) > 0) then
                call mesh%node_set(trim(b%fixed), fixed, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'fixed = ''' // trim(b%fixed) &
                                    // ''': ' // status%text() // known_sets(mesh, .true.))
                    return
                end if
            end if
            call new_flexible_body(body, mesh, materials, fixed, status, b%gravity, &
                                   element_material)
            if (.not. status%ok()) then
                call status%set(status_bad_input, where // status%text())
                return
            end if

            if (len_trim(b%load_set) > 0) then
                call mesh%node_set(trim(b%load_set), loaded, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'load_set = ''' // &
                        trim(b%load_set) // ''': ' // status%text() // known_sets(mesh, .true.))
                    return
                end if
                nfree = count([(any(body%dof(:, loaded(i)) > 0), i = 1, size(loaded))])
                if (nfree == 0) then
                    call status%set(status_bad_input, where // 'load_set = ''' // &
                        trim(b%load_set) // ''': all its nodes are fixed')
                    return
                end if
                do i = 1, size(loaded)
                    if (all(body%dof(:, loaded(i)) == 0)) cycle
                    call body%add_nodal_load(loaded(i), b%load / nfree, status)
                    if (.not. status%ok()) return
                end do
            end if

            q0 = body%free_positions()
            allocate (v0(body%nv), source=0.0_wp)
            centroid = sum(mesh%x, dim=2) / mesh%node_count()
            do i = 1, mesh%node_count()
                w = b%velocity + cross(b%angular_velocity, mesh%x(:, i) - centroid)
                do j = 1, 3
                    if (body%dof(j, i) > 0) v0(body%dof(j, i)) = w(j)
                end do
            end do
        end associate
    end subroutine build_flexible_body

    !> ' (sets: a, b, …)' listing the mesh's node or element sets.
    function known_sets(mesh, nodes) result(list)
        type(mesh_t), intent(in) :: mesh
        logical, intent(in) :: nodes
        character(len=:), allocatable :: list
        integer :: i
        list = ''
        if (nodes .and. allocated(mesh%node_sets)) then
            do i = 1, size(mesh%node_sets)
                list = list // merge(', ', '  ', i > 1) // mesh%node_sets(i)%name
            end do
        else if (.not. nodes .and. allocated(mesh%element_sets)) then
            do i = 1, size(mesh%element_sets)
                list = list // merge(', ', '  ', i > 1) // mesh%element_sets(i)%name
            end do
        end if
        if (len(list) > 0) list = ' (sets: ' // list(3:) // ')'
    end function known_sets
end module flexmbs_io_body_input
