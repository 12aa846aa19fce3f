!> `flexmbs modes SCENE.nml [...]`: the eigen-analysis of run/modes on
!> standard output, the spectrum as PREFIX.csv and, when gnuplot is on
!> PATH, as PREFIX.png (docs/modes.md); without gnuplot the command says so
!> and succeeds. The outputs follow the rules of
!> every run (io/output_files), checked before anything is computed.
module flexmbs_app_modes_command
    use, intrinsic :: iso_fortran_env, only: output_unit
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: int_text, real_text
    use flexmbs_core_files, only: read_text_file, delete_file
    use flexmbs_core_processes, only: start_process, wait_any_process
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_io_output_files, only: named_path_t, named_path, check_output_paths, &
        output_table, output_plot, scene_inputs
    use flexmbs_io_spectrum_file, only: write_spectrum, spectrum_plot_commands
    use flexmbs_run_modes, only: modes_options_t, modes_result_t, analyse_modes, median
    use flexmbs_run_modes_report, only: modes_report
    implicit none
    private

    public :: modes_command

contains

    !> The analysis of the scene at `path`; `prefix` ('' = the scene's path
    !> without .nml, followed by _modes) names the outputs. `status` is bad
    !> input, I/O or solver failure as for `run`; `run_failed` says that
    !> the analysis stands but its BDF run failed (exit 3 all the same).
    subroutine modes_command(path, options, prefix, force, status, run_failed)
        character(len=*), intent(in) :: path, prefix
        type(modes_options_t), intent(in) :: options
        logical, intent(in) :: force
        type(status_t), intent(out) :: status
        logical, intent(out) :: run_failed
        type(scene_input_t) :: scene
        type(modes_result_t) :: result
        character(len=:), allocatable :: stem, csv, png
        run_failed = .false.
        call read_scene(path, scene, status)
        if (.not. status%ok()) return
        stem = prefix
        if (len(stem) == 0) then
            stem = path
            if (len(stem) > 4) then
                if (stem(len(stem) - 3:) == '.nml') stem = stem(1:len(stem) - 4)
            end if
            stem = stem // '_modes'
        end if
        csv = stem // '.csv'
        png = stem // '.png'
        call check_outputs(scene, csv, png, force, status)
        if (.not. status%ok()) return
        call analyse_modes(scene, options, result, status)
        if (.not. status%ok()) return
        write (output_unit, '(a)', advance='no') modes_report(result, options%count)
        call write_spectrum(csv, result%lambda, result%mode, status)
        if (.not. status%ok()) return
        write (output_unit, '(a)') 'spectrum: ' // csv
        call plot(result, csv, png)
        run_failed = result%has_run .and. .not. result%run_status%ok()
    end subroutine modes_command

    subroutine check_outputs(scene, csv, png, force, status)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: csv, png
        logical, intent(in) :: force
        type(status_t), intent(inout) :: status
        type(named_path_t), allocatable :: inputs(:), outputs(:)
        ! element by element: gfortran 12 leaks the components of structure
        ! constructors inside an array constructor
        allocate (outputs(2))
        outputs(1) = named_path(csv, 'modes: table', output_table)
        outputs(2) = named_path(png, 'modes: plot', output_plot)
        inputs = scene_inputs(scene)
        call check_output_paths(scene%path // ': ', outputs, inputs, force, status)
    end subroutine check_outputs

    !> gnuplot draws the PNG; without gnuplot, or without a mode to draw,
    !> the PNG is skipped and standard output says why. gnuplot's own
    !> messages go to a file beside the PNG, shown when it fails.
    subroutine plot(result, csv, png)
        type(modes_result_t), intent(in) :: result
        character(len=*), intent(in) :: csv, png
        character(len=:), allocatable :: commands, log, args(:), complaint, title
        real(wp), allocatable :: h(:)
        character(len=6), allocatable :: names(:)
        type(status_t) :: status
        integer :: pid, index, code, signo
        logical :: gone
        ! a skipped plot leaves no PNG of an earlier run beside the new table
        if (result%modes == 0) then
            write (output_unit, '(a)') 'plot: skipped (no mode to draw)'
            gone = delete_file(png)
            return
        end if
        allocate (h(0), names(0))
        if (result%has_run .and. size(result%h) > 0) then
            h = [median(result%h), maxval(result%h)]
            names = [character(len=6) :: 'median', 'max']
        end if
        title = 'flexmbs modes: ' // result%path // ' at t = ' // real_text(result%t) // ' s'
        commands = spectrum_plot_commands(csv, png, title, result%alpha, h, names, &
            maxval(abs(result%lambda)), maxval(real(result%lambda, wp)))
        log = png // '.log'
        allocate (character(len=max(len(commands), 8)) :: args(3))
        args(1) = 'gnuplot'
        args(2) = '-e'
        args(3) = commands
        call start_process(args, log, pid, status)
        if (.not. status%ok()) then
            write (output_unit, '(a)') 'plot: skipped (gnuplot not found on PATH; Debian''s &
                &gnuplot-nox has it)'
            gone = delete_file(log)
            gone = delete_file(png)
            return
        end if
        call wait_any_process([pid], -1, .false., index, code, signo)
        if (code == 0 .and. signo == 0) then
            write (output_unit, '(a)') 'plot: ' // png
        else
            call read_text_file(log, complaint, status)
            if (.not. status%ok()) complaint = ''
            write (output_unit, '(a)') 'plot: gnuplot failed (exit ' // int_text(code) // &
                '): ' // trim(complaint)
        end if
        gone = delete_file(log)
    end subroutine plot
end module flexmbs_app_modes_command
