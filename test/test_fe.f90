!> Finite elements: shape functions, quadrature and kinematics of the hexahedra.
module test_fe
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_det_f
    use flexmbs_fe_tensor, only: det3, inverse3, identity3, voigt_i, voigt_j
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_hexahedron, only: hexahedron_t, new_hexahedron, shape_functions, &
        gauss_rule, reference_gradients, deformation_gradient, hex8, hex27, hex_node_xi
    use test_problems, only: fill_random
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_fe, random_element, random_rotation, paper_material, strains

    ! Relative accuracy asked of analytic stresses and of FD tangents (issue 5).
    real(wp), parameter :: stress_rtol = 1.0e-10_wp
    real(wp), parameter :: tangent_rtol = 1.0e-6_wp

    ! Central differences of polynomials of degree ≤ 2 per variable are exact
    ! up to rounding, about eps/h.
    real(wp), parameter :: fd_step = 1.0e-5_wp
    integer, parameter :: element_kinds(2) = [hex8, hex27]

contains

    function collect_fe() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('hex_partition_of_unity', test_partition_of_unity), &
                 new_test('hex_derivatives_fd', test_derivatives_fd), &
                 new_test('gauss_exact_polynomials', test_gauss_exact), &
                 new_test('deformation_gradient_affine', test_deformation_gradient), &
                 new_test('deformation_gradient_det_f', test_det_f_failure), &
                 new_test('neo_hooke_uniaxial_tension', test_uniaxial_tension), &
                 new_test('neo_hooke_simple_shear', test_simple_shear), &
                 new_test('neo_hooke_small_strain_kelvin_voigt', test_small_strain), &
                 new_test('neo_hooke_energy_derivative', test_energy_derivative), &
                 new_test('neo_hooke_tangents_fd', test_material_tangents), &
                 new_test('neo_hooke_rigid_motion', test_material_rigid), &
                 new_test('neo_hooke_bad_input', test_material_bad_input)]
    end function collect_fe

    ! ------------------------------------------------------------------ helpers

    !> Reference positions of a distorted element: an affine image of the
    !> reference cube (matrix a, centre c) plus node perturbations of relative
    !> size `distortion`.
    subroutine random_element(nnode, seed, distortion, x, a, c)
        integer, intent(in) :: nnode
        integer(i8), intent(inout) :: seed
        real(wp), intent(in) :: distortion
        real(wp), intent(out) :: x(3, nnode), a(3, 3), c(3)
        real(wp) :: p(3 * nnode)
        integer :: i
        call fill_random(a(:, 1), seed, -0.2_wp, 0.2_wp)
        call fill_random(a(:, 2), seed, -0.2_wp, 0.2_wp)
        call fill_random(a(:, 3), seed, -0.2_wp, 0.2_wp)
        a = a + reshape([0.5_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.7_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
                         0.4_wp], [3, 3])
        call fill_random(c, seed, -1.0_wp, 1.0_wp)
        call fill_random(p, seed, -distortion, distortion)
        do i = 1, nnode
            x(:, i) = c + matmul(a, hex_node_xi(:, i)) + p(3 * i - 2:3 * i)
        end do
    end subroutine random_element

    !> Rotation matrix from a random axis and angle (Rodrigues).
    subroutine random_rotation(seed, r)
        integer(i8), intent(inout) :: seed
        real(wp), intent(out) :: r(3, 3)
        real(wp) :: axis(3), angle(1), k(3, 3)
        call fill_random(axis, seed, -1.0_wp, 1.0_wp)
        axis = axis / norm2(axis)
        call fill_random(angle, seed, 0.5_wp, 3.0_wp)
        k = reshape([0.0_wp, axis(3), -axis(2), -axis(3), 0.0_wp, axis(1), axis(2), &
                     -axis(1), 0.0_wp], [3, 3])
        r = identity3 + sin(angle(1)) * k + (1.0_wp - cos(angle(1))) * matmul(k, k)
    end subroutine random_rotation

    !> The paper's soft material, damped (E = 7e5 Pa, ν = 0.3, ρ = 920, η = 1000).
    subroutine paper_material(material)
        type(neo_hooke_t), intent(out) :: material
        type(status_t) :: status
        call new_neo_hooke(material, 7.0e5_wp, 0.3_wp, 920.0_wp, 1000.0_wp, status)
    end subroutine paper_material

    !> E and Ė from F and Ḟ.
    pure subroutine strains(f, fdot, e, edot)
        real(wp), intent(in) :: f(3, 3), fdot(3, 3)
        real(wp), intent(out) :: e(3, 3), edot(3, 3)
        e = 0.5_wp * (matmul(transpose(f), f) - identity3)
        edot = 0.5_wp * (matmul(transpose(fdot), f) + matmul(transpose(f), fdot))
    end subroutine strains

    !> Record max |a - b| / scale > tol as a failure.
    subroutine check_tensor(error, a, b, scale, tol, what)
        type(error_t), allocatable, intent(inout) :: error
        real(wp), intent(in) :: a(:, :), b(:, :), scale, tol
        character(len=*), intent(in) :: what
        character(len=60) :: buf
        write (buf, '(a,es10.3)') ': relative deviation ', maxval(abs(a - b)) / scale
        call check(error, maxval(abs(a - b)) <= tol * scale, what // trim(buf))
    end subroutine check_tensor

    ! ------------------------------------------------------------------ tests

    !> Σ N_a = 1, Σ ∂N_a/∂ξ = 0, N_a(ξ_b) = δ_ab, and Σ N_a ξ_a = ξ (linear
    !> completeness), at random points, for both elements.
    subroutine test_partition_of_unity(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: xi(3), n(hex27), dn(3, hex27)
        integer(i8) :: seed
        integer :: e, nn, k, a, b
        seed = 11_i8
        do e = 1, 2
            nn = element_kinds(e)
            do k = 1, 20
                call fill_random(xi, seed, -1.0_wp, 1.0_wp)
                call shape_functions(nn, xi, n(1:nn), dn(:, 1:nn))
                call check_close(error, sum(n(1:nn)), 1.0_wp, 1.0e-14_wp, 'sum N')
                call check(error, all(abs(sum(dn(:, 1:nn), dim=2)) < 1.0e-13_wp), 'sum dN')
                call check(error, all(abs(matmul(hex_node_xi(:, 1:nn), n(1:nn)) - xi) &
                                      < 1.0e-14_wp), 'sum N_a xi_a = xi')
            end do
            do b = 1, nn
                call shape_functions(nn, hex_node_xi(:, b), n(1:nn), dn(:, 1:nn))
                do a = 1, nn
                    call check_close(error, n(a), merge(1.0_wp, 0.0_wp, a == b), 1.0e-15_wp, &
                                     'N_a(xi_b) = delta_ab')
                end do
            end do
            if (allocated(error)) return
        end do
    end subroutine test_partition_of_unity

    !> ∂N/∂ξ against central differences at random points; worst error
    !> relative to max |∂N| ≤ 1e-9.
    subroutine test_derivatives_fd(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: xi(3), xh(3), n(hex27), dn(3, hex27), np(hex27), nm(hex27), &
            dummy(3, hex27), worst
        integer(i8) :: seed
        integer :: e, nn, k, j
        seed = 12_i8
        do e = 1, 2
            nn = element_kinds(e)
            worst = 0.0_wp
            do k = 1, 20
                call fill_random(xi, seed, -1.0_wp, 1.0_wp)
                call shape_functions(nn, xi, n(1:nn), dn(:, 1:nn))
                do j = 1, 3
                    xh = xi
                    xh(j) = xi(j) + fd_step
                    call shape_functions(nn, xh, np(1:nn), dummy(:, 1:nn))
                    xh(j) = xi(j) - fd_step
                    call shape_functions(nn, xh, nm(1:nn), dummy(:, 1:nn))
                    worst = max(worst, maxval(abs((np(1:nn) - nm(1:nn)) / (2 * fd_step) &
                                                  - dn(j, 1:nn))) / maxval(abs(dn(:, 1:nn))))
                end do
            end do
            call check(error, worst < 1.0e-9_wp, 'shape function derivatives vs FD')
        end do
    end subroutine test_derivatives_fd

    !> The np-point rule integrates ξ^p η^q ζ^r exactly for p, q, r ≤ 2np−1
    !> (odd powers give 0, even 2/(p+1)), and not ξ^(2np).
    subroutine test_gauss_exact(error)
        type(error_t), allocatable, intent(out) :: error
        real(wp) :: xi(3, 27), w(27), integral, exact
        integer :: np, ng, p, q, r
        do np = 2, 3
            ng = np**3
            call gauss_rule(np, xi(:, 1:ng), w(1:ng))
            do r = 0, 2 * np - 1
                do q = 0, 2 * np - 1
                    do p = 0, 2 * np - 1
                        integral = sum(w(1:ng) * xi(1, 1:ng)**p * xi(2, 1:ng)**q &
                                       * xi(3, 1:ng)**r)
                        exact = moment_1d(p) * moment_1d(q) * moment_1d(r)
                        call check_close(error, integral, exact, 1.0e-14_wp, 'Gauss monomial')
                    end do
                end do
            end do
            integral = sum(w(1:ng) * xi(1, 1:ng)**(2 * np))
            call check(error, abs(integral - 4 * moment_1d(2 * np)) > 1.0e-3_wp, &
                       'Gauss rule is not exact beyond its degree')
        end do
    contains
        pure real(wp) function moment_1d(p)
            integer, intent(in) :: p
            moment_1d = merge(2.0_wp / (p + 1), 0.0_wp, mod(p, 2) == 0)
        end function moment_1d
    end subroutine test_gauss_exact

    !> On distorted elements, x = A X + b gives F = A and det F = det A at every
    !> Gauss point, and Σ_g w_g det J_g equals the volume of the affine cube when
    !> the element is undistorted.
    subroutine test_deformation_gradient(error)
        type(error_t), allocatable, intent(out) :: error
        type(hexahedron_t) :: hex
        type(status_t) :: status
        real(wp) :: xref(3, hex27), x(3, hex27), a(3, 3), c(3), amap(3, 3), b(3), &
            f(3, 3), detf
        real(wp), allocatable :: dndx(:, :, :), wdv(:)
        integer(i8) :: seed
        integer :: e, nn, g, i
        seed = 13_i8
        do e = 1, 2
            nn = element_kinds(e)
            call new_hexahedron(hex, nn, status)
            call check(error, status%ok(), 'new_hexahedron')
            if (allocated(dndx)) deallocate (dndx, wdv)
            allocate (dndx(3, nn, hex%ngauss), wdv(hex%ngauss))
            call random_element(nn, seed, 0.0_wp, xref(:, 1:nn), a, c)
            call reference_gradients(hex, xref(:, 1:nn), dndx, wdv, status)
            call check_close(error, sum(wdv), 8 * det3(a), 1.0e-13_wp, &
                             'volume of a parallelepiped', rel=.true.)
            call random_element(nn, seed, 0.08_wp, xref(:, 1:nn), a, c)
            call reference_gradients(hex, xref(:, 1:nn), dndx, wdv, status)
            call check(error, status%ok(), 'reference gradients of a distorted element')
            call fill_random(amap(:, 1), seed, -0.5_wp, 0.5_wp)
            call fill_random(amap(:, 2), seed, -0.5_wp, 0.5_wp)
            call fill_random(amap(:, 3), seed, -0.5_wp, 0.5_wp)
            amap = amap + reshape([1, 0, 0, 0, 1, 0, 0, 0, 1] * 1.0_wp, [3, 3])
            call fill_random(b, seed, -1.0_wp, 1.0_wp)
            do i = 1, nn
                x(:, i) = matmul(amap, xref(:, i)) + b
            end do
            do g = 1, hex%ngauss
                call deformation_gradient(nn, dndx(:, :, g), x(:, 1:nn), f, detf, status)
                call check(error, all(abs(f - amap) < 1.0e-13_wp), 'F = A')
                call check_close(error, detf, det3(amap), 1.0e-13_wp, 'det F', rel=.true.)
            end do
            call check(error, status%ok(), 'status ok for det F > 0')
            if (allocated(error)) return
        end do
    end subroutine test_deformation_gradient

    !> A reflected configuration (det F < 0) is a solver failure with
    !> reason_det_f, so that the step is rejected for that reason.
    subroutine test_det_f_failure(error)
        type(error_t), allocatable, intent(out) :: error
        type(hexahedron_t) :: hex
        type(status_t) :: status
        real(wp) :: xref(3, hex8), x(3, hex8), a(3, 3), c(3), dndx(3, hex8, 8), wdv(8), &
            f(3, 3), detf
        integer(i8) :: seed
        seed = 14_i8
        call new_hexahedron(hex, hex8, status)
        call random_element(hex8, seed, 0.05_wp, xref, a, c)
        call reference_gradients(hex, xref, dndx, wdv, status)
        x = xref
        x(1, :) = -xref(1, :)
        call deformation_gradient(hex8, dndx(:, :, 1), x, f, detf, status)
        call check(error, status%code == status_solver_failure .and. &
                   status%reason == reason_det_f, 'det F <= 0 reported with reason_det_f')
        call check(error, detf < 0.0_wp, 'det F of a reflection is negative')
    end subroutine test_det_f_failure

    !> Uniaxial stress: F = diag(λ1, λ2, λ2) with λ2 from σ22 = 0; S against
    !> the Cauchy form σ = μ/J (B − I) + λ (J − 1) I pulled back,
    !> S = J F⁻¹ σ F⁻ᵀ, for stretches from compression to 100 % tension.
    subroutine test_uniaxial_tension(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: l1, l2, jac, g, dg, f(3, 3), e(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), &
            expected(3, 3), sigma11
        integer :: k, it
        call paper_material(mat)
        do k = 1, 6
            l1 = 0.6_wp + 0.28_wp * k
            ! Newton on g(λ2) = μ (λ2² − 1) + λ J (J − 1), J = λ1 λ2² (σ22 J = g).
            l2 = 1.0_wp
            do it = 1, 50
                jac = l1 * l2**2
                g = mat%mu * (l2**2 - 1.0_wp) + mat%lambda * jac * (jac - 1.0_wp)
                dg = 2.0_wp * mat%mu * l2 + mat%lambda * (2.0_wp * jac - 1.0_wp) * 2.0_wp * l1 * l2
                l2 = l2 - g / dg
            end do
            jac = l1 * l2**2
            sigma11 = mat%mu / jac * (l1**2 - 1.0_wp) + mat%lambda * (jac - 1.0_wp)
            expected = 0.0_wp
            expected(1, 1) = jac * sigma11 / l1**2
            f = 0.0_wp
            f(1, 1) = l1
            f(2, 2) = l2
            f(3, 3) = l2
            call strains(f, 0.0_wp * f, e, edot)
            call mat%stress(e, edot, s_el, s_v)
            call check_tensor(error, s_el, expected, abs(expected(1, 1)), stress_rtol, &
                              'uniaxial S')
            call check(error, all(s_v == 0.0_wp), 'no viscous stress at rest')
        end do
    end subroutine test_uniaxial_tension

    !> Simple shear F = I + γ e1⊗e2 (J = 1): S = μ [[−γ², γ, 0], [γ, 0, 0], 0];
    !> and the viscous stress of the shear rate γ̇ at the same state.
    subroutine test_simple_shear(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: gam, gdot, f(3, 3), fdot(3, 3), e(3, 3), edot(3, 3), s_el(3, 3), &
            s_v(3, 3), expected(3, 3), cinv(3, 3), d(3, 3), det
        integer :: k
        call paper_material(mat)
        gdot = 2.5_wp
        do k = 1, 5
            gam = 0.4_wp * k - 0.9_wp
            f = identity3
            f(1, 2) = gam
            fdot = 0.0_wp
            fdot(1, 2) = gdot
            call strains(f, fdot, e, edot)
            call mat%stress(e, edot, s_el, s_v)
            expected = 0.0_wp
            expected(1, 1) = -mat%mu * gam**2
            expected(1, 2) = mat%mu * gam
            expected(2, 1) = mat%mu * gam
            call check_tensor(error, s_el, expected, mat%mu * max(abs(gam), gam**2), &
                              stress_rtol, 'simple shear S')
            ! Shear flow: d = sym(Ḟ F⁻¹) = γ̇/2 (e1⊗e2 + e2⊗e1); Ė* is its pull-back
            ! F⁻¹ d F⁻ᵀ (J = 1), whose trace d : B⁻¹ = −γ γ̇ is not tr d = 0.
            d = 0.0_wp
            d(1, 2) = 0.5_wp * gdot
            d(2, 1) = 0.5_wp * gdot
            call inverse3(f, cinv, det)
            d = matmul(cinv, matmul(d, transpose(cinv)))
            call check_close(error, d(1, 1) + d(2, 2) + d(3, 3), -gam * gdot, 1.0e-14_wp, &
                             'trace of the scaled rate')
            expected = mat%beta * (2.0_wp * mat%mu * d + mat%lambda * (-gam * gdot) * identity3)
            call check_tensor(error, s_v, expected, maxval(abs(expected)), stress_rtol, &
                              'simple shear S_v')
        end do
    end subroutine test_simple_shear

    !> At E = 0 the viscous law is linear Kelvin–Voigt: S_v = 2η Ė + (λη/μ) tr Ė I.
    subroutine test_small_strain(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: e(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), expected(3, 3), eta
        integer(i8) :: seed
        seed = 21_i8
        call paper_material(mat)
        eta = mat%beta * mat%mu
        e = 0.0_wp
        call fill_random(edot(:, 1), seed, -1.0_wp, 1.0_wp)
        call fill_random(edot(:, 2), seed, -1.0_wp, 1.0_wp)
        call fill_random(edot(:, 3), seed, -1.0_wp, 1.0_wp)
        edot = 0.5_wp * (edot + transpose(edot))
        call mat%stress(e, edot, s_el, s_v)
        expected = 2.0_wp * eta * edot + mat%lambda * eta / mat%mu &
            * (edot(1, 1) + edot(2, 2) + edot(3, 3)) * identity3
        call check_tensor(error, s_v, expected, maxval(abs(expected)), stress_rtol, &
                          'small-strain Kelvin-Voigt')
        call check(error, all(abs(s_el) < 1.0e-12_wp * mat%mu), 'S_el(0) = 0')
        call check_close(error, eta, 1000.0_wp, 1.0e-12_wp, 'beta mu = eta', rel=.true.)
    end subroutine test_small_strain

    !> S_el = ∂W/∂E by central differences of the strain energy.
    subroutine test_energy_derivative(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: f(3, 3), e(3, 3), eh(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), fd(3, 3)
        real(wp), parameter :: h = 1.0e-6_wp
        integer(i8) :: seed
        integer :: jj
        seed = 22_i8
        call paper_material(mat)
        call fill_random(f(:, 1), seed, -0.3_wp, 0.3_wp)
        call fill_random(f(:, 2), seed, -0.3_wp, 0.3_wp)
        call fill_random(f(:, 3), seed, -0.3_wp, 0.3_wp)
        f = f + identity3
        call strains(f, 0.0_wp * f, e, edot)
        call mat%stress(e, edot, s_el, s_v)
        do jj = 1, 6
            ! dW = S : dE; a symmetric perturbation of E_kl = E_lk by h/2 each
            ! changes W by h S_kl.
            eh = e
            eh(voigt_i(jj), voigt_j(jj)) = eh(voigt_i(jj), voigt_j(jj)) + 0.5_wp * h
            eh(voigt_j(jj), voigt_i(jj)) = eh(voigt_j(jj), voigt_i(jj)) + 0.5_wp * h
            fd(1, 1) = mat%strain_energy(eh)
            eh = e
            eh(voigt_i(jj), voigt_j(jj)) = eh(voigt_i(jj), voigt_j(jj)) - 0.5_wp * h
            eh(voigt_j(jj), voigt_i(jj)) = eh(voigt_j(jj), voigt_i(jj)) - 0.5_wp * h
            fd(1, 1) = (fd(1, 1) - mat%strain_energy(eh)) / (2 * h)
            call check_close(error, fd(1, 1), s_el(voigt_i(jj), voigt_j(jj)), &
                             tangent_rtol * maxval(abs(s_el)), 'S = dW/dE')
        end do
    end subroutine test_energy_derivative

    !> ∂S_el/∂E, ∂S_v/∂E, ∂S_v/∂Ė against central differences at random
    !> large strains and rates; worst deviation relative to the largest entry.
    subroutine test_material_tangents(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: f(3, 3), fdot(3, 3), e(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), &
            d_el(6, 6), d_ve(6, 6), d_vr(6, 6), fd_el(6, 6), fd_ve(6, 6), fd_vr(6, 6), &
            dummy(6, 6, 3), sp(3, 3, 2), sm(3, 3, 2), eh(3, 3), h
        integer(i8) :: seed
        integer :: trial, jj, ii, which
        seed = 23_i8
        call paper_material(mat)
        do trial = 1, 5
            call fill_random(f(:, 1), seed, -0.4_wp, 0.4_wp)
            call fill_random(f(:, 2), seed, -0.4_wp, 0.4_wp)
            call fill_random(f(:, 3), seed, -0.4_wp, 0.4_wp)
            f = f + identity3
            call fill_random(fdot(:, 1), seed, -2.0_wp, 2.0_wp)
            call fill_random(fdot(:, 2), seed, -2.0_wp, 2.0_wp)
            call fill_random(fdot(:, 3), seed, -2.0_wp, 2.0_wp)
            call strains(f, fdot, e, edot)
            call mat%stress_tangent(e, edot, s_el, s_v, d_el, d_ve, d_vr)
            do which = 1, 2
                h = merge(1.0e-6_wp, 1.0e-4_wp, which == 1) ! E ~ 0.3, Ė ~ 2
                do jj = 1, 6
                    ! Engineering Voigt perturbation: Ê_J ± h, shear split in half.
                    eh = 0.0_wp
                    eh(voigt_i(jj), voigt_j(jj)) = merge(h, 0.5_wp * h, jj <= 3)
                    eh(voigt_j(jj), voigt_i(jj)) = merge(h, 0.5_wp * h, jj <= 3)
                    if (which == 1) then
                        call mat%stress(e + eh, edot, sp(:, :, 1), sp(:, :, 2))
                        call mat%stress(e - eh, edot, sm(:, :, 1), sm(:, :, 2))
                    else
                        call mat%stress(e, edot + eh, sp(:, :, 1), sp(:, :, 2))
                        call mat%stress(e, edot - eh, sm(:, :, 1), sm(:, :, 2))
                    end if
                    do ii = 1, 6
                        dummy(ii, jj, 1) = (sp(voigt_i(ii), voigt_j(ii), 1) &
                                            - sm(voigt_i(ii), voigt_j(ii), 1)) / (2 * h)
                        dummy(ii, jj, 2) = (sp(voigt_i(ii), voigt_j(ii), 2) &
                                            - sm(voigt_i(ii), voigt_j(ii), 2)) / (2 * h)
                    end do
                end do
                if (which == 1) then
                    fd_el = dummy(:, :, 1)
                    fd_ve = dummy(:, :, 2)
                else
                    fd_vr = dummy(:, :, 2)
                end if
            end do
            call check_tensor(error, d_el, fd_el, maxval(abs(d_el)), tangent_rtol, 'dS_el/dE')
            call check_tensor(error, d_ve, fd_ve, maxval(abs(d_ve)), tangent_rtol, 'dS_v/dE')
            call check_tensor(error, d_vr, fd_vr, maxval(abs(d_vr)), tangent_rtol, &
                              'dS_v/dEdot')
            if (allocated(error)) return
        end do
    end subroutine test_material_tangents

    !> Rigid rotation (F = R) gives S_el = 0; a rigid velocity on a deformed
    !> state (Ḟ = Ω F, Ω skew) gives S_v = 0; and both stresses are objective:
    !> S(QF, Q̇F + QḞ) = S(F, Ḟ).
    subroutine test_material_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        real(wp) :: r(3, 3), omega(3, 3), w(3), f(3, 3), fdot(3, 3), e(3, 3), edot(3, 3), &
            s_el(3, 3), s_v(3, 3), s_el2(3, 3), s_v2(3, 3)
        integer(i8) :: seed
        seed = 24_i8
        call paper_material(mat)
        call random_rotation(seed, r)
        call fill_random(w, seed, -3.0_wp, 3.0_wp)
        omega = reshape([0.0_wp, w(3), -w(2), -w(3), 0.0_wp, w(1), w(2), -w(1), 0.0_wp], [3, 3])
        call strains(r, matmul(omega, r), e, edot)
        call mat%stress(e, edot, s_el, s_v)
        call check(error, maxval(abs(s_el)) <= 1.0e-15_wp * 1.0e2_wp * mat%lambda, &
                   'S_el = 0 under rigid rotation')
        call check(error, maxval(abs(s_v)) <= 1.0e-15_wp * 1.0e2_wp * mat%beta * mat%lambda &
                   * norm2(w), 'S_v = 0 under rigid rotation and velocity')
        call fill_random(f(:, 1), seed, -0.3_wp, 0.3_wp)
        call fill_random(f(:, 2), seed, -0.3_wp, 0.3_wp)
        call fill_random(f(:, 3), seed, -0.3_wp, 0.3_wp)
        f = f + identity3
        call strains(f, matmul(omega, f), e, edot)
        call mat%stress(e, edot, s_el, s_v)
        call check(error, maxval(abs(s_v)) <= 1.0e-13_wp * mat%beta * mat%lambda * norm2(w), &
                   'S_v = 0 for a rigid velocity of a deformed body')
        call fill_random(fdot(:, 1), seed, -1.0_wp, 1.0_wp)
        call fill_random(fdot(:, 2), seed, -1.0_wp, 1.0_wp)
        call fill_random(fdot(:, 3), seed, -1.0_wp, 1.0_wp)
        call strains(f, fdot, e, edot)
        call mat%stress(e, edot, s_el, s_v)
        call strains(matmul(r, f), matmul(matmul(omega, r), f) + matmul(r, fdot), e, edot)
        call mat%stress(e, edot, s_el2, s_v2)
        call check_tensor(error, s_el2, s_el, maxval(abs(s_el)), stress_rtol, 'objective S_el')
        call check_tensor(error, s_v2, s_v, maxval(abs(s_v)), stress_rtol, 'objective S_v')
    end subroutine test_material_rigid

    !> Invalid constants are bad input naming the variable.
    subroutine test_material_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(neo_hooke_t) :: mat
        type(status_t) :: status
        call new_neo_hooke(mat, 7.0e5_wp, 0.5_wp, 920.0_wp, 0.0_wp, status)
        call check(error, .not. status%ok() .and. index(status%text(), 'poisson') > 0, &
                   'nu = 0.5 rejected')
        call new_neo_hooke(mat, -1.0_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        call check(error, .not. status%ok() .and. index(status%text(), 'young') > 0, &
                   'E < 0 rejected')
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, -1.0_wp, status)
        call check(error, .not. status%ok() .and. index(status%text(), 'viscosity') > 0, &
                   'eta < 0 rejected')
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        call check(error, status%ok() .and. mat%beta == 0.0_wp, 'undamped material')
    end subroutine test_material_bad_input
end module test_fe
