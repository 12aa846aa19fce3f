!> The checkpoint a run keeps in its HDF5 result, from which `flexmbs run
!> --resume` continues it (docs/output.md, "Restart"):
!>
!>   /checkpoint/state  (n + 4)  t, h, order, records, then y: one write, so
!>                      that a run killed while writing it leaves either the
!>                      old or the new state, never a mix of the two
!>   attributes of /checkpoint: written (ISO 8601), piece (1 for the first
!>                      run, +1 per resume), the piece's live counters NST,
!>                      NAC, CPU, WALL up to the checkpoint, and prior_NST ..
!>                      prior_WALL, the statistics of the pieces before it
!>
!> y is the state of an accepted step (not an interpolated output record:
!> those lie slightly off the constraints), h that step's size, order the
!> order its method used (0 for Runge–Kutta and extrapolation), records the
!> number of records of /time up to and including t: a resume keeps those
!> and replaces the rest.
!>
!> The root attributes `scene_fingerprint` and `scene_settings` say which
!> scene wrote the file (run/resume compares them); `restart_times` lists
!> the time at which each resume started.
module flexmbs_io_checkpoint
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_timer, only: iso_now
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_count, cause_attributes
    use flexmbs_io_hdf5_text, only: read_string_attribute, read_stored_text, &
        write_string_attribute, write_int_attribute, write_real_attribute, &
        read_int_attribute, read_real_attribute
    implicit none
    private

    public :: write_checkpoint, read_checkpoint, add_restart_time, stats_sum, put_stats

    !> Values of /checkpoint/state before y.
    integer, parameter :: head = 4

    !> A run's last checkpoint and what its file says of the run (module
    !> header).
    type, public :: checkpoint_t
        real(wp) :: t = 0.0_wp          !! time of the accepted step
        real(wp) :: h = 0.0_wp          !! its step size
        integer :: order = 0            !! its order (0: none, RK or extrapolation)
        integer :: records = 0          !! records of /time up to t
        integer :: piece = 1            !! 1 for the first run, +1 per resume
        real(wp), allocatable :: y(:)   !! the state at t
        !> statistics of the pieces before this one, and this piece's
        !> counters up to the checkpoint (NST, NAC, NRJ, CPU, WALL only)
        type(dae_stats_t) :: prior, live
        ! What the file says besides (read_checkpoint only):
        character(len=:), allocatable :: fingerprint, settings
        !> the outcome written when the last piece ended ('' when it was
        !> killed outright), the time it reached, its (summed) statistics
        character(len=:), allocatable :: outcome
        real(wp) :: t_reached = 0.0_wp
        type(dae_stats_t) :: ended
    end type checkpoint_t

