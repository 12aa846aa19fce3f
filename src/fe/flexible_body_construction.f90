!> A flexible body built from its mesh: the free dofs numbered (fixed nodes
!> and components removed), the reference gradients, the element colouring,
!> the per-thread workspace, and the CSC patterns of the tangents and the mass
!> with the mass values and the gravity force (module flexmbs_fe_flexible_body).
submodule (flexmbs_fe_flexible_body) flexmbs_fe_flexible_body_construction
    implicit none

contains

    module procedure new_flexible_body
        integer :: e, n, i, j, nfree, nthreads
        character(len=120) :: msg
        body%mesh = mesh
        n = mesh%node_count()
        call new_hexahedron(body%hex, mesh%nnode_element, status)
        if (.not. status%ok()) return
        if (any(fixed_nodes < 1 .or. fixed_nodes > n)) then
            i = findloc(fixed_nodes < 1 .or. fixed_nodes > n, .true., dim=1)
            write (msg, '(a,i0,a,i0)') 'flexible body: fixed node ', fixed_nodes(i), &
                ' outside 1..', n
            call status%set(status_bad_input, trim(msg))
            return
        end if
        body%materials = materials
        allocate (body%element_material(mesh%element_count()), source=1)
        if (present(element_material)) then
            if (size(element_material) /= mesh%element_count()) then
                write (msg, '(a,i0,a,i0,a)') 'flexible body: ', size(element_material), &
                    ' element materials given for ', mesh%element_count(), ' elements'
                call status%set(status_bad_input, trim(msg))
                return
            end if
            body%element_material = element_material
        end if
        if (any(body%element_material < 1 .or. body%element_material > size(materials))) then
            write (msg, '(a,i0,a)') 'flexible body: element material numbers must lie in 1..', &
                size(materials), ' (materials given)'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        allocate (body%dndx(3, body%hex%nnode, body%hex%ngauss, mesh%element_count()), &
                  body%wdv(body%hex%ngauss, mesh%element_count()), stat=e)
        if (e /= 0) then
            call out_of_memory(status, 'shape function gradients', 4_i8 * body%hex%nnode * &
                               body%hex%ngauss * int(mesh%element_count(), i8), 8)
            return
        end if
        do e = 1, mesh%element_count()
            call reference_gradients(body%hex, mesh%x(:, mesh%connectivity(:, e)), &
                                     body%dndx(:, :, :, e), body%wdv(:, e), status)
            if (.not. status%ok()) then
                write (msg, '(a,i0,a)') 'flexible body: element ', e, ': '
                call status%set(status_bad_input, trim(msg) // ' ' // status%text())
                return
            end if
        end do
        allocate (body%dof(3, n), source=1)
        body%dof(:, fixed_nodes) = 0
        if (present(fixed_components)) then
            if (size(fixed_components, 1) /= 3 .or. size(fixed_components, 2) /= n) then
                write (msg, '(a,i0,a,i0,a,i0,a)') 'flexible body: fixed components given as (', &
                    size(fixed_components, 1), ', ', size(fixed_components, 2), &
                    '), expected (3, ', n, ')'
                call status%set(status_bad_input, trim(msg))
                return
            end if
            where (fixed_components) body%dof = 0
        end if
        nfree = 0
        do i = 1, n
            do j = 1, 3
                if (body%dof(j, i) == 0) cycle
                nfree = nfree + 1
                body%dof(j, i) = nfree
            end do
        end do
        body%nq = nfree
        body%nv = nfree
        body%nc = 0
        if (present(gravity)) body%gravity = gravity
        body%x = mesh%x
        allocate (body%v(3, n), source=0.0_wp)
        allocate (body%me(mesh%nnode_element, mesh%nnode_element), body%force_work(nfree))
        nthreads = 1
        !$ nthreads = omp_get_max_threads()
        call allocate_workspace(body, nthreads)
        call colour_elements(mesh%connectivity, mesh%node_count(), body%colour_start, &
                             body%colour_elements)
        call build_patterns(body, status)
    end procedure new_flexible_body

    module procedure element_dofs
        integer :: a
        do a = 1, body%hex%nnode
            dofs(3 * a - 2:3 * a) = body%dof(:, body%mesh%connectivity(a, e))
        end do
    end procedure element_dofs

    !> Tangent pattern (all free–free pairs of each element, column-major over
    !> the local dofs), mass pattern and values, and the gravity force.
    subroutine build_patterns(body, status)
        type(flexible_body_t), intent(inout) :: body
        type(status_t), intent(out) :: status
        integer, allocatable :: rows(:), cols(:), mrows(:), mcols(:)
        real(wp), allocatable :: mvals(:), m(:, :)
        integer :: dofs(3 * max_nodes), e, p, q, nd, nf, a, b, i
        integer(i8) :: nt, nm
        nd = 3 * body%hex%nnode
        allocate (m(body%hex%nnode, body%hex%nnode))
        allocate (body%triplet_start(body%mesh%element_count() + 1))
        nt = 0
        nm = 0
        do e = 1, body%mesh%element_count()
            call element_dofs(body, e, dofs(1:nd))
            nf = count(dofs(1:nd) > 0)
            body%triplet_start(e) = nt + 1
            nt = nt + nf * nf
            do a = 1, 3 ! mass couples equal directions only
                nm = nm + count(dofs(a:nd:3) > 0)**2
            end do
        end do
        body%triplet_start(body%mesh%element_count() + 1) = nt + 1
        ! the largest arrays of a body: one triplet per free-free pair
        allocate (rows(nt), cols(nt), mrows(nm), mcols(nm), mvals(nm), stat=e)
        if (e /= 0) then
            call out_of_memory(status, 'tangent and mass triplets', 2_i8 * nt + 3_i8 * nm, 8)
            return
        end if
        allocate (body%applied_force(body%nv), source=0.0_wp)
        nt = 0
        nm = 0
        do e = 1, body%mesh%element_count()
            call element_dofs(body, e, dofs(1:nd))
            call element_mass(body%hex, body%wdv(:, e), &
                              body%materials(body%element_material(e))%density, m)
            do q = 1, nd
                if (dofs(q) == 0) cycle
                b = (q - 1) / 3 + 1
                do p = 1, nd
                    if (dofs(p) == 0) cycle
                    nt = nt + 1
                    rows(nt) = dofs(p)
                    cols(nt) = dofs(q)
                    a = (p - 1) / 3 + 1
                    if (mod(p - q, 3) == 0) then
                        nm = nm + 1
                        mrows(nm) = dofs(p)
                        mcols(nm) = dofs(q)
                        mvals(nm) = m(a, b)
                    end if
                end do
            end do
            ! ∫ ρ N_a g dV = Σ_b m_ab g, fixed nodes b included.
            do p = 1, nd
                if (dofs(p) == 0) cycle
                a = (p - 1) / 3 + 1
                i = p - 3 * (a - 1)
                body%applied_force(dofs(p)) = body%applied_force(dofs(p)) &
                    + sum(m(a, :)) * body%gravity(i)
            end do
        end do
        call body%stiffness%build(body%nv, body%nv, rows, cols, status)
        if (.not. status%ok()) return
        body%damping = body%stiffness
        call body%mass_matrix%build(body%nv, body%nv, mrows, mcols, status)
        if (.not. status%ok()) return
        call body%mass_matrix%fill(mvals)
    end subroutine build_patterns

    module procedure allocate_workspace
        integer :: nn, i
        nn = body%hex%nnode
        if (allocated(body%work)) deallocate (body%work)
        allocate (body%work(n))
        do i = 1, n
            allocate (body%work(i)%xe(3, nn), body%work(i)%ve(3, nn), body%work(i)%k_el(3, nn), &
                      body%work(i)%k_v(3, nn), body%work(i)%ke(3 * nn, 3 * nn), &
                      body%work(i)%ce(3 * nn, 3 * nn))
        end do
    end procedure allocate_workspace
end submodule flexmbs_fe_flexible_body_construction
