!> A modal body of a validated scene (`&flexible_body model = 'modal'`):
!> the FE body of its mesh and materials (run/body_builder), its interface
!> node sets, the Craig–Bampton basis (computed, or read from
!> `modes_cache` when the fingerprint of mesh, materials, interfaces and k
!> matches, and then written there), the inertia invariants and the
!> floating-frame body, with its initial state: the frame at the mesh's
!> centre of mass with the mesh's axes, η = 0, the body's rigid initial
!> velocity field as ṙ and ω′.
module flexmbs_run_modal_builder
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_fe_mesh, only: node_set_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_fe_modal_basis, only: modal_basis_t, craig_bampton, basis_fingerprint
    use flexmbs_fe_modal_invariants, only: modal_invariants
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_mbs_modal_body, only: modal_body_t, new_modal_body
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_modal_cache, only: read_modal_cache, write_modal_cache
    use flexmbs_io_scene_schema, only: len_name
    use flexmbs_run_body_builder, only: build_flexible_body
    implicit none
    private

    public :: build_modal_body, modal_interfaces, interface_number

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
        real(wp), allocatable :: qf(:), vf(:)
        character(len=:), allocatable :: where, print, set_name
        real(wp) :: centroid(3), centre(3)
        integer, allocatable :: nodes(:)
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
                call fe%node_set(trim(names(j)), nodes, status)
                if (.not. status%ok()) then
                    call status%set(status_bad_input, where // 'interfaces: ''' // &
                        trim(names(j)) // ''': ' // status%text())
                    return
                end if
                ! through a named variable: gfortran 12 leaks a trimmed temporary
                ! given to the allocatable name of a structure constructor
                set_name = trim(names(j))
                sets(j) = node_set_t(set_name, nodes)
            end do
            print = basis_fingerprint(fe, sets, b%modes)
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
            call new_modal_body(body, basis, modal_invariants(fe, basis), status, &
                                gravity=b%gravity, fe=fe)
            if (.not. status%ok()) then
                call status%set(status_bad_input, where // status%text())
                return
            end if
            ! the rigid initial field v₀ + ω × (X − X̄) of a nonlinear body
            centroid = fe%centroid()
            centre = body%reference_centre()
            allocate (q0(body%nq), v0(body%nv), source=0.0_wp)
            q0(1:3) = centre
            q0(4) = 1.0_wp
            v0(1:3) = b%initial_velocity + cross(b%initial_angular_velocity, centre - centroid)
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
end module flexmbs_run_modal_builder
