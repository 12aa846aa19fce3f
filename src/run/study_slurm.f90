!> A study on a Slurm cluster (`flexmbs sweep STUDY --slurm`): a job-array
!> script whose tasks run the grid's points (`flexmbs sweep STUDY --point
!> K`, each writing its record into the results folder), and a merge job
!> script that assembles the table (`flexmbs sweep STUDY --merge`), both
!> written into the results folder (run/study_results) with absolute
!> paths, so that they run from any folder. Task I of the array runs the
!> points I .. I + K - 1 (run/study_grid); the script's first argument
!> overrides K, so that `sbatch --array=2,5 array.sbatch 1` runs points 2
!> and 5 alone (what `--merge` prints for the missing ones).
!>
!> A task asks for SIGTERM `warning_seconds` before its time limit, to its
!> batch shell, which passes it on to the running point: the point stops
!> after its step with its checkpoint (run/study point_K.h5), the shell
!> requeues the task, and the task, run again, skips the points whose
!> records its first run wrote and resumes the stopped one.
module flexmbs_run_study_slurm
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_version, only: written_by
    use flexmbs_core_files, only: write_file_atomically, absolute_path
    use flexmbs_io_namelist, only: study_input_t
    use flexmbs_run_study_grid, only: array_spec
    use flexmbs_run_study_results, only: array_script_path, merge_script_path
    implicit none
    private

    !> `--chunk`, `--partition`, `--time`, `--mem` ('' = not given: the
    !> cluster's default); `force`: the tasks and the merge job run with
    !> --force (a stale reference used all the same, run/reference_fingerprint).
    type, public :: slurm_options_t
        integer :: chunk = 1
        character(len=:), allocatable :: partition, time, mem
        logical :: force = .false.
    end type slurm_options_t

    public :: check_slurm_options, slurm_time_valid, array_script_text, merge_script_text, &
        write_slurm_scripts, shell_word

    character, parameter :: nl = new_line('a')
    !> Seconds before its time limit at which a task gets the warning signal
    !> (Slurm sends it within about a minute of the time asked): enough for
    !> the running point to finish its step and write its checkpoint.
    integer, parameter :: warning_seconds = 120

contains

    !> Every option's value as Slurm takes it; bad input naming the option,
    !> its value and what it must be otherwise (the first found).
    subroutine check_slurm_options(options, status)
        type(slurm_options_t), intent(in) :: options
        type(status_t), intent(out) :: status
        if (options%chunk < 1) then
            call status%set(status_bad_input, '--chunk ' // int_text(options%chunk) // &
                ': needs a whole number >= 1 (grid points per array task)')
        else if (.not. plain_word(text_of(options%partition), '_-.,')) then
            call status%set(status_bad_input, '--partition ''' // text_of(options%partition) &
                // ''': needs a partition name (letters, digits, ''_'', ''-'', ''.''; ' // &
                'several separated by '','')')
        else if (.not. slurm_time_valid(text_of(options%time))) then
            call status%set(status_bad_input, '--time ''' // text_of(options%time) // &
                ''': needs a Slurm time limit: minutes, minutes:seconds, ' // &
                'hours:minutes:seconds, days-hours, days-hours:minutes or ' // &
                'days-hours:minutes:seconds')
        else if (.not. memory_valid(text_of(options%mem))) then
            call status%set(status_bad_input, '--mem ''' // text_of(options%mem) // &
                ''': needs a whole number with an optional unit K, M, G or T (M when none)')
        end if
    end subroutine check_slurm_options

    !> Whether `time` is a time limit sbatch takes (`--time`): M, M:S,
    !> H:M:S, D-H, D-H:M, D-H:M:S (whole numbers; every field after the
    !> first below 60, hours after days below 24) or UNLIMITED; '' (not
    !> given) too.
    pure logical function slurm_time_valid(time) result(valid)
        character(len=*), intent(in) :: time
        character(len=:), allocatable :: clock
        integer :: dash, fields, i, start, value
        valid = len(time) == 0 .or. time == 'UNLIMITED' .or. time == 'INFINITE'
        if (valid) return
        dash = index(time, '-')
        if (dash > 0) then
            if (.not. digits_only(time(1:dash - 1))) return
        end if
        clock = time(dash + 1:)
        fields = 0
        start = 1
        do i = 1, len(clock) + 1
            if (i <= len(clock)) then
                if (clock(i:i) /= ':') cycle
            end if
            fields = fields + 1
            if (fields > 3 .or. .not. digits_only(clock(start:i - 1)) .or. i - start > 9) return
            read (clock(start:i - 1), *) value
            ! minutes and seconds after the first field; hours after days
            if (fields > 1 .and. value >= 60) return
            if (fields == 1 .and. dash > 0 .and. value >= 24) return
            start = i + 1
        end do
        valid = .true.
    end function slurm_time_valid

    !> The job-array script (module header) for `npoints` points of the
    !> study at the absolute path `study_path`, run by `exe`, records and
    !> Slurm's output into `folder` (absolute).
    function array_script_text(exe, study_path, folder, npoints, options, name) result(text)
        character(len=*), intent(in) :: exe, study_path, folder, name
        integer, intent(in) :: npoints
        type(slurm_options_t), intent(in) :: options
        character(len=:), allocatable :: text
        text = '#!/bin/bash' // nl // &
            '# ' // written_by // ': the job array of the study' // nl // &
            '#   ' // study_path // nl // &
            '# (`flexmbs sweep STUDY --slurm`). Task I runs grid points I .. I+K-1 of ' // &
            int_text(npoints) // ', K = ' // int_text(options%chunk) // nl // &
            '# or the first argument: `sbatch --array=2,5 array.sbatch 1` runs points 2 ' // &
            'and 5 alone.' // nl // &
            '# Each point writes its record into this folder; `flexmbs sweep STUDY ' // &
            '--merge` makes the table.' // nl // &
            '#SBATCH --job-name=' // name // nl // &
            '#SBATCH --array=' // array_spec(npoints, options%chunk) // nl // &
            '#SBATCH --output=' // folder // '/slurm_%A_%a.out' // nl // &
            '# the warning before the time limit (the batch shell passes it on):' // nl // &
            '# the running point stops after its step, keeping its checkpoint, and' // nl // &
            '# the task is requeued and resumes it' // nl // &
            '#SBATCH --signal=B:TERM@' // int_text(warning_seconds) // nl // &
            '#SBATCH --requeue' // nl // &
            '#SBATCH --open-mode=append' // nl // &
            sbatch_options(options) // &
            'set -u' // nl // &
            'exe=' // shell_quoted(exe) // nl // &
            'study=' // shell_quoted(study_path) // nl // &
            'points=' // int_text(npoints) // nl // &
            'chunk=${1:-' // int_text(options%chunk) // '}' // nl // &
            'first=${SLURM_ARRAY_TASK_ID:?submit this script with sbatch: it is a job array}' &
            // nl // &
            'last=$((first + chunk - 1))' // nl // &
            '[ "$last" -gt "$points" ] && last=$points' // nl // &
            '# one CPU per task: no threads in the linear algebra' // nl // &
            'export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1' // nl // &
            'status=0' // nl // &
            'child=""' // nl // &
            'trap ''[ -n "$child" ] && kill -TERM "$child" 2>/dev/null'' TERM INT' // nl // &
            'for ((k = first; k <= last; k++)); do' // nl // &
            '    # a requeued task keeps the points it finished before' // nl // &
            '    [ "${SLURM_RESTART_COUNT:-0}" -gt 0 ] && [ -f ' // &
            shell_quoted(folder) // '"/point_$k.rec" ] && continue' // nl // &
            '    "$exe" sweep "$study" --point "$k" --quiet' // forced(options) // ' &' // nl // &
            '    child=$!' // nl // &
            '    point=0' // nl // &
            '    wait "$child" || point=$?' // nl // &
            '    # the trap ends `wait` early: wait for the point to stop' // nl // &
            '    while kill -0 "$child" 2>/dev/null; do point=0; wait "$child" || point=$?; done' &
            // nl // &
            '    child=""' // nl // &
            '    [ "$point" -ne 0 ] && status=$point' // nl // &
            '    # stopped by the warning or scancel --signal=TERM (the task still' // nl // &
            '    # running, not cancelled): again later, from the checkpoint (requeue' // nl // &
            '    # ends this run of the task)' // nl // &
            '    task="${SLURM_ARRAY_JOB_ID:-}_${SLURM_ARRAY_TASK_ID}"' // nl // &
            '    if [ "$point" -eq 143 ] && [ -n "${SLURM_ARRAY_JOB_ID:-}" ] &&' // nl // &
            '        [ "$(squeue -h -j "$task" -o %T 2>/dev/null)" = RUNNING ]; then' // nl // &
            '        scontrol requeue "$task" && exit 0' // nl // &
            '    fi' // nl // &
            '    # stopped by another signal: no further point' // nl // &
            '    [ "$point" -gt 128 ] && exit "$point"' // nl // &
            'done' // nl // &
            'exit "$status"' // nl
    end function array_script_text

    !> The merge job's script: `exe sweep STUDY --merge`, its output into
    !> `folder`.
    function merge_script_text(exe, study_path, folder, options, name) result(text)
        character(len=*), intent(in) :: exe, study_path, folder, name
        type(slurm_options_t), intent(in) :: options
        character(len=:), allocatable :: text
        text = '#!/bin/bash' // nl // &
            '# ' // written_by // ': the merge job of the study' // nl // &
            '#   ' // study_path // nl // &
            '# (`flexmbs sweep STUDY --slurm`), submitted to run once the array has ' // &
            'ended:' // nl // &
            '#   sbatch --dependency=afterany:ARRAY_JOB_ID merge.sbatch' // nl // &
            '#SBATCH --job-name=' // name // '-merge' // nl // &
            '#SBATCH --output=' // folder // '/slurm_merge_%j.out' // nl // &
            sbatch_options(options) // &
            'exec ' // shell_quoted(exe) // ' sweep ' // shell_quoted(study_path) // &
            ' --merge' // forced(options) // nl
    end function merge_script_text

    !> Both scripts into the results folder `folder` (which exists) for a
    !> study of `npoints` points run by `exe` (absolute): `array` and
    !> `merge`, their paths.
    subroutine write_slurm_scripts(study, exe, folder, npoints, options, array, merge, status)
        type(study_input_t), intent(in) :: study
        character(len=*), intent(in) :: exe, folder
        integer, intent(in) :: npoints
        type(slurm_options_t), intent(in) :: options
        character(len=:), allocatable, intent(out) :: array, merge
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: study_path, where, name
        integer :: slash
        study_path = absolute_path(study%path)
        where = absolute_path(folder)
        if (len(study_path) == 0 .or. len(where) == 0) then
            call status%set(status_io_error, study%path // ': cannot find its absolute path')
            return
        end if
        slash = index(study_path, '/', back=.true.)
        name = 'flexmbs-' // job_name(study_path(slash + 1:))
        array = array_script_path(where)
        merge = merge_script_path(where)
        call write_file_atomically(array, array_script_text(exe, study_path, where, npoints, &
                                                            options, name), status)
        if (status%ok()) call write_file_atomically(merge, merge_script_text(exe, study_path, &
                                                    where, options, name), status)
    end subroutine write_slurm_scripts

    !> ' --force' when the scripts pass it on, else ''.
    pure function forced(options) result(text)
        type(slurm_options_t), intent(in) :: options
        character(len=:), allocatable :: text
        text = merge(' --force', '        ', options%force)
        text = trim(text)
    end function forced

    !> The #SBATCH lines of the options given, and one CPU per task.
    function sbatch_options(options) result(text)
        type(slurm_options_t), intent(in) :: options
        character(len=:), allocatable :: text
        text = '#SBATCH --cpus-per-task=1' // nl
        if (len(text_of(options%partition)) > 0) &
            text = text // '#SBATCH --partition=' // options%partition // nl
        if (len(text_of(options%time)) > 0) text = text // '#SBATCH --time=' // options%time // nl
        if (len(text_of(options%mem)) > 0) text = text // '#SBATCH --mem=' // options%mem // nl
    end function sbatch_options

    !> `text` as one word of a shell command line: as it is when made of
    !> letters, digits and /._-+=:,@ only, else shell_quoted.
    pure function shell_word(text) result(word)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: word
        if (len(text) > 0 .and. plain_word(text, '/._-+=:,@')) then
            word = text
        else
            word = shell_quoted(text)
        end if
    end function shell_word

    !> `text` as one word of a shell command line: in single quotes, each
    !> of its own single quotes as '\''.
    pure function shell_quoted(text) result(quoted)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: quoted
        integer :: i
        quoted = ''''
        do i = 1, len(text)
            if (text(i:i) == '''') then
                quoted = quoted // '''\'''''
            else
                quoted = quoted // text(i:i)
            end if
        end do
        quoted = quoted // ''''
    end function shell_quoted

    !> A study file's name as a job name: without its extension, anything
    !> but letters, digits, '_', '-' and '.' as '_'.
    pure function job_name(file) result(name)
        character(len=*), intent(in) :: file
        character(len=:), allocatable :: name
        integer :: i, dot
        dot = index(file, '.', back=.true.)
        name = file
        if (dot > 1) name = file(1:dot - 1)
        do i = 1, len(name)
            if (.not. plain_word(name(i:i), '_-.')) name(i:i) = '_'
        end do
    end function job_name

    !> Letters, digits and the characters of `others` only ('' is plain).
    pure logical function plain_word(text, others)
        character(len=*), intent(in) :: text, others
        integer :: i
        plain_word = .true.
        do i = 1, len(text)
            plain_word = plain_word .and. (scan(text(i:i), others) > 0 .or. &
                (text(i:i) >= 'a' .and. text(i:i) <= 'z') .or. &
                (text(i:i) >= 'A' .and. text(i:i) <= 'Z') .or. &
                (text(i:i) >= '0' .and. text(i:i) <= '9'))
        end do
    end function plain_word

    !> A size for --mem: digits, then optionally one of K, M, G, T.
    pure logical function memory_valid(mem)
        character(len=*), intent(in) :: mem
        integer :: n
        n = len(mem)
        memory_valid = n == 0
        if (n == 0) return
        if (scan(mem(n:n), 'KMGTkmgt') > 0) n = n - 1
        memory_valid = n > 0 .and. digits_only(mem(1:n))
    end function memory_valid

    pure logical function digits_only(text)
        character(len=*), intent(in) :: text
        digits_only = len(text) > 0 .and. verify(text, '0123456789') == 0
    end function digits_only

    !> An optional text's value, '' when not allocated.
    pure function text_of(text) result(value)
        character(len=:), allocatable, intent(in) :: text
        character(len=:), allocatable :: value
        value = ''
        if (allocated(text)) value = text
    end function text_of
end module flexmbs_run_study_slurm
