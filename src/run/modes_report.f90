!> The eigen-analysis of a scene for people (`flexmbs modes`): what was
!> linearised, how many eigenvalues are finite against the count the
!> formulation should have, the lowest modes with frequency and damping,
!> and per BDF order the stiff modes outside the A(α) sector at the step
!> sizes DDASSL took (run/modes).
module flexmbs_run_modes_report
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_dae_bdf_stability, only: sector_angle
    use flexmbs_run_modes, only: modes_result_t, max_bdf_order, stiff_outside, median, &
        stiff_bound
    implicit none
    private

    !> Mode numbers listed per order at most.
    integer, parameter :: max_listed = 8

    public :: modes_report

contains

    !> The report, lines ended by newlines: the `count` lowest modes.
    function modes_report(result, count) result(text)
        type(modes_result_t), intent(in) :: result
        integer, intent(in) :: count
        character(len=:), allocatable :: text
        text = spectrum_text(result) // modes_table(result, count)
        if (result%has_run) text = text // sector_text(result)
    end function modes_report

    !> What was linearised and the counts.
    function spectrum_text(result) result(text)
        type(modes_result_t), intent(in) :: result
        character(len=:), allocatable :: text
        character(len=:), allocatable :: title, what
        integer :: zeros
        what = 'formulation ''' // result%formulation // ''''
        if (result%formulation == '-') what = 'M y'' = F(t, y)'
        title = ''
        if (len(result%title) > 0) title = ' ''' // result%title // ''''
        text = 'modes of' // title // ' (' // result%path // ') at t = ' // &
            real_text(result%t) // ' s' // new_line('a') // &
            'linearised: ' // what // ' as ' // result%solver // ' integrates it, n = ' // &
            int_text(result%n) // ' unknowns; ' // result%method // new_line('a')
        text = text // 'eigenvalues: ' // int_text(result%finite) // ' finite'
        if (result%infinite >= 0) text = text // ', ' // int_text(result%infinite) // &
            ' infinite (the algebraic components)'
        text = text // new_line('a')
        if (result%expected >= 0) then
            text = text // 'expected finite: ' // int_text(result%expected) // ' = 2 x ' // &
                int_text(result%dof) // ' (motion on the constraint manifold, n_v - n_c)'
            if (result%quaternions > 0) text = text // ' + ' // int_text(result%quaternions) &
                // ' (unit quaternions'' lengths)'
            if (result%constraint_values > 0) text = text // ' + ' // &
                int_text(result%constraint_values) // ' (constraint values, ' // &
                result%formulation // ')'
            if (result%infinite >= 0 .and. result%finite /= result%expected) text = text // &
                '; found ' // int_text(result%finite) // ': dependent constraints, or &
                &eigenvalues beyond the infinite bound (docs/modes.md)'
            text = text // new_line('a')
        end if
        zeros = count(result%mode == 0)
        if (zeros > 0) text = text // int_text(zeros) // ' at zero (|lambda| <= ' // &
            real_text(result%zero_bound) // ' 1/s)' // new_line('a')
    end function spectrum_text

    !> The `count` lowest modes: λ, ω = |Im λ|, f = ω/2π, ζ = −Re λ/|λ| and
    !> the angle |arg(−λ)| that the sectors are measured in.
    function modes_table(result, count) result(text)
        type(modes_result_t), intent(in) :: result
        integer, intent(in) :: count
        character(len=:), allocatable :: text
        character(len=120) :: line
        real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)
        complex(wp) :: lambda
        integer :: m, i
        text = '  mode   Re(lambda) [1/s]   Im(lambda) [1/s]  omega [rad/s]      f [Hz]' // &
            '     zeta  angle [deg]' // new_line('a')
        do m = 1, min(count, result%modes)
            i = result%mode_index(m)
            lambda = result%lambda(i)
            if (aimag(lambda) < 0.0_wp) lambda = conjg(lambda)
            write (line, '(i6,2es19.10,2es14.6,f9.4,f13.4)') m, real(lambda, wp), &
                aimag(lambda), aimag(lambda), aimag(lambda) / two_pi, &
                -real(lambda, wp) / abs(lambda), sector_angle(lambda)
            text = text // trim(line) // new_line('a')
        end do
        text = text // '(the ' // int_text(min(count, result%modes)) // ' lowest of ' // &
            int_text(result%modes) // ' modes: a conjugate pair or a real eigenvalue each)' &
            // new_line('a')
    end function modes_table

    !> The DDASSL run and, per order, the stiff modes outside the sector at
    !> the median and the largest step taken at that order (the run's, '*',
    !> when it took none).
    function sector_text(result) result(text)
        type(modes_result_t), intent(in) :: result
        character(len=:), allocatable :: text
        character(len=160) :: line
        integer, allocatable :: at_median(:), at_max(:)
        real(wp), allocatable :: h(:)
        real(wp) :: h_median, h_max
        integer :: k, steps, j
        character :: mark
        logical :: starred
        text = new_line('a') // result%solver // ' on the same scene (' // &
            result%run_settings // '): ' // result%stats%summary() // new_line('a')
        if (allocated(result%stats%warning)) text = text // 'warning: ' // &
            result%stats%warning // new_line('a')
        if (.not. result%run_status%ok()) text = text // result%solver // ' stopped at t = ' // &
            real_text(result%stats%t_reached) // ': ' // result%run_status%text() // &
            '; the check uses the ' // int_text(size(result%h)) // ' steps it accepted' // &
            new_line('a')
        if (size(result%h) == 0) then
            text = text // 'no accepted step: no sector check' // new_line('a')
            return
        end if
        text = text // 'accepted steps: ' // int_text(size(result%h)) // ', h from ' // &
            real_text(minval(result%h)) // ' to ' // real_text(maxval(result%h)) // &
            ' s, median ' // real_text(median(result%h)) // ' s' // new_line('a')
        text = text // '  order  alpha [deg]  steps  h median [s]   h max [s]  stiff &
            &outside: at median, at max  (modes at max)' // new_line('a')
        starred = .false.
        do k = 1, max_bdf_order
            h = pack(result%h, result%order == k)
            steps = size(h)
            mark = ' '
            if (steps == 0) then
                h = result%h
                mark = '*'
                starred = .true.
            end if
            h_median = median(h)
            h_max = maxval(h)
            at_median = stiff_outside(result, k, h_median)
            at_max = stiff_outside(result, k, h_max)
            write (line, '(a,i0,f13.4,i7,2(es12.3,a),2i11,a)') '  BDF-', k, result%alpha(k), &
                steps, h_median, mark, h_max, mark, size(at_median), size(at_max), '  '
            do j = 1, min(size(at_max), max_listed)
                line = trim(line) // ' ' // int_text(at_max(j))
            end do
            if (size(at_max) > max_listed) line = trim(line) // ' ...'
            text = text // trim(line) // new_line('a')
        end do
        text = text // 'stiff: |h lambda| >= ' // real_text(stiff_bound) // '; outside: &
            &|arg(-h lambda)| > alpha_k, where BDF-k is not guaranteed stable' // &
            new_line('a')
        if (starred) text = text // '* no step at that order: the run''s h' // new_line('a')
    end function sector_text
end module flexmbs_run_modes_report
