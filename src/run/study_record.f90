!> A grid point's record: what one run of a sweep gives the table, kept
!> as a file of the study's results folder (run/study_results) so that the
!> points can run in other processes, on other machines (a Slurm job
!> array) and at other times, and `sweep --merge` assembles the table.
!>
!> A record is text, one `key = value` a line after its heading line:
!>
!>   # flexmbs sweep record
!>   format = 1
!>   point = 3                   grid point, and its coordinates:
!>   solver = radau5, stabilisation = ggl, tolerance = ..., pmax = 2,
!>   derivatives = analytic      (each on its own line)
!>   study_sha256 = ...          SHA-256 of the study file's text, the
!>   scene_sha256 = ...          scene file's, the mesh file's ('-' when the
!>   mesh_sha256 = -             scene names none): a record is used only
!>                               while all three are those of the files now
!>   outcome = ok                or failed
!>   reason = ...                why it failed ('' when ok)
!>   label = radau5, stab = ggl  the table row's solver and stab. columns
!>   err = ...                   ERR (-1: not measured)
!>   t_reached, nst, nac, nrj, nfe, nfe_jac, nje, ndec, nsol, nprj, cpu,
!>   wall, h_last = ...          the statistics (each on its own line)
!>   nrj_error_test, ... = ...   NRJ by cause (dae_stats_t%rejections,
!>   refusal = ...               cause_keys) and the last refusal's reason
!>   summary = ...               the sweep's line for the run
!>
!> Reals are written with 17 significant digits, so they read back to the
!> bit and a merged table equals the serial sweep's. The file is written
!> whole or not at all (core/files write_file_atomically).
module flexmbs_run_study_record
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_text, only: int_text
    use flexmbs_core_files, only: read_text_file, write_file_atomically
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_io_namelist, only: study_input_t, scene_input_t
    use flexmbs_io_table, only: stats_row_t
    use flexmbs_dae_rejections, only: cause_count, cause_keys
    use flexmbs_run_study_grid, only: sweep_point_t
    implicit none
    private

    !> One run of a sweep: its table row, a line for the log, and for a
    !> failed run the reason.
    type, public :: sweep_run_t
        type(stats_row_t) :: row
        logical :: ok = .false.
        character(len=:), allocatable :: summary
        character(len=:), allocatable :: reason
    end type sweep_run_t

    !> What a record was computed from: SHA-256 of the study file's text,
    !> the scene file's and the mesh file's ('-' when none).
    type, public :: fingerprint_t
        character(len=64) :: study = '', scene = '', mesh = '-'
    end type fingerprint_t

    !> What read_record found.
    integer, parameter, public :: record_missing = 0, record_current = 1, record_stale = 2, &
        record_damaged = 3

    character(len=*), parameter :: heading = '# flexmbs sweep record'
    !> Format 2, with NRJ by cause (a format-1 record is damaged: the point runs again)
    character(len=*), parameter :: record_format = '2'
    character, parameter :: nl = new_line('a')

    !> One `key = value` line of a record (or of a reference's fingerprint).
    type, public :: pair_t
        character(len=:), allocatable :: key, value
    end type pair_t

    public :: study_fingerprint, mesh_digest, record_text, write_record, read_record, &
        split_pairs, pair_value

contains

    !> The fingerprint of a study as it is now (`base`: its scene, read).
    subroutine study_fingerprint(study, base, print, status)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(in) :: base
        type(fingerprint_t), intent(out) :: print
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text
        call read_text_file(study%path, text, status)
        if (.not. status%ok()) return
        print%study = sha256_hex(text)
        print%scene = sha256_hex(base%text)
        call mesh_digest(base, print%mesh, status)
    end subroutine study_fingerprint

    !> SHA-256 of the texts of the scene's mesh files one after the other
    !> (one file: its hash alone); '-' when the scene names none.
    subroutine mesh_digest(base, digest, status)
        type(scene_input_t), intent(in) :: base
        character(len=64), intent(out) :: digest
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: text, meshes
        integer :: b
        digest = '-'
        meshes = ''
        do b = 1, size(base%bodies)
            if (len_trim(base%bodies(b)%mesh_file) == 0) cycle
            call read_text_file(trim(base%bodies(b)%mesh_file), text, status)
            if (.not. status%ok()) return
            meshes = meshes // text
        end do
        if (any(len_trim(base%bodies%mesh_file) > 0)) digest = sha256_hex(meshes)
    end subroutine mesh_digest

    !> The record of grid point k (module header).
    function record_text(k, point, print, run) result(text)
        integer, intent(in) :: k
        type(sweep_point_t), intent(in) :: point
        type(fingerprint_t), intent(in) :: print
        type(sweep_run_t), intent(in) :: run
        character(len=:), allocatable :: text
        character(len=:), allocatable :: reason, causes
        integer :: counts(cause_count), c
        reason = ''
        if (allocated(run%reason)) reason = run%reason
        counts = run%row%stats%rejections%counts_by_cause()
        causes = ''
        do c = 1, cause_count
            causes = causes // line('nrj_' // trim(cause_keys(c)), int_text(counts(c)))
        end do
        associate (st => run%row%stats)
            text = heading // nl // line('format', record_format) // &
                line('point', int_text(k)) // line('solver', trim(point%solver)) // &
                line('stabilisation', trim(point%stab)) // line('tolerance', exact(point%tol)) &
                // line('pmax', int_text(point%pmax)) // &
                line('derivatives', trim(point%source)) // &
                line('study_sha256', print%study) // line('scene_sha256', print%scene) // &
                line('mesh_sha256', trim(print%mesh)) // &
                line('outcome', merge('ok    ', 'failed', run%ok)) // &
                line('reason', one_line(reason)) // line('label', run%row%solver) // &
                line('stab', run%row%stab) // line('err', exact(run%row%err)) // &
                line('t_reached', exact(st%t_reached)) // line('nst', int_text(st%nst)) // &
                line('nac', int_text(st%nac)) // line('nrj', int_text(st%nrj)) // &
                line('nfe', int_text(st%nfe)) // line('nfe_jac', int_text(st%nfe_jac)) // &
                line('nje', int_text(st%nje)) // line('ndec', int_text(st%ndec)) // &
                line('nsol', int_text(st%nsol)) // line('nprj', int_text(st%nprj)) // &
                line('cpu', exact(st%cpu)) // line('wall', exact(st%wall)) // &
                line('h_last', exact(st%h_last)) // causes // &
                line('refusal', one_line(st%rejections%refusal_reason())) // &
                line('summary', one_line(run%summary))
        end associate
    end function record_text

    !> Point k's record into the file `path`, whole or not at all.
    subroutine write_record(path, k, point, print, run, status)
        character(len=*), intent(in) :: path
        integer, intent(in) :: k
        type(sweep_point_t), intent(in) :: point
        type(fingerprint_t), intent(in) :: print
        type(sweep_run_t), intent(in) :: run
        type(status_t), intent(out) :: status
        call write_file_atomically(path, record_text(k, point, print, run), status)
    end subroutine write_record

    !> The record of point k in the file `path`, checked against the point
    !> and the fingerprint of the study now: `state` is record_missing (no
    !> file), record_current (`run` read), record_stale (from another study
    !> text, or another grid point) or record_damaged; `note` says why for
    !> the last two.
    subroutine read_record(path, k, point, print, run, state, note)
        character(len=*), intent(in) :: path
        integer, intent(in) :: k
        type(sweep_point_t), intent(in) :: point
        type(fingerprint_t), intent(in) :: print
        type(sweep_run_t), intent(out) :: run
        integer, intent(out) :: state
        character(len=:), allocatable, intent(out) :: note
        type(pair_t), allocatable :: pairs(:)
        type(status_t) :: status
        character(len=:), allocatable :: text, changed, numbers
        logical :: exists
        integer :: ios, c, counts(cause_count)
        note = ''
        state = record_missing
        inquire (file=path, exist=exists)
        if (.not. exists) return
        state = record_damaged
        call read_text_file(path, text, status)
        if (.not. status%ok()) then
            note = status%text()
            return
        end if
        if (index(text, heading // nl) /= 1) then
            note = path // ': not a flexmbs sweep record'
            return
        end if
        call split_pairs(text(len(heading) + 2:), pairs)
        if (value_of('format') /= record_format .or. value_of('point') /= int_text(k)) then
            note = path // ': format ''' // value_of('format') // ''' or point ''' // &
                value_of('point') // ''' is not format ' // record_format // ', point ' // &
                int_text(k)
            return
        end if
        changed = ''
        if (value_of('study_sha256') /= print%study) changed = changed // ', the study file'
        if (value_of('scene_sha256') /= print%scene) changed = changed // ', the scene file'
        if (value_of('mesh_sha256') /= trim(print%mesh)) changed = changed // ', the mesh file'
        if (len(changed) > 0) then
            state = record_stale
            note = 'computed from another text of ' // changed(3:)
            return
        end if
        if (value_of('solver') /= trim(point%solver) .or. value_of('stabilisation') /= &
            trim(point%stab) .or. value_of('tolerance') /= exact(point%tol) .or. &
            value_of('pmax') /= int_text(point%pmax) .or. &
            value_of('derivatives') /= trim(point%source)) then
            state = record_stale
            note = 'computed for another grid point'
            return
        end if
        run%ok = value_of('outcome') == 'ok'
        run%reason = value_of('reason')
        run%row%solver = value_of('label')
        run%row%stab = value_of('stab')
        run%summary = value_of('summary')
        run%row%tol = point%tol
        numbers = value_of('err') // ' ' // value_of('t_reached') // ' ' // value_of('nst') &
            // ' ' // value_of('nac') // ' ' // value_of('nrj') // ' ' // value_of('nfe') // &
            ' ' // value_of('nfe_jac') // ' ' // value_of('nje') // ' ' // value_of('ndec') // &
            ' ' // value_of('nsol') // ' ' // value_of('nprj') // ' ' // value_of('cpu') // &
            ' ' // value_of('wall') // ' ' // value_of('h_last')
        do c = 1, cause_count
            numbers = numbers // ' ' // value_of('nrj_' // trim(cause_keys(c)))
        end do
        associate (st => run%row%stats)
            read (numbers, *, iostat=ios) run%row%err, st%t_reached, &
                st%nst, st%nac, st%nrj, st%nfe, st%nfe_jac, st%nje, st%ndec, st%nsol, &
                st%nprj, st%cpu, st%wall, st%h_last, counts
            if (ios == 0) call st%rejections%restore(counts, value_of('refusal'))
        end associate
        if (ios /= 0 .or. all(value_of('outcome') /= ['ok    ', 'failed'])) then
            note = path // ': a number or the outcome is missing or unreadable'
            return
        end if
        state = record_current

    contains

        !> The value of `key`, '' when the record lacks it.
        function value_of(key) result(value)
            character(len=*), intent(in) :: key
            character(len=:), allocatable :: value
            value = pair_value(pairs, key)
        end function value_of
    end subroutine read_record

    !> The value of `key` among `pairs` (the first one), '' when none has it.
    function pair_value(pairs, key) result(value)
        type(pair_t), intent(in) :: pairs(:)
        character(len=*), intent(in) :: key
        character(len=:), allocatable :: value
        integer :: i
        value = ''
        do i = 1, size(pairs)
            if (pairs(i)%key == key) then
                value = pairs(i)%value
                return
            end if
        end do
    end function pair_value

    !> The `key = value` lines of a text (others are left out).
    subroutine split_pairs(text, pairs)
        character(len=*), intent(in) :: text
        type(pair_t), allocatable, intent(out) :: pairs(:)
        integer :: pass, n, start, end, eq
        ! two passes, counting first: no array grown element by element
        do pass = 1, 2
            n = 0
            start = 1
            do while (start <= len(text))
                end = index(text(start:), nl)
                end = merge(len(text) + 1, start + end - 1, end == 0)
                eq = index(text(start:end - 1), ' = ')
                if (eq > 0) then
                    n = n + 1
                    if (pass == 2) then
                        pairs(n)%key = text(start:start + eq - 2)
                        pairs(n)%value = text(start + eq + 2:end - 1)
                    end if
                end if
                start = end + 1
            end do
            if (pass == 1) allocate (pairs(n))
        end do
    end subroutine split_pairs

    pure function line(key, value) result(text)
        character(len=*), intent(in) :: key, value
        character(len=:), allocatable :: text
        text = key // ' = ' // trim(value) // nl
    end function line

    !> x with 17 significant digits: it reads back to the same bits.
    pure function exact(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf
        write (buf, '(es25.16e3)') x
        text = trim(adjustl(buf))
    end function exact

    !> A text on one line: its line ends as ' / '.
    pure function one_line(text) result(flat)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: flat
        integer :: i
        flat = ''
        do i = 1, len(text)
            if (text(i:i) == nl) then
                flat = flat // ' / '
            else if (iachar(text(i:i)) < 32) then
                flat = flat // ' '
            else
                flat = flat // text(i:i)
            end if
        end do
    end function one_line
end module flexmbs_run_study_record
