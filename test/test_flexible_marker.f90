!> Markers on flexible bodies: rigid motion is followed exactly, the hand
!> Jacobians match central differences of the pose, a rigid velocity field
!> gives the body's angular velocity, and collinear sets are refused.
module test_flexible_marker
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_mbs_rotation, only: cross
    use flexmbs_mbs_flexible_marker, only: flexible_marker_t, new_flexible_marker
    use test_problems, only: fill_random
    use test_fe, only: random_rotation
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_flexible_marker

    character(len=10), parameter :: sets(3) = [character(len=10) :: 'xmax', 'xmax_layer', &
                                               'ymin']

contains

    function collect_flexible_marker() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('rigid_motion_exact', test_rigid), &
                 new_test('jacobian_vs_differences', test_jacobian), &
                 new_test('rigid_velocity_field', test_velocity), &
                 new_test('collinear_set_refused', test_collinear)]
    end function collect_flexible_marker

    subroutine make(kind, setname, mesh, marker, status)
        integer, intent(in) :: kind
        character(len=*), intent(in) :: setname
        type(mesh_t), intent(out) :: mesh
        type(flexible_marker_t), intent(out) :: marker
        type(status_t), intent(out) :: status
        integer, allocatable :: nodes(:)
        real(wp) :: u0(3, 3)
        integer(i8) :: seed
        call box_mesh(mesh, kind, [3, 2, 2], [0.6_wp, 0.2_wp, 0.3_wp], status)
        if (status%ok()) call mesh%node_set(setname, nodes, status)
        if (.not. status%ok()) return
        seed = 5_i8
        call random_rotation(seed, u0)
        call new_flexible_marker(marker, mesh%x, nodes, status, &
                                 origin=[0.65_wp, 0.1_wp, 0.2_wp], axes=u0)
    end subroutine make

    !> x = c + Q X: origin c + Q P, axes Q U0, for face, layer and side sets.
    subroutine test_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(flexible_marker_t) :: marker
        type(status_t) :: status
        real(wp) :: q(3, 3), c(3), origin(3), axes(3, 3)
        real(wp), allocatable :: x(:, :)
        integer(i8) :: seed
        integer :: k, s, i
        seed = 9_i8
        do k = 1, 2
            do s = 1, size(sets)
                call make(merge(hex8, hex27, k == 1), trim(sets(s)), mesh, marker, status)
                call check(error, status%ok(), 'marker: ' // status%text())
                if (allocated(error)) return
                call random_rotation(seed, q)
                call fill_random(c, seed, -1.0_wp, 1.0_wp)
                allocate (x, mold=mesh%x)
                do i = 1, size(x, 2)
                    x(:, i) = c + matmul(q, mesh%x(:, i))
                end do
                call marker%pose(x, origin, axes, status)
                call check(error, status%ok() .and. &
                           norm2(origin - c - matmul(q, [0.65_wp, 0.1_wp, 0.2_wp])) < 1.0e-13_wp &
                           .and. maxval(abs(axes - matmul(q, marker%axes))) < 1.0e-13_wp, &
                           'rigid motion not followed: set ' // trim(sets(s)))
                deallocate (x)
            end do
        end do
    end subroutine test_rigid

    !> On a randomly deformed mesh: jx against central differences of the
    !> origin, jr against axial((R₊ − R₋)/2h Rᵀ), ≤ 1e-7 relative.
    subroutine test_jacobian(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(flexible_marker_t) :: marker
        type(status_t) :: status
        real(wp), allocatable :: x(:, :), xp(:, :), p(:), jx(:, :), jr(:, :)
        real(wp) :: op(3), om(3), ap(3, 3), am(3, 3), a0(3, 3), o0(3), dr(3, 3), &
            fx(3), fr(3), dev
        real(wp), parameter :: h = 1.0e-6_wp
        integer(i8) :: seed
        integer :: k, s, i, j, col
        seed = 21_i8
        dev = 0.0_wp
        do k = 1, 2
            do s = 1, size(sets)
                call make(merge(hex8, hex27, k == 1), trim(sets(s)), mesh, marker, status)
                allocate (p(size(mesh%x)))
                call fill_random(p, seed, -0.02_wp, 0.02_wp)
                x = mesh%x + reshape(p, shape(mesh%x))
                allocate (jx(3, 3 * size(marker%nodes)), jr(3, 3 * size(marker%nodes)))
                call marker%jacobian(x, jx, jr, status)
                call marker%pose(x, o0, a0, status)
                call check(error, status%ok(), 'jacobian: ' // status%text())
                if (allocated(error)) return
                do i = 1, size(marker%nodes)
                    do j = 1, 3
                        col = 3 * (i - 1) + j
                        xp = x
                        xp(j, marker%nodes(i)) = x(j, marker%nodes(i)) + h
                        call marker%pose(xp, op, ap, status)
                        xp(j, marker%nodes(i)) = x(j, marker%nodes(i)) - h
                        call marker%pose(xp, om, am, status)
                        fx = (op - om) / (2 * h)
                        dr = matmul((ap - am) / (2 * h), transpose(a0))
                        fr = 0.5_wp * [dr(3, 2) - dr(2, 3), dr(1, 3) - dr(3, 1), &
                                       dr(2, 1) - dr(1, 2)]
                        dev = max(dev, norm2(fx - jx(:, col)) / maxval(abs(jx)), &
                                  norm2(fr - jr(:, col)) / maxval(abs(jr)))
                    end do
                end do
                deallocate (p, jx, jr)
            end do
        end do
        print '(4x,a,es9.2)', 'flexible marker Jacobians vs differences: ', dev
        call check(error, dev <= 1.0e-7_wp, 'marker Jacobian differs from differences')
    end subroutine test_jacobian

    !> Nodal velocities ω × (x − c) of a deformed, rigidly rotating body
    !> give jr v = ω and jx v = ω × (x_m − c) to round-off.
    subroutine test_velocity(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(flexible_marker_t) :: marker
        type(status_t) :: status
        real(wp), allocatable :: x(:, :), p(:), jx(:, :), jr(:, :), vs(:)
        real(wp) :: w(3), c(3), origin(3), axes(3, 3)
        integer(i8) :: seed
        integer :: i
        seed = 33_i8
        call make(hex27, 'xmax_layer', mesh, marker, status)
        allocate (p(size(mesh%x)), vs(3 * size(marker%nodes)))
        call fill_random(p, seed, -0.02_wp, 0.02_wp)
        x = mesh%x + reshape(p, shape(mesh%x))
        w = [0.3_wp, -1.2_wp, 2.0_wp]
        c = [0.1_wp, 0.2_wp, -0.3_wp]
        do i = 1, size(marker%nodes)
            vs(3 * i - 2:3 * i) = cross(w, x(:, marker%nodes(i)) - c)
        end do
        allocate (jx(3, size(vs)), jr(3, size(vs)))
        call marker%jacobian(x, jx, jr, status)
        call marker%pose(x, origin, axes, status)
        call check(error, norm2(matmul(jr, vs) - w) < 1.0e-12_wp, 'angular velocity')
        call check(error, norm2(matmul(jx, vs) - cross(w, origin - c)) < 1.0e-12_wp, &
                   'origin velocity')
    end subroutine test_velocity

    !> An edge (collinear nodes) defines no orientation: bad input.
    subroutine test_collinear(error)
        type(error_t), allocatable, intent(out) :: error
        type(mesh_t) :: mesh
        type(flexible_marker_t) :: marker
        type(status_t) :: status
        call make(hex8, 'xmin_ymin', mesh, marker, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'collinear') > 0, 'collinear: ' // status%text())
    end subroutine test_collinear
end module test_flexible_marker
