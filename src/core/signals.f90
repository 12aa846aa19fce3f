!> SIGINT and SIGTERM as a request to stop (docs/user_guide.md, exit codes).
!>
!> The application installs the handlers once (`install_signals`); the
!> run checks `signal_pending` after every accepted step (io/signal_sink)
!> and between the runs of a study, and stops there: outputs flushed and
!> closed, status `status_signal`, and the application exits with
!> 128 + the signal's number (130 for SIGINT, 143 for SIGTERM). The
!> handler itself only records the signal (signals_shim.c); after the
!> first one the default action is back, so a second signal ends the
!> process at once. A library user who installs nothing never sees a
!> pending signal.
module flexmbs_core_signals
    use, intrinsic :: iso_c_binding, only: c_int
    implicit none
    private

    public :: install_signals, signal_pending, caught_signal, signal_name, signal_number

    interface
        function c_install(even_if_ignored) bind(C, name='flexmbs_signals_install') result(rc)
            import :: c_int
            integer(c_int), value :: even_if_ignored
            integer(c_int) :: rc
        end function c_install
        function c_caught() bind(C, name='flexmbs_signals_caught') result(signo)
            import :: c_int
            integer(c_int) :: signo
        end function c_caught
        function c_sigint() bind(C, name='flexmbs_signals_sigint') result(signo)
            import :: c_int
            integer(c_int) :: signo
        end function c_sigint
        function c_sigterm() bind(C, name='flexmbs_signals_sigterm') result(signo)
            import :: c_int
            integer(c_int) :: signo
        end function c_sigterm
    end interface

contains

    !> Catch SIGINT and SIGTERM from now on; false when the system refused.
    !> A signal ignored at start stays ignored (a background job of a shell
    !> without job control ignores SIGINT) unless `even_if_ignored`.
    logical function install_signals(even_if_ignored)
        logical, intent(in), optional :: even_if_ignored
        integer(c_int) :: even
        even = 0_c_int
        if (present(even_if_ignored)) even = merge(1_c_int, 0_c_int, even_if_ignored)
        install_signals = c_install(even) == 0_c_int
    end function install_signals

    !> True once SIGINT or SIGTERM has come.
    logical function signal_pending()
        signal_pending = c_caught() /= 0_c_int
    end function signal_pending

    !> The number of the first signal caught, 0 while none.
    integer function caught_signal()
        caught_signal = int(c_caught())
    end function caught_signal

    !> 'SIGINT', 'SIGTERM' or 'signal N'.
    function signal_name(signo) result(name)
        integer, intent(in) :: signo
        character(len=:), allocatable :: name
        character(len=12) :: buf
        if (signo == int(c_sigint())) then
            name = 'SIGINT'
        else if (signo == int(c_sigterm())) then
            name = 'SIGTERM'
        else
            write (buf, '(a,i0)') 'signal ', signo
            name = trim(buf)
        end if
    end function signal_name

    !> The number of 'SIGINT' or 'SIGTERM'; 0 for any other name.
    integer function signal_number(name)
        character(len=*), intent(in) :: name
        select case (name)
        case ('SIGINT'); signal_number = int(c_sigint())
        case ('SIGTERM'); signal_number = int(c_sigterm())
        case default; signal_number = 0
        end select
    end function signal_number
end module flexmbs_core_signals
