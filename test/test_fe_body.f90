!> Flexible bodies assembled from box meshes: mass, gravity, rigid motion,
!> assembled tangents in the fixed CSC pattern, the mechanical-problem face.
module test_fe_body
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_det_f
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use test_problems, only: fill_random
    use test_fe, only: random_rotation, paper_material
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_fe_body

    integer, parameter :: element_kinds(2) = [hex8, hex27]
    real(wp), parameter :: box(3) = [0.4_wp, 0.1_wp, 0.2_wp]
    integer, parameter :: divisions(3) = [3, 1, 2]

contains

    function collect_fe_body() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('total_mass_and_gravity', test_mass_gravity), &
                 new_test('rigid_motion_zero_force', test_body_rigid), &
                 new_test('tangents_fd', test_body_tangents), &
                 new_test('det_f_names_element', test_body_det_f), &
                 new_test('bad_fixed_node', test_bad_fixed), &
                 new_test('momenta_kinetic_energy', test_momenta), &
                 new_test('strain_energy_gradient', test_strain_energy), &
                 new_test('tip_layers_and_nodal_loads', test_tip_layers), &
                 new_test('formulation_jacobian_fd', test_formulation_jacobian), &
                 new_test('element_stress_analytic', test_element_stress)]
    end function collect_fe_body

    subroutine make_body(kind, fixed_face, body, status, gravity, origin)
        integer, intent(in) :: kind
        character(len=*), intent(in) :: fixed_face  !! '' for a free body
        type(flexible_body_t), intent(out) :: body
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: gravity(3), origin(3)
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        integer, allocatable :: fixed(:)
        call paper_material(mat)
        call box_mesh(mesh, element_kinds(kind), divisions, box, status, origin)
        if (.not. status%ok()) return
        allocate (fixed(0))
        if (len(fixed_face) > 0) call mesh%node_set(fixed_face, fixed, status)
        if (.not. status%ok()) return
        call new_flexible_body(body, mesh, [mat], fixed, status, gravity)
    end subroutine make_body

    !> Free body: M sums to 3 ρ V (one ρ V per direction), M·1 per direction
    !> and the gravity force at rest sum to m g; nc = 0, nq = nv = 3 nodes.
    !> Clamped body: the free rows lose the fixed nodes only.
    subroutine test_mass_gravity(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: f(:), q(:), v(:), ones(:), mv(:)
        real(wp) :: g(3), total
        integer :: kind, i
        g = [0.0_wp, -9.81_wp, 2.0_wp]
        do kind = 1, 2
            call make_body(kind, '', body, status, g)
            call check(error, status%ok(), 'free body')
            if (allocated(error)) return
            total = body%materials(1)%density * product(box)
            call check(error, body%nc == 0 .and. body%nq == 3 * body%mesh%node_count() &
                       .and. body%nv == body%nq, 'sizes of a free body')
            call check_close(error, sum(body%mass_matrix%values), 3 * total, 1.0e-13_wp, &
                             'sum of M = 3 rho V', rel=.true.)
            ones = [(merge(1.0_wp, 0.0_wp, mod(i, 3) == 1), i=1, body%nv)]
            allocate (mv(body%nv))
            call body%mass_matrix%matvec(ones, mv)
            call check_close(error, sum(mv), total, 1.0e-13_wp, 'M e_x sums to m', rel=.true.)
            q = body%free_positions()
            allocate (v(body%nv), source=0.0_wp)
            allocate (f(body%nv))
            call body%forces(0.0_wp, q, v, f, status)
            call check(error, status%ok(), 'forces at rest')
            do i = 1, 3
                call check_close(error, sum(f(i::3)), total * g(i), 1.0e-12_wp * total * 10, &
                                 'resultant = m g at rest')
            end do
            deallocate (mv, v, f)
            call make_body(kind, 'xmin', body, status)
            call check(error, status%ok() .and. body%nq == 3 * (body%mesh%node_count() &
                       - (kind * divisions(2) + 1) * (kind * divisions(3) + 1)), &
                       'clamped face removed from q')
        end do
    end subroutine test_mass_gravity

    !> Rotation + translation with a rigid velocity field on the assembled
    !> free mesh: internal (elastic + viscous) force zero to round-off
    !> relative to μ L².
    subroutine test_body_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), k(:)
        real(wp) :: r(3, 3), omega(3, 3), w(3), t(3), scale
        integer(i8) :: seed
        integer :: kind, i
        character(len=60) :: buf
        seed = 41_i8
        do kind = 1, 2
            call make_body(kind, '', body, status)
            q = body%free_positions()
            call random_rotation(seed, r)
            call fill_random(w, seed, -5.0_wp, 5.0_wp)
            omega = reshape([0.0_wp, w(3), -w(2), -w(3), 0.0_wp, w(1), w(2), -w(1), 0.0_wp], &
                            [3, 3])
            call fill_random(t, seed, -10.0_wp, 10.0_wp)
            allocate (v(body%nv), k(body%nv))
            do i = 1, body%nv / 3
                v(3 * i - 2:3 * i) = matmul(matmul(omega, r), q(3 * i - 2:3 * i)) + w
                q(3 * i - 2:3 * i) = matmul(r, q(3 * i - 2:3 * i)) + t
            end do
            call body%internal_forces(q, v, k, status)
            call check(error, status%ok(), 'rigid motion admissible')
            scale = body%materials(1)%mu * maxval(box)**2
            write (buf, '(a,es10.2)') ': |k| / mu L^2 = ', maxval(abs(k)) / scale
            call check(error, maxval(abs(k)) <= 1.0e-11_wp * scale, 'rigid motion' // trim(buf))
            deallocate (v, k)
        end do
    end subroutine test_body_rigid

    !> Assembled ∂k/∂q and ∂k/∂v in the CSC pattern against central differences
    !> of the assembled force, clamped body, random deformation and velocity.
    subroutine test_body_tangents(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), k(:), kp(:), km(:), dq(:), kd(:, :), cd(:, :), &
            fd_k(:, :), fd_c(:, :), h(:)
        real(wp), parameter :: h_q = 1.0e-7_wp, h_v = 1.0e-4_wp
        real(wp) :: dev_k, dev_c
        integer(i8) :: seed
        integer :: kind, j, n
        character(len=80) :: buf
        seed = 42_i8
        do kind = 1, 2
            call make_body(kind, 'xmin', body, status)
            n = body%nv
            q = body%free_positions()
            allocate (dq(n), v(n), k(n), kp(n), km(n), kd(n, n), cd(n, n), fd_k(n, n), fd_c(n, n))
            call fill_random(dq, seed, -0.01_wp, 0.01_wp)
            q = q + dq
            call fill_random(v, seed, -0.5_wp, 0.5_wp)
            call body%tangents(q, v, k, status)
            call check(error, status%ok(), 'deformed body admissible')
            call body%stiffness%to_dense(kd)
            call body%damping%to_dense(cd)
            do j = 1, n
                h = q
                h(j) = q(j) + h_q
                call body%internal_forces(h, v, kp, status)
                h(j) = q(j) - h_q
                call body%internal_forces(h, v, km, status)
                fd_k(:, j) = (kp - km) / (2 * h_q)
                h = v
                h(j) = v(j) + h_v
                call body%internal_forces(q, h, kp, status)
                h(j) = v(j) - h_v
                call body%internal_forces(q, h, km, status)
                fd_c(:, j) = (kp - km) / (2 * h_v)
            end do
            dev_k = maxval(abs(kd - fd_k)) / maxval(abs(kd))
            dev_c = maxval(abs(cd - fd_c)) / maxval(abs(cd))
            write (buf, '(a,2es10.2)') ': relative deviation K, C =', dev_k, dev_c
            call check(error, dev_k <= 1.0e-6_wp, 'assembled stiffness' // trim(buf))
            call check(error, dev_c <= 1.0e-6_wp, 'assembled damping' // trim(buf))
            call check(error, body%stiffness%nnz < int(n, i8) * n, 'pattern is sparse')
            deallocate (dq, v, k, kp, km, kd, cd, fd_k, fd_c)
        end do
    end subroutine test_body_tangents

    !> An inverted configuration fails with reason_det_f and names the element.
    subroutine test_body_det_f(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), f(:)
        call make_body(1, '', body, status)
        q = body%free_positions()
        q(1::3) = -q(1::3)
        allocate (v(body%nv), source=0.0_wp)
        allocate (f(body%nv))
        call body%forces(0.0_wp, q, v, f, status)
        call check(error, status%code == status_solver_failure .and. &
                   status%reason == reason_det_f, 'reason_det_f')
        call check(error, index(status%text(), 'element 1') > 0, 'message names the element')
    end subroutine test_body_det_f

    subroutine test_bad_fixed(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        call paper_material(mat)
        call box_mesh(mesh, hex8, [1, 1, 1], [1.0_wp, 1.0_wp, 1.0_wp], status)
        call new_flexible_body(body, mesh, [mat], [1, 9], status)
        call check(error, .not. status%ok() .and. index(status%text(), 'fixed node 9') > 0, &
                   'fixed node outside the mesh')
    end subroutine test_bad_fixed

    !> Box centred at the origin moving rigidly with ẋ = ω × x + w: linear
    !> momentum m w, angular momentum I ω with I = m/12 diag(b²+c², a²+c², a²+b²),
    !> kinetic energy m|w|²/2 + ωᵀIω/2, exactly.
    subroutine test_momenta(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:)
        real(wp) :: omega(3), w(3), linear(3), angular(3), inertia(3), total
        integer(i8) :: seed
        integer :: kind, i
        seed = 43_i8
        do kind = 1, 2
            call make_body(kind, '', body, status, origin=-0.5_wp * box)
            q = body%free_positions()
            call fill_random(omega, seed, -3.0_wp, 3.0_wp)
            call fill_random(w, seed, -2.0_wp, 2.0_wp)
            allocate (v(body%nv))
            do i = 1, body%nv / 3
                associate (x => q(3 * i - 2:3 * i))
                    v(3 * i - 2:3 * i) = [omega(2) * x(3) - omega(3) * x(2), &
                                          omega(3) * x(1) - omega(1) * x(3), &
                                          omega(1) * x(2) - omega(2) * x(1)] + w
                end associate
            end do
            total = body%materials(1)%density * product(box)
            inertia = total / 12 * [box(2)**2 + box(3)**2, box(1)**2 + box(3)**2, &
                                    box(1)**2 + box(2)**2]
            call body%momenta(q, v, linear, angular)
            call check(error, maxval(abs(linear - total * w)) <= 1.0e-13_wp * total * norm2(w), &
                       'linear momentum m w')
            call check(error, maxval(abs(angular - inertia * omega)) <= 1.0e-13_wp &
                       * maxval(inertia) * norm2(omega), 'angular momentum I omega')
            call check_close(error, body%kinetic_energy(v), 0.5_wp * total * dot_product(w, w) &
                             + 0.5_wp * dot_product(omega, inertia * omega), 1.0e-13_wp, &
                             'kinetic energy', rel=.true.)
            deallocate (v)
        end do
    end subroutine test_momenta

    !> The elastic force is the gradient of the strain energy (v = 0), and the
    !> strain energy of the reference configuration is zero.
    subroutine test_strain_energy(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), k(:), dq(:), fd(:)
        real(wp), parameter :: h = 1.0e-7_wp
        real(wp) :: qj
        integer(i8) :: seed
        integer :: kind, j
        seed = 44_i8
        do kind = 1, 2
            call make_body(kind, 'zmin', body, status)
            q = body%free_positions()
            ! W ≈ μ tr E with E of round-off size at the reference state.
            call check(error, abs(body%strain_energy(q, status)) <= 1.0e-12_wp &
                       * body%materials(1)%mu * product(box), 'U(X) = 0')
            allocate (dq(body%nq), v(body%nv), k(body%nv), fd(body%nv), source=0.0_wp)
            call fill_random(dq, seed, -0.01_wp, 0.01_wp)
            q = q + dq
            call body%internal_forces(q, v, k, status)
            do j = 1, body%nq
                qj = q(j)
                q(j) = qj + h
                fd(j) = body%strain_energy(q, status)
                q(j) = qj - h
                fd(j) = (fd(j) - body%strain_energy(q, status)) / (2 * h)
                q(j) = qj
            end do
            call check(error, maxval(abs(fd - k)) <= 1.0e-6_wp * maxval(abs(k)), &
                       'k_el = dU/dq')
            ! the mechanical problem's energy binding: U + T - f·(q - q_ref)
            v = 1.0e-3_wp
            associate (u => body%strain_energy(q, status), t => body%kinetic_energy(v))
                call check(error, abs(body%total_energy(q, v, q) - (u + t)) <= &
                           1.0e-12_wp * (u + t), 'total energy from q_ref = q')
                call check(error, abs(body%total_energy(q, v) - (u + t - dot_product( &
                           body%applied_force, q - body%free_positions()))) <= 1.0e-12_wp * &
                           (u + t), 'total energy from the reference configuration')
            end associate
            deallocate (dq, v, k, fd)
        end do
    end subroutine test_strain_energy

    !> The paper's two materials: soft body with stiff top and bottom element
    !> layers; the mass adds up per layer, a wrong material number is bad
    !> input, and a nodal load enters f at rest.
    subroutine test_tip_layers(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mats(2)
        type(status_t) :: status
        integer, allocatable :: which(:), fixed(:)
        real(wp), allocatable :: q(:), v(:), f(:)
        integer :: layers
        call paper_material(mats(1))
        call new_neo_hooke(mats(2), 1.0e7_wp, 0.3_wp, 1000.0_wp, 1000.0_wp, status)
        layers = 4
        call box_mesh(mesh, hex27, [1, 1, layers], [0.1_wp, 0.1_wp, 0.4_wp], status)
        allocate (which(mesh%element_count()), source=1)
        ! elements are numbered x fastest, z slowest: first and last layer
        which(1) = 2
        which(mesh%element_count()) = 2
        call mesh%node_set('zmin', fixed, status)
        call new_flexible_body(body, mesh, mats, fixed, status, element_material=which)
        call check(error, status%ok(), 'body with tip layers')
        ! Free mass: the sum of M over free dofs misses the fixed nodes' rows,
        ! so compare on a free body instead.
        call new_flexible_body(body, mesh, mats, [integer ::], status, element_material=which)
        call check_close(error, sum(body%mass_matrix%values), &
                         3 * 0.1_wp * 0.1_wp * 0.1_wp * (2 * 1000.0_wp + 2 * 920.0_wp), &
                         1.0e-13_wp, 'layered mass', rel=.true.)
        q = body%free_positions()
        allocate (v(body%nv), source=0.0_wp)
        allocate (f(body%nv))
        call body%add_nodal_load(mesh%node_count(), [1.0_wp, -2.0_wp, 3.0_wp], status)
        call body%forces(0.0_wp, q, v, f, status)
        call check(error, maxval(abs(f(body%nv - 2:) - [1.0_wp, -2.0_wp, 3.0_wp])) < 1.0e-6_wp, &
                   'nodal load at rest (internal force at X is round-off)')
        call body%add_nodal_load(0, [1.0_wp, 0.0_wp, 0.0_wp], status)
        call check(error, .not. status%ok(), 'load on node 0 rejected')
        which(2) = 3
        call new_flexible_body(body, mesh, mats, fixed, status, element_material=which)
        call check(error, .not. status%ok() .and. index(status%text(), '1..2') > 0, &
                   'material number 3 of 2 rejected')
    end subroutine test_tip_layers
    !> The body's analytic force derivatives (−∂k/∂q, −∂k/∂v, zero kinematic
    !> and mass derivatives) make the formulation's dense Jacobian equal
    !> central differences of its right-hand side (≤ 1e-6 relative).
    subroutine test_formulation_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t), target :: body
        type(formulation_t) :: dae
        type(status_t) :: status
        real(wp), allocatable :: y(:), jac(:, :), fd(:, :), fp(:), fm(:), yp(:), dq(:)
        real(wp) :: h
        integer(i8) :: seed
        integer :: kind, j, n, nq
        seed = 11_i8
        do kind = 1, 2
            call make_body(kind, 'xmin', body, status, gravity=[0.0_wp, 0.0_wp, -9.81_wp])
            nq = body%nq
            dae = new_formulation(body, formulation_index2, body%free_positions(), &
                                  constant_mass=.true., status=status)
            call check(error, status%ok(), 'formulation: ' // status%text())
            if (allocated(error)) return
            n = dae%n
            allocate (y(n), jac(n, n), fd(n, n), fp(n), fm(n), dq(nq))
            call fill_random(dq, seed, -0.01_wp, 0.01_wp)
            y(1:nq) = body%free_positions() + dq
            call fill_random(y(nq + 1:), seed, -0.5_wp, 0.5_wp)
            call dae%jacobian_dense(0.0_wp, y, jac, status)
            call check(error, status%ok(), 'jacobian: ' // status%text())
            if (allocated(error)) return
            do j = 1, n
                h = merge(1.0e-7_wp, 1.0e-4_wp, j <= nq)
                yp = y
                yp(j) = y(j) + h
                call dae%rhs(0.0_wp, yp, fp, status)
                yp(j) = y(j) - h
                call dae%rhs(0.0_wp, yp, fm, status)
                fd(:, j) = (fp - fm) / (2 * h)
            end do
            call check(error, maxval(abs(jac - fd)) <= 1.0e-6_wp * maxval(abs(jac)), &
                       'formulation Jacobian differs from central differences')
            deallocate (y, jac, fd, fp, fm, dq)
            if (allocated(error)) return
        end do
    end subroutine test_formulation_jacobian
    !> The Cauchy stress of a homogeneous stretch F = diag(s, 1, 1) (hex8 and
    !> hex27, every element): σ_xx = μ (s − 1/s) + λ (s − 1), σ_yy = σ_zz =
    !> λ (s − 1), no shear (S = μ (I − C⁻¹) + λ J (J − 1) C⁻¹, σ = F S Fᵀ/J);
    !> a rigid rotation on top rotates it (σ' = Q σ Qᵀ: von Mises unchanged).
    subroutine test_element_stress(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: kinds(2) = [hex8, hex27]
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), sigma(:, :), mises(:), mises0(:)
        real(wp) :: s, expect(6), qrot(3, 3), dev
        integer :: k, i, node
        integer(i8) :: seed
        s = 1.2_wp
        dev = 0.0_wp
        do k = 1, 2
            call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 1000.0_wp, status)
            call box_mesh(mesh, kinds(k), [2, 1, 1], [0.4_wp, 0.1_wp, 0.1_wp], status)
            call new_flexible_body(body, mesh, [mat], [integer ::], status)
            call check(error, status%ok(), 'body: ' // status%text())
            if (allocated(error)) return
            q = body%free_positions()
            allocate (v(body%nv), source=0.0_wp)
            do node = 1, mesh%node_count()
                q(body%dof(1, node)) = s * mesh%x(1, node)
            end do
            allocate (sigma(6, mesh%element_count()), mises(mesh%element_count()))
            call body%element_stress(q, v, sigma, mises, status)
            call check(error, status%ok(), 'stress: ' // status%text())
            if (allocated(error)) return
            expect = [mat%mu * (s - 1.0_wp / s) + mat%lambda * (s - 1.0_wp), &
                      mat%lambda * (s - 1.0_wp), mat%lambda * (s - 1.0_wp), 0.0_wp, 0.0_wp, 0.0_wp]
            do i = 1, mesh%element_count()
                dev = max(dev, maxval(abs(sigma(:, i) - expect)) / abs(expect(1)))
            end do
            ! the same stretch, rotated: von Mises is invariant
            mises0 = mises
            seed = 3_i8
            call random_rotation(seed, qrot)
            do node = 1, mesh%node_count()
                q(3 * node - 2:3 * node) = matmul(qrot, q(3 * node - 2:3 * node))
            end do
            call body%element_stress(q, v, sigma, mises, status)
            dev = max(dev, maxval(abs(mises - mises0)) / maxval(mises0))
            deallocate (v, sigma, mises)
        end do
        print '(4x,a,es9.2)', 'element stress against the analytic stretch: ', dev
        call check(error, dev <= 1.0e-12_wp, 'element stress differs from the analytic one')
    end subroutine test_element_stress
end module test_fe_body
