!> Element routines of the total Lagrangian solid in absolute nodal
!> coordinates: consistent mass, internal force k = ∫ Bᵀ F S dV (eq. 3) split
!> into elastic and viscous parts, tangent stiffness ∂k/∂x and damping ∂k/∂ẋ.
!>
!> Nodal unknowns are the absolute positions x_a (and velocities ẋ_a); element
!> vectors are ordered node by node, dof 3(a−1)+i. The reference gradients
!> ∂N_a/∂X and weights w_g det J_g come from reference_gradients, computed once.
!>
!> With the engineering Voigt strain Ê (flexmbs_fe_tensor) and
!> B(I, ia) = ∂Ê_I/∂x_ia, i.e. B(kl, ia) = F_ik N_a,l + F_il N_a,k (halved on
!> the diagonal), eq. (3) reads k_ia = Σ_g w_g det J_g B(:, ia)·S, and since
!> Ė = sym(FᵀḞ) also B(I, ia) = ∂Ê̇_I/∂ẋ_ia. Differentiating,
!>   ∂k/∂x = Σ_g [Bᵀ (D_el + D_ve) B + Bᵀ D_vr Ḃ + (N_a,J S_JL N_b,L) δ_ik] w det J,
!>   ∂k/∂ẋ = Σ_g Bᵀ D_vr B w det J,
!> where Ḃ is B with Ḟ in place of F (∂Ê̇/∂x) and the last term of ∂k/∂x is the
!> geometric (initial stress) part with the total stress S = S_el + S_v.
!>
!> No allocation: local work arrays have the fixed size of the largest element.
module flexmbs_fe_element
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_fe_tensor, only: identity3, voigt_i, voigt_j
    use flexmbs_fe_hexahedron, only: hexahedron_t, max_nodes, deformation_gradient, &
        nodal_gradient
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    implicit none
    private

    public :: element_mass, element_forces

