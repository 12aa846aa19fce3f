!> The grid of a study (`flexmbs sweep`): its points in the order of the
!> table, how a job array's tasks share them (`--slurm --chunk K`), and
!> lists of point numbers as text ('2-4,7', Slurm's `--array` syntax).
module flexmbs_run_study_grid
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_run_catalogue, only: solver_projects, solver_pmax_grid, problem_stabilisations
    use flexmbs_io_namelist, only: study_input_t, scene_input_t
    implicit none
    private

    !> One point of a sweep's grid: its coordinates.
    type, public :: sweep_point_t
        character(len=32) :: solver = '', stab = ''
        real(wp) :: tol = 0.0_wp
        integer :: pmax = 5
        character(len=32) :: source = '' !! derivatives ('' for scenes without constraints)
    end type sweep_point_t

    public :: sweep_points, array_spec, array_task_count, task_first_points, task_last_point, &
        point_list_text

contains

    !> The grid of a study, in the order of the table: solvers, then
    !> stabilisations, tolerances, p_max (DDASSL), derivative sources.
    subroutine sweep_points(study, base, points)
        type(study_input_t), intent(in) :: study
        type(scene_input_t), intent(in) :: base
        type(sweep_point_t), allocatable, intent(out) :: points(:)
        character(len=32), allocatable :: stabs(:), sources(:)
        character(len=:), allocatable :: solver
        integer :: is, ib, it, ip, id, np
        stabs = [character(len=32) :: '-']
        sources = [character(len=32) :: '']
        if (problem_stabilisations(base%problem)) then
            stabs = [character(len=32) :: study%stabilisations]
            sources = [character(len=32) :: study%derivatives]
        end if
        allocate (points(0))
        do is = 1, size(study%solvers)
            solver = trim(study%solvers(is))
            do ib = 1, size(stabs)
                ! a solver that projects by itself (MEXAX): once per tolerance
                if (solver_projects(solver) .and. ib > 1) exit
                do it = 1, size(study%tolerances)
                    np = merge(size(study%pmax), 1, solver_pmax_grid(solver))
                    do ip = 1, np
                        do id = 1, size(sources)
                            points = [points, sweep_point_t(solver, stabs(ib), &
                                study%tolerances(it), study%pmax(ip), sources(id))]
                        end do
                    end do
                end do
            end do
        end do
    end subroutine sweep_points

    ! A job array's task is numbered by the first point it runs and runs
    ! `chunk` consecutive points from there: the array of n points in
    ! chunks of k is Slurm's 1-n:k (tasks 1, 1 + k, 1 + 2k, ...), and a
    ! point can be run again alone as the task of its own number.

    !> Slurm's `--array` value for `npoints` points in tasks of `chunk`.
    pure function array_spec(npoints, chunk) result(spec)
        integer, intent(in) :: npoints, chunk
        character(len=:), allocatable :: spec
        if (npoints == 1) then
            spec = '1'
        else if (chunk <= 1) then
            spec = '1-' // int_text(npoints)
        else
            spec = '1-' // int_text(npoints) // ':' // int_text(chunk)
        end if
    end function array_spec

    !> The number of tasks of that array.
    pure integer function array_task_count(npoints, chunk) result(n)
        integer, intent(in) :: npoints, chunk
        n = (npoints + max(chunk, 1) - 1) / max(chunk, 1)
    end function array_task_count

    !> The task numbers (each its first point) of that array.
    pure function task_first_points(npoints, chunk) result(first)
        integer, intent(in) :: npoints, chunk
        integer, allocatable :: first(:)
        integer :: i
        first = [(1 + (i - 1) * max(chunk, 1), i=1, array_task_count(npoints, chunk))]
    end function task_first_points

    !> The last point of the task `first` that runs `chunk` points.
    pure integer function task_last_point(first, chunk, npoints) result(last)
        integer, intent(in) :: first, chunk, npoints
        last = min(first + max(chunk, 1) - 1, npoints)
    end function task_last_point

    !> Ascending point numbers as ranges and single numbers: '2-4,7'.
    pure function point_list_text(list) result(text)
        integer, intent(in) :: list(:)
        character(len=:), allocatable :: text
        integer :: i, j
        text = ''
        i = 1
        do while (i <= size(list))
            j = i
            do while (j < size(list))
                if (list(j + 1) /= list(j) + 1) exit
                j = j + 1
            end do
            if (len(text) > 0) text = text // ','
            text = text // int_text(list(i))
            if (j > i) text = text // '-' // int_text(list(j))
            i = j + 1
        end do
    end function point_list_text
end module flexmbs_run_study_grid
