!> The paper's material (docs/theory.md §2.4):
!> compressible neo-Hookean elasticity with Kelvin–Voigt damping on the scaled
!> strain rate (Kübler, Eberhard & Geisler 2003).
!>
!> State: the Green–Lagrange strain E = (C − I)/2 and its rate Ė, with
!> C = FᵀF = I + 2E, J = det F = sqrt(det C). No internal variables.
!>
!> Elastic part, W = μ/2 (tr C − 3) − μ ln J + λ/2 (J − 1)²:
!>   S_el = 2 ∂W/∂C = μ (I − C⁻¹) + λ J (J − 1) C⁻¹,
!> using ∂J/∂C = J C⁻¹/2 and ∂ tr C/∂C = I.
!>
!> Viscous part, with the scaled rate Ė* = J C⁻¹ Ė C⁻¹ (the pull-back by F of
!> J times the spatial rate of deformation d = F⁻ᵀ Ė F⁻¹, hence objective, and
!> zero under rigid motion because Ė = 0 there):
!>   S_v = β (2μ Ė* + λ tr(Ė*) I),   β = η/μ,
!> so that for small strain (C ≈ I, J ≈ 1) S_v = 2η Ė + (λη/μ) tr(Ė) I,
!> linear Kelvin–Voigt with shear viscosity η.
!>
!> Tangents, in Voigt order (11, 22, 33, 12, 23, 13) of flexmbs_fe_tensor:
!> D(I, J) = ∂S_ij/∂E_kl with I = (i,j), J = (k,l), so that δS = D δÊ for the
!> engineering strain vector Ê = (E11, E22, E33, 2E12, 2E23, 2E13). With
!> A = C⁻¹, ∂A_ij/∂E_kl = −(A_ik A_jl + A_il A_jk) and ∂J/∂E_kl = J A_kl:
!>   ∂S_el/∂E = λ J (2J − 1) A ⊗ A + (μ − λ J (J − 1)) (A_ik A_jl + A_il A_jk);
!> with P = A Ė A (Ė* = J P):
!>   ∂Ė*_ij/∂Ė_kl = J (A_ik A_jl + A_il A_jk)/2,
!>   ∂Ė*_ij/∂E_kl = Ė*_ij A_kl − J (A_ik P_jl + A_il P_jk + P_ik A_jl + P_il A_jk),
!> and S_v is linear in Ė*. ∂S_v/∂Ė lacks major symmetry (λ I ⊗ J A²), so the
!> damping matrix is not symmetric away from the reference state.
module flexmbs_fe_neo_hooke
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_fe_tensor, only: det3, inverse3, identity3, voigt_i, voigt_j
    implicit none
    private

    !> Material constants: Lamé μ, λ (from E, ν), β = η/μ, density ρ.
    type, public :: neo_hooke_t
        real(wp) :: mu = 0.0_wp       !! shear modulus μ [Pa]
        real(wp) :: lambda = 0.0_wp   !! Lamé λ [Pa]
        real(wp) :: beta = 0.0_wp     !! η/μ [s]
        real(wp) :: density = 0.0_wp  !! ρ [kg/m³]
    contains
        procedure :: strain_energy => neo_hooke_strain_energy
        procedure :: stress => neo_hooke_stress
        procedure :: stress_tangent => neo_hooke_stress_tangent
    end type neo_hooke_t

    public :: new_neo_hooke