contains

    !> Write `cp` as the file's checkpoint (module header), replacing the
    !> one before; err < 0 on failure. The caller has written the records
    !> up to cp%t and flushes after.
    subroutine write_checkpoint(file, cp, buffer, err)
        integer(hid_t), intent(in) :: file
        type(checkpoint_t), intent(in) :: cp
        real(wp), intent(inout) :: buffer(:)   !! size(cp%y) + 4, the caller's
        integer, intent(out) :: err
        integer(hid_t) :: group, space, dset
        integer :: close_err
        logical :: exists
        buffer(1:head) = [cp%t, cp%h, real(cp%order, wp), real(cp%records, wp)]
        buffer(head + 1:) = cp%y
        call h5lexists_f(file, 'checkpoint', exists, err)
        if (err < 0) return
        if (exists) then
            call h5gopen_f(file, 'checkpoint', group, err)
            if (err < 0) return
            call h5dopen_f(group, 'state', dset, err)
        else
            call h5gcreate_f(file, 'checkpoint', group, err)
            if (err < 0) return
            call write_string_attribute(group, 'layout', 't, h, order, records, then y', err)
            if (err >= 0) call h5screate_simple_f(1, [size(buffer, kind=hsize_t)], space, err)
            if (err >= 0) then
                call h5dcreate_f(group, 'state', H5T_NATIVE_DOUBLE, space, dset, err)
                call h5sclose_f(space, close_err)
            end if
        end if
        if (err >= 0) then
            call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, buffer, [size(buffer, kind=hsize_t)], err)
            call h5dclose_f(dset, close_err)
        end if
        if (err >= 0) call write_int_attribute(group, 'piece', cp%piece, err)
        if (err >= 0) call write_string_attribute(group, 'written', iso_now(), err)
        if (err >= 0) call put_stats(group, '', cp%live, err)
        if (err >= 0) call put_stats(group, 'prior_', cp%prior, err)
        call h5gclose_f(group, close_err)
    end subroutine write_checkpoint

    !> The checkpoint of the flexmbs result `path`, with its fingerprint,
    !> settings, outcome and statistics; bad input (naming the file and what
    !> it lacks) when it is not a result or has no checkpoint.
    subroutine read_checkpoint(path, cp, status)
        character(len=*), intent(in) :: path
        type(checkpoint_t), intent(out) :: cp
        type(status_t), intent(out) :: status
        integer(hid_t) :: file, group, dset, space
        integer(hsize_t) :: dims(1), maxdims(1)
        integer :: err, close_err
        logical :: exists
        real(wp), allocatable :: state(:)
        call h5open_f(err)
        call h5eset_auto_f(0, err)
        inquire (file=path, exist=exists)
        if (.not. exists) then
            call status%set(status_bad_input, path // ': no such file to resume from')
            return
        end if
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0) then
            call status%set(status_bad_input, path // ': not an HDF5 file (or one another &
                &program is writing, or a run killed while creating it): nothing to resume from')
            return
        end if
        ! (a run killed while creating its file has no fingerprint yet either)
        call h5lexists_f(file, 'checkpoint', exists, err)
        if (err < 0 .or. .not. exists) then
            call status%set(status_bad_input, path // ': no checkpoint: the run ended or was &
                &stopped before its first accepted step; run the scene again instead')
            call h5fclose_f(file, close_err)
            return
        end if
        call read_stored_text(file, 'scene_fingerprint', cp%fingerprint, err)
        if (err < 0 .or. len(cp%fingerprint) == 0) then
            call status%set(status_bad_input, path // ': not a flexmbs result that can be &
                &resumed (no root attribute scene_fingerprint: another program or an &
                &older flexmbs wrote it)')
            call h5fclose_f(file, close_err)
            return
        end if
        call read_stored_text(file, 'scene_settings', cp%settings, err)
        call h5gopen_f(file, 'checkpoint', group, err)
        if (err >= 0) call h5dopen_f(group, 'state', dset, err)
        if (err >= 0) then
            call h5dget_space_f(dset, space, err)
            if (err >= 0) call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
            call h5sclose_f(space, close_err)
            if (err >= 0 .and. dims(1) > head) then
                allocate (state(dims(1)))
                call h5dread_f(dset, H5T_NATIVE_DOUBLE, state, dims, err)
            else
                err = -1
            end if
            call h5dclose_f(dset, close_err)
        end if
        if (err >= 0) call read_int_attribute(group, 'piece', cp%piece, err)
        if (err >= 0) call get_stats(group, '', cp%live, err)
        if (err >= 0) call get_stats(group, 'prior_', cp%prior, err)
        call h5gclose_f(group, close_err)
        if (err < 0) then
            call status%set(status_bad_input, path // ': its /checkpoint cannot be read')
            call h5fclose_f(file, close_err)
            return
        end if
        cp%t = state(1)
        cp%h = state(2)
        cp%order = nint(state(3))
        cp%records = nint(state(4))
        cp%y = state(head + 1:)
        ! the outcome and statistics the last piece wrote when it ended
        cp%outcome = ''
        call h5aexists_f(file, 'outcome', exists, err)
        if (err >= 0 .and. exists) then
            call read_string_attribute(file, 'outcome', cp%outcome, err)
            if (err >= 0) call read_real_attribute(file, 't_reached', cp%t_reached, err)
            if (err >= 0) call get_stats(file, '', cp%ended, err)
            if (err < 0) cp%outcome = ''
        end if
        call h5fclose_f(file, close_err)
    end subroutine read_checkpoint

    !> Append t to the root attribute `restart_times` of the open file.
    subroutine add_restart_time(file, t, err)
        integer(hid_t), intent(in) :: file
        real(wp), intent(in) :: t
        integer, intent(out) :: err
        real(wp), allocatable :: times(:)
        integer(hid_t) :: attr, space
        integer(hsize_t) :: dims(1), maxdims(1)
        integer :: close_err
        logical :: exists
        allocate (times(0))
        call h5aexists_f(file, 'restart_times', exists, err)
        if (err < 0) return
        if (exists) then
            call h5aopen_f(file, 'restart_times', attr, err)
            if (err >= 0) call h5aget_space_f(attr, space, err)
            if (err >= 0) then
                call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
                call h5sclose_f(space, close_err)
            end if
            if (err >= 0) then
                deallocate (times)
                allocate (times(dims(1)))
                call h5aread_f(attr, H5T_NATIVE_DOUBLE, times, dims, err)
            end if
            call h5aclose_f(attr, close_err)
            if (err < 0) return
            call h5adelete_f(file, 'restart_times', err)
            if (err < 0) return
        end if
        times = [times, t]
        dims(1) = size(times, kind=hsize_t)
        call h5screate_simple_f(1, dims, space, err)
        if (err < 0) return
        call h5acreate_f(file, 'restart_times', H5T_NATIVE_DOUBLE, space, attr, err)
        if (err >= 0) then
            call h5awrite_f(attr, H5T_NATIVE_DOUBLE, times, dims, err)
            call h5aclose_f(attr, close_err)
        end if
        call h5sclose_f(space, close_err)
    end subroutine add_restart_time

    !> The statistics of two pieces of one run: counters, causes and times
    !> added; the last time reached, step, linear solver and warning of `b`
    !> (the later piece).
    function stats_sum(a, b) result(total)
        type(dae_stats_t), intent(in) :: a, b
        type(dae_stats_t) :: total
        total = b
        total%nst = a%nst + b%nst
        total%nac = a%nac + b%nac
        total%nrj = a%nrj + b%nrj
        total%nfe = a%nfe + b%nfe
        total%nfe_jac = a%nfe_jac + b%nfe_jac
        total%nje = a%nje + b%nje
        total%ndec = a%ndec + b%ndec
        total%nsol = a%nsol + b%nsol
        total%nprj = a%nprj + b%nprj
        total%cpu = a%cpu + b%cpu
        total%wall = a%wall + b%wall
        call total%rejections%restore(a%rejections%counts_by_cause() + &
            b%rejections%counts_by_cause(), b%rejections%refusal_reason())
    end function stats_sum

    !> The counters and times as attributes PREFIX NST .. PREFIX WALL of obj.
    subroutine put_stats(obj, prefix, stats, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: prefix
        type(dae_stats_t), intent(in) :: stats
        integer, intent(inout) :: err
        integer :: c, counts(cause_count)
        call write_int_attribute(obj, prefix // 'NST', stats%nst, err)
        call write_int_attribute(obj, prefix // 'NAC', stats%nac, err)
        call write_int_attribute(obj, prefix // 'NRJ', stats%nrj, err)
        call write_int_attribute(obj, prefix // 'NFE', stats%nfe, err)
        call write_int_attribute(obj, prefix // 'NFE_JAC', stats%nfe_jac, err)
        call write_int_attribute(obj, prefix // 'NJE', stats%nje, err)
        call write_int_attribute(obj, prefix // 'NDEC', stats%ndec, err)
        call write_int_attribute(obj, prefix // 'NSOL', stats%nsol, err)
        call write_int_attribute(obj, prefix // 'NPRJ', stats%nprj, err)
        counts = stats%rejections%counts_by_cause()
        do c = 1, cause_count
            call write_int_attribute(obj, prefix // trim(cause_attributes(c)), counts(c), err)
        end do
        call write_real_attribute(obj, prefix // 'CPU', stats%cpu, err)
        call write_real_attribute(obj, prefix // 'WALL', stats%wall, err)
    end subroutine put_stats

    !> put_stats' attributes read back (those missing count 0: the causes of
    !> an older file).
    subroutine get_stats(obj, prefix, stats, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: prefix
        type(dae_stats_t), intent(out) :: stats
        integer, intent(inout) :: err
        integer :: c, counts(cause_count)
        call read_int_attribute(obj, prefix // 'NST', stats%nst, err)
        call read_int_attribute(obj, prefix // 'NAC', stats%nac, err)
        call read_int_attribute(obj, prefix // 'NRJ', stats%nrj, err)
        call read_int_attribute(obj, prefix // 'NFE', stats%nfe, err)
        call read_int_attribute(obj, prefix // 'NFE_JAC', stats%nfe_jac, err)
        call read_int_attribute(obj, prefix // 'NJE', stats%nje, err)
        call read_int_attribute(obj, prefix // 'NDEC', stats%ndec, err)
        call read_int_attribute(obj, prefix // 'NSOL', stats%nsol, err)
        call read_int_attribute(obj, prefix // 'NPRJ', stats%nprj, err)
        do c = 1, cause_count
            call read_int_attribute(obj, prefix // trim(cause_attributes(c)), counts(c), err)
        end do
        call stats%rejections%restore(counts, '')
        call read_real_attribute(obj, prefix // 'CPU', stats%cpu, err)
        call read_real_attribute(obj, prefix // 'WALL', stats%wall, err)
    end subroutine get_stats
end module flexmbs_io_checkpoint
