!> `flexmbs sweep STUDY --slurm --submit`: the job array with `sbatch
!> --parsable`, then the merge job with `--dependency=afterany:<array
!> job>`, so that it runs once every task has ended, however it ended.
!> sbatch runs as a child process (core/processes, no shell); its output
!> goes through files of the results folder, removed afterwards.
module flexmbs_app_slurm_submit
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_signals, only: signal_name
    use flexmbs_core_text, only: int_text
    use flexmbs_core_files, only: read_text_file, delete_file
    use flexmbs_core_processes, only: start_process, wait_any_process
    implicit none
    private

    public :: submit_study

contains

    !> Submit the scripts `array` and `merge` (absolute paths); their job
    !> ids. `folder` holds sbatch's output meanwhile.
    subroutine submit_study(array, merge, folder, array_id, merge_id, status)
        character(len=*), intent(in) :: array, merge, folder
        character(len=:), allocatable, intent(out) :: array_id, merge_id
        type(status_t), intent(out) :: status
        call sbatch(['--parsable'], array, folder, array_id, status)
        if (.not. status%ok()) return
        call sbatch([character(len=64) :: '--parsable', '--dependency=afterany:' // array_id], &
                    merge, folder, merge_id, status)
        if (.not. status%ok()) call status%set(status_io_error, status%text() // &
            ' (the array, job ' // array_id // ', is submitted: cancel it with scancel ' // &
            array_id // ', or submit the merge job yourself)')
    end subroutine submit_study

    !> `sbatch OPTIONS SCRIPT`: the job id it answers (before a ';cluster').
    subroutine sbatch(options, script, folder, id, status)
        character(len=*), intent(in) :: options(:), script, folder
        character(len=:), allocatable, intent(out) :: id
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: out, err, answer, complaint, args(:)
        type(status_t) :: read_status
        integer :: pid, index, code, signo, width, i, end
        logical :: gone
        out = folder // '/.sbatch.out'
        err = folder // '/.sbatch.err'
        id = ''
        width = max(len(script), len(options), 6)
        allocate (character(len=width) :: args(size(options) + 2))
        args(1) = 'sbatch'
        do i = 1, size(options)
            args(i + 1) = options(i)
        end do
        args(size(args)) = script
        call start_process(args, out, pid, status, errors=err)
        if (.not. status%ok()) then
            call status%set(status_io_error, status%text() // ' (is Slurm''s sbatch on PATH?)')
            return
        end if
        call wait_any_process([pid], -1, .false., index, code, signo)
        call read_text_file(out, answer, read_status)
        if (.not. read_status%ok()) answer = ''
        call read_text_file(err, complaint, read_status)
        if (.not. read_status%ok()) complaint = ''
        ! a file left behind (a folder made read-only meanwhile) does no harm
        gone = delete_file(out) .and. delete_file(err)
        end = scan(answer, ';' // new_line('a'))
        if (end == 0) end = len(answer) + 1
        id = answer(1:end - 1)
        if (code /= 0 .or. signo /= 0 .or. len(id) == 0 .or. verify(id, '0123456789') /= 0) &
            then
            if (signo /= 0) then
                call status%set(status_io_error, 'sbatch ' // script // ' failed (killed by ' &
                    // signal_name(signo) // '): ' // trim(complaint // answer))
            else
                call status%set(status_io_error, 'sbatch ' // script // ' failed (exit ' // &
                    int_text(code) // '): ' // trim(complaint // answer))
            end if
            id = ''
        end if
    end subroutine sbatch
end module flexmbs_app_slurm_submit
