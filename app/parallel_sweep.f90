!> `flexmbs sweep STUDY -j N`: the grid's points as processes of this
!> program (`flexmbs sweep STUDY --point K --quiet`, core/processes, no
!> shell), at most N at a time, each writing its record into the study's
!> results folder and its output into point_K.log there; the table is then
!> merged from the records (run/study_merge), as after a Slurm job array.
!>
!> The children run in process groups of their own, so that a Ctrl-C at
!> the terminal reaches this process only: SIGINT or SIGTERM caught here
!> is passed on once to every running point, which stops after its step
!> (a second signal would end it at once); no further point starts. A
!> point stopped by a signal from elsewhere stops the sweep the same way.
module flexmbs_app_parallel_sweep
    use flexmbs_core_status, only: status_t, status_io_error, status_signal
    use flexmbs_core_text, only: int_text
    use flexmbs_core_signals, only: caught_signal, signal_name, signal_number
    use flexmbs_core_files, only: delete_file
    use flexmbs_core_processes, only: start_process, wait_any_process, signal_process, &
        wait_signal
    use flexmbs_run_study_results, only: record_path, log_path
    implicit none
    private

    !> Exit status of a flexmbs stopped by a signal: 128 + its number.
    integer, parameter :: signal_exit_base = 128

    public :: run_points_in_processes

contains

    !> Points 1 .. npoints of the study `study_path` by `exe`, `jobs` at a
    !> time, with --force when `force` (a stale reference used all the
    !> same); `problems` gets a line per point that ended without its
    !> record (its exit status and log). status_signal when a signal
    !> stopped the sweep; an I/O error when an old record cannot be removed.
    subroutine run_points_in_processes(exe, study_path, npoints, folder, jobs, force, &
                                       problems, status)
        character(len=*), intent(in) :: exe, study_path, folder
        integer, intent(in) :: npoints, jobs
        logical, intent(in) :: force
        character(len=:), allocatable, intent(out) :: problems
        type(status_t), intent(out) :: status
        integer :: pids(max(jobs, 1)), points(max(jobs, 1))
        integer :: next, slot, code, signo, stopped_by, done
        logical :: forwarded
        type(status_t) :: start_status
        character(len=12) :: number
        character(len=:), allocatable :: args(:)

        problems = ''
        ! exe sweep STUDY --point K --quiet [--force]
        allocate (character(len=max(len(exe), len(study_path), 12)) :: args(merge(7, 6, force)))
        args(1:6) = [character(len=12) :: '', 'sweep', '', '--point', '', '--quiet']
        if (force) args(7) = '--force'
        args(1) = exe
        args(3) = study_path
        ! a record left from an earlier sweep must not stand for this one
        do next = 1, npoints
            if (.not. delete_file(record_path(folder, next))) then
                call status%set(status_io_error, record_path(folder, next) // &
                    ': cannot remove the record of an earlier sweep')
                return
            end if
        end do
        pids = 0
        points = 0
        next = 1
        done = 0
        stopped_by = 0
        forwarded = .false.
        do
            ! start points while there is room, none stopped and no signal
            do while (next <= npoints .and. stopped_by == 0 .and. caught_signal() == 0 &
                      .and. any(pids == 0))
                slot = findloc(pids, 0, dim=1)
                write (number, '(i0)') next
                args(5) = number
                call start_process(args, log_path(folder, next), pids(slot), start_status, &
                                   own_group=.true.)
                if (.not. start_status%ok()) then
                    problems = problems // 'point ' // int_text(next) // ': ' // &
                        start_status%text() // new_line('a')
                    pids(slot) = 0
                else
                    points(slot) = next
                end if
                next = next + 1
            end do
            if (all(pids == 0)) exit
            call wait_any_process(pids, -1, .not. forwarded, slot, code, signo)
            if (slot == wait_signal) then
                ! once to each running point: they stop after their step
                do slot = 1, size(pids)
                    if (pids(slot) > 0) call signal_process(pids(slot), caught_signal())
                end do
                forwarded = .true.
                cycle
            end if
            if (slot < 1) cycle
            if (signo == 0 .and. code > signal_exit_base) signo = code - signal_exit_base
            if (signo == signal_number('SIGINT') .or. signo == signal_number('SIGTERM')) then
                if (stopped_by == 0) stopped_by = signo
            else if (code /= 0 .or. signo /= 0) then
                problems = problems // 'point ' // int_text(points(slot)) // ': ' // &
                    ended(code, signo) // ', no record (see ' // log_path(folder, &
                    points(slot)) // ')' // new_line('a')
            end if
            done = done + 1
            pids(slot) = 0
        end do
        if (caught_signal() > 0) stopped_by = caught_signal()
        if (stopped_by > 0) call status%set(status_signal, study_path // ': stopped by ' // &
            signal_name(stopped_by) // ' after ' // int_text(done) // ' of ' // &
            int_text(npoints) // ' points had ended; their records are in ' // folder // &
            ' (''sweep --merge'' makes a table of them); no table written', stopped_by)
    end subroutine run_points_in_processes

    !> How a child ended: 'exit N' or 'killed by SIGNAME'.
    function ended(code, signo) result(text)
        integer, intent(in) :: code, signo
        character(len=:), allocatable :: text
        if (signo /= 0) then
            text = 'killed by ' // signal_name(signo)
        else
            text = 'exit ' // int_text(code)
        end if
    end function ended
end module flexmbs_app_parallel_sweep
