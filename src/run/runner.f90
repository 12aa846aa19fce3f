!> The runner: from a validated scene to a finished run — its plan
!> (run/plan: problem, solver, options), the output sinks, the run itself
!> and what it produced.
!>
!> Everything that can be checked is checked before any output file is
!> created, so bad input never leaves a half-written file behind.
module flexmbs_run_runner
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_interrupted, status_signal
    use flexmbs_core_signals, only: signal_pending, caught_signal, signal_name
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_core_resources, only: free_space, bytes_text
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_mbs_formulation, only: block_q, block_v, block_lambda
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_mbs_system, only: mbs_system_t, part_rigid, part_flexible, part_modal
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_scene_input, only: nonlinear_body, modal_body
    use flexmbs_io_scene_schema, only: len_name
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_progress, only: progress_t, new_progress, announce
    use flexmbs_io_multi_sink, only: multi_sink_t
    use flexmbs_io_signal_sink, only: signal_sink_t
    use flexmbs_io_table, only: new_stats_row, write_table
    use flexmbs_io_vtk_sink, only: vtk_sink_t
    use flexmbs_io_output_files, only: named_path_t, named_path, check_output_paths, &
        output_hdf5, output_vtk, output_table, output_xdmf, scene_inputs
    use flexmbs_io_xdmf_file, only: xdmf_body_t, xdmf_beside, write_xdmf, xdmf_most_records
    use flexmbs_run_flexible_output, only: xdmf_body
    use flexmbs_run_problem_factory, only: block_spec_t
    use flexmbs_run_plan, only: run_plan_t, make_plan, scene_stab
    use flexmbs_run_monitor_sink, only: monitor_sink_t
    use flexmbs_run_named_output, only: add_named_output
    use flexmbs_run_summary, only: state_summary
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    use flexmbs_run_body_builder, only: body_energies
    use flexmbs_io_checkpoint, only: checkpoint_t, stats_sum
    use flexmbs_run_checkpoint_sink, only: checkpoint_sink_t, new_checkpoint_sink
    use flexmbs_run_resume, only: scene_fingerprint, prepare_resume, pieces_note
    use flexmbs_run_chain_builder, only: link_names, tree_count
    implicit none
    private

    !> What a run produced, successful or not.
    type, public :: run_result_t
        real(wp) :: t = 0.0_wp                !! last time reached
        real(wp), allocatable :: y(:)         !! state there
        type(dae_stats_t) :: stats
        character(len=:), allocatable :: solver_name
        logical :: hdf5_written = .false.     !! an HDF5 file was created (and kept)
        !> the XDMF file written beside it (flexible bodies), '' for none
        character(len=:), allocatable :: xdmf_file
        !> A flexible body: strain, kinetic and total energy (with the
        !> potential of gravity and loads) at the start and at the end [J].
        logical :: has_energy = .false.
        real(wp) :: energy_start(3) = 0.0_wp, energy_end(3) = 0.0_wp
        !> A formulated mechanical scene: ‖g‖∞ and ‖G v + g_I‖∞ at the end
        !> (the whole history is /monitor in the HDF5 file), constraint rows.
        logical :: has_drift = .false.
        real(wp) :: drift_end(2) = 0.0_wp
        integer :: constraints = 0
        !> a multibody scene: how far the initial assembly moved each body
        character(len=:), allocatable :: assembly
        !> the positions in y (block 'q'), all of y when there is none
        integer :: q_first = 0, q_last = 0
        !> a mechanical scene: its bodies and joints at the last time reached,
        !> for people (run/summary); '' otherwise
        character(len=:), allocatable :: summary
        !> a formulated mechanical scene: the energy at the first and the
        !> last record [J] (NaN where the model defines none)
        logical :: has_monitor_energy = .false.
        real(wp) :: monitor_energy(2) = 0.0_wp
        !> a resume: the time it started from (the checkpoint's), and
        !> whether the file held a finished run (nothing was run then)
        logical :: resumed = .false., finished_before = .false.
        real(wp) :: resumed_from = 0.0_wp
    end type run_result_t

    public :: run_scene

    !> An output from this size on is announced before the run, with the
    !> time its writing alone takes at output_bytes_per_second (what the
    !> writer reached here, bench/output.sh: about 150 MB/s for a small
    !> state on a local disk).
    real(wp), parameter :: large_output_bytes = 2.0e9_wp
    real(wp), parameter :: output_bytes_per_second = 1.5e8_wp

contains

    !> The HDF5 file of n_output records (y, its blocks and the time) must
    !> fit in the free space of its folder: an output grid that cannot be
    !> written is bad input, said before the run (with every_step the
    !> number of records is not known in advance).
    subroutine check_output_size(scene, n, blocks, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: n
        type(block_spec_t), intent(in) :: blocks(:)
        type(status_t), intent(inout) :: status
        real(wp) :: bytes
        integer(i8) :: free
        integer :: i, per_record
        if (len(scene%output_file) == 0 .or. scene%every_step) return
        per_record = n + 1
        do i = 1, size(blocks)
            per_record = per_record + blocks(i)%last - blocks(i)%first + 1
        end do
        bytes = 8.0_wp * real(per_record, wp) * real(scene%n_output, wp)
        free = free_space(scene%output_file(1:index(scene%output_file, '/', back=.true.)))
        if (free >= 0 .and. bytes > real(free, wp)) then
            call status%set(status_bad_input, &
                scene%path // ': &output: n_output = ' // int_text(scene%n_output) // ': the &
                &HDF5 file ''' // scene%output_file // ''' would need ~' // bytes_text(bytes) // &
                ' (' // int_text(per_record) // ' values a record); its file system has ' // &
                bytes_text(real(free, wp)) // ' free')
        else if (bytes >= large_output_bytes) then
            ! it fits, but a user should know before waiting for it
            call announce(scene%path // ': &output: n_output = ' // int_text(scene%n_output) // &
                ': the HDF5 file ''' // scene%output_file // ''' will hold at least ' // &
                bytes_text(bytes) // '; writing it alone takes about ' // &
                int_text(nint(bytes / output_bytes_per_second)) // ' s at ' // &
                bytes_text(output_bytes_per_second) // '/s (docs/output.md)')
        end if
    end subroutine check_output_size

    !> Run a validated scene: build, check, create the outputs, integrate,
    !> store the statistics. `status` is ok, bad_input (before any file is
    !> created), solver_failure or signal (SIGINT/SIGTERM, checked after
    !> every accepted step: outputs kept, `result` says how far it got) or
    !> io_error.
    subroutine run_scene(scene, quiet, result, status, record, force, resume)
        type(scene_input_t), intent(in) :: scene
        logical, intent(in) :: quiet             !! no progress display
        type(run_result_t), intent(out) :: result
        type(status_t), intent(out) :: status
        !> also given the solution at every output time
        class(sink_t), intent(inout), target, optional :: record
        !> replace existing files that are not flexmbs's own (io/output_files)
        logical, intent(in), optional :: force
        !> continue the run kept in this result (run/resume), which becomes
        !> the run's HDF5 file
        character(len=*), intent(in), optional :: resume
        type(run_plan_t), target :: plan
        type(checkpoint_sink_t), target :: checkpoints
        type(checkpoint_t) :: cp
        type(dae_stats_t) :: prior
        type(monitor_sink_t), target :: monitor
        type(vtk_sink_t), target :: vtk
        type(hdf5_sink_t), target :: h5
        type(progress_t), target :: progress
        type(signal_sink_t), target :: signals
        type(multi_sink_t) :: sinks
        type(status_t) :: io_status
        real(wp), allocatable :: y_start(:)

        result%xdmf_file = ''
        call make_plan(scene, plan, status)
        if (.not. status%ok()) return
        result%y = plan%y0
        if (allocated(plan%assembly)) result%assembly = plan%assembly
        result%q_first = plan%q_first
        result%q_last = plan%q_last
        result%solver_name = plan%solver%name()
        result%t = scene%t_start
        ! energies and work count from the scene's start, also when resumed
        y_start = plan%y0
        if (present(resume)) then
            call start_resume(scene, resume, plan, result, cp, prior, status)
            if (.not. status%ok() .or. result%finished_before) return
        end if

        ! ParaView output is checked before any file is created
        if (len_trim(scene%vtk) > 0) then
            call setup_vtk(vtk, plan, scene, status)
            if (.not. status%ok()) return
        end if
        ! which files the run may write; checked before any file is created
        call check_outputs(scene, vtk, size(plan%options%output_times), force_given(), status)
        if (.not. status%ok()) return
        call check_output_size(scene, plan%problem%n, plan%blocks, status)
        if (.not. status%ok()) return
        if (len(scene%output_file) > 0) then
            if (result%resumed) then
                call create_hdf5(h5, plan, scene, result, status, cp)
            else
                call create_hdf5(h5, plan, scene, result, status)
            end if
            if (.not. status%ok()) return
            call sinks%attach(h5)
        end if
        progress = new_progress(scene%t_start, scene%t_end, quiet .or. .not. scene%progress)
        call progress%watch(plan%solver)
        call sinks%attach(progress)
        call sinks%attach(signals)
        ! after the file's sink and the signals: the records up to a step
        ! are there when its checkpoint is written, and a stop is seen
        if (h5%is_open) then
            checkpoints = new_checkpoint_sink(h5, plan%solver, plan%problem%n, &
                scene%checkpoint_interval, cp%piece + merge(1, 0, result%resumed), prior)
            call sinks%attach(checkpoints)
        end if
        if (present(record)) call sinks%attach(record)
        if (len_trim(scene%vtk) > 0) call sinks%attach(vtk)
        call attach_monitor(monitor, plan, scene, y_start, result, sinks)

        call record_energy(y_start, result%energy_start)
        ! the records kept, to the sinks that build on every record
        if (result%resumed .and. status%ok()) call replay(h5, cp%records, monitor, vtk, &
            len_trim(scene%vtk) > 0, status, record)
        if (status%ok()) call plan%integrate(result%t, result%y, scene%t_end, result%stats, &
                                             status, sinks)
        if (result%resumed) result%stats = stats_sum(prior, result%stats)
        call explain_end(scene, result%t, status)
        if (status%ok()) call record_energy(result%y, result%energy_end)
        result%has_energy = result%has_energy .and. status%ok()

        if (monitor%records > 0) then
            result%has_drift = monitor%formulation%block_size(block_lambda) > 0
            result%drift_end = monitor%table(2:3, monitor%records)
            result%monitor_energy = [monitor%table(4, 1), monitor%table(4, monitor%records)]
            result%has_monitor_energy = .not. any(ieee_is_nan(result%monitor_energy))
        end if
        result%summary = state_summary(plan, scene, result%y)
        if (h5%is_open) call close_hdf5(h5, monitor, plan, scene, cp%piece, result, status)
        if (len_trim(scene%table) > 0 .and. status%code /= status_bad_input) then
            call write_table(trim(scene%table), [new_stats_row(result%solver_name, &
                scene%rtol, scene_stab(scene), result%stats)], io_status, reasons=scene%reasons)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
        end if

    contains

        logical function force_given()
            force_given = .false.
            if (present(force)) force_given = force
        end function force_given

        !> Energies of a flexible body at y = (q, v, ...).
        subroutine record_energy(y, energies)
            real(wp), intent(in) :: y(:)
            real(wp), intent(out) :: energies(3)
            type(status_t) :: energy_status
            energies = 0.0_wp
            if (.not. allocated(plan%mechanical)) return
            select type (body => plan%mechanical)
            type is (flexible_body_t)
                associate (nq => body%nq)
                    call body_energies(body, y(1:nq), y(nq + 1:2 * nq), y_start(1:nq), &
                                       energies, energy_status)
                end associate
                result%has_energy = energy_status%ok()
            end select
        end subroutine record_energy
    end subroutine run_scene

    !> A resume's start (run/resume): the plan, t and y from the checkpoint
    !> `cp` of the file `path`, `prior` the statistics before it; nothing to
    !> do when the file holds a finished run (result%finished_before).
    subroutine start_resume(scene, path, plan, result, cp, prior, status)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: path
        type(run_plan_t), intent(inout) :: plan
        type(run_result_t), intent(inout) :: result
        type(checkpoint_t), intent(out) :: cp
        type(dae_stats_t), intent(out) :: prior
        type(status_t), intent(out) :: status
        call prepare_resume(scene, path, plan, result%t, result%y, cp, prior, &
                            result%finished_before, status)
        if (.not. status%ok() .or. result%finished_before) return
        result%resumed = .true.
        result%resumed_from = result%t
        if (scene%every_step .and. len_trim(scene%vtk) > 0) call status%set(status_bad_input, &
            scene%path // ': &output: vtk with every_step: the ParaView pieces before the &
            &checkpoint are not in ' // path // ', so this run cannot be resumed; run it again')
    end subroutine start_resume

    !> Drift, energy and reactions of a formulated mechanical scene at the
    !> output times (or steps): the monitor, attached to `sinks`.
    subroutine attach_monitor(monitor, plan, scene, y_start, result, sinks)
        type(monitor_sink_t), intent(inout), target :: monitor
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        real(wp), intent(in) :: y_start(:)   !! the scene's start: the work's origin
        type(run_result_t), intent(inout) :: result
        type(multi_sink_t), intent(inout) :: sinks
        if (.not. allocated(plan%mechanical)) return
        select type (p => plan%problem)
        type is (formulation_t)
            monitor%formulation => p
            monitor%mechanical => plan%mechanical
            monitor%every_step = scene%every_step
            monitor%resumed = result%resumed
            monitor%q_start = y_start(p%offset(block_q) + 1:p%last(block_q))
            call sinks%attach(monitor)
            result%constraints = p%block_size(block_lambda)
        end select
    end subroutine attach_monitor

    !> How the integration ended, said for people: a solver's refusal names
    !> the file and group; a stop requested on the last step (t = t_end)
    !> came too late to stop anything; a stop by SIGINT or SIGTERM says so.
    subroutine explain_end(scene, t, status)
        type(scene_input_t), intent(in) :: scene
        real(wp), intent(in) :: t      !! the time reached
        type(status_t), intent(inout) :: status
        if (status%code == status_bad_input) then
            if (index(status%text(), scene%path // ':') /= 1) status%message = scene%path // &
                ': &solver: ' // status%text()
        end if
        if (status%code == status_interrupted .and. t == scene%t_end) call status%clear()
        if (status%code == status_interrupted .and. signal_pending()) call status%set( &
            status_signal, 'stopped by ' // signal_name(caught_signal()) // ' at t = ' // &
            real_text(t), caught_signal())
    end subroutine explain_end

    !> The end of the open HDF5 file: the monitor's table, the statistics
    !> and outcome (summed over the pieces of a resumed run, `piece` that
    !> of its checkpoint), the close, the XDMF file beside it. A solver that
    !> refused its input computed nothing: no file is left then. An I/O
    !> error becomes `status` when it was ok.
    subroutine close_hdf5(h5, monitor, plan, scene, piece, result, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(monitor_sink_t), intent(in) :: monitor
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: piece
        type(run_result_t), intent(inout) :: result
        type(status_t), intent(inout) :: status
        type(status_t) :: io_status
        character(len=:), allocatable :: outcome
        real(wp), allocatable :: xdmf_times(:)
        integer, allocatable :: xdmf_rows(:)
        integer :: xdmf_records
        if (monitor%records > 0) then
            call write_monitor(h5, monitor, io_status)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
        end if
        outcome = 'ok'
        if (.not. status%ok()) outcome = status%text()
        call h5%write_statistics(result%stats, io_status, result%solver_name, outcome)
        if (result%resumed .and. io_status%ok()) call h5%write_text('statistics', &
            pieces_note(piece + 1), io_status)
        if (status%ok() .and. .not. io_status%ok()) status = io_status
        ! the records the XDMF file lists, read back before the file closes
        if (xdmf_wanted(scene)) call h5%record_times(xdmf_most_records, xdmf_rows, &
                                                     xdmf_times, xdmf_records, io_status)
        if (status%ok() .and. .not. io_status%ok()) status = io_status
        call h5%close(io_status)
        if (status%ok() .and. .not. io_status%ok()) status = io_status
        if (status%code == status_bad_input .and. h5%records == 0) then
            call delete_file(scene%output_file)
            result%hdf5_written = .false.
        end if
        ! the records there are, also after a failure
        if (result%hdf5_written .and. xdmf_wanted(scene)) then
            call write_xdmf_beside(plan, scene, xdmf_rows, xdmf_times, xdmf_records, &
                                   result, io_status)
            if (status%ok() .and. .not. io_status%ok()) status = io_status
        end if
    end subroutine close_hdf5

    !> The HDF5 file of the run: y's blocks, the named series, the scene's
    !> texts. `result%hdf5_written` once it exists.
    subroutine create_hdf5(h5, plan, scene, result, status, resume)
        type(hdf5_sink_t), intent(inout) :: h5
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        type(run_result_t), intent(inout) :: result
        type(status_t), intent(out) :: status
        !> continue the file from this checkpoint instead of creating it
        type(checkpoint_t), intent(in), optional :: resume
        type(status_t) :: io_status
        character(len=:), allocatable :: settings
        character(len=64) :: digest
        integer :: i
        call scene_fingerprint(scene, settings, digest, status)
        if (.not. status%ok()) return
        if (present(resume)) then
            call h5%reopen(scene%output_file, plan%problem%n, resume, status, &
                           every_step=scene%every_step)
        else
            call h5%create(scene%output_file, plan%problem%n, status, input_text=scene%text, &
                           every_step=scene%every_step)
        end if
        if (.not. status%ok()) then
            call h5%close(io_status)
            return
        end if
        result%hdf5_written = .true.
        do i = 1, size(plan%blocks)
            call h5%add_block(plan%blocks(i)%name, plan%blocks(i)%first, &
                              plan%blocks(i)%last, status)
            if (.not. status%ok()) return
        end do
        call add_named_output(h5, plan, scene, status)
        if (.not. status%ok()) return
        call h5%write_text('scene_fingerprint', digest, status)
        if (status%ok()) call h5%write_text('scene_settings', settings, status)
        if (status%ok()) call h5%write_text('problem', trim(scene%problem), status)
        if (status%ok()) call h5%write_text('title', trim(scene%title), status)
        if (status%ok()) call h5%write_text('input_file', scene%path, status)
        if (status%ok() .and. allocated(result%assembly)) call h5%write_text('assembly', &
            'moves of the initial assembly from the given positions: ' // &
            result%assembly, status)
    end subroutine create_hdf5

    !> The `kept` records of a resumed run's file, read back, to the sinks
    !> that build on every record: the monitor, the ParaView pieces (with
    !> `vtk_on`) and the caller's record.
    subroutine replay(h5, kept, monitor, vtk, vtk_on, status, record)
        type(hdf5_sink_t), intent(inout) :: h5
        integer, intent(in) :: kept
        type(monitor_sink_t), intent(inout) :: monitor
        type(vtk_sink_t), intent(inout) :: vtk
        logical, intent(in) :: vtk_on
        type(status_t), intent(inout) :: status
        class(sink_t), intent(inout), optional :: record
        integer, parameter :: block = 256
        real(wp), allocatable :: t(:), y(:, :)
        integer :: first, m, k
        if (.not. h5%is_open) return
        allocate (t(block), y(h5%n, block))
        do first = 1, kept, block
            m = min(block, kept - first + 1)
            call h5%read_records(first, t(1:m), y(:, 1:m), status)
            do k = 1, m
                if (.not. status%ok()) return
                if (associated(monitor%formulation)) call monitor%replay(t(k), y(:, k), status)
                if (vtk_on .and. status%ok()) call vtk%output(t(k), y(:, k), status)
                if (present(record) .and. status%ok()) call record%output(t(k), y(:, k), status)
            end do
        end do
    end subroutine replay

    !> The monitor's table, and the energy, drift (or the note why there is
    !> none) and reactions by name, into the open HDF5 file.
    subroutine write_monitor(h5, monitor, io_status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(monitor_sink_t), intent(in) :: monitor
        type(status_t), intent(out) :: io_status
        real(wp), allocatable :: energy(:), drift(:, :)
        call h5%write_matrix('monitor', monitor%table(:, 1:monitor%records), io_status)
        if (io_status%ok()) call h5%write_text('monitor_columns', &
            't, |g|_inf, |G v + g_I|_inf, energy [J]', io_status)
        ! the same by name, with units
        ! contiguous copies: HDF5 writes whole arrays
        energy = monitor%table(4, 1:monitor%records)
        drift = monitor%table(2:3, 1:monitor%records)
        if (io_status%ok()) call h5%write_vector('energy', energy, io_status)
        if (io_status%ok()) call h5%annotate('energy', 'unit', 'J', io_status)
        if (io_status%ok()) call h5%annotate('energy', 'description', 'kinetic plus &
            &potential energy at each record of /time', io_status)
        if (monitor%formulation%block_size(block_lambda) == 0) then
            ! nothing to drift: said, not written as zeros
            if (io_status%ok()) call h5%write_text('drift_note', 'no /drift: the &
                &scene has no constraints (its /monitor drift columns are 0)', io_status)
        else
            if (io_status%ok()) call h5%write_matrix('drift', drift, io_status)
            if (io_status%ok()) call h5%annotate('drift', 'unit', &
                'm or 1; m/s or rad/s', io_status)
            if (io_status%ok()) call h5%annotate('drift', 'description', '|g|_inf and &
                &|G v + g_I|_inf at each record (the rows of g are lengths or &
                &direction cosines)', io_status)
        end if
        if (io_status%ok() .and. size(monitor%reactions, 1) > 0) then
            call h5%write_matrix('reactions', &
                monitor%reactions(:, 1:monitor%records), io_status)
            if (io_status%ok()) call h5%write_text('reactions_columns', 'per joint &
                &of the system: force and torque on the body of marker i, then of &
                &marker j (N, N m; global; torque about the marker)', io_status)
        end if
    end subroutine write_monitor

    !> ParaView output of the flexible bodies, the rigid bodies and the
    !> joints (y starts with q in every layout: the bodies' (r, p), then v
    !> behind q).
    subroutine setup_vtk(vtk, plan, scene, status)
        type(vtk_sink_t), intent(inout) :: vtk
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        type(status_t), intent(inout) :: status
        integer :: k, nf, ob, ov, oq, ovk
        vtk%prefix = trim(scene%vtk)
        vtk%binary = scene%vtk_format /= 'ascii'
        if (.not. allocated(plan%mechanical)) then
            call status%set(status_bad_input, scene%path // ': &output: vtk: problem = ''' &
                // trim(scene%problem) // ''' has no bodies to draw')
            return
        end if
        select type (m => plan%mechanical)
        type is (flexible_body_t)
            allocate (vtk%flexible(1))
            vtk%flexible(1)%body => m
            vtk%flexible(1)%ov = m%nq
            vtk%flexible(1)%name = scene%bodies(1)%name
        type is (mbs_system_t)
            nf = m%part_count(part_flexible)
            vtk%bodies = m%part_count(part_rigid)
            vtk%names = body_names(scene, vtk%bodies)
            vtk%system => m
            ! y's q block starts at the formulation's offset (0 without one)
            select type (p => plan%problem)
            type is (formulation_t)
                ob = p%offset(block_q)
                ov = p%offset(block_v)
                vtk%system_q = ob
                ! the reactions need a formulation's multipliers (consistent with q, v)
                if (m%joint_count() > 0 .and. p%block_size(block_lambda) > 0) vtk%formulation => p
            class default
                ob = 0
                ov = m%nq
            end select
            allocate (vtk%flexible(nf + m%part_count(part_modal)))
            do k = 1, nf
                call m%part_offsets(part_flexible, k, oq, ovk)
                vtk%flexible(k)%body => m%flexible_of(k)
                vtk%flexible(k)%name = scene%bodies(nonlinear_body(scene, k))%name
                vtk%flexible(k)%oq = ob + oq
                vtk%flexible(k)%ov = ov + ovk
            end do
            do k = 1, m%part_count(part_modal)
                call m%part_offsets(part_modal, k, oq, ovk)
                associate (vf => vtk%flexible(nf + k))
                    vf%modal => m%modal_of(k)
                    vf%body => vf%modal%fe_body()
                    vf%name = scene%bodies(modal_body(scene, k))%name
                    vf%oq = ob + oq
                    vf%ov = ov + ovk
                end associate
            end do
            if (m%joint_count() > 0 .and. allocated(plan%joint_names)) &
                vtk%joint_names = plan%joint_names
        class default
            call status%set(status_bad_input, scene%path // ': &output: vtk: problem = ''' &
                // trim(scene%problem) // ''' has no bodies to draw')
        end select
    end subroutine setup_vtk

    !> The XDMF file beside the closed HDF5 file: its flexible bodies and
    !> the times of its records (io/xdmf_file).
    subroutine write_xdmf_beside(plan, scene, rows, times, records, result, io_status)
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: rows(:), records   !! the records listed, of all
        real(wp), intent(in) :: times(:)
        type(run_result_t), intent(inout) :: result
        type(status_t), intent(inout) :: io_status
        type(xdmf_body_t), allocatable :: bodies(:)
        type(modal_body_t), pointer :: modal
        integer :: k, nf
        call io_status%clear()
        if (.not. allocated(plan%mechanical)) return
        select type (m => plan%mechanical)
        type is (flexible_body_t)
            allocate (bodies(1))
            bodies(1) = xdmf_body(m, scene%bodies(1)%name)
        type is (mbs_system_t)
            nf = m%part_count(part_flexible)
            allocate (bodies(nf + m%part_count(part_modal)))
            do k = 1, nf
                bodies(k) = xdmf_body(m%flexible_of(k), &
                                      scene%bodies(nonlinear_body(scene, k))%name)
            end do
            do k = 1, m%part_count(part_modal)
                modal => m%modal_of(k)
                bodies(nf + k) = xdmf_body(modal%fe_body(), &
                                           scene%bodies(modal_body(scene, k))%name)
            end do
        class default
            return
        end select
        if (size(bodies) == 0) return
        call write_xdmf(xdmf_beside(scene%output_file), scene%output_file, bodies, &
                        rows, times, records, io_status)
        if (io_status%ok()) result%xdmf_file = xdmf_beside(scene%output_file)
    end subroutine write_xdmf_beside

    !> The scene's rigid bodies, the node frames after them, then the
    !> chains' links, by name (the ParaView bodies' names).
    function body_names(scene, n) result(names)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: n  !! rigid bodies, node frames included
        character(len=len_name), allocatable :: names(:)
        integer :: i, k
        allocate (names(n + size(scene%chain)))
        do i = 1, n
            if (i <= size(scene%rigid_bodies)) then
                names(i) = scene%rigid_bodies(i)%name
            else
                names(i) = 'node frame ' // int_text(i - size(scene%rigid_bodies))
            end if
        end do
        ! the chains' links, chain by chain (one chain per tree)
        k = n
        do i = 1, tree_count(scene)
            associate (tree => link_names(scene, i))
                names(k + 1:k + size(tree)) = tree
                k = k + size(tree)
            end associate
        end do
    end function body_names

    !> The run's outputs (the HDF5 file, the table, the ParaView collection
    !> and the pieces of its `records` records) against its inputs (the
    !> scene file, a mesh file) and each other, and what they would replace
    !> (io/output_files).
    subroutine check_outputs(scene, vtk, records, force, status)
        type(scene_input_t), intent(in) :: scene
        type(vtk_sink_t), intent(in) :: vtk
        integer, intent(in) :: records
        logical, intent(in) :: force
        type(status_t), intent(inout) :: status
        type(named_path_t), allocatable :: outputs(:), inputs(:)
        character(len=:), allocatable :: pieces(:)
        integer :: n, k
        inputs = scene_inputs(scene)
        allocate (character(len=0) :: pieces(0))
        if (len_trim(scene%vtk) > 0) pieces = vtk%pieces(records)
        allocate (outputs(4 + size(pieces)))
        n = 0
        if (len(scene%output_file) > 0) call add(scene%output_file, 'file', output_hdf5)
        if (xdmf_wanted(scene)) call add(xdmf_beside(scene%output_file), &
            'file (its XDMF file)', output_xdmf)
        if (len_trim(scene%table) > 0) call add(trim(scene%table), 'table', output_table)
        if (len_trim(scene%vtk) > 0) call add(trim(scene%vtk) // '.pvd', 'vtk', output_vtk)
        do k = 1, size(pieces)
            call add(trim(pieces(k)), 'vtk', output_vtk)
            outputs(n)%series = .true.
        end do
        call check_output_paths(scene%path // ': ', outputs(1:n), inputs, force, status)
    contains
        subroutine add(path, name, kind)
            character(len=*), intent(in) :: path, name
            integer, intent(in) :: kind
            n = n + 1
            outputs(n) = named_path(path, '&output: ' // name, kind)
        end subroutine add
    end subroutine check_outputs

    !> Whether an XDMF file goes beside the HDF5 file: the scene has
    !> flexible bodies (/flexible/<name>/ in the file).
    logical function xdmf_wanted(scene)
        type(scene_input_t), intent(in) :: scene
        xdmf_wanted = len(scene%output_file) > 0 .and. scene%has_body()
    end function xdmf_wanted

    subroutine delete_file(path)
        character(len=*), intent(in) :: path
        integer :: unit, ios
        open (newunit=unit, file=path, status='old', iostat=ios)
        if (ios == 0) close (unit, status='delete')
    end subroutine delete_file
end module flexmbs_run_runner
