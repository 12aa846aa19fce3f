!> The condensed Newton systems (flexmbs_mbs_condensed_newton, docs/theory.md
!> §3.7) against the full iteration matrix A = c M_dae − J they condense:
!> for the example scenes (rigid bodies with quaternions, node frames, set
!> markers, chains, flexible bodies), every formulation and both layouts,
!> at states with nonzero accelerations, multipliers λ and GGL's μ (along a
!> trajectory μ → 0, which would hide a dropped term), real and complex c:
!> the solutions of random right-hand sides agree with KLU's solution of A
!> to round-off, and their backward error in A is at round-off level.
module test_condensed_newton
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: real_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_formulation, only: block_q, block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index1, &
        formulation_index2, formulation_index3, formulation_ggl
    use flexmbs_mbs_condensed_newton, only: condensed_solver_t
    use flexmbs_io_namelist, only: scene_input_t, read_scene
    use flexmbs_dae_solver_setting, only: solver_setting_t
    use flexmbs_run_runner, only: run_result_t, run_scene
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_run_problem_factory, only: build_problem, block_spec_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_condensed_newton

    character(len=*), parameter :: scenes(*) = [character(len=40) :: &
        'inputs/five_body.nml', 'inputs/four_bar_chains.nml', &
        'inputs/rigid_flexible_pendulum.nml', 'inputs/two_soft_links.nml', &
        'inputs/arm_with_pad.nml', 'inputs/face_hinge.nml', 'inputs/four_bar.nml', &
        'inputs/flexible_cantilever.nml']
    integer, parameter :: forms(*) = [formulation_index1, formulation_index2, &
        formulation_index3, formulation_ggl]
    character(len=*), parameter :: form_names(*) = [character(len=6) :: 'index1', &
        'index2', 'index3', 'ggl']

    !> Bounds: relative difference to KLU's solution of A, and backward error
    !> ‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞) of the condensed solution. Measured:
    !> backward errors ≤ 3.3e-16 for the integrators' c, ≤ 7e-13 at the
    !> modes' small shift c = −1 with KLU (its threshold pivoting admits
    !> growth; MUMPS ≤ 2e-14 there); differences up to 3e-8 where A is
    !> ill-conditioned (index 1 and 3 at small c).
    real(wp), parameter :: max_difference = 5.0e-8_wp, max_backward = 1.0e-12_wp

