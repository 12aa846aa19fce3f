!> Finite elements: shape functions, quadrature and kinematics of the hexahedra.
module test_fe
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_det_f
    use flexmbs_fe_tensor, only: det3
    use flexmbs_fe_hexahedron, only: hexahedron_t, new_hexahedron, shape_functions, &
        gauss_rule, reference_gradients, deformation_gradient, hex8, hex27, hex_node_xi
    use test_problems, only: fill_random
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_fe, random_element

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
                 new_test('deformation_gradient_det_f', test_det_f_failure)]
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
end module test_fe