contains

    !> Material from Young's modulus, Poisson's ratio, density and the dynamic
    !> viscosity η (0: undamped). The paper's soft body: E = 7e5 Pa, ν = 0.3,
    !> ρ = 920 kg/m³, η = 1000 Pa·s.
    subroutine new_neo_hooke(material, young, poisson, density, viscosity, status)
        type(neo_hooke_t), intent(out) :: material
        real(wp), intent(in) :: young     !! E [Pa], > 0
        real(wp), intent(in) :: poisson   !! ν, in (−1, 1/2)
        real(wp), intent(in) :: density   !! ρ [kg/m³], > 0
        real(wp), intent(in) :: viscosity !! η [Pa·s], ≥ 0
        type(status_t), intent(out) :: status
        character(len=120) :: msg
        if (.not. (young > 0.0_wp)) then
            write (msg, '(a,es10.3,a)') 'material: young = ', young, ': must be positive'
        else if (.not. (poisson > -1.0_wp .and. poisson < 0.5_wp)) then
            write (msg, '(a,es10.3,a)') 'material: poisson = ', poisson, &
                ': must lie in (-1, 0.5)'
        else if (.not. (density > 0.0_wp)) then
            write (msg, '(a,es10.3,a)') 'material: density = ', density, ': must be positive'
        else if (.not. (viscosity >= 0.0_wp)) then
            write (msg, '(a,es10.3,a)') 'material: viscosity = ', viscosity, &
                ': must be >= 0'
        else
            material%mu = young / (2.0_wp * (1.0_wp + poisson))
            material%lambda = young * poisson / ((1.0_wp + poisson) * (1.0_wp - 2.0_wp * poisson))
            material%beta = viscosity / material%mu
            material%density = density
            return
        end if
        call status%set(status_bad_input, trim(msg))
    end subroutine new_neo_hooke

    !> C⁻¹ and J from E; J = sqrt(det C) is positive whenever E comes from an
    !> admissible F (the element checks det F first).
    pure subroutine metric(e, cinv, j)
        real(wp), intent(in) :: e(3, 3)
        real(wp), intent(out) :: cinv(3, 3), j
        real(wp) :: detc
        call inverse3(identity3 + 2.0_wp * e, cinv, detc)
        j = sqrt(max(detc, 0.0_wp))
    end subroutine metric

    !> Strain energy density W(E) per reference volume.
    pure real(wp) function neo_hooke_strain_energy(self, e) result(w)
        class(neo_hooke_t), intent(in) :: self
        real(wp), intent(in) :: e(3, 3)  !! Green–Lagrange strain
        real(wp) :: j
        j = sqrt(det3(identity3 + 2.0_wp * e))
        w = self%mu * (e(1, 1) + e(2, 2) + e(3, 3)) - self%mu * log(j) &
            + 0.5_wp * self%lambda * (j - 1.0_wp)**2
    end function neo_hooke_strain_energy

    !> Second Piola–Kirchhoff stresses S_el(E) and S_v(E, Ė).
    pure subroutine neo_hooke_stress(self, e, edot, s_el, s_v)
        class(neo_hooke_t), intent(in) :: self
        real(wp), intent(in) :: e(3, 3)      !! Green–Lagrange strain E
        real(wp), intent(in) :: edot(3, 3)   !! its rate Ė
        real(wp), intent(out) :: s_el(3, 3)  !! elastic S
        real(wp), intent(out) :: s_v(3, 3)   !! viscous S
        real(wp) :: cinv(3, 3), j, p(3, 3)
        call metric(e, cinv, j)
        call stress_at(self, cinv, j, edot, s_el, s_v, p)
    end subroutine neo_hooke_stress

    !> Both stresses from A = C⁻¹ and J; also P = A Ė A (0 when undamped).
    pure subroutine stress_at(self, a, j, edot, s_el, s_v, p)
        class(neo_hooke_t), intent(in) :: self
        real(wp), intent(in) :: a(3, 3), j, edot(3, 3)
        real(wp), intent(out) :: s_el(3, 3), s_v(3, 3), p(3, 3)
        real(wp) :: estar(3, 3)
        s_el = self%mu * identity3 + (self%lambda * j * (j - 1.0_wp) - self%mu) * a
        if (self%beta == 0.0_wp) then
            s_v = 0.0_wp
            p = 0.0_wp
            return
        end if
        p = matmul(a, matmul(edot, a))
        estar = j * p
        s_v = self%beta * (2.0_wp * self%mu * estar &
                           + self%lambda * (estar(1, 1) + estar(2, 2) + estar(3, 3)) * identity3)
    end subroutine stress_at

    !> Stresses and their tangents ∂S_el/∂E, ∂S_v/∂E, ∂S_v/∂Ė (Voigt 6x6, see
    !> the module header for the convention).
    pure subroutine neo_hooke_stress_tangent(self, e, edot, s_el, s_v, d_el, d_ve, d_vr)
        class(neo_hooke_t), intent(in) :: self
        real(wp), intent(in) :: e(3, 3), edot(3, 3)
        real(wp), intent(out) :: s_el(3, 3), s_v(3, 3)
        real(wp), intent(out) :: d_el(6, 6)  !! ∂S_el/∂E
        real(wp), intent(out) :: d_ve(6, 6)  !! ∂S_v/∂E
        real(wp), intent(out) :: d_vr(6, 6)  !! ∂S_v/∂Ė
        real(wp) :: a(3, 3), p(3, 3), a2(3, 3), estar(3, 3), j, c1, c2, &
            destar(6, 6), dtr(6)
        integer :: ii, jj, i, k, l, m
        call metric(e, a, j)
        call stress_at(self, a, j, edot, s_el, s_v, p)
        c1 = self%lambda * j * (2.0_wp * j - 1.0_wp)
        c2 = self%mu - self%lambda * j * (j - 1.0_wp)
        a2 = matmul(a, a)
        estar = j * p
        ! ∂S_v/∂Ė = 2μβ ∂Ė*/∂Ė + λβ I ⊗ ∂tr Ė*/∂Ė, with ∂ tr Ė*/∂Ė = J A².
        do jj = 1, 6
            k = voigt_i(jj)
            l = voigt_j(jj)
            do ii = 1, 6
                i = voigt_i(ii)
                m = voigt_j(ii)
                d_el(ii, jj) = c1 * a(i, m) * a(k, l) + c2 * (a(i, k) * a(m, l) + a(i, l) * a(m, k))
                d_vr(ii, jj) = self%beta * self%mu * j * (a(i, k) * a(m, l) + a(i, l) * a(m, k))
                if (ii <= 3) d_vr(ii, jj) = d_vr(ii, jj) + self%beta * self%lambda * j * a2(k, l)
                destar(ii, jj) = estar(i, m) * a(k, l) - j * (a(i, k) * p(m, l) &
                    + a(i, l) * p(m, k) + p(i, k) * a(m, l) + p(i, l) * a(m, k))
            end do
        end do
        ! ∂S_v/∂E through ∂Ė*/∂E, the trace taken row-wise.
        dtr = destar(1, :) + destar(2, :) + destar(3, :)
        d_ve = 2.0_wp * self%beta * self%mu * destar
        do ii = 1, 3
            d_ve(ii, :) = d_ve(ii, :) + self%beta * self%lambda * dtr
        end do
    end subroutine neo_hooke_stress_tangent
end module flexmbs_fe_neo_hooke
