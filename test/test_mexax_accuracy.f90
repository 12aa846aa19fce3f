!> MEXAX delivered accuracy against TOL on the §8 chain with 3 to 16 bars:
!> ERR of eq. (13) over the positions at t = 1 for TOL 1e-3, 1e-5, 1e-7 and
!> 1e-9, against a reference of the midpoint base at TOL 1e-12 (which the
!> Euler base at 1e-11 confirms), for both base methods. On every chain the
!> error must fall as TOL tightens and stay within `err_bound` TOL: local
!> error control does not bound the global error, and on these chains it
!> grows to about 20 TOL (midpoint base, NB = 12).
module test_mexax_accuracy
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler, mexax_base_midpoint
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_pendulum_chain, only: pendulum_chain_t, new_pendulum_chain, &
        pendulum_chain_initial
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mexax_accuracy

    !> Chain lengths (bars) and tolerances of the table.
    integer, parameter :: chains(5) = [3, 4, 8, 12, 16]
    integer, parameter :: tol_exponents(4) = [3, 5, 7, 9]
    !> Tolerance of the reference (midpoint base) and of its check (Euler
    !> base, which at 1e-12 meets its round-off floor on NB = 12); the two
    !> must agree to `reference_agreement` of the tightest TOL.
    real(wp), parameter :: reference_tol = 1.0e-12_wp, check_tol = 1.0e-11_wp
    real(wp), parameter :: reference_agreement = 0.3_wp
    !> ERR/TOL above this fails.
    real(wp), parameter :: err_bound = 30.0_wp

contains

    function collect_mexax_accuracy() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [ &
            new_test('accuracy_vs_tol_euler', test_euler), &
            new_test('accuracy_vs_tol_midpoint', test_midpoint)]
    end function collect_mexax_accuracy

    !> The chain of `bodies` bars from its §8 start to t = 1 at rtol = atol =
    !> tol; the positions at t = 1 in q.
    subroutine chain_run(bodies, base, tol, q, stats, status)
        integer, intent(in) :: bodies, base
        real(wp), intent(in) :: tol
        real(wp), allocatable, intent(out) :: q(:)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        type(pendulum_chain_t) :: chain
        type(mexax_t) :: solver
        type(dae_options_t) :: options
        real(wp), allocatable :: v(:), lam(:)
        real(wp) :: t
        chain = new_pendulum_chain(bodies)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        call pendulum_chain_initial(chain, q, v, lam)
        solver%base = base
        options%rtol = tol
        options%atol = tol
        options%h0 = 1.0e-3_wp
        t = 0.0_wp
        call solver%integrate_mechanical(chain, t, q, v, 1.0_wp, options, stats, status, &
                                         lambda=lam)
    end subroutine chain_run

    subroutine accuracy_table(error, base, label)
        type(error_t), allocatable, intent(out) :: error
        integer, intent(in) :: base
        character(len=*), intent(in) :: label
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:), qref(:), qcheck(:)
        real(wp) :: tol, tight, ratio(size(tol_exponents)), err(size(tol_exponents))
        integer :: b, e, nac(size(tol_exponents))
        character(len=200) :: line
        write (*, '(a)') '  mexax ' // label // ': ERR/TOL (accepted steps) at TOL 1e-3, 1e-5, ' &
            // '1e-7, 1e-9; reference check'
        tight = 10.0_wp**(-maxval(tol_exponents))
        do b = 1, size(chains)
            call chain_run(chains(b), mexax_base_midpoint, reference_tol, qref, stats, status)
            call check(error, status%ok(), 'reference: ' // status%text())
            call chain_run(chains(b), mexax_base_euler, check_tol, qcheck, stats, status)
            call check(error, status%ok(), 'reference check: ' // status%text())
            if (allocated(error)) return
            do e = 1, size(tol_exponents)
                tol = 10.0_wp**(-tol_exponents(e))
                call chain_run(chains(b), base, tol, q, stats, status)
                call check(error, status%ok(), status%text())
                if (allocated(error)) return
                err(e) = paper_error(q, qref, tol, tol)
                ratio(e) = err(e) / tol
                nac(e) = stats%nac
            end do
            write (line, '(a,i3,a,4(es10.2,a,i4,a),es10.2)') 'NB', chains(b), ':', &
                (ratio(e), ' (', nac(e), ')', e=1, size(tol_exponents)), &
                paper_error(qcheck, qref, tight, tight) / tight
            write (*, '(a)') '    ' // trim(line)
            call check(error, paper_error(qcheck, qref, tight, tight) <= reference_agreement &
                * tight, trim(line) // ': the references of both bases differ')
            do e = 2, size(tol_exponents)
                call check(error, err(e) < err(e - 1), trim(line) // &
                    ': ERR does not fall as TOL tightens')
            end do
            call check(error, all(ratio <= err_bound), trim(line) // ': ERR above the bound')
            if (allocated(error)) return
        end do
    end subroutine accuracy_table

    subroutine test_euler(error)
        type(error_t), allocatable, intent(out) :: error
        call accuracy_table(error, mexax_base_euler, 'Euler base')
    end subroutine test_euler

    subroutine test_midpoint(error)
        type(error_t), allocatable, intent(out) :: error
        call accuracy_table(error, mexax_base_midpoint, 'midpoint base')
    end subroutine test_midpoint
end module test_mexax_accuracy
