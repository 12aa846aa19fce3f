!> Force elements of flexmbs_mbs_system (the type and the procedures'
!> interfaces are there; the laws are flexmbs_mbs_force_element's).
!>
!> A wrench (F, n) on marker k (F at its origin x, n global) does virtual
!> work F·δx + n·δθ: its generalised force is Jxᵀ F + Jωᵀ n with the
!> marker's velocity-space Jacobians, Jω(:, l) = ½ Σ_k a_k × ∂a_k/∂v_l (so
!> the same code serves rigid, chain and node markers). Evaluated on dual
!> numbers seeded with the bodies' coordinates (or velocities), the
!> generalised forces carry their exact ∂f/∂q (or ∂f/∂v), the markers'
!> Jacobians' own dependence on q included. That is the 'ad' and 'ad_full'
!> path; 'analytic' (the default) takes the hand-coded laws of
!> flexmbs_mbs_system_element_tangents.
submodule (flexmbs_mbs_system) flexmbs_mbs_system_elements
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_mbs_dual, only: operator(-), operator(*), matmul
    use flexmbs_mbs_rotation_dual, only: cross_d => cross
    use flexmbs_mbs_force_element, only: element_wrench, &
        element_uses_rotation, force_element_name, element_frame_t, force_applied, &
        force_bushing
    implicit none

