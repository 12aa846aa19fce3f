!> The reduced basis of a modal (floating-frame) body, computed from the
!> body's own mesh and material linearised at the reference configuration
!> (docs/theory.md §2.7): Craig–Bampton with rigidified interfaces.
!>
!> Interfaces: each interface node set j (the sets that markers and joints
!> use) moves as a rigid plate about its centroid X_cj (equal weights, the
!> centroid a set marker of a nonlinear body uses): u_i = t_j + θ_j ×
!> (X_i − X_cj). That leaves 6 boundary coordinates per interface and the
!> interior nodes' displacements, the linear FE model "with rigidified
!> interfaces". On it:
!> - k fixed-interface normal modes (every interface held): the lowest
!>   eigenpairs of K_ii φ = ω² M_ii φ on the interior dofs (dense LAPACK
!>   or ARPACK shift-invert, flexmbs_linalg_symmetric_modes);
!> - 6 static constraint modes per interface: one boundary coordinate at 1,
!>   the others 0, the interior in static equilibrium, −K_ii⁻¹ K_ib.
!> The rigid-body motions lie in the span of the constraint modes (a rigid
!> motion of every interface leaves the interior unstrained), and are
!> removed: every column is made M-orthogonal to the six rigid motions of
!> the body about its centre of mass (the linearised mean-axis, or Buckens,
!> frame condition: ∫ρ u dV = 0 and ∫ρ X × u dV = 0). The rest, of rank k +
!> 6 (n_I − 1), is M-orthonormalised (eigen-decomposition of its Gram
!> matrix) and then diagonalised on K, so that the final shapes Φ satisfy
!> Φᵀ M Φ = I and Φᵀ K Φ = diag(ω²): ω are the reduced body's own
!> frequencies, which a run reports. A single interface with k = 0 leaves
!> no elastic coordinate: the body is rigid.
!>
!> K and D are the body's tangent stiffness ∂k/∂q and damping ∂k/∂v at the
!> reference configuration at rest, M its consistent mass (fe/flexible_body).
module flexmbs_fe_modal_basis
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text, real_text
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_sub_block, only: sub_block_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_linalg_lapack, only: dsyev_quiet, dgetrf, dgetrs
    use flexmbs_linalg_symmetric_modes, only: lowest_modes
    use flexmbs_fe_mesh, only: node_set_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    implicit none
    private

    public :: craig_bampton, rigid_motions, basis_fingerprint

    !> The version of the basis the fingerprint covers: a change of the
    !> algorithm that changes the shapes changes it, so old caches are redone.
    character(len=*), parameter :: basis_version = 'craig-bampton 1'

    !> Gram eigenvalues below this fraction of the largest are the removed
    !> rigid directions (round-off: 1e-16 relative; the smallest kept ones
    !> of the meshes tested: 1e-6).
    real(wp), parameter :: rank_tolerance = 1.0e-10_wp
    !> An interface is degenerate (its nodes on a line) when the area its
    !> three most spread nodes span is below this fraction of its extent².
    real(wp), parameter :: collinear_tolerance = 1.0e-8_wp

    !> A modal body's basis: shapes, reduced stiffness and damping, and the
    !> rigid motion of every interface in every mode.
    type, public :: modal_basis_t
        integer :: nodes = 0          !! mesh nodes
        integer :: fixed_modes = 0    !! k: fixed-interface normal modes asked for
        integer :: count = 0          !! elastic coordinates, k + 6 (interfaces − 1)
        !> (3 nodes, count): the nodal displacement of each mode, node by node
        !> x y z, in the body's frame
        real(wp), allocatable :: shapes(:, :)
        real(wp), allocatable :: frequencies(:)   !! ω [rad/s], ascending
        real(wp), allocatable :: damping(:, :)    !! Φᵀ D Φ [1/s] (count x count)
        !> (6, count, interfaces): translation t (1:3) and small rotation θ
        !> (4:6) of interface j in each mode
        real(wp), allocatable :: interface_motion(:, :, :)
        real(wp), allocatable :: interface_centre(:, :) !! (3, interfaces) X_cj, mesh frame
        real(wp), allocatable :: fixed_frequencies(:)   !! ω of the k fixed-interface modes
        character(len=:), allocatable :: eigen_method   !! 'dense' | 'arpack' as used
    contains
        procedure :: export_parts => basis_export_parts
        procedure :: import_parts => basis_import_parts
    end type modal_basis_t