contains

    function collect_condensed_newton() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('solves_equal_full_matrix', test_solves), &
                 new_test('trajectories_condensed_vs_full', test_trajectories), &
                 new_test('mexax_structured_vs_full', test_mexax_structured)]
    end function collect_condensed_newton

    !> Every scene, formulation and layout (module header).
    subroutine test_solves(error)
        type(error_t), allocatable, intent(out) :: error
        type(scene_input_t) :: scene
        class(dae_problem_t), allocatable :: built
        class(mechanical_problem_t), allocatable, target :: mech
        type(block_spec_t), allocatable :: blocks(:)
        type(formulation_t) :: f
        type(status_t) :: status
        real(wp), allocatable :: y0(:), q0(:), v0(:)
        real(wp) :: worst_difference, worst_backward
        integer :: s, k, layout
        logical :: constant_mass
        worst_difference = 0.0_wp
        worst_backward = 0.0_wp
        do s = 1, size(scenes)
            call read_scene(trim(scenes(s)), scene, status)
            call check(error, status%ok(), trim(scenes(s)) // ': ' // status%text())
            if (allocated(error)) return
            scene%linear_solver = 'auto'
            call build_problem(scene, built, y0, blocks, status, mech)
            call check(error, status%ok(), trim(scenes(s)) // ': ' // status%text())
            if (allocated(error)) return
            select type (built)
            type is (formulation_t)
                q0 = y0(built%offset(block_q) + 1:built%last(block_q))
                v0 = y0(built%offset(block_v) + 1:built%last(block_v))
                constant_mass = .not. built%accelerations
            class default
                call check(error, .false., trim(scenes(s)) // ': not a formulation')
                return
            end select
            do layout = 1, merge(2, 1, constant_mass)
                do k = 1, size(forms)
                    f = new_formulation(mech, forms(k), q0, constant_mass=layout == 2, &
                        status=status, sparse=.true.)
                    call check(error, status%ok() .and. f%is_sparse(), trim(scenes(s)) // &
                        ': formulation ' // status%text())
                    if (allocated(error)) return
                    call compare(error, f, q0, v0, trim(scenes(s)) // ' ' // &
                        trim(form_names(k)) // merge(' constant mass', ' accelerations', &
                        layout == 2), worst_difference, worst_backward)
                    if (allocated(error)) return
                end do
            end do
            deallocate (built, mech)
        end do
        print '(a,es9.2,a,es9.2)', '    condensed vs full: largest relative difference ', &
            worst_difference, ', largest backward error ', worst_backward
    end subroutine test_solves

    !> One formulation: J and M_dae at a state with nonzero a, λ, μ; the
    !> condensed solves (KLU and MUMPS on S) of A x = b against KLU's solve
    !> of the full A, for real c of a small and a large step and a complex c.
    subroutine compare(error, f, q0, v0, what, worst_difference, worst_backward)
        type(error_t), allocatable, intent(inout) :: error
        type(formulation_t), intent(inout) :: f
        real(wp), intent(in) :: q0(:), v0(:)
        character(len=*), intent(in) :: what
        real(wp), intent(inout) :: worst_difference, worst_backward
        ! RADAU5's γ and α ± iβ over h = 1e-3 and 1e-1, DDASSL's cj at h = 1e-4,
        ! the modes' default shift σ = −1
        real(wp), parameter :: cs(*) = [3.637834252744495_wp / 1.0e-3_wp, &
            3.637834252744495_wp / 0.1_wp, 2.0e4_wp, -1.0_wp]
        complex(wp), parameter :: zc = cmplx(2.681082873627752_wp, 3.050430199247410_wp, &
            kind=wp) / 1.0e-3_wp
        type(matrix_t) :: jac, mass
        class(linear_solver_t), allocatable :: full, condensed
        type(dae_options_t) :: options
        type(status_t) :: status
        real(wp), allocatable :: y(:), b(:), xf(:), xc(:)
        complex(wp), allocatable :: zb(:), zf(:), zx(:)
        character(len=5), parameter :: lus(2) = ['klu  ', 'mumps']
        integer :: n, i, l, ic
        n = f%n
        allocate (y(n), b(n), xf(n), xc(n), zb(n), zf(n), zx(n))
        y = 0.0_wp
        y(f%offset(block_q) + 1:f%last(block_q)) = q0
        y(f%offset(block_v) + 1:f%last(block_v)) = v0
        do i = 1, n
            b(i) = sin(1.3_wp * i) + 0.5_wp * cos(0.37_wp * i * i)
            zb(i) = cmplx(b(i), cos(2.1_wp * i), kind=wp)
        end do
        ! positions and velocities a little off the trajectory; a, λ, μ nonzero
        do i = 1, f%block_size(block_q) + f%block_size(block_v)
            y(i) = y(i) + 1.0e-3_wp * sin(1.7_wp * i)
        end do
        do i = f%block_size(block_q) + f%block_size(block_v) + 1, n
            y(i) = 3.0_wp * sin(0.9_wp * i) + 0.5_wp
        end do
        jac%n = n
        jac%storage = storage_sparse
        call f%jacobian_pattern(jac%csc, status)
        call f%jacobian_sparse(0.1_wp, y, jac%csc%values, status)
        mass%n = n
        mass%storage = storage_sparse
        call f%mass_sparse(mass%csc, status)
        call check(error, status%ok(), what // ': evaluation ' // status%text())
        if (allocated(error)) return
        call new_linear_solver('klu', n, storage_sparse, full, status)
        if (status%ok()) call full%init(mass, jac, status)
        call check(error, status%ok(), what // ': full KLU ' // status%text())
        if (allocated(error)) return
        do l = 1, size(lus)
            options%linear_solver = trim(lus(l))
            call f%iteration_solver(options, condensed, status)
            call check(error, allocated(condensed), what // ': no condensed solver offered')
            if (allocated(error)) return
            call condensed%init(mass, jac, status)
            call check(error, status%ok(), what // ': condensed init ' // status%text())
            if (allocated(error)) return
            select type (condensed)
            type is (condensed_solver_t)
                if (l == 1) print '(4x,a,a,i0,a,i0,a,i0,a,i0)', what, ': n = ', n, ', S ', &
                    condensed%order(), ', eliminated ', condensed%eliminated(), ', block ', &
                    condensed%largest_block()
            end select
            do ic = 1, size(cs)
                call full%factor_real(cs(ic), mass, jac, status)
                if (status%ok()) call condensed%factor_real(cs(ic), mass, jac, status)
                call check(error, status%ok(), what // ': factor ' // status%text())
                if (allocated(error)) return
                xf = b
                call full%solve_real(xf)
                xc = b
                call condensed%solve_real(xc)
                call judge(real_difference(xc, xf), real_backward(mass, jac, cs(ic), xc, b), &
                    'real c = ' // real_text(cs(ic)))
                if (allocated(error)) return
            end do
            call full%factor_complex(zc, mass, jac, status)
            if (status%ok()) call condensed%factor_complex(zc, mass, jac, status)
            call check(error, status%ok(), what // ': complex factor ' // status%text())
            if (allocated(error)) return
            zf = zb
            call full%solve_complex(zf)
            zx = zb
            call condensed%solve_complex(zx)
            call judge(maxval(abs(zx - zf)) / maxval(abs(zf)), complex_backward(mass, jac, zc, zx, zb), &
                'complex c')
            if (allocated(error)) return
            deallocate (condensed)
        end do
    contains
        subroutine judge(difference, backward, which)
            real(wp), intent(in) :: difference, backward
            character(len=*), intent(in) :: which
            worst_difference = max(worst_difference, difference)
            worst_backward = max(worst_backward, backward)
            call check(error, difference <= max_difference .and. backward <= max_backward, &
                what // ' ' // trim(lus(l)) // ', ' // which // ': difference to the full ' &
                // 'solve ' // real_text(difference) // ', backward error ' // &
                real_text(backward))
        end subroutine judge

        real(wp) function real_difference(x, ref)
            real(wp), intent(in) :: x(:), ref(:)
            real_difference = maxval(abs(x - ref)) / maxval(abs(ref))
        end function real_difference

    end subroutine compare

    !> ‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞), A = c M − J.
    real(wp) function real_backward(mass, jac, c, x, rhs)
        type(matrix_t), intent(in) :: mass, jac
        real(wp), intent(in) :: c, x(:), rhs(:)
        real(wp), allocatable :: r(:), t(:), rowsum(:)
        allocate (r(size(x)), t(size(x)))
        call mass%csc%matvec(x, r)
        call jac%csc%matvec(x, t)
        r = c * r - t - rhs
        rowsum = norm_rows(mass, jac, c)
        real_backward = maxval(abs(r)) / (maxval(rowsum) * maxval(abs(x)) + maxval(abs(rhs)))
    end function real_backward

    !> The same for A = zc M − J and complex x, b.
    real(wp) function complex_backward(mass, jac, zc, x, rhs)
        type(matrix_t), intent(in) :: mass, jac
        complex(wp), intent(in) :: zc, x(:), rhs(:)
        real(wp), allocatable :: rr(:), ri(:), t(:), rowsum(:)
        allocate (rr(size(x)), ri(size(x)), t(size(x)))
        ! (c M − J)(xr + i xi) with c = zc
        call mass%csc%matvec(real(x, wp), rr)
        call mass%csc%matvec(aimag(x), ri)
        associate (mr => rr, mi => ri)
            t = real(zc) * mr - aimag(zc) * mi
            ri = aimag(zc) * mr + real(zc) * mi
            rr = t
        end associate
        call jac%csc%matvec(real(x, wp), t)
        rr = rr - t - real(rhs, wp)
        call jac%csc%matvec(aimag(x), t)
        ri = ri - t - aimag(rhs)
        rowsum = norm_rows(mass, jac, abs(zc))
        complex_backward = maxval(sqrt(rr**2 + ri**2)) / (maxval(rowsum) * &
            maxval(abs(x)) + maxval(abs(rhs)))
    end function complex_backward

    !> Row sums of |c| |M| + |J|: ‖A‖∞ bounded by the largest.
    function norm_rows(mass, jac, c) result(rowsum)
        type(matrix_t), intent(in) :: mass, jac
        real(wp), intent(in) :: c
        real(wp), allocatable :: rowsum(:)
        integer :: j
        integer(kind(jac%csc%colptr)) :: p
        allocate (rowsum(jac%n), source=0.0_wp)
        do j = 1, jac%n
            do p = jac%csc%colptr(j) + 1, jac%csc%colptr(j + 1)
                rowsum(jac%csc%rowind(p) + 1) = rowsum(jac%csc%rowind(p) + 1) &
                    + abs(jac%csc%values(p))
            end do
            do p = mass%csc%colptr(j) + 1, mass%csc%colptr(j + 1)
                rowsum(mass%csc%rowind(p) + 1) = rowsum(mass%csc%rowind(p) + 1) &
                    + c * abs(mass%csc%values(p))
            end do
        end do
    end function norm_rows

    !> Every mechanical scene of inputs/ over a short time, RADAU5, DDASSL
    !> and IDA at TOL 1e-6 with newton_system = 'condensed' against 'full'
    !> (compare_paths).
    subroutine test_trajectories(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: files(*) = [character(len=40) :: &
            'inputs/arm_with_pad.nml', 'inputs/bushing_mount.nml', 'inputs/face_hinge.nml', &
            'inputs/five_body.nml', 'inputs/five_body_undamped.nml', &
            'inputs/five_body_fine.nml', 'inputs/five_body_fine_undamped.nml', &
            'inputs/flexible_cantilever.nml', 'inputs/four_bar.nml', &
            'inputs/four_bar_chain.nml', 'inputs/four_bar_chains.nml', &
            'inputs/rigid_flexible_pendulum.nml', 'inputs/two_soft_links.nml']
        real(wp), parameter :: t_ends(*) = [0.02_wp, 0.02_wp, 0.02_wp, 0.05_wp, 0.05_wp, &
            2.0e-3_wp, 2.0e-3_wp, 0.05_wp, 0.1_wp, 0.1_wp, 0.1_wp, 0.05_wp, 0.02_wp]
        call compare_paths(error, files, t_ends, [character(len=8) :: 'radau5', 'ddassl', &
            'ida'])
    end subroutine test_trajectories

    !> MEXAX with its augmented systems solved by the structure of M
    !> (newton_system = 'condensed': constant mass blocks factored once,
    !> massless node frames in a small system) against KLU on the whole
    !> [M Gᵀ; G 0] ('full'), on the five-body and chain scenes (compare_paths),
    !> under ODEX/SEULEX's control: the comparison is of the linear algebra,
    !> and Deuflhard's control, rejecting more often, turns the first
    !> round-off flip on five_body_undamped into 5.4 % more steps over 0.2 s
    !> (503 against 477; ERR 2.2e-9 and 2.9e-9).
    subroutine test_mexax_structured(error)
        type(error_t), allocatable, intent(out) :: error
        character(len=*), parameter :: files(*) = [character(len=40) :: &
            'inputs/five_body.nml', 'inputs/five_body_undamped.nml', &
            'inputs/four_bar_chain.nml', 'inputs/four_bar_chains.nml', &
            'inputs/arm_with_pad.nml', 'inputs/two_soft_links.nml', 'inputs/face_hinge.nml']
        ! five_body_undamped over 0.2 s: over 0.05 s its NST differ by 9 %
        ! (108 and 118, debug build), over 0.2 s by 0.4 % (the fine mesh is
        ! left out: 'full' needs minutes for a few milliseconds of it there)
        real(wp), parameter :: t_ends(*) = [0.05_wp, 0.2_wp, 0.1_wp, 0.1_wp, 0.02_wp, &
            0.02_wp, 0.02_wp]
        call compare_paths(error, files, t_ends, [character(len=8) :: 'mexax'], 'hairer')
    end subroutine test_mexax_structured

    !> The scenes `files` up to `t_ends` with each of `solvers` at TOL 1e-6,
    !> newton_system = 'condensed' against 'full': with the same counters,
    !> the positions agree to 1e-9 (relative to their scale; the multipliers,
    !> index-2 variables whose round-off the iteration matrix amplifies like
    !> 1/h, are not compared); where round-off flipped a step decision, the
    !> ERRs (eq. 13) of both against a tight reference (RADAU5, 1e-10) are
    !> within a factor 2 of each other and NST, NFE, NJE within 15 %: one
    !> flipped decision moves the work that much (five_body_undamped on an
    !> AMD EPYC, OpenBLAS 0.3.21: DDASSL's NFE 1454 full, 1641 condensed,
    !> after one Jacobian kept a step longer, NJE 10 and 9; MEXAX's NST 485
    !> and 515; on the machine of earlier sessions both were within 5 %).
    subroutine compare_paths(error, files, t_ends, solvers, mexax_control)
        type(error_t), allocatable, intent(inout) :: error
        character(len=*), intent(in) :: files(:), solvers(:)
        real(wp), intent(in) :: t_ends(:)
        character(len=*), intent(in), optional :: mexax_control !! &solver mexax_control
        real(wp), parameter :: tol = 1.0e-6_wp
        type(run_result_t) :: rf, rc, ref
        logical :: same, have_ref
        integer :: f, k, identical, flipped
        real(wp) :: dev, worst, err_f, err_c
        worst = 0.0_wp
        identical = 0
        flipped = 0
        do f = 1, size(files)
            have_ref = .false.
            do k = 1, size(solvers)
                call run(error, trim(files(f)), trim(solvers(k)), 'full', tol, t_ends(f), rf)
                if (allocated(error)) return
                call run(error, trim(files(f)), trim(solvers(k)), 'condensed', tol, t_ends(f), rc)
                if (allocated(error)) return
                same = rf%stats%nst == rc%stats%nst .and. rf%stats%nac == rc%stats%nac .and. &
                    rf%stats%nfe == rc%stats%nfe .and. rf%stats%nje == rc%stats%nje .and. &
                    rf%stats%ndec == rc%stats%ndec .and. rf%stats%nsol == rc%stats%nsol
                if (same) then
                    identical = identical + 1
                    dev = maxval(abs(rf%y(rf%q_first:rf%q_last) - rc%y(rc%q_first:rc%q_last))) &
                        / max(1.0_wp, maxval(abs(rf%y(rf%q_first:rf%q_last))))
                    worst = max(worst, dev)
                    call check(error, dev <= 1.0e-9_wp, trim(files(f)) // ' ' // &
                        trim(solvers(k)) // ': condensed vs full, same counters, positions ' &
                        // real_text(dev) // ' apart')
                else
                    flipped = flipped + 1
                    if (.not. have_ref) then
                        call run(error, trim(files(f)), 'radau5', 'full', 1.0e-10_wp, &
                            t_ends(f), ref)
                        if (allocated(error)) return
                        have_ref = .true.
                    end if
                    associate (q => ref%y(ref%q_first:ref%q_last))
                        err_f = paper_error(rf%y(rf%q_first:rf%q_last), q, tol, tol)
                        err_c = paper_error(rc%y(rc%q_first:rc%q_last), q, tol, tol)
                    end associate
                    print '(4x,a,a,a,6(a,i0),2(a,es9.2))', trim(files(f)), ' ', trim(solvers(k)), &
                        ': NST full ', rf%stats%nst, ', condensed ', rc%stats%nst, &
                        '; NFE ', rf%stats%nfe, ', ', rc%stats%nfe, '; NJE ', rf%stats%nje, &
                        ', ', rc%stats%nje, '; ERR ', err_f, ', ', err_c
                    call check(error, max(err_f, err_c) <= 2.0_wp * max(min(err_f, err_c), &
                        1.0e-3_wp * tol) .and. within(rf%stats%nst, rc%stats%nst) .and. &
                        within(rf%stats%nfe, rc%stats%nfe) .and. &
                        within(rf%stats%nje, rc%stats%nje), trim(files(f)) // ' ' // &
                        trim(solvers(k)) // ': condensed vs full with other counters: ERR ' // &
                        real_text(err_c) // ' against ' // real_text(err_f) // ', NST ' // &
                        real_text(real(rc%stats%nst, wp)) // ' against ' // &
                        real_text(real(rf%stats%nst, wp)))
                end if
                if (allocated(error)) return
            end do
        end do
        print '(4x,a,i0,a,es9.2,a,i0,a)', 'condensed vs full: ', identical, &
            ' runs with the same counters (positions at most ', worst, ' apart), ', flipped, &
            ' with a step decision flipped by round-off'
    contains
        logical function within(a, b)
            integer, intent(in) :: a, b
            within = abs(a - b) <= max(1, nint(0.15_wp * max(a, b)))
        end function within

        subroutine run(error, path, solver, system, rtol, t_end, result)
            type(error_t), allocatable, intent(inout) :: error
            character(len=*), intent(in) :: path, solver, system
            real(wp), intent(in) :: rtol, t_end
            type(run_result_t), intent(out) :: result
            type(scene_input_t) :: scene
            type(status_t) :: status
            call read_scene(path, scene, status)
            call check(error, status%ok(), path // ': ' // status%text())
            if (allocated(error)) return
            scene%output_file = ''
            scene%progress = .false.
            scene%solver_name = solver
            scene%rtol = rtol
            scene%atol = rtol
            scene%t_end = t_end
            scene%newton_system = system
            if (present(mexax_control) .and. solver == 'mexax') then
                scene%solver_settings = [scene%solver_settings, &
                    solver_setting_t(name='mexax_control', string_value=mexax_control)]
            end if
            call run_scene(scene, .true., result, status)
            call check(error, status%ok(), path // ' ' // solver // ' ' // system // ': ' // &
                status%text())
        end subroutine run
    end subroutine compare_paths
end module test_condensed_newton
