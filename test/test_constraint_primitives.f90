!> Constraint primitives between rigid-body markers: AD (the same formulas on dual
!> numbers) against the hand-coded velocity-space Jacobian C = c_q T, the
!> position-space c_q, c_t, (C v)_q T v and 2 C_t v + c_tt, on random rigid-rigid,
!> rigid-ground and ground-rigid configurations; closed-form values of the drivers.
module test_constraint_primitives
    use flexmbs_core_kinds, only: wp
    use flexmbs_mbs_dual, only: dual_t, dual_variable, operator(+), operator(-), &
        operator(*), sin, cos, assignment(=)
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_rate_matrix, quat_from_axis_angle
    use flexmbs_mbs_rotation_dual, only: rotation_matrix_d => rotation_matrix
    use flexmbs_mbs_primitive_kinds, only: primitive_dot1, primitive_dot2, &
        primitive_spherical, primitive_distance, primitive_angle_driver, &
        primitive_translation_driver, primitive_name
    use flexmbs_mbs_constraint_primitives, only: marker_state_t, rigid_marker_state, &
        ground_marker_state, rigid_marker_jacobian, rigid_marker_jacobian_q, &
        primitive_value, joint_value, joint_jacobian, joint_rows
    use flexmbs_mbs_constraint_primitives_dual, only: marker_state_d => marker_state_t, &
        rigid_marker_state_d => rigid_marker_state, &
        ground_marker_state_d => ground_marker_state, &
        rigid_marker_jacobian_d => rigid_marker_jacobian, &
        joint_value_d => joint_value, joint_jacobian_d => joint_jacobian, &
        joint_rows_d => joint_rows
    use flexmbs_mbs_joint, only: joint_t, new_joint, new_primitive_joint, joint_name, &
        joint_spherical, joint_revolute, joint_cylindrical, joint_prismatic, &
        joint_universal, joint_fixed, joint_primitive, joint_part_time_derivative, &
        joint_part_convective, joint_part_time_terms
    use flexmbs_core_status, only: status_t
    use mbs_random, only: random_state_t, uniform, random_vector, random_quaternion
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_constraint_primitives

    !> The issue's bound: AD against hand-coded, relative to the largest entry (floor 1).
    real(wp), parameter :: tol_ad = 1.0e-12_wp
    integer, parameter :: ntrials = 40
    integer, parameter :: nkinds = 6
    integer, parameter :: kinds(nkinds) = [primitive_dot1, primitive_dot2, &
        primitive_spherical, primitive_distance, primitive_angle_driver, &
        primitive_translation_driver]
    integer, parameter :: njoints = 6
    integer, parameter :: joints(njoints) = [joint_spherical, joint_revolute, &
        joint_cylindrical, joint_prismatic, joint_universal, joint_fixed]
    ! Marker pairings: both on bodies, j on the ground, i on the ground.
    integer, parameter :: rigid_rigid = 1, rigid_ground = 2, ground_rigid = 3

    !> One end of a primitive: a marker on a rigid body, or a ground marker (nv = 0).
    type :: end_t
        logical :: ground = .false.
        real(wp) :: r(3), p(4), rd(3), wb(3), sb(3), ub(3, 3)
    end type end_t

    !> Worst relative AD-vs-hand differences of one primitive.
    type :: errors_t
        real(wp) :: c_v = 0, c_q = 0, ct = 0, conv = 0, time_terms = 0
    end type errors_t

