!> The catalogue: every solver and every problem a scene or study can name,
!> with what each can do. It is the one place that knows their names (the
!> scene schema offers `solver_choices` and `problem_choices` from here);
!> everything else asks it by capability, never by name. It depends on
!> nothing, so the input checks consult it too; the factories that build a
!> named solver or problem are run/solver_factory and run/problem_factory.
module flexmbs_run_catalogue
    implicit none
    private

    !> Solvers, in the order of the catalogue (and of a study's default grid).
    integer, parameter, public :: solver_radau5 = 1, solver_ddassl = 2, solver_ida = 3, &
        solver_mexax = 4

    !> One solver of the catalogue: its name in scenes, a one-line description
    !> and the capabilities that the run and study layers ask about.
    type, public :: solver_info_t
        character(len=8) :: name = ''
        character(len=64) :: doc = ''
        !> integrates the mechanical form itself, y = (q, v, λ) (MEXAX): a
        !> problem without one cannot be given to it
        logical :: mechanical_only = .false.
        !> projects onto the constraints itself: a study runs it once per
        !> tolerance, not once per stabilisation
        logical :: projects = .false.
        !> a study runs it at every p_max of its grid (the paper's Table 2)
        logical :: pmax_grid = .false.
        !> largest p_max it accepts (0: no limit beyond the schema's)
        integer :: max_order = 0
        !> offers the band LU
        logical :: band = .false.
    end type solver_info_t

    type(solver_info_t), parameter, public :: solvers(4) = [ &
        solver_info_t('radau5', 'Radau IIA of order 5 (Hairer-Wanner)', band=.true.), &
        solver_info_t('ddassl', 'BDF of orders 1-5 (Petzold)', pmax_grid=.true., &
            max_order=5, band=.true.), &
        solver_info_t('ida', 'BDF of orders 1-5 (SUNDIALS IDA)'), &
        solver_info_t('mexax', 'extrapolated half-explicit Euler (Lubich et al.)', &
            mechanical_only=.true., projects=.true.)]

    !> The admissible solver names, as the scene schema lists choices.
    character(len=*), parameter, public :: solver_choices = 'radau5|ddassl|ida|mexax'

    !> Problems.
    integer, parameter, public :: problem_van_der_pol = 1, problem_pendulum = 2, &
        problem_robertson = 3, problem_brusselator_1d = 4, problem_brusselator_2d = 5, &
        problem_flexible_body = 6, problem_multibody = 7, problem_rigid_chain = 8

    !> One problem of the catalogue: its name in scenes and what it offers
    !> (a mechanical form, bodies to draw, stabilisations to vary).
    type, public :: problem_info_t
        character(len=16) :: name = ''
        !> has a mechanical form (q, v, λ) that a mechanical_only solver integrates
        logical :: mechanical = .false.
        !> has bodies to draw (ParaView output)
        logical :: bodies = .false.
        !> a study varies its stabilisation (none, ggl, projection) and its
        !> constraint derivatives
        logical :: stabilisations = .false.
    end type problem_info_t

    type(problem_info_t), parameter, public :: problems(8) = [ &
        problem_info_t('van_der_pol'), &
        problem_info_t('pendulum', mechanical=.true.), &
        problem_info_t('robertson'), &
        problem_info_t('brusselator_1d'), &
        problem_info_t('brusselator_2d'), &
        problem_info_t('flexible_body', mechanical=.true., bodies=.true.), &
        problem_info_t('multibody', mechanical=.true., bodies=.true., stabilisations=.true.), &
        problem_info_t('rigid_chain', mechanical=.true.)]

    character(len=*), parameter, public :: problem_choices = 'van_der_pol|pendulum|&
        &robertson|brusselator_1d|brusselator_2d|flexible_body|multibody|rigid_chain'

    public :: solver_id, solver_info, problem_id, problem_info, mechanical_problem_names, &
        band_solver_names, solver_projects, solver_pmax_grid, solver_mechanical_only, &
        problem_stabilisations, pmax_grid_solver

contains

    !> The number of the solver named `name` (case and blanks as stored by
    !> the reader: lower case, trailing blanks ignored); 0 when unknown.
    pure integer function solver_id(name) result(id)
        character(len=*), intent(in) :: name
        do id = 1, size(solvers)
            if (trim(solvers(id)%name) == trim(adjustl(name))) return
        end do
        id = 0
    end function solver_id

    !> What the solver named `name` can do; an empty name when unknown.
    pure function solver_info(name) result(info)
        character(len=*), intent(in) :: name
        type(solver_info_t) :: info
        integer :: id
        id = solver_id(name)
        if (id > 0) info = solvers(id)
    end function solver_info

    !> The index of problem `name` in `problems` (leading blanks ignored), 0 when
    !> there is none.
    pure integer function problem_id(name) result(id)
        character(len=*), intent(in) :: name
        do id = 1, size(problems)
            if (trim(problems(id)%name) == trim(adjustl(name))) return
        end do
        id = 0
    end function problem_id

    !> The catalogue's entry of problem `name`; the default entry (no name, no
    !> capabilities) for an unknown name.
    pure function problem_info(name) result(info)
        character(len=*), intent(in) :: name
        type(problem_info_t) :: info
        integer :: id
        id = problem_id(name)
        if (id > 0) info = problems(id)
    end function problem_info

    !> Capabilities by name (false for an unknown name), for conditions.
    pure logical function solver_projects(name)
        character(len=*), intent(in) :: name
        type(solver_info_t) :: info
        info = solver_info(name)
        solver_projects = info%projects
    end function solver_projects

    !> True when a study runs the solver at every p_max of its grid.
    pure logical function solver_pmax_grid(name)
        character(len=*), intent(in) :: name
        type(solver_info_t) :: info
        info = solver_info(name)
        solver_pmax_grid = info%pmax_grid
    end function solver_pmax_grid

    !> The first solver with a p_max grid (a BDF code whose largest order a
    !> study varies, as the paper's Table 2 does): `flexmbs modes` checks its
    !> steps against the A(α) sectors (run/modes).
    pure function pmax_grid_solver() result(name)
        character(len=:), allocatable :: name
        integer :: id
        do id = 1, size(solvers)
            if (.not. solvers(id)%pmax_grid) cycle
            name = trim(solvers(id)%name)
            return
        end do
        name = ''
    end function pmax_grid_solver

    !> True when the solver integrates only mechanical forms (MEXAX).
    pure logical function solver_mechanical_only(name)
        character(len=*), intent(in) :: name
        type(solver_info_t) :: info
        info = solver_info(name)
        solver_mechanical_only = info%mechanical_only
    end function solver_mechanical_only

    !> True when a study varies the problem's stabilisation and constraint
    !> derivatives (false for an unknown name).
    pure logical function problem_stabilisations(name)
        character(len=*), intent(in) :: name
        type(problem_info_t) :: info
        info = problem_info(name)
        problem_stabilisations = info%stabilisations
    end function problem_stabilisations

    !> The names of the problems with a mechanical form, quoted and joined
    !> for a message: 'pendulum', 'flexible_body', ... or 'rigid_chain'.
    function mechanical_problem_names() result(text)
        character(len=:), allocatable :: text
        character(len=len(problems%name)) :: names(size(problems))
        logical :: chosen(size(problems))
        names = problems%name
        chosen = problems%mechanical
        text = joined(names, chosen, '''', ' or ')
    end function mechanical_problem_names

    !> The solvers that offer the band LU, for a message: radau5 and ddassl.
    function band_solver_names() result(text)
        character(len=:), allocatable :: text
        character(len=len(solvers%name)) :: names(size(solvers))
        logical :: chosen(size(solvers))
        names = solvers%name
        chosen = solvers%band
        text = joined(names, chosen, '', ' and ')
    end function band_solver_names

    !> The names where `chosen`, each in `quote`s, joined by ', ' and
    !> `last` before the last one.
    function joined(names, chosen, quote, last) result(text)
        character(len=*), intent(in) :: names(:), quote, last
        logical, intent(in) :: chosen(:)
        character(len=:), allocatable :: text
        integer :: k, seen, n
        text = ''
        n = count(chosen)
        seen = 0
        do k = 1, size(names)
            if (.not. chosen(k)) cycle
            seen = seen + 1
            if (seen == n .and. n > 1) then
                text = text // last
            else if (seen > 1) then
                text = text // ', '
            end if
            text = text // quote // trim(names(k)) // quote
        end do
    end function joined
end module flexmbs_run_catalogue
