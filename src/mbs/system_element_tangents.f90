!> Force elements of flexmbs_mbs_system with hand-coded derivatives
!> (constraint_derivatives = 'analytic'; 'ad' and 'ad_full' take the
!> dual-number laws of flexmbs_mbs_system_elements).
!>
!> The generalised force of element e is Q = Σ_k J_kᵀ w_k over its markers
!> k, J_k = [Jx; Jω] marker k's velocity-space Jacobian (hand-coded), w_k
!> its wrench (flexmbs_mbs_force_element_tangent, real). Its derivatives:
!>   ∂Q/∂v_l = Σ_k J_kᵀ δw_k, δw along the tangent (δẋ_m, δω_m) = J_m(:, l)
!>             of the marker m whose body owns the rate v_l;
!>   ∂Q/∂q_c = Σ_k J_kᵀ δw_k + (∂J_m/∂q_c)ᵀ w_m, δw along marker m's pose
!>             and motion tangent (δx, δa, δẋ, δω) per coordinate q_c.
!> The laws' δw are hand-coded; the markers' tangents per coordinate and
!> ∂J_m/∂q_c come from the markers' hand-coded kinematics differentiated
!> by dual numbers, as the joints' second derivatives do.
submodule (flexmbs_mbs_system) flexmbs_mbs_system_element_tangents
    use flexmbs_mbs_dual, only: operator(*), operator(-)
    use flexmbs_mbs_rotation_dual, only: cross_d => cross
    use flexmbs_mbs_force_element, only: element_energy, force_applied
    use flexmbs_mbs_force_element_tangent, only: frame_t, element_wrench_real, &
        element_wrench_tangent
    implicit none

