!> Resuming a run from the checkpoint in its HDF5 result (`flexmbs run
!> SCENE --resume [RESULT.h5]`, docs/output.md "Restart").
!>
!> A result records which scene wrote it: the root attributes
!> `scene_settings` (io/scene_settings: every variable, given or by
!> default, less the &output variables that change no number of the run:
!> progress, checkpoint_interval, table, reasons, vtk, vtk_format, file;
!> then, as `&run NAME = VALUE` lines, the values a study sets in the
!> scene of each grid point: solver, tolerances, order, steps, interval,
!> formulation) and `scene_fingerprint`, the SHA-256 of those settings and
!> of the mesh files' texts. A resume is refused unless the scene's fingerprint now is
!> the file's; the message names the variables that differ.
!>
!> The run continues from the checkpoint's state, re-initialised by the
!> problem's own consistent_initial where it has one (the formulations
!> project q and v onto the constraints and solve for a and λ; DDASSL and
!> IDA find y′ as at a start), with the checkpoint's step size as the
!> first step and the order starting again at 1. Output times after the
!> checkpoint remain; the records up to it stay in the file.
module flexmbs_run_resume
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_sha256, only: sha256_hex
    use flexmbs_core_text, only: real_text, int_text, exact_text
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_scene_settings, only: scene_settings
    use flexmbs_io_checkpoint, only: checkpoint_t, read_checkpoint, stats_sum
    use flexmbs_run_study_record, only: mesh_digest
    use flexmbs_run_reference_fingerprint, only: setting_changes
    use flexmbs_run_plan, only: run_plan_t
    implicit none
    private

    public :: scene_fingerprint, prepare_resume, pieces_note

    !> The &output variables a resume may change (module header).
    character(len=*), parameter :: omitted(*) = [character(len=26) :: 'output/progress', &
        'output/checkpoint_interval', 'output/table', 'output/reasons', 'output/vtk', &
        'output/vtk_format', 'output/file']
    character, parameter :: nl = new_line('a')

contains

    !> The scene's settings and fingerprint (module header).
    subroutine scene_fingerprint(scene, settings, digest, status)
        type(scene_input_t), intent(in) :: scene
        character(len=:), allocatable, intent(out) :: settings
        character(len=64), intent(out) :: digest
        type(status_t), intent(out) :: status
        character(len=64) :: mesh
        settings = scene_settings(scene%text, omitted) // run_values(scene)
        call mesh_digest(scene, mesh, status)
        if (.not. status%ok()) return
        digest = sha256_hex(settings // 'mesh = ' // trim(mesh) // nl)
    end subroutine scene_fingerprint

    !> Read the checkpoint of `path`, check that `scene` wrote it, and set
    !> the plan to continue from it: t, y (re-initialised), the first step,
    !> the output times left. `prior` sums the statistics of the pieces
    !> before; `finished` when the run it holds reached t_end (nothing is
    !> set then). Bad input, naming the file, otherwise.
    subroutine prepare_resume(scene, path, plan, t, y, cp, prior, finished, status)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: path
        type(run_plan_t), intent(inout) :: plan
        real(wp), intent(out) :: t
        real(wp), allocatable, intent(inout) :: y(:)
        type(checkpoint_t), intent(out) :: cp
        type(dae_stats_t), intent(out) :: prior
        logical, intent(out) :: finished
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: settings, changes
        character(len=64) :: digest
        real(wp), allocatable :: yp(:), y_try(:)
        type(status_t) :: local
        finished = .false.
        call read_checkpoint(path, cp, status)
        if (.not. status%ok()) return
        call scene_fingerprint(scene, settings, digest, status)
        if (.not. status%ok()) return
        if (cp%fingerprint /= digest) then
            changes = setting_changes(cp%settings, settings, 'the result')
            if (cp%settings == settings) changes = 'the mesh file (its text changed)'
            call status%set(status_bad_input, path // ': was written by another scene than ' // &
                scene%path // ', so it cannot be continued; what differs: ' // changes)
            return
        end if
        ! finished, or stopped on its last step: every record is there
        if (cp%outcome == 'ok' .or. cp%t >= scene%t_end) then
            finished = .true.
            return
        end if
        if (size(cp%y) /= plan%problem%n) then
            call status%set(status_bad_input, path // ': its checkpoint holds ' // &
                int_text(size(cp%y)) // ' values, the scene''s state ' // &
                int_text(plan%problem%n))
            return
        end if
        if (.not. cp%t >= scene%t_start) then
            call status%set(status_bad_input, path // ': its checkpoint at t = ' // &
                real_text(cp%t) // ' lies before the scene''s t_start')
            return
        end if
        t = cp%t
        y = cp%y
        ! consistent again for the problem, when it says how
        y_try = y
        allocate (yp(size(y)), source=0.0_wp)
        call plan%problem%consistent_initial(t, y_try, yp, local)
        if (local%ok()) then
            y = y_try
        else if (allocated(plan%mechanical)) then
            call status%set(status_bad_input, path // ': the checkpoint''s state at t = ' // &
                real_text(t) // ' cannot be made consistent: ' // local%text())
            return
        end if
        plan%options%h0 = abs(cp%h)
        plan%options%output_times = pack(plan%options%output_times, &
                                         (plan%options%output_times - t) > 0.0_wp)
        ! a piece ended with its statistics (a clean stop) counts them all;
        ! one killed outright only its steps and times up to the checkpoint
        if (len(cp%outcome) > 0 .and. cp%t_reached == cp%t) then
            prior = cp%ended
        else
            prior = stats_sum(cp%prior, cp%live)
        end if
    end subroutine prepare_resume

    !> The values a study sets in a run's scene besides its text (run/study
    !> configure, read_study_scene), as settings lines: a grid point's
    !> result is its own.
    function run_values(scene) result(text)
        type(scene_input_t), intent(in) :: scene
        character(len=:), allocatable :: text
        text = line('solver', trim(scene%solver_name)) // line('rtol', exact_text(scene%rtol)) &
            // line('atol', exact_text(scene%atol)) // line('pmax', int_text(scene%pmax)) // &
            line('max_steps', int_text(scene%max_steps)) // &
            line('t_start', exact_text(scene%t_start)) // &
            line('t_end', exact_text(scene%t_end)) // &
            line('formulation', trim(scene%multibody%formulation)) // &
            line('projection', merge('T', 'F', scene%multibody%projection)) // &
            line('constraint_derivatives', trim(scene%multibody%constraint_derivatives))
    contains
        pure function line(name, value) result(text)
            character(len=*), intent(in) :: name, value
            character(len=:), allocatable :: text
            text = '&run ' // name // ' = ' // value // nl
        end function line
    end function run_values

    !> What the statistics of a resumed run are (the root attribute
    !> `statistics`).
    function pieces_note(pieces) result(text)
        integer, intent(in) :: pieces
        character(len=:), allocatable :: text
        text = 'sums over the ' // int_text(pieces) // ' pieces of the run (it was resumed &
            &at each time of restart_times); a piece killed outright (SIGKILL) counts &
            &only its steps and times up to its last checkpoint'
    end function pieces_note
end module flexmbs_run_resume