contains

    !> Check the elements against the markers and keep them.
    module procedure place_elements
        integer :: k, side, mk
        character(len=:), allocatable :: where
        allocate (self%elements(size(elements)))
        do k = 1, size(elements)
            associate (e => elements(k))
                where = 'mbs system: force element ' // int_text(k) // ' (' // &
                    force_element_name(e%kind) // ')'
                if (e%kind < 1 .or. e%kind > force_applied) then
                    call status%set(status_bad_input, where // ': unknown kind ' // &
                        int_text(e%kind))
                    return
                end if
                do side = 1, 2
                    mk = merge(e%marker_i, e%marker_j, side == 1)
                    if (side == 2 .and. e%kind == force_applied) then
                        if (mk == 0) cycle
                        call status%set(status_bad_input, where // ': an applied load &
                            &acts on one marker (marker_j = ' // int_text(mk) // ')')
                        return
                    end if
                    if (mk < 1 .or. mk > size(self%markers)) then
                        call status%set(status_bad_input, where // ': marker ' // &
                            int_text(mk) // ': must name markers 1 .. ' // &
                            int_text(size(self%markers)))
                        return
                    end if
                    if (allocated(self%markers(mk)%nodes)) then
                        call status%set(status_bad_input, where // ': marker ' // &
                            int_text(mk) // ' is a node-set centroid (spherical joints &
                            &only): the element needs a node or a marker frame')
                        return
                    end if
                    if (element_uses_rotation(e) .and. self%markers(mk)%flexible > 0) then
                        call status%set(status_bad_input, where // ': marker ' // &
                            int_text(mk) // ' is a node marker (no rotation): the element &
                            &needs a marker frame')
                        return
                    end if
                end do
                if (e%kind /= force_applied .and. e%marker_i == e%marker_j) then
                    call status%set(status_bad_input, where // ': marker_i and marker_j &
                        &are both marker ' // int_text(e%marker_i))
                    return
                end if
                if (e%kind == force_bushing .and. .not. (all(ieee_is_finite(e%stiffness6)) &
                    .and. all(ieee_is_finite(e%damping6)))) then
                    call status%set(status_bad_input, where // ': K or C is not finite')
                    return
                end if
            end associate
            self%elements(k) = elements(k)
        end do
    end procedure place_elements

    !> Generalised forces gi(1:ni), gj(1:nj) of element e on the velocity
    !> columns of its markers' bodies, seeded by `seed` (seed_position:
    !> tangents ∂/∂q, seed_velocity: ∂/∂v) in the columns of `window`
    !> (marker_state_dual): directions 1..di of marker i's body and offj + 1
    !> .. offj + dj of marker j's (offj = 0: the same body).
    module procedure element_generalised
        type(marker_state_d) :: mi, mj
        type(element_frame_t) :: fi, fj
        type(dual_t) :: force(3, 2), torque(3, 2)
        integer :: bi, bj, iqi, iqj, ivi, ivj
        associate (e => self%elements(ie), w1 => self%work(1), w2 => self%work(2))
            call marker_state_dual(self, e%marker_i, q, v, seed, 1, mi, w1%p, di, window=window)
            call frame_of_state(mi, fi)
            ni = marker_columns(self, e%marker_i, .false.)
            offj = di
            dj = 0
            nj = 0
            if (e%marker_j > 0) then
                call marker_offsets(self, e%marker_i, bi, iqi, ivi)
                call marker_offsets(self, e%marker_j, bj, iqj, ivj)
                if (bi /= 0 .and. bi == bj .and. iqi == iqj) offj = 0
                call marker_state_dual(self, e%marker_j, q, v, seed, offj + 1, mj, w2%p, dj, &
                                       window=window)
                nj = marker_columns(self, e%marker_j, .false.)
            else
                ! an applied load: marker j is unused, give it marker i's frame
                mj = mi
            end if
            call frame_of_state(mj, fj)
            call element_wrench(e, t, fi, fj, force, torque, status)
            if (.not. status%ok()) then
                status%message = 'force element ' // int_text(ie) // ': ' // status%message
                return
            end if
            call project(e%marker_i, w1, mi, force(:, 1), torque(:, 1), ni, gi)
            if (e%marker_j > 0) call project(e%marker_j, w2, mj, force(:, 2), &
                                             torque(:, 2), nj, gj)
        end associate
    contains
        !> g(l) = Jx(:, l)·F + Jω(:, l)·n, l = 1 .. n (Jacobians in wk).
        subroutine project(k, wk, m, f, n_, n, g)
            integer, intent(in) :: k, n
            type(marker_work_t), intent(inout) :: wk
            type(dual_t), intent(in) :: f(3), n_(3)
            type(marker_state_d), intent(in) :: m
            type(dual_t), intent(inout) :: g(:)
            type(dual_t) :: jw(3)
            integer :: l, a
            call marker_jacobian_dual(self, k, wk%p, wk%jxd, wk%jad)
            do l = 1, n
                jw = 0.0_wp
                do a = 1, 3
                    jw = jw + 0.5_wp * cross_d(m%a(:, a), wk%jad(:, l, a))
                end do
                g(l) = dot_product(wk%jxd(:, l), f) + dot_product(jw, n_)
            end do
        end subroutine project
    end procedure element_generalised

    !> f += the elements' generalised forces.
    module procedure add_element_forces
        integer :: ie, ni, nj, di, dj, offj, b, iq, iv
        if (self%derivatives == constraint_derivatives_analytic) then
            call add_element_forces_analytic(self, t, q, v, f, status)
            return
        end if
        associate (gi => self%work(1)%g, gj => self%work(2)%g)
            do ie = 1, size(self%elements)
                call element_generalised(self, ie, t, q, v, seed_velocity, 1, gi, gj, ni, nj, &
                                         di, dj, offj, status)
                if (.not. status%ok()) return
                call marker_offsets(self, self%elements(ie)%marker_i, b, iq, iv)
                f(iv + 1:iv + ni) = f(iv + 1:iv + ni) + gi(1:ni)%val
                if (nj == 0) cycle
                call marker_offsets(self, self%elements(ie)%marker_j, b, iq, iv)
                f(iv + 1:iv + nj) = f(iv + 1:iv + nj) + gj(1:nj)%val
            end do
        end associate
    end procedure add_element_forces

    !> ∂f/∂q and ∂f/∂v of the elements added into fq, fv (dense or sparse):
    !> one dual pass per window of the markers' columns.
    module procedure add_element_derivatives
        integer :: ie, ni, nj, di, dj, offj, pass, window, nw, c0
        logical :: position_space
        if (self%derivatives == constraint_derivatives_analytic) then
            call add_element_derivatives_analytic(self, t, q, v, fq, fv, status)
            return
        end if
        associate (gi => self%work(1)%g, gj => self%work(2)%g)
            do ie = 1, size(self%elements)
                do pass = 1, 2
                    position_space = pass == 1
                    associate (e => self%elements(ie))
                        nw = marker_windows(self, e%marker_i, position_space)
                        if (e%marker_j > 0) nw = max(nw, marker_windows(self, e%marker_j, &
                                                                        position_space))
                    end associate
                    do window = 1, nw
                        c0 = (window - 1) * window_columns
                        call element_generalised(self, ie, t, q, v, &
                            merge(seed_position, seed_velocity, position_space), window, gi, &
                            gj, ni, nj, di, dj, offj, status)
                        if (.not. status%ok()) return
                        associate (e => self%elements(ie))
                            if (position_space) then
                                call scatter(e%marker_i, gi, ni, fq)
                                if (nj > 0) call scatter(e%marker_j, gj, nj, fq)
                            else
                                call scatter(e%marker_i, gi, ni, fv)
                                if (nj > 0) call scatter(e%marker_j, gj, nj, fv)
                            end if
                        end associate
                    end do
                end do
            end do
        end associate
    contains
        !> Rows of marker k's body: tangents 1..di to marker i's body's
        !> columns c0 + 1 .., offj + 1 .. offj + dj to marker j's (once if the
        !> same body).
        subroutine scatter(k, g, n, out)
            integer, intent(in) :: k, n
            type(dual_t), intent(in) :: g(:)
            type(accumulator_t), intent(inout) :: out
            integer :: b, iq, iv, ci, cj, l, c
            call marker_offsets(self, k, b, iq, iv)
            call marker_offsets(self, self%elements(ie)%marker_i, b, ci, c)
            if (.not. position_space) ci = c
            cj = 0
            if (self%elements(ie)%marker_j > 0) then
                call marker_offsets(self, self%elements(ie)%marker_j, b, cj, c)
                if (.not. position_space) cj = c
            end if
            ci = ci + c0
            cj = cj + c0
            do l = 1, n
                do c = 1, di
                    call out%add(iv + l, ci + c, g(l)%der(c))
                end do
                if (offj == 0 .and. di > 0) cycle
                do c = 1, dj
                    call out%add(iv + l, cj + c, g(l)%der(offj + c))
                end do
            end do
        end subroutine scatter
    end procedure add_element_derivatives

    !> The elements' columns in the ∂f/∂q and ∂f/∂v patterns: each marker's
    !> body's rows times both markers' bodies' columns.
    module procedure add_element_patterns
        integer :: ie, side, other, ks, ko, b, iqs, ivs, iqo, ivo
        do ie = 1, size(self%elements)
            associate (e => self%elements(ie))
                do side = 1, 2
                    ks = merge(e%marker_i, e%marker_j, side == 1)
                    if (ks == 0) cycle
                    call marker_offsets(self, ks, b, iqs, ivs)
                    do other = 1, 2
                        ko = merge(e%marker_i, e%marker_j, other == 1)
                        if (ko == 0) cycle
                        call marker_offsets(self, ko, b, iqo, ivo)
                        call fq%add_range(ivs, iqo, marker_columns(self, ks, .false.), &
                                          marker_columns(self, ko, .true.))
                        call fv%add_range(ivs, ivo, marker_columns(self, ks, .false.), &
                                          marker_columns(self, ko, .false.))
                    end do
                end do
            end associate
        end do
    end procedure add_element_patterns
end submodule flexmbs_mbs_system_elements
