!> A progress line on standard error: simulated time, percentage, steps
!> and rejections, the wall time elapsed and an estimate of the time left
!> (the elapsed time scaled by the simulated time still to go: steps grow
!> or shrink as the solution does, so it is a guess that firms up as the
!> run goes), redrawn in place with a carriage return.
!>
!> It is silent when standard error is not a terminal (logs and pipes get
!> no '\r' clutter) or when the user asked for quiet. Redraws are limited
!> to a few per second so that cheap steps are not slowed by output.
module flexmbs_io_progress
    use, intrinsic :: iso_c_binding, only: c_int
    use, intrinsic :: iso_fortran_env, only: error_unit
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_timer, only: timer_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    implicit none
    private

    !> Seconds between two redraws.
    real(wp), parameter :: redraw_interval = 0.2_wp

    interface
        function c_isatty(fd) bind(c, name='isatty') result(yes)
            import :: c_int
            integer(c_int), value :: fd
            integer(c_int) :: yes
        end function c_isatty
    end interface

    !> The progress line (see the module): the run's time span, the state of
    !> the display and the solver asked for its step counts.
    type, extends(sink_t), public :: progress_t
        logical :: enabled = .false.
        integer :: unit = error_unit
        real(wp) :: t_start = 0.0_wp, t_end = 1.0_wp
        real(wp) :: t = 0.0_wp
        integer :: steps = 0
        !> The running solver, asked for its live step counts
        !> (dae_solver_t%step_counts); rejections are shown only with it.
        class(dae_solver_t), pointer :: solver => null()
        logical :: drawn = .false.
        real(wp) :: last_draw = -huge(1.0_wp)
        type(timer_t) :: clock
    contains
        procedure :: output => progress_output
        procedure :: wants_steps => progress_wants_steps
        procedure :: step => progress_step
        procedure :: finish => progress_finish
        procedure :: watch => progress_watch
        procedure :: line => progress_line
    end type progress_t

    public :: new_progress, stderr_is_terminal, announce

contains

    !> A progress display for [t_start, t_end]; disabled when `quiet` or
    !> when standard error is no terminal, unless `unit` is given (tests).
    function new_progress(t_start, t_end, quiet, unit) result(progress)
        real(wp), intent(in) :: t_start, t_end
        logical, intent(in) :: quiet
        integer, intent(in), optional :: unit !! draw here instead, terminal or not
        type(progress_t) :: progress
        progress%t_start = t_start
        progress%t_end = t_end
        progress%t = t_start
        if (present(unit)) then
            progress%unit = unit
            progress%enabled = .not. quiet
        else
            progress%enabled = .not. quiet .and. stderr_is_terminal()
        end if
        call progress%clock%start()
    end function new_progress

    !> A line a user must read before a long wait (an output of gigabytes),
    !> on standard error, terminal or not, quiet or not.
    subroutine announce(text)
        character(len=*), intent(in) :: text
        write (error_unit, '(a)') 'flexmbs: ' // text
        flush (error_unit)
    end subroutine announce

    !> True when file descriptor 2 is a terminal.
    logical function stderr_is_terminal()
        stderr_is_terminal = c_isatty(2_c_int) == 1_c_int
    end function stderr_is_terminal

    !> Show rejections from the counts the solver keeps as it goes; it must
    !> outlive the display.
    subroutine progress_watch(self, solver)
        class(progress_t), intent(inout) :: self
        class(dae_solver_t), intent(in), target :: solver
        self%solver => solver
    end subroutine progress_watch

    subroutine progress_output(self, t, y, status)
        class(progress_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
        if (.not. self%enabled) return
        self%t = t
        call draw(self, .false.)
    end subroutine progress_output

    logical function progress_wants_steps(self)
        class(progress_t), intent(in) :: self
        progress_wants_steps = self%enabled
    end function progress_wants_steps

    subroutine progress_step(self, nr, t_old, t, y, dense, stop, status)
        class(progress_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        if (.not. self%enabled) return
        self%t = t
        self%steps = nr - 1
        call draw(self, .false.)
    end subroutine progress_step

    !> Draw the final state and end the line, so later output starts clean.
    subroutine progress_finish(self, status)
        class(progress_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        if (.not. self%enabled) return
        call draw(self, .true.)
        write (self%unit, '(a)') ''
        flush (self%unit)
        self%drawn = .false.
    end subroutine progress_finish

    !> The text of the line as it stands; `elapsed` (wall seconds) instead
    !> of the display's own clock (tests).
    function progress_line(self, elapsed) result(line)
        class(progress_t), intent(in) :: self
        real(wp), intent(in), optional :: elapsed
        character(len=:), allocatable :: line
        character(len=160) :: buf
        real(wp) :: percent, span, seconds
        integer :: attempted, accepted
        span = self%t_end - self%t_start
        percent = 100.0_wp
        if (span /= 0.0_wp) percent = 100.0_wp * (self%t - self%t_start) / span
        percent = max(0.0_wp, min(100.0_wp, percent))
        write (buf, '(a,es12.5,a,f6.1,a,i0)') 't = ', self%t, ' s  ', percent, &
            ' %  steps ', self%steps
        line = trim(buf)
        if (associated(self%solver)) then
            call self%solver%step_counts(attempted, accepted)
            if (attempted > 0) then
                write (buf, '(a,i0)') '  rejected ', attempted - accepted
                line = line // trim(buf)
            end if
        end if
        if (present(elapsed)) then
            seconds = elapsed
        else
            seconds = self%clock%wall()
        end if
        line = line // '  elapsed ' // duration_text(seconds)
        ! nothing to scale before the first step, nothing left at the end
        if (percent > 0.0_wp .and. percent < 100.0_wp) line = line // '  left ~' // &
            duration_text(seconds * (100.0_wp - percent) / percent)
    end function progress_line

    !> Wall seconds as m:ss, or h:mm:ss from an hour on.
    pure function duration_text(seconds) result(text)
        real(wp), intent(in) :: seconds
        character(len=:), allocatable :: text
        character(len=32) :: buf
        integer :: s
        s = nint(max(0.0_wp, min(seconds, 1.0e8_wp)))
        if (s < 3600) then
            write (buf, '(i0,a,i2.2)') s / 60, ':', mod(s, 60)
        else
            write (buf, '(i0,a,i2.2,a,i2.2)') s / 3600, ':', mod(s, 3600) / 60, ':', mod(s, 60)
        end if
        text = trim(buf)
    end function duration_text

    subroutine draw(self, force)
        class(progress_t), intent(inout) :: self
        logical, intent(in) :: force
        real(wp) :: now
        now = self%clock%wall()
        if (.not. force .and. now - self%last_draw < redraw_interval) return
        self%last_draw = now
        ! pad so a shorter line fully covers the previous one
        write (self%unit, '(a)', advance='no') achar(13) // self%line() // '   '
        flush (self%unit)
        self%drawn = .true.
    end subroutine draw
end module flexmbs_io_progress
