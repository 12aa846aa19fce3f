!> MEXAX delivered accuracy against TOL on the bar chain of docs/solvers.md
!> (flexmbs_problems_pendulum_chain) with 3 to 16 bars: ERR of eq. (13)
!> over the positions at t = 1 for TOL 1e-3, 1e-5, 1e-7 and 1e-9, for both
!> base methods, against a reference from another integrator: RADAU5
!> (collocation, index-2 formulation) at rtol = atol = 1e-12. The reference
!> is confirmed on NB = 8 by the original MEXX's positions at t = 1 (TOL
!> 1e-11, chain_anchor_t1: within 1e-10; measured 3.0e-11) and on every
!> chain by MEXAX's midpoint base at 1e-12 (ERR within 0.3 of the tightest
!> TOL; measured at most 0.035). On every chain the error must fall as TOL
!> tightens and stay within `err_bound` TOL: local error control does not
!> bound the global error, and on these chains it grows to about 20 TOL
!> (midpoint base, NB = 12).
!>
!> Deuflhard's control (docs/theory.md §7.3) is held to a sharper measure
!> as well: the largest relative error of the bars' angles at t = 1, at
!> most 20 TOL for every chain and every TOL from 1e-3 to 1e-9 (ERR of eq.
!> (13) over all positions does not show the gap that measure opened
!> between ODEX/SEULEX's control and the original's figures).
module test_mexax_accuracy
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_mexax, only: mexax_t, mexax_base_euler, mexax_base_midpoint, &
        mexax_control_hairer, mexax_control_deuflhard
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_mbs_formulation, only: block_q, block_v
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_dae_error_measure, only: paper_error
    use flexmbs_problems_pendulum_chain, only: pendulum_chain_t, new_pendulum_chain, &
        pendulum_chain_initial, chain_anchor_t1
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_mexax_accuracy

    !> Chain lengths (bars) and tolerances of the table.
    integer, parameter :: chains(6) = [3, 4, 5, 8, 12, 16]
    integer, parameter :: tol_exponents(4) = [3, 5, 7, 9]
    !> Tolerance of the RADAU5 reference and of MEXAX's check of it (midpoint
    !> base); the two must agree to `reference_agreement` of the tightest
    !> TOL, and the reference on NB = 8 to the original's anchor within
    !> `anchor_agreement`.
    real(wp), parameter :: reference_tol = 1.0e-12_wp
    real(wp), parameter :: reference_agreement = 0.3_wp
    real(wp), parameter :: anchor_agreement = 1.0e-10_wp
    !> ERR/TOL above this fails.
    real(wp), parameter :: err_bound = 30.0_wp
    !> Deuflhard's control: the largest relative angle error over TOL above
    !> this fails (the original's figures on these chains: 1.2 to 17 TOL).
    real(wp), parameter :: angle_bound = 20.0_wp

    !> A chain's reference positions at t = 1 and MEXAX's ERR against them
    !> at 1e-12 over the tightest TOL, computed once for both tests (RADAU5
    !> at 1e-12 takes 100 to 6000 steps, the bulk of the suite's time).
    type :: reference_t
        real(wp), allocatable :: q(:)
        real(wp) :: check = 0.0_wp
    end type reference_t
    type(reference_t) :: references(size(chains))

contains

    function collect_mexax_accuracy() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [ &
            new_test('accuracy_vs_tol_euler', test_euler), &
            new_test('accuracy_vs_tol_midpoint', test_midpoint), &
            new_test('angles_vs_tol_deuflhard_euler', test_angles_euler), &
            new_test('angles_vs_tol_deuflhard_midpoint', test_angles_midpoint)]
    end function collect_mexax_accuracy

    !> MEXAX on the chain of `bodies` bars from its start (horizontal, at
    !> rest) to t = 1 at rtol = atol = tol; the positions at t = 1 in q.
    subroutine chain_run(bodies, base, tol, q, stats, status, control)
        integer, intent(in) :: bodies, base
        integer, intent(in), optional :: control !! mexax_control_*; the solver's default
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
        if (present(control)) solver%control = control
        options%rtol = tol
        options%atol = tol
        options%h0 = 1.0e-3_wp
        t = 0.0_wp
        call solver%integrate_mechanical(chain, t, q, v, 1.0_wp, options, stats, status, &
                                         lambda=lam)
    end subroutine chain_run

    !> RADAU5 on the same chain and span in the index-2 formulation (constant
    !> mass, y = (q, v, λ)) from consistent values, rtol = atol = tol.
    subroutine radau5_run(bodies, tol, q, stats, status)
        integer, intent(in) :: bodies
        real(wp), intent(in) :: tol
        real(wp), allocatable, intent(out) :: q(:)
        type(dae_stats_t), intent(out) :: stats
        type(status_t), intent(out) :: status
        type(pendulum_chain_t), target :: chain
        type(formulation_t) :: gen
        type(radau5_t) :: solver
        type(dae_options_t) :: options
        real(wp), allocatable :: v(:), lam(:), y(:), yp(:)
        real(wp) :: t
        chain = new_pendulum_chain(bodies)
        allocate (q(chain%nq), v(chain%nv), lam(chain%nc))
        call pendulum_chain_initial(chain, q, v, lam)
        gen = new_formulation(chain, formulation_index2, q, constant_mass=.true., status=status)
        if (.not. status%ok()) return
        allocate (y(gen%n), yp(gen%n), source=0.0_wp)
        y(gen%offset(block_q) + 1:gen%last(block_q)) = q
        y(gen%offset(block_v) + 1:gen%last(block_v)) = v
        call gen%consistent_initial(0.0_wp, y, yp, status)
        if (.not. status%ok()) return
        options%rtol = tol
        options%atol = tol
        ! A new Jacobian only when Newton slows (Hairer's advice for costly
        ! Jacobians): 40 % less time here, same accuracy.
        solver%thet = 0.1_wp
        t = 0.0_wp
        call solver%integrate(gen, t, y, 1.0_wp, options, stats, status)
        q = y(gen%offset(block_q) + 1:gen%last(block_q))
    end subroutine radau5_run

    !> The reference of chain b (computed and checked on first use).
    subroutine reference_positions(error, b, reference)
        type(error_t), allocatable, intent(inout) :: error
        integer, intent(in) :: b
        type(reference_t), intent(out) :: reference
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q(:), qcheck(:)
        real(wp) :: tight, offset
        if (.not. allocated(references(b)%q)) then
            tight = 10.0_wp**(-maxval(tol_exponents))
            call radau5_run(chains(b), reference_tol, q, stats, status)
            call check(error, status%ok(), 'reference (radau5): ' // status%text())
            call chain_run(chains(b), mexax_base_midpoint, reference_tol, qcheck, stats, status)
            call check(error, status%ok(), 'reference check (mexax): ' // status%text())
            if (allocated(error)) return
            references(b)%q = q
            references(b)%check = paper_error(qcheck, q, tight, tight) / tight
            if (chains(b) == 8) then
                offset = maxval(abs(q(1:3) - chain_anchor_t1))
                write (*, '(4x,a,es9.2)') 'NB 8: RADAU5 reference off the original''s ' // &
                    'anchor by ', offset
                call check(error, offset <= anchor_agreement, &
                           'NB 8: the reference is off the original''s anchor')
                if (allocated(error)) return
            end if
        end if
        reference = references(b)
    end subroutine reference_positions

    !> ERR over TOL under ODEX/SEULEX's control.
    subroutine accuracy_table(error, base, label)
        type(error_t), allocatable, intent(out) :: error
        integer, intent(in) :: base
        character(len=*), intent(in) :: label
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(reference_t) :: reference
        real(wp), allocatable :: q(:)
        real(wp) :: tol, ratio(size(tol_exponents)), err(size(tol_exponents))
        integer :: b, e, nac(size(tol_exponents))
        character(len=200) :: line
        write (*, '(a)') '  mexax ' // label // ': ERR/TOL (accepted steps) at TOL 1e-3, 1e-5, ' &
            // '1e-7, 1e-9 against RADAU5 at 1e-12; its check'
        do b = 1, size(chains)
            call reference_positions(error, b, reference)
            if (allocated(error)) return
            do e = 1, size(tol_exponents)
                tol = 10.0_wp**(-tol_exponents(e))
                call chain_run(chains(b), base, tol, q, stats, status, mexax_control_hairer)
                call check(error, status%ok(), status%text())
                if (allocated(error)) return
                err(e) = paper_error(q, reference%q, tol, tol)
                ratio(e) = err(e) / tol
                nac(e) = stats%nac
            end do
            write (line, '(a,i3,a,4(es10.2,a,i4,a),es10.2)') 'NB', chains(b), ':', &
                (ratio(e), ' (', nac(e), ')', e=1, size(tol_exponents)), reference%check
            write (*, '(a)') '    ' // trim(line)
            call check(error, reference%check <= reference_agreement, trim(line) // &
                ': RADAU5 and MEXAX at 1e-12 differ')
            do e = 2, size(tol_exponents)
                call check(error, err(e) < err(e - 1), trim(line) // &
                    ': ERR does not fall as TOL tightens')
            end do
            call check(error, all(ratio <= err_bound), trim(line) // ': ERR above the bound')
            if (allocated(error)) return
        end do
    end subroutine accuracy_table

    !> The largest relative error of the angles φ_i at t = 1 over TOL, for
    !> every chain and TOL 1e-3, 1e-4, …, 1e-9, under Deuflhard's control.
    subroutine angle_table(error, base, label)
        type(error_t), allocatable, intent(out) :: error
        integer, intent(in) :: base
        character(len=*), intent(in) :: label
        integer, parameter :: first_exponent = 3, last_exponent = 9
        type(dae_stats_t) :: stats
        type(status_t) :: status
        type(reference_t) :: reference
        real(wp), allocatable :: q(:)
        real(wp) :: tol, ratio(first_exponent:last_exponent)
        integer :: b, e
        character(len=200) :: line
        write (*, '(a)') '  mexax ' // label // ', Deuflhard''s control: max |dphi/phi| / TOL ' // &
            'at TOL 1e-3 ... 1e-9 against RADAU5 at 1e-12'
        do b = 1, size(chains)
            call reference_positions(error, b, reference)
            if (allocated(error)) return
            associate (phi_ref => reference%q(3::3))
                do e = first_exponent, last_exponent
                    tol = 10.0_wp**(-e)
                    call chain_run(chains(b), base, tol, q, stats, status, mexax_control_deuflhard)
                    call check(error, status%ok(), status%text())
                    if (allocated(error)) return
                    ratio(e) = maxval(abs(q(3::3) - phi_ref) / abs(phi_ref)) / tol
                end do
            end associate
            write (line, '(a,i3,a,7f7.2)') 'NB', chains(b), ':', ratio
            write (*, '(a)') '    ' // trim(line)
            call check(error, all(ratio <= angle_bound), trim(line) // ': above ' // &
                       '20 TOL')
            if (allocated(error)) return
        end do
    end subroutine angle_table

    subroutine test_angles_euler(error)
        type(error_t), allocatable, intent(out) :: error
        call angle_table(error, mexax_base_euler, 'Euler base')
    end subroutine test_angles_euler

    subroutine test_angles_midpoint(error)
        type(error_t), allocatable, intent(out) :: error
        call angle_table(error, mexax_base_midpoint, 'midpoint base')
    end subroutine test_angles_midpoint

    subroutine test_euler(error)
        type(error_t), allocatable, intent(out) :: error
        call accuracy_table(error, mexax_base_euler, 'Euler base')
    end subroutine test_euler

    subroutine test_midpoint(error)
        type(error_t), allocatable, intent(out) :: error
        call accuracy_table(error, mexax_base_midpoint, 'midpoint base')
    end subroutine test_midpoint
end module test_mexax_accuracy
