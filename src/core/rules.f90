!> Admissible ranges of settings, as text rules that the scene schema
!> prints and checks and that the solvers check their own settings with:
!> a range that both a scene and a library caller can set is written once.
!>
!> A rule is 'positive', 'nonnegative', 'tolerance' ([1e-14, 1)),
!> 'abs_tolerance' ([1e-14, inf)) or an interval such as '(0,1]' or
!> '[2,12]', with `inf` for no bound.
module flexmbs_core_rules
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    public :: rule_reason

    !> Smallest tolerance a scene or study may ask for: below it rounding
    !> errors of double precision dominate every solver's error estimate.
    real(wp), parameter, public :: min_tolerance = 1.0e-14_wp

    !> The safety factor of a step-size control (RADAU5's SAFE, WORK(2)):
    !> at 1 or above the controller aims at the tolerance itself and rejects
    !> every other step; below 0.001 it no longer lets the step grow.
    character(len=*), parameter, public :: safety_factor_rule = '(0.001,1)'

contains

    !> Why `x` breaks `rule` ('' if it does not); `integer_valued` writes a
    !> closed interval as 'a..b'.
    pure function rule_reason(rule, x, integer_valued) result(reason)
        character(len=*), intent(in) :: rule
        real(wp), intent(in) :: x
        logical, intent(in) :: integer_valued
        character(len=:), allocatable :: reason
        real(wp) :: a, b
        integer :: comma
        logical :: open_a, open_b
        reason = ''
        select case (rule)
        case ('positive')
            if (.not. x > 0.0_wp) reason = 'must be positive'
        case ('nonnegative')
            if (.not. x >= 0.0_wp) reason = 'must not be negative'
        case ('tolerance', 'abs_tolerance')
            if (.not. x > 0.0_wp) then
                reason = 'must be positive'
            else if (x < min_tolerance) then
                reason = 'must be at least 1e-14 (below, rounding errors of double precision &
                    &dominate the error estimates)'
            else if (rule == 'tolerance' .and. .not. x < 1.0_wp) then
                reason = 'must be less than 1'
            end if
        case default
            comma = index(rule, ',')
            open_a = rule(1:1) == '('
            open_b = rule(len(rule):len(rule)) == ')'
            a = bound(rule(2:comma - 1))
            b = bound(rule(comma + 1:len(rule) - 1))
            if ((open_a .and. .not. x > a) .or. (.not. open_a .and. .not. x >= a) .or. &
                (open_b .and. .not. x < b) .or. (.not. open_b .and. .not. x <= b)) then
                if (b == huge(1.0_wp)) then
                    if (open_a) then
                        reason = 'must be greater than ' // rule(2:comma - 1)
                    else
                        reason = 'must be at least ' // rule(2:comma - 1)
                    end if
                else if (a == -huge(1.0_wp)) then
                    if (open_b) then
                        reason = 'must be less than ' // rule(comma + 1:len(rule) - 1)
                    else
                        reason = 'must be at most ' // rule(comma + 1:len(rule) - 1)
                    end if
                else if (integer_valued .and. .not. open_a .and. .not. open_b) then
                    reason = 'must lie in ' // rule(2:comma - 1) // '..' // &
                        rule(comma + 1:len(rule) - 1)
                else
                    reason = 'must lie in ' // rule(1:comma) // ' ' // rule(comma + 1:)
                end if
            end if
        end select
    end function rule_reason

    !> An interval's bound: a number, or `inf`/`-inf` for none.
    pure real(wp) function bound(text)
        character(len=*), intent(in) :: text
        integer :: ios
        if (text == 'inf') then
            bound = huge(1.0_wp)
        else if (text == '-inf') then
            bound = -huge(1.0_wp)
        else
            read (text, *, iostat=ios) bound
        end if
    end function bound
end module flexmbs_core_rules
