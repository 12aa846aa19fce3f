!> A modal body of a validated scene (`&flexible_body model = 'modal'`):
!> the FE body of its mesh and materials (run/body_builder), its interface
!> node sets, the Craig–Bampton basis (computed, or read from
!> `modes_cache` when the fingerprint of mesh, materials, interfaces and k
!> matches, and then written there), the inertia invariants and the
!> floating-frame body, with its initial state: the frame at the mesh's
!> centre of mass with the mesh's axes, η = 0, the body's rigid initial
!> velocity field as ṙ and ω′.
module flexmbs_run_modal_builder
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_fe_mesh, only: node_set_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_fe_modal_basis, only: modal_basis_t, craig_bampton
    use flexmbs_fe_modal_invariants, only: modal_invariants_t, modal_invariants
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_mbs_modal_body, only: modal_body_t, new_modal_body
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_modal_cache, only: read_modal_cache, write_modal_cache
    use flexmbs_io_scene_schema, only: len_name
    use flexmbs_run_body_builder, only: build_flexible_body
    implicit none
    private

    public :: build_modal_body, modal_interfaces, interface_number

    !> The version of the basis the fingerprint covers: a change of the
    !> algorithm that changes the shapes changes it, so old caches are redone.
    character(len=*), parameter :: basis_version = 'craig-bampton 1'

