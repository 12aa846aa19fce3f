!> RADAU5 core: anchors, orders, DAEs, dense output, counters.
module test_radau5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_problems_van_der_pol, only: van_der_pol_t, new_van_der_pol
    use testing, only: test_case_t, new_test, error_t, check, check_close
    implicit none
    private
    public :: collect_radau5

contains

    function collect_radau5() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('van_der_pol_anchor_counters', test_vdp_anchor)]
    end function collect_radau5

    subroutine test_vdp_anchor(error)
        type(error_t), allocatable, intent(out) :: error
        type(van_der_pol_t) :: problem
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp) :: t, y(2)
        problem = new_van_der_pol(1.0e-6_wp)
        options%rtol = 1.0e-4_wp
        options%atol = 1.0e-4_wp
        options%h0 = 1.0e-6_wp
        t = 0.0_wp
        y = [2.0_wp, -0.66_wp]
        call solver%integrate(problem, t, y, 2.0_wp, options, stats, status)
        call check(error, status%ok(), 'integration failed: ' // status%text())
        call check_close(error, y(1), 1.706161101_wp, 1e-6_wp, 'y1(2)')
        call check_close(error, y(2), -0.8928074777_wp, 1e-6_wp, 'y2(2)')
        ! ALGORITHMS.md §8 anchor: the original's counters, exactly.
        call check(error, solver%native%nfcn == 2218, 'NFCN /= 2218')
        call check(error, solver%native%njac == 161, 'NJAC /= 161')
        call check(error, solver%native%nstep == 275, 'NSTEP /= 275')
        call check(error, solver%native%naccpt == 238, 'NACCPT /= 238')
        call check(error, solver%native%nrejct == 8, 'NREJCT /= 8')
        call check(error, solver%native%ndec == 248, 'NDEC /= 248')
        call check(error, solver%native%nsol == 660, 'NSOL /= 660')
        call check(error, stats%nst == stats%nac + stats%nrj, 'NST /= NAC + NRJ')
        call check(error, stats%nst == 275 .and. stats%nac == 238 .and. stats%nfe == 2218, &
            'common counters differ from native ones')
        call check(error, stats%nsol == 660 + solver%nsol_error, 'common NSOL')
    end subroutine test_vdp_anchor
end module test_radau5
