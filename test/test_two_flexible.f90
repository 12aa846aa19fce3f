!> Several flexible bodies in one multibody scene (repeatable
!> `&flexible_body`): a free system of two soft bars and a rigid hub joined
!> by spherical joints, at the centroids of the bars' face node sets (set
!> markers) and through node frames, undamped and without gravity,
!> conserves linear momentum to round-off and angular momentum and energy
!> to tolerance level, shrinking with the tolerance, for RADAU5, DDASSL,
!> IDA and MEXAX; and inputs/two_soft_links.nml, the double pendulum of two
!> soft links, runs with the same motion for the four solvers.
module test_two_flexible
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_mbs_system, only: mbs_system_t, part_rigid, part_flexible
    use flexmbs_io_namelist, only: scene_input_t, parse_scene, read_scene
    use flexmbs_run_runner, only: run_scene, run_result_t
    use flexmbs_run_multibody_builder, only: build_multibody
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_two_flexible, check_invariants, solvers

    character(len=*), parameter :: nl = new_line('a')
    !> the four solvers every invariant is checked with
    character(len=8), parameter :: solvers(4) = [character(len=8) :: 'radau5', 'ddassl', &
        'ida', 'mexax']

contains

    function collect_two_flexible() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('free_system_invariants_four_solvers', test_invariants), &
                 new_test('two_soft_links_four_solvers', test_two_soft_links)]
    end function collect_two_flexible

    !> Everything moves with v = (0.2, -0.1, 0.05) and turns with ω = (0.3,
    !> 0.5, 4) about the origin, the hub 2 rad/s faster about x: the joints'
    !> markers lie on the x axis, so the initial velocities are consistent,
    !> and the bars swing and stretch (centrifugal load) relative to the hub.
    function free_scene(framed) result(text)
        logical, intent(in) :: framed !! markers given positions: node frames
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.05 /' // nl // &
            '&multibody formulation = ''ggl'', gravity = 0, 0, 0 /' // nl // &
            '&rigid_body name = ''hub'', mass = 0.5, inertia = 0.002, 0.01, 0.01, ' // &
            'velocity = 0.2, -0.1, 0.05, angular_velocity = 2.3, 0.5, 4.0 /' // nl // &
            bar('right', '0.05', '0.2, 0.7, -0.05') // bar('left', '-0.35', '0.2, -0.9, 0.15') // &
            '&material name = ''r'', body = ''right'', youngs_modulus = 7e5, density = 920 /' &
            // nl // &
            '&material name = ''l'', body = ''left'', youngs_modulus = 7e5, density = 920 /' &
            // nl // &
            '&marker name = ''hr'', body = ''hub'', position = 0.05, 0, 0 /' // nl // &
            '&marker name = ''hl'', body = ''hub'', position = -0.05, 0, 0 /' // nl // &
            '&marker name = ''r0'', body = ''right'', node_set = ''xmin''' // &
            trim(merge(', position = 0.05, 0, 0 ', '                        ', framed)) // &
            ' /' // nl // &
            '&marker name = ''l0'', body = ''left'', node_set = ''xmax''' // &
            trim(merge(', position = -0.05, 0, 0', '                        ', framed)) // &
            ' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''hr'', marker_j = ''r0'' /' // nl // &
            '&joint type = ''spherical'', marker_i = ''hl'', marker_j = ''l0'' /' // nl // &
            '&output file = ''none'', n_output = 2 /' // nl
    contains
        !> A bar from x = x0 on, its centroid c moving at v + ω × c.
        function bar(name, x0, velocity) result(group)
            character(len=*), intent(in) :: name, x0, velocity
            character(len=:), allocatable :: group
            group = '&flexible_body name = ''' // name // ''', divisions = 2, 1, 1, ' // &
                'lengths = 0.3, 0.04, 0.04, origin = ' // x0 // ', -0.02, -0.02, ' // &
                'initial_velocity = ' // velocity // ', ' // &
                'initial_angular_velocity = 0.3, 0.5, 4.0 /' // nl
        end function bar
    end function free_scene

    !> Per joining (set markers, node frames): two flexible bodies, the hub
    !> and (framed) two node frames, and the invariants (check_invariants).
    subroutine test_invariants(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:)
        integer :: framed
        do framed = 0, 1
            call parse_scene(free_scene(framed == 1), 'free.nml', scene, status)
            if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
            call check(error, status%ok(), 'scene: ' // status%text())
            if (allocated(error)) return
            call check(error, sys%part_count(part_flexible) == 2 .and. &
                       sys%part_count(part_rigid) == 1 + 2 * framed, &
                       'two flexible bodies, the hub and (framed) two node frames')
            if (allocated(error)) return
            if (framed == 1) then
                print '(4x,a)', 'through node frames:'
            else
                print '(4x,a)', 'at the sets'' centroids (set markers):'
            end if
            call check_invariants(error, scene, sys, q0, v0)
            if (allocated(error)) return
        end do
    end subroutine test_invariants

    !> The free system of `scene` (built as sys, starting at q0, v0) per
    !> solver, at rtol = atol = 1e-5 and 1e-7: the change of linear momentum
    !> (round-off: every method here keeps linear invariants), of angular
    !> momentum about the origin and of energy over t_end, relative to their
    !> sizes at the start, within 100 rtol and smaller at the tighter
    !> tolerance.
    subroutine check_invariants(error, scene, sys, q0, v0)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t), intent(inout) :: scene !! its solver and tolerances are set
        type(mbs_system_t), intent(inout) :: sys !! (its energy and momenta evaluations)
        real(wp), intent(in) :: q0(:), v0(:)
        real(wp), parameter :: tols(2) = [1.0e-5_wp, 1.0e-7_wp]
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp) :: l0(3), a0(3), l1(3), a1(3), e0, e1, dl(2), da(2), de(2)
        integer :: k, i
        call sys%momenta(q0, v0, l0, a0)
        e0 = sys%total_energy(q0, v0)
        do k = 1, size(solvers)
            do i = 1, size(tols)
                scene%solver_name = solvers(k)
                scene%rtol = tols(i)
                scene%atol = tols(i)
                scene%progress = .false.
                call run_scene(scene, .true., result, status)
                call check(error, status%ok(), trim(solvers(k)) // ': ' // status%text())
                if (allocated(error)) return
                associate (q => result%y(1:sys%nq), v => result%y(sys%nq + 1:sys%nq + sys%nv))
                    call sys%momenta(q, v, l1, a1)
                    e1 = sys%total_energy(q, v)
                end associate
                dl(i) = norm2(l1 - l0) / norm2(l0)
                da(i) = norm2(a1 - a0) / norm2(a0)
                de(i) = abs(e1 - e0) / abs(e0)
            end do
            print '(4x,a8,a,2es9.2,a,2es9.2,a,2es9.2)', solvers(k), ' rtol 1e-5, 1e-7: &
                &linear ', dl, ', angular ', da, ', energy ', de
            call check(error, all(dl <= 1.0e-12_wp), trim(solvers(k)) // &
                       ': linear momentum changed beyond round-off')
            call check(error, all(da <= 100 * tols) .and. all(de <= 100 * tols), &
                       trim(solvers(k)) // ': angular momentum or energy beyond 100 rtol')
            call check(error, da(2) < da(1) .and. de(2) < de(1), trim(solvers(k)) // &
                       ': angular momentum or energy error does not shrink with the tolerance')
            if (allocated(error)) return
        end do
    end subroutine check_invariants

    !> inputs/two_soft_links.nml over its first 0.1 s: DDASSL, IDA and MEXAX
    !> end where RADAU5 does (the lower bar's positions, 1e-4 m at rtol 1e-6),
    !> and the lower link has swung down.
    subroutine test_two_soft_links(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(mbs_system_t) :: sys
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), q_ref(:)
        integer :: k, first, last, n
        call read_scene('inputs/two_soft_links.nml', scene, status)
        if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), 'scene: ' // status%text())
        if (allocated(error)) return
        call sys%flexible_coordinates(2, first, n)
        last = first + n
        first = first + 1
        do k = 1, size(solvers)
            scene%solver_name = solvers(k)
            scene%rtol = 1.0e-6_wp
            scene%atol = 1.0e-6_wp
            scene%t_end = 0.1_wp
            scene%output_file = ''
            scene%progress = .false.
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), trim(solvers(k)) // ': ' // status%text())
            if (allocated(error)) return
            if (k == 1) then
                q_ref = result%y(first:last)
                print '(4x,a,es9.2,a)', 'two soft links: the lower bar fell ', &
                    maxval(q0(first:last) - q_ref), ' m (largest node drop, RADAU5)'
                call check(error, maxval(q0(first:last) - q_ref) > 0.02_wp, &
                           'the lower link did not fall')
            else
                print '(4x,a8,a,es9.2,a)', solvers(k), ' ends ', &
                    maxval(abs(result%y(first:last) - q_ref)), ' m from RADAU5'
                call check(error, maxval(abs(result%y(first:last) - q_ref)) <= 1.0e-4_wp, &
                           trim(solvers(k)) // ': the lower bar ends away from RADAU5''s')
            end if
            if (allocated(error)) return
        end do
    end subroutine test_two_soft_links
end module test_two_flexible
