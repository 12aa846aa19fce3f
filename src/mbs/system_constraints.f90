!> Joint rows and their first derivatives; reactions of flexmbs_mbs_system
!> (the type and the procedures' interfaces are there).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_constraints
    implicit none

contains

    ! ------------------------------------------------ joint rows, first derivatives

    !> Joint k's blocks ci, cj of G (velocity space) or c_q (position space),
    !> and its c_t, by the selected constraint_derivatives; ni, nj columns.
    module procedure joint_first_derivatives
        type(marker_state_t) :: mi, mj
        type(marker_state_d) :: mid, mjd
        real(wp) :: drv(3)
        type(dual_t) :: cd(max_rows)
        integer :: seed, nr, r, td, pass, wi, wj, ci0, cj0
        ci = 0.0_wp
        cj = 0.0_wp
        ct = 0.0_wp
        associate (jt => self%joints(k), w1 => self%work(1), w2 => self%work(2))
            nr = jt%joint%nrows
            drv = joint_driver(self, k, t)
            if (self%derivatives /= constraint_derivatives_ad_full) then
                call marker_state(self, jt%marker_i, q, self%zero_v, mi)
                call marker_state(self, jt%marker_j, q, self%zero_v, mj)
                call marker_jacobian(self, jt%marker_i, q, position_space, w1%jx, w1%ja, ni, &
                                     w1%p)
                call marker_jacobian(self, jt%marker_j, q, position_space, w2%jx, w2%ja, nj, &
                                     w2%p)
            else
                ni = marker_columns(self, jt%marker_i, position_space)
                nj = marker_columns(self, jt%marker_j, position_space)
            end if
            if (self%derivatives == constraint_derivatives_analytic) then
                call joint_jacobian(jt%joint, mi, w1%jx(:, 1:ni), w1%ja(:, 1:ni, :), mj, &
                                    w2%jx(:, 1:nj), w2%ja(:, 1:nj, :), drv, ci(1:nr, 1:ni), &
                                    cj(1:nr, 1:nj))
                call joint_rows(joint_part_time_derivative, jt%joint, mi, mj, drv, ct(1:nr))
                return
            end if
            ! AD: one pass per window of each marker's columns (module header)
            seed = merge(seed_position, seed_velocity_space, position_space)
            do pass = 1, max(marker_windows(self, jt%marker_i, position_space), &
                             marker_windows(self, jt%marker_j, position_space))
                ci0 = (pass - 1) * window_columns
                cj0 = ci0
                wi = max(0, min(window_columns, ni - ci0))
                wj = max(0, min(window_columns, nj - cj0))
                if (self%derivatives == constraint_derivatives_ad) then
                    ! the frames' tangents are the markers' Jacobian columns: AD
                    ! of the vector relations only
                    call seeded_frame(mi, w1%jx(:, ci0 + 1:ci0 + wi), &
                                      w1%ja(:, ci0 + 1:ci0 + wi, :), 0, mid)
                    call seeded_frame(mj, w2%jx(:, cj0 + 1:cj0 + wj), &
                                      w2%ja(:, cj0 + 1:cj0 + wj, :), wi, mjd)
                else
                    call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed, 1, mid, &
                                           w1%p, wi, pose_only=.true., window=pass)
                    call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed, 1 + wi, &
                                           mjd, w2%p, wj, pose_only=.true., window=pass)
                end if
                ! tangents: marker i's window, marker j's, time
                td = wi + wj + 1
                call joint_value_d(jt%joint, mid, mjd, driver_dual(drv, td), cd(1:nr))
                do r = 1, nr
                    ci(r, ci0 + 1:ci0 + wi) = cd(r)%der(1:wi)
                    cj(r, cj0 + 1:cj0 + wj) = cd(r)%der(wi + 1:wi + wj)
                    if (pass == 1) ct(r) = cd(r)%der(td)
                end do
            end do
        end associate
    end procedure joint_first_derivatives

    module procedure system_constraint
        type(marker_state_t) :: mi, mj
        integer :: k
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                call marker_state(self, jt%marker_i, q, self%zero_v, mi)
                call marker_state(self, jt%marker_j, q, self%zero_v, mj)
                call joint_value(jt%joint, mi, mj, joint_driver(self, k, t), &
                                 g(jt%row0 + 1:jt%row0 + jt%joint%nrows))
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                call frame_value(fr, q, g(fr%row0 + 1:fr%row0 + node_frame_rows))
            end associate
        end do
    end procedure system_constraint

    !> G = c_q T, nc x nv.
    module procedure system_constraint_jacobian
        call self%acc(block_cv)%start_dense(self%nc, self%nv)
        call assemble_first_derivative(self, t, q, .false., self%acc(block_cv))
        call self%acc(block_cv)%get_dense(gmat)
    end procedure system_constraint_jacobian

    !> c_q, nc x nq.
    module procedure system_constraint_position_jacobian
        call self%acc(block_cq)%start_dense(self%nc, self%nq)
        call assemble_first_derivative(self, t, q, .true., self%acc(block_cq))
        call self%acc(block_cq)%get_dense(gq)
    end procedure system_constraint_position_jacobian

    !> G (velocity space) or c_q (position space) added into out.
    module procedure assemble_first_derivative
        real(wp) :: ct(max_rows)
        integer :: k, ni, nj, r0, nr
        do k = 1, size(self%joints)
            associate (jt => self%joints(k), ci => self%work(1)%c, cj => self%work(2)%c)
                r0 = jt%row0
                nr = jt%joint%nrows
                call joint_first_derivatives(self, k, t, q, position_space, ci, cj, ni, nj, ct)
                call add_columns(self, jt%marker_i, position_space, ci(1:nr, 1:ni), r0, out)
                call add_columns(self, jt%marker_j, position_space, cj(1:nr, 1:nj), r0, out)
            end associate
        end do
        do k = 1, size(self%frames)
            block
                real(wp) :: fb(node_frame_rows, frame_columns(self%frames(k), position_space))
                call frame_first_derivatives(self, k, q, position_space, fb)
                r0 = self%frames(k)%row0
                call add_frame_columns(self%frames(k), position_space, fb, r0, out)
            end block
        end do
    end procedure assemble_first_derivative

    !> c_t = ∂c/∂t.
    module procedure system_constraint_time_derivative
        real(wp) :: ct(max_rows)
        integer :: k, ni, nj
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                call joint_first_derivatives(self, k, t, q, .false., self%work(1)%c, &
                                             self%work(2)%c, ni, nj, ct)
                gt(jt%row0 + 1:jt%row0 + jt%joint%nrows) = ct(1:jt%joint%nrows)
            end associate
        end do
        ! node frames do not depend on t
        do k = 1, size(self%frames)
            gt(self%frames(k)%row0 + 1:self%frames(k)%row0 + node_frame_rows) = 0.0_wp
        end do
    end procedure system_constraint_time_derivative

    !> γ = (G v)_q T v + 2 G_t v + c_tt: hand-coded (convective accelerations
    !> of the markers), or AD of the hand-coded G v along q' = T v (direction
    !> 1) and t (direction 2).
    module procedure system_constraint_curvature
        type(marker_state_t) :: mi, mj
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: xi(3, 1), ai(3, 1, 3), xj(3, 1), aj(3, 1, 3), cid(max_rows, 1), &
            cjd(max_rows, 1), ctd(max_rows), drvd(3), cv
        type(marker_state_j) :: mij, mjj
        type(jet_t) :: drvj(3), cjet(max_rows)
        real(wp) :: drv(3), tt(max_rows)
        integer :: k, r0, nr, ni, nj, r
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                r0 = jt%row0
                nr = jt%joint%nrows
                drv = joint_driver(self, k, t)
                if (self%derivatives == constraint_derivatives_analytic) then
                    call marker_state(self, jt%marker_i, q, v, mi)
                    call marker_state(self, jt%marker_j, q, v, mj)
                    call joint_rows(joint_part_convective, jt%joint, mi, mj, drv, &
                                    gamma(r0 + 1:r0 + nr))
                    call joint_rows(joint_part_time_terms, jt%joint, mi, mj, drv, tt(1:nr))
                    gamma(r0 + 1:r0 + nr) = gamma(r0 + 1:r0 + nr) + tt(1:nr)
                else if (self%derivatives == constraint_derivatives_ad) then
                    ! c(s) along the markers' motion and t + s: γ = c''(0)
                    call marker_state(self, jt%marker_i, q, v, mi)
                    call marker_state(self, jt%marker_j, q, v, mj)
                    call moving_frame(mi, mij)
                    call moving_frame(mj, mjj)
                    ! s(t + σ) to second order (the values use s only)
                    drvj(1) = jet_t(drv(1), drv(2), drv(3))
                    drvj(2) = jet_t(drv(2), drv(3), 0.0_wp)
                    drvj(3) = jet_t(drv(3), 0.0_wp, 0.0_wp)
                    call joint_value_j(jt%joint, mij, mjj, drvj, cjet(1:nr))
                    gamma(r0 + 1:r0 + nr) = cjet(1:nr)%f2
                else
                    ! G v = the joint's first derivatives along the markers'
                    ! velocities (linear in the columns): one column each
                    call marker_state_dual(self, jt%marker_i, q, v, seed_rate, 1, mid, &
                                           self%work(1)%p, ni)
                    call marker_state_dual(self, jt%marker_j, q, v, seed_rate, 1, mjd, &
                                           self%work(2)%p, nj)
                    xi(:, 1) = mid%xd
                    ai(:, 1, :) = mid%ad
                    xj(:, 1) = mjd%xd
                    aj(:, 1, :) = mjd%ad
                    drvd = driver_dual(drv, 2)
                    call joint_jacobian_d(jt%joint, mid, xi, ai, mjd, xj, aj, drvd, &
                                          cid(1:nr, :), cjd(1:nr, :))
                    call joint_rows_d(joint_part_time_derivative, jt%joint, mid, mjd, drvd, &
                                      ctd(1:nr))
                    do r = 1, nr
                        cv = cid(r, 1) + cjd(r, 1)
                        gamma(r0 + r) = cv%der(1) + 2.0_wp * cv%der(2) + ctd(r)%der(2)
                    end do
                end if
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                if (self%derivatives == constraint_derivatives_analytic) then
                    call frame_curvature(fr, q, v, gamma(fr%row0 + 1:fr%row0 + node_frame_rows))
                else
                    call frame_curvature_ad(fr, q, v, &
                                            gamma(fr%row0 + 1:fr%row0 + node_frame_rows))
                end if
            end associate
        end do
    end procedure system_constraint_curvature

    ! ------------------------------------------------ reactions

    !> The force and torque joint k exerts on the body of marker i (column 1)
    !> and of marker j (column 2), global components, the torque about the
    !> marker's origin: the generalised force −C_bᵀλ_k of the equations of
    !> motion M v' = f − Gᵀλ (module header). On the ground, which has no
    !> columns in G, and on a chain link, whose columns are the chain's joint
    !> coordinates, it is the generalised force along the marker frame's own
    !> displacement and rotation (marker_frame_reaction): on the ground the
    !> bearing load, for a massless joint −F_j and the matching torque.
    module procedure system_joint_reaction
        real(wp) :: ct(max_rows)
        real(wp) :: gen(6), a(3, 3)
        integer :: ni, nj, side, b, iq, iv, mk, r0, nr
        force = 0.0_wp
        torque = 0.0_wp
        associate (jt => self%joints(k), ci => self%work(1)%c, cj => self%work(2)%c)
            r0 = jt%row0
            nr = jt%joint%nrows
            call joint_first_derivatives(self, k, t, q, .false., ci, cj, ni, nj, ct)
            do side = 1, 2
                mk = merge(jt%marker_i, jt%marker_j, side == 1)
                call marker_offsets(self, mk, b, iq, iv)
                ! the ground (no coordinates) and a chain link: along the
                ! marker frame's own displacement and rotation
                if (b == 0 .or. self%markers(mk)%chain > 0) then
                    gen = marker_frame_reaction(self, k, t, q, lambda(r0 + 1:r0 + nr), side)
                    force(:, side) = gen(1:3)
                    torque(:, side) = gen(4:6)
                    cycle
                end if
                if (b < 0) then
                    ! a node takes the force only
                    if (side == 1) force(:, side) = -matmul(lambda(r0 + 1:r0 + nr), ci(1:nr, 1:3))
                    if (side == 2) force(:, side) = -matmul(lambda(r0 + 1:r0 + nr), cj(1:nr, 1:3))
                    cycle
                end if
                if (side == 1) then
                    gen = -matmul(lambda(r0 + 1:r0 + nr), ci(1:nr, 1:6))
                else
                    gen = -matmul(lambda(r0 + 1:r0 + nr), cj(1:nr, 1:6))
                end if
                a = rotation_matrix(q(iq + 4:iq + 7))
                force(:, side) = gen(1:3)
                ! gen(4:6) = s_b × Aᵀ F + n′ (body-fixed moment about the centre)
                torque(:, side) = matmul(a, gen(4:6) - cross(self%markers(mk)%position, &
                                                              matmul(transpose(a), gen(1:3))))
            end do
        end associate
    end procedure system_joint_reaction

    !> −C_mᵀλ of joint k for the marker of `side` (1: i, 2: j), C_m the rows'
    !> derivatives along the marker's displacement δx and its rotation δθ
    !> (global; δa = δθ × a for each axis a): the force and the torque about
    !> the marker's origin that the joint exerts there, whatever carries it.
    function marker_frame_reaction(self, k, t, q, lambda, side) result(gen)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k, side
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(in) :: lambda(:) !! joint k's multipliers
        real(wp) :: gen(6)
        type(marker_state_t) :: mi, mj
        real(wp) :: jxi(3, 6), jai(3, 6, 3), jxj(3, 6), jaj(3, 6, 3), c(max_rows, 6, 2)
        integer :: nr
        associate (jt => self%joints(k))
            nr = jt%joint%nrows
            call marker_state(self, jt%marker_i, q, self%zero_v, mi)
            call marker_state(self, jt%marker_j, q, self%zero_v, mj)
            call frame_tangents(mi, jxi, jai)
            call frame_tangents(mj, jxj, jaj)
            call joint_jacobian(jt%joint, mi, jxi, jai, mj, jxj, jaj, joint_driver(self, k, t), &
                                c(1:nr, :, 1), c(1:nr, :, 2))
            gen = -matmul(lambda, c(1:nr, :, side))
        end associate
    end function marker_frame_reaction

    !> A marker frame's tangents along (δx, δθ): x' = δx, a' = δθ × a.
    pure subroutine frame_tangents(m, jx, ja)
        type(marker_state_t), intent(in) :: m
        real(wp), intent(out) :: jx(3, 6), ja(3, 6, 3)
        integer :: l, a
        jx = 0.0_wp
        ja = 0.0_wp
        do l = 1, 3
            jx(l, l) = 1.0_wp
            do a = 1, 3
                ja(:, 3 + l, a) = cross(identity3(:, l), m%a(:, a))
            end do
        end do
    end subroutine frame_tangents
end submodule flexmbs_mbs_system_constraints