contains

    function collect_constraint_primitives() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('ad_vs_hand_rigid_rigid', test_rigid_rigid), &
                 new_test('ad_vs_hand_rigid_ground', test_rigid_ground), &
                 new_test('ad_vs_hand_ground_rigid', test_ground_rigid), &
                 new_test('driver_closed_form', test_driver_closed_form), &
                 new_test('joints_vanish_when_assembled', test_joints_assembled)]
    end function collect_constraint_primitives

    ! ---------------------------------------------------------------- helpers

    function random_end(rng, ground) result(e)
        type(random_state_t), intent(inout) :: rng
        logical, intent(in) :: ground
        type(end_t) :: e
        e%ground = ground
        e%r = random_vector(rng, 3, -1.0_wp, 1.0_wp)
        e%p = random_quaternion(rng)
        e%rd = random_vector(rng, 3, -1.0_wp, 1.0_wp)
        e%wb = random_vector(rng, 3, -2.0_wp, 2.0_wp)
        e%sb = random_vector(rng, 3, -0.5_wp, 0.5_wp)
        e%ub = rotation_matrix(random_quaternion(rng))
    end function random_end

    integer function nv_of(e)
        type(end_t), intent(in) :: e
        nv_of = merge(0, 6, e%ground)
    end function nv_of

    !> The prescribed function s(t) = 1.2 + 0.3 sin(1.7 t) + 0.1 t^2 and its first two
    !> derivatives, as functions of a (dual) time.
    function driver_d(t) result(drv)
        type(dual_t), intent(in) :: t
        type(dual_t) :: drv(3)
        drv(1) = 1.2_wp + 0.3_wp * sin(1.7_wp * t) + 0.1_wp * t * t
        drv(2) = (0.3_wp * 1.7_wp) * cos(1.7_wp * t) + 0.2_wp * t
        drv(3) = (-0.3_wp * 1.7_wp**2) * sin(1.7_wp * t) + 0.2_wp
    end function driver_d

    !> Real marker state and velocity/position-space Jacobians of one end.
    subroutine hand_end(e, m, jx, ja, jxq, jaq)
        type(end_t), intent(in) :: e
        type(marker_state_t), intent(out) :: m
        real(wp), intent(out) :: jx(:, :), ja(:, :, :), jxq(:, :), jaq(:, :, :)
        if (e%ground) then
            ! A ground marker sits where the body frame would be.
            call ground_marker_state(e%r + matmul(rotation_matrix(e%p), e%sb), &
                                     matmul(rotation_matrix(e%p), e%ub), m)
        else
            call rigid_marker_state(e%r, e%p, e%rd, e%wb, e%sb, e%ub, m)
            call rigid_marker_jacobian(e%p, e%sb, e%ub, jx, ja)
            call rigid_marker_jacobian_q(e%p, e%sb, e%ub, jxq, jaq)
        end if
    end subroutine hand_end

    !> Dual marker state of one end with q seeded: r along tangents dr(:, 1:nd),
    !> p along dp(:, 1:nd), into directions first..first+nd-1.
    subroutine dual_end(e, first, dr, dp, m, p)
        type(end_t), intent(in) :: e
        integer, intent(in) :: first
        real(wp), intent(in) :: dr(:, :), dp(:, :)
        type(marker_state_d), intent(out) :: m
        type(dual_t), intent(out) :: p(4)
        type(dual_t) :: r(3), rd(3), wb(3), sb(3), ub(3, 3), x(3), a(3, 3)
        integer :: k, nd
        nd = size(dr, 2)
        r = e%r
        p = e%p
        do k = 1, nd
            r%der(first + k - 1) = dr(:, k)
            p%der(first + k - 1) = dp(:, k)
        end do
        rd = e%rd
        wb = e%wb
        sb = e%sb
        ub = e%ub
        if (e%ground) then
            x = e%r + matmul(rotation_matrix(e%p), e%sb)
            a = matmul(rotation_matrix(e%p), e%ub)
            call ground_marker_state_d(x, a, m)
        else
            call rigid_marker_state_d(r, p, rd, wb, sb, ub, m)
        end if
    end subroutine dual_end

    !> max |ad - hand| / max(1, max |hand|).
    pure real(wp) function rel_err(ad, hand)
        real(wp), intent(in) :: ad(:), hand(:)
        rel_err = 0.0_wp
        if (size(hand) == 0) return
        rel_err = maxval(abs(ad - hand)) / max(1.0_wp, maxval(abs(hand)))
    end function rel_err

    pure function identity(n) result(e)
        integer, intent(in) :: n
        real(wp) :: e(n, n)
        integer :: i
        e = 0.0_wp
        do i = 1, n
            e(i, i) = 1.0_wp
        end do
    end function identity

    !> One random configuration of a joint (joint_primitive: of the primitive `kind`
    !> on random axes): AD against hand-coded.
    subroutine compare_once(rng, jkind, kind, pairing, err)
        type(random_state_t), intent(inout) :: rng
        integer, intent(in) :: jkind, kind, pairing
        type(errors_t), intent(inout) :: err
        type(end_t) :: ei, ej
        type(marker_state_t) :: mi, mj
        type(marker_state_d) :: mid, mjd
        real(wp) :: jxi(3, 6), jai(3, 6, 3), jxj(3, 6), jaj(3, 6, 3)
        real(wp) :: jxqi(3, 7), jaqi(3, 7, 3), jxqj(3, 7), jaqj(3, 7, 3)
        real(wp) :: t0, drv(3), ti(4, 3), tj(4, 3), zero3(3, 3), zero34(3, 4)
        real(wp), allocatable :: ci(:, :), cj(:, :), ciq(:, :), cjq(:, :), ct(:), gam(:), tt(:)
        type(dual_t) :: t, drvd(3), pid(4), pjd(4), jxid(3, 6), jaid(3, 6, 3), &
            jxjd(3, 6), jajd(3, 6, 3), cv
        type(dual_t), allocatable :: cd(:), cid(:, :), cjd(:, :), ctd(:)
        type(joint_t) :: joint
        type(status_t) :: status
        integer :: nr, ni, nj, ki, kj, k, r
        ei = random_end(rng, pairing == ground_rigid)
        ej = random_end(rng, pairing == rigid_ground)
        ni = nv_of(ei)
        nj = nv_of(ej)
        ki = 1 + int(uniform(rng, 0.0_wp, 3.0_wp))
        kj = 1 + int(uniform(rng, 0.0_wp, 3.0_wp))
        if (jkind == joint_primitive) then
            call new_primitive_joint(joint, kind, ki, kj, status)
        else
            call new_joint(joint, jkind, status)
        end if
        nr = joint%nrows
        t0 = uniform(rng, -1.0_wp, 1.0_wp)
        allocate (ci(nr, ni), cj(nr, nj), ciq(nr, ni + ni / 6), cjq(nr, nj + nj / 6), &
                  ct(nr), gam(nr), tt(nr), cd(nr), cid(nr, ni), cjd(nr, nj), ctd(nr))
        drvd = driver_d(dual_variable(t0, 1))
        drv = drvd%val

        ! Hand-coded, real.
        call hand_end(ei, mi, jxi, jai, jxqi, jaqi)
        call hand_end(ej, mj, jxj, jaj, jxqj, jaqj)
        call joint_jacobian(joint, mi, jxi(:, 1:ni), jai(:, 1:ni, :), mj, &
                            jxj(:, 1:nj), jaj(:, 1:nj, :), drv, ci, cj)
        call joint_jacobian(joint, mi, jxqi(:, 1:size(ciq, 2)), &
                            jaqi(:, 1:size(ciq, 2), :), mj, jxqj(:, 1:size(cjq, 2)), &
                            jaqj(:, 1:size(cjq, 2), :), drv, ciq, cjq)
        call joint_rows(joint_part_time_derivative, joint, mi, mj, drv, ct)
        call joint_rows(joint_part_convective, joint, mi, mj, drv, gam)
        call joint_rows(joint_part_time_terms, joint, mi, mj, drv, tt)

        ti = quat_rate_matrix(ei%p)
        tj = quat_rate_matrix(ej%p)
        zero3 = 0.0_wp
        zero34 = 0.0_wp

        ! Pass 1: velocity directions T e_k of body i (1..6), of body j (7..12), time (13).
        call dual_end(ei, 1, reshape([identity(3), zero3], [3, 6]), &
                      reshape([zero34, ti], [4, 6]), mid, pid)
        call dual_end(ej, 7, reshape([identity(3), zero3], [3, 6]), &
                      reshape([zero34, tj], [4, 6]), mjd, pjd)
        t = dual_variable(t0, 13)
        drvd = driver_d(t)
        call joint_value_d(joint, mid, mjd, drvd, cd)
        do r = 1, nr
            err%c_v = max(err%c_v, rel_err(cd(r)%der(1:ni), ci(r, :)), &
                          rel_err(cd(r)%der(7:6 + nj), cj(r, :)))
        end do
        err%ct = max(err%ct, rel_err([(cd(r)%der(13), r = 1, nr)], ct))

        ! Pass 2: position directions e_k of q_i (1..7) and q_j (8..14).
        call dual_end(ei, 1, reshape([identity(3), zero34], [3, 7]), &
                      reshape([zero3(1:1, :), zero3, identity(4)], [4, 7]), mid, pid)
        call dual_end(ej, 8, reshape([identity(3), zero34], [3, 7]), &
                      reshape([zero3(1:1, :), zero3, identity(4)], [4, 7]), mjd, pjd)
        drvd = drv
        call joint_value_d(joint, mid, mjd, drvd, cd)
        do r = 1, nr
            err%c_q = max(err%c_q, rel_err(cd(r)%der(1:size(ciq, 2)), ciq(r, :)), &
                          rel_err(cd(r)%der(8:7 + size(cjq, 2)), cjq(r, :)))
        end do

        ! Pass 3: direction 1 = q_dot = T v (both bodies), direction 2 = time. AD of the
        ! hand-coded C v gives (C v)_q T v and C_t v; AD of the hand-coded c_t gives c_tt.
        call dual_end(ei, 1, reshape(ei%rd, [3, 1]), reshape(matmul(ti, ei%wb), [4, 1]), &
                      mid, pid)
        call dual_end(ej, 1, reshape(ej%rd, [3, 1]), reshape(matmul(tj, ej%wb), [4, 1]), &
                      mjd, pjd)
        t = dual_variable(t0, 2)
        drvd = driver_d(t)
        if (.not. ei%ground) call rigid_marker_jacobian_d(pid, dual_body_offset(ei), &
                                                          dual_axes(ei), jxid, jaid)
        if (.not. ej%ground) call rigid_marker_jacobian_d(pjd, dual_body_offset(ej), &
                                                          dual_axes(ej), jxjd, jajd)
        call joint_jacobian_d(joint, mid, jxid(:, 1:ni), jaid(:, 1:ni, :), mjd, &
                              jxjd(:, 1:nj), jajd(:, 1:nj, :), drvd, cid, cjd)
        call joint_rows_d(joint_part_time_derivative, joint, mid, mjd, drvd, ctd)
        do r = 1, nr
            cv = 0.0_wp
            do k = 1, ni
                cv = cv + cid(r, k) * velocity(ei, k)
            end do
            do k = 1, nj
                cv = cv + cjd(r, k) * velocity(ej, k)
            end do
            err%conv = max(err%conv, rel_err([cv%der(1)], [gam(r)]))
            err%time_terms = max(err%time_terms, &
                                 rel_err([2.0_wp * cv%der(2) + ctd(r)%der(2)], [tt(r)]))
        end do
    end subroutine compare_once

    function dual_body_offset(e) result(s)
        type(end_t), intent(in) :: e
        type(dual_t) :: s(3)
        s = e%sb
    end function dual_body_offset

    function dual_axes(e) result(u)
        type(end_t), intent(in) :: e
        type(dual_t) :: u(3, 3)
        u = e%ub
    end function dual_axes

    !> Component k of v = (r_dot, w_b).
    real(wp) function velocity(e, k)
        type(end_t), intent(in) :: e
        integer, intent(in) :: k
        if (k <= 3) then
            velocity = e%rd(k)
        else
            velocity = e%wb(k - 3)
        end if
    end function velocity

    subroutine run_pairing(error, pairing, label)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: pairing
        character(len=*), intent(in) :: label
        type(random_state_t) :: rng
        integer :: n
        do n = 1, nkinds
            call run_case(error, rng, joint_primitive, kinds(n), pairing, &
                          label // ' ' // primitive_name(kinds(n)))
        end do
        do n = 1, njoints
            call run_case(error, rng, joints(n), 0, pairing, &
                          label // ' ' // joint_name(joints(n)) // ' joint')
        end do
    end subroutine run_pairing

    !> ntrials random configurations of one joint or primitive; FLEXMBS_TEST_VERBOSE
    !> set prints the worst errors (C, c_q, c_t, (C v)_q T v, 2 C_t v + c_tt).
    subroutine run_case(error, rng, jkind, kind, pairing, label)
        type(error_t), allocatable, intent(inout) :: error
        type(random_state_t), intent(inout) :: rng
        integer, intent(in) :: jkind, kind, pairing
        character(len=*), intent(in) :: label
        type(errors_t) :: err
        integer :: trial, st
        character(len=16) :: verbose
        call get_environment_variable('FLEXMBS_TEST_VERBOSE', verbose, status=st)
        do trial = 1, ntrials
            call compare_once(rng, jkind, kind, pairing, err)
        end do
        if (st == 0) write (*, '(a40,5es10.2)') label, err%c_v, err%c_q, err%ct, err%conv, &
            err%time_terms
        call check_close(error, err%c_v, 0.0_wp, tol_ad, label // ': C = c_q T, AD vs hand')
        call check_close(error, err%c_q, 0.0_wp, tol_ad, label // ': c_q, AD vs hand')
        call check_close(error, err%ct, 0.0_wp, tol_ad, label // ': c_t, AD vs hand')
        call check_close(error, err%conv, 0.0_wp, tol_ad, label // &
                         ': (C v)_q T v, AD vs hand')
        call check_close(error, err%time_terms, 0.0_wp, tol_ad, label // &
                         ': 2 C_t v + c_tt, AD vs hand')
    end subroutine run_case

    ! ------------------------------------------------------------------ tests

    subroutine test_rigid_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        call run_pairing(error, rigid_rigid, 'rigid-rigid')
    end subroutine test_rigid_rigid

    subroutine test_rigid_ground(error)
        type(error_t), allocatable, intent(out) :: error
        call run_pairing(error, rigid_ground, 'rigid-ground')
    end subroutine test_rigid_ground

    subroutine test_ground_rigid(error)
        type(error_t), allocatable, intent(out) :: error
        call run_pairing(error, ground_rigid, 'ground-rigid')
    end subroutine test_ground_rigid

    !> A body turned by theta about z of a ground frame, shifted by h along z:
    !> the angle driver gives sin(theta - s), the translation driver h - s, the
    !> distance driver h^2 + |xy|^2 - s^2.
    subroutine test_driver_closed_form(error)
        type(error_t), allocatable, intent(out) :: error
        type(marker_state_t) :: mg, mb
        real(wp) :: theta, h, s, drv(3), c(1), ez(3), eye(3, 3), zero(3)
        theta = 0.83_wp
        h = 0.4_wp
        s = 0.5_wp
        drv = [s, 0.0_wp, 0.0_wp]
        ez = [0.0_wp, 0.0_wp, 1.0_wp]
        eye = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
                       1.0_wp], [3, 3])
        zero = 0.0_wp
        call ground_marker_state(zero, eye, mg)
        call rigid_marker_state(h * ez, quat_from_axis_angle(ez, theta), zero, zero, &
                                zero, eye, mb)
        call primitive_value(primitive_angle_driver, 1, 1, mg, mb, drv, c)
        call check_close(error, c(1), sin(theta - s), 1.0e-15_wp, 'angle driver')
        call primitive_value(primitive_translation_driver, 3, 1, mg, mb, drv, c)
        call check_close(error, c(1), h - s, 1.0e-15_wp, 'translation driver')
        call primitive_value(primitive_distance, 1, 1, mg, mb, drv, c)
        call check_close(error, c(1), h**2 - s**2, 1.0e-15_wp, 'distance')
        call primitive_value(primitive_dot1, 3, 3, mg, mb, drv, c)
        call check_close(error, c(1), 1.0_wp, 1.0e-15_wp, 'dot-1 of parallel z axes')
    end subroutine test_driver_closed_form

    !> Each joint's rows vanish on a configuration it allows (marker i random; marker j
    !> moved by the joint's own freedoms) and not on a violating one.
    subroutine test_joints_assembled(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(marker_state_t) :: mi, mj
        type(joint_t) :: joint
        type(status_t) :: status
        real(wp) :: ai(3, 3), aj(3, 3), xi(3), xj(3), drv(3), c(6), spin(3, 3), ex(3), ez(3)
        integer :: n
        ex = [1.0_wp, 0.0_wp, 0.0_wp]
        ez = [0.0_wp, 0.0_wp, 1.0_wp]
        drv = 0.0_wp
        do n = 1, njoints
            ai = rotation_matrix(random_quaternion(rng))
            xi = random_vector(rng, 3, -1.0_wp, 1.0_wp)
            spin = rotation_matrix(quat_from_axis_angle(ez, 0.7_wp))
            xj = xi
            aj = ai
            select case (joints(n))
            case (joint_spherical)
                aj = rotation_matrix(random_quaternion(rng))
            case (joint_revolute)
                aj = matmul(ai, spin)
            case (joint_cylindrical)
                xj = xi + 0.3_wp * ai(:, 3)
                aj = matmul(ai, spin)
            case (joint_prismatic)
                xj = xi + 0.3_wp * ai(:, 3)
            case (joint_universal)
                aj = matmul(ai, matmul(rotation_matrix(quat_from_axis_angle(ex, &
                            2.0_wp * atan(1.0_wp))), spin))
            end select
            call new_joint(joint, joints(n), status)
            call ground_marker_state(xi, ai, mi)
            call ground_marker_state(xj, aj, mj)
            call joint_value(joint, mi, mj, drv, c(1:joint%nrows))
            call check_close(error, maxval(abs(c(1:joint%nrows))), 0.0_wp, 1.0e-15_wp, &
                             joint_name(joints(n)) // ' joint: rows on an allowed motion')
            ! Moving j off along x_i violates every joint but the cylindrical and
            ! prismatic in a direction they forbid as well.
            call ground_marker_state(xj + 0.1_wp * ai(:, 1), aj, mj)
            call joint_value(joint, mi, mj, drv, c(1:joint%nrows))
            call check(error, maxval(abs(c(1:joint%nrows))) > 1.0e-3_wp, &
                       joint_name(joints(n)) // ' joint: a forbidden offset is seen')
        end do
        call new_joint(joint, 99, status)
        call check(error, .not. status%ok(), 'unknown joint kind is an error')
    end subroutine test_joints_assembled
end module test_constraint_primitives
