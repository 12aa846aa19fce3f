!> `flexmbs-bench-newton SCENE.nml [FORMULATION]`: the Newton matrices of a
!> mechanical scene's formulation, full (c M − ∂F/∂y as it stands) against
!> condensed (docs/theory.md §3.7), each with KLU (AMD and nested
!> dissection) and MUMPS: one row per path and LU with the order, the
!> nonzeros of the matrix and of its LU factors, and the CPU seconds of the
!> analysis, of a real and a complex factorisation and of a real and a
!> complex solve (best of 3), at the scene's consistent initial state with
!> c = γ/h for h = 1e-3 (RADAU5's real shift) and (α + iβ)/h. Also what
!> `linear_solver = 'auto'` picks on each path. FORMULATION overrides the
!> scene's (index1, index2, index3, ggl). Figures, not tests.
program flexmbs_bench_newton
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_timer, only: timer_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_linalg_klu_solver, only: klu_solver_t
    use flexmbs_linalg_mumps_solver, only: mumps_solver_t
    use flexmbs_linalg_klu, only: klu_part_real
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_mbs_condensed_newton, only: condensed_solver_t
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_run_problem_factory, only: build_problem, block_spec_t
    implicit none
    real(wp), parameter :: h = 1.0e-3_wp
    real(wp), parameter :: gamma = 3.637834252744495_wp
    complex(wp), parameter :: zc = cmplx(2.681082873627752_wp, 3.050430199247410_wp, &
        kind=wp) / h
    integer, parameter :: repeats = 3
    character(len=512) :: path
    character(len=16) :: form
    type(scene_input_t) :: scene
    class(dae_problem_t), allocatable :: problem
    class(mechanical_problem_t), allocatable, target :: mech
    type(block_spec_t), allocatable :: blocks(:)
    type(status_t) :: status
    type(matrix_t) :: jac, mass
    real(wp), allocatable :: y0(:)
    character(len=*), parameter :: paths(2) = ['full     ', 'condensed']
    character(len=*), parameter :: lus(4) = ['klu   ', 'klu-nd', 'mumps ', 'auto  ']
    integer :: p, l

    if (command_argument_count() < 1) then
        write (*, '(a)') 'usage: flexmbs-bench-newton SCENE.nml [index1|index2|index3|ggl]'
        error stop 2
    end if
    call get_command_argument(1, path)
    call read_scene(trim(path), scene, status)
    if (.not. status%ok()) call fail(status%text())
    if (command_argument_count() >= 2) then
        call get_command_argument(2, form)
        scene%multibody%formulation = form
        if (size(scene%bodies) > 0) scene%bodies(1)%formulation = form
    end if
    scene%linear_solver = 'auto'
    call build_problem(scene, problem, y0, blocks, status, mech)
    if (.not. status%ok()) call fail(status%text())
    jac%n = problem%n
    jac%storage = storage_sparse
    call problem%jacobian_pattern(jac%csc, status)
    call problem%jacobian_sparse(scene%t_start, y0, jac%csc%values, status)
    mass%n = problem%n
    mass%storage = storage_sparse
    call problem%mass_sparse(mass%csc, status)
    if (.not. status%ok()) call fail(status%text())
    print '(a,a,a,i0,a,i0)', 'newton ', trim(path), ': n = ', problem%n, ', nnz(dF/dy) = ', &
        jac%csc%nnz
    print '(a)', 'newton path      asked  used              order      nnz(A)   nnz(L+U) ' // &
        'analyse[s] factor_r[s] factor_c[s] solve_r[s] solve_c[s]'
    do p = 1, size(paths)
        do l = 1, size(lus)
            call measure(trim(paths(p)), trim(lus(l)))
        end do
    end do

contains

    subroutine fail(text)
        character(len=*), intent(in) :: text
        write (*, '(a)') 'flexmbs-bench-newton: ' // text
        error stop 1
    end subroutine fail

    !> One row: path 'full' or 'condensed', lu 'klu', 'klu-nd', 'mumps', 'auto'.
    subroutine measure(which, lu)
        character(len=*), intent(in) :: which, lu
        class(linear_solver_t), allocatable :: solver
        type(dae_options_t) :: options
        type(timer_t) :: timer
        real(wp) :: t_analyse, t_real, t_complex, t_solve_r, t_solve_c
        real(wp), allocatable :: b(:)
        complex(wp), allocatable :: zb(:)
        integer(i8) :: order, nnz_a, nnz_lu
        character(len=24) :: name
        integer :: k, i
        options%linear_solver = lu
        options%sparse_ordering = 'auto'
        if (lu == 'klu-nd') then
            options%linear_solver = 'klu'
            options%sparse_ordering = 'nd'
        end if
        options%newton_system = which
        if (which == 'condensed') then
            call problem%iteration_solver(options, solver, status)
            if (.not. allocated(solver)) call fail('no condensed Newton system offered')
        else
            call new_linear_solver(options%linear_solver, problem%n, storage_sparse, solver, &
                status, ordering=options%sparse_ordering, mass=mass, jac=jac)
        end if
        if (.not. status%ok()) call fail(status%text())
        call timer%start()
        call solver%init(mass, jac, status)
        t_analyse = timer%cpu()
        if (.not. status%ok()) call fail(which // ' ' // lu // ': ' // status%text())
        allocate (b(problem%n), zb(problem%n))
        t_real = huge(1.0_wp)
        t_complex = huge(1.0_wp)
        t_solve_r = huge(1.0_wp)
        t_solve_c = huge(1.0_wp)
        do k = 1, repeats
            call timer%start()
            call solver%factor_real(gamma / h, mass, jac, status)
            t_real = min(t_real, timer%cpu())
            call timer%start()
            call solver%factor_complex(zc, mass, jac, status)
            t_complex = min(t_complex, timer%cpu())
            if (.not. status%ok()) call fail(which // ' ' // lu // ': ' // status%text())
            do i = 1, problem%n
                b(i) = sin(1.3_wp * i)
            end do
            zb = b
            call timer%start()
            call solver%solve_real(b)
            t_solve_r = min(t_solve_r, timer%cpu())
            call timer%start()
            call solver%solve_complex(zb)
            t_solve_c = min(t_solve_c, timer%cpu())
        end do
        name = solver%name()
        order = problem%n
        nnz_a = 0
        nnz_lu = 0
        select type (solver)
        type is (condensed_solver_t)
            order = solver%order()
            nnz_a = solver%nonzeros()
            nnz_lu = solver%factor_nonzeros()
            if (lu == 'auto') print '(a,i0,a,i0)', 'newton condensed: positions eliminated ', &
                solver%eliminated(), ', the largest kinematic block with a dense LU ', &
                solver%largest_block()
        type is (klu_solver_t)
            nnz_a = solver%nonzeros()
            nnz_lu = solver%factor_nonzeros()
        type is (mumps_solver_t)
            nnz_a = solver%nonzeros()
            nnz_lu = solver%factor_nonzeros()
        end select
        print '(a,a10,1x,a6,1x,a17,i8,2i12,5es11.3)', 'newton ', which, lu, name, order, &
            nnz_a, nnz_lu, t_analyse, t_real, t_complex, t_solve_r, t_solve_c
    end subroutine measure
end program flexmbs_bench_newton
