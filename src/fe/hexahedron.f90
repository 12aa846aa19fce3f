!> Isoparametric hexahedra on the reference cube [-1,1]³: the 8-node trilinear
!> and the 27-node triquadratic Lagrange element, Gauss rules 2³ and 3³, and the
!> total Lagrangian kinematics (reference gradients, deformation gradient).
!>
!> Both elements are tensor products of 1D Lagrange polynomials: node a sits at
!> natural coordinates (ξ_a, η_a, ζ_a) and N_a(ξ) = L_a(ξ) L_a(η) L_a(ζ), with
!> linear L on {-1, 1} or quadratic L on {-1, 0, 1}. Node order is VTK's
!> (VTK_HEXAHEDRON, VTK_TRIQUADRATIC_HEXAHEDRON) so output needs no permutation:
!> corners, then (27-node) edge midpoints, face centres (-x,+x,-y,+y,-z,+z),
!> centre.
module flexmbs_fe_hexahedron
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_det_f
    use flexmbs_fe_tensor, only: det3, inverse3
    implicit none
    private

    integer, parameter, public :: hex8 = 8    !! nodes of the trilinear element
    integer, parameter, public :: hex27 = 27  !! nodes of the triquadratic element
    integer, parameter, public :: max_nodes = 27
    integer, parameter, public :: max_gauss = 27

    !> Natural coordinates of the nodes (VTK order); the first 8 are the corners.
    real(wp), parameter, public :: hex_node_xi(3, hex27) = reshape([ &
        -1, -1, -1,   1, -1, -1,   1,  1, -1,  -1,  1, -1, &
        -1, -1,  1,   1, -1,  1,   1,  1,  1,  -1,  1,  1, &
         0, -1, -1,   1,  0, -1,   0,  1, -1,  -1,  0, -1, &
         0, -1,  1,   1,  0,  1,   0,  1,  1,  -1,  0,  1, &
        -1, -1,  0,   1, -1,  0,   1,  1,  0,  -1,  1,  0, &
        -1,  0,  0,   1,  0,  0,   0, -1,  0,   0,  1,  0, &
         0,  0, -1,   0,  0,  1,   0,  0,  0] * 1.0_wp, [3, hex27])

    !> An element type: node count, Gauss rule, and the shape functions and their
    !> natural derivatives tabulated at the Gauss points (fixed-size storage so
    !> that element routines need no allocation).
    type, public :: hexahedron_t
        integer :: nnode = 0
        integer :: ngauss = 0
        real(wp) :: xi(3, max_gauss) = 0.0_wp       !! Gauss points
        real(wp) :: weight(max_gauss) = 0.0_wp      !! Gauss weights
        real(wp) :: n(max_nodes, max_gauss) = 0.0_wp       !! N_a(ξ_g)
        real(wp) :: dn(3, max_nodes, max_gauss) = 0.0_wp   !! ∂N_a/∂ξ_j at ξ_g
    end type hexahedron_t

    public :: new_hexahedron, shape_functions, gauss_rule, reference_gradients, &
        deformation_gradient, nodal_gradient

