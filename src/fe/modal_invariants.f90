!> The inertia invariants of a modal body (docs/theory.md §2.7): the volume
!> integrals of ρ over products of the reference position X (from the
!> centre of mass) and the mode shapes Φ_k, computed once from the
!> consistent FE mass matrix, from which the floating-frame mass matrix and
!> inertia forces follow for every η.
!>
!> The FE fields interpolate nodal vectors with the shape functions N_i, so
!> for fields a = Σ N_i a_i and b = Σ N_j b_j, ∫ρ a bᵀ dV = Σ_ij m_ij a_i
!> b_jᵀ, m_ij = ∫ρ N_i N_j dV: the consistent mass matrix is m_ij I₃, and
!> (M b)_i = Σ_j m_ij b_j. Every invariant is therefore Σ_i a_i (M b)_iᵀ,
!> exact for the mesh (no lumping). With s = X + Σ_k η_k Φ_k:
!>   ∫ρ s sᵀ = P₀ + Σ_k η_k (C_k + C_kᵀ) + Σ_kl η_k η_l P_kl,
!> P₀ = ∫ρ X Xᵀ, C_k = ∫ρ X Φ_kᵀ, P_kl = ∫ρ Φ_k Φ_lᵀ; the inertia tensor is
!> J = tr(∫ρ s sᵀ) I − ∫ρ s sᵀ. ∫ρ Φ_k dV (zero in the mean-axis frame of
!> flexmbs_fe_modal_basis) is kept so that tests can say so.
module flexmbs_fe_modal_invariants
    use flexmbs_core_kinds, only: wp
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_fe_modal_basis, only: modal_basis_t
    implicit none
    private

    public :: modal_invariants

    !> The invariants of a basis: from the mass matrix, positions and
    !> shapes, or from the FE body and its modal basis.
    interface modal_invariants
        module procedure invariants_of_shapes, invariants_of_basis
    end interface modal_invariants

    !> The invariants of one modal body.
    type, public :: modal_invariants_t
        real(wp) :: mass = 0.0_wp             !! ∫ρ dV
        real(wp) :: centre(3) = 0.0_wp        !! reference centre of mass (mesh frame)
        real(wp) :: second(3, 3) = 0.0_wp     !! P₀ = ∫ρ X Xᵀ, X from the centre
        real(wp), allocatable :: first(:, :)        !! (3, n): ∫ρ Φ_k
        real(wp), allocatable :: coupling(:, :, :)  !! (3, 3, n): C_k = ∫ρ X Φ_kᵀ
        real(wp), allocatable :: products(:, :, :, :) !! (3, 3, n, n): P_kl = ∫ρ Φ_k Φ_lᵀ
    end type modal_invariants_t

contains

    !> The invariants of the shapes (3 nodes x n, node by node x y z) on the
    !> mesh positions x with the consistent mass matrix `mass` (3 nodes x 3
    !> nodes, every node free).
    function invariants_of_shapes(mass, x, shapes) result(inv)
        type(csc_matrix_t), intent(in) :: mass
        real(wp), intent(in) :: x(:, :)
        real(wp), intent(in) :: shapes(:, :)
        type(modal_invariants_t) :: inv
        real(wp), allocatable :: unit(:), mu(:), ms(:, :), xc(:, :)
        integer :: nn, n, k, l, i
        nn = size(x, 2)
        n = size(shapes, 2)
        ! M e_x carries Σ_j m_ij in node i's x slot.
        allocate (unit(3 * nn), source=0.0_wp)
        unit(1::3) = 1.0_wp
        allocate (mu(3 * nn))
        call mass%matvec(unit, mu)
        inv%mass = sum(mu(1::3))
        do i = 1, 3
            inv%centre(i) = sum(mu(1::3) * x(i, :)) / inv%mass
        end do
        xc = x - spread(inv%centre, 2, nn)
        ! M X (node by node) = Σ_j m_ij X_j
        call mass%matvec(reshape(xc, [3 * nn]), mu)
        inv%second = density_product(reshape(xc, [3 * nn]), mu)
        allocate (ms(3 * nn, n))
        do k = 1, n
            call mass%matvec(shapes(:, k), ms(:, k))
        end do
        allocate (inv%first(3, n), inv%coupling(3, 3, n), inv%products(3, 3, n, n))
        do k = 1, n
            inv%first(:, k) = [sum(ms(1::3, k)), sum(ms(2::3, k)), sum(ms(3::3, k))]
            inv%coupling(:, :, k) = density_product(reshape(xc, [3 * nn]), ms(:, k))
            ! P_lk = P_klᵀ exactly (M is symmetric): the power balance of
            ! the modal body relies on it
            do l = k, n
                inv%products(:, :, k, l) = density_product(shapes(:, k), ms(:, l))
                inv%products(:, :, l, k) = transpose(inv%products(:, :, k, l))
            end do
        end do
    end function invariants_of_shapes

    !> The invariants of `basis`'s shapes on the FE body `body` it was
    !> computed from (its consistent mass and reference positions).
    function invariants_of_basis(body, basis) result(inv)
        type(flexible_body_t), intent(in) :: body
        type(modal_basis_t), intent(in) :: basis
        type(modal_invariants_t) :: inv
        inv = invariants_of_shapes(body%mass_matrix, body%mesh%x, basis%shapes)
    end function invariants_of_basis

    !> Σ_i a_i (M b)_iᵀ for nodal vectors a and mb = M b (node by node).
    pure function density_product(a, mb) result(p)
        real(wp), intent(in) :: a(:), mb(:)
        real(wp) :: p(3, 3)
        integer :: r, c
        do c = 1, 3
            do r = 1, 3
                p(r, c) = dot_product(a(r::3), mb(c::3))
            end do
        end do
    end function density_product
end module flexmbs_fe_modal_invariants
