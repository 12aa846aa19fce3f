!> Analytic derivatives of a rigid chain's dynamics (docs/theory.md §2.3):
!> the recursive Newton–Euler algorithm differentiated in forward mode along
!> one coordinate at a time. A direction on joint k moves only k's subtree:
!> the tangents of its frames, motion subspaces and spatial inertias follow
!> the forward pass from k outwards, the tangents of velocities, accelerations
!> and forces the RNEA's forward pass, and the force tangents pass back through
!> k's ancestors. Each direction costs O(n), all of them O(n²), with no
!> allocation (the tangents live in the chain's workspace).
!>   ∂(M w)/∂q = ∂τ/∂q of τ(q, v = 0, v' = w) without gravity,
!>   ∂f/∂q = −∂τ/∂q, ∂f/∂v = −∂τ/∂v of τ(q, v, v' = 0) with gravity.
submodule (flexmbs_mbs_rigid_chain) flexmbs_mbs_rigid_chain_derivatives
    implicit none

contains

    module procedure chain_mass_derivative
        integer :: k, l, n
        self%rates0 = 0.0_wp
        call chain_inverse_dynamics(self, q, self%rates0, w, self%tau0, with_gravity=.false.)
        do k = 1, size(self%bodies)
            n = self%iq(k + 1) - self%iq(k)
            do l = 1, n
                call frame_tangents(self, q, k, l)
                call rnea_tangent(self, self%rates0, w, k, 0, dq(:, self%iq(k) + l))
            end do
        end do
    end procedure chain_mass_derivative

    module procedure chain_force_derivatives
        integer :: k, l, n
        self%rates0 = 0.0_wp
        call chain_inverse_dynamics(self, q, v, self%rates0, self%tau0)
        do k = 1, size(self%bodies)
            n = self%iq(k + 1) - self%iq(k)
            do l = 1, n
                call frame_tangents(self, q, k, l)
                call rnea_tangent(self, v, self%rates0, k, 0, fq(:, self%iq(k) + l))
            end do
            call mark_subtree(self, k)
            do l = self%iv(k) + 1, self%iv(k + 1)
                call rnea_tangent(self, v, self%rates0, k, l, fv(:, l))
            end do
        end do
        fq = -fq
        fv = -fv
    end procedure chain_force_derivatives

    !> moved(i): body i lies in the subtree of body k (bodies before k do not).
    pure subroutine mark_subtree(self, k)
        class(rigid_chain_t), intent(inout) :: self
        integer, intent(in) :: k
        integer :: i
        self%moved = .false.
        self%moved(k) = .true.
        do i = k + 1, size(self%bodies)
            self%moved(i) = self%moved(self%bodies(i)%parent)
        end do
    end subroutine mark_subtree

    !> Tangents of the frames (tan_o, tan_r), motion subspaces (tan_s) and
    !> spatial inertias (tan_inert) of k's subtree along k's local
    !> coordinate l, from the frames of the last RNEA pass at q.
    pure subroutine frame_tangents(self, q, k, l)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        integer, intent(in) :: k, l
        real(wp) :: rj(3, 3), drj(3, 3), drl(3, 3), u(3), du(3), c(3), dc(3), x(3, 3), &
            cx(3, 3), dcx(3, 3), e(4)
        integer :: i, p, jq, jv, m
        call mark_subtree(self, k)
        ! k's parent stays put
        p = self%bodies(k)%parent
        self%tan_o(:, p) = 0.0_wp
        self%tan_r(:, :, p) = 0.0_wp
        do i = k, size(self%bodies)
            if (.not. self%moved(i)) cycle
            associate (b => self%bodies(i), o => self%o(:, i), r => self%r(:, :, i), &
                       dob => self%tan_o(:, i), dr => self%tan_r(:, :, i))
                p = b%parent
                jq = self%iq(i) + 1
                jv = self%iv(i) + 1
                rj = matmul(self%r(:, :, p), b%joint_rotation)
                drj = matmul(self%tan_r(:, :, p), b%joint_rotation)
                u = matmul(rj, b%axis)
                du = matmul(drj, b%axis)
                dob = self%tan_o(:, p) + matmul(self%tan_r(:, :, p), b%joint_position)
                ! the joint's own rotation moves only along its own coordinate
                drl = 0.0_wp
                select case (b%joint)
                case (chain_joint_revolute)
                    if (i == k) drl = matmul(skew(b%axis), self%rloc(:, :, i))
                    dr = matmul(drj, self%rloc(:, :, i)) + matmul(rj, drl)
                    self%tan_s(1:3, jv) = du
                    self%tan_s(4:6, jv) = cross(dob, u) + cross(o, du)
                case (chain_joint_prismatic)
                    dob = dob + du * q(jq)
                    if (i == k) dob = dob + u
                    dr = drj
                    self%tan_s(1:3, jv) = 0.0_wp
                    self%tan_s(4:6, jv) = du
                case default
                    if (i == k) then
                        e = 0.0_wp
                        e(l) = 1.0_wp
                        drl = rotation_matrix_tangent(q(jq:jq + 3), e)
                    end if
                    dr = matmul(drj, self%rloc(:, :, i)) + matmul(rj, drl)
                    do m = 0, 2
                        self%tan_s(1:3, jv + m) = dr(:, m + 1)
                        self%tan_s(4:6, jv + m) = cross(dob, r(:, m + 1)) + cross(o, dr(:, m + 1))
                    end do
                end select
                ! I = [R J Rᵀ + m [c]×[c]×ᵀ, m [c]×; m [c]×ᵀ, m 1], c = o + R s
                c = o + matmul(r, b%centre)
                dc = dob + matmul(dr, b%centre)
                cx = skew(c)
                dcx = skew(dc)
                x = matmul(dr, matmul(b%inertia, transpose(r))) &
                    + b%mass * matmul(dcx, transpose(cx))
                self%tan_inert(1:3, 1:3, i) = x + transpose(x)
                self%tan_inert(1:3, 4:6, i) = b%mass * dcx
                self%tan_inert(4:6, 1:3, i) = b%mass * transpose(dcx)
                self%tan_inert(4:6, 4:6, i) = 0.0_wp
            end associate
        end do
    end subroutine frame_tangents

    !> Column dtau = ∂τ/∂(direction) of the RNEA at (q, qd, qdd) of the last
    !> pass: along k's coordinate (rate = 0, frame_tangents done) or along
    !> rate index `rate` of body k (moved flags set by mark_subtree).
    pure subroutine rnea_tangent(self, qd, qdd, k, rate, dtau)
        class(rigid_chain_t), intent(inout) :: self
        real(wp), intent(in) :: qd(:), qdd(:)
        integer, intent(in) :: k, rate
        real(wp), intent(out) :: dtau(:)
        real(wp) :: sv(6), sa(6), dsv(6), dsa(6), iv(6), div(6)
        logical :: position
        integer :: i, p, c
        position = rate == 0
        p = self%bodies(k)%parent
        self%tan_vel(:, p) = 0.0_wp
        self%tan_acc(:, p) = 0.0_wp
        do i = k, size(self%bodies)
            if (.not. self%moved(i)) cycle
            p = self%bodies(i)%parent
            sv = 0.0_wp
            sa = 0.0_wp
            dsv = 0.0_wp
            dsa = 0.0_wp
            do c = self%iv(i) + 1, self%iv(i + 1)
                sv = sv + self%s(:, c) * qd(c)
                sa = sa + self%s(:, c) * qdd(c)
                if (position) then
                    dsv = dsv + self%tan_s(:, c) * qd(c)
                    dsa = dsa + self%tan_s(:, c) * qdd(c)
                end if
            end do
            if (.not. position .and. i == k) dsv = self%s(:, rate)
            associate (vel => self%vel(:, i), dvel => self%tan_vel(:, i), &
                       dacc => self%tan_acc(:, i), inert => self%inert(:, :, i))
                dvel = self%tan_vel(:, p) + dsv
                dacc = self%tan_acc(:, p) + dsa + cross_motion(dvel, sv) + cross_motion(vel, dsv)
                iv = matmul(inert, vel)
                div = matmul(inert, dvel)
                self%tan_frc(:, i) = matmul(inert, dacc) + cross_force(dvel, iv)
                if (position) then
                    div = div + matmul(self%tan_inert(:, :, i), vel)
                    self%tan_frc(:, i) = self%tan_frc(:, i) &
                        + matmul(self%tan_inert(:, :, i), self%acc(:, i))
                end if
                self%tan_frc(:, i) = self%tan_frc(:, i) + cross_force(vel, div)
            end associate
        end do
        ! backward: the subtree's force tangents gather in k, and k's
        ! ancestors carry that sum (their other children do not move)
        dtau = 0.0_wp
        do i = size(self%bodies), k, -1
            if (.not. self%moved(i)) cycle
            do c = self%iv(i) + 1, self%iv(i + 1)
                dtau(c) = dot_product(self%s(:, c), self%tan_frc(:, i))
                if (position) dtau(c) = dtau(c) + dot_product(self%tan_s(:, c), self%frc(:, i))
            end do
            p = self%bodies(i)%parent
            if (i /= k) self%tan_frc(:, p) = self%tan_frc(:, p) + self%tan_frc(:, i)
        end do
        p = self%bodies(k)%parent
        do while (p > 0)
            do c = self%iv(p) + 1, self%iv(p + 1)
                dtau(c) = dot_product(self%s(:, c), self%tan_frc(:, k))
            end do
            p = self%bodies(p)%parent
        end do
    end subroutine rnea_tangent

    ! (in the submodule: gfortran drops private procedures of a module that
    ! only its submodule calls after inlining them)
    module procedure cross_motion
        w(1:3) = cross(v(1:3), u(1:3))
        w(4:6) = cross(v(1:3), u(4:6)) + cross(v(4:6), u(1:3))
    end procedure cross_motion

    module procedure cross_force
        w(1:3) = cross(v(1:3), f(1:3)) + cross(v(4:6), f(4:6))
        w(4:6) = cross(v(1:3), f(4:6))
    end procedure cross_force

    !> dR(p)[dp] of the quadratic rotation_matrix(p) (any p, unit or not).
    pure function rotation_matrix_tangent(p, dp) result(a)
        real(wp), intent(in) :: p(4), dp(4)
        real(wp) :: a(3, 3)
        real(wp) :: d
        integer :: i, j
        d = 2.0_wp * (p(1) * dp(1) - dot_product(p(2:4), dp(2:4)))
        do j = 1, 3
            do i = 1, 3
                a(i, j) = 2.0_wp * (dp(i + 1) * p(j + 1) + p(i + 1) * dp(j + 1))
            end do
            a(j, j) = a(j, j) + d
        end do
        a = a + 2.0_wp * (dp(1) * skew(p(2:4)) + p(1) * skew(dp(2:4)))
    end function rotation_matrix_tangent
end submodule flexmbs_mbs_rigid_chain_derivatives
