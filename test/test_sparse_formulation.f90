!> The sparse path of the formulations (flexmbs_mbs_formulation_sparse) on
!> the example scenes with flexible bodies and chains: the same F, ∂F/∂y
!> and DAE mass matrix as the dense path to round-off, for every
!> formulation and both layouts; ∂F/∂y against central differences of F;
!> and every solver's trajectory with sparse and dense linear algebra the
!> same to well within the tolerance, with the same step counts up to a
!> few per cent (pivot orders differ at round-off level).
module test_sparse_formulation
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: real_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_formulation, only: formulation_t, block_q
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_run_problem_factory, only: build_problem, block_spec_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_sparse_formulation

    character(len=*), parameter :: scenes(*) = [character(len=40) :: &
        'inputs/flexible_cantilever.nml', 'inputs/rigid_flexible_pendulum.nml', 'inputs/face_hinge.nml', &
        'inputs/five_body.nml', 'inputs/four_bar_chain.nml', 'inputs/four_bar.nml', &
        'inputs/four_bar_chains.nml']
    character(len=*), parameter :: forms(*) = [character(len=8) :: 'index1', 'index2', &
        'index3', 'ggl']

contains

    function collect_sparse_formulation() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('sparse_equals_dense', test_equals_dense), &
                 new_test('jacobian_vs_differences', test_differences), &
                 new_test('trajectories_sparse_vs_dense', test_trajectories), &
                 new_test('fine_five_body', test_fine), &
                 new_test('auto_klu_slender_mumps_bulky', test_auto_choice)]
    end function collect_sparse_formulation

    !> The scene at `path` with formulation `form` and linear solver `ls`
    !> built into `problem` (a formulation_t), at a state y0 + a smooth
    !> perturbation that makes every block of ∂F/∂y nonzero.
    subroutine build(error, path, form, ls, problem, mech, y)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: path, form, ls
        class(dae_problem_t), allocatable, intent(out) :: problem
        class(mechanical_problem_t), allocatable, target, intent(inout) :: mech
        real(wp), allocatable, intent(out) :: y(:)
        type(scene_input_t) :: scene
        type(block_spec_t), allocatable :: blocks(:)
        type(status_t) :: status
        integer :: i
        call read_scene(path, scene, status)
        call check(error, status%ok(), path // ': ' // status%text())
        if (allocated(error)) return
        scene%multibody%formulation = form
        if (size(scene%bodies) > 0) scene%bodies(1)%formulation = form
        scene%linear_solver = ls
        call build_problem(scene, problem, y, blocks, status, mech)
        call check(error, status%ok(), path // ' ' // form // ': ' // status%text())
        if (allocated(error)) return
        do i = 1, size(y)
            y(i) = y(i) + 1.0e-3_wp * sin(1.7_wp * i)
        end do
    end subroutine build

    !> F, ∂F/∂y and M of the sparse path equal the dense path's to round-off
    !> (relative to the largest entry), for every scene and formulation; the
    !> sparse path is taken wherever the layout allows it.
    subroutine test_equals_dense(error)
        type(error_t), allocatable, intent(out) :: error
        class(dae_problem_t), allocatable :: pd, ps
        class(mechanical_problem_t), allocatable, target :: md, ms
        real(wp), allocatable :: y(:), fd(:), fs(:), jd(:, :), js(:, :), m_d(:, :), m_s(:, :)
        type(csc_matrix_t) :: pattern, mass
        type(status_t) :: status
        integer :: s, k, n
        real(wp) :: dev
        do s = 1, size(scenes)
            do k = 1, size(forms)
                call build(error, trim(scenes(s)), trim(forms(k)), 'dense', pd, md, y)
                if (allocated(error)) return
                call build(error, trim(scenes(s)), trim(forms(k)), 'auto', ps, ms, y)
                if (allocated(error)) return
                select type (ps)
                type is (formulation_t)
                    call check(error, ps%is_sparse(), trim(scenes(s)) // ' ' // &
                        trim(forms(k)) // ': sparse path taken')
                    if (.not. ps%is_sparse()) cycle
                end select
                if (allocated(error)) return
                n = size(y)
                allocate (fd(n), fs(n), jd(n, n), js(n, n), m_d(n, n), m_s(n, n))
                call pd%rhs(0.1_wp, y, fd, status)
                call ps%rhs(0.1_wp, y, fs, status)
                call pd%jacobian_dense(0.1_wp, y, jd, status)
                call ps%jacobian_pattern(pattern, status)
                call ps%jacobian_sparse(0.1_wp, y, pattern%values, status)
                call check(error, status%ok(), 'evaluations: ' // status%text())
                if (allocated(error)) return
                call pattern%to_dense(js)
                call pd%mass_dense(m_d)
                call ps%mass_sparse(mass, status)
                call mass%to_dense(m_s)
                dev = maxval(abs(fd - fs)) / max(1.0_wp, maxval(abs(fd)))
                call check(error, dev <= 1.0e-13_wp, trim(scenes(s)) // ' ' // &
                           trim(forms(k)) // ': F sparse vs dense ' // real_text(dev))
                dev = maxval(abs(jd - js)) / max(1.0_wp, maxval(abs(jd)))
                call check(error, dev <= 1.0e-13_wp, trim(scenes(s)) // ' ' // &
                           trim(forms(k)) // ': dF/dy sparse vs dense ' // real_text(dev))
                call check(error, maxval(abs(m_d - m_s)) <= 1.0e-14_wp * maxval(abs(m_d)), &
                           trim(scenes(s)) // ' ' // trim(forms(k)) // ': mass matrix')
                deallocate (fd, fs, jd, js, m_d, m_s)
                if (allocated(error)) return
            end do
        end do
    end subroutine test_equals_dense

    !> The sparse ∂F/∂y of the face hinge (flexible body, node frame, GGL and
    !> index 1 in the acceleration layout) and of the four-bar with three
    !> chains (one of 11 coordinates) against central differences of F.
    subroutine test_differences(error)
        type(error_t), allocatable, intent(out) :: error
        class(dae_problem_t), allocatable :: ps
        class(mechanical_problem_t), allocatable, target :: ms
        real(wp), allocatable :: y(:), yp(:), fp(:), fm(:), js(:, :), jfd(:, :)
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), parameter :: delta = 1.0e-6_wp
        real(wp) :: dev
        character(len=*), parameter :: paths(2) = [character(len=28) :: &
            'inputs/face_hinge.nml', 'inputs/four_bar_chains.nml']
        integer :: k, j, n, s
        do s = 1, size(paths)
            do k = 1, size(forms)
                call build(error, trim(paths(s)), trim(forms(k)), 'auto', ps, ms, y)
                if (allocated(error)) return
                n = size(y)
                allocate (yp(n), fp(n), fm(n), js(n, n), jfd(n, n))
                call ps%jacobian_pattern(pattern, status)
                call ps%jacobian_sparse(0.1_wp, y, pattern%values, status)
                call pattern%to_dense(js)
                do j = 1, n
                    yp = y
                    yp(j) = y(j) + delta
                    call ps%rhs(0.1_wp, yp, fp, status)
                    yp(j) = y(j) - delta
                    call ps%rhs(0.1_wp, yp, fm, status)
                    jfd(:, j) = (fp - fm) / (2 * delta)
                end do
                call check(error, status%ok(), 'evaluations: ' // status%text())
                if (allocated(error)) return
                dev = maxval(abs(js - jfd)) / maxval(abs(jfd))
                print '(4x,a,1x,a,a,es9.2)', trim(paths(s)), trim(forms(k)), &
                    ': sparse dF/dy vs differences ', dev
                call check(error, dev <= 1.0e-6_wp, trim(paths(s)) // ' ' // trim(forms(k)) // &
                           ': sparse dF/dy vs differences ' // real_text(dev))
                deallocate (yp, fp, fm, js, jfd)
                if (allocated(error)) return
            end do
        end do
    end subroutine test_differences

    !> Every solver, sparse ('auto'; 'mumps' for RADAU5 and DDASSL) against
    !> dense: end states equal to well within the tolerance (relative to the
    !> state's scale), step counts within 5 % (plus one step).
    subroutine test_trajectories(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: solvers(*) = [character(len=8) :: 'radau5', 'ddassl', &
            'ida', 'mexax']
        character(len=*), parameter :: files(*) = [character(len=40) :: &
            'inputs/flexible_cantilever.nml', 'inputs/rigid_flexible_pendulum.nml', &
            'inputs/face_hinge.nml', 'inputs/five_body.nml', 'inputs/four_bar.nml']
        real(wp), parameter :: t_ends(*) = [0.05_wp, 0.05_wp, 0.05_wp, 0.05_wp, 0.2_wp]
        real(wp), parameter :: tol = 1.0e-6_wp
        type(run_result_t) :: rd, rs
        integer :: f, k
        real(wp) :: dev
        do f = 1, size(files)
            do k = 1, size(solvers)
                call run(error, trim(files(f)), trim(solvers(k)), 'dense', t_ends(f), rd)
                if (allocated(error)) return
                call run(error, trim(files(f)), trim(solvers(k)), 'auto', t_ends(f), rs)
                if (allocated(error)) return
                dev = maxval(abs(rd%y(rd%q_first:rd%q_last) - rs%y(rs%q_first:rs%q_last))) &
                    / max(1.0_wp, maxval(abs(rd%y(rd%q_first:rd%q_last))))
                call check(error, dev <= 0.1_wp * tol, trim(files(f)) // ' ' // &
                           trim(solvers(k)) // ': positions sparse vs dense ' // real_text(dev))
                call check(error, abs(rd%stats%nst - rs%stats%nst) <= 1 + rd%stats%nst / 20, &
                           trim(files(f)) // ' ' // trim(solvers(k)) // ': NST sparse vs dense ' // &
                           real_text(real(rs%stats%nst - rd%stats%nst, wp)))
                if (allocated(error)) return
                ! MUMPS (RADAU5 and DDASSL take it; IDA keeps SUNDIALS' KLU, MEXAX KLU)
                if (k > 2) cycle
                call run(error, trim(files(f)), trim(solvers(k)), 'mumps', t_ends(f), rs)
                if (allocated(error)) return
                dev = maxval(abs(rd%y(rd%q_first:rd%q_last) - rs%y(rs%q_first:rs%q_last))) &
                    / max(1.0_wp, maxval(abs(rd%y(rd%q_first:rd%q_last))))
                call check(error, dev <= 0.1_wp * tol .and. &
                           abs(rd%stats%nst - rs%stats%nst) <= 1 + rd%stats%nst / 20, &
                           trim(files(f)) // ' ' // trim(solvers(k)) // ': MUMPS vs dense ' // &
                           real_text(dev))
                if (allocated(error)) return
            end do
        end do
    contains
        subroutine run(error, path, solver, ls, t_end, result)
            type(error_t), allocatable, intent(inout) :: error
            character(len=*), intent(in) :: path, solver, ls
            real(wp), intent(in) :: t_end
            type(run_result_t), intent(out) :: result
            type(scene_input_t) :: scene
            type(status_t) :: status
            call read_scene(path, scene, status)
            call check(error, status%ok(), path // ': ' // status%text())
            if (allocated(error)) return
            scene%output_file = ''
            scene%progress = .false.
            scene%solver_name = solver
            scene%rtol = tol
            scene%atol = tol
            scene%t_end = t_end
            scene%linear_solver = ls
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), path // ' ' // solver // ' ' // ls // ': ' // &
                       status%text())
        end subroutine run
    end subroutine test_trajectories

    !> inputs/five_body_fine.nml (2268 FE coordinates): built on the sparse
    !> path, its Jacobian checked column-wise against differences of F on a
    !> sample of columns, and a few RADAU5 steps run.
    subroutine test_fine(error)
        type(error_t), allocatable, intent(out) :: error
        class(dae_problem_t), allocatable :: ps
        class(mechanical_problem_t), allocatable, target :: ms
        type(scene_input_t) :: scene
        type(run_result_t) :: result
        type(csc_matrix_t) :: pattern
        type(status_t) :: status
        real(wp), allocatable :: y(:), yp(:), fp(:), fm(:), col(:)
        real(wp), parameter :: delta = 1.0e-6_wp
        real(wp) :: dev
        integer :: j, k, n
        integer(8) :: p
        call build(error, 'inputs/five_body_fine.nml', 'ggl', 'auto', ps, ms, y)
        if (allocated(error)) return
        n = size(y)
        select type (ps)
        type is (formulation_t)
            call check(error, ps%is_sparse() .and. ps%block_size(block_q) == 4 * 7 + 2 + 3 * 756, &
                       'fine five-body: sparse, 2268 FE coordinates')
        end select
        if (allocated(error)) return
        call ps%jacobian_pattern(pattern, status)
        call ps%jacobian_sparse(0.1_wp, y, pattern%values, status)
        call check(error, real(pattern%nnz, wp) < 0.01_wp * real(n, wp)**2, &
                   'fine five-body: dF/dy has under 1 % nonzeros')
        allocate (yp(n), fp(n), fm(n), col(n))
        dev = 0.0_wp
        do k = 1, 25
            j = 1 + mod(k * 977, n)
            yp = y
            yp(j) = y(j) + delta
            call ps%rhs(0.1_wp, yp, fp, status)
            yp(j) = y(j) - delta
            call ps%rhs(0.1_wp, yp, fm, status)
            col = 0.0_wp
            do p = pattern%colptr(j) + 1, pattern%colptr(j + 1)
                col(pattern%rowind(p) + 1) = pattern%values(p)
            end do
            dev = max(dev, maxval(abs(col - (fp - fm) / (2 * delta))) &
                      / max(1.0_wp, maxval(abs(col))))
        end do
        call check(error, status%ok() .and. dev <= 1.0e-5_wp, &
                   'fine five-body: sampled Jacobian columns vs differences ' // real_text(dev))
        if (allocated(error)) return
        call read_scene('inputs/five_body_fine.nml', scene, status)
        scene%output_file = ''
        scene%progress = .false.
        scene%t_end = 2.0e-3_wp
        call run_scene(scene, .true., result, status)
        call check(error, status%ok() .and. result%t == scene%t_end, &
                   'fine five-body: RADAU5 steps: ' // status%text())
    end subroutine test_fine

    !> `linear_solver = 'auto'` on the formulations' iteration matrices: KLU
    !> for the five-body scene with the fine coupler mesh (slender, predicted
    !> fill ~5), MUMPS for a bulky hex8 cube of 12 x 12 x 12 elements clamped
    !> on one face (predicted fill ~13), as the measurements behind
    !> auto_mumps_min_fill say.
    subroutine test_auto_choice(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=:), allocatable :: chosen
        call choice('inputs/five_body_fine.nml', .false., chosen)
        call check(error, chosen == 'klu', "fine five-body: 'auto' chose " // chosen)
        call choice('inputs/flexible_cantilever.nml', .true., chosen)
        call check(error, chosen == 'mumps', "12^3 cube: 'auto' chose " // chosen)
    contains
        subroutine choice(path, cube, name)
            character(len=*), intent(in) :: path
            logical, intent(in) :: cube
            character(len=:), allocatable, intent(out) :: name
            type(scene_input_t) :: scene
            class(dae_problem_t), allocatable :: problem
            class(mechanical_problem_t), allocatable, target :: mech
            class(linear_solver_t), allocatable :: solver
            type(block_spec_t), allocatable :: blocks(:)
            type(matrix_t) :: jac, mass
            type(status_t) :: status
            real(wp), allocatable :: y(:)
            name = 'none'
            call read_scene(path, scene, status)
            if (cube) then
                scene%bodies(1)%divisions = [12, 12, 12]
                scene%bodies(1)%lengths = [0.4_wp, 0.4_wp, 0.4_wp]
            end if
            call build_problem(scene, problem, y, blocks, status, mech)
            call check(error, status%ok(), path // ': ' // status%text())
            if (allocated(error)) return
            jac%storage = storage_sparse
            jac%n = problem%n
            call problem%jacobian_pattern(jac%csc, status)
            mass%storage = storage_sparse
            mass%n = problem%n
            call problem%mass_sparse(mass%csc, status)
            call new_linear_solver('auto', problem%n, storage_sparse, solver, status, &
                                   mass=mass, jac=jac)
            call check(error, status%ok(), path // ': ' // status%text())
            if (allocated(error)) return
            name = solver%name()
        end subroutine choice
    end subroutine test_auto_choice
end module test_sparse_formulation
