!> A sweep's table from the records of its points (`flexmbs sweep STUDY
!> --merge`, and the end of `sweep -j N`): every grid point whose record
!> in the results folder is current (run/study_record: the same study,
!> scene and mesh texts, the same grid point) is a row, in the grid's
!> order, exactly as a serial sweep makes it; a record from another text
!> of the study is stale, and like a damaged one counts as missing. The
!> table file is written only when no point is missing, so that it always
!> holds the whole study; what is missing is listed with the commands that
!> run only those points (here, and with the Slurm script when there is one).
!> As every sweep, a merge first checks that the reference is the one
!> `flexmbs reference` would make of the study now (run/reference_fingerprint).
module flexmbs_run_study_merge
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: int_text
    use flexmbs_core_files, only: absolute_path
    use flexmbs_io_namelist, only: study_input_t, scene_input_t
    use flexmbs_io_table, only: stats_row_t, write_table
    use flexmbs_io_output_files, only: output_table
    use flexmbs_run_study, only: read_study_scene, check_study_output
    use flexmbs_run_study_grid, only: sweep_point_t, sweep_points, point_list_text
    use flexmbs_run_study_results, only: results_folder, record_path, array_script_path, &
        merge_script_path
    use flexmbs_run_study_record, only: sweep_run_t, fingerprint_t, study_fingerprint, &
        read_record, record_missing, record_current, record_stale, record_damaged
    use flexmbs_run_study_slurm, only: shell_word
    use flexmbs_run_reference_fingerprint, only: reference_print_t, reference_print, &
        check_reference_print
    implicit none
    private

    !> The records of a study's points, sorted.
    type, public :: merged_t
        integer :: npoints = 0
        character(len=:), allocatable :: folder       !! the results folder
        type(sweep_run_t), allocatable :: runs(:)     !! the current records, grid order
        integer, allocatable :: present(:)            !! their point numbers
        integer, allocatable :: missing(:)            !! points without a current record
        integer, allocatable :: failed(:)             !! points whose run failed
        !> a line per stale or damaged record, and per failed run: why
        character(len=:), allocatable :: notes
        !> '', or with --force that the reference is stale (the table's note)
        character(len=:), allocatable :: stale_reference
        logical :: table_written = .false.
    contains
        procedure :: complete => merged_complete
    end type merged_t

    character, parameter :: nl = new_line('a')

    public :: merge_records, merge_report

contains

    !> The records of the study's results folder (module header); the
    !> table written (`table_written`) when the study names one and none is
    !> missing. `status` is not ok only when the study, its scene, its
    !> reference or the table's path is wrong: missing points are in `merged`.
    subroutine merge_records(study, merged, status, force)
        type(study_input_t), intent(in) :: study
        type(merged_t), intent(out) :: merged
        type(status_t), intent(out) :: status
        !> use a stale reference, replace a file at the table's path that is
        !> not flexmbs's own
        logical, intent(in), optional :: force
        type(scene_input_t) :: base
        type(sweep_point_t), allocatable :: points(:)
        type(fingerprint_t) :: print
        type(reference_print_t) :: now
        type(sweep_run_t), allocatable :: runs(:)
        type(stats_row_t), allocatable :: rows(:)
        logical, allocatable :: current(:)
        character(len=:), allocatable :: note
        integer :: k, state, unit_row
        logical :: forced

        forced = .false.
        if (present(force)) forced = force
        merged%stale_reference = ''
        call read_study_scene(study, base, status)
        if (status%ok()) call reference_print(study, base, now, status)
        if (status%ok()) call check_reference_print(study, now, forced, &
                                                    merged%stale_reference, status)
        if (status%ok()) call study_fingerprint(study, base, print, status)
        if (.not. status%ok()) return
        if (len(study%table) > 0) call check_study_output(study, base, 'table', study%table, &
                                                          output_table, forced, status)
        if (.not. status%ok()) return
        call sweep_points(study, base, points)
        merged%npoints = size(points)
        merged%folder = results_folder(study)
        merged%notes = ''
        allocate (runs(size(points)), current(size(points)))
        do k = 1, size(points)
            call read_record(record_path(merged%folder, k), k, points(k), print, runs(k), &
                             state, note)
            current(k) = state == record_current
            select case (state)
            case (record_stale)
                merged%notes = merged%notes // 'stale: point ' // int_text(k) // ': ' // note &
                    // ' (not used: counted as missing)' // nl
            case (record_damaged)
                merged%notes = merged%notes // 'damaged: point ' // int_text(k) // ': ' // &
                    note // ' (not used: counted as missing)' // nl
            case (record_current)
                if (.not. runs(k)%ok) merged%notes = merged%notes // 'failed: point ' // &
                    int_text(k) // ': ' // runs(k)%reason // nl
            case (record_missing)
            end select
        end do
        merged%present = pack([(k, k=1, size(points))], current)
        merged%missing = pack([(k, k=1, size(points))], .not. current)
        merged%failed = pack([(k, k=1, size(points))], current .and. .not. runs%ok)
        allocate (merged%runs(size(merged%present)))
        do k = 1, size(merged%present)
            merged%runs(k) = runs(merged%present(k))
        end do
        ! CPU normalised to the row cpu_reference, as in a serial sweep
        unit_row = findloc(merged%present, study%cpu_reference, dim=1)
        if (unit_row > 0) then
            if (merged%runs(unit_row)%ok) merged%runs%row%cpu_unit = &
                merged%runs(unit_row)%row%stats%cpu
        end if
        if (merged%complete() .and. len(study%table) > 0) then
            rows = merged%runs%row
            call write_table(study%table, rows, status, trim(study%layout), study%reasons, &
                             merged%stale_reference)
            merged%table_written = status%ok()
        end if
    end subroutine merge_records

    !> No point is missing.
    pure logical function merged_complete(self)
        class(merged_t), intent(in) :: self
        merged_complete = .true.
        if (allocated(self%missing)) merged_complete = size(self%missing) == 0
    end function merged_complete

    !> What is missing or failed, and how to run only those points again:
    !> with `exe` here, and with the results folder's Slurm script when
    !> there is one; '' when all points are there and none failed.
    function merge_report(merged, study, exe) result(text)
        type(merged_t), intent(in) :: merged
        type(study_input_t), intent(in) :: study
        character(len=*), intent(in) :: exe
        character(len=:), allocatable :: text
        character(len=:), allocatable :: study_path
        study_path = absolute_path(study%path)
        if (len(study_path) == 0) study_path = study%path
        text = merged%notes
        if (size(merged%missing) > 0) then
            text = text // 'missing: ' // int_text(size(merged%missing)) // ' of ' // &
                int_text(merged%npoints) // ' points have no current record in ' // &
                merged%folder // ': ' // point_list_text(merged%missing) // nl // &
                'the table is not written until every point has its record' // nl // &
                commands('resubmit', merged%missing)
        end if
        if (size(merged%failed) > 0) text = text // 'failed: ' // &
            int_text(size(merged%failed)) // ' runs (rows with ERR ''-''): ' // &
            point_list_text(merged%failed) // nl // commands('rerun failed', merged%failed)

    contains

        !> The commands that run `list` only, each line headed by `what`.
        function commands(what, list) result(lines)
            character(len=*), intent(in) :: what
            integer, intent(in) :: list(:)
            character(len=:), allocatable :: lines
            character(len=:), allocatable :: script
            logical :: exists
            integer :: i
            lines = ''
            do i = 1, size(list)
                lines = lines // what // ': ' // shell_word(exe) // ' sweep ' // &
                    shell_word(study_path) // ' --point ' // int_text(list(i)) // nl
            end do
            script = array_script_path(merged%folder)
            inquire (file=script, exist=exists)
            if (.not. exists) return
            lines = lines // what // ' (Slurm): sbatch --array=' // point_list_text(list) // &
                ' ' // shell_word(absolute_path(script)) // ' 1' // nl // &
                what // ' (Slurm), then merge: sbatch --dependency=afterany:ARRAY_JOB_ID ' // &
                shell_word(absolute_path(merge_script_path(merged%folder))) // nl
        end function commands
    end function merge_report
end module flexmbs_run_study_merge
