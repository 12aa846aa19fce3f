!> The planar joint (src/mbs/joint_types.f90: z axes parallel, marker j's
!> origin in marker i's xy plane): its hand-coded derivatives against
!> central differences (against AD: mbs_system/ad_vs_analytic), and
!> inputs/planar_slider.nml (a free puck on a tilted plane) against the
!> closed form of its motion with every solver, its named outputs
!> (/joints/slider/angle, displacement) included.
module test_planar_joint
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_rotation, only: rotation_matrix, quat_from_axis_angle, cross
    use flexmbs_mbs_joint, only: joint_planar
    use flexmbs_mbs_system, only: mbs_system_t, new_mbs_system, marker_t, mbs_joint_t
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use test_mbs_system, only: test_body, random_state, rel_err, random_marker, unit
    use test_multibody_scene, only: run_file, read_matrix
    use mbs_random, only: random_state_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_planar_joint

    !> Central differences (step h = 1e-6): truncation h² |c'''| ~ 1e-12,
    !> rounding ε/h ~ 2e-10 for entries of order 1.
    real(wp), parameter :: h_fd = 1.0e-6_wp, tol_fd = 1.0e-8_wp
    character(len=*), parameter :: scene_file = 'inputs/planar_slider.nml'

contains

    !> The suite.
    function collect_planar_joint() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('derivatives_central_differences', test_derivatives), &
                 new_test('tilted_plane_closed_form', test_closed_form), &
                 new_test('named_outputs_closed_form', test_named_outputs)]
    end function collect_planar_joint

    !> Two bodies, each on a planar joint (ground-body 1, body 1-body 2),
    !> markers random.
    function planar_system(rng, derivatives, status) result(sys)
        type(random_state_t), intent(inout) :: rng
        character(len=*), intent(in) :: derivatives
        type(status_t), intent(out) :: status
        type(mbs_system_t) :: sys
        type(marker_t) :: markers(4)
        markers = [random_marker(rng, 0), random_marker(rng, 1), random_marker(rng, 1), &
                   random_marker(rng, 2)]
        sys = new_mbs_system([test_body(1.0_wp, 1.0_wp), test_body(2.0_wp, 0.5_wp)], markers, &
                             [mbs_joint_t(joint_planar, 1, 2), mbs_joint_t(joint_planar, 3, 4)], &
                             gravity=[0.0_wp, 0.0_wp, -9.81_wp], &
                             constraint_derivatives=derivatives, status=status)
    end function planar_system

    !> On random states: the hand-coded G is the central difference of c
    !> along q' = T e_j, and γ = (G v)_q T v (no time terms: c_t = 0) that of
    !> G v along q' = T v. (AD against the hand-coded derivatives, the
    !> planar joint among every kind: mbs_system/ad_vs_analytic; the
    !> formulations' Jacobians with a planar joint against differences:
    !> mbs_system/formulation_jacobians.)
    subroutine test_derivatives(error)
        type(error_t), allocatable, intent(out) :: error
        type(random_state_t) :: rng
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp) :: q(14), v(12), tv(14), cp(6), cm(6), g(6, 12), ct(6), gam(6), gfd(6, 12), &
            gp(6, 12), gm(6, 12)
        real(wp) :: e_g, e_gam, e_t
        integer :: trial, j
        e_g = 0.0_wp
        e_gam = 0.0_wp
        e_t = 0.0_wp
        sys = planar_system(rng, 'analytic', status)
        call check(error, status%ok() .and. sys%nc == 6, 'two planar joints: 6 rows')
        if (allocated(error)) return
        do trial = 1, 10
            call random_state(rng, 2, q, v)
            call sys%constraint_jacobian(0.2_wp, q, g, status)
            call sys%constraint_time_derivative(0.2_wp, q, ct, status)
            call sys%constraint_curvature(0.2_wp, q, v, gam, status)
            do j = 1, 12
                call sys%kinematics(0.2_wp, q, unit(12, j), tv, status)
                call sys%constraint(0.2_wp, q + h_fd * tv, cp, status)
                call sys%constraint(0.2_wp, q - h_fd * tv, cm, status)
                gfd(:, j) = (cp - cm) / (2.0_wp * h_fd)
            end do
            call sys%kinematics(0.2_wp, q, v, tv, status)
            call sys%constraint_jacobian(0.2_wp, q + h_fd * tv, gp, status)
            call sys%constraint_jacobian(0.2_wp, q - h_fd * tv, gm, status)
            e_g = max(e_g, rel_err(gfd, g))
            e_gam = max(e_gam, maxval(abs(matmul(gp - gm, v) / (2.0_wp * h_fd) - gam)) / &
                        max(1.0_wp, maxval(abs(gam))))
            e_t = max(e_t, maxval(abs(ct)))
        end do
        print '(4x,a,3es9.2)', 'planar: G, gamma off central differences; |c_t| ', e_g, &
            e_gam, e_t
        call check(error, status%ok(), status%text())
        call check(error, max(e_g, e_gam) <= tol_fd .and. e_t == 0.0_wp, &
                   'hand-coded derivatives off central differences')
    end subroutine test_derivatives

    !> The puck's closed form from its scene: n the plane marker's z, P = I - n nᵀ;
    !> r(t) = r0 + v0 t + ½ P g t², ω = ω0, R(t) = rot(n, |ω0| t) R0 (spin
    !> about n). The scene must start the puck in the plane, moving in it
    !> and spinning about n, with marker j at its centre of mass.
    subroutine closed_form(error, scene, t, r, v, omega, rot)
        type(error_t), allocatable, intent(inout) :: error
        type(scene_input_t), intent(in) :: scene
        real(wp), intent(in) :: t
        real(wp), intent(out) :: r(3), v(3), omega(3), rot(3, 3)
        real(wp) :: n(3), pg(3), spin
        associate (b => scene%rigid_bodies(1), plane => scene%markers(1))
            n = plane%z_axis / norm2(plane%z_axis)
            pg = scene%multibody%gravity - dot_product(scene%multibody%gravity, n) * n
            call check(error, abs(dot_product(b%position - plane%position, n)) <= 1e-15_wp &
                .and. abs(dot_product(b%velocity, n)) <= 1e-15_wp .and. &
                norm2(cross(b%angular_velocity, n)) <= 1e-15_wp .and. &
                all(scene%markers(2)%position == 0.0_wp), scene_file // ': the puck does &
                &not start in the plane, moving in it, spinning about n at its centre')
            spin = dot_product(b%angular_velocity, n)
            r = b%position + b%velocity * t + 0.5_wp * pg * t**2
            v = b%velocity + pg * t
            omega = b%angular_velocity
            rot = matmul(rotation_matrix(quat_from_axis_angle(n, spin * t)), &
                         rotation_matrix(quat_from_axis_angle(b%rotation_axis, b%rotation_angle)))
        end associate
    end subroutine closed_form

    !> inputs/planar_slider.nml with each solver at rtol = atol = tol, tol
    !> 1e-6 and 1e-9, against the closed form at t = 1 s: centre, velocity,
    !> world angular velocity, attitude, and the distance from the plane.
    !> Bound: 100 tol. The motion neither contracts nor grows errors faster
    !> than linearly (free flight in the plane, a constant spin), so the
    !> global error is the sum of the local errors the controllers keep
    !> near tol per unit step, times the 1 s flight: a small multiple of
    !> tol, the factor covering the BDF solvers' lower-order start.
    subroutine test_closed_form(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=8), parameter :: solvers(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        real(wp), parameter :: tols(2) = [1.0e-6_wp, 1.0e-9_wp], bound = 100.0_wp
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        real(wp) :: r(3), v(3), omega(3), rot(3, 3), rq(3, 3), n(3), dev(5)
        integer :: k, i
        do i = 1, size(tols)
            do k = 1, size(solvers)
                call run_file(error, scene_file, solvers(k), scene, result, tol=tols(i))
                if (allocated(error)) return
                call closed_form(error, scene, scene%t_end, r, v, omega, rot)
                if (allocated(error)) return
                n = scene%markers(1)%z_axis / norm2(scene%markers(1)%z_axis)
                ! y = (r, p, ṙ, ω′, ...): ω′ in the body frame
                rq = rotation_matrix(result%y(4:7))
                dev = [norm2(result%y(1:3) - r), norm2(result%y(8:10) - v), &
                       norm2(matmul(rq, result%y(11:13)) - omega), maxval(abs(rq - rot)), &
                       abs(dot_product(result%y(1:3) - scene%markers(1)%position, n))]
                print '(4x,a,a,es8.1,a,5es9.2)', solvers(k), ' tol ', tols(i), &
                    ': r, v, omega, R, out of plane off by', dev
                call check(error, abs(scene%t_end - 1.0_wp) < 1e-12_wp .and. &
                           maxval(dev) <= bound * tols(i), trim(solvers(k)) // &
                           ': puck off the closed form')
            end do
        end do
    end subroutine test_closed_form

    !> The scene's HDF5 file (RADAU5, tol 1e-9): /joints/slider/angle is the
    !> spin times t, /joints/slider/displacement the centre's coordinates
    !> along the plane marker's x and y, at every record (t = (k - 1)/100).
    subroutine test_named_outputs(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: h5 = 'build/test-planar-slider.h5'
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: angle(:, :), disp(:, :)
        real(wp) :: r(3), v(3), omega(3), rot(3, 3), axes(3, 3), t, dev(2)
        integer :: k
        call read_scene(scene_file, scene, status)
        scene%output_file = h5
        scene%progress = .false.
        scene%rtol = 1.0e-9_wp
        scene%atol = 1.0e-9_wp
        call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call read_matrix(h5, 'joints/slider/angle', angle, error)
        if (allocated(error)) return
        call read_matrix(h5, 'joints/slider/displacement', disp, error)
        if (allocated(error)) return
        call check(error, size(angle, 1) == 1 .and. size(disp, 1) == 2 .and. &
                   size(disp, 2) == scene%n_output, 'shapes of angle and displacement')
        if (allocated(error)) return
        associate (plane => scene%markers(1))
            axes(:, 3) = plane%z_axis / norm2(plane%z_axis)
            axes(:, 1) = plane%x_axis / norm2(plane%x_axis)
            axes(:, 2) = cross(axes(:, 3), axes(:, 1))
            dev = 0.0_wp
            do k = 1, size(disp, 2)
                t = real(k - 1, wp) / real(size(disp, 2) - 1, wp) * scene%t_end
                call closed_form(error, scene, t, r, v, omega, rot)
                dev(1) = max(dev(1), abs(angle(1, k) - dot_product(omega, axes(:, 3)) * t))
                dev(2) = max(dev(2), maxval(abs(disp(:, k) - &
                                                matmul(r - plane%position, axes(:, 1:2)))))
            end do
        end associate
        print '(4x,a,2es9.2)', 'planar_slider.h5: angle, displacement off by ', dev
        call check(error, maxval(dev) <= 100.0_wp * scene%rtol, 'named outputs off the closed form')
    end subroutine test_named_outputs
end module test_planar_joint