contains

    !> Consistent mass per direction, m_ab = Σ_g ρ N_a N_b w_g det J_g; the
    !> element mass matrix is m ⊗ I₃ (absolute coordinates make it constant).
    pure subroutine element_mass(hex, wdv, density, m)
        type(hexahedron_t), intent(in) :: hex
        real(wp), intent(in) :: wdv(hex%ngauss)              !! w_g det J_g
        real(wp), intent(in) :: density                     !! ρ
        real(wp), intent(out) :: m(hex%nnode, hex%nnode)    !! m_ab
        integer :: g, a, b, nn
        nn = hex%nnode
        m = 0.0_wp
        do g = 1, hex%ngauss
            do b = 1, nn
                do a = 1, nn
                    m(a, b) = m(a, b) + density * wdv(g) * hex%n(a, g) * hex%n(b, g)
                end do
            end do
        end do
    end subroutine element_mass

    !> F, Ḟ, E, Ė at one Gauss point.
    subroutine kinematics(nn, dndx, x, v, f, fdot, e, edot, status)
        integer, intent(in) :: nn
        real(wp), intent(in) :: dndx(3, nn), x(3, nn), v(3, nn)
        real(wp), intent(out) :: f(3, 3), fdot(3, 3), e(3, 3), edot(3, 3)
        type(status_t), intent(inout) :: status
        real(wp) :: detf
        call deformation_gradient(nn, dndx, x, f, detf, status)
        call nodal_gradient(nn, dndx, v, fdot)
        e = 0.5_wp * (matmul(transpose(f), f) - identity3)
        edot = 0.5_wp * (matmul(transpose(fdot), f) + matmul(transpose(f), fdot))
    end subroutine kinematics

    !> Strain–displacement matrix B(I, 3(a−1)+i) = ∂Ê_I/∂x_ia for the given F.
    pure subroutine strain_matrix(nn, dndx, f, b)
        integer, intent(in) :: nn
        real(wp), intent(in) :: dndx(3, nn), f(3, 3)
        real(wp), intent(out) :: b(6, 3 * nn)
        integer :: a, i, ii, k, l
        do a = 1, nn
            do i = 1, 3
                do ii = 1, 6
                    k = voigt_i(ii)
                    l = voigt_j(ii)
                    if (ii <= 3) then
                        b(ii, 3 * (a - 1) + i) = f(i, k) * dndx(k, a)
                    else
                        b(ii, 3 * (a - 1) + i) = f(i, k) * dndx(l, a) + f(i, l) * dndx(k, a)
                    end if
                end do
            end do
        end do
    end subroutine strain_matrix

    !> Internal forces of one element, elastic ∫ Bᵀ F S_el dV and viscous
    !> ∫ Bᵀ F S_v dV, each (3, nnode); with `stiffness` and `damping` present
    !> also the tangent stiffness ∂(k_el + k_v)/∂x and the damping matrix
    !> ∂k_v/∂ẋ, both (3 nnode, 3 nnode). det F ≤ 0 at a Gauss point returns a
    !> solver failure with reason_det_f (outputs then zero).
    subroutine element_forces(hex, material, dndx, wdv, x, v, k_el, k_v, status, stiffness, &
                              damping)
        type(hexahedron_t), intent(in) :: hex
        type(neo_hooke_t), intent(in) :: material
        real(wp), intent(in) :: dndx(3, hex%nnode, hex%ngauss) !! ∂N_a/∂X
        real(wp), intent(in) :: wdv(hex%ngauss)                !! w_g det J_g
        real(wp), intent(in) :: x(3, hex%nnode)   !! nodal positions
        real(wp), intent(in) :: v(3, hex%nnode)   !! nodal velocities
        real(wp), intent(out) :: k_el(3, hex%nnode), k_v(3, hex%nnode)
        type(status_t), intent(out) :: status
        real(wp), intent(out), optional :: stiffness(3 * hex%nnode, 3 * hex%nnode) !! ∂k/∂x
        real(wp), intent(out), optional :: damping(3 * hex%nnode, 3 * hex%nnode)   !! ∂k/∂ẋ
        real(wp) :: f(3, 3), fdot(3, 3), e(3, 3), edot(3, 3), s_el(3, 3), s_v(3, 3), &
            d_el(6, 6), d_ve(6, 6), d_vr(6, 6), b(6, 3 * max_nodes), bdot(6, 3 * max_nodes), &
            db(6, 3 * max_nodes), dr_b(6, 3 * max_nodes), sn(3, max_nodes), geo, &
            fs_el(3, 3), fs_v(3, 3)
        logical :: tangents
        integer :: g, nn, ndof, p, q, a, bn, i
        nn = hex%nnode
        ndof = 3 * nn
        tangents = present(stiffness) .and. present(damping)
        call clear_outputs()
        do g = 1, hex%ngauss
            call kinematics(nn, dndx(:, :, g), x, v, f, fdot, e, edot, status)
            if (.not. status%ok()) then
                call clear_outputs()
                return
            end if
            if (.not. tangents) then
                call material%stress(e, edot, s_el, s_v)
            else
                call material%stress_tangent(e, edot, s_el, s_v, d_el, d_ve, d_vr)
            end if
            ! k_ia = Σ_JL F_iJ S_JL N_a,L (eq. 3); node by node so that every
            ! temporary has a fixed size (no heap allocation).
            fs_el = wdv(g) * matmul(f, s_el)
            fs_v = wdv(g) * matmul(f, s_v)
            do a = 1, nn
                k_el(:, a) = k_el(:, a) + matmul(fs_el, dndx(:, a, g))
                k_v(:, a) = k_v(:, a) + matmul(fs_v, dndx(:, a, g))
            end do
            if (.not. tangents) cycle
            call strain_matrix(nn, dndx(:, :, g), f, b(:, 1:ndof))
            call strain_matrix(nn, dndx(:, :, g), fdot, bdot(:, 1:ndof))
            ! db = (D_el + D_ve) B + D_vr Ḃ (∂Ŝ/∂x), dr_b = D_vr B (∂Ŝ/∂ẋ)
            d_ve = d_el + d_ve
            do q = 1, ndof
                db(:, q) = matmul(d_ve, b(:, q)) + matmul(d_vr, bdot(:, q))
                dr_b(:, q) = matmul(d_vr, b(:, q))
            end do
            do q = 1, ndof
                do p = 1, ndof
                    stiffness(p, q) = stiffness(p, q) + wdv(g) * dot_product(b(:, p), db(:, q))
                    damping(p, q) = damping(p, q) + wdv(g) * dot_product(b(:, p), dr_b(:, q))
                end do
            end do
            ! Geometric part: (∂N_a/∂X)ᵀ S ∂N_b/∂X on the 3x3 diagonal of block ab.
            s_el = s_el + s_v
            do a = 1, nn
                sn(:, a) = matmul(s_el, dndx(:, a, g))
            end do
            do bn = 1, nn
                do a = 1, nn
                    geo = wdv(g) * dot_product(dndx(:, a, g), sn(:, bn))
                    do i = 1, 3
                        stiffness(3 * (a - 1) + i, 3 * (bn - 1) + i) = &
                            stiffness(3 * (a - 1) + i, 3 * (bn - 1) + i) + geo
                    end do
                end do
            end do
        end do

    contains

        subroutine clear_outputs()
            k_el = 0.0_wp
            k_v = 0.0_wp
            if (tangents) then
                stiffness = 0.0_wp
                damping = 0.0_wp
            end if
        end subroutine clear_outputs
    end subroutine element_forces
end module flexmbs_fe_element
