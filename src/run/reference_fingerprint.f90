!> What a study's reference was made from, kept in the reference file, so
!> that a sweep measures its runs only against the reference of the study
!> as it is now (`flexmbs reference` writes it, every kind of `flexmbs
!> sweep` checks it).
!>
!> The fingerprint is the SHA-256 of its parts, `key = value` lines:
!>
!>   format = 1
!>   scene = SHA-256 of the scene's settings (io/scene_settings: every
!>           variable given or by default; the solver's name, rtol and atol,
!>           t_start, t_end and &output left out: the study sets them, or
!>           they are parts of their own)
!>   mesh = SHA-256 of the mesh files' texts, as a point's record has it
!>          (run/study_record mesh_digest), '-' when none
!>   t_start = ..., t_end = ...          the run's interval (the study's t_end)
!>   output_times = N from A to B, sha256 ...  (', and every step' with every_step)
!>   reference_solver = radau5, reference_tolerance = 1E-10
!>
!> The cross-check (check_solver, check_tolerance) is not a part: it
!> validates the reference and does not change a number of it, so studies
!> that share a reference may check it differently. Reals are written
!> with as few digits as read back to their bits (core/text exact_text).
!>
!> The file holds the fingerprint (attribute `reference_fingerprint`), its
!> parts (`reference_fingerprint_parts`) and the scene's settings
!> (`reference_scene_settings`), so that a mismatch names what differs,
!> down to the scene's variable.
module flexmbs_run_reference_fingerprint
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: exact_text, int_text
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_io_namelist, only: study_input_t, scene_input_t, scene_dae_options
    use flexmbs_io_scene_settings, only: scene_settings
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_io_hdf5_text, only: read_stored_text
    use flexmbs_run_study_record, only: mesh_digest, pair_t, split_pairs, pair_value
    use flexmbs_run_study_slurm, only: shell_word
    implicit none
    private

    !> A reference's fingerprint (module header).
    type, public :: reference_print_t
        character(len=:), allocatable :: settings  !! the scene's settings text
        character(len=:), allocatable :: parts     !! the `key = value` lines hashed
        character(len=64) :: digest = ''           !! SHA-256 of `parts`
    end type reference_print_t

    public :: reference_print, write_reference_print, check_reference_print, &
        check_reference_times, remake_command, same_times, setting_changes

    !> What the scene's settings leave out (io/scene_settings `omit`).
    character(len=*), parameter :: omitted(*) = [character(len=24) :: 'solver/name', &
        'solver/rtol', 'solver/atol', 'simulation/t_start', 'simulation/t_end', 'output/*']
    !> The parts, in their order, and how a message names each.
    character(len=*), parameter :: keys(*) = [character(len=19) :: 'format', 'scene', &
        'mesh', 't_start', 't_end', 'output_times', 'reference_solver', 'reference_tolerance']
    character(len=*), parameter :: names(*) = [character(len=36) :: 'fingerprint format', &
        'the scene text', 'the mesh file', 't_start', 't_end', &
        'the output times', 'reference_solver', 'reference_tolerance']
    !> Relative difference below which two output times are the same time.
    real(wp), parameter :: time_match = 1.0e-12_wp
    character, parameter :: nl = new_line('a')

