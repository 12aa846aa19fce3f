!> Static equilibrium: homogeneous uniaxial tension against the analytic
!> neo-Hookean solution, quadratic convergence of Newton, the small-load
!> cantilever against Timoshenko beam theory under refinement, linearity,
!> the large-deflection cantilever against the elastica, the extreme load
!> against a bar in uniaxial tension, and the failure paths.
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
        real(wp) :: traction
        integer :: d, i
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
        call uniaxial_state(mat, stretch, lambda2, traction)
        call face_load_weights(mesh, divisions, cube, 'xmax', 1, nodes, weights, status)
        if (.not. status%ok()) return
        do i = 1, size(nodes)
            call body%add_nodal_load(nodes(i), [traction * weights(i), 0.0_wp, 0.0_wp], status)
            if (.not. status%ok()) return
        end do
        q = body%free_positions()
        call solve_static(body, q, status, options, report)
    end subroutine uniaxial_case

    !> Homogeneous uniaxial tension of the neo-Hookean material at the axial
    !> stretch λ1: the lateral stretch λ2 from a zero lateral stress,
    !> μ (λ2² − 1) + λ J (J − 1) = 0 with J = λ1 λ2², and the nominal
    !> traction P = J σ11 / λ1, σ11 = μ (λ1² − 1) / J + λ (J − 1).
    pure subroutine uniaxial_state(mat, stretch, lambda2, traction)
        type(neo_hooke_t), intent(in) :: mat
        real(wp), intent(in) :: stretch
        real(wp), intent(out) :: lambda2, traction
        real(wp) :: jac, g, dg, sigma11
        integer :: it
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
    end subroutine uniaxial_state

    !> The axial stretch of uniaxial tension under the nominal traction P ≥ 0
    !> (P rises monotonically with the stretch): bisection to round-off.
    pure real(wp) function uniaxial_stretch(mat, traction) result(stretch)
        type(neo_hooke_t), intent(in) :: mat
        real(wp), intent(in) :: traction
        real(wp) :: lo, hi, lambda2, p
        integer :: it
        lo = 1.0_wp
        hi = 2.0_wp
        call uniaxial_state(mat, hi, lambda2, p)
        do while (p < traction)
            lo = hi
            hi = 2.0_wp * hi
            call uniaxial_state(mat, hi, lambda2, p)
        end do
        do it = 1, 200
            stretch = 0.5_wp * (lo + hi)
            if (stretch <= lo .or. stretch >= hi) exit
            call uniaxial_state(mat, stretch, lambda2, p)
            if (p < traction) then
                lo = stretch
            else
                hi = stretch
            end if
        end do
        stretch = 0.5_wp * (lo + hi)
    end function uniaxial_stretch

    !> Largest deviation of the free positions q from the homogeneous state
    !> x = X [λ1, λ2, λ2].
    real(wp) function homogeneous_deviation(body, q, stretch, lambda2) result(worst)
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: q(:), stretch, lambda2
        real(wp) :: expected(3)
        integer :: i, j
        worst = 0.0_wp
        do i = 1, body%mesh%node_count()
            expected = body%mesh%x(:, i) * [stretch, lambda2, lambda2]
            do j = 1, 3
                if (body%dof(j, i) > 0) worst = max(worst, abs(q(body%dof(j, i)) - expected(j)))
            end do
        end do
    end function homogeneous_deviation

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
        real(wp) :: lambda2, worst
        real(wp), parameter :: stretch = 1.5_wp
        integer :: k
        do k = 1, 2
            call uniaxial_case(kinds(k), stretch, body, q, status, report, lambda2)
            call check(error, status%ok(), 'uniaxial: ' // status%text())
            if (allocated(error)) return
            call check_close(error, report%load_factor, 1.0_wp, 0.0_wp, 'uniaxial: load factor')
            worst = homogeneous_deviation(body, q, stretch, lambda2)
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
    !> consistently over the xmax face; the face-averaged deflection and,
    !> if asked, the out-of-balance force ‖k(q) − g‖∞ / ‖g‖∞ of the static
    !> equations evaluated afresh at the returned q.
    subroutine cantilever(n, load, deflection, status, report, options, imbalance)
        integer, intent(in) :: n
        real(wp), intent(in) :: load
        real(wp), intent(out) :: deflection
        type(status_t), intent(out) :: status
        type(static_report_t), intent(out), optional :: report
        type(static_options_t), intent(in), optional :: options
        real(wp), intent(out), optional :: imbalance
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        type(flexible_body_t) :: body
        integer, allocatable :: clamped(:), tip(:)
        real(wp), allocatable :: weights(:), q(:), k(:), zero_v(:)
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
        if (present(imbalance) .and. status%ok()) then
            allocate (k(body%nv), zero_v(body%nv), source=0.0_wp)
            call body%internal_forces(q, zero_v, k, status)
            imbalance = maxval(abs(k - body%applied_force)) / maxval(abs(body%applied_force))
        end if
    end subroutine cantilever

    !> Tip deflection δ/L and end shortening u/L of the elastica: the
    !> inextensible, unshearable cantilever under a dead tip load
    !> perpendicular to its axis, α = P L²/(E I). With θ(s) the slope,
    !> θ'' = −α cos θ on s ∈ [0, 1], θ(0) = 0 and θ'(1) = 0 (no moment at
    !> the tip); δ/L = ∫ sin θ ds, u/L = 1 − ∫ cos θ ds. Shooting on θ'(0)
    !> by Newton with the variational equation, RK4 with 2000 steps (its
    !> error, O(h⁴), is below 1e-12).
    pure subroutine elastica(alpha, deflection, shortening)
        real(wp), intent(in) :: alpha
        real(wp), intent(out) :: deflection, shortening
        integer, parameter :: steps = 2000
        real(wp) :: c, y(6), k1(6), k2(6), k3(6), k4(6), h
        integer :: it, i
        h = 1.0_wp / steps
        c = alpha
        do it = 1, 30
            ! θ, θ', ∫ sin θ, ∫ cos θ, ∂θ/∂c, ∂θ'/∂c
            y = [0.0_wp, c, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp]
            do i = 1, steps
                k1 = rate(y)
                k2 = rate(y + 0.5_wp * h * k1)
                k3 = rate(y + 0.5_wp * h * k2)
                k4 = rate(y + h * k3)
                y = y + h / 6.0_wp * (k1 + 2.0_wp * k2 + 2.0_wp * k3 + k4)
            end do
            if (abs(y(2)) <= 1.0e-15_wp * alpha) exit
            c = c - y(2) / y(6)
        end do
        deflection = y(3)
        shortening = 1.0_wp - y(4)
    contains
        pure function rate(z) result(dz)
            real(wp), intent(in) :: z(6)
            real(wp) :: dz(6)
            dz = [z(2), -alpha * cos(z(1)), sin(z(1)), cos(z(1)), z(6), alpha * sin(z(1)) * z(5)]
        end function rate
    end subroutine elastica

    !> Timoshenko's tip deflection δ = P L³/(3 E I) + P L/(κ G A), κ = 10(1+ν)/(12+11ν).
    pure real(wp) function timoshenko(mat, load)
        type(neo_hooke_t), intent(in) :: mat
        real(wp), intent(in) :: load
        timoshenko = load * beam(1)**3 / (3.0_wp * bending_stiffness(mat)) &
                     + shear_deflection(mat, load)
    end function timoshenko

    !> E I of the beam's section about y.
    pure real(wp) function bending_stiffness(mat)
        type(neo_hooke_t), intent(in) :: mat
        real(wp) :: nu
        nu = mat%lambda / (2.0_wp * (mat%lambda + mat%mu))
        bending_stiffness = 2.0_wp * mat%mu * (1.0_wp + nu) * beam(2) * beam(3)**3 / 12.0_wp
    end function bending_stiffness

    !> Timoshenko's shear part of the tip deflection, P L/(κ G A).
    pure real(wp) function shear_deflection(mat, load)
        type(neo_hooke_t), intent(in) :: mat
        real(wp), intent(in) :: load
        real(wp) :: nu, kappa
        nu = mat%lambda / (2.0_wp * (mat%lambda + mat%mu))
        kappa = 10.0_wp * (1.0_wp + nu) / (12.0_wp + 11.0_wp * nu)
        shear_deflection = load * beam(1) / (kappa * mat%mu * beam(2) * beam(3))
    end function shear_deflection

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
    !> 0.3), an inhomogeneous state with large rotations, against the
    !> elastica. Its shooting solution first reproduces the published
    !> elastica at α = P L²/(E I) = 1, δ/L = 0.30172 and u/L = 0.05643
    !> (Bisshopp & Drucker, Q. Appl. Math. 3 (1945) 272; Mattiasson, Int. J.
    !> Numer. Meth. Eng. 17 (1981) 145). The beam: elastica at the test's α =
    !> 0.893 plus Timoshenko's shear deflection P L/(κ G A) (0.8 % of δ; its
    !> change as the section turns, below 0.1 % of δ, is left out).
    !> The 4 × 1 × 1 mesh is 3.2 % too stiff in the linear range
    !> (cantilever_timoshenko), so δ must be within 4 % of the beam's
    !> (measured −3.4 %); the nonlinear softening, δ over the same mesh's
    !> linear δ, within 1 % of the beam's δ over Timoshenko's (measured 0.920
    !> against 0.922; geometric linearity would give 1, 8 % off). Newton's
    !> decrement in the last load step shrinks quadratically (log ratio ≥ 1.7
    !> once below 1e-3 of the first).
    subroutine test_large_deflection(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        type(static_report_t) :: report
        type(static_options_t) :: options
        real(wp) :: load, deflection, alpha, elastica_d, elastica_u, reference, small, &
            linear, softening, beam_softening
        real(wp), allocatable :: r(:)
        call elastica(1.0_wp, elastica_d, elastica_u)
        call check_close(error, elastica_d, 0.30172_wp, 1.0e-5_wp, &
                         'large deflection: elastica δ/L at α = 1 (Bisshopp-Drucker)')
        call check_close(error, elastica_u, 0.05643_wp, 1.0e-5_wp, &
                         'large deflection: elastica u/L at α = 1 (Mattiasson)')
        if (allocated(error)) return
        call paper_material(mat)
        load = 0.3_wp * beam(1) / timoshenko(mat, 1.0_wp)
        alpha = load * beam(1)**2 / bending_stiffness(mat)
        call elastica(alpha, elastica_d, elastica_u)
        reference = elastica_d * beam(1) + shear_deflection(mat, load)
        options%residual_tolerance = 1.0e-14_wp
        options%increment_tolerance = 1.0e-14_wp
        call cantilever(4, load, deflection, status, report, options)
        call check(error, status%ok(), 'large deflection: ' // status%text())
        if (allocated(error)) return
        ! The same mesh in its linear range (δ/L ≈ 1e-4), scaled to the load.
        small = 1.0e-4_wp * beam(1) / timoshenko(mat, 1.0_wp)
        call cantilever(4, small, linear, status)
        call check(error, status%ok(), 'large deflection, linear range: ' // status%text())
        if (allocated(error)) return
        linear = linear * load / small
        softening = deflection / linear
        beam_softening = reference / timoshenko(mat, load)
        print '(4x,a,f7.4,a,f7.4,a,f7.4,a,f6.2,a)', 'large deflection: δ/L ', &
            deflection / beam(1), ', elastica (α ', alpha, ') + shear ', reference / beam(1), &
            ', error ', 100 * (deflection / reference - 1), ' %'
        print '(4x,a,f7.4,a,f7.4,a,i0,a,i0,a,i0,a)', 'large deflection: softening ', &
            softening, ', beam ', beam_softening, '; ', report%load_steps, ' load steps, ', &
            report%failed_steps, ' halvings, ', report%newton_iterations, ' Newton iterations'
        call check(error, abs(deflection / reference - 1.0_wp) <= 0.04_wp, &
                   'large deflection: tip deflection not within 4 % of the elastica')
        call check(error, abs(softening / beam_softening - 1.0_wp) <= 0.01_wp, &
                   'large deflection: softening not within 1 % of the elastica''s')
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
    !> stretches several times over, and the load stepping still reaches it.
    !> The returned state is in equilibrium (‖k(q) − g‖∞ evaluated afresh,
    !> at most 1e-9 ‖g‖∞, the solver's tolerance being 1e-10; measured
    !> 3e-14), and the beam hangs along the load as a bar in uniaxial tension:
    !> the tip moves by the analytic stretch λ1 = 6.483 of the nominal stress
    !> P/A times L, within 1 % (measured +0.06 %; the clamped end, which
    !> holds the section's contraction and turns the beam through 90°,
    !> disturbs the uniform state over about the section's size).
    subroutine test_extreme_load(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        type(static_report_t) :: report
        real(wp) :: load, deflection, imbalance, stretch
        call paper_material(mat)
        load = 1.0e3_wp * beam(1) / timoshenko(mat, 1.0_wp)
        call cantilever(2, load, deflection, status, report, imbalance=imbalance)
        call check(error, status%ok(), 'extreme load: ' // status%text())
        if (allocated(error)) return
        stretch = uniaxial_stretch(mat, load / (beam(2) * beam(3)))
        print '(4x,a,f6.3,a,f6.3,a,es9.2,a,i0,a,i0,a,i0,a)', 'extreme load: δ/L ', &
            deflection / beam(1), ', bar in tension ', stretch, ', imbalance ', imbalance, &
            '; ', report%load_steps, ' load steps, ', report%failed_steps, ' halvings, ', &
            report%newton_iterations, ' Newton iterations'
        call check(error, imbalance <= 1.0e-9_wp, 'extreme load: not in equilibrium')
        call check(error, abs(deflection / (stretch * beam(1)) - 1.0_wp) <= 0.01_wp, &
                   'extreme load: tip deflection not within 1 % of the stretched bar''s')
    end subroutine test_extreme_load

    !> A load step that cannot converge in one iteration with a large minimum
    !> increment fails with the load factor reached (0), and a run stopped
    !> by its count of load steps part of the way (load factor 0.49); a
    !> wrong q size is bad input. Each failure returns the last equilibrium:
    !> the analytic homogeneous state at the load factor reported, to 1e-8.
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
        call check_last_equilibrium(error, body, q, report%load_factor, 'increment')
        if (allocated(error)) return
        options = static_options_t()
        options%max_iterations = 3
        options%max_load_steps = 16
        call uniaxial_case(hex8, 1.5_wp, body, q, status, report, lambda2, options)
        call check(error, status%code == status_solver_failure .and. &
                   index(status%text(), 'load steps reached at load factor') > 0, &
                   'failures: expected the load steps to run out, got: ' // status%text())
        call check(error, report%load_factor > 0.0_wp .and. report%load_factor < 1.0_wp, &
                   'failures: load steps out at load factor ' // status%text())
        call check_last_equilibrium(error, body, q, report%load_factor, 'load steps')
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

    !> q of the cube of uniaxial_case (stretch 1.5 at load factor 1) stopped
    !> at load_factor: the homogeneous state under that fraction of the
    !> traction, to 1e-8.
    subroutine check_last_equilibrium(error, body, q, load_factor, what)
        type(error_t), allocatable, intent(inout) :: error
        type(flexible_body_t), intent(in) :: body
        real(wp), intent(in) :: q(:), load_factor
        character(len=*), intent(in) :: what
        type(neo_hooke_t) :: mat
        real(wp) :: lambda2, traction, stretch, worst
        call paper_material(mat)
        call uniaxial_state(mat, 1.5_wp, lambda2, traction)
        stretch = uniaxial_stretch(mat, load_factor * traction)
        call uniaxial_state(mat, stretch, lambda2, traction)
        worst = homogeneous_deviation(body, q, stretch, lambda2)
        print '(4x,a,f9.6,a,f8.5,a,es9.2)', 'failure (' // what // ') at load factor ', &
            load_factor, ': stretch ', stretch, ', q off it by ', worst
        call check(error, worst <= 1.0e-8_wp, 'failures (' // what // '): q is not the ' // &
                   'analytic state at the load factor reported')
    end subroutine check_last_equilibrium
end module test_fe_statics
