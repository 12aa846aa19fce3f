!> MEXAX with KLU: the chain's CSC M and G equal its dense ones; the KLU
!> path gives the dense trajectory to round-off with the same counters on a
!> chain of 50 bars (augmented order 250), for both base methods; 'klu'
!> without sparse interfaces, and 'band', are refused as bad input; a
!> singular augmented matrix stops both paths alike.
module test_mexax_sparse
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler, mexax_base_midpoint
    use flexmbs_problems_pendulum, only: pendulum_mechanical_t, new_pendulum_mechanical, &
        pendulum_mechanical_initial
    use flexmbs_problems_pendulum_chain, only: pendulum_chain_t, new_pendulum_chain, &
        pendulum_chain_initial
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mexax_sparse

    !> Bars of the comparison chain: nv + nc = 5 NB = 250 unknowns in the
    !> augmented system, well above the dense/KLU threshold.
    integer, parameter :: bodies = 50
    !> Agreement "to round-off" of the dense and KLU trajectories, relative
    !> to the size of each block of the state: the two LU factorisations
    !> differ by ~1e-16, which the Aitken–Neville weights of the tableau
    !> (largest for the Euler base) and the 1/h in a and λ amplify to ~1e-9
    !> over the run, still 1e-3 of the tolerance 1e-5 that the step
    !> control works to.
    real(wp), parameter :: roundoff = 1.0e-8_wp

