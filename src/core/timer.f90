!> CPU and wall-clock timers.
module flexmbs_core_timer
    use, intrinsic :: iso_fortran_env, only: int64
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    public :: iso_now

    !> Measures CPU and wall seconds since `start`.
    type, public :: timer_t
        real(wp) :: cpu0 = 0.0_wp
        integer(int64) :: count0 = 0
    contains
        procedure :: start => timer_start
        procedure :: cpu => timer_cpu
        procedure :: wall => timer_wall
    end type timer_t

contains

    !> Start (or restart) the timer.
    subroutine timer_start(self)
        class(timer_t), intent(inout) :: self
        call cpu_time(self%cpu0)
        call system_clock(self%count0)
    end subroutine timer_start

    !> CPU seconds since start.
    function timer_cpu(self) result(seconds)
        class(timer_t), intent(in) :: self
        real(wp) :: seconds
        real(wp) :: now
        call cpu_time(now)
        seconds = now - self%cpu0
    end function timer_cpu

    !> Wall seconds since start.
    function timer_wall(self) result(seconds)
        class(timer_t), intent(in) :: self
        real(wp) :: seconds
        integer(int64) :: now, rate
        call system_clock(now, rate)
        seconds = real(now - self%count0, wp) / real(max(rate, 1_int64), wp)
    end function timer_wall

    !> The local date and time in ISO 8601 with the offset from UTC
    !> (2026-11-26T11:08:53+00:00), as results record when they were made.
    function iso_now() result(text)
        character(len=:), allocatable :: text
        character(len=8) :: date
        character(len=10) :: time
        character(len=5) :: zone
        call date_and_time(date, time, zone)
        text = date(1:4) // '-' // date(5:6) // '-' // date(7:8) // 'T' // time(1:2) // ':' // &
            time(3:4) // ':' // time(5:6) // zone(1:3) // ':' // zone(4:5)
    end function iso_now
end module flexmbs_core_timer