contains

    !> f += the elements' generalised forces (real laws).
    module procedure add_element_forces_analytic
        type(frame_t) :: fr(2)
        real(wp) :: w(12)
        integer :: ie, side, k, n, b, iq, iv, l
        do ie = 1, size(self%elements)
            call element_frames(self, ie, q, v, fr)
            call element_wrench_real(self%elements(ie), t, fr(1), fr(2), w, status)
            if (.not. status%ok()) then
                status%message = 'force element ' // int_text(ie) // ': ' // status%message
                return
            end if
            do side = 1, 2
                k = side_marker(self, ie, side)
                if (k == 0) cycle
                associate (wk => self%work(side))
                    call velocity_jacobian(self, k, q, fr(side)%a, wk%jx, wk%ja, wk%jw, n)
                    call marker_offsets(self, k, b, iq, iv)
                    do l = 1, n
                        f(iv + l) = f(iv + l) + dot_product(wk%jx(:, l), &
                            w(6 * side - 5:6 * side - 3)) + dot_product(wk%jw(:, l), &
                            w(6 * side - 2:6 * side))
                    end do
                end associate
            end do
        end do
    end procedure add_element_forces_analytic

    !> ∂f/∂q and ∂f/∂v of the elements added into fq, fv (module header).
    module procedure add_element_derivatives_analytic
        type(frame_t) :: fr(2), tangent(2)
        type(marker_state_d) :: md
        type(element_frame_t) :: frd
        type(dual_t) :: jwd(3), g
        real(wp) :: w(12), dw(12)
        integer :: ie, m, km, n(2), nm, b, iqm, ivm, l, c, a, window, c0
        do ie = 1, size(self%elements)
            call element_frames(self, ie, q, v, fr)
            n = 0
            do m = 1, 2
                km = side_marker(self, ie, m)
                if (km > 0) call velocity_jacobian(self, km, q, fr(m)%a, self%work(m)%jx, &
                                                   self%work(m)%ja, self%work(m)%jw, n(m))
            end do
            do m = 1, 2
                km = side_marker(self, ie, m)
                if (km == 0) cycle
                call marker_offsets(self, km, b, iqm, ivm)
                associate (wm => self%work(m))
                    ! rates of marker m's body: its motion moves along J_m(:, l)
                    do l = 1, n(m)
                        tangent = frame_t()
                        tangent(m)%xd = wm%jx(:, l)
                        tangent(m)%w = wm%jw(:, l)
                        if (.not. law_tangent(tangent)) return
                        call scatter(fv, ivm + l)
                    end do
                    ! coordinates of marker m's body: pose and motion tangents by
                    ! dual numbers through the hand-coded marker kinematics, one
                    ! pass per window of its columns
                    do window = 1, marker_windows(self, km, .true.)
                        c0 = (window - 1) * window_columns
                        call marker_state_dual(self, km, q, v, seed_position, 1, md, wm%p, nm, &
                                               window=window)
                        call frame_of_state(md, frd)
                        call marker_jacobian_dual(self, km, wm%p, wm%jxd, wm%jad)
                        do c = 1, nm
                            tangent = frame_t()
                            tangent(m)%x = frd%x%der(c)
                            do a = 1, 3
                                tangent(m)%a(:, a) = frd%a(:, a)%der(c)
                            end do
                            tangent(m)%xd = frd%xd%der(c)
                            tangent(m)%w = frd%w%der(c)
                            if (.not. law_tangent(tangent)) return
                            call scatter(fq, iqm + c0 + c)
                            ! (∂J_m/∂q_c)ᵀ w_m: marker m's own rows
                            do l = 1, n(m)
                                jwd = 0.0_wp
                                do a = 1, 3
                                    jwd = jwd + 0.5_wp * cross_d(md%a(:, a), wm%jad(:, l, a))
                                end do
                                g = dot_product(wm%jxd(:, l), w(6 * m - 5:6 * m - 3)) + &
                                    dot_product(jwd, w(6 * m - 2:6 * m))
                                call fq%add(ivm + l, iqm + c0 + c, g%der(c))
                            end do
                        end do
                    end do
                end associate
            end do
        end do

    contains

        !> dw of element ie along `tangent`; .false. (status set) on failure.
        logical function law_tangent(tangent) result(ok)
            type(frame_t), intent(in) :: tangent(2)
            call element_wrench_tangent(self%elements(ie), t, fr(1), fr(2), tangent(1), &
                                        tangent(2), w, dw, status)
            ok = status%ok()
            if (.not. ok) status%message = 'force element ' // int_text(ie) // ': ' // &
                status%message
        end function law_tangent

        !> Column `col` of out: J_kᵀ dw_k on the rows of each marker k's body.
        subroutine scatter(out, col)
            type(accumulator_t), intent(inout) :: out
            integer, intent(in) :: col
            integer :: k, side, bk, iqk, ivk, r
            do side = 1, 2
                k = side_marker(self, ie, side)
                if (k == 0) cycle
                call marker_offsets(self, k, bk, iqk, ivk)
                do r = 1, n(side)
                    call out%add(ivk + r, col, dot_product(self%work(side)%jx(:, r), &
                        dw(6 * side - 5:6 * side - 3)) + dot_product(self%work(side)%jw(:, r), &
                        dw(6 * side - 2:6 * side)))
                end do
            end do
        end subroutine scatter
    end procedure add_element_derivatives_analytic

    !> Force and torque (global, about the marker origins) element ie
    !> exerts on marker i (column 1) and marker j (column 2; zero for a load):
    !> the real laws, whatever the derivatives' setting.
    module procedure system_element_wrench
        type(frame_t) :: fr(2)
        real(wp) :: w(12)
        call element_frames(self, ie, q, v, fr)
        call element_wrench_real(self%elements(ie), t, fr(1), fr(2), w, status)
        force = reshape([w(1:3), w(7:9)], [3, 2])
        torque = reshape([w(4:6), w(10:12)], [3, 2])
    end procedure system_element_wrench

    !> Potential energy of the elements' springs (the laws' element_energy,
    !> on the real frames).
    module procedure elements_energy
        type(frame_t) :: fr(2)
        type(element_frame_t) :: fi, fj
        integer :: ie
        e = 0.0_wp
        do ie = 1, size(self%elements)
            if (self%elements(ie)%kind == force_applied) cycle
            call element_frames(self, ie, q, v, fr)
            fi%x = fr(1)%x
            fi%a = fr(1)%a
            fi%xd = fr(1)%xd
            fi%w = fr(1)%w
            fj%x = fr(2)%x
            fj%a = fr(2)%a
            fj%xd = fr(2)%xd
            fj%w = fr(2)%w
            e = e + element_energy(self%elements(ie), fi, fj)
        end do
    end procedure elements_energy

    !> Marker of side 1 (i) or 2 (j) of element ie; 0 for a load's side 2.
    pure integer function side_marker(self, ie, side) result(k)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: ie, side
        k = merge(self%elements(ie)%marker_i, self%elements(ie)%marker_j, side == 1)
    end function side_marker

    !> The real frames of element ie's markers (a load's side 2: marker i's).
    pure subroutine element_frames(self, ie, q, v, fr)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: ie
        real(wp), intent(in) :: q(:), v(:)
        type(frame_t), intent(out) :: fr(2)
        type(marker_state_t) :: ms
        integer :: side, k, a
        do side = 1, 2
            k = side_marker(self, ie, side)
            if (k == 0) then
                fr(2) = fr(1)
                cycle
            end if
            call marker_state(self, k, q, v, ms)
            fr(side)%x = ms%x
            fr(side)%a = ms%a
            fr(side)%xd = ms%xd
            fr(side)%w = 0.0_wp
            do a = 1, 3
                fr(side)%w = fr(side)%w + 0.5_wp * cross(ms%a(:, a), ms%ad(:, a))
            end do
        end do
    end subroutine element_frames

    !> Marker k's velocity-space Jacobian: jx (origin) and jw (angular
    !> velocity, ½ Σ a_a × ∂a_a/∂v) for its body's n rates (ja: scratch).
    pure subroutine velocity_jacobian(self, k, q, axes, jx, ja, jw, n)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        real(wp), intent(in) :: q(:), axes(3, 3)
        real(wp), intent(out) :: jx(:, :), ja(:, :, :), jw(:, :) !! 3 x n at least
        integer, intent(out) :: n
        integer :: l, a
        call marker_jacobian(self, k, q, .false., jx, ja, n)
        jw(:, 1:n) = 0.0_wp
        do l = 1, n
            do a = 1, 3
                jw(:, l) = jw(:, l) + 0.5_wp * cross(axes(:, a), ja(:, l, a))
            end do
        end do
    end subroutine velocity_jacobian

    !> The dual element frame of a dual marker state: ω = ½ Σ_a a_a × ȧ_a.
    module procedure frame_of_state
        integer :: a
        fr%x = ms%x
        fr%a = ms%a
        fr%xd = ms%xd
        fr%w = 0.0_wp
        do a = 1, 3
            fr%w = fr%w + 0.5_wp * cross_d(ms%a(:, a), ms%ad(:, a))
        end do
    end procedure frame_of_state
end submodule flexmbs_mbs_system_element_tangents
