!> Second derivatives by AD of flexmbs_mbs_system
!> (the type and the procedures' interfaces are there).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_second_derivatives
    implicit none

contains

    ! ------------------------------------------------ second derivatives (AD)

    module procedure system_constraint_jacobian_derivatives
        call self%acc(block_cq)%start_dense(self%nc, self%nq)
        call self%acc(block_rq)%start_dense(self%nv, self%nq)
        call jacobian_derivatives_into(self, t, q, w, lambda, self%acc(block_cq), self%acc(block_rq))
        call self%acc(block_cq)%get_dense(gwq)
        call self%acc(block_rq)%get_dense(gtlq)
    end procedure system_constraint_jacobian_derivatives

    module procedure system_constraint_jacobian_derivatives_sparse
        call self%acc(block_cq)%start_sparse(self%patterns%constraint_q)
        call self%acc(block_rq)%start_sparse(self%patterns%reaction_q)
        call jacobian_derivatives_into(self, t, q, w, lambda, self%acc(block_cq), self%acc(block_rq))
        call self%acc(block_cq)%get_values(gwq, 'mbs system: d(G w)/dq', status)
        call self%acc(block_rq)%get_values(gtlq, 'mbs system: d(G^T lambda)/dq', status)
    end procedure system_constraint_jacobian_derivatives_sparse

    !> ∂(G w)/∂q (nc x nq) and ∂(Gᵀλ)/∂q (nv x nq) added into gwq, gtlq: AD of
    !> the hand-coded G along the position unit vectors of the joint's two
    !> bodies. A set marker's side of G is constant: it adds nothing, and
    !> its rows of Gᵀλ are left out.
    module procedure jacobian_derivatives_into
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: s
        integer :: k, r0, nr, qi, qj, ni, nj, r, l, bi, bj, iqi, iqj, ivi, ivj, pass, c0
        logical :: keep_i, keep_j
        do k = 1, size(self%joints)
            associate (jt => self%joints(k), w1 => self%work(1), w2 => self%work(2))
                if (jt%linear) cycle ! G constant
                keep_i = .not. is_set_marker(self, jt%marker_i)
                keep_j = .not. is_set_marker(self, jt%marker_j)
                r0 = jt%row0
                nr = jt%joint%nrows
                ni = marker_columns(self, jt%marker_i, .false.)
                nj = marker_columns(self, jt%marker_j, .false.)
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                ! one pass per window of the bodies' positions (module header)
                do pass = 1, max(marker_windows(self, jt%marker_i, .true.), &
                                 marker_windows(self, jt%marker_j, .true.))
                    c0 = (pass - 1) * window_columns
                    call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed_position, 1, &
                                           mid, w1%p, qi, pose_only=.true., window=pass)
                    call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed_position, &
                                           1 + qi, mjd, w2%p, qj, pose_only=.true., window=pass)
                    call marker_jacobian_dual(self, jt%marker_i, w1%p, w1%jxd, w1%jad)
                    call marker_jacobian_dual(self, jt%marker_j, w2%p, w2%jxd, w2%jad)
                    call joint_jacobian_d(jt%joint, mid, w1%jxd(:, 1:ni), w1%jad(:, 1:ni, :), &
                                          mjd, w2%jxd(:, 1:nj), w2%jad(:, 1:nj, :), &
                                          driver_dual(joint_driver(self, k, t), 0), &
                                          w1%cd(1:nr, 1:ni), w2%cd(1:nr, 1:nj))
                    do r = 1, nr
                        s = 0.0_wp
                        if (keep_i) s = dot_product(w1%cd(r, 1:ni), w(ivi + 1:ivi + ni))
                        if (keep_j) s = s + dot_product(w2%cd(r, 1:nj), w(ivj + 1:ivj + nj))
                        call add_tangents(gwq, r0 + r, s, qi, iqi + c0, qj, iqj + c0, &
                                          keep_i, keep_j)
                    end do
                    do l = 1, merge(ni, 0, keep_i)
                        call add_tangents(gtlq, ivi + l, &
                                          dot_product(w1%cd(1:nr, l), lambda(r0 + 1:r0 + nr)), &
                                          qi, iqi + c0, qj, iqj + c0, keep_i, keep_j)
                    end do
                    do l = 1, merge(nj, 0, keep_j)
                        call add_tangents(gtlq, ivj + l, &
                                          dot_product(w2%cd(1:nr, l), lambda(r0 + 1:r0 + nr)), &
                                          qi, iqi + c0, qj, iqj + c0, keep_i, keep_j)
                    end do
                end do
            end associate
        end do
        call frame_jacobian_derivatives(self, q, w, lambda, gwq, gtlq)
    end procedure jacobian_derivatives_into

    !> The node frames' part of jacobian_derivatives_into: their blocks of
    !> ∂(G w)/∂q and ∂(Gᵀλ)/∂q added into gwq, gtlq.
    subroutine frame_jacobian_derivatives(self, q, w, lambda, gwq, gtlq)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), w(:), lambda(:)
        type(accumulator_t), intent(inout) :: gwq, gtlq
        integer :: k, l, r
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                block
                    real(wp) :: bq(node_frame_rows, frame_columns(fr, .true.)), &
                        bl(frame_columns(fr, .false.), frame_columns(fr, .true.))
                    integer :: c
                    call frame_rate_q(fr, q, w, bq)
                    call add_frame_columns(fr, .true., bq, fr%row0, gwq)
                    call frame_gtl_q(fr, q, lambda(fr%row0 + 1:fr%row0 + node_frame_rows), bl)
                    do l = 1, size(bl, 2)
                        c = frame_column(fr, l, .true.)
                        do r = 1, size(bl, 1)
                            call gtlq%add(frame_column(fr, r, .false.), c, bl(r, l))
                        end do
                    end do
                end block
            end associate
        end do
    end subroutine frame_jacobian_derivatives

    !> out(row, q columns of body i and j) += tangents of s (directions 1..qi
    !> for body i at offset iqi, qi+1..qi+qj for body j at offset iqj).
    module procedure add_tangents
        integer :: l
        if (keep_i) then
            do l = 1, qi
                call out%add(row, iqi + l, s%der(l))
            end do
        end if
        if (keep_j) then
            do l = 1, qj
                call out%add(row, iqj + l, s%der(qi + l))
            end do
        end if
    end procedure add_tangents

    module procedure system_constraint_time_derivative_jacobian
        call self%acc(block_cq)%start_dense(self%nc, self%nq)
        call time_derivative_jacobian_into(self, t, q, self%acc(block_cq))
        call self%acc(block_cq)%get_dense(dq)
    end procedure system_constraint_time_derivative_jacobian

    module procedure system_constraint_time_derivative_jacobian_sparse
        call self%acc(block_cq)%start_sparse(self%patterns%constraint_q)
        call time_derivative_jacobian_into(self, t, q, self%acc(block_cq))
        call self%acc(block_cq)%get_values(values, 'mbs system: dg_I/dq', status)
    end procedure system_constraint_time_derivative_jacobian_sparse

    !> ∂c_t/∂q added into dq: AD of the hand-coded c_t.
    module procedure time_derivative_jacobian_into
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: ctd(max_rows)
        integer :: k, nr, qi, qj, r, bi, bj, iqi, iqj, ivi, ivj, pass, c0
        logical :: keep_i, keep_j
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                if (jt%linear) cycle ! c_t = 0
                keep_i = .not. is_set_marker(self, jt%marker_i)
                keep_j = .not. is_set_marker(self, jt%marker_j)
                nr = jt%joint%nrows
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                do pass = 1, max(marker_windows(self, jt%marker_i, .true.), &
                                 marker_windows(self, jt%marker_j, .true.))
                    c0 = (pass - 1) * window_columns
                    call marker_state_dual(self, jt%marker_i, q, self%zero_v, seed_position, 1, &
                                           mid, self%work(1)%p, qi, pose_only=.true., &
                                           window=pass)
                    call marker_state_dual(self, jt%marker_j, q, self%zero_v, seed_position, &
                                           1 + qi, mjd, self%work(2)%p, qj, pose_only=.true., &
                                           window=pass)
                    call joint_rows_d(joint_part_time_derivative, jt%joint, mid, mjd, &
                                      driver_dual(joint_driver(self, k, t), 0), ctd(1:nr))
                    do r = 1, nr
                        call add_tangents(dq, jt%row0 + r, ctd(r), qi, iqi + c0, qj, iqj + c0, &
                                          keep_i, keep_j)
                    end do
                end do
            end associate
        end do
    end procedure time_derivative_jacobian_into

    module procedure system_constraint_curvature_derivatives
        call self%acc(block_cq)%start_dense(self%nc, self%nq)
        call self%acc(block_cv)%start_dense(self%nc, self%nv)
        call curvature_derivatives_into(self, t, q, v, self%acc(block_cq), self%acc(block_cv))
        call self%acc(block_cq)%get_dense(gq)
        call self%acc(block_cv)%get_dense(gv)
    end procedure system_constraint_curvature_derivatives

    module procedure system_constraint_curvature_derivatives_sparse
        call self%acc(block_cq)%start_sparse(self%patterns%constraint_q)
        call self%acc(block_cv)%start_sparse(self%patterns%constraint_v)
        call curvature_derivatives_into(self, t, q, v, self%acc(block_cq), self%acc(block_cv))
        call self%acc(block_cq)%get_values(gq, 'mbs system: dgamma/dq', status)
        call self%acc(block_cv)%get_values(gv, 'mbs system: dgamma/dv', status)
    end procedure system_constraint_curvature_derivatives_sparse

    !> ∂γ/∂q and ∂γ/∂v added into gq, gv: AD of the hand-coded γ, one pass
    !> along the positions and one along the velocities of the joint's two bodies.
    module procedure curvature_derivatives_into
        type(marker_state_d) :: mid, mjd
        type(dual_t) :: conv(max_rows), tt(max_rows), drvd(3)
        integer :: k, nr, ni, nj, r, bi, bj, iqi, iqj, ivi, ivj, pass, seed, window, c0
        logical :: keep_i, keep_j
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                if (jt%linear) cycle ! γ = 0
                keep_i = .not. is_set_marker(self, jt%marker_i)
                keep_j = .not. is_set_marker(self, jt%marker_j)
                nr = jt%joint%nrows
                drvd = driver_dual(joint_driver(self, k, t), 0)
                call marker_offsets(self, jt%marker_i, bi, iqi, ivi)
                call marker_offsets(self, jt%marker_j, bj, iqj, ivj)
                do pass = 1, 2
                    seed = merge(seed_position, seed_velocity, pass == 1)
                    do window = 1, max(marker_windows(self, jt%marker_i, pass == 1), &
                                       marker_windows(self, jt%marker_j, pass == 1))
                        c0 = (window - 1) * window_columns
                        call marker_state_dual(self, jt%marker_i, q, v, seed, 1, mid, &
                                               self%work(1)%p, ni, window=window)
                        call marker_state_dual(self, jt%marker_j, q, v, seed, 1 + ni, mjd, &
                                               self%work(2)%p, nj, window=window)
                        call joint_rows_d(joint_part_convective, jt%joint, mid, mjd, drvd, &
                                          conv(1:nr))
                        call joint_rows_d(joint_part_time_terms, jt%joint, mid, mjd, drvd, &
                                          tt(1:nr))
                        do r = 1, nr
                            if (pass == 1) then
                                call add_tangents(gq, jt%row0 + r, conv(r) + tt(r), ni, &
                                                  iqi + c0, nj, iqj + c0, keep_i, keep_j)
                            else
                                call add_tangents(gv, jt%row0 + r, conv(r) + tt(r), ni, &
                                                  ivi + c0, nj, ivj + c0, keep_i, keep_j)
                            end if
                        end do
                    end do
                end do
            end associate
        end do
        call frame_curvature_derivatives(self, q, v, gq, gv)
    end procedure curvature_derivatives_into

    !> The node frames' part of curvature_derivatives_into: their blocks of
    !> ∂γ/∂q and ∂γ/∂v added into gq, gv.
    subroutine frame_curvature_derivatives(self, q, v, gq, gv)
        class(mbs_system_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        type(accumulator_t), intent(inout) :: gq, gv
        integer :: k
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                block
                    real(wp) :: bq(node_frame_rows, frame_columns(fr, .true.)), &
                        bv(node_frame_rows, frame_columns(fr, .false.))
                    call frame_curvature_qv(fr, q, v, bq, bv)
                    call add_frame_columns(fr, .true., bq, fr%row0, gq)
                    call add_frame_columns(fr, .false., bv, fr%row0, gv)
                end block
            end associate
        end do
    end subroutine frame_curvature_derivatives
end submodule flexmbs_mbs_system_second_derivatives