contains

    !> The arrays that make the basis (a cache file keeps them; see the
    !> type's components for their meaning and shapes).
    subroutine basis_export_parts(self, eigen_method, frequencies, shapes, damping, &
                                  interface_centre, interface_motion, fixed_frequencies)
        class(modal_basis_t), intent(in) :: self
        character(len=:), allocatable, intent(out) :: eigen_method
        real(wp), allocatable, intent(out) :: frequencies(:), shapes(:, :), damping(:, :), &
            interface_centre(:, :), interface_motion(:, :, :), fixed_frequencies(:)
        eigen_method = self%eigen_method
        frequencies = self%frequencies
        shapes = self%shapes
        damping = self%damping
        interface_centre = self%interface_centre
        interface_motion = self%interface_motion
        fixed_frequencies = self%fixed_frequencies
    end subroutine basis_export_parts

    !> The basis made of the arrays export_parts gives (read back from a
    !> cache); count and nodes follow from their shapes. Without
    !> `eigen_method` the basis keeps its own.
    subroutine basis_import_parts(self, frequencies, shapes, damping, interface_centre, &
                                  interface_motion, fixed_frequencies, eigen_method)
        class(modal_basis_t), intent(inout) :: self
        real(wp), intent(in) :: frequencies(:), shapes(:, :), damping(:, :), &
            interface_centre(:, :), interface_motion(:, :, :), fixed_frequencies(:)
        character(len=*), intent(in), optional :: eigen_method
        if (present(eigen_method)) self%eigen_method = eigen_method
        self%frequencies = frequencies
        self%shapes = shapes
        self%damping = damping
        self%interface_centre = interface_centre
        self%interface_motion = interface_motion
        self%fixed_frequencies = fixed_frequencies
        self%count = size(frequencies)
        self%nodes = size(shapes, 1) / 3
    end subroutine basis_import_parts

    !> The SHA-256 of what craig_bampton's basis depends on: the basis
    !> version, k = `modes`, the element type, every node's position and
    !> element's nodes (bit for bit), every element's material constants,
    !> the interfaces' names and nodes. The text is filled in place (long
    !> meshes: no repeated concatenation).
    function basis_fingerprint(body, interfaces, modes) result(digest)
        type(flexible_body_t), intent(in) :: body
        type(node_set_t), intent(in) :: interfaces(:)
        integer, intent(in) :: modes
        character(len=:), allocatable :: digest
        character(len=:), allocatable :: text
        integer :: i, j, n, at
        n = 64 + 17 * (size(body%mesh%x) + 4 * size(body%materials)) + &
            12 * (size(body%mesh%connectivity) + size(body%element_material))
        do j = 1, size(interfaces)
            n = n + len(interfaces(j)%name) + 12 * size(interfaces(j)%nodes) + 2
        end do
        allocate (character(len=n) :: text)
        at = 0
        call put(basis_version // ' k=' // int_text(modes) // ' nnode=' // &
                 int_text(body%mesh%nnode_element) // ';')
        do j = 1, size(body%mesh%x, 2)
            do i = 1, 3
                call put(hex(body%mesh%x(i, j)))
            end do
        end do
        call put(';')
        do j = 1, size(body%mesh%connectivity, 2)
            do i = 1, size(body%mesh%connectivity, 1)
                call put(int_text(body%mesh%connectivity(i, j)) // ',')
            end do
        end do
        call put(';')
        do j = 1, size(body%element_material)
            call put(int_text(body%element_material(j)) // ',')
        end do
        do j = 1, size(body%materials)
            associate (m => body%materials(j))
                call put(';' // hex(m%mu) // hex(m%lambda) // hex(m%beta) // hex(m%density))
            end associate
        end do
        do j = 1, size(interfaces)
            call put(';' // interfaces(j)%name // ':')
            do i = 1, size(interfaces(j)%nodes)
                call put(int_text(interfaces(j)%nodes(i)) // ',')
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
    end function basis_fingerprint

    !> The Craig–Bampton basis of `body` (free: no fixed node or component)
    !> with k = `modes` fixed-interface modes and the interface node sets
    !> `interfaces` (disjoint, each at least three nodes off one line).
    !> `method` ('auto' | 'dense' | 'arpack') picks the eigen-solver of the
    !> fixed-interface problem. `body`'s tangents are left at the reference
    !> configuration at rest.
    subroutine craig_bampton(body, interfaces, modes, basis, status, method)
        type(flexible_body_t), intent(inout) :: body
        type(node_set_t), intent(in) :: interfaces(:)
        integer, intent(in) :: modes
        type(modal_basis_t), intent(out) :: basis
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: method
        integer, allocatable :: owner(:), interior_of(:)
        real(wp), allocatable :: v(:, :), b(:, :), lambda(:), phi(:, :)
        type(sub_block_t) :: k_ii, m_ii
        integer :: n, ni, nb, ncol, j, stat
        real(wp) :: scale
        character(len=:), allocatable :: eigen

        eigen = 'auto'
        if (present(method)) eigen = method
        n = body%mesh%node_count()
        basis%nodes = n
        basis%fixed_modes = modes
        if (body%nq /= 3 * n) then
            call status%set(status_bad_input, 'modal basis: the body has fixed nodes or &
                &components; a modal body is held by joints on its interfaces')
            return
        end if
        call check_interfaces(body%mesh%x, interfaces, owner, basis%interface_centre, status)
        if (.not. status%ok()) return
        nb = 6 * size(interfaces)
        allocate (interior_of(3 * n), source=0)
        ni = 0
        do j = 1, 3 * n
            if (owner((j - 1) / 3 + 1) /= 0) cycle
            ni = ni + 1
            interior_of(j) = ni
        end do
        if (modes < 0 .or. modes > ni) then
            call status%set(status_bad_input, 'modes = ' // int_text(modes) // ': the mesh &
                &allows 0 to ' // int_text(ni) // ' (its interior coordinates, the &
                &interfaces'' nodes held)')
            return
        end if
        call body%assemble_tangents(body%free_positions(), spread(0.0_wp, 1, 3 * n), status)
        if (.not. status%ok()) return
        call k_ii%pick(body%stiffness, interior_of, interior_of, ni, ni, status)
        if (status%ok()) call m_ii%pick(body%mass_matrix, interior_of, interior_of, ni, ni, &
                                        status)
        if (.not. status%ok()) return
        call k_ii%gather(body%stiffness%values)
        call m_ii%gather(body%mass_matrix%values)
        call lowest_modes(k_ii%a, m_ii%a, modes, eigen, lambda, phi, status, &
                          used=basis%eigen_method)
        if (.not. status%ok()) then
            status%message = 'modal basis, fixed-interface modes: ' // status%message
            return
        end if
        basis%fixed_frequencies = sqrt(max(lambda, 0.0_wp))

        ! Columns: the constraint modes, then the fixed-interface modes; b
        ! keeps each column's interface coordinates alongside.
        ncol = nb + modes
        allocate (v(3 * n, ncol), b(nb, ncol), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'modal basis: columns', 3_i8 * n * ncol, 8)
            return
        end if
        v = 0.0_wp
        b = 0.0_wp
        call constraint_modes(body, k_ii, interior_of, owner, basis%interface_centre, v(:, 1:nb), &
                              status)
        if (.not. status%ok()) return
        do j = 1, nb
            b(j, j) = 1.0_wp
        end do
        do j = 1, modes
            call scatter_interior(phi(:, j), interior_of, v(:, nb + j))
        end do
        scale = column_scale(body, v)
        call remove_rigid(body, basis%interface_centre, v, b, status)
        if (.not. status%ok()) return
        call orthonormalise(body, v, b, ncol - 6, scale, basis, status)
    end subroutine craig_bampton

    !> Every interface non-empty, disjoint from the others and not on one
    !> line; owner(node) = its interface or 0; centre(:, j) its centroid.
    subroutine check_interfaces(x, interfaces, owner, centre, status)
        real(wp), intent(in) :: x(:, :)
        type(node_set_t), intent(in) :: interfaces(:)
        integer, allocatable, intent(out) :: owner(:)
        real(wp), allocatable, intent(out) :: centre(:, :)
        type(status_t), intent(inout) :: status
        integer :: j, i, node
        real(wp) :: extent, area
        allocate (owner(size(x, 2)), source=0)
        allocate (centre(3, size(interfaces)), source=0.0_wp)
        if (size(interfaces) == 0) then
            call status%set(status_bad_input, 'modal basis: no interface; a modal body needs &
                &at least one interface node set (its markers and joints sit there)')
            return
        end if
        do j = 1, size(interfaces)
            associate (nodes => interfaces(j)%nodes, name => interfaces(j)%name)
                if (any(nodes < 1 .or. nodes > size(x, 2))) then
                    call status%set(status_bad_input, "interface '" // name // "': a node &
                        &outside 1.." // int_text(size(x, 2)))
                    return
                end if
                do i = 1, size(nodes)
                    node = nodes(i)
                    if (owner(node) /= 0 .and. owner(node) /= j) then
                        call status%set(status_bad_input, "interface '" // name // "': node " &
                            // int_text(node) // " also belongs to interface '" // &
                            interfaces(owner(node))%name // "'; interfaces must be disjoint")
                        return
                    end if
                    owner(node) = j
                end do
                area = 0.0_wp
                extent = 0.0_wp
                if (size(nodes) >= 3) then
                    centre(:, j) = sum(x(:, nodes), dim=2) / size(nodes)
                    call spread_area(x(:, nodes), extent, area)
                end if
                if (size(nodes) < 3 .or. .not. area > collinear_tolerance * extent**2) then
                    call status%set(status_bad_input, "interface '" // name // "': " // &
                        int_text(size(nodes)) // ' nodes on one line or point; a rigidified &
                        &interface needs three nodes off one line')
                    return
                end if
            end associate
        end do
    end subroutine check_interfaces

    !> The largest distance from the first point (extent) and the area of
    !> the triangle it spans with the point farthest off their line.
    pure subroutine spread_area(x, extent, area)
        real(wp), intent(in) :: x(:, :)
        real(wp), intent(out) :: extent, area
        real(wp) :: d(3), e(3), a
        integer :: i, far
        extent = 0.0_wp
        area = 0.0_wp
        far = 1
        do i = 2, size(x, 2)
            if (norm2(x(:, i) - x(:, 1)) > extent) then
                extent = norm2(x(:, i) - x(:, 1))
                far = i
            end if
        end do
        d = x(:, far) - x(:, 1)
        do i = 2, size(x, 2)
            e = x(:, i) - x(:, 1)
            a = 0.5_wp * norm2([d(2) * e(3) - d(3) * e(2), d(3) * e(1) - d(1) * e(3), &
                               d(1) * e(2) - d(2) * e(1)])
            area = max(area, a)
        end do
    end subroutine spread_area

    !> The six rigid motions about `centre` as nodal displacements (3 n x 6):
    !> translations e_1..e_3, then small rotations e_α × (X_i − centre).
    pure function rigid_motions(x, centre) result(g)
        real(wp), intent(in) :: x(:, :), centre(3)
        real(wp) :: g(3 * size(x, 2), 6)
        integer :: i
        real(wp) :: d(3)
        g = 0.0_wp
        do i = 1, size(x, 2)
            d = x(:, i) - centre
            associate (r => g(3 * i - 2:3 * i, :))
                r(1, 1) = 1.0_wp
                r(2, 2) = 1.0_wp
                r(3, 3) = 1.0_wp
                ! columns 4..6: e_α × d
                r(:, 4) = [0.0_wp, -d(3), d(2)]
                r(:, 5) = [d(3), 0.0_wp, -d(1)]
                r(:, 6) = [-d(2), d(1), 0.0_wp]
            end associate
        end do
    end function rigid_motions

    !> Full vector from interior values (interfaces 0).
    pure subroutine scatter_interior(values, interior_of, full)
        real(wp), intent(in) :: values(:)
        integer, intent(in) :: interior_of(:)
        real(wp), intent(out) :: full(:)
        integer :: j
        full = 0.0_wp
        do j = 1, size(interior_of)
            if (interior_of(j) > 0) full(j) = values(interior_of(j))
        end do
    end subroutine scatter_interior

    !> The 6 n_I static constraint modes: interface coordinate l at 1 (the
    !> interface's nodes moved rigidly), the others 0, the interior from
    !> K_ii u_i = −K_ib u_b, one factorisation of K_ii for all of them.
    subroutine constraint_modes(body, k_ii, interior_of, owner, centre, v, status)
        type(flexible_body_t), intent(in) :: body
        type(sub_block_t), intent(in) :: k_ii
        integer, intent(in) :: interior_of(:), owner(:)
        real(wp), intent(in) :: centre(:, :)
        real(wp), intent(out) :: v(:, :)
        type(status_t), intent(inout) :: status
        class(linear_solver_t), allocatable :: solver
        type(matrix_t) :: k_mat, zero
        real(wp), allocatable :: g(:, :), ku(:), rhs(:)
        integer :: ni, j, l, i
        ni = k_ii%a%nrow
        v = 0.0_wp
        allocate (ku(size(interior_of)), rhs(ni))
        if (ni > 0) then
            k_mat%storage = storage_sparse
            k_mat%n = ni
            k_mat%csc = k_ii%a
            zero = k_mat
            zero%csc%values = 0.0_wp
            call new_linear_solver('auto', ni, storage_sparse, solver, status, mass=zero, &
                                   jac=k_mat)
            if (status%ok()) call solver%init(zero, k_mat, status)
            ! factor_real factors c M − J = −K_ii (c = 0)
            if (status%ok()) call solver%factor_real(0.0_wp, zero, k_mat, status)
            if (.not. status%ok()) then
                status%message = 'modal basis: the interior stiffness K_ii cannot be factored &
                    &(interfaces that do not hold the body): ' // status%message
                return
            end if
        end if
        allocate (g(size(v, 1), 6))   ! before the assignment (see remove_rigid)
        do j = 1, size(centre, 2)
            g = rigid_motions(body%mesh%x, centre(:, j))
            do l = 1, 6
                associate (col => v(:, 6 * (j - 1) + l))
                    do i = 1, size(owner)
                        if (owner(i) == j) col(3 * i - 2:3 * i) = g(3 * i - 2:3 * i, l)
                    end do
                    if (ni == 0) cycle
                    call body%stiffness%matvec(col, ku)
                    rhs = pack(ku, interior_of > 0)
                    ! solve_real gives (−K_ii)⁻¹ rhs = K_ii⁻¹ (−K_ib u_b)
                    call solver%solve_real(rhs)
                    where (interior_of > 0) col = rhs(max(interior_of, 1))
                end associate
            end do
        end do
    end subroutine constraint_modes

    !> v ← v − G (Gᵀ M G)⁻¹ Gᵀ M v with G the rigid motions about the centre
    !> of mass; b (the columns' interface coordinates) follows: a rigid
    !> motion (c, ϑ) about the centre moves interface j by (c + ϑ × (X_cj −
    !> centre), ϑ).
    subroutine remove_rigid(body, centre, v, b, status)
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: centre(:, :)
        real(wp), intent(inout) :: v(:, :), b(:, :)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: g(:, :), mg(:, :), coef(:, :)
        real(wp) :: gmg(6, 6), c(3), total, d(3)
        integer :: l, j, info, ipiv(6)
        ! allocated before the assignments: gfortran's reallocation reads the
        ! bounds of an unallocated array (valgrind's uninitialised jumps)
        allocate (mg(size(v, 1), 6), g(size(v, 1), 6))
        g = rigid_motions(body%mesh%x, [0.0_wp, 0.0_wp, 0.0_wp])
        call body%mass_matrix%matvec(g(:, 1), mg(:, 1))
        ! M e_x holds ∫ρ N_i dV in every node's x slot: mass and centre.
        total = sum(mg(1::3, 1))
        c = [sum(mg(1::3, 1) * body%mesh%x(1, :)), sum(mg(1::3, 1) * body%mesh%x(2, :)), &
             sum(mg(1::3, 1) * body%mesh%x(3, :))] / total
        g = rigid_motions(body%mesh%x, c)
        do l = 1, 6
            call body%mass_matrix%matvec(g(:, l), mg(:, l))
        end do
        gmg = matmul(transpose(g), mg)
        coef = matmul(transpose(mg), v)
        call dgetrf(6, 6, gmg, 6, ipiv, info)
        if (info == 0) call dgetrs('N', 6, size(v, 2), gmg, 6, ipiv, coef, 6, info)
        if (info /= 0) then
            call status%set(status_solver_failure, 'modal basis: the rigid-body mass matrix &
                &is singular (a body without mass?)')
            return
        end if
        v = v - matmul(g, coef)
        do j = 1, size(centre, 2)
            d = centre(:, j) - c
            associate (bj => b(6 * j - 5:6 * j, :))
                bj(1:3, :) = bj(1:3, :) - coef(1:3, :)
                bj(1, :) = bj(1, :) - (coef(5, :) * d(3) - coef(6, :) * d(2))
                bj(2, :) = bj(2, :) - (coef(6, :) * d(1) - coef(4, :) * d(3))
                bj(3, :) = bj(3, :) - (coef(4, :) * d(2) - coef(5, :) * d(1))
                bj(4:6, :) = bj(4:6, :) - coef(4:6, :)
            end associate
        end do
    end subroutine remove_rigid

    !> Eigenvalues (ascending) and orthonormal eigenvectors (in a) of the
    !> symmetric part of a, by LAPACK dsyev.
    subroutine symmetric_eigen(a, values, what, status)
        real(wp), intent(inout) :: a(:, :)
        real(wp), allocatable, intent(out) :: values(:)
        character(len=*), intent(in) :: what
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: work(:)
        integer :: n, info
        n = size(a, 1)
        allocate (values(n), work(max(1, 3 * n)))
        if (n == 0) return
        a = 0.5_wp * (a + transpose(a))
        call dsyev_quiet('V', 'U', n, a, n, values, work, size(work), info)
        if (info /= 0) call status%set(status_solver_failure, 'modal basis: LAPACK dsyev &
            &failed on ' // what // ' (info = ' // int_text(info) // ')')
    end subroutine symmetric_eigen

    !> The largest M-norm² of the columns v (before the rigid motions are
    !> removed): the scale against which the removed directions are zero.
    real(wp) function column_scale(body, v) result(scale)
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: v(:, :)
        real(wp) :: mv(size(v, 1))
        integer :: j
        scale = 0.0_wp
        do j = 1, size(v, 2)
            call body%mass_matrix%matvec(v(:, j), mv)
            scale = max(scale, dot_product(v(:, j), mv))
        end do
    end function column_scale

    !> M-orthonormal, K-diagonal shapes from the columns v (rank `rank`
    !> expected; `scale` the columns' M-norm² before the rigid motions were
    !> removed), with their interface motions and reduced damping.
    subroutine orthonormalise(body, v, b, rank, scale, basis, status)
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: v(:, :), b(:, :)
        integer, intent(in) :: rank
        real(wp), intent(in) :: scale
        type(modal_basis_t), intent(inout) :: basis
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: mv(:, :), kv(:, :), gram(:, :), g0(:, :), mu(:), w(:, :), &
            kw(:, :), om2(:), dphi(:, :), phib(:, :)
        integer :: ncol, j, kept, ni
        ncol = size(v, 2)
        allocate (mv(size(v, 1), ncol), kv(size(v, 1), ncol))
        do j = 1, ncol
            call body%mass_matrix%matvec(v(:, j), mv(:, j))
            call body%stiffness%matvec(v(:, j), kv(:, j))
        end do
        g0 = matmul(transpose(v), mv)
        gram = g0
        call symmetric_eigen(gram, mu, 'the Gram matrix', status)
        if (.not. status%ok()) return
        kept = count(mu > rank_tolerance * scale)
        if (kept /= rank) then
            call status%set(status_solver_failure, 'modal basis: ' // int_text(kept) // &
                ' independent shapes where ' // int_text(rank) // ' were expected (k + 6 &
                &(interfaces - 1)): interfaces that move together?')
            return
        end if
        ! w = Q_kept diag(μ^-1/2): v w is M-orthonormal; a second pass on
        ! wᵀ G w (near I) removes what the first one's conditioning left.
        allocate (w(ncol, kept))
        do j = 1, kept
            w(:, j) = gram(:, ncol - kept + j) / sqrt(mu(ncol - kept + j))
        end do
        gram = matmul(transpose(w), matmul(g0, w))
        call symmetric_eigen(gram, mu, 'the Gram matrix', status)
        if (.not. status%ok()) return
        do j = 1, kept
            gram(:, j) = gram(:, j) / sqrt(mu(j))
        end do
        w = matmul(w, gram)
        kw = matmul(transpose(w), matmul(matmul(transpose(v), kv), w))
        call symmetric_eigen(kw, om2, 'the reduced stiffness', status)
        if (.not. status%ok()) return
        w = matmul(w, kw)
        basis%count = kept
        basis%shapes = matmul(v, w)
        basis%frequencies = sqrt(max(om2, 0.0_wp))
        phib = matmul(b, w)
        ni = size(basis%interface_centre, 2)
        allocate (basis%interface_motion(6, kept, ni))
        do j = 1, ni
            basis%interface_motion(:, :, j) = phib(6 * j - 5:6 * j, :)
        end do
        allocate (dphi(size(v, 1), kept))
        do j = 1, kept
            call body%damping%matvec(basis%shapes(:, j), dphi(:, j))
        end do
        basis%damping = matmul(transpose(basis%shapes), dphi)
        basis%damping = 0.5_wp * (basis%damping + transpose(basis%damping))
    end subroutine orthonormalise
end module flexmbs_fe_modal_basis
