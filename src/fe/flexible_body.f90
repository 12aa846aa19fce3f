!> A flexible body on its own: a hexahedral mesh of neo-Hookean material in
!> absolute nodal coordinates, with fixed nodes removed, as a mechanical
!> problem (q' = v, M v' = g − k(q, v), no constraints).
!>
!> q holds the positions of the free nodal dofs (node by node, x y z), v their
!> velocities; fixed nodes stay at their reference positions. M (constant,
!> consistent), the tangent stiffness ∂k/∂q and the damping ∂k/∂v live in
!> CSC patterns fixed at construction; each assembly refills their values in
!> place through the triplet-to-slot map, element by element in a fixed order.
!> Submodules: flexible_body_construction (the constructor: dofs, gradients,
!> colouring, workspace, patterns, mass and gravity) and flexible_body_views
!> (what the body says of its mesh).
module flexmbs_fe_flexible_body
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    !$ use omp_lib, only: omp_get_max_threads, omp_get_thread_num
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t, mechanical_patterns_t
    use flexmbs_fe_tensor, only: identity3
    use flexmbs_fe_hexahedron, only: hexahedron_t, new_hexahedron, reference_gradients, &
        deformation_gradient, nodal_gradient, max_nodes
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    use flexmbs_fe_element, only: element_mass, element_forces
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_element_colouring, only: colour_elements
    implicit none
    private

    !> One thread's element workspace: gathers and element results, each
    !> its own allocation (no cache lines shared between threads).
    type :: element_work_t
        real(wp), allocatable :: xe(:, :), ve(:, :), k_el(:, :), k_v(:, :), ke(:, :), ce(:, :)
        type(status_t) :: status
    end type element_work_t

    !> A meshed neo-Hookean body as a mechanical problem (the module's form):
    !> its materials, quadrature data, free-dof numbering, the constant M and the
    !> CSC patterns of ∂k/∂q and ∂k/∂v, and the workspaces of the assembly.
    type, extends(mechanical_problem_t), public :: flexible_body_t
        type(mesh_t) :: mesh
        type(hexahedron_t) :: hex
        type(neo_hooke_t), allocatable :: materials(:)   !! one per element set
        integer, allocatable :: element_material(:)      !! material of each element
        real(wp), allocatable :: dndx(:, :, :, :)        !! (3, nnode, ngauss, elements)
        real(wp), allocatable :: wdv(:, :)               !! (ngauss, elements)
        integer, allocatable :: dof(:, :)                !! (3, nodes): free dof or 0
        real(wp) :: gravity(3) = 0.0_wp                  !! acceleration of gravity
        real(wp), allocatable :: applied_force(:)        !! gravity ∫ ρ N_a dV g + nodal loads, free dofs
        type(csc_matrix_t) :: mass_matrix                !! M on free dofs
        type(csc_matrix_t) :: stiffness                  !! ∂k/∂q, refilled by tangents
        type(csc_matrix_t) :: damping                    !! ∂k/∂v, same pattern
        integer(i8), allocatable :: triplet_start(:)     !! first tangent triplet of element e
        ! Workspace, allocated once: nodal positions and velocities, element
        ! gathers and element results (exact sizes, so no copies on calls).
        real(wp), allocatable :: x(:, :), v(:, :), me(:, :)
        real(wp), allocatable :: force_work(:)            !! k for force_derivatives
        type(element_work_t), allocatable :: work(:)     !! one per thread
        !> Elements colour by colour: colour c is colour_elements(colour_start(c)
        !> : colour_start(c+1)-1), no two of them sharing a node.
        integer, allocatable :: colour_start(:), colour_elements(:)
    contains
        procedure :: kinematics => body_kinematics
        procedure :: mass => body_mass
        procedure :: forces => body_forces
        procedure :: constraint => body_constraint
        procedure :: constraint_jacobian => body_constraint_jacobian
        procedure :: constraint_curvature => body_constraint_curvature
        procedure :: internal_forces => body_internal_forces
        procedure :: tangents => body_tangents
        procedure :: assemble_tangents => body_assemble_tangents
        procedure :: free_positions => body_free_positions
        procedure :: strain_energy => body_strain_energy
        procedure :: kinetic_energy => body_kinetic_energy
        procedure :: total_energy => body_total_energy
        procedure :: momenta => body_momenta
        procedure :: add_nodal_load => body_add_nodal_load
        procedure :: admissible => body_admissible
        procedure :: element_stress => body_element_stress
        procedure :: force_derivatives => body_force_derivatives
        procedure :: kinematics_derivative => body_kinematics_derivative
        procedure :: mass_derivative => body_mass_derivative
        procedure :: has_sparse => body_has_sparse
        procedure :: has_sparse_derivatives => body_has_sparse
        procedure :: mass_pattern => body_mass_pattern
        procedure :: mass_sparse => body_mass_sparse
        procedure :: constraint_jacobian_pattern => body_constraint_jacobian_pattern
        procedure :: constraint_jacobian_sparse => body_no_values
        procedure :: constraint_position_jacobian_sparse => body_no_values
        procedure :: constraint_time_derivative_jacobian_sparse => body_no_values
        procedure :: derivative_patterns => body_derivative_patterns
        procedure :: kinematics_sparse => body_kinematics_sparse
        procedure :: kinematics_derivative_sparse => body_no_values_w
        procedure :: mass_derivative_sparse => body_no_values_w
        procedure :: force_derivatives_sparse => body_force_derivatives_sparse
        procedure :: constraint_jacobian_derivatives_sparse => body_no_second_derivatives
        procedure :: constraint_curvature_derivatives_sparse => body_no_curvature_derivatives
        procedure :: reference_mesh => body_reference_mesh
        procedure :: node_set => body_node_set
        procedure :: centroid => body_centroid
        procedure :: node_dofs => body_node_dofs
        procedure :: node_count => body_node_count
        procedure :: element_count => body_element_count
        procedure :: nodes_per_element => body_nodes_per_element
        procedure :: element_nodes => body_element_nodes
        procedure :: reference_nodes => body_reference_nodes
        procedure :: reference_node => body_reference_node
        procedure :: applied_work => body_applied_work
        procedure :: nodal_values => body_nodal_values
        procedure :: displacements_of => body_displacements_of
    end type flexible_body_t

    interface
        !> Body from a mesh, its materials, and fixed nodes. With one material it
        !> applies to all elements; with several, element_material(e) picks the
        !> material of element e (the paper's stiffer tip layers).
        module subroutine new_flexible_body(body, mesh, materials, fixed_nodes, status, gravity, &
                                     element_material, fixed_components)
            type(flexible_body_t), intent(out) :: body
            type(mesh_t), intent(in) :: mesh
            type(neo_hooke_t), intent(in) :: materials(:)
            integer, intent(in) :: fixed_nodes(:)     !! node numbers held at X
            type(status_t), intent(out) :: status
            real(wp), intent(in), optional :: gravity(3)
            integer, intent(in), optional :: element_material(:) !! one per element
            !> Further supports by component (3, nodes): .true. holds that
            !> coordinate at X (symmetry planes, rollers).
            logical, intent(in), optional :: fixed_components(:, :)
        end subroutine new_flexible_body
        !> Free global dofs of element e in local order (0 for fixed ones).
        pure module subroutine element_dofs(body, e, dofs)
            type(flexible_body_t), intent(in) :: body
            integer, intent(in) :: e
            integer, intent(out) :: dofs(3 * body%hex%nnode)
        end subroutine element_dofs
        !> Element workspaces for n threads (gathers and element results).
        module subroutine allocate_workspace(body, n)
            class(flexible_body_t), intent(inout) :: body
            integer, intent(in) :: n
        end subroutine allocate_workspace
    end interface

    interface
        !> The body's mesh (reference configuration, sets), a copy.
        module function body_reference_mesh(self) result(mesh)
            class(flexible_body_t), intent(in) :: self
            type(mesh_t) :: mesh
        end function body_reference_mesh
        !> The nodes of the mesh's node set `name` (flexmbs_fe_mesh's node_set).
        module subroutine body_node_set(self, name, nodes, status)
            class(flexible_body_t), intent(in) :: self
            character(len=*), intent(in) :: name
            integer, allocatable, intent(out) :: nodes(:)
            type(status_t), intent(out) :: status
        end subroutine body_node_set
        !> The mean of the mesh's reference positions, or of those of `nodes`.
        pure module function body_centroid(self, nodes) result(c)
            class(flexible_body_t), intent(in) :: self
            integer, intent(in), optional :: nodes(:)
            real(wp) :: c(3)
        end function body_centroid
        !> The free dofs (numbers in q and v) of node `node`'s x, y, z; 0 where held.
        pure module function body_node_dofs(self, node) result(dofs)
            class(flexible_body_t), intent(in) :: self
            integer, intent(in) :: node
            integer :: dofs(3)
        end function body_node_dofs
        !> The number of nodes (of the mesh, held ones counted).
        pure integer module function body_node_count(self) result(n)
            class(flexible_body_t), intent(in) :: self
        end function body_node_count
        !> The number of elements of the mesh.
        pure integer module function body_element_count(self) result(n)
            class(flexible_body_t), intent(in) :: self
        end function body_element_count
        !> The number of nodes of an element (8 or 27).
        pure integer module function body_nodes_per_element(self) result(n)
            class(flexible_body_t), intent(in) :: self
        end function body_nodes_per_element
        !> The nodes of element k, in the mesh's order.
        pure module function body_element_nodes(self, k) result(nodes)
            class(flexible_body_t), intent(in) :: self
            integer, intent(in) :: k
            integer :: nodes(self%mesh%nodes_per_element())
        end function body_element_nodes
        !> Every node's reference position X into x (3, nodes): no allocation.
        pure module subroutine body_reference_nodes(self, x)
            class(flexible_body_t), intent(in) :: self
            real(wp), intent(out) :: x(:, :)
        end subroutine body_reference_nodes
        !> Node `node`'s reference position X.
        pure module function body_reference_node(self, node) result(x)
            class(flexible_body_t), intent(in) :: self
            integer, intent(in) :: node
            real(wp) :: x(3)
        end function body_reference_node
        !> Every node's displacement w − X (`displacement`) or velocity w (node
        !> by node x y z) from the free positions or velocities `w`; 0 for a
        !> held coordinate.
        pure module subroutine body_nodal_values(self, w, displacement, values)
            class(flexible_body_t), intent(in) :: self
            real(wp), intent(in) :: w(:)
            logical, intent(in) :: displacement
            real(wp), intent(out) :: values(:)  !! (3 nodes)
        end subroutine body_nodal_values
        !> The displacement x − X of nodal positions `x` (every node, node by
        !> node x y z) from the reference.
        pure module subroutine body_displacements_of(self, x, values)
            class(flexible_body_t), intent(in) :: self
            real(wp), intent(in) :: x(:)        !! (3 nodes)
            real(wp), intent(out) :: values(:)  !! (3 nodes)
        end subroutine body_displacements_of
    end interface

    public :: new_flexible_body