contains

    function collect_mexax_sparse() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [ &
            new_test('chain_sparse_equals_dense', test_chain_sparse), &
            new_test('klu_equals_dense_midpoint', test_klu_midpoint), &
            new_test('klu_equals_dense_euler', test_klu_euler), &
            new_test('klu_needs_sparse_interfaces', test_bad_input), &
            new_test('singular_augmented_matrix', test_singular)]
    end function collect_mexax_sparse

    !> The chain's CSC M and G, scattered, equal the dense ones at a
    !> configuration with all angle terms nonzero.
    subroutine test_chain_sparse(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_chain_t) :: chain
        type(csc_matrix_t) :: mpat, gpat
        type(status_t) :: status
        real(wp), allocatable :: q(:), md(:, :), gd(:, :), ms(:, :), gs(:, :)
        integer :: i
        chain = new_pendulum_chain(7)
        call check(error, chain%has_sparse(), 'chain reports sparse M and G')
        allocate (q(chain%nq), md(chain%nv, chain%nv), ms(chain%nv, chain%nv), &
            gd(chain%nc, chain%nv), gs(chain%nc, chain%nv))
        q = [(0.3_wp + 0.17_wp * i, i=1, chain%nq)]
        call chain%mass_pattern(mpat, status)
        call check(error, status%ok(), 'mass pattern: ' // status%text())
        call chain%constraint_jacobian_pattern(gpat, status)
        call check(error, status%ok(), 'G pattern: ' // status%text())
        if (allocated(error)) return
        call check(error, mpat%nrow == chain%nv .and. mpat%ncol == chain%nv .and. &
            mpat%nnz == chain%nv, 'M pattern is the nv x nv diagonal')
        call check(error, gpat%nrow == chain%nc .and. gpat%ncol == chain%nv .and. &
            gpat%nnz == 8 * chain%bodies - 4, 'G pattern: nc x nv with 8 NB - 4 slots')
        call chain%mass(0.0_wp, q, md, status)
        call chain%constraint_jacobian(0.0_wp, q, gd, status)
        call chain%mass_sparse(0.0_wp, q, mpat%values, status)
        call chain%constraint_jacobian_sparse(0.0_wp, q, gpat%values, status)
        call check(error, status%ok(), 'sparse values: ' // status%text())
        call mpat%to_dense(ms)
        call gpat%to_dense(gs)
        call check(error, all(ms == md), 'sparse M equals dense M')
        call check(error, all(gs == gd), 'sparse G equals dense G')
        call check(error, count(gd /= 0.0_wp) == gpat%nnz, 'G pattern has no spare slots')
    end subroutine test_chain_sparse

    !> The chain of `bodies` bars from rest, horizontal, to t = 0.1.
    subroutine chain_run(base, linear_solver, q, v, lam, acc, stats, solver, status)
        integer, intent(in) :: base
        character(len=*), intent(in) :: linear_solver
        real(wp), allocatable, intent(out) :: q(:), v(:), lam(:), acc(:)
        type(dae_stats_t), intent(out) :: stats
        type(mexax_t), intent(out) :: solver
        type(status_t), intent(out) :: status
        type(pendulum_chain_t) :: chain
        type(dae_options_t) :: options
        real(wp) :: t
        chain = new_pendulum_chain(bodies)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc), acc(chain%nv))
        call pendulum_chain_initial(chain, q, v, lam)
        solver%base = base
        options%rtol = 1.0e-5_wp
        options%atol = 1.0e-5_wp
        options%h0 = 1.0e-3_wp
        options%linear_solver = linear_solver
        t = 0.0_wp
        call solver%integrate_mechanical(chain, t, q, v, 0.1_wp, options, stats, status, &
            lambda=lam, accel=acc)
    end subroutine chain_run

    subroutine compare_dense_klu(error, base)
        type(error_t), allocatable, intent(out) :: error
        integer, intent(in) :: base
        type(mexax_t) :: sd, sk
        type(dae_stats_t) :: std, stk
        type(status_t) :: status
        real(wp), allocatable :: qd(:), vd(:), ld(:), ad(:), qk(:), vk(:), lk(:), ak(:)
        character(len=200) :: msg
        call chain_run(base, 'dense', qd, vd, ld, ad, std, sd, status)
        call check(error, status%ok(), 'dense run: ' // status%text())
        call chain_run(base, 'klu', qk, vk, lk, ak, stk, sk, status)
        call check(error, status%ok(), 'klu run: ' // status%text())
        if (allocated(error)) return
        write (msg, '(a,4es10.2)') 'dense and KLU differ beyond round-off in q, v, lambda, a: ', &
            diff(qk, qd), diff(vk, vd), diff(lk, ld), diff(ak, ad)
        call check(error, diff(qk, qd) <= roundoff .and. diff(vk, vd) <= roundoff .and. &
            diff(lk, ld) <= roundoff .and. diff(ak, ad) <= roundoff, trim(msg))
        write (msg, '(a,7(1x,i0),a,7(1x,i0))') 'counters NST NAC NFE NDEC NSOL NPRJ NMULT: dense', &
            std%nst, std%nac, std%nfe, std%ndec, std%nsol, std%nprj, sd%native%nmult, ' klu', &
            stk%nst, stk%nac, stk%nfe, stk%ndec, stk%nsol, stk%nprj, sk%native%nmult
        write (*, '(a)') '  mexax_sparse ' // trim(msg)
        call check(error, std%nst == stk%nst .and. std%nac == stk%nac .and. &
            std%nfe == stk%nfe .and. std%ndec == stk%ndec .and. std%nsol == stk%nsol .and. &
            std%nprj == stk%nprj .and. sd%native%nfprob == sk%native%nfprob .and. &
            sd%native%ngcn == sk%native%ngcn .and. sd%native%nmult == sk%native%nmult .and. &
            sd%native%nrejct == sk%native%nrejct, trim(msg))
        call check(error, std%nst > 5 .and. std%ndec > 50, 'comparison run too short')
    end subroutine compare_dense_klu

    !> max |a - b| / max(1, max |b|)
    pure real(wp) function diff(a, b)
        real(wp), intent(in) :: a(:), b(:)
        diff = maxval(abs(a - b)) / max(1.0_wp, maxval(abs(b)))
    end function diff

    subroutine test_klu_midpoint(error)
        type(error_t), allocatable, intent(out) :: error
        call compare_dense_klu(error, mexax_base_midpoint)
    end subroutine test_klu_midpoint

    subroutine test_klu_euler(error)
        type(error_t), allocatable, intent(out) :: error
        call compare_dense_klu(error, mexax_base_euler)
    end subroutine test_klu_euler

    !> 'klu' on a problem without sparse M and G, and 'band', are bad input
    !> that names the option; 'auto' falls back to dense there.
    subroutine test_bad_input(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_mechanical_t) :: pend
        type(mexax_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: q(2), v(2), lam(1), t
        pend = new_pendulum_mechanical()
        call check(error, .not. pend%has_sparse(), 'the pendulum has no sparse interfaces')
        call pendulum_mechanical_initial(pend, 1.0_wp, q, v, lam)
        options%linear_solver = 'klu'
        t = 0.0_wp
        call solver%integrate_mechanical(pend, t, q, v, 1.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input, "'klu': " // status%text())
        call check(error, index(status%text(), "linear_solver = 'klu'") > 0 .and. &
            index(status%text(), 'sparse') > 0, "'klu' message: " // status%text())
        call check(error, t == 0.0_wp .and. stats%nst == 0, "'klu': nothing integrated")
        options%linear_solver = 'band'
        call solver%integrate_mechanical(pend, t, q, v, 1.0_wp, options, stats, status)
        call check(error, status%code == status_bad_input .and. &
            index(status%text(), "'band'") > 0, "'band': " // status%text())
        options%linear_solver = 'auto'
        call solver%integrate_mechanical(pend, t, q, v, 1.0_wp, options, stats, status)
        call check(error, status%ok() .and. t == 1.0_wp, "'auto' on the pendulum: " // &
            status%text())
    end subroutine test_bad_input

    !> Bars of zero length and inertia: the angles enter neither M nor G, so
    !> [M Gᵀ; G 0] has zero rows. Dense LU and KLU both stop at t0 with a
    !> singular-matrix failure.
    subroutine test_singular(error)
        type(error_t), allocatable, intent(out) :: error
        type(pendulum_chain_t) :: chain
        type(mexax_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), lam(:)
        real(wp) :: t
        character(len=5), parameter :: names(2) = ['dense', 'klu  ']
        integer :: s
        chain = new_pendulum_chain(12)
        chain%half_length = 0.0_wp
        chain%inertia = 0.0_wp
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        do s = 1, 2
            call pendulum_chain_initial(chain, q, v, lam)
            options%linear_solver = trim(names(s))
            t = 0.0_wp
            call solver%integrate_mechanical(chain, t, q, v, 1.0_wp, options, stats, status)
            call check(error, status%code == status_solver_failure .and. &
                status%reason == reason_singular_matrix .and. &
                index(status%text(), 'singular') > 0 .and. t == 0.0_wp, &
                trim(names(s)) // ': ' // status%text())
        end do
    end subroutine test_singular
end module test_mexax_sparse