contains

    !> Modal body `ib` of the scene with the interfaces `names` (the scene's
    !> `interfaces`, or the node sets its markers use), its q0 = (r, p, η)
    !> and v0 = (ṙ, ω′, η̇).
    subroutine build_modal_body(scene, ib, names, body, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: ib
        character(len=*), intent(in) :: names(:)
        type(modal_body_t), intent(out) :: body
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        type(flexible_body_t) :: fe
        type(node_set_t), allocatable :: sets(:)
        type(modal_basis_t) :: basis
        type(modal_invariants_t) :: inv
        real(wp), allocatable :: qf(:), vf(:)
        character(len=:), allocatable :: where, print
        real(wp) :: centroid(3)
        integer :: j
        logical :: found

        where = scene%path // ': &flexible_body ''' // trim(scene%bodies(ib)%name) // ''': '
        call build_flexible_body(scene, ib, fe, qf, vf, status)
        if (.not. status%ok()) return
        associate (b => scene%bodies(ib))
            if (size(names) == 0) then
                call status%set(status_bad_input, where // 'model = ''modal'': no interface: &
                    &name node sets in interfaces, or put markers on its node sets (line ' // &
                    int_text(b%line) // ')')
                return
            end if
            allocate (sets(size(names)))
            do j = 1, size(names)
                sets(j)%name = trim(names(j))
                call fe%mesh%node_set(trim(names(j)), sets(j)%nodes, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'interfaces: ''' // &
                        trim(names(j)) // ''': ' // status%text())
                    return
                end if
            end do
            print = fingerprint(fe, sets, b%modes)
            found = .false.
            if (len_trim(b%modes_cache) > 0) then
                call read_modal_cache(trim(b%modes_cache), print, basis, found, status)
                if (.not. status%ok()) then
                    call status%set(status%code, where // status%text())
                    return
                end if
            end if
            if (.not. found) then
                call craig_bampton(fe, sets, b%modes, basis, status, method=trim(b%modes_method))
                if (.not. status%ok()) then
                    call status%set(status%code, where // status%text() // ' (line ' // &
                        int_text(b%line) // ')')
                    return
                end if
                if (len_trim(b%modes_cache) > 0) then
                    call write_modal_cache(trim(b%modes_cache), print, basis, status)
                    if (.not. status%ok()) return
                end if
            end if
            inv = modal_invariants(fe%mass_matrix, fe%mesh%x, basis%shapes)
            call new_modal_body(body, basis, inv, status, gravity=b%gravity, fe=fe)
            if (.not. status%ok()) then
                call status%set(status_bad_input, where // status%text())
                return
            end if
            ! the rigid initial field v₀ + ω × (X − X̄) of a nonlinear body
            centroid = sum(fe%mesh%x, dim=2) / fe%mesh%node_count()
            allocate (q0(body%nq), v0(body%nv), source=0.0_wp)
            q0(1:3) = inv%centre
            q0(4) = 1.0_wp
            v0(1:3) = b%initial_velocity + cross(b%initial_angular_velocity, inv%centre - centroid)
            v0(4:6) = b%initial_angular_velocity
        end associate
    end subroutine build_modal_body

    !> The interface node sets of modal body ib: its `interfaces`, or else
    !> the node sets of the markers on it, in marker order, each once.
    pure function modal_interfaces(scene, ib) result(names)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: ib
        character(len=len_name), allocatable :: names(:)
        integer :: k
        associate (b => scene%bodies(ib))
            names = pack(b%interfaces, len_trim(b%interfaces) > 0)
            if (size(names) > 0) return
            do k = 1, size(scene%markers)
                associate (m => scene%markers(k))
                    if (m%body /= b%name .or. len_trim(m%node_set) == 0) cycle
                    if (any(names == m%node_set)) cycle
                    names = [character(len=len(names)) :: names, m%node_set]
                end associate
            end do
        end associate
    end function modal_interfaces

    !> The number of node set `set` among modal body ib's interfaces (0: not one).
    pure integer function interface_number(scene, ib, set) result(j)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: ib
        character(len=*), intent(in) :: set
        character(len=len_name), allocatable :: names(:)
        names = modal_interfaces(scene, ib)
        do j = 1, size(names)
            if (names(j) == set) return
        end do
        j = 0
    end function interface_number

    !> The SHA-256 of what the basis depends on: the basis version, k, the
    !> element type, every node's position and element's nodes (bit for
    !> bit), every element's material constants, the interfaces' names and
    !> nodes. The text is filled in place (long meshes: no repeated
    !> concatenation).
    function fingerprint(fe, sets, modes) result(digest)
        type(flexible_body_t), intent(in) :: fe
        type(node_set_t), intent(in) :: sets(:)
        integer, intent(in) :: modes
        character(len=:), allocatable :: digest
        character(len=:), allocatable :: text
        integer :: i, j, n, at
        n = 64 + 17 * (size(fe%mesh%x) + 4 * size(fe%materials)) + &
            12 * (size(fe%mesh%connectivity) + size(fe%element_material))
        do j = 1, size(sets)
            n = n + len(sets(j)%name) + 12 * size(sets(j)%nodes) + 2
        end do
        allocate (character(len=n) :: text)
        at = 0
        call put(basis_version // ' k=' // int_text(modes) // ' nnode=' // &
                 int_text(fe%mesh%nnode_element) // ';')
        do j = 1, size(fe%mesh%x, 2)
            do i = 1, 3
                call put(hex(fe%mesh%x(i, j)))
            end do
        end do
        call put(';')
        do j = 1, size(fe%mesh%connectivity, 2)
            do i = 1, size(fe%mesh%connectivity, 1)
                call put(int_text(fe%mesh%connectivity(i, j)) // ',')
            end do
        end do
        call put(';')
        do j = 1, size(fe%element_material)
            call put(int_text(fe%element_material(j)) // ',')
        end do
        do j = 1, size(fe%materials)
            associate (m => fe%materials(j))
                call put(';' // hex(m%mu) // hex(m%lambda) // hex(m%beta) // hex(m%density))
            end associate
        end do
        do j = 1, size(sets)
            call put(';' // sets(j)%name // ':')
            do i = 1, size(sets(j)%nodes)
                call put(int_text(sets(j)%nodes(i)) // ',')
            end do
        end do
        digest = sha256_hex(text(1:at))
    contains
        subroutine put(part)
            character(len=*), intent(in) :: part
            text(at + 1:at + len(part)) = part
            at = at + len(part)
        end subroutine put
        function hex(x) result(w)
            real(wp), intent(in) :: x
            character(len=17) :: w
            write (w, '(z16.16,a)') transfer(x, 1_i8), ','
        end function hex
    end function fingerprint
end module flexmbs_run_modal_builder
