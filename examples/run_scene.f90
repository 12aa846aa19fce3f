!> A scene run from a program: read a scene file (by default the rigid link
!> carrying a soft bar, inputs/rigid_flexible_pendulum.nml), change what the
!> program wants — here the end time and the output file — and run it as
!> `flexmbs run` would. The result file names its bodies and joints
!> (examples/plot_result.py plots them).
!>
!>   gfortran run_scene.f90 $(pkg-config --cflags --libs flexmbs)
!>   ./a.out [SCENE.nml [RESULT.h5]]
program run_scene_example
    use flexmbs
    implicit none
    type(scene_input_t) :: scene
    type(run_result_t) :: result
    type(status_t) :: status
    character(len=512) :: path, output

    path = 'inputs/rigid_flexible_pendulum.nml'
    output = 'rigid_flexible.h5'
    if (command_argument_count() >= 1) call get_command_argument(1, path)
    if (command_argument_count() >= 2) call get_command_argument(2, output)
    call read_scene(trim(path), scene, status)
    if (.not. status%ok()) then
        write (*, '(a)') status%text()
        error stop 2
    end if
    scene%t_end = scene%t_start + 0.1_wp   ! the first tenth of a second
    scene%output_file = trim(output)
    scene%progress = .false.
    call run_scene(scene, .true., result, status, force=.true.)
    if (.not. status%ok()) then
        write (*, '(a)') status%text()
        error stop 3
    end if
    write (*, '(a)') result%solver_name // ': ' // result%stats%summary()
    write (*, '(a,f6.3,a)', advance='no') 'at t = ', result%t, ' s:' // new_line('a')
    write (*, '(a)', advance='no') result%summary
    write (*, '(a)') 'written: ' // trim(output)
end program run_scene_example