contains

    !> Element type with nnode = hex8 or hex27 and npoint Gauss points per
    !> direction (2 or 3; default 2 for hex8, 3 for hex27, the full rules).
    subroutine new_hexahedron(hex, nnode, status, npoint)
        type(hexahedron_t), intent(out) :: hex
        integer, intent(in) :: nnode
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: npoint
        integer :: np, g
        character(len=80) :: msg
        if (nnode /= hex8 .and. nnode /= hex27) then
            write (msg, '(a,i0,a)') 'hexahedron: nnode = ', nnode, ': must be 8 or 27'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        np = merge(2, 3, nnode == hex8)
        if (present(npoint)) np = npoint
        if (np /= 2 .and. np /= 3) then
            write (msg, '(a,i0,a)') 'hexahedron: Gauss points per direction = ', np, &
                ': must be 2 or 3'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        hex%nnode = nnode
        hex%ngauss = np**3
        call gauss_rule(np, hex%xi(:, 1:hex%ngauss), hex%weight(1:hex%ngauss))
        do g = 1, hex%ngauss
            call shape_functions(nnode, hex%xi(:, g), hex%n(1:nnode, g), hex%dn(:, 1:nnode, g))
        end do
    end subroutine new_hexahedron

    !> 1D Lagrange basis on {-1,1} (order 1) or {-1,0,1} (order 2) for the node
    !> at natural coordinate c, and its derivative, at s.
    pure subroutine lagrange_1d(order, c, s, l, dl)
        integer, intent(in) :: order
        real(wp), intent(in) :: c, s
        real(wp), intent(out) :: l, dl
        if (order == 1) then
            l = 0.5_wp * (1.0_wp + c * s)
            dl = 0.5_wp * c
        else if (c == 0.0_wp) then
            l = 1.0_wp - s * s
            dl = -2.0_wp * s
        else
            l = 0.5_wp * s * (s + c)
            dl = s + 0.5_wp * c
        end if
    end subroutine lagrange_1d

    !> Shape functions N(nnode) and natural derivatives dn(3, nnode) at xi.
    pure subroutine shape_functions(nnode, xi, n, dn)
        integer, intent(in) :: nnode      !! hex8 or hex27
        real(wp), intent(in) :: xi(3)     !! natural coordinates
        real(wp), intent(out) :: n(nnode), dn(3, nnode)
        real(wp) :: l(3), dl(3)
        integer :: a, j, order
        order = merge(1, 2, nnode == hex8)
        do a = 1, nnode
            do j = 1, 3
                call lagrange_1d(order, hex_node_xi(j, a), xi(j), l(j), dl(j))
            end do
            n(a) = l(1) * l(2) * l(3)
            dn(1, a) = dl(1) * l(2) * l(3)
            dn(2, a) = l(1) * dl(2) * l(3)
            dn(3, a) = l(1) * l(2) * dl(3)
        end do
    end subroutine shape_functions

    !> Tensor Gauss–Legendre rule with np = 2 or 3 points per direction
    !> (exact for polynomials of degree 2np−1 in each variable).
    pure subroutine gauss_rule(np, xi, w)
        integer, intent(in) :: np
        real(wp), intent(out) :: xi(3, np**3), w(np**3)
        real(wp) :: s(3), ws(3)
        integer :: i, j, k, g
        if (np == 2) then
            s(1:2) = [-1.0_wp, 1.0_wp] / sqrt(3.0_wp)
            ws(1:2) = 1.0_wp
        else
            s(1:3) = [-sqrt(0.6_wp), 0.0_wp, sqrt(0.6_wp)]
            ws(1:3) = [5.0_wp, 8.0_wp, 5.0_wp] / 9.0_wp
        end if
        g = 0
        do k = 1, np
            do j = 1, np
                do i = 1, np
                    g = g + 1
                    xi(:, g) = [s(i), s(j), s(k)]
                    w(g) = ws(i) * ws(j) * ws(k)
                end do
            end do
        end do
    end subroutine gauss_rule

    !> Reference-configuration gradients ∂N_a/∂X at every Gauss point and the
    !> volume weights w_g det J_g, from the reference nodal positions X.
    !> A non-positive det J (inverted or degenerate reference element) is bad input.
    subroutine reference_gradients(hex, xref, dndx, wdv, status)
        type(hexahedron_t), intent(in) :: hex
        real(wp), intent(in) :: xref(3, hex%nnode)               !! reference positions
        real(wp), intent(out) :: dndx(3, hex%nnode, hex%ngauss)  !! ∂N_a/∂X_J
        real(wp), intent(out) :: wdv(hex%ngauss)                 !! w_g det J_g
        type(status_t), intent(out) :: status
        real(wp) :: jac(3, 3), jinv(3, 3), detj
        integer :: g, nn
        character(len=120) :: msg
        nn = hex%nnode
        do g = 1, hex%ngauss
            ! J_ij = ∂X_i/∂ξ_j; ∂N/∂X = J⁻ᵀ ∂N/∂ξ.
            jac = matmul(xref, transpose(hex%dn(:, 1:nn, g)))
            call inverse3(jac, jinv, detj)
            if (.not. (detj > 0.0_wp)) then
                write (msg, '(a,es10.3,a,i0)') 'hexahedron: reference det J = ', detj, &
                    ' <= 0 at Gauss point ', g
                call status%set(status_bad_input, trim(msg))
                return
            end if
            dndx(:, :, g) = matmul(transpose(jinv), hex%dn(:, 1:nn, g))
            wdv(g) = hex%weight(g) * detj
        end do
    end subroutine reference_gradients

    !> Material gradient Σ_a u_a ⊗ ∂N_a/∂X of a nodal field u (F for positions,
    !> Ḟ for velocities), summed node by node without array temporaries.
    pure subroutine nodal_gradient(nnode, dndx, u, grad)
        integer, intent(in) :: nnode
        real(wp), intent(in) :: dndx(3, nnode) !! ∂N_a/∂X at one Gauss point
        real(wp), intent(in) :: u(3, nnode)    !! nodal values
        real(wp), intent(out) :: grad(3, 3)    !! grad(i, J) = Σ_a u_ia ∂N_a/∂X_J
        integer :: a, j
        grad = 0.0_wp
        do a = 1, nnode
            do j = 1, 3
                grad(:, j) = grad(:, j) + u(:, a) * dndx(j, a)
            end do
        end do
    end subroutine nodal_gradient

    !> Deformation gradient F_iJ = Σ_a x_ia ∂N_a/∂X_J and J = det F.
    !> det F ≤ 0 is reported as a solver failure with reason_det_f (the step
    !> must be rejected).
    subroutine deformation_gradient(nnode, dndx, x, f, detf, status)
        integer, intent(in) :: nnode
        real(wp), intent(in) :: dndx(3, nnode) !! ∂N_a/∂X at one Gauss point
        real(wp), intent(in) :: x(3, nnode)    !! nodal absolute positions
        real(wp), intent(out) :: f(3, 3), detf
        type(status_t), intent(inout) :: status
        character(len=80) :: msg
        call nodal_gradient(nnode, dndx, x, f)
        detf = det3(f)
        if (.not. (detf > 0.0_wp)) then
            write (msg, '(a,es10.3)') 'det F = ', detf
            call status%set(status_solver_failure, trim(msg), reason_det_f)
        end if
    end subroutine deformation_gradient
end module flexmbs_fe_hexahedron