contains

    !> Scatter free positions q and velocities w into the nodal arrays.
    pure subroutine scatter(body, q, w)
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: q(:)
        real(wp), intent(in), optional :: w(:) !! absent: velocities zero
        integer :: i, j
        do i = 1, size(body%dof, 2)
            do j = 1, 3
                if (body%dof(j, i) == 0) cycle
                body%x(j, i) = q(body%dof(j, i))
                body%v(j, i) = 0.0_wp
                if (present(w)) body%v(j, i) = w(body%dof(j, i))
            end do
        end do
    end subroutine scatter

    !> The free positions of the reference configuration (the natural q0).
    !> An allocatable result: for `q = body%free_positions()` into an
    !> unallocated q, gfortran's bounds check of an explicit-shape result
    !> reads the undefined bounds of q (valgrind: uninitialised value).
    pure function body_free_positions(self) result(q)
        class(flexible_body_t), intent(in) :: self
        real(wp), allocatable :: q(:)
        integer :: i, j
        allocate (q(self%nq))
        do i = 1, size(self%dof, 2)
            do j = 1, 3
                if (self%dof(j, i) > 0) q(self%dof(j, i)) = self%mesh%x(j, i)
            end do
        end do
    end function body_free_positions

    !> Internal force k(q, v) = k_el + k_v on the free dofs; with `tangents`
    !> also the values of ∂k/∂q and ∂k/∂v. A det F ≤ 0 failure names the
    !> element (the lowest-numbered failing one of the first failing colour).
    !>
    !> Elements go colour by colour (no two elements of a colour share a
    !> node), so every entry of k, ∂k/∂q and ∂k/∂v receives its element
    !> contributions in the same order whatever the number of threads: the
    !> results are bitwise identical with and without OpenMP.
    subroutine assemble(body, q, v, k, status, tangents)
        class(flexible_body_t), intent(inout) :: body
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: k(:)
        type(status_t), intent(out) :: status
        logical, intent(in) :: tangents
        integer :: c, i, e, tid, failed_element, nthreads
        type(status_t) :: failure
        call scatter(body, q, v)
        k = 0.0_wp
        if (tangents) then
            body%stiffness%values = 0.0_wp
            body%damping%values = 0.0_wp
        end if
        nthreads = 1
        !$ nthreads = omp_get_max_threads()
        if (nthreads > size(body%work)) call allocate_workspace(body, nthreads)
        failed_element = huge(1)
        do c = 1, size(body%colour_start) - 1
            !$omp parallel do default(shared) private(i, e, tid) schedule(static)
            do i = body%colour_start(c), body%colour_start(c + 1) - 1
                e = body%colour_elements(i)
                tid = 1
                !$ tid = omp_get_thread_num() + 1
                call element_contribution(body, e, tid, k, tangents, body%work(tid)%status)
                if (.not. body%work(tid)%status%ok()) then
                    !$omp critical (flexmbs_fe_assembly_failure)
                    if (e < failed_element) then
                        failed_element = e
                        failure = body%work(tid)%status
                    end if
                    !$omp end critical (flexmbs_fe_assembly_failure)
                end if
            end do
            !$omp end parallel do
            if (failed_element < huge(1)) then
                status = failure
                call name_element(status, failed_element)
                return
            end if
        end do
    end subroutine assemble

    !> Element e's forces (and tangents) added into k and the CSC values,
    !> with the workspace of thread tid.
    subroutine element_contribution(body, e, tid, k, tangents, status)
        class(flexible_body_t), intent(inout) :: body
        integer, intent(in) :: e, tid
        real(wp), intent(inout) :: k(:)
        logical, intent(in) :: tangents
        type(status_t), intent(out) :: status
        integer :: dofs(3 * max_nodes), nn, nd, p, qq, a
        integer(i8) :: t, slot
        nn = body%hex%nnode
        nd = 3 * nn
        call gather(body, e, tid)
        associate (mat => body%materials(body%element_material(e)))
            if (tangents) then
                call element_forces(body%hex, mat, body%dndx(:, :, :, e), body%wdv(:, e), &
                                    body%work(tid)%xe, body%work(tid)%ve, &
                                    body%work(tid)%k_el, body%work(tid)%k_v, status, &
                                    body%work(tid)%ke, body%work(tid)%ce)
            else
                call element_forces(body%hex, mat, body%dndx(:, :, :, e), body%wdv(:, e), &
                                    body%work(tid)%xe, body%work(tid)%ve, &
                                    body%work(tid)%k_el, body%work(tid)%k_v, status)
            end if
        end associate
        if (.not. status%ok()) return
        call element_dofs(body, e, dofs(1:nd))
        do a = 1, nn
            do p = 1, 3
                if (dofs(3 * (a - 1) + p) > 0) k(dofs(3 * (a - 1) + p)) = &
                    k(dofs(3 * (a - 1) + p)) + body%work(tid)%k_el(p, a) + body%work(tid)%k_v(p, a)
            end do
        end do
        if (.not. tangents) return
        ! Same local order as build_patterns.
        t = body%triplet_start(e)
        do qq = 1, nd
            if (dofs(qq) == 0) cycle
            do p = 1, nd
                if (dofs(p) == 0) cycle
                slot = body%stiffness%triplet_map(t)
                body%stiffness%values(slot) = body%stiffness%values(slot) + body%work(tid)%ke(p, qq)
                body%damping%values(slot) = body%damping%values(slot) + body%work(tid)%ce(p, qq)
                t = t + 1
            end do
        end do
    end subroutine element_contribution

    !> Prefix a failure's message with its element.
    pure subroutine name_element(status, e)
        type(status_t), intent(inout) :: status
        integer, intent(in) :: e
        integer :: code, reason
        ! copies: set must not see its own components as arguments
        code = status%code
        reason = status%reason
        call status%set(code, 'flexible body: element ' // int_text(e) // ': ' // &
                        status%text(), reason)
    end subroutine name_element

    !> k(q, v) on the free dofs.
    subroutine body_internal_forces(self, q, v, k, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: k(:)
        type(status_t), intent(out) :: status
        call assemble(self, q, v, k, status, .false.)
    end subroutine body_internal_forces

    !> ∂k/∂q, ∂k/∂v into self%stiffness, self%damping (k itself unused).
    subroutine body_assemble_tangents(self, q, v, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        type(status_t), intent(out) :: status
        call assemble(self, q, v, self%force_work, status, .true.)
    end subroutine body_assemble_tangents

    !> k(q, v), and ∂k/∂q, ∂k/∂v into self%stiffness, self%damping.
    subroutine body_tangents(self, q, v, k, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: k(:)
        type(status_t), intent(out) :: status
        call assemble(self, q, v, k, status, .true.)
    end subroutine body_tangents

    !> Add a constant force on a node (its fixed components are ignored).
    subroutine body_add_nodal_load(self, node, force, status)
        class(flexible_body_t), intent(inout) :: self
        integer, intent(in) :: node
        real(wp), intent(in) :: force(3)
        type(status_t), intent(out) :: status
        integer :: j
        character(len=80) :: msg
        if (node < 1 .or. node > size(self%dof, 2)) then
            write (msg, '(a,i0,a,i0)') 'flexible body: load on node ', node, ' outside 1..', &
                size(self%dof, 2)
            call status%set(status_bad_input, trim(msg))
            return
        end if
        do j = 1, 3
            if (self%dof(j, node) > 0) self%applied_force(self%dof(j, node)) = &
                self%applied_force(self%dof(j, node)) + force(j)
        end do
    end subroutine body_add_nodal_load

    !> Gather element e's nodal positions and velocities into thread tid's
    !> xe, ve (serial callers use tid = 1).
    pure subroutine gather(body, e, tid)
        class(flexible_body_t), intent(inout) :: body
        integer, intent(in) :: e, tid
        integer :: a
        do a = 1, body%hex%nnode
            body%work(tid)%xe(:, a) = body%x(:, body%mesh%connectivity(a, e))
            body%work(tid)%ve(:, a) = body%v(:, body%mesh%connectivity(a, e))
        end do
    end subroutine gather

    !> F and det F at Gauss point g of element e, whose nodes gather put in
    !> work(1); det F ≤ 0 fails.
    subroutine point_gradient(self, e, g, f, detf, status)
        class(flexible_body_t), intent(in) :: self
        integer, intent(in) :: e, g
        real(wp), intent(out) :: f(3, 3), detf
        type(status_t), intent(inout) :: status
        call deformation_gradient(self%hex%nnode, self%dndx(:, :, g, e), self%work(1)%xe, f, &
                                  detf, status)
    end subroutine point_gradient

    !> Strain energy Σ_e Σ_g W(E) w_g det J_g; det F ≤ 0 fails as in forces.
    function body_strain_energy(self, q, status) result(energy)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        type(status_t), intent(out) :: status
        real(wp) :: energy
        real(wp) :: f(3, 3), detf
        integer :: e, g
        call scatter(self, q)
        energy = 0.0_wp
        do e = 1, self%mesh%element_count()
            call gather(self, e, 1)
            do g = 1, self%hex%ngauss
                call point_gradient(self, e, g, f, detf, status)
                if (.not. status%ok()) return
                energy = energy + self%wdv(g, e) * self%materials(self%element_material(e)) &
                    %strain_energy(0.5_wp * (matmul(transpose(f), f) - identity3))
            end do
        end do
    end function body_strain_energy

    !> Strain plus kinetic energy, less the work of the constant applied
    !> forces from q_ref (default: the reference configuration).
    real(wp) function body_total_energy(self, q, v, q_ref) result(e)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(in), optional :: q_ref(:)
        type(status_t) :: st
        e = self%strain_energy(q, st) + self%kinetic_energy(v)
        if (present(q_ref)) then
            e = e - dot_product(self%applied_force, q - q_ref)
        else
            e = e - dot_product(self%applied_force, q - self%free_positions())
        end if
    end function body_total_energy

    !> The work f·(q − q_ref) of the constant applied forces (gravity, loads).
    real(wp) function body_applied_work(self, q, q_ref) result(w)
        class(flexible_body_t), intent(in) :: self
        real(wp), intent(in) :: q(:), q_ref(:)
        w = dot_product(self%applied_force, q - q_ref)
    end function body_applied_work

    !> det F > 0 at every quadrature point of every element; otherwise a
    !> solver failure with reason_det_f naming the element.
    subroutine body_admissible(self, q, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        type(status_t), intent(out) :: status
        real(wp) :: f(3, 3), detf
        integer :: e, g
        call scatter(self, q)
        do e = 1, self%mesh%element_count()
            call gather(self, e, 1)
            do g = 1, self%hex%ngauss
                call point_gradient(self, e, g, f, detf, status)
                if (.not. status%ok()) then
                    call name_element(status, e)
                    return
                end if
            end do
        end do
    end subroutine body_admissible

    !> Cauchy stress σ = F (S_el + S_v) Fᵀ / J of every element, averaged
    !> over its Gauss points with their volume weights, in Voigt order (xx,
    !> yy, zz, xy, yz, xz), and its von Mises equivalent [Pa] (for output).
    subroutine body_element_stress(self, q, v, sigma, von_mises, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: sigma(:, :)    !! (6, elements)
        real(wp), intent(out) :: von_mises(:)   !! (elements)
        type(status_t), intent(out) :: status
        real(wp) :: f(3, 3), fdot(3, 3), detf, e(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), &
            c(3, 3), acc(3, 3), volume
        integer :: el, g
        call scatter(self, q, v)
        do el = 1, self%mesh%element_count()
            call gather(self, el, 1)
            acc = 0.0_wp
            volume = 0.0_wp
            do g = 1, self%hex%ngauss
                call point_gradient(self, el, g, f, detf, status)
                if (.not. status%ok()) then
                    call name_element(status, el)
                    return
                end if
                call nodal_gradient(self%hex%nnode, self%dndx(:, :, g, el), self%work(1)%ve, fdot)
                e = 0.5_wp * (matmul(transpose(f), f) - identity3)
                edot = 0.5_wp * (matmul(transpose(fdot), f) + matmul(transpose(f), fdot))
                call self%materials(self%element_material(el))%stress(e, edot, s_el, s_v)
                c = matmul(f, matmul(s_el + s_v, transpose(f))) / detf
                acc = acc + self%wdv(g, el) * c
                volume = volume + self%wdv(g, el)
            end do
            c = acc / volume
            sigma(:, el) = [c(1, 1), c(2, 2), c(3, 3), c(1, 2), c(2, 3), c(1, 3)]
            von_mises(el) = sqrt(0.5_wp * ((c(1, 1) - c(2, 2))**2 + (c(2, 2) - c(3, 3))**2 + &
                (c(3, 3) - c(1, 1))**2) + 3.0_wp * (c(1, 2)**2 + c(2, 3)**2 + c(1, 3)**2))
        end do
    end subroutine body_element_stress

    !> Kinetic energy ½ vᵀ M v (fixed nodes are at rest).
    function body_kinetic_energy(self, v) result(energy)
        class(flexible_body_t), intent(in) :: self
        real(wp), intent(in) :: v(:)
        real(wp) :: energy
        integer :: j
        integer(i8) :: p
        energy = 0.0_wp
        do j = 1, self%mass_matrix%ncol
            do p = self%mass_matrix%colptr(j) + 1, self%mass_matrix%colptr(j + 1)
                energy = energy + v(self%mass_matrix%rowind(p) + 1) * self%mass_matrix%values(p) &
                    * v(j)
            end do
        end do
        energy = 0.5_wp * energy
    end function body_kinetic_energy

    !> Linear momentum ∫ ρ ẋ dV and angular momentum about the origin
    !> ∫ ρ x × ẋ dV, both exact for the isoparametric fields:
    !> Σ_e Σ_ab m_ab v_b and Σ_e Σ_ab m_ab x_a × v_b (fixed nodes included).
    subroutine body_momenta(self, q, v, linear, angular)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        real(wp), intent(out) :: linear(3), angular(3)
        real(wp) :: mv(3)
        integer :: e, a, b
        call scatter(self, q, v)
        linear = 0.0_wp
        angular = 0.0_wp
        do e = 1, self%mesh%element_count()
            call gather(self, e, 1)
            call element_mass(self%hex, self%wdv(:, e), &
                              self%materials(self%element_material(e))%density, self%me)
            do a = 1, self%hex%nnode
                mv = 0.0_wp
                do b = 1, self%hex%nnode
                    mv = mv + self%me(a, b) * self%work(1)%ve(:, b)
                end do
                linear = linear + mv
                associate (x => self%work(1)%xe(:, a))
                    angular = angular + [x(2) * mv(3) - x(3) * mv(2), &
                                         x(3) * mv(1) - x(1) * mv(3), &
                                         x(1) * mv(2) - x(2) * mv(1)]
                end associate
            end do
        end do
    end subroutine body_momenta

    !> q' = v (absolute coordinates: T = I).
    subroutine body_kinematics(self, t, q, w, qdot, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: qdot(:)
        type(status_t), intent(inout) :: status
        qdot = w
    end subroutine body_kinematics

    !> The constant consistent mass matrix, dense.
    subroutine body_mass(self, t, q, m, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: m(:, :)
        type(status_t), intent(inout) :: status
        call self%mass_matrix%to_dense(m)
    end subroutine body_mass

    !> f = g − k(q, v): applied (gravity, nodal) minus internal forces (eq. 7).
    subroutine body_forces(self, t, q, v, f, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        call assemble(self, q, v, f, local, .false.)
        if (.not. local%ok()) then
            status = local
            return
        end if
        f = self%applied_force - f
    end subroutine body_forces

    !> ∂f/∂q = −∂k/∂q and ∂f/∂v = −∂k/∂v from the analytic tangents (the
    !> applied force is constant), dense for the formulations.
    subroutine body_force_derivatives(self, t, q, v, fq, fv, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:, :), fv(:, :)
        type(status_t), intent(inout) :: status
        logical :: ok
        call refresh_tangents(self, q, v, status, ok)
        if (.not. ok) return
        call self%stiffness%to_dense(fq)
        call self%damping%to_dense(fv)
        fq = -fq
        fv = -fv
    end subroutine body_force_derivatives

    !> The tangents at (q, v) assembled; when that fails, status takes its
    !> status and ok is false (otherwise status, the caller's, is left as it
    !> is).
    subroutine refresh_tangents(self, q, v, status, ok)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        type(status_t), intent(inout) :: status
        logical, intent(out) :: ok
        type(status_t) :: local
        call self%assemble_tangents(q, v, local)
        ok = local%ok()
        if (.not. ok) status = local
    end subroutine refresh_tangents

    !> T = I: ∂(T w)/∂q = 0.
    subroutine body_kinematics_derivative(self, t, q, w, dq, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
    end subroutine body_kinematics_derivative

    !> M constant: ∂(M w)/∂q = 0.
    subroutine body_mass_derivative(self, t, q, w, dq, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: dq(:, :)
        type(status_t), intent(inout) :: status
        dq = 0.0_wp
    end subroutine body_mass_derivative

    !> No constraints (nc = 0): fixed nodes are removed from q.
    subroutine body_constraint(self, t, q, g, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: g(:)
        type(status_t), intent(inout) :: status
    end subroutine body_constraint

    !> No constraints: γ is empty.
    subroutine body_constraint_curvature(self, t, q, v, gamma, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gamma(:)
        type(status_t), intent(inout) :: status
    end subroutine body_constraint_curvature

    subroutine body_constraint_jacobian(self, t, q, gmat, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: gmat(:, :)
        type(status_t), intent(inout) :: status
    end subroutine body_constraint_jacobian
    ! ------------------------------------------------ sparse form (formulations)

    logical function body_has_sparse(self)
        class(flexible_body_t), intent(in) :: self
        body_has_sparse = .true.
    end function body_has_sparse

    subroutine body_mass_pattern(self, pattern, status)
        class(flexible_body_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        pattern = self%mass_matrix
    end subroutine body_mass_pattern

    subroutine body_mass_sparse(self, t, q, values, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = self%mass_matrix%values
    end subroutine body_mass_sparse

    !> No constraint rows: an empty 0 x nv pattern.
    subroutine body_constraint_jacobian_pattern(self, pattern, status)
        class(flexible_body_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        integer :: empty(0)
        call pattern%build(0, self%nv, empty, empty, status)
    end subroutine body_constraint_jacobian_pattern

    !> Blocks without entries (no constraints, T = I constant).
    subroutine body_no_values(self, t, q, values, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
    end subroutine body_no_values

    subroutine body_no_values_w(self, t, q, w, values, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 0.0_wp
    end subroutine body_no_values_w

    subroutine body_no_second_derivatives(self, t, q, w, lambda, gwq, gtlq, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), w(:), lambda(:)
        real(wp), intent(out) :: gwq(:), gtlq(:)
        type(status_t), intent(inout) :: status
        gwq = 0.0_wp
        gtlq = 0.0_wp
    end subroutine body_no_second_derivatives

    subroutine body_no_curvature_derivatives(self, t, q, v, gq, gv, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: gq(:), gv(:)
        type(status_t), intent(inout) :: status
        gq = 0.0_wp
        gv = 0.0_wp
    end subroutine body_no_curvature_derivatives

    !> M; T = I; ∂f/∂q and ∂f/∂v on the tangent pattern; empty rest.
    subroutine body_derivative_patterns(self, patterns, status)
        class(flexible_body_t), intent(inout) :: self
        type(mechanical_patterns_t), intent(inout) :: patterns
        type(status_t), intent(inout) :: status
        integer :: empty(0), i
        integer, allocatable :: diag(:)
        call self%mass_pattern(patterns%mass, status)
        patterns%force_q = self%stiffness
        patterns%force_v = self%damping
        diag = [(i, i = 1, self%nv)]
        call patterns%kinematics%build(self%nq, self%nv, diag, diag, status)
        if (status%ok()) call patterns%kinematics_q%build(self%nq, self%nq, empty, empty, status)
        if (status%ok()) call self%constraint_jacobian_pattern(patterns%constraint_v, status)
        if (status%ok()) call patterns%constraint_q%build(0, self%nq, empty, empty, status)
        if (status%ok()) call patterns%reaction_q%build(self%nv, self%nq, empty, empty, status)
    end subroutine body_derivative_patterns

    subroutine body_kinematics_sparse(self, t, q, values, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = 1.0_wp
    end subroutine body_kinematics_sparse

    !> −∂k/∂q and −∂k/∂v in the slots of the tangent pattern.
    subroutine body_force_derivatives_sparse(self, t, q, v, fq, fv, status)
        class(flexible_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: fq(:), fv(:)
        type(status_t), intent(inout) :: status
        logical :: ok
        call refresh_tangents(self, q, v, status, ok)
        if (.not. ok) return
        fq = -self%stiffness%values
        fv = -self%damping%values
    end subroutine body_force_derivatives_sparse
end module flexmbs_fe_flexible_body
