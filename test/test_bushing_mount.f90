!> inputs/bushing_mount.nml (issue 20): a block on four bushings under a
!> harmonic force. After the transient, the bounce, pitch and fore-aft
!> amplitudes (least-squares fit of a sin + b cos + c over the last 0.5 s)
!> against the closed-form frequency response |(K − ω²M + iωC)⁻¹ F₀| of the
!> linearised system (zgetrf/zgetrs), within 1 %; the &force groups' bad
!> input messages.
module test_bushing_mount
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_lapack, only: zgetrf, zgetrs, dgetrf, dgetrs
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene
    use flexmbs_run_multibody_builder, only: build_multibody
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_mbs_rotation, only: skew
    use flexmbs_mbs_system, only: mbs_system_t, marker_t
    use flexmbs_mbs_rigid_body, only: rigid_body_t
    use flexmbs_mbs_force_element, only: force_element_t
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_dae_stats, only: dae_stats_t
    use test_mbs_system, only: integrate
    use test_multibody_scene, only: read_matrix, expect
    use hdf5, only: h5open_f
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_bushing_mount

    character(len=*), parameter :: nl = new_line('a')

contains

    function collect_bushing_mount() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('frequency_response', test_frequency_response), &
                 new_test('hdf5_forces', test_hdf5_forces), &
                 new_test('bad_force_groups', test_bad_forces)]
    end function collect_bushing_mount

    !> Amplitudes (x, z, pitch) of the linear model of the scene's block: M,
    !> K = Σ Tᵀ K_b T, C = Σ Tᵀ C_b T with T = [I, −S(s_b); 0, I] for a
    !> bushing at s_b from the centre of mass, F₀ = (F, s_f × F).
    function closed_form(sys, omega, f0, s_f) result(amp)
        type(mbs_system_t), intent(in) :: sys
        real(wp), intent(in) :: omega, f0(3), s_f(3)
        real(wp) :: amp(3)
        real(wp) :: m(6, 6), k(6, 6), c(6, 6), t(6, 6)
        complex(wp) :: a(6, 6), x(6, 1)
        type(rigid_body_t) :: body
        type(force_element_t) :: el
        type(marker_t) :: marker
        integer :: e, ipiv(6), info
        body = sys%rigid_body_of(1)
        m = 0.0_wp
        m(1, 1) = body%mass
        m(2, 2) = m(1, 1)
        m(3, 3) = m(1, 1)
        m(4:6, 4:6) = body%inertia
        k = 0.0_wp
        c = 0.0_wp
        do e = 1, sys%element_count()
            el = sys%element_of(e)
            associate (mj => el%marker_j)
                if (mj == 0) cycle
                t = 0.0_wp
                t(1, 1) = 1.0_wp
                t(2, 2) = 1.0_wp
                t(3, 3) = 1.0_wp
                t(4, 4) = 1.0_wp
                t(5, 5) = 1.0_wp
                t(6, 6) = 1.0_wp
                marker = sys%marker_of(mj)
                t(1:3, 4:6) = -skew(marker%position)
                k = k + matmul(transpose(t), matmul(el%stiffness6, t))
                c = c + matmul(transpose(t), matmul(el%damping6, t))
            end associate
        end do
        a = cmplx(k - omega**2 * m, omega * c, kind=wp)
        x(1:3, 1) = f0
        x(4:6, 1) = [s_f(2) * f0(3) - s_f(3) * f0(2), s_f(3) * f0(1) - s_f(1) * f0(3), &
                     s_f(1) * f0(2) - s_f(2) * f0(1)]
        call zgetrf(6, 6, a, 6, ipiv, info)
        call zgetrs('N', 6, 1, a, 6, ipiv, x, 6, info)
        amp = abs([x(1, 1), x(3, 1), x(5, 1)])
    end function closed_form

    !> Amplitude of a sin(ω t) + b cos(ω t) + c fitted to samples y(t).
    function fitted_amplitude(t, y, omega) result(amp)
        real(wp), intent(in) :: t(:), y(:), omega
        real(wp) :: amp
        real(wp) :: basis(size(t), 3), n(3, 3), r(3, 1)
        integer :: ipiv(3), info
        basis(:, 1) = sin(omega * t)
        basis(:, 2) = cos(omega * t)
        basis(:, 3) = 1.0_wp
        n = matmul(transpose(basis), basis)
        r(:, 1) = matmul(transpose(basis), y)
        call dgetrf(3, 3, n, 3, ipiv, info)
        call dgetrs('N', 3, 1, n, 3, ipiv, r, 3, info)
        amp = hypot(r(1, 1), r(2, 1))
    end function fitted_amplitude

    !> The scene with RADAU5 (rtol 1e-8) to 1 s, then sampled every 2.5 ms
    !> to 1.5 s; x, z of the centre of mass and the pitch 2 p₂ against the
    !> closed form within 1 %.
    subroutine test_frequency_response(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(mbs_system_t), target :: sys
        type(formulation_t) :: gen
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), y(:), yp(:)
        integer, parameter :: nsamples = 200
        real(wp) :: ts(nsamples), samples(nsamples, 3), exact(3), measured(3), omega, dev
        character(len=200) :: msg
        character(len=5), parameter :: what(3) = ['x    ', 'z    ', 'pitch']
        type(force_element_t) :: shaker
        type(marker_t) :: marker
        integer :: k, i
        call read_scene('inputs/bushing_mount.nml', scene, status)
        if (status%ok()) call build_multibody(scene, sys, q0, v0, status)
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        allocate (y(sys%nq + 2 * sys%nv + sys%nc), yp(sys%nq + 2 * sys%nv + sys%nc))
        y = 0.0_wp
        y(1:sys%nq) = q0
        y(sys%nq + 1:sys%nq + sys%nv) = v0
        gen = new_formulation(sys, formulation_index2, q0, status=status)
        if (status%ok()) call gen%consistent_initial(0.0_wp, y, yp, status)
        if (status%ok()) call integrate(gen, y, 1.0_wp, 1.0e-8_wp, stats, status)
        do k = 1, nsamples
            if (.not. status%ok()) exit
            ts(k) = 1.0_wp + 0.0025_wp * k
            call integrate(gen, y, ts(k), 1.0e-8_wp, stats, status, t0=ts(k) - 0.0025_wp)
            samples(k, :) = [y(1), y(3), 2.0_wp * y(6)]
        end do
        call check(error, status%ok(), status%text())
        if (allocated(error)) return
        shaker = sys%element_of(sys%element_count())
        marker = sys%marker_of(shaker%marker_i)
        omega = shaker%driver%frequency
        exact = closed_form(sys, omega, shaker%driver%amplitude * shaker%force, marker%position)
        do i = 1, 3
            measured(i) = fitted_amplitude(ts, samples(:, i), omega)
            dev = abs(measured(i) / exact(i) - 1.0_wp)
            write (msg, '(a,2(a,es12.5),a,f8.4,a)') what(i), ': amplitude ', measured(i), &
                ', closed form ', exact(i), ', off by ', 100 * dev, ' %'
            print '(4x,a)', trim(msg)
            call check(error, dev < 0.01_wp, trim(msg))
            if (allocated(error)) return
        end do
    end subroutine test_frequency_response

    !> The scene's first 0.1 s written: /forces/shaker/force_i is
    !> 20 sin(90 t) e_z at every record, each bushing's force_i = −force_j,
    !> and the bushings carry the block's weight at the end within 5 %.
    subroutine test_hdf5_forces(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: h5 = 'build/test-bushing-mount.h5'
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: shaker(:, :), fi(:, :), fj(:, :)
        real(wp) :: load(3), lift
        character(len=*), parameter :: mounts(4) = ['mount 1', 'mount 2', 'mount 3', 'mount 4']
        integer :: err, unit, m, n
        call read_scene('inputs/bushing_mount.nml', scene, status)
        scene%output_file = h5
        scene%progress = .false.
        scene%t_end = 0.1_wp
        if (status%ok()) call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        call h5open_f(err)
        call read_matrix(h5, 'forces/shaker/force_i', shaker, error)
        if (allocated(error)) return
        n = size(shaker, 2)
        load = 0.0_wp
        ! n_output records, evenly spaced from 0 to 0.1 s
        do m = 1, n
            load = max(load, abs(shaker(:, m) - [0.0_wp, 0.0_wp, 20.0_wp * sin(9.0_wp * &
                                                                   (m - 1) / (n - 1))]))
        end do
        call check(error, n == scene%n_output .and. maxval(load) < 1.0e-12_wp, &
                   '/forces/shaker/force_i is not 20 sin(90 t) e_z')
        lift = 0.0_wp
        do m = 1, size(mounts)
            call read_matrix(h5, 'forces/' // trim(mounts(m)) // '/force_i', fi, error)
            if (.not. allocated(error)) call read_matrix(h5, 'forces/' // trim(mounts(m)) // &
                                                         '/force_j', fj, error)
            if (allocated(error)) return
            call check(error, maxval(abs(fi + fj)) <= 1.0e-12_wp * maxval(abs(fj)), &
                       trim(mounts(m)) // ': force_i is not -force_j')
            if (allocated(error)) return
            lift = lift + fj(3, n)
        end do
        print '(4x,a,f9.4,a)', 'bushings lift the block by ', lift, ' N at t = 0.1 (weight 196.2 N)'
        call check(error, abs(lift - 20.0_wp * 9.81_wp) < 0.05_wp * 20.0_wp * 9.81_wp + &
                   abs(20.0_wp * sin(9.0_wp)), 'the bushings carry the weight')
        open (newunit=unit, file=h5)
        close (unit, status='delete')
    end subroutine test_hdf5_forces

    !> A one-body scene with a &force group varied into each defect.
    function mount(forces) result(text)
        character(len=*), intent(in) :: forces
        character(len=:), allocatable :: text
        text = '&simulation problem = ''multibody'', t_end = 0.01 /' // nl // &
               '&rigid_body name = ''b'', mass = 1, inertia = 0.1, 0.1, 0.1 /' // nl // &
               '&marker name = ''G'', body = ''ground'' /' // nl // &
               '&marker name = ''P'', body = ''b'' /' // nl // &
               '&marker name = ''Q'', body = ''b'', position = 0.1, 0, 0 /' // nl // &
               forces // nl // '&output file = ''none'' /'
    end function mount

    subroutine test_bad_forces(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: bush = '&force type = ''bushing'', marker_i = ''G'', &
            &marker_j = ''P'', '
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(status_t) :: status
        ! the valid scene runs
        call parse_scene(mount(bush // 'stiffness = 1e3, 1e3, 1e3, 10, 10, 10 /'), &
                         'mb.nml', scene, status)
        if (status%ok()) call run_scene(scene, .true., result, status)
        call check(error, status%ok(), 'valid mount: ' // status%text())
        if (allocated(error)) return
        call expect(error, mount('&force type = ''spring'', marker_i = ''G'', marker_j = ''P'' /'), &
            "mb.nml: &force: type = 'spring': must be one of")
        call expect(error, mount(bush // 'stiffness = 1e3, 1e3, 1e3 /'), &
            "mb.nml: &force: stiffness = 1e3, 1e3, 1e3: 3 values: a bushing takes 6")
        call expect(error, mount('&force name = ''s'', type = ''spring_damper'', marker_i = ''G'', &
            &marker_j = ''P'' /'), "&force 's': stiffness: required")
        call expect(error, mount('&force type = ''spring_damper'', marker_i = ''G'', &
            &marker_j = ''R'', stiffness = 10 /'), &
            "&force: marker_j = 'R': no &marker of that name")
        call expect(error, mount('&force type = ''rotational'', marker_i = ''P'', &
            &marker_j = ''Q'', stiffness = 10 /'), &
            "&force: marker_j = 'Q': on the same body as marker_i ('b')")
        call expect(error, mount('&force type = ''applied'', marker_i = ''P'', marker_j = ''G'', &
            &force = 1, 0, 0, coefficients = 1, 0, 0, 0 /'), &
            "&force: marker_j = 'G': an applied load acts on marker_i alone")
        call expect(error, mount('&force type = ''applied'', marker_i = ''P'', &
            &force = 1, 0, 0 /'), "&force 'force 1': coefficients (default): s(t) is zero")
        call expect(error, mount('&force type = ''spring_damper'', marker_i = ''G'', &
            &marker_j = ''P'', stiffness = 10, damping = -1 /'), "&force: damping = -1")
        call expect(error, mount('&force type = ''spring_damper'', marker_i = ''G'', &
            &marker_j = ''Q'', stiffness = 10, amplitude = 3 /'), &
            "&force: amplitude = 3: not read by a spring_damper element")
        call expect(error, mount(bush // 'stiffness = 1e3, 1e3, 1e3, 10, 10, 10 /' // nl // &
            '&force type = ''spring_damper'', marker_i = ''G'', marker_j = ''P'', stiffness = 1 /'), &
            "the markers are 0.000000E+00 m apart")
    end subroutine test_bad_forces
end module test_bushing_mount
