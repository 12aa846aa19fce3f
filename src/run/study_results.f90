!> Where a study's runs keep their results between processes: the results
!> folder `<study stem>_points/`, beside the study's table when it names
!> one, else beside the study file (inputs/paper/q.nml, no table:
!> inputs/paper/q_points/). In it:
!>
!>   point_K.rec     grid point K's record (run/study_record), written whole
!>                   or not at all
!>   point_K.log     what `sweep -j N`'s process of point K printed
!>   point_K.h5      grid point K's HDF5 result while it runs, with its
!>                   checkpoints: a point stopped by a signal (a Slurm
!>                   task's time limit) resumes from it; deleted (with its
!>                   .xdmf) once the point's record is written
!>   array.sbatch    the job array of `sweep --slurm`; merge.sbatch its merge job
!>   slurm_J_K.out   what task K of Slurm job J printed; slurm_merge_J.out
!>                   the merge job's
module flexmbs_run_study_results
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t
    use flexmbs_core_files, only: make_folder
    use flexmbs_io_namelist, only: study_input_t
    implicit none
    private

    public :: results_folder, make_results_folder, record_path, log_path, array_script_path, &
        merge_script_path, point_result_path

contains

    !> The study's results folder (module header), without a trailing '/'.
    function results_folder(study) result(folder)
        type(study_input_t), intent(in) :: study
        character(len=:), allocatable :: folder
        character(len=:), allocatable :: name
        integer :: slash, dot
        slash = index(study%path, '/', back=.true.)
        name = study%path(slash + 1:)
        dot = index(name, '.', back=.true.)
        if (dot > 1) name = name(1:dot - 1)
        if (len(study%table) > 0) then
            folder = study%table(1:index(study%table, '/', back=.true.)) // name // '_points'
        else
            folder = study%path(1:slash) // name // '_points'
        end if
    end function results_folder

    !> The results folder, created when missing (its parent must exist).
    subroutine make_results_folder(study, folder, status)
        type(study_input_t), intent(in) :: study
        character(len=:), allocatable, intent(out) :: folder
        type(status_t), intent(out) :: status
        folder = results_folder(study)
        call make_folder(folder, status)
    end subroutine make_results_folder

    !> Point k's record in `folder`.
    pure function record_path(folder, k) result(path)
        character(len=*), intent(in) :: folder
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = folder // '/point_' // int_text(k) // '.rec'
    end function record_path

    !> Point k's HDF5 result in `folder` while it runs (module header).
    pure function point_result_path(folder, k) result(path)
        character(len=*), intent(in) :: folder
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = folder // '/point_' // int_text(k) // '.h5'
    end function point_result_path

    !> The output of point k's process in `folder`.
    pure function log_path(folder, k) result(path)
        character(len=*), intent(in) :: folder
        integer, intent(in) :: k
        character(len=:), allocatable :: path
        path = folder // '/point_' // int_text(k) // '.log'
    end function log_path

    !> FOLDER/array.sbatch: the script of the Slurm array job that
    !> `sweep --slurm` writes into the study's results folder.
    pure function array_script_path(folder) result(path)
        character(len=*), intent(in) :: folder
        character(len=:), allocatable :: path
        path = folder // '/array.sbatch'
    end function array_script_path

    !> FOLDER/merge.sbatch: the script of the merge job (`sweep STUDY --merge`,
    !> after the array job) in the study's results folder.
    pure function merge_script_path(folder) result(path)
        character(len=*), intent(in) :: folder
        character(len=:), allocatable :: path
        path = folder // '/merge.sbatch'
    end function merge_script_path
end module flexmbs_run_study_results
