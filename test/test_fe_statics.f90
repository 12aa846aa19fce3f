!> Static equilibrium: homogeneous uniaxial tension against the analytic
!> neo-Hookean solution, quadratic convergence of Newton, the small-load
!> cantilever against Timoshenko beam theory under refinement, linearity,
!> and the failure paths.
module test_fe_statics
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, status_bad_input
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_fe_statics, only: solve_static, static_options_t, static_report_t
    use test_fe, only: paper_material
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_fe_statics, face_load_weights

    ! Cantilever: length, width (y) and height (z); L/h = 10.
    real(wp), parameter :: beam(3) = [1.0_wp, 0.1_wp, 0.1_wp]

contains

    function collect_fe_statics() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('uniaxial_tension_analytic', test_uniaxial), &
                 new_test('newton_quadratic', test_quadratic), &
                 new_test('load_stepping_recovers', test_stepping), &
                 new_test('cantilever_timoshenko', test_cantilever), &
                 new_test('small_load_linear', test_linear), &
                 new_test('large_deflection_quadratic', test_large_deflection), &
                 new_test('extreme_load', test_extreme_load), &
                 new_test('failures_reported', test_failures)]
    end function collect_fe_statics

    !> Consistent nodal weights of a uniform traction on the box face
    !> `face` (a node set of box_mesh, normal along axis d), summing to the
    !> face area: tensor products of the 1-D element rules, [1, 1]/2 · h
    !> (hex8) and [1, 4, 1]/6 · h (hex27), over the face's grid.
    subroutine face_load_weights(mesh, divisions, lengths, face, d, nodes, weights, status)
        type(mesh_t), intent(in) :: mesh
        integer, intent(in) :: divisions(3), d
        real(wp), intent(in) :: lengths(3)
        character(len=*), intent(in) :: face
        integer, allocatable, intent(out) :: nodes(:)
        real(wp), allocatable, intent(out) :: weights(:)
        type(status_t), intent(out) :: status
        integer :: p, i, k, dirs(2), idx
        real(wp) :: w, h, xmin(3)
        real(wp), allocatable :: w1(:)
        call mesh%node_set(face, nodes, status)
        if (.not. status%ok()) return
        p = merge(1, 2, mesh%nnode_element == hex8)
        dirs = pack([1, 2, 3], [1, 2, 3] /= d)
        xmin = minval(mesh%x, dim=2)
        allocate (weights(size(nodes)), source=1.0_wp)
        do k = 1, 2
            associate (dk => dirs(k))
                h = lengths(dk) / divisions(dk)
                allocate (w1(0:p * divisions(dk)), source=0.0_wp)
                do i = 0, divisions(dk) - 1
                    if (p == 1) then
                        w1(i:i + 1) = w1(i:i + 1) + h * [0.5_wp, 0.5_wp]
                    else
                        w1(2 * i:2 * i + 2) = w1(2 * i:2 * i + 2) + h * [1.0_wp, 4.0_wp, 1.0_wp] / 6
                    end if
                end do
                do i = 1, size(nodes)
                    idx = nint((mesh%x(dk, nodes(i)) - xmin(dk)) / (h / p))
                    w = w1(idx)
                    weights(i) = weights(i) * w
                end do
                deallocate (w1)
            end associate
        end do
    end subroutine face_load_weights

    !> A unit cube in homogeneous uniaxial tension: symmetry supports on the
    !> three min faces (one component each), a uniform nominal traction P on
    !> xmax. Exact: x = λ1 X, y = λ2 Y, z = λ2 Z with the lateral stress zero,
    !> μ (λ2² − 1) + λ J (J − 1) = 0, and P = J σ11 / λ1.
    subroutine uniaxial_case(kind, stretch, body, q, status, report, lambda2, options)
        integer, intent(in) :: kind
        real(wp), intent(in) :: stretch
        type(flexible_body_t), intent(out) :: body
        real(wp), allocatable, intent(out) :: q(:)
        type(status_t), intent(out) :: status
        type(static_report_t), intent(out) :: report
        real(wp), intent(out) :: lambda2
        type(static_options_t), intent(in), optional :: options
        integer, parameter :: divisions(3) = [2, 2, 2]
        real(wp), parameter :: cube(3) = [1.0_wp, 1.0_wp, 1.0_wp]
        character(len=4), parameter :: min_faces(3) = ['xmin', 'ymin', 'zmin']
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        logical, allocatable :: fixed(:, :)
        integer, allocatable :: nodes(:)
        real(wp), allocatable :: weights(:)
        real(wp) :: jac, g, dg, sigma11, traction
        integer :: d, it, i
        call paper_material(mat)
        call box_mesh(mesh, kind, divisions, cube, status)
        if (.not. status%ok()) return
        allocate (fixed(3, mesh%node_count()), source=.false.)
        do d = 1, 3
            call mesh%node_set(min_faces(d), nodes, status)
            if (.not. status%ok()) return
            fixed(d, nodes) = .true.
        end do
        call new_flexible_body(body, mesh, [mat], [integer ::], status, &
                               fixed_components=fixed)
        if (.not. status%ok()) return
        lambda2 = 1.0_wp
        do it = 1, 60
            jac = stretch * lambda2**2
            g = mat%mu * (lambda2**2 - 1.0_wp) + mat%lambda * jac * (jac - 1.0_wp)
            dg = 2.0_wp * mat%mu * lambda2 + mat%lambda * (2.0_wp * jac - 1.0_wp) * 2.0_wp &
                 * stretch * lambda2
            lambda2 = lambda2 - g / dg
        end do
        jac = stretch * lambda2**2
        sigma11 = mat%mu / jac * (stretch**2 - 1.0_wp) + mat%lambda * (jac - 1.0_wp)
        traction = jac * sigma11 / stretch
        call face_load_weights(mesh, divisions, cube, 'xmax', 1, nodes, weights, status)
        if (.not. status%ok()) return
        do i = 1, size(nodes)
            call body%add_nodal_load(nodes(i), [traction * weights(i), 0.0_wp, 0.0_wp], status)
            if (.not. status%ok()) return
        end do
        q = body%free_positions()
        call solve_static(body, q, status, options, report)
    end subroutine uniaxial_case

    !> Quadratic convergence of a relative error measure e: every pair with
    !> e_i < upper and e_{i+1} > lower (above round-off) has
    !> log e_{i+1} / log e_i ≥ 1.7, and there is at least one such pair.
    subroutine check_quadratic(error, e, upper, lower, what)
        type(error_t), allocatable, intent(inout) :: error
        real(wp), intent(in) :: e(:), upper, lower
        character(len=*), intent(in) :: what
        real(wp) :: order
        integer :: i, npairs
        npairs = 0
        do i = 1, size(e) - 1
            if (e(i) < upper .and. e(i + 1) > lower) then
                order = log(e(i + 1)) / log(e(i))
                print '(4x,a,es9.2,a,es9.2,a,f5.2)', what // ' ', e(i), ' -> ', e(i + 1), &
                    ', log ratio ', order
                call check(error, order >= 1.7_wp, what // ': Newton not quadratic')
                npairs = npairs + 1
            end if
        end do
        call check(error, npairs >= 1, what // ': no iteration pair in the asymptotic range')
    end subroutine check_quadratic

    !> Both element types reach the exact homogeneous state to 1e-8 relative
    !> at a large stretch (1.5).
    subroutine test_uniaxial(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: kinds(2) = [hex8, hex27]
        type(flexible_body_t) :: body
        type(status_t) :: status
        type(static_report_t) :: report
        real(wp), allocatable :: q(:)
        real(wp) :: lambda2, expected(3), worst
        real(wp), parameter :: stretch = 1.5_wp
        integer :: k, i, j
        do k = 1, 2
            call uniaxial_case(kinds(k), stretch, body, q, status, report, lambda2)
            call check(error, status%ok(), 'uniaxial: ' // status%text())
            if (allocated(error)) return
            call check_close(error, report%load_factor, 1.0_wp, 0.0_wp, 'uniaxial: load factor')
            worst = 0.0_wp
            do i = 1, body%mesh%node_count()
                expected = body%mesh%x(:, i) * [stretch, lambda2, lambda2]
                do j = 1, 3
                    if (body%dof(j, i) > 0) &
                        worst = max(worst, abs(q(body%dof(j, i)) - expected(j)))
                end do
            end do
            call check(error, worst <= 1.0e-8_wp * stretch, 'uniaxial: positions off the ' // &
                       'analytic homogeneous state')
            if (allocated(error)) return
        end do
        print '(4x,a,i0,a,i0,a,es9.2)', 'uniaxial tension 1.5: ', report%load_steps, &
            ' load steps, ', report%newton_iterations, ' Newton iterations, max error ', worst
    end subroutine test_uniaxial

    !> In the last load step, once ‖r‖ is below 1 % of the load, each
    !> iteration squares the relative residual (up to a constant):
    !> log ratio ≥ 1.7 while above round-off.
    subroutine test_quadratic(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        type(static_report_t) :: report
        type(static_options_t) :: options
        real(wp), allocatable :: q(:)
        real(wp) :: lambda2, gnorm
        options%residual_tolerance = 1.0e-14_wp
        options%increment_tolerance = 1.0e-14_wp
        call uniaxial_case(hex8, 1.3_wp, body, q, status, report, lambda2, options)
        call check(error, status%ok(), 'quadratic: ' // status%text())
        if (allocated(error)) return
        gnorm = maxval(abs(body%applied_force))
        call check_quadratic(error, report%residual_history / gnorm, 1.0e-2_wp, 1.0e-13_wp, &
                             'quadratic: |r|')
    end subroutine test_quadratic

    !> With at most 3 Newton iterations per step the full load fails; the
    !> halved increments succeed and reach the same exact state.
    subroutine test_stepping(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        type(static_report_t) :: report
        type(static_options_t) :: options
        real(wp), allocatable :: q(:)
        real(wp) :: lambda2
        integer :: i
        options%max_iterations = 3
        call uniaxial_case(hex8, 1.5_wp, body, q, status, report, lambda2, options)
        call check(error, status%ok(), 'stepping: ' // status%text())
        if (allocated(error)) return
        call check(error, report%failed_steps >= 1 .and. report%load_steps >= 2, &
                   'stepping: expected halved increments')
        i = body%mesh%node_count()
        call check_close(error, q(body%dof(1, i)), 1.5_wp * body%mesh%x(1, i), 1.0e-8_wp, &
                         'stepping: corner x')
        print '(4x,a,i0,a,i0,a,i0,a)', 'max 3 iterations: ', report%load_steps, &
            ' load steps, ', report%failed_steps, ' halvings, ', report%newton_iterations, &
            ' iterations'
    end subroutine test_stepping

    !> Clamped box beam (27-node, n × 1 × 1), tip load P in z spread
    !> consistently over the xmax face; the face-averaged deflection.
    subroutine cantilever(n, load, deflection, status, report, options)
        integer, intent(in) :: n
        real(wp), intent(in) :: load
        real(wp), intent(out) :: deflection
        type(status_t), intent(out) :: status
        type(static_report_t), intent(out), optional :: report
        type(static_options_t), intent(in), optional :: options
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: body
        integer, allocatable :: clamped(:), tip(:)
        real(wp), allocatable :: weights(:), q(:)
        integer :: i, divisions(3)
        call paper_material(mat)
        divisions = [n, 1, 1]
        call box_mesh(mesh, hex27, divisions, beam, status)
        if (.not. status%ok()) return
        call mesh%node_set('xmin', clamped, status)
        if (.not. status%ok()) return
        call new_flexible_body(body, mesh, [mat], clamped, status)
        if (.not. status%ok()) return
        call face_load_weights(mesh, divisions, beam, 'xmax', 1, tip, weights, status)
        if (.not. status%ok()) return
        weights = weights / sum(weights)
        do i = 1, size(tip)
            call body%add_nodal_load(tip(i), [0.0_wp, 0.0_wp, load * weights(i)], status)
            if (.not. status%ok()) return
        end do
        q = body%free_positions()
        call solve_static(body, q, status, options, report)
        deflection = 0.0_wp
        do i = 1, size(tip)
            deflection = deflection + weights(i) * (q(body%dof(3, tip(i))) - mesh%x(3, tip(i)))
        end do
    end subroutine cantilever

    !> Timoshenko: δ = P L³/(3 E I) + P L/(κ G A), κ = 10(1+ν)/(12+11ν).
    pure real(wp) function timoshenko(mat, load)
        type(neo_hooke_t), intent(in) :: mat
        real(wp), intent(in) :: load
        real(wp) :: e, nu, inertia, area, kappa
        nu = mat%lambda / (2.0_wp * (mat%lambda + mat%mu))
        e = 2.0_wp * mat%mu * (1.0_wp + nu)
        area = beam(2) * beam(3)
        inertia = beam(2) * beam(3)**3 / 12.0_wp
        kappa = 10.0_wp * (1.0_wp + nu) / (12.0_wp + 11.0_wp * nu)
        timoshenko = load * beam(1)**3 / (3.0_wp * e * inertia) &
                     + load * beam(1) / (kappa * mat%mu * area)
    end function timoshenko

    !> The tip deflection converges to Timoshenko under refinement along the
    !> beam: the error shrinks and the finest mesh is within 2 %.
    subroutine test_cantilever(error)
        type(error_t), allocatable, intent(out) :: error
        integer, parameter :: ns(3) = [2, 4, 8]
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        type(static_report_t) :: report
        real(wp) :: load, reference, deflection, rel(3)
        integer :: i
        call paper_material(mat)
        ! δ/L ≈ 1e-4: the linear regime.
        load = 1.0e-4_wp * beam(1) / timoshenko(mat, 1.0_wp)
        reference = timoshenko(mat, load)
        do i = 1, size(ns)
            call cantilever(ns(i), load, deflection, status, report)
            call check(error, status%ok(), 'cantilever: ' // status%text())
            if (allocated(error)) return
            rel(i) = abs(deflection - reference) / reference
            print '(4x,a,i0,a,es12.5,a,es12.5,a,f6.2,a,i0,a,i0,a)', 'cantilever ', ns(i), &
                'x1x1 hex27: tip ', deflection, ', Timoshenko ', reference, ', error ', &
                100 * rel(i), ' % (', report%load_steps, ' load steps, ', &
                report%newton_iterations, ' Newton iterations)'
        end do
        call check(error, rel(2) < rel(1) .and. rel(3) < rel(2), &
                   'cantilever: error does not decrease under refinement')
        call check(error, rel(3) < 0.02_wp, 'cantilever: finest mesh not within 2 % of Timoshenko')
    end subroutine test_cantilever

    !> Doubling a tiny load doubles the deflection (to 1e-6).
    subroutine test_linear(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        real(wp) :: load, d1, d2
        call paper_material(mat)
        load = 1.0e-5_wp * beam(1) / timoshenko(mat, 1.0_wp)
        call cantilever(2, load, d1, status)
        if (status%ok()) call cantilever(2, 2.0_wp * load, d2, status)
        call check(error, status%ok(), 'linear: ' // status%text())
        if (allocated(error)) return
        call check_close(error, d2 / d1, 2.0_wp, 2.0e-6_wp, 'linear: deflection ratio')
    end subroutine test_linear

    !> A cantilever bent far into the nonlinear range (linear theory: δ/L =
    !> 0.3), an inhomogeneous state with large rotations: Newton's decrement
    !> in the last load step shrinks quadratically (log ratio ≥ 1.7 once
    !> below 1e-3 of the first), and the deflection stays below the linear
    !> prediction (the tip moves inwards as the beam rotates).
    subroutine test_large_deflection(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        type(static_report_t) :: report
        type(static_options_t) :: options
        real(wp) :: load, deflection
        real(wp), allocatable :: r(:)
        call paper_material(mat)
        load = 0.3_wp * beam(1) / timoshenko(mat, 1.0_wp)
        options%residual_tolerance = 1.0e-14_wp
        options%increment_tolerance = 1.0e-14_wp
        call cantilever(4, load, deflection, status, report, options)
        call check(error, status%ok(), 'large deflection: ' // status%text())
        if (allocated(error)) return
        print '(4x,a,f7.4,a,i0,a,i0,a,i0,a)', 'large deflection: δ/L ', deflection / beam(1), &
            ' (linear 0.3), ', report%load_steps, ' load steps, ', report%failed_steps, &
            ' halvings, ', report%newton_iterations, ' Newton iterations'
        call check(error, deflection > 0.1_wp * beam(1) .and. deflection < 0.3_wp * beam(1), &
                   'large deflection: tip deflection outside (0.1, 0.3) L')
        ! ‖r‖ is dominated by the stiff axial terms and need not fall
        ! monotonically; the Newton decrement, normalised by the first one
        ! (= sqrt(P δ_linear)), is the affine-invariant error measure. Pairs
        ! ending within a factor 10 of the round-off floor are left out.
        r = report%decrement_history / report%decrement_history(1)
        call check_quadratic(error, r, 1.0e-3_wp, 10.0_wp * r(size(r)), &
                             'large deflection: decrement')
    end subroutine test_large_deflection

    !> A tip load a thousand times what bends the beam by its length in
    !> linear theory (nominal stress 2.5 E): the beam swings round and
    !> stretches several times over (tip deflection > L), and the load
    !> stepping still reaches it.
    subroutine test_extreme_load(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        type(static_report_t) :: report
        real(wp) :: load, deflection
        call paper_material(mat)
        load = 1.0e3_wp * beam(1) / timoshenko(mat, 1.0_wp)
        call cantilever(2, load, deflection, status, report)
        call check(error, status%ok(), 'extreme load: ' // status%text())
        if (allocated(error)) return
        print '(4x,a,f6.3,a,i0,a,i0,a,i0,a)', 'extreme load: δ/L ', deflection / beam(1), ', ', &
            report%load_steps, ' load steps, ', report%failed_steps, ' halvings, ', &
            report%newton_iterations, ' Newton iterations'
        call check(error, deflection > beam(1), 'extreme load: tip did not swing round')
    end subroutine test_extreme_load

    !> A load step that cannot converge in one iteration with a large minimum
    !> increment fails with the load factor reached; a wrong q size is bad
    !> input; the last equilibrium is returned.
    subroutine test_failures(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        type(static_report_t) :: report
        type(static_options_t) :: options
        real(wp), allocatable :: q(:), q0(:)
        real(wp) :: lambda2
        options%max_iterations = 1
        options%min_increment = 0.3_wp
        call uniaxial_case(hex8, 1.5_wp, body, q, status, report, lambda2, options)
        call check(error, status%code == status_solver_failure, &
                   'failures: expected a solver failure, got: ' // status%text())
        call check(error, index(status%text(), 'load increment below') > 0 .and. &
                   index(status%text(), 'at load factor') > 0, &
                   'failures: message lacks the reason: ' // status%text())
        call check(error, report%load_factor < 1.0_wp, 'failures: load factor reported 1')
        call check(error, all(q == q), 'failures: q not returned')
        if (allocated(error)) return
        q0 = body%free_positions()
        q = q0(1:size(q0) - 1)
        call solve_static(body, q, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'entries') > 0, 'failures: wrong size: ' // status%text())
        if (allocated(error)) return
        ! A NaN load is bad input, reported before any iteration.
        call body%add_nodal_load(body%mesh%node_count(), [ieee_value(1.0_wp, ieee_quiet_nan), &
                                 0.0_wp, 0.0_wp], status)
        q = q0
        call solve_static(body, q, status, report=report)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'not finite') > 0 .and. report%newton_iterations == 0, &
                   'failures: NaN load: ' // status%text())
    end subroutine test_failures
end module test_fe_statics
