!> The modal body's basis (fe/modal_basis, fe/modal_invariants,
!> linalg/symmetric_modes): with every fixed-interface mode, Craig–Bampton
!> is exact, so its frequencies equal those of the rigidified-interface FE
!> model solved whole by a dense QZ-free eigen-solve built here; the shapes
!> are M-orthonormal, K-diagonal, free of rigid motion (mean-axis frame)
!> and rigid on every interface; ARPACK agrees with the dense solver; the
!> invariants of a box equal its closed-form mass and second moments; and
!> bad interfaces or mode counts are refused by name.
module test_modal_basis
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: real_text
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    use flexmbs_fe_mesh, only: mesh_t, node_set_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_fe_modal_basis, only: modal_basis_t, craig_bampton, rigid_motions
    use flexmbs_fe_modal_invariants, only: modal_invariants_t, modal_invariants
    use flexmbs_linalg_lapack, only: dsygv_quiet
    use test_fe, only: paper_material
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_modal_basis, modal_test_body

    ! A bar along x with unequal sides (no double bending frequencies).
    real(wp), parameter :: bar(3) = [0.6_wp, 0.08_wp, 0.05_wp]

contains

    function collect_modal_basis() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('all_modes_equal_rigidified_fe', test_all_modes), &
                 new_test('orthonormal_mean_axis_rigid_interfaces', test_properties), &
                 new_test('arpack_equals_dense', test_arpack), &
                 new_test('box_invariants_closed_form', test_invariants), &
                 new_test('mode_counts', test_counts), &
                 new_test('bad_input_named', test_bad_input)]
    end function collect_modal_basis

    !> The bar (divisions d, hex8, paper's material) free, and its end faces
    !> as interfaces.
    subroutine modal_test_body(divisions, body, interfaces, status)
        integer, intent(in) :: divisions(3)
        type(flexible_body_t), intent(out) :: body
        type(node_set_t), allocatable, intent(out) :: interfaces(:)
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        call box_mesh(mesh, hex8, divisions, bar, status)
        if (.not. status%ok()) return
        call paper_material(material)
        call new_flexible_body(body, mesh, [material], [integer ::], status)
        if (.not. status%ok()) return
        allocate (interfaces(2))
        interfaces(1)%name = 'xmin'
        interfaces(2)%name = 'xmax'
        call mesh%node_set('xmin', interfaces(1)%nodes, status)
        if (status%ok()) call mesh%node_set('xmax', interfaces(2)%nodes, status)
    end subroutine modal_test_body

    !> Every fixed-interface mode: the reduced frequencies are the nonzero
    !> ones of (T₀ᵀ K T₀, T₀ᵀ M T₀), T₀ the rigidified-interface map built
    !> here from the mesh, solved as one dense symmetric pencil.
    subroutine test_all_modes(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(node_set_t), allocatable :: faces(:)
        type(modal_basis_t) :: basis
        type(status_t) :: status
        real(wp), allocatable :: t0(:, :), k(:, :), m(:, :), kw(:, :), mw(:, :), w(:), work(:)
        real(wp), allocatable :: g(:, :)
        integer :: n, nw, i, j, col, info, interior
        logical, allocatable :: on_face(:)
        call modal_test_body([4, 1, 1], body, faces, status)
        call check(error, status%ok(), 'body: ' // status%text())
        if (allocated(error)) return
        n = body%mesh%node_count()
        allocate (on_face(n), source=.false.)
        on_face(faces(1)%nodes) = .true.
        on_face(faces(2)%nodes) = .true.
        interior = 3 * count(.not. on_face)
        call craig_bampton(body, faces, interior, basis, status)
        call check(error, status%ok(), 'craig_bampton: ' // status%text())
        if (allocated(error)) return
        ! T₀: 6 columns per face (its rigid motions about its centroid),
        ! then one per interior dof.
        nw = 12 + interior
        allocate (t0(3 * n, nw), source=0.0_wp)
        allocate (g(3 * n, 6))
        do j = 1, 2
            g = rigid_motions(body%mesh%x, sum(body%mesh%x(:, faces(j)%nodes), dim=2) / &
                              size(faces(j)%nodes))
            do i = 1, n
                if (any(faces(j)%nodes == i)) t0(3 * i - 2:3 * i, 6 * j - 5:6 * j) = &
                    g(3 * i - 2:3 * i, :)
            end do
        end do
        col = 12
        do i = 1, n
            if (on_face(i)) cycle
            do j = 1, 3
                col = col + 1
                t0(3 * (i - 1) + j, col) = 1.0_wp
            end do
        end do
        allocate (k(3 * n, 3 * n), m(3 * n, 3 * n))
        call body%stiffness%to_dense(k)
        call body%mass_matrix%to_dense(m)
        kw = matmul(transpose(t0), matmul(k, t0))
        mw = matmul(transpose(t0), matmul(m, t0))
        allocate (w(nw), work(10 * nw))
        call dsygv_quiet(1, 'N', 'U', nw, kw, nw, mw, nw, w, work, size(work), info)
        call check(error, info == 0, 'dsygv of the rigidified model failed')
        if (allocated(error)) return
        call check(error, basis%count == nw - 6, 'count: expected the rigidified model''s &
            &elastic modes')
        if (allocated(error)) return
        ! six rigid motions at zero (relative to the largest), then the rest
        call check(error, all(abs(w(1:6)) < 1.0e-9_wp * w(nw)), 'six zero frequencies')
        do i = 1, basis%count
            call check_close(error, basis%frequencies(i), sqrt(w(6 + i)), 1.0e-8_wp, &
                             'frequency of mode ' // char(48 + mod(i, 10)), rel=.true.)
        end do
    end subroutine test_all_modes

    !> Φᵀ M Φ = I, Φᵀ K Φ = diag(ω²), ∫ρ Φ = 0 and ∫ρ X × Φ = 0 (mean-axis
    !> frame), every interface node moving as its interface's rigid motion,
    !> and the reduced damping symmetric positive semidefinite.
    subroutine test_properties(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(node_set_t), allocatable :: faces(:)
        type(modal_basis_t) :: basis
        type(modal_invariants_t) :: inv
        type(status_t) :: status
        real(wp), allocatable :: mphi(:, :), kphi(:, :), gram(:, :), stiff(:, :), g(:, :)
        real(wp) :: worst, d(3), scale
        integer :: i, j, l, nb
        call modal_test_body([6, 2, 1], body, faces, status)
        if (status%ok()) call craig_bampton(body, faces, 8, basis, status)
        call check(error, status%ok(), 'craig_bampton: ' // status%text())
        if (allocated(error)) return
        call check(error, basis%count == 8 + 6, 'count = k + 6 (interfaces - 1)')
        allocate (mphi, kphi, mold=basis%shapes)
        do j = 1, basis%count
            call body%mass_matrix%matvec(basis%shapes(:, j), mphi(:, j))
            call body%stiffness%matvec(basis%shapes(:, j), kphi(:, j))
        end do
        gram = matmul(transpose(basis%shapes), mphi)
        stiff = matmul(transpose(basis%shapes), kphi)
        do j = 1, basis%count
            gram(j, j) = gram(j, j) - 1.0_wp
            stiff(j, j) = stiff(j, j) - basis%frequencies(j)**2
        end do
        call check(error, maxval(abs(gram)) < 1.0e-13_wp, 'Phi^T M Phi = I: ' // real_text(maxval(abs(gram))))
        call check(error, maxval(abs(stiff)) < 1.0e-9_wp * maxval(basis%frequencies)**2, &
                   'Phi^T K Phi = diag(omega^2)')
        call check(error, all(basis%frequencies(2:) >= basis%frequencies(:basis%count - 1)), &
                   'frequencies ascending')
        inv = modal_invariants(body%mass_matrix, body%mesh%x, basis%shapes)
        scale = sqrt(inv%mass)
        call check(error, maxval(abs(inv%first)) < 1.0e-12_wp * scale, 'int rho Phi = 0')
        worst = 0.0_wp
        do j = 1, basis%count
            associate (c => inv%coupling(:, :, j))
                worst = max(worst, abs(c(2, 3) - c(3, 2)), abs(c(3, 1) - c(1, 3)), &
                            abs(c(1, 2) - c(2, 1)))
            end associate
        end do
        call check(error, worst < 1.0e-12_wp * scale * maxval(bar), 'int rho X x Phi = 0')
        ! interfaces rigid: u_i = t + θ × (X_i − X_c)
        worst = 0.0_wp
        nb = size(faces)
        allocate (g(size(basis%shapes, 1), 6))
        do l = 1, nb
            g = rigid_motions(body%mesh%x, basis%interface_centre(:, l))
            do i = 1, size(faces(l)%nodes)
                associate (node => faces(l)%nodes(i))
                    do j = 1, basis%count
                        d = basis%shapes(3 * node - 2:3 * node, j) - &
                            matmul(g(3 * node - 2:3 * node, :), basis%interface_motion(:, j, l))
                        worst = max(worst, maxval(abs(d)))
                    end do
                end associate
            end do
        end do
        call check(error, worst < 1.0e-12_wp * maxval(abs(basis%shapes)), &
                   'interface nodes follow their interface''s rigid motion')
        call check(error, maxval(abs(basis%damping - transpose(basis%damping))) == 0.0_wp, &
                   'reduced damping symmetric')
        do j = 1, basis%count
            call check(error, basis%damping(j, j) > 0.0_wp, 'reduced damping positive')
        end do
    end subroutine test_properties

    !> The same basis with the fixed-interface modes by ARPACK and by LAPACK.
    subroutine test_arpack(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(node_set_t), allocatable :: faces(:)
        type(modal_basis_t) :: dense, arpack
        type(status_t) :: status
        real(wp), allocatable :: mphi(:), overlap(:, :)
        integer :: j
        call modal_test_body([12, 2, 2], body, faces, status)
        if (status%ok()) call craig_bampton(body, faces, 10, dense, status, method='dense')
        call check(error, status%ok(), 'dense: ' // status%text())
        if (allocated(error)) return
        call craig_bampton(body, faces, 10, arpack, status, method='arpack')
        call check(error, status%ok(), 'arpack: ' // status%text())
        if (allocated(error)) return
        call check(error, arpack%eigen_method == 'arpack' .and. dense%eigen_method == 'dense', &
                   'methods reported')
        do j = 1, 10
            call check_close(error, arpack%fixed_frequencies(j), dense%fixed_frequencies(j), &
                             1.0e-10_wp, 'fixed-interface frequency', rel=.true.)
        end do
        do j = 1, dense%count
            call check_close(error, arpack%frequencies(j), dense%frequencies(j), 1.0e-10_wp, &
                             'reduced frequency', rel=.true.)
        end do
        ! the same shapes up to sign: |Φ_aᵀ M Φ_d| = I
        allocate (mphi(size(dense%shapes, 1)), overlap(dense%count, dense%count))
        do j = 1, dense%count
            call body%mass_matrix%matvec(dense%shapes(:, j), mphi)
            overlap(:, j) = matmul(transpose(arpack%shapes), mphi)
        end do
        do j = 1, dense%count
            overlap(j, j) = abs(overlap(j, j)) - 1.0_wp
        end do
        call check(error, maxval(abs(overlap)) < 1.0e-7_wp, 'shapes agree up to sign')
    end subroutine test_arpack

    !> A box a x b x c of density ρ: mass ρabc, centre at its middle,
    !> ∫ρ X Xᵀ = ρabc diag(a², b², c²)/12 (exact: the trilinear field
    !> reproduces X, and the consistent mass integrates N_i N_j exactly).
    subroutine test_invariants(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(node_set_t), allocatable :: faces(:)
        type(modal_invariants_t) :: inv
        type(status_t) :: status
        real(wp) :: m, expected(3, 3)
        real(wp), allocatable :: none(:, :)
        integer :: i
        call modal_test_body([3, 2, 2], body, faces, status)
        call check(error, status%ok(), 'body: ' // status%text())
        if (allocated(error)) return
        allocate (none(3 * body%mesh%node_count(), 0))
        inv = modal_invariants(body%mass_matrix, body%mesh%x, none)
        m = body%materials(1)%density * product(bar)
        call check_close(error, inv%mass, m, 1.0e-13_wp, 'mass', rel=.true.)
        do i = 1, 3
            call check_close(error, inv%centre(i), bar(i) / 2, 1.0e-13_wp * bar(1), 'centre')
        end do
        expected = 0.0_wp
        do i = 1, 3
            expected(i, i) = m * bar(i)**2 / 12
        end do
        call check(error, maxval(abs(inv%second - expected)) < 1.0e-13_wp * expected(1, 1), &
                   'second moments')
    end subroutine test_invariants

    !> One interface and k = 0: no elastic coordinate (a rigid body); two
    !> interfaces and k = 0: their six relative static modes.
    subroutine test_counts(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(node_set_t), allocatable :: faces(:)
        type(modal_basis_t) :: basis
        type(status_t) :: status
        call modal_test_body([4, 1, 1], body, faces, status)
        if (status%ok()) call craig_bampton(body, faces(1:1), 0, basis, status)
        call check(error, status%ok() .and. basis%count == 0, 'one interface, k = 0: rigid')
        if (allocated(error)) return
        call craig_bampton(body, faces(1:1), 3, basis, status)
        call check(error, status%ok() .and. basis%count == 3, 'one interface, k = 3')
        call craig_bampton(body, faces, 0, basis, status)
        call check(error, status%ok() .and. basis%count == 6, 'two interfaces, k = 0: 6')
        call check(error, all(basis%frequencies > 0.0_wp), 'static modes are elastic')
    end subroutine test_counts

    !> Too many modes, overlapping interfaces, an interface on a line, no
    !> interface, a body with fixed nodes: refused with the value named.
    subroutine test_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body, held
        type(node_set_t), allocatable :: faces(:)
        type(node_set_t) :: both(2), line(1)
        type(modal_basis_t) :: basis
        type(status_t) :: status
        type(neo_hooke_t) :: material
        call modal_test_body([4, 1, 1], body, faces, status)
        call craig_bampton(body, faces, 1000, basis, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'modes = 1000') > 0 .and. &
                   index(status%text(), 'allows 0 to 36') > 0, 'too many modes: ' // status%text())
        both(1) = faces(1)
        both(2) = faces(1)
        both(2)%name = 'copy'
        both(2)%nodes = [faces(1)%nodes(1), faces(2)%nodes]
        call craig_bampton(body, both, 2, basis, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), "'copy'") > 0, 'overlap: ' // status%text())
        line(1)%name = 'edge'
        line(1)%nodes = faces(1)%nodes(1:2)
        call body%mesh%node_set('xmin_ymin', line(1)%nodes, status)
        call craig_bampton(body, line, 2, basis, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), "'edge'") > 0 .and. index(status%text(), 'line') > 0, &
                   'collinear: ' // status%text())
        call craig_bampton(body, faces(1:0), 2, basis, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'no interface') > 0, 'none: ' // status%text())
        call paper_material(material)
        call new_flexible_body(held, body%mesh, [material], faces(1)%nodes, status)
        call craig_bampton(held, faces(2:2), 2, basis, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'fixed') > 0, 'fixed nodes: ' // status%text())
    end subroutine test_bad_input
end module test_modal_basis
