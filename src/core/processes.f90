!> Child processes without a shell (processes_shim.c, posix_spawnp):
!> start a program with its arguments as they are, wait for one of several
!> to end, pass a signal on, and the path of this program's executable.
!> A parallel sweep runs its points so (app/), and `--submit` runs sbatch.
module flexmbs_core_processes
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_files, only: error_text
    implicit none
    private

    public :: start_process, wait_any_process, signal_process, executable_path

    !> wait_any_process's answers besides an index: the time limit passed,
    !> or SIGINT or SIGTERM was caught (core/signals).
    integer, parameter, public :: wait_timeout = -1, wait_signal = -2

    integer, parameter :: max_path = 4096

    interface
        function c_spawn(args, nargs, out, err, own_group) &
            bind(C, name='flexmbs_process_spawn') result(pid)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: args(*), out(*), err(*)
            integer(c_int), value :: nargs, own_group
            integer(c_int) :: pid
        end function c_spawn
        function c_wait_any(pids, n, timeout_ms, stop_on_signal, code, signo) &
            bind(C, name='flexmbs_process_wait_any') result(index)
            import :: c_int
            integer(c_int), intent(in) :: pids(*)
            integer(c_int), value :: n, timeout_ms, stop_on_signal
            integer(c_int), intent(out) :: code, signo
            integer(c_int) :: index
        end function c_wait_any
        function c_signal(pid, signo) bind(C, name='flexmbs_process_signal') result(rc)
            import :: c_int
            integer(c_int), value :: pid, signo
            integer(c_int) :: rc
        end function c_signal
        function c_self(out, n) bind(C, name='flexmbs_process_self') result(length)
            import :: c_char, c_int
            character(kind=c_char), intent(out) :: out(*)
            integer(c_int), value :: n
            integer(c_int) :: length
        end function c_self
    end interface

contains

    !> Start `args(1)` (searched in PATH) with the arguments `args(2:)`,
    !> each without its trailing blanks; standard output to the file
    !> `output` ('' = this program's), standard error to `errors` or, when
    !> absent or '', with the output. `own_group`: in a process group of its
    !> own (a terminal's Ctrl-C then reaches this program only).
    subroutine start_process(args, output, pid, status, errors, own_group)
        character(len=*), intent(in) :: args(:), output
        integer, intent(out) :: pid
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: errors
        logical, intent(in), optional :: own_group
        character(len=:), allocatable :: packed, err
        integer :: i
        packed = ''
        do i = 1, size(args)
            packed = packed // trim(args(i)) // c_null_char
        end do
        err = ''
        if (present(errors)) err = errors
        pid = int(c_spawn(packed, int(size(args), c_int), output // c_null_char, &
                          err // c_null_char, merge(1_c_int, 0_c_int, given(own_group))))
        if (pid <= 0) call status%set(status_io_error, trim(args(1)) // &
            ': cannot start it: ' // error_text(int(-pid, c_int)))
    end subroutine start_process

    !> Wait until one of the children `pids` (entries <= 0 are skipped)
    !> ends: `index` is its position in `pids` and `exit_code` its exit
    !> status, or `signo` the signal that ended it. `index` is wait_timeout
    !> when `timeout_ms` (>= 0; < 0 waits for ever) passed first, and
    !> wait_signal when `stop_on_signal` and SIGINT or SIGTERM was caught.
    subroutine wait_any_process(pids, timeout_ms, stop_on_signal, index, exit_code, signo)
        integer, intent(in) :: pids(:)
        integer, intent(in) :: timeout_ms
        logical, intent(in) :: stop_on_signal
        integer, intent(out) :: index, exit_code, signo
        integer(c_int) :: code, sig
        index = int(c_wait_any(int(pids, c_int), int(size(pids), c_int), &
                               int(timeout_ms, c_int), merge(1_c_int, 0_c_int, stop_on_signal), &
                               code, sig))
        if (index >= 0) index = index + 1
        exit_code = int(code)
        signo = int(sig)
    end subroutine wait_any_process

    !> Send signal `signo` to the child `pid` (nothing when it has ended).
    subroutine signal_process(pid, signo)
        integer, intent(in) :: pid, signo
        integer(c_int) :: rc
        rc = c_signal(int(pid, c_int), int(signo, c_int))
    end subroutine signal_process

    !> The absolute path of this program's executable ('' when unknown).
    function executable_path() result(path)
        character(len=:), allocatable :: path
        character(kind=c_char, len=max_path) :: buf
        integer :: length
        length = int(c_self(buf, int(max_path, c_int)))
        path = ''
        if (length > 0) path = buf(1:length)
    end function executable_path

    pure logical function given(flag)
        logical, intent(in), optional :: flag
        given = .false.
        if (present(flag)) given = flag
    end function given
end module flexmbs_core_processes
