!> Modal bodies in scenes (`&flexible_body model = 'modal'`):
!> inputs/five_body_modal.nml against the nonlinear inputs/five_body.nml,
!> every solver on it, the basis cache reused and redone, and bad input
!> named.
module test_modal_scene
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: real_text
    use flexmbs_core_files, only: delete_file
    use flexmbs_io_namelist, only: scene_input_t, read_scene, parse_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_modal_scene

    character(len=*), parameter :: nl = new_line('a')
    character(len=*), parameter :: cache = 'test_modal_scene_cache.h5'

contains

    function collect_modal_scene() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('five_body_modal_vs_nonlinear', test_five_body), &
                 new_test('every_solver', test_solvers), &
                 new_test('every_formulation', test_formulations), &
                 new_test('spring_on_an_interface', test_spring), &
                 new_test('basis_cache', test_cache), &
                 new_test('bad_input_named', test_bad)]
    end function collect_modal_scene

    !> Run the scene file with `solver` to t_end (in `formulation` when
    !> given), no output file.
    subroutine run_file(path, solver, t_end, result, status, formulation)
        character(len=*), intent(in) :: path, solver
        real(wp), intent(in) :: t_end
        type(run_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: formulation
        type(scene_input_t) :: scene
        call read_scene(path, scene, status)
        if (.not. status%ok()) return
        scene%output_file = ''
        scene%progress = .false.
        scene%solver_name = solver
        scene%t_end = t_end
        if (present(formulation)) scene%multibody%formulation = formulation
        call run_scene(scene, .true., result, status)
    end subroutine run_file

    !> 0.3 s of the five-body mechanism, the coupler modal (k = 8) or
    !> nonlinear: the rocker (the first body: y(1:7)) and slider agree to
    !> the reduction's error, far below the motion (the rocker has turned
    !> by about 0.2 rad).
    subroutine test_five_body(error)
        type(error_t), allocatable, intent(out) :: error
        type(run_result_t) :: modal, full
        type(status_t) :: status
        real(wp) :: dev
        call run_file('inputs/five_body_modal.nml', 'radau5', 0.3_wp, modal, status)
        call check(error, status%ok(), 'modal: ' // status%text())
        if (allocated(error)) return
        call run_file('inputs/five_body.nml', 'radau5', 0.3_wp, full, status)
        call check(error, status%ok(), 'nonlinear: ' // status%text())
        if (allocated(error)) return
        dev = maxval(abs(modal%y(1:14) - full%y(1:14)))
        print '(4x,a,es9.2,a,f8.5)', 'five-body, modal vs nonlinear coupler at 0.3 s: rocker &
            &and slider ', dev, ', rocker e1 ', full%y(5)
        call check(error, full%y(5) > 0.05_wp, 'the rocker did not fall')
        call check(error, dev <= 2.0e-3_wp * abs(full%y(5)), 'modal and nonlinear differ: ' // &
                   real_text(dev))
        call check(error, index(modal%summary, 'coupler (modal)') > 0, 'summary: ' // &
                   modal%summary)
    end subroutine test_five_body

    !> RADAU5, DDASSL, IDA and MEXAX on the modal five-body, 0.1 s: the same
    !> state to the tolerance, the constraints held.
    subroutine test_solvers(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: solvers(4) = ['radau5', 'ddassl', 'ida   ', 'mexax ']
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: y_ref(:)
        real(wp) :: dev
        integer :: k
        do k = 1, size(solvers)
            call run_file('inputs/five_body_modal.nml', trim(solvers(k)), 0.1_wp, result, status)
            call check(error, status%ok(), trim(solvers(k)) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, result%has_drift .and. result%drift_end(1) <= 1.0e-8_wp, &
                       trim(solvers(k)) // ': drift')
            if (k == 1) then
                y_ref = result%y(result%q_first:result%q_last)
                cycle
            end if
            dev = maxval(abs(result%y(result%q_first:result%q_last) - y_ref))
            print '(4x,a,es9.2)', trim(solvers(k)) // ': positions off RADAU5 by ', dev
            call check(error, dev <= 1.0e-5_wp, trim(solvers(k)) // ': positions differ')
        end do
    end subroutine test_solvers

    !> The modal five-body in each formulation (RADAU5, 0.05 s): the same
    !> state as GGL's to the tolerance, the position constraints held.
    subroutine test_formulations(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=6), parameter :: forms(4) = ['ggl   ', 'index1', 'index2', 'index3']
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), allocatable :: y_ref(:)
        real(wp) :: dev
        integer :: k
        do k = 1, size(forms)
            call run_file('inputs/five_body_modal.nml', 'radau5', 0.05_wp, result, status, &
                          formulation=forms(k))
            call check(error, status%ok(), trim(forms(k)) // ': ' // status%text())
            if (allocated(error)) return
            call check(error, result%has_drift .and. result%drift_end(1) <= 1.0e-5_wp, &
                       trim(forms(k)) // ': position drift ' // real_text(result%drift_end(1)))
            if (k == 1) then
                y_ref = result%y(result%q_first:result%q_last)
                cycle
            end if
            dev = maxval(abs(result%y(result%q_first:result%q_last) - y_ref))
            print '(4x,a,es9.2)', trim(forms(k)) // ': positions off GGL by ', dev
            call check(error, dev <= 1.0e-4_wp, trim(forms(k)) // ': positions differ')
        end do
    end subroutine test_formulations

    !> A force element on a modal body's interface: the modal bar hung by a
    !> spring at each end face (no joint) from ground points above them
    !> settles where the springs carry its weight, m g / 2k below their
    !> free length (3 s, the springs' damping).
    subroutine test_spring(error)
        type(error_t), allocatable, intent(out) :: error
        type(run_result_t) :: result
        type(status_t) :: status
        real(wp), parameter :: stiffness = 200.0_wp, length = 0.5_wp, g = 9.81_wp
        real(wp) :: mass, stretch
        character(len=:), allocatable :: text
        mass = 920.0_wp * 0.6_wp * 0.08_wp * 0.05_wp
        text = '&simulation problem = ''multibody'', t_end = 3 /' // nl // &
            '&flexible_body name = ''bar'', divisions = 4, 1, 1, lengths = 0.6, 0.08, 0.05, &
            &origin = -0.3, -0.04, -0.025, model = ''modal'', modes = 2, gravity = 0, 0, -9.81 /' &
            // nl // &
            '&material youngs_modulus = 7e5, density = 920, viscosity = 500 /' // nl // &
            '&multibody gravity = 0, 0, -9.81 /' // nl // &
            '&marker name = ''hook'', body = ''ground'', position = -0.3, 0, 0.5 /' // nl // &
            '&marker name = ''end'', body = ''bar'', node_set = ''xmin'' /' // nl // &
            '&marker name = ''far'', body = ''bar'', node_set = ''xmax'' /' // nl // &
            '&marker name = ''hook 2'', body = ''ground'', position = 0.3, 0, 0.5 /' // nl // &
            '&force name = ''s1'', type = ''spring_damper'', marker_i = ''hook'', &
            &marker_j = ''end'', stiffness = 200, damping = 20, free_length = 0.5 /' // nl // &
            '&force name = ''s2'', type = ''spring_damper'', marker_i = ''hook 2'', &
            &marker_j = ''far'', stiffness = 200, damping = 20, free_length = 0.5 /' // nl // &
            '&output file = ''none'' /'
        call run_text(text, result, status)
        call check(error, status%ok(), 'run: ' // status%text())
        if (allocated(error)) return
        ! two springs share the weight: each face's centroid (where its
        ! interface frame, the first rigid body, sits) hangs (m g / 2) / k
        ! below z = 0
        stretch = mass * g / 2 / stiffness
        associate (z => result%y(result%q_first + 2))
            print '(4x,a,es12.4,a,es12.4)', 'modal bar on two springs: xmin face z ', z, &
                ', expected ', -stretch
            call check(error, abs(z + stretch) <= 2.0e-3_wp * stretch, 'centre at ' // &
                       real_text(z) // ', expected ' // real_text(-stretch))
        end associate
    end subroutine test_spring

    !> A modal pendulum: a bar hung at its xmin face. With modes_cache the
    !> first run writes the basis, the second reads it and gives the same
    !> trajectory bit for bit; another k is computed afresh (and replaces
    !> the file); a file that is not a cache is refused.
    subroutine test_cache(error)
        type(error_t), allocatable, intent(out) :: error
        type(run_result_t) :: first, second, other
        type(status_t) :: status
        integer :: unit
        logical :: exists
        call check(error, delete_file(cache), 'cannot delete ' // cache)
        call run_text(pendulum(4, 'modes_cache = ''' // cache // ''''), first, status)
        inquire (file=cache, exist=exists)
        call check(error, status%ok() .and. exists, 'first run: ' // status%text())
        if (allocated(error)) return
        call run_text(pendulum(4, 'modes_cache = ''' // cache // ''''), second, status)
        call check(error, status%ok(), 'second run: ' // status%text())
        if (allocated(error)) return
        call check(error, all(first%y == second%y), 'the cached basis changes the run')
        call run_text(pendulum(2, 'modes_cache = ''' // cache // ''''), other, status)
        call check(error, status%ok() .and. size(other%y) < size(first%y), &
                   'another k: ' // status%text())
        open (newunit=unit, file=cache, status='replace', action='write')
        write (unit, '(a)') 'not an HDF5 file'
        close (unit)
        call run_text(pendulum(2, 'modes_cache = ''' // cache // ''''), other, status)
        call check(error, status%code == status_bad_input .and. &
                   index(status%text(), 'not an HDF5 file') > 0, 'a foreign file: ' // &
                   status%text())
        call check(error, delete_file(cache), 'cannot delete ' // cache)
    end subroutine test_cache

    !> The modal pendulum's scene text with k modes and `extra` in its
    !> &flexible_body.
    function pendulum(k, extra) result(text)
        integer, intent(in) :: k
        character(len=*), intent(in) :: extra
        character(len=:), allocatable :: text
        character(len=8) :: kt
        write (kt, '(i0)') k
        text = '&simulation problem = ''multibody'', t_end = 0.05 /' // nl // &
            '&flexible_body name = ''bar'', divisions = 4, 1, 1, lengths = 0.6, 0.08, 0.05, &
            &model = ''modal'', modes = ' // trim(kt) // ', ' // extra // ' /' // nl // &
            '&material youngs_modulus = 7e5, density = 920, viscosity = 500 /' // nl // &
            '&multibody gravity = 0, -9.81, 0 /' // nl // &
            '&marker name = ''hinge'', body = ''ground'', position = 0, 0.04, 0.025 /' // nl // &
            '&marker name = ''end'', body = ''bar'', node_set = ''xmin'' /' // nl // &
            '&joint name = ''pin'', type = ''revolute'', marker_i = ''hinge'', &
            &marker_j = ''end'' /' // nl // '&output file = ''none'' /'
    end function pendulum

    subroutine run_text(text, result, status)
        character(len=*), intent(in) :: text
        type(run_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        type(scene_input_t) :: scene
        call parse_scene(text, 'modal.nml', scene, status)
        if (.not. status%ok()) return
        scene%progress = .false.
        call run_scene(scene, .true., result, status)
    end subroutine run_text

    !> Too many modes, an interface that is no node set, a marker on a set
    !> that is no interface, modal settings on a nonlinear body, supports on
    !> a modal one: each refused naming the group, variable and value.
    subroutine test_bad(error)
        type(error_t), allocatable, intent(out) :: error
        call expect(error, pendulum(1000, 'modes_method = ''dense'''), &
                    'modes = 1000: the mesh allows 0 to')
        call expect(error, pendulum(2, 'interfaces = ''xmin'', ''nope'''), &
                    'interfaces: ''nope''')
        call expect(error, pendulum(2, 'interfaces = ''xmax'''), &
                    'not an interface of the modal body ''bar''')
        call expect(error, pendulum(2, 'fixed = ''xmax'''), &
                    'fixed')
        call expect(error, '&simulation problem = ''multibody'' /' // nl // &
            '&flexible_body divisions = 2, 1, 1, lengths = 1, 1, 1, modes = 2 /' // nl // &
            '&material youngs_modulus = 1e6, density = 1000 /' // nl // &
            '&output file = ''none'' /', 'only with model = ''modal''')
        call expect(error, '&simulation problem = ''multibody'' /' // nl // &
            '&flexible_body divisions = 2, 1, 1, lengths = 1, 1, 1, model = ''modal'' /' // nl &
            // '&output file = ''none'' /', 'needs a &material')
    contains
        subroutine expect(error, text, part)
            type(error_t), allocatable, intent(inout) :: error
            character(len=*), intent(in) :: text, part
            type(run_result_t) :: result
            type(status_t) :: status
            call run_text(text, result, status)
            call check(error, status%code == status_bad_input .and. &
                       index(status%text(), part) > 0, 'expected "' // part // '", got: ' // &
                       status%text())
        end subroutine expect
    end subroutine test_bad
end module test_modal_scene
