!> Restart from the result file: the checkpoint written and read back, the
!> file continued in place (records after the checkpoint replaced), the
!> statistics summed over the pieces, and a run stopped after a step and
!> resumed that ends where the uninterrupted run ends, within its
!> tolerance; a resume with a changed scene refused, naming the change.
module test_restart
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_error_test, cause_newton_diverged
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_checkpoint, only: checkpoint_t, read_checkpoint, stats_sum
    use flexmbs_io_namelist, only: scene_input_t, parse_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use test_io, only: scratch, read_series
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_restart

    !> Stops the integration after accepted step `at` (as SIGTERM would).
    type, extends(sink_t) :: stop_sink_t
        integer :: at = 0
    contains
        procedure :: output => stop_output
        procedure :: wants_steps => stop_wants_steps
        procedure :: step => stop_step
    end type stop_sink_t

    character, parameter :: nl = new_line('a')
    real(wp), parameter :: tol = 1.0e-8_wp

contains

    function collect_restart() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('checkpoint_round_trip_and_reopen', test_round_trip), &
                 new_test('statistics_sum_over_pieces', test_stats_sum), &
                 new_test('stopped_run_resumed_to_t_end', test_resume), &
                 new_test('changed_scene_refused', test_changed_scene)]
    end function collect_restart

    subroutine stop_output(self, t, y, status)
        class(stop_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
    end subroutine stop_output

    logical function stop_wants_steps(self)
        class(stop_sink_t), intent(in) :: self
        stop_wants_steps = self%at > 0
    end function stop_wants_steps

    subroutine stop_step(self, nr, t_old, t, y, dense, stop, status)
        class(stop_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        logical, intent(inout) :: stop
        type(status_t), intent(inout) :: status
        if (nr == self%at + 1) stop = .true.
    end subroutine stop_step

    !> Five records, a checkpoint after them, two more: the checkpoint reads
    !> back as written and counts five records; reopened from it, the file
    !> keeps those five (/time and the block), takes new ones after them and
    !> lists the restart's time.
    subroutine test_round_trip(error)
        type(error_t), allocatable, intent(out) :: error
        type(hdf5_sink_t) :: h5
        type(checkpoint_t) :: cp, back
        type(status_t) :: status
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        character(len=:), allocatable :: path
        integer :: k, nst
        path = scratch('checkpoint.h5')
        call h5%create(path, 3, status)
        if (status%ok()) call h5%add_block('q', 2, 3, status)
        if (status%ok()) call h5%write_text('scene_fingerprint', repeat('a', 64), status)
        do k = 1, 5
            call h5%output(0.1_wp * k, [1.0_wp, 2.0_wp, 3.0_wp] * k, status)
        end do
        cp%t = 0.55_wp
        cp%h = 0.05_wp
        cp%order = 3
        cp%piece = 2
        cp%y = [5.5_wp, -1.0_wp, 2.5_wp]
        cp%live%nst = 10
        cp%live%nac = 8
        cp%live%nrj = 2
        cp%live%wall = 1.25_wp
        cp%prior%nfe = 77
        call h5%keep_checkpoint(cp, status)
        do k = 6, 7
            call h5%output(0.1_wp * k, [1.0_wp, 2.0_wp, 3.0_wp] * k, status)
        end do
        call h5%close(status)
        call check(error, status%ok(), 'writing: ' // status%text())
        if (allocated(error)) return
        call read_checkpoint(path, back, status)
        call check(error, status%ok(), 'read_checkpoint: ' // status%text())
        if (allocated(error)) return
        call check(error, back%t == cp%t .and. back%h == cp%h .and. back%order == 3 .and. &
            back%piece == 2 .and. back%records == 5, 'the checkpoint''s t, h, order, piece, records')
        call check(error, all(back%y == cp%y), 'the checkpoint''s y')
        call check(error, back%live%nst == 10 .and. back%live%nac == 8 .and. &
            back%live%wall == 1.25_wp .and. back%prior%nfe == 77, 'its statistics')
        call check(error, back%outcome == '', 'no outcome: the run did not end cleanly')
        if (allocated(error)) return

        call h5%reopen(path, 3, back, status)
        if (status%ok()) call h5%add_block('q', 2, 3, status)
        call h5%output(0.6_wp, [9.0_wp, 8.0_wp, 7.0_wp], status)
        call h5%close(status)
        call check(error, status%ok(), 'continuing: ' // status%text())
        if (allocated(error)) return
        call read_series(path, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 6 .and. size(y, 2) == 6 .and. size(q, 2) == 6, &
            'records: 5 kept, 1 new')
        if (allocated(error)) return
        call check_close(error, time(6), 0.6_wp, 0.0_wp, 'the new record''s time')
        call check(error, all(q(:, 5) == [10.0_wp, 15.0_wp]), 'a kept record of the block')
        call check(error, all(q(:, 6) == [8.0_wp, 7.0_wp]), 'the new record of the block')
    end subroutine test_round_trip

    !> Counters, causes and times add; the last piece's time reached stays.
    subroutine test_stats_sum(error)
        type(error_t), allocatable, intent(out) :: error
        type(dae_stats_t) :: a, b, total
        a%nst = 10; a%nac = 7; a%nrj = 3; a%nfe = 40; a%ndec = 5; a%cpu = 1.0_wp
        a%t_reached = 0.4_wp
        call a%rejections%add(cause_error_test)
        b%nst = 20; b%nac = 19; b%nrj = 1; b%nfe = 60; b%ndec = 6; b%cpu = 2.0_wp
        b%t_reached = 1.0_wp
        call b%rejections%add(cause_error_test)
        call b%rejections%add(cause_newton_diverged)
        total = stats_sum(a, b)
        call check(error, total%nst == 30 .and. total%nac == 26 .and. total%nrj == 4 .and. &
            total%nfe == 100 .and. total%ndec == 11, 'counters')
        call check(error, total%rejections%count_of(cause_error_test) == 2 .and. &
            total%rejections%count_of(cause_newton_diverged) == 1, 'causes')
        call check_close(error, total%cpu, 3.0_wp, 0.0_wp, 'CPU')
        call check_close(error, total%t_reached, 1.0_wp, 0.0_wp, 't reached')
    end subroutine test_stats_sum

    !> The pendulum at rtol = atol = 1e-8, stopped after 60 accepted steps
    !> (checkpoints at every step), then resumed: it reaches t_end, all 41
    !> records are there, the end state is the uninterrupted run's within
    !> 10 TOL, and the statistics sum both pieces.
    subroutine test_resume(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        type(run_result_t) :: full, first, resumed
        type(status_t) :: status
        type(stop_sink_t) :: stopper
        real(wp), allocatable :: time(:), y(:, :), q(:, :)
        character(len=:), allocatable :: path
        integer :: nst
        path = scratch('pendulum.h5')
        call parse_scene(pendulum(path, tol), 'pendulum.nml', scene, status)
        call check(error, status%ok(), 'scene: ' // status%text())
        if (allocated(error)) return
        call run_scene(scene, .true., full, status)
        call check(error, status%ok(), 'uninterrupted: ' // status%text())
        if (allocated(error)) return
        stopper%at = 60
        call run_scene(scene, .true., first, status, record=stopper)
        call check(error, status%code == status_interrupted .and. first%t < 2.0_wp, &
            'stopped: ' // status%text())
        if (allocated(error)) return
        call run_scene(scene, .true., resumed, status, resume=path)
        call check(error, status%ok() .and. resumed%resumed, 'resumed: ' // status%text())
        if (allocated(error)) return
        call check_close(error, resumed%resumed_from, first%t, 0.0_wp, &
            'resumed from the last step reached')
        call check_close(error, resumed%t, 2.0_wp, 0.0_wp, 'reached t_end')
        call check(error, maxval(abs(resumed%y(1:4) - full%y(1:4))) <= 10.0_wp * tol, &
            'the end state is the uninterrupted run''s within 10 TOL')
        call check(error, resumed%stats%nac >= first%stats%nac + 1 .and. &
            resumed%stats%nfe > first%stats%nfe, 'statistics sum both pieces')
        call read_series(path, time, y, q, nst, error)
        if (allocated(error)) return
        call check(error, size(time) == 41, 'all 41 records')
        if (allocated(error)) return
        call check(error, all(time(2:) > time(:40)), 'records strictly increasing')
    end subroutine test_resume

    !> A resume whose scene differs in a number is refused, naming it; one
    !> differing only in &output's progress display is not.
    subroutine test_changed_scene(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene, changed
        type(run_result_t) :: result
        type(status_t) :: status
        type(stop_sink_t) :: stopper
        character(len=:), allocatable :: path
        path = scratch('changed.h5')
        call parse_scene(pendulum(path, tol), 'pendulum.nml', scene, status)
        stopper%at = 20
        call run_scene(scene, .true., result, status, record=stopper)
        call check(error, status%code == status_interrupted, 'stopped: ' // status%text())
        if (allocated(error)) return
        call parse_scene(pendulum(path, 2.0_wp * tol), 'changed.nml', changed, status)
        call run_scene(changed, .true., result, status, resume=path)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), '&solver rtol = 1E-8 in the result, 2E-8 now') > 0, &
            'refused, naming rtol: ' // status%text())
        if (allocated(error)) return
        call run_scene(scene, .true., result, status, resume=path)
        call check(error, status%ok(), 'the same scene resumes: ' // status%text())
    end subroutine test_changed_scene

    !> The pendulum scene at rtol = atol = `rtol`, writing `path`, with a
    !> checkpoint at every accepted step.
    function pendulum(path, rtol) result(text)
        character(len=*), intent(in) :: path
        real(wp), intent(in) :: rtol
        character(len=:), allocatable :: text
        character(len=24) :: value
        write (value, '(es9.1e1)') rtol
        text = '&simulation problem = ''pendulum'', t_end = 2.0, pendulum_formulation = &
            &''index2'', pendulum_angle = 1.2 /' // nl // &
            '&solver name = ''radau5'', rtol = ' // trim(value) // ', atol = ' // &
            trim(value) // ' /' // nl // &
            '&output file = ''' // path // ''', n_output = 41, checkpoint_interval = 0, &
            &progress = .false. /' // nl
    end function pendulum
end module test_restart
