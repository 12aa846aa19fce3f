!> The flexible body of a validated scene (`&flexible_body`, `&material`):
!> its mesh (a box or a mesh file), materials by element set, supports,
!> loads, gravity and the rigid initial velocity field.
!>
!> Materials partition the elements: each `&material` names an element
!> set, at most one leaves `elements` out and takes every element the others
!> do not name. An element in two named sets, or in none when no material
!> takes the rest, is bad input. The load is the total force on `load_set`,
!> shared equally by the set's nodes that are not fixed. The initial
!> velocity is rigid: v = v₀ + ω × (X − X̄), X̄ the mean of the nodes.
!> Every error names the file, the group, the variable and the reason.
module flexmbs_run_body_builder
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_mesh_file, only: read_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_scene_input, only: material_of
    implicit none
    private

    public :: build_flexible_body, body_energies

contains

    !> Flexible body `ib` of the scene (its `ib`-th &flexible_body group), its
    !> initial free positions q0 (the reference configuration) and velocities v0.
    subroutine build_flexible_body(scene, ib, body, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: ib
        type(flexible_body_t), intent(out) :: body
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t), allocatable :: materials(:)
        integer, allocatable :: element_material(:), fixed(:), set(:)
        character(len=:), allocatable :: where
        real(wp) :: centroid(3), w(3)
        integer :: k, i, nfree, nnode_element, stat, dofs(3)

        where = scene%path // ': &flexible_body: '
        if (size(scene%bodies) > 1) where = scene%path // ': &flexible_body ''' // &
            trim(scene%bodies(ib)%name) // ''': '
        associate (b => scene%bodies(ib))
            nnode_element = merge(hex8, hex27, b%element == 'hex8')
            if (len_trim(b%mesh_file) > 0) then
                call read_mesh(trim(b%mesh_file), mesh, status)
                if (.not. status%ok()) then
                    ! the path as resolved against the scene's folder, and where
                    call status%set(status_bad_input, where // 'mesh_file = ''' // &
                        trim(b%mesh_file) // ''': ' // status%text() // ' (line ' // &
                        int_text(b%line) // ')')
                    return
                end if
                if (mesh%nodes_per_element() /= nnode_element) then
                    call status%set(status_bad_input, where // 'element = ''' // &
                        trim(b%element) // ''': the mesh file ''' // trim(b%mesh_file) // &
                        ''' has ' // int_text(mesh%nodes_per_element()) // '-node elements')
                    return
                end if
            else
                call box_mesh(mesh, nnode_element, b%divisions, b%lengths, status, b%origin)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // status%text())
                    return
                end if
            end if

            call assign_materials(scene, ib, mesh, materials, element_material, status)
            if (.not. status%ok()) return

            allocate (fixed(0))
            do k = 1, size(b%fixed)
                if (len_trim(b%fixed(k)) == 0) cycle
                call mesh%node_set(trim(b%fixed(k)), set, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'fixed = ''' // trim(b%fixed(k)) &
                        // ''': ' // status%text())
                    return
                end if
                fixed = [fixed, set]
            end do

            call new_flexible_body(body, mesh, materials, fixed, status, gravity=b%gravity, &
                                   element_material=element_material)
            if (.not. status%ok()) then
                call status%set(status_bad_input, where // status%text())
                return
            end if

            if (len_trim(b%load_set) > 0) then
                call mesh%node_set(trim(b%load_set), set, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'load_set = ''' // &
                        trim(b%load_set) // ''': ' // status%text())
                    return
                end if
                nfree = count([(any(body%node_dofs(set(i)) > 0), i = 1, size(set))])
                if (nfree == 0) then
                    call status%set(status_bad_input, where // 'load_set = ''' // &
                        trim(b%load_set) // ''': every node of the set is fixed')
                    return
                end if
                do i = 1, size(set)
                    if (.not. any(body%node_dofs(set(i)) > 0)) cycle
                    call body%add_nodal_load(set(i), b%load / real(nfree, wp), status)
                    if (.not. status%ok()) then
                        call status%set(status_bad_input, where // 'load: ' // status%text())
                        return
                    end if
                end do
            end if

            q0 = body%free_positions()
            allocate (v0(body%nv), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, where // 'initial velocities', int(body%nv, i8), 8)
                return
            end if
            centroid = mesh%centroid()
            do i = 1, mesh%node_count()
                w = b%initial_velocity + cross(b%initial_angular_velocity, &
                                               mesh%reference_position(i) - centroid)
                dofs = body%node_dofs(i)
                do k = 1, 3
                    if (dofs(k) > 0) v0(dofs(k)) = w(k)
                end do
            end do
        end associate
    end subroutine build_flexible_body

    !> The materials of body `ib` and the material of each of its elements
    !> (see the module header); materials(k) is the k-th &material of the body.
    subroutine assign_materials(scene, ib, mesh, materials, element_material, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: ib
        type(mesh_t), intent(in) :: mesh
        type(neo_hooke_t), allocatable, intent(out) :: materials(:)
        integer, allocatable, intent(out) :: element_material(:)
        type(status_t), intent(inout) :: status
        integer, allocatable :: set(:), own(:)
        integer :: i, j, e, rest, stat, k
        character(len=:), allocatable :: where, where_body

        own = pack([(i, i=1, size(scene%materials))], &
                   [(material_of(scene, i, ib), i=1, size(scene%materials))])
        allocate (materials(size(own)))
        allocate (element_material(mesh%element_count()), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, scene%path // ': material of each element', &
                int(mesh%element_count(), i8), 4)
            return
        end if
        element_material = 0
        rest = 0
        do k = 1, size(own)
            i = own(k)
            associate (m => scene%materials(i))
                where = scene%path // ': &material ''' // trim(m%name) // ''': '
                call new_neo_hooke(materials(k), m%youngs_modulus, m%poisson_ratio, &
                                   m%density, m%viscosity, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // status%text() // at(m%line))
                    return
                end if
                if (len_trim(m%elements) == 0) then
                    rest = k
                    cycle
                end if
                call mesh%element_set(trim(m%elements), set, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'elements = ''' // &
                        trim(m%elements) // ''': ' // status%text() // at(m%line))
                    return
                end if
                do j = 1, size(set)
                    e = set(j)
                    if (element_material(e) /= 0) then
                        call status%set(status_bad_input, where // 'elements = ''' // &
                            trim(m%elements) // ''': element ' // int_text(e) // &
                            ' is also in ''' // &
                            trim(scene%materials(own(element_material(e)))%elements) // &
                            ''' of &material ''' // &
                            trim(scene%materials(own(element_material(e)))%name) // &
                            ''' (each element takes one material)' // at(m%line))
                        return
                    end if
                    element_material(e) = k
                end do
            end associate
        end do
        if (rest > 0) where (element_material == 0) element_material = rest
        if (any(element_material == 0)) then
            where_body = scene%path // ': '
            if (size(scene%bodies) > 1) where_body = where_body // '&flexible_body ''' // &
                trim(scene%bodies(ib)%name) // ''': '
            e = findloc(element_material, 0, dim=1)
            call status%set(status_bad_input, where_body // '&material: elements: element ' &
                // int_text(e) // ' has no material (name a set containing it, or leave &
                &elements out of one &material to cover the rest)')
        end if
    end subroutine assign_materials

    !> Strain, kinetic and total energy at (q, v); the total adds the
    !> potential −f·(q − q_ref) of the constant applied forces (gravity,
    !> loads), so that it is conserved without damping and decreases with it.
    subroutine body_energies(body, q, v, q_ref, energies, status)
        type(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: q(:), v(:), q_ref(:)
        real(wp), intent(out) :: energies(3) !! strain, kinetic, total [J]
        type(status_t), intent(inout) :: status
        energies(1) = body%strain_energy(q, status)
        energies(2) = body%kinetic_energy(v)
        energies(3) = energies(1) + energies(2) - body%applied_work(q, q_ref)
    end subroutine body_energies

    pure function at(line) result(text)
        integer, intent(in) :: line
        character(len=:), allocatable :: text
        text = ' (line ' // int_text(line) // ')'
    end function at
end module flexmbs_run_body_builder
