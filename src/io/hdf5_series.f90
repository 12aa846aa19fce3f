!> Extendible record series in an HDF5 file, written in batches.
!>
!> A series is a chunked dataset whose last dimension grows by one record
!> at a time: (records) for the time, (m, records) for a vector per record,
!> (m, columns, records) for a matrix per record. Records are collected in
!> memory (`add`) and written together (`write_pending`): one extent change
!> and one hyperslab write per batch instead of per record, which is what
!> lets a small state reach millions of records a second.
module flexmbs_io_hdf5_series
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_io_hdf5_text, only: group_creating
    implicit none
    private

    public :: create_series, open_series

    !> One series and the records not yet written to it.
    type, public :: series_batch_t
        integer(hid_t) :: dset = -1
        integer :: rows = 0          !! m; 0 for the 1-D time series
        integer :: columns = 1       !! > 1: an (m, columns) matrix per record
        integer :: count = 0         !! records held
        real(wp), allocatable :: pending(:, :) !! (values of a record, capacity)
    contains
        procedure :: reserve => batch_reserve
        procedure :: add => batch_add
        procedure :: write_pending => batch_write_pending
        procedure :: width => batch_width
        procedure :: close => batch_close
    end type series_batch_t

contains

    !> Values of one record.
    pure integer function batch_width(self)
        class(series_batch_t), intent(in) :: self
        batch_width = max(self%rows, 1) * self%columns
    end function batch_width

    !> Room for `capacity` records (the records held are kept); stat /= 0
    !> when the memory cannot be had.
    subroutine batch_reserve(self, capacity, stat)
        class(series_batch_t), intent(inout) :: self
        integer, intent(in) :: capacity
        integer, intent(out) :: stat
        real(wp), allocatable :: grown(:, :)
        stat = 0
        if (allocated(self%pending)) then
            if (size(self%pending, 2) >= capacity) return
        end if
        allocate (grown(self%width(), max(capacity, 1)), stat=stat)
        if (stat /= 0) return
        if (self%count > 0) grown(:, 1:self%count) = self%pending(:, 1:self%count)
        call move_alloc(grown, self%pending)
    end subroutine batch_reserve

    !> Hold one record (the caller has reserved room for it).
    pure subroutine batch_add(self, values)
        class(series_batch_t), intent(inout) :: self
        real(wp), intent(in) :: values(:)
        self%count = self%count + 1
        self%pending(:, self%count) = values
    end subroutine batch_add

    !> Write the records held after the first `written` records of the
    !> dataset (extending it), and forget them; err < 0 on failure.
    subroutine batch_write_pending(self, written, err)
        class(series_batch_t), intent(inout) :: self
        integer, intent(in) :: written
        integer, intent(out) :: err
        integer(hid_t) :: filespace, memspace
        integer(hsize_t) :: size_new(3), offset(3), count(3)
        integer :: rank, close_err
        err = 0
        if (self%count == 0) return
        if (self%rows == 0) then
            rank = 1
            size_new(1) = int(written + self%count, hsize_t)
            offset(1) = int(written, hsize_t)
            count(1) = int(self%count, hsize_t)
        else if (self%columns > 1) then
            rank = 3
            size_new = [int(self%rows, hsize_t), int(self%columns, hsize_t), &
                        int(written + self%count, hsize_t)]
            offset = [0_hsize_t, 0_hsize_t, int(written, hsize_t)]
            count = [int(self%rows, hsize_t), int(self%columns, hsize_t), &
                     int(self%count, hsize_t)]
        else
            rank = 2
            size_new(1:2) = [int(self%rows, hsize_t), int(written + self%count, hsize_t)]
            offset(1:2) = [0_hsize_t, int(written, hsize_t)]
            count(1:2) = [int(self%rows, hsize_t), int(self%count, hsize_t)]
        end if
        call h5dset_extent_f(self%dset, size_new(1:rank), err)
        if (err < 0) return
        call h5dget_space_f(self%dset, filespace, err)
        if (err < 0) return
        call h5sselect_hyperslab_f(filespace, H5S_SELECT_SET_F, offset(1:rank), &
                                   count(1:rank), err)
        if (err >= 0) call h5screate_simple_f(rank, count(1:rank), memspace, err)
        if (err >= 0) then
            ! pending(:, 1:count) is contiguous: it is the hyperslab's memory image
            call h5dwrite_f(self%dset, H5T_NATIVE_DOUBLE, self%pending(:, 1:self%count), &
                            count(1:rank), err, mem_space_id=memspace, file_space_id=filespace)
            call h5sclose_f(memspace, close_err)
        end if
        call h5sclose_f(filespace, close_err)
        if (err >= 0) self%count = 0
    end subroutine batch_write_pending

    !> Close the dataset (records still held are dropped: write them first).
    subroutine batch_close(self, err)
        class(series_batch_t), intent(inout) :: self
        integer, intent(out) :: err
        err = 0
        if (self%dset >= 0) call h5dclose_f(self%dset, err)
        self%dset = -1
        self%count = 0
    end subroutine batch_close

    !> An empty extendible dataset: (0) for m = 0, else (m, 0), or
    !> (m, columns, 0) for columns > 1, chunked by `per_chunk` records; the
    !> batch that writes it in `batch`.
    subroutine create_series(file, name, m, per_chunk, batch, err, groups, columns)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: m, per_chunk
        type(series_batch_t), intent(out) :: batch
        integer, intent(out) :: err
        logical, intent(in), optional :: groups !! create the groups of a path
        integer, intent(in), optional :: columns !! > 1: (m, columns, records)
        integer(hid_t) :: space, plist, lcpl
        integer(hsize_t), allocatable :: fixed(:)
        integer :: rank, close_err
        call record_shape(batch, m, columns, fixed)
        rank = size(fixed) + 1
        call h5screate_simple_f(rank, [fixed, 0_hsize_t], space, err, [fixed, H5S_UNLIMITED_F])
        if (err < 0) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, err)
        if (err >= 0) call h5pset_chunk_f(plist, rank, [fixed, int(per_chunk, hsize_t)], err)
        lcpl = H5P_DEFAULT_F
        if (present(groups)) then
            if (groups .and. err >= 0) call group_creating(lcpl, err)
        end if
        if (err >= 0) call h5dcreate_f(file, name, H5T_NATIVE_DOUBLE, space, batch%dset, err, &
                                       plist, lcpl_id=lcpl)
        if (lcpl /= H5P_DEFAULT_F) call h5pclose_f(lcpl, close_err)
        if (err >= 0) call h5pclose_f(plist, err)
        if (err >= 0) call h5sclose_f(space, err)
    end subroutine create_series

    !> The series `name` that an earlier run created (create_series' m and
    !> columns), cut to its first `kept` records: a resumed run continues
    !> it. err < 0 when it is missing, has another shape or fewer records.
    subroutine open_series(file, name, m, kept, batch, err, columns)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: m, kept
        type(series_batch_t), intent(out) :: batch
        integer, intent(out) :: err
        integer, intent(in), optional :: columns
        integer(hid_t) :: space
        integer(hsize_t) :: dims(3), maxdims(3)
        integer(hsize_t), allocatable :: fixed(:)
        integer :: rank, close_err
        call record_shape(batch, m, columns, fixed)
        rank = size(fixed) + 1
        call h5dopen_f(file, name, batch%dset, err)
        if (err < 0) return
        call h5dget_space_f(batch%dset, space, err)
        if (err < 0) return
        call h5sget_simple_extent_ndims_f(space, close_err, err)
        if (err >= 0 .and. close_err /= rank) err = -1
        if (err >= 0) call h5sget_simple_extent_dims_f(space, dims(1:rank), maxdims(1:rank), err)
        call h5sclose_f(space, close_err)
        if (err < 0) return
        if (any(dims(1:rank - 1) /= fixed) .or. dims(rank) < int(kept, hsize_t)) then
            err = -1
            return
        end if
        dims(rank) = int(kept, hsize_t)
        call h5dset_extent_f(batch%dset, dims(1:rank), err)
    end subroutine open_series

    !> A series' shape before its records: () for m = 0, (m), or (m,
    !> columns) for columns > 1; the batch learns its rows and columns.
    subroutine record_shape(batch, m, columns, fixed)
        type(series_batch_t), intent(inout) :: batch
        integer, intent(in) :: m
        integer, intent(in), optional :: columns
        integer(hsize_t), allocatable, intent(out) :: fixed(:)
        integer :: nc
        nc = 1
        if (present(columns)) nc = max(columns, 1)
        batch%rows = m
        batch%columns = nc
        if (m == 0) then
            allocate (fixed(0))
        else if (nc > 1) then
            fixed = [int(m, hsize_t), int(nc, hsize_t)]
        else
            fixed = [int(m, hsize_t)]
        end if
    end subroutine record_shape
end module flexmbs_io_hdf5_series
