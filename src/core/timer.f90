!> CPU and wall-clock timers.
module flexmbs_core_timer
    use, intrinsic :: iso_fortran_env, only: int64
    use flexmbs_core_kinds, only: wp
    implicit none
    private

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
end module flexmbs_core_timer
