!> The floating-frame modal body (mbs/modal_body): its analytic
!> derivatives against central differences, the formulation's Jacobian
!> against differences, k = 0 on one interface against a rigid body of the
!> same mass and inertia, and a free undamped body's linear momentum (to
!> round-off), angular momentum and energy (to 10 rtol) under every solver.
module test_modal_body
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: real_text
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_mexax, only: mexax_t
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t, node_set_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_fe_modal_basis, only: modal_basis_t, craig_bampton
    use flexmbs_fe_modal_invariants, only: modal_invariants
    use flexmbs_mbs_rotation, only: quat_from_axis_angle, skew
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs
    use flexmbs_mbs_rigid_body, only: rigid_body_t, rigid_bodies_t, new_rigid_bodies
    use flexmbs_mbs_modal_body, only: modal_body_t, new_modal_body
    use test_formulation, only: difference_jacobian
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_modal_body, new_test_modal_body, allocate_solver

    real(wp), parameter :: bar(3) = [0.6_wp, 0.08_wp, 0.05_wp]

contains

    function collect_modal_body() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('derivatives_vs_differences', test_derivatives), &
                 new_test('power_balance', test_power), &
                 new_test('formulation_jacobian_vs_differences', test_jacobian), &
                 new_test('no_modes_one_interface_is_rigid', test_rigid), &
                 new_test('free_body_conserves_every_solver', test_conservation), &
                 new_test('clamped_static_deflection_converges', test_static)]
    end function collect_modal_body

    !> A modal bar (hex8, divisions d) with k fixed-interface modes on the
    !> interfaces `faces`, viscosity η [Pa s] (0: undamped).
    subroutine new_test_modal_body(divisions, faces, k, viscosity, body, status, gravity)
        integer, intent(in) :: divisions(3), k
        character(len=*), intent(in) :: faces(:)
        real(wp), intent(in) :: viscosity
        type(modal_body_t), intent(out) :: body
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: gravity(3)
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        type(flexible_body_t) :: fe
        type(node_set_t), allocatable :: sets(:)
        type(modal_basis_t) :: basis
        integer :: j
        call box_mesh(mesh, hex8, divisions, bar, status)
        if (status%ok()) call new_neo_hooke(material, 7.0e5_wp, 0.3_wp, 920.0_wp, viscosity, &
                                            status)
        if (status%ok()) call new_flexible_body(fe, mesh, [material], [integer ::], status)
        if (.not. status%ok()) return
        allocate (sets(size(faces)))
        do j = 1, size(faces)
            sets(j)%name = trim(faces(j))
            call mesh%node_set(trim(faces(j)), sets(j)%nodes, status)
            if (.not. status%ok()) return
        end do
        call craig_bampton(fe, sets, k, basis, status)
        if (.not. status%ok()) return
        call new_modal_body(body, basis, modal_invariants(fe%mass_matrix, fe%mesh%x, &
                            basis%shapes), status, gravity, fe=fe)
    end subroutine new_test_modal_body

    !> Solver s of RADAU5, DDASSL, IDA, MEXAX.
    subroutine allocate_solver(s, solver)
        integer, intent(in) :: s
        class(dae_solver_t), allocatable, intent(out) :: solver
        select case (s)
        case (1)
            allocate (radau5_t :: solver)
        case (2)
            allocate (ddassl_t :: solver)
        case (3)
            allocate (ida_t :: solver)
        case default
            allocate (mexax_t :: solver)
        end select
    end subroutine allocate_solver

    !> A state with every term awake: off-unit quaternion excluded, η of
    !> the size of a visible deflection.
    subroutine test_state(body, q, v)
        type(modal_body_t), intent(in) :: body
        real(wp), allocatable, intent(out) :: q(:), v(:)
        integer :: j
        allocate (q(body%nq), v(body%nv))
        q(1:3) = [0.3_wp, -0.1_wp, 0.2_wp]
        q(4:7) = quat_from_axis_angle([1.0_wp, 2.0_wp, -0.5_wp] / norm2([1.0_wp, 2.0_wp, &
                                      -0.5_wp]), 0.7_wp)
        do j = 1, body%modes
            q(7 + j) = 0.01_wp * sin(1.7_wp * j)
        end do
        do j = 1, body%nv
            v(j) = cos(0.9_wp * j)
        end do
    end subroutine test_state

    !> ∂(M w)/∂q, ∂f/∂q, ∂f/∂v and ∂(T w)/∂q against central differences.
    subroutine test_derivatives(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), w(:), mq(:, :), fq(:, :), fv(:, :), kq(:, :), &
            dm(:, :), dfq(:, :), dfv(:, :), dkq(:, :), mp(:, :), mm(:, :), fp(:), fm(:), &
            tp(:), tm(:), qs(:), vs(:)
        real(wp), parameter :: delta = 1.0e-6_wp
        integer :: j
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin', 'xmax'], 3, &
                                 1000.0_wp, body, status, gravity=[0.0_wp, -9.81_wp, 0.0_wp])
        call check(error, status%ok() .and. body%modes == 9, 'body: ' // status%text())
        if (allocated(error)) return
        call test_state(body, q, v)
        w = v(body%nv:1:-1)
        allocate (mq(body%nv, body%nq), fq(body%nv, body%nq), fv(body%nv, body%nv), &
                  kq(body%nq, body%nq), dm(body%nv, body%nq), dfq(body%nv, body%nq), &
                  dfv(body%nv, body%nv), dkq(body%nq, body%nq))
        allocate (mp(body%nv, body%nv), mm(body%nv, body%nv), fp(body%nv), fm(body%nv), &
                  tp(body%nq), tm(body%nq))
        call body%mass_derivative(0.0_wp, q, w, mq, status)
        call body%force_derivatives(0.0_wp, q, v, fq, fv, status)
        call body%kinematics_derivative(0.0_wp, q, w, kq, status)
        do j = 1, body%nq
            qs = q
            qs(j) = q(j) + delta
            call body%mass(0.0_wp, qs, mp, status)
            call body%forces(0.0_wp, qs, v, fp, status)
            call body%kinematics(0.0_wp, qs, w, tp, status)
            qs(j) = q(j) - delta
            call body%mass(0.0_wp, qs, mm, status)
            call body%forces(0.0_wp, qs, v, fm, status)
            call body%kinematics(0.0_wp, qs, w, tm, status)
            dm(:, j) = matmul(mp - mm, w) / (2 * delta)
            dfq(:, j) = (fp - fm) / (2 * delta)
            dkq(:, j) = (tp - tm) / (2 * delta)
        end do
        do j = 1, body%nv
            vs = v
            vs(j) = v(j) + delta
            call body%forces(0.0_wp, q, vs, fp, status)
            vs(j) = v(j) - delta
            call body%forces(0.0_wp, q, vs, fm, status)
            dfv(:, j) = (fp - fm) / (2 * delta)
        end do
        call check(error, maxval(abs(mq - dm)) <= 1.0e-7_wp * maxval(abs(dm)), &
                   'd(M w)/dq: ' // real_text(maxval(abs(mq - dm)) / maxval(abs(dm))))
        call check(error, maxval(abs(fq - dfq)) <= 1.0e-7_wp * maxval(abs(dfq)), &
                   'df/dq: ' // real_text(maxval(abs(fq - dfq)) / maxval(abs(dfq))))
        call check(error, maxval(abs(fv - dfv)) <= 1.0e-7_wp * maxval(abs(dfv)), &
                   'df/dv: ' // real_text(maxval(abs(fv - dfv)) / maxval(abs(dfv))))
        call check(error, maxval(abs(kq - dkq)) <= 1.0e-8_wp, 'd(T w)/dq')
        call check(error, maxval(abs(dm(:, 1:7))) == 0.0_wp .and. &
                   maxval(abs(dfq(:, 1:7))) == 0.0_wp, 'M and f free of r and p')
    end subroutine test_derivatives

    !> Undamped and unloaded, the inertia forces do no work: dE/dt = vᵀ f +
    !> ½ vᵀ Ṁ v + Σ ω_l² η_l η̇_l = 0 at any state (Ṁ v = ∂(M v)/∂q q̇).
    subroutine test_power(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), f(:), qd(:), mq(:, :)
        real(wp) :: power, scale
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin', 'xmax'], 3, &
                                 0.0_wp, body, status)
        call check(error, status%ok(), 'body: ' // status%text())
        if (allocated(error)) return
        call test_state(body, q, v)
        allocate (f(body%nv), qd(body%nq), mq(body%nv, body%nq))
        call body%forces(0.0_wp, q, v, f, status)
        call body%kinematics(0.0_wp, q, v, qd, status)
        call body%mass_derivative(0.0_wp, q, v, mq, status)
        power = dot_product(v, f) + 0.5_wp * dot_product(v, matmul(mq, qd)) + &
            dot_product(body%stiffness * q(8:), v(7:))
        scale = sum(abs(v * f))
        call check(error, abs(power) <= 1.0e-12_wp * scale, 'dE/dt = ' // real_text(power) // &
                   ' against terms of ' // real_text(scale))
    end subroutine test_power

    !> The index-2 formulation's analytic Jacobian against differences of F.
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_body_t), target :: body
        type(formulation_t) :: gen
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), y(:), jac(:, :), jfd(:, :)
        integer :: j
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin', 'xmax'], 2, &
                                 1000.0_wp, body, status, gravity=[0.0_wp, 0.0_wp, -9.81_wp])
        call check(error, status%ok(), 'body: ' // status%text())
        if (allocated(error)) return
        call test_state(body, q, v)
        gen = new_formulation(body, formulation_index2, q, status=status)
        call check(error, status%ok(), 'formulation: ' // status%text())
        if (allocated(error)) return
        allocate (y(gen%n), jac(gen%n, gen%n), jfd(gen%n, gen%n))
        do j = 1, gen%n
            y(j) = 0.3_wp * sin(1.3_wp * j)
        end do
        y(1:body%nq) = q
        y(body%nq + 1:body%nq + body%nv) = v
        call gen%jacobian_dense(0.0_wp, y, jac, status)
        call difference_jacobian(gen, y, jfd, status)
        call check(error, status%ok() .and. maxval(abs(jac - jfd)) <= 1.0e-7_wp * &
                   maxval(abs(jfd)), 'Jacobian vs central differences: ' // &
                   real_text(maxval(abs(jac - jfd)) / maxval(abs(jfd))))
    end subroutine test_jacobian

    !> One interface and k = 0: M and f equal those of a rigid body with
    !> the box's mass ρabc and inertia m diag(b² + c², a² + c², a² + b²)/12.
    subroutine test_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_body_t) :: body
        type(rigid_bodies_t) :: rigid
        type(rigid_body_t) :: one
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:)
        real(wp) :: m(6, 6), mr(6, 6), f(6), fr(6), g(3)
        g = [0.0_wp, -9.81_wp, 0.0_wp]
        call new_test_modal_body([3, 2, 2], [character(len=4) :: 'xmin'], 0, 1000.0_wp, &
                                 body, status, gravity=g)
        call check(error, status%ok() .and. body%modes == 0 .and. body%nq == 7, &
                   'k = 0 on one interface: ' // status%text())
        if (allocated(error)) return
        one%mass = 920.0_wp * product(bar)
        one%inertia = 0.0_wp
        one%inertia(1, 1) = one%mass * (bar(2)**2 + bar(3)**2) / 12
        one%inertia(2, 2) = one%mass * (bar(1)**2 + bar(3)**2) / 12
        one%inertia(3, 3) = one%mass * (bar(1)**2 + bar(2)**2) / 12
        rigid = new_rigid_bodies([one], gravity=g, status=status)
        call test_state(body, q, v)
        call body%mass(0.0_wp, q, m, status)
        call rigid%mass(0.0_wp, q, mr, status)
        call body%forces(0.0_wp, q, v, f, status)
        call rigid%forces(0.0_wp, q, v, fr, status)
        call check(error, maxval(abs(m - mr)) <= 1.0e-13_wp * maxval(abs(mr)), 'M: ' // &
                   real_text(maxval(abs(m - mr)) / maxval(abs(mr))))
        call check(error, maxval(abs(f - fr)) <= 1.0e-13_wp * maxval(abs(fr)), 'f: ' // &
                   real_text(maxval(abs(f - fr)) / maxval(abs(fr))))
    end subroutine test_rigid

    !> A free, undamped, spinning and vibrating modal bar without gravity,
    !> 0.4 s, by RADAU5, DDASSL, IDA (index 2) and MEXAX: linear momentum
    !> to round-off, angular momentum and energy within 10 rtol.
    subroutine test_conservation(error)
        type(error_t), allocatable, intent(out) :: error
        type(modal_body_t), target :: body
        type(formulation_t) :: gen
        class(dae_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), y(:), yp(:)
        real(wp) :: l0(3), h0(3), e0, l1(3), h1(3), e1, t, de, dh, dl
        real(wp), parameter :: rtol = 1.0e-8_wp, t_end = 0.4_wp
        integer :: s
        character(len=6), parameter :: names(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        call new_test_modal_body([4, 1, 1], [character(len=4) :: 'xmin', 'xmax'], 2, &
                                 0.0_wp, body, status)
        call check(error, status%ok(), 'body: ' // status%text())
        if (allocated(error)) return
        call test_state(body, q, v)
        ! the two lowest modes excited, the others driven by the spin alone:
        ! with every mode excited, RADAU5 at this rtol lost 2.0e-6 of the
        ! energy (its steps damp the upper modes, up to 590 rad/s)
        q(10:) = 0.0_wp
        v(9:) = 0.0_wp
        v(7:8) = 0.05_wp
        print '(a)', '    frequencies [rad/s] ' // real_text(body%stiffness(1)**0.5_wp) // ' .. ' &
            // real_text(body%stiffness(body%modes)**0.5_wp)
        call body%momenta(q, v, l0, h0)
        e0 = body%total_energy(q, v)
        options%rtol = rtol
        options%atol = rtol
        do s = 1, 4
            call allocate_solver(s, solver)
            t = 0.0_wp
            if (s < 4) then
                gen = new_formulation(body, formulation_index2, q, status=status)
                allocate (y(gen%n), yp(gen%n), source=0.0_wp)
                y(1:body%nq) = q
                y(body%nq + 1:body%nq + body%nv) = v
                if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
                if (status%ok()) call solver%integrate(gen, t, y, t_end, options, stats, status)
            else
                allocate (y(body%nq + body%nv), yp(0))
                y(1:body%nq) = q
                y(body%nq + 1:) = v
                select type (solver)
                type is (mexax_t)
                    call solver%integrate_mechanical(body, t, y(1:body%nq), y(body%nq + 1:), &
                                                     t_end, options, stats, status)
                end select
            end if
            call check(error, status%ok(), names(s) // ': ' // status%text())
            if (allocated(error)) return
            call body%momenta(y(1:body%nq), y(body%nq + 1:body%nq + body%nv), l1, h1)
            e1 = body%total_energy(y(1:body%nq), y(body%nq + 1:body%nq + body%nv))
            dl = norm2(l1 - l0) / norm2(l0)
            dh = norm2(h1 - h0) / norm2(h0)
            de = abs(e1 - e0) / abs(e0)
            print '(a)', '    ' // names(s) // ': linear ' // real_text(dl) // ', angular ' // &
                real_text(dh) // ', energy ' // real_text(de)
            call check(error, dl <= 1.0e-13_wp, names(s) // ': linear momentum ' // &
                       real_text(dl))
            call check(error, dh <= 10 * rtol, names(s) // ': angular momentum ' // &
                       real_text(dh))
            call check(error, de <= 10 * rtol, names(s) // ': energy ' // real_text(de))
            deallocate (solver, y, yp)
        end do
    end subroutine test_conservation

    !> A cantilever clamped at its xmin interface under gravity: the modal
    !> body's linear static deflection converges to the linear FE one of the
    !> same mesh clamped there as k grows, and equals it with every mode.
    !> Statics of the modal body: the interface held, δθ = −Θη and
    !> δt = −Uη − δθ × d; gravity works on r alone, so η minimises
    !> ½ ηᵀ diag(ω²) η + m gᵀ (U η + d̃ Θ η): diag(ω²) η = −m (Uᵀ g − Θᵀ d̃ g);
    !> a node moves by δt + δθ × (X − c) + Φ η.
    subroutine test_static(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: ks(5) = [1, 2, 4, 8, 72]
        real(wp), parameter :: g(3) = [0.0_wp, -9.81_wp, 0.0_wp]
        type(modal_body_t) :: body
        type(status_t) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: material
        type(flexible_body_t) :: clamped
        integer, allocatable :: xmin(:), xmax(:), ipiv(:)
        real(wp), allocatable :: k(:, :), u_fe(:), eta(:), u(:)
        real(wp) :: tip_fe, tip(size(ks)), dt(3), dth(3), d(3), rhs(1)
        integer :: info, l, node, nf, j
        call box_mesh(mesh, hex8, [6, 1, 1], bar, status)
        if (status%ok()) call new_neo_hooke(material, 7.0e5_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        if (status%ok()) call mesh%node_set('xmin', xmin, status)
        if (status%ok()) call mesh%node_set('xmax', xmax, status)
        if (status%ok()) call new_flexible_body(clamped, mesh, [material], xmin, status, &
                                                gravity=g)
        if (status%ok()) call clamped%assemble_tangents(clamped%free_positions(), &
            spread(0.0_wp, 1, clamped%nv), status)
        call check(error, status%ok(), 'FE: ' // status%text())
        if (allocated(error)) return
        nf = clamped%nv
        allocate (k(nf, nf), ipiv(nf))
        call clamped%stiffness%to_dense(k)
        u_fe = clamped%applied_force
        call dgetrf(nf, nf, k, nf, ipiv, info)
        if (info == 0) call dgetrs('N', nf, 1, k, nf, ipiv, u_fe, nf, info)
        call check(error, info == 0, 'FE solve')
        if (allocated(error)) return
        ! the tip: the mean y displacement of the xmax face
        tip_fe = 0.0_wp
        do j = 1, size(xmax)
            tip_fe = tip_fe + u_fe(clamped%dof(2, xmax(j))) / size(xmax)
        end do
        do l = 1, size(ks)
            call new_test_modal_body([6, 1, 1], [character(len=4) :: 'xmin'], ks(l), 0.0_wp, &
                                     body, status, gravity=g)
            call check(error, status%ok(), 'modal: ' // status%text())
            if (allocated(error)) return
            associate (uu => body%interface_motion(1:3, :, 1), th => body%interface_motion(4:6, :, 1))
                d = body%interface_offset(:, 1)
                eta = -body%total_mass * (matmul(transpose(uu), g) - &
                                          matmul(transpose(th), matmul(skew(d), g))) / body%stiffness
                dth = -matmul(th, eta)
                dt = -matmul(uu, eta) + matmul(skew(d), dth)
            end associate
            u = matmul(body%shapes, eta)
            tip(l) = 0.0_wp
            do j = 1, size(xmax)
                node = xmax(j)
                rhs = dt(2) + dth(3) * body%reference(1, node) - dth(1) * body%reference(3, node) &
                    + u(3 * node - 1)
                tip(l) = tip(l) + rhs(1) / size(xmax)
            end do
        end do
        print '(4x,a,es11.4,a,5es10.2)', 'clamped static tip deflection: FE ', tip_fe, &
            ', modal error (k = 1, 2, 4, 8, all) ', abs(tip - tip_fe) / abs(tip_fe)
        call check(error, all(abs(tip(2:) - tip_fe) <= abs(tip(:size(ks) - 1) - tip_fe) * &
                   (1.0_wp + 1.0e-9_wp)), 'the error does not fall with k')
        call check(error, abs(tip(size(ks)) - tip_fe) <= 1.0e-9_wp * abs(tip_fe), &
                   'every mode: not the FE deflection')
        ! mode 1 bends the bar about y (its thinner side), mode 2 along g
        call check(error, abs(tip(2) - tip_fe) <= 0.05_wp * abs(tip_fe), &
                   'two modes: more than 5 % off')
    end subroutine test_static
end module test_modal_body