contains

    !> The fingerprint of the reference that `flexmbs reference` would make
    !> of the study now; `base` is the study's scene (read_study_scene, not
    !> the sweep's step limit).
    subroutine reference_print(study, base, print, status)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(in) :: base
        type(reference_print_t), intent(out) :: print
        type(status_t), intent(out) :: status
        character(len=64) :: mesh
        call mesh_digest(base, mesh, status)
        if (.not. status%ok()) return
        print%settings = scene_settings(base%text, omitted)
        print%parts = line('format', '1') // line('scene', sha256_hex(print%settings)) // &
            line('mesh', trim(mesh)) // line('t_start', exact_text(base%t_start)) // &
            line('t_end', exact_text(base%t_end)) // &
            line('output_times', times_text(output_times(base), base%every_step)) // &
            line('reference_solver', trim(study%reference_solver)) // &
            line('reference_tolerance', exact_text(study%reference_tolerance))
        print%digest = sha256_hex(print%parts)
    end subroutine reference_print

    !> The fingerprint into the reference file being written (module header).
    subroutine write_reference_print(h5, print, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(reference_print_t), intent(in) :: print
        type(status_t), intent(out) :: status
        call h5%write_text('reference_fingerprint', print%digest, status)
        if (status%ok()) call h5%write_text('reference_fingerprint_parts', print%parts, status)
        if (status%ok()) call h5%write_text('reference_scene_settings', print%settings, status)
    end subroutine write_reference_print

    !> Whether the study's reference file was made from the study as it is
    !> now (`now`: reference_print's): bad input naming what differs and the
    !> command that remakes it when not, and when the file has no
    !> fingerprint (an older flexmbs wrote it); with `force` the file is
    !> used all the same and `stale` says so, for the table ('' when the
    !> reference is current).
    subroutine check_reference_print(study, now, force, stale, status)
        type(study_input_t), intent(in) :: study
        type(reference_print_t), intent(in) :: now
        logical, intent(in) :: force
        character(len=:), allocatable, intent(out) :: stale
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: digest, parts, settings, why, path
        logical :: exists
        path = study%reference_file
        stale = ''
        inquire (file=path, exist=exists)
        if (.not. exists) then
            call status%set(status_bad_input, path // ': no reference file (make it with ' // &
                remake_command(study) // ' first)')
            return
        end if
        call read_print(path, digest, parts, settings, status)
        if (.not. status%ok()) return
        if (digest == now%digest) return
        if (len(digest) == 0) then
            why = 'has no fingerprint: it predates reference fingerprints (an older flexmbs &
                &wrote it), so whether it belongs to this study cannot be told'
            stale = 'predates reference fingerprints'
        else
            why = 'was not made from the study as it is now; what differs: ' // &
                differences(parts, settings, now)
            stale = 'it differs in ' // changed_parts(parts, now)
        end if
        if (force) then
            stale = 'note: the reference ' // path // ' is stale (' // stale // '), used as &
                &it is (--force)'
            return
        end if
        call status%set(status_bad_input, study%path // ': the reference ' // path // ' ' // &
            why // nl // 'remake it: ' // remake_command(study) // ' (or use it as it is: --force)')
    end subroutine check_reference_print

    !> The reference's /time (`t_ref`) against the scene's output times now:
    !> bad input when they differ, even with --force (ERR compares the two
    !> at the same times). A scene that records every step has no times
    !> known before its run: each run's are compared then.
    subroutine check_reference_times(study, base, t_ref, status)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(in) :: base
        real(wp), intent(in) :: t_ref(:)
        type(status_t), intent(out) :: status
        real(wp), allocatable :: times(:)
        if (base%every_step) return
        times = output_times(base)
        if (same_times(times, t_ref)) return
        call status%set(status_bad_input, study%path // ': the output times of the scene (' // &
            times_text(times, .false., .false.) // ') are not those of the reference ' // &
            study%reference_file // ' (' // times_text(t_ref, .false., .false.) // &
            '): ERR compares the runs with it at the same times' // nl // 'remake it: ' // &
            remake_command(study))
    end subroutine check_reference_times

    !> Whether two series of output times are one: the same number, each
    !> within `time_match` relative to the largest time (its rounding, when
    !> made by another build or read back from a file).
    pure logical function same_times(a, b)
        real(wp), intent(in) :: a(:), b(:)
        same_times = size(a) == size(b)
        if (.not. same_times .or. size(b) == 0) return
        same_times = .not. any(abs(a - b) > time_match * max(1.0_wp, maxval(abs(b))))
    end function same_times

    !> The fingerprint, its parts and the scene's settings that the file
    !> `path` holds ('' each when it has none).
    subroutine read_print(path, digest, parts, settings, status)
        character(len=*), intent(in) :: path
        character(len=:), allocatable, intent(out) :: digest, parts, settings
        type(status_t), intent(out) :: status
        integer(hid_t) :: file
        integer :: err
        digest = ''
        parts = ''
        settings = ''
        call h5open_f(err)
        ! a file that is not HDF5 is said here, not by HDF5's error stack
        call h5eset_auto_f(0, err)
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0) then
            call status%set(status_bad_input, path // ': the reference is not an HDF5 file')
            return
        end if
        call read_stored_text(file, 'reference_fingerprint', digest, err)
        if (err >= 0) call read_stored_text(file, 'reference_fingerprint_parts', parts, err)
        if (err >= 0) call read_stored_text(file, 'reference_scene_settings', settings, err)
        ! a part missing: as good as no fingerprint
        if (err < 0) digest = ''
        call h5fclose_f(file, err)
    end subroutine read_print

    !> The command that remakes the study's reference.
    function remake_command(study) result(command)
        type(study_input_t), intent(in) :: study
        character(len=:), allocatable :: command
        command = 'flexmbs reference ' // shell_word(study%path)
    end function remake_command

    !> The scene's output times, as every run of it has them.
    function output_times(base) result(times)
        type(scene_input_t), intent(in) :: base
        real(wp), allocatable :: times(:)
        type(dae_options_t) :: options
        options = scene_dae_options(base)
        times = options%output_times
    end function output_times

    !> Output times as a part's value ('N from A to B, sha256 ...'; the
    !> digest of every time, `hashed`) or for a message.
    function times_text(times, every_step, hashed) result(text)
        real(wp), intent(in) :: times(:)
        logical, intent(in) :: every_step
        logical, intent(in), optional :: hashed
        character(len=:), allocatable :: text
        character(len=:), allocatable :: all
        integer :: k
        text = int_text(size(times)) // ' from ' // exact_text(times(1)) // ' to ' // &
            exact_text(times(size(times))) // ' s'
        if (present(hashed)) then
            if (.not. hashed) return
        end if
        all = ''
        do k = 1, size(times)
            all = all // exact_text(times(k)) // nl
        end do
        text = text // ', sha256 ' // sha256_hex(all)
        if (every_step) text = text // ', and every step'
    end function times_text

    !> The parts that differ between a file's (`parts`, `settings`) and
    !> `now`, each with its values there and now, the scene's down to its
    !> variables.
    function differences(parts, settings, now) result(text)
        character(len=*), intent(in) :: parts, settings
        type(reference_print_t), intent(in) :: now
        character(len=:), allocatable :: text
        type(pair_t), allocatable :: old(:), new(:)
        character(len=:), allocatable :: was, is
        integer :: k
        call split_pairs(parts, old)
        call split_pairs(now%parts, new)
        text = ''
        do k = 1, size(keys)
            was = pair_value(old, trim(keys(k)))
            is = pair_value(new, trim(keys(k)))
            if (was == is) cycle
            if (len(text) > 0) text = text // '; '
            text = text // trim(names(k))
            select case (keys(k))
            case ('scene')
                text = text // ' (after defaults): ' // setting_changes(settings, now%settings)
            case ('mesh')
                text = text // ' (its text changed)'
            case default
                text = text // ' (' // shown(was) // ' in the reference, ' // shown(is) // &
                    ' now)'
            end select
        end do
    end function differences

    !> The names of the parts that differ, for the table's note.
    function changed_parts(parts, now) result(text)
        character(len=*), intent(in) :: parts
        type(reference_print_t), intent(in) :: now
        character(len=:), allocatable :: text
        type(pair_t), allocatable :: old(:), new(:)
        integer :: k
        call split_pairs(parts, old)
        call split_pairs(now%parts, new)
        text = ''
        do k = 1, size(keys)
            if (pair_value(old, trim(keys(k))) == pair_value(new, trim(keys(k)))) cycle
            if (len(text) > 0) text = text // ', '
            text = text // trim(names(k))
        end do
    end function changed_parts

    !> A part's value for a message: output times without their digest.
    function shown(value) result(text)
        character(len=*), intent(in) :: value
        character(len=:), allocatable :: text
        integer :: cut
        text = value
        if (len(text) == 0) text = '(none)'
        cut = index(text, ', sha256 ')
        if (cut > 0) text = text(1:cut - 1) // text(cut + 73:)
    end function shown

    !> The scene's variables whose values differ between the settings `old`
    !> (the reference's, or those of the file `where` names) and `new`: the
    !> first three, then how many more.
    function setting_changes(old, new, where) result(text)
        character(len=*), intent(in) :: old, new
        character(len=*), intent(in), optional :: where !! 'the reference' unless given
        character(len=:), allocatable :: text
        integer, parameter :: listed = 3
        type(pair_t), allocatable :: was(:), is(:)
        character(len=:), allocatable :: before, there
        integer :: k, n
        there = 'the reference'
        if (present(where)) there = where
        text = ''
        if (len(old) == 0) then
            text = there // ' keeps no settings to compare'
            return
        end if
        call split_pairs(old, was)
        call split_pairs(new, is)
        n = 0
        do k = 1, size(is)
            before = value_near(was, is(k)%key, k)
            if (before == is(k)%value) cycle
            n = n + 1
            if (n > listed) cycle
            if (n > 1) text = text // ', '
            if (len(before) == 0) then
                text = text // is(k)%key // ' = ' // is(k)%value // ' (not in ' // there // ')'
            else
                text = text // is(k)%key // ' = ' // before // ' in ' // there // ', ' // &
                    is(k)%value // ' now'
            end if
        end do
        do k = 1, size(was)
            if (len(value_near(is, was(k)%key, k)) > 0) cycle
            n = n + 1
            if (n > listed) cycle
            if (n > 1) text = text // ', '
            text = text // was(k)%key // ' (in ' // there // ' only)'
        end do
        if (n > listed) text = text // ' and ' // int_text(n - listed) // ' more'
    end function setting_changes

    !> The value of `key` among `pairs`, looked for first at position k
    !> (where it is when the two texts have the same lines): '' when none.
    function value_near(pairs, key, k) result(value)
        type(pair_t), intent(in) :: pairs(:)
        character(len=*), intent(in) :: key
        integer, intent(in) :: k
        character(len=:), allocatable :: value
        if (k <= size(pairs)) then
            if (pairs(k)%key == key) then
                value = pairs(k)%value
                return
            end if
        end if
        value = pair_value(pairs, key)
    end function value_near

    pure function line(key, value) result(text)
        character(len=*), intent(in) :: key, value
        character(len=:), allocatable :: text
        text = key // ' = ' // value // nl
    end function line
end module flexmbs_run_reference_fingerprint
