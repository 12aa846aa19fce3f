!> Markers on flexible bodies. FE nodes carry no rotations, so a marker
!> frame is defined from a node set S (weights w_a = 1/|S|):
!>
!>   origin       x_m = x̄ + R d,     x̄ = Σ w_a x_a,  d = P − X̄
!>   orientation  R_m = R U0,        R = the rotation of the best rigid fit
!>                of the set (Kabsch): the polar factor of
!>                A = Σ w_a (x_a − x̄)(X_a − X̄)ᵀ, by SVD A = V Σ Wᵀ,
!>                R = V diag(1, 1, det(V Wᵀ)) Wᵀ
!>
!> with X the reference positions, P the marker's reference origin (default
!> X̄) and U0 its reference axes. Under a rigid motion x = c + Q X the marker
!> moves rigidly (R = Q). The set must not be collinear (a face, an edge
!> pair or a volume; A may have rank 2 for a planar set).
!>
!> Derivatives. With U = RᵀA (symmetric) and a variation δx,
!> δA = Σ w_a δx_a (X_a − X̄)ᵀ (the δx̄ term vanishes: Σ w_a (X_a − X̄) = 0),
!> δR = [δθ]× R, and from skew(RᵀδA) = (W U + U W)/2, W = [w]×:
!>   (tr U I − U) w = axial(RᵀδA − δAᵀR),   δθ = R w (world),
!>   δx_m = Σ w_a δx_a + δθ × (R d).
!> So the Jacobians ∂x_m/∂x and ∂θ/∂x (3 × 3|S|, node by node x y z) are
!> linear maps of the set's nodal displacements; with nodal velocities they
!> give the marker's velocity and angular velocity.
module flexmbs_mbs_flexible_marker
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_text, only: int_text
    use flexmbs_linalg_lapack, only: dgesvd_quiet, dgetrf, dgetrs
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_fe_tensor, only: det3
    implicit none
    private

    real(wp), parameter :: identity3(3, 3) = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
        1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])

    !> A marker on a node set of a flexible body (the module's formulas): the
    !> set, its reference offsets and weight, the marker's offset d and axes U0.
    type, public :: flexible_marker_t
        integer, allocatable :: nodes(:)          !! mesh node numbers of the set
        real(wp), allocatable :: dx_ref(:, :)     !! (3, |S|): X_a − X̄
        real(wp) :: weight = 0.0_wp               !! w_a = 1/|S|
        real(wp) :: offset(3) = 0.0_wp            !! d = P − X̄
        real(wp) :: axes(3, 3) = identity3        !! U0, columns
    contains
        procedure :: pose => marker_pose
        procedure :: jacobian => marker_jacobian
    end type flexible_marker_t

    public :: new_flexible_marker

contains

    !> The marker on node set `nodes` of a mesh with reference positions x_ref
    !> (3, nodes); `origin` (default: the set's centroid) and `axes` (default:
    !> the global axes) in the reference configuration.
    subroutine new_flexible_marker(marker, x_ref, nodes, status, origin, axes)
        type(flexible_marker_t), intent(out) :: marker
        real(wp), intent(in) :: x_ref(:, :)
        integer, intent(in) :: nodes(:)
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: origin(3), axes(3, 3)
        real(wp) :: centre(3), a(3, 3), sv(3), u(3, 3), vt(3, 3), work(64)
        integer :: i, info, stat
        if (size(nodes) < 3 .or. any(nodes < 1 .or. nodes > size(x_ref, 2))) then
            call status%set(status_bad_input, 'flexible marker: needs at least 3 nodes ' // &
                            'within 1..' // int_text(size(x_ref, 2)))
            return
        end if
        marker%nodes = nodes
        marker%weight = 1.0_wp / size(nodes)
        centre = sum(x_ref(:, nodes), dim=2) * marker%weight
        allocate (marker%dx_ref(3, size(nodes)), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'flexible marker offsets', 3 * size(nodes, kind=i8), 8)
            return
        end if
        do i = 1, size(nodes)
            marker%dx_ref(:, i) = x_ref(:, nodes(i)) - centre
        end do
        ! the set must span a plane at least: second singular value of A(X)
        a = matmul(marker%dx_ref, transpose(marker%dx_ref)) * marker%weight
        call dgesvd_quiet('N', 'N', 3, 3, a, 3, sv, u, 3, vt, 3, work, size(work), info)
        if (info /= 0 .or. sv(2) <= 1.0e-12_wp * sv(1)) then
            call status%set(status_bad_input, 'flexible marker: the node set is collinear ' // &
                            '(no orientation can be defined)')
            return
        end if
        if (present(origin)) marker%offset = origin - centre
        if (present(axes)) then
            if (maxval(abs(matmul(transpose(axes), axes) - identity3)) > 1.0e-10_wp) then
                call status%set(status_bad_input, 'flexible marker: axes are not orthonormal')
                return
            end if
            marker%axes = axes
        end if
    end subroutine new_flexible_marker

    !> Centroid x̄, fit rotation R and A of the set at nodal positions x.
    subroutine fit(self, x, centre, r, a, status)
        class(flexible_marker_t), intent(in) :: self
        real(wp), intent(in) :: x(:, :)
        real(wp), intent(out) :: centre(3), r(3, 3), a(3, 3)
        type(status_t), intent(out) :: status
        real(wp) :: work_a(3, 3), sv(3), v(3, 3), wt(3, 3), work(64), d(3, 3), dx(3)
        integer :: i, info, j
        centre = 0.0_wp
        do i = 1, size(self%nodes)
            centre = centre + x(:, self%nodes(i))
        end do
        centre = centre * self%weight
        a = 0.0_wp
        do i = 1, size(self%nodes)
            dx = x(:, self%nodes(i)) - centre
            do j = 1, 3
                a(:, j) = a(:, j) + dx * self%dx_ref(j, i)
            end do
        end do
        a = a * self%weight
        work_a = a
        call dgesvd_quiet('A', 'A', 3, 3, work_a, 3, sv, v, 3, wt, 3, work, size(work), info)
        if (info /= 0) then
            call status%set(status_solver_failure, 'flexible marker: SVD failed')
            return
        end if
        d = identity3
        r = matmul(v, wt)
        d(3, 3) = sign(1.0_wp, det3(r))
        r = matmul(v, matmul(d, wt))
    end subroutine fit

    !> Marker origin and axes (columns) at nodal positions x (3, all nodes).
    subroutine marker_pose(self, x, origin, axes, status)
        class(flexible_marker_t), intent(in) :: self
        real(wp), intent(in) :: x(:, :)
        real(wp), intent(out) :: origin(3), axes(3, 3)
        type(status_t), intent(out) :: status
        real(wp) :: centre(3), r(3, 3), a(3, 3)
        call fit(self, x, centre, r, a, status)
        if (.not. status%ok()) return
        origin = centre + matmul(r, self%offset)
        axes = matmul(r, self%axes)
    end subroutine marker_pose

    !> jx = ∂x_m/∂x and jr = ∂θ/∂x (3, 3|S|), columns node by node (x, y, z)
    !> in the order of the set: ẋ_m = jx ẋ_S, ω = jr ẋ_S.
    subroutine marker_jacobian(self, x, jx, jr, status)
        class(flexible_marker_t), intent(in) :: self
        real(wp), intent(in) :: x(:, :)
        real(wp), intent(out) :: jx(:, :), jr(:, :)
        type(status_t), intent(out) :: status
        real(wp) :: centre(3), r(3, 3), a(3, 3), u(3, 3), k(3, 3), da(3, 3), s(3, 3), &
            w(3, 1), rd(3)
        integer :: i, j, piv(3), info
        call fit(self, x, centre, r, a, status)
        if (.not. status%ok()) return
        u = matmul(transpose(r), a)
        u = 0.5_wp * (u + transpose(u))
        k = (u(1, 1) + u(2, 2) + u(3, 3)) * identity3 - u
        call dgetrf(3, 3, k, 3, piv, info)
        if (info /= 0) then
            call status%set(status_solver_failure, 'flexible marker: the fit rotation is ' // &
                            'not unique (degenerate node set)')
            return
        end if
        rd = matmul(r, self%offset)
        do i = 1, size(self%nodes)
            do j = 1, 3
                ! δA for δx_a = e_j
                da = 0.0_wp
                da(j, :) = self%weight * self%dx_ref(:, i)
                s = matmul(transpose(r), da)
                s = s - transpose(s)
                w(:, 1) = [s(3, 2), s(1, 3), s(2, 1)]
                call dgetrs('N', 3, 1, k, 3, piv, w, 3, info)
                jr(:, 3 * (i - 1) + j) = matmul(r, w(:, 1))
                jx(:, 3 * (i - 1) + j) = cross(jr(:, 3 * (i - 1) + j), rd)
                jx(j, 3 * (i - 1) + j) = jx(j, 3 * (i - 1) + j) + self%weight
            end do
        end do
    end subroutine marker_jacobian
end module flexmbs_mbs_flexible_marker
