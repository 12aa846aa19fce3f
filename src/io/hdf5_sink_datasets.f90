!> The static datasets and attributes of an HDF5 result (the trajectory's
!> series are the parent module's): texts, real and integer arrays, string
!> lists, attributes of any object; groups of a path created as needed.
submodule (flexmbs_io_hdf5_sink) flexmbs_io_hdf5_sink_datasets
    implicit none

contains

    !> Store a text as a string attribute of '/' (a scalar string dataset
    !> when it is too large for an attribute), replacing an earlier one.
    module procedure sink_write_text
        integer(hid_t) :: str_type, space, dset
        integer :: err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_text before create')
            return
        end if
        if (len(text) <= max_attribute_text) then
            call write_string_attribute(self%file, name, text, err)
        else
            call remove_link(self%file, name, err)
            if (err >= 0) call string_type(len(text), str_type, err)
            if (err >= 0) call h5screate_f(H5S_SCALAR_F, space, err)
            if (err >= 0) call h5dcreate_f(self%file, name, str_type, space, dset, err)
            if (err >= 0) call h5dwrite_f(dset, str_type, text, [1_hsize_t], err)
            if (err >= 0) call h5dclose_f(dset, err)
            if (err >= 0) call h5sclose_f(space, err)
            if (err >= 0) call h5tclose_f(str_type, err)
            if (err >= 0) call write_string_attribute(self%file, name, &
                'stored in dataset /' // name, err)
        end if
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write ' // name)
    end procedure sink_write_text

    !> A 2-D real dataset /name (rows, columns), e.g. the monitor table
    !> (groups of a path created as needed).
    module procedure sink_write_matrix
        integer(hsize_t) :: dims(2)
        integer(hid_t) :: dset
        integer :: err
        dims = shape(values, kind=hsize_t)
        call new_dataset(self, name, H5T_NATIVE_DOUBLE, dims, dset, err, status)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, values, dims, err)
        call close_dataset(self, name, dset, err, status)
    end procedure sink_write_matrix

    !> A 1-D real dataset /name, e.g. the energy at each record.
    module procedure sink_write_vector
        integer(hsize_t) :: dims(1)
        integer(hid_t) :: dset
        integer :: err
        dims = [size(values, kind=hsize_t)]
        call new_dataset(self, name, H5T_NATIVE_DOUBLE, dims, dset, err, status)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, values, dims, err)
        call close_dataset(self, name, dset, err, status)
    end procedure sink_write_vector

    !> A 2-D integer dataset /name (rows, columns), e.g. a connectivity
    !> (groups of a path created as needed).
    module procedure sink_write_integers
        integer(hsize_t) :: dims(2)
        integer(hid_t) :: dset
        integer :: err
        dims = shape(values, kind=hsize_t)
        call new_dataset(self, name, H5T_NATIVE_INTEGER, dims, dset, err, status)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_INTEGER, values, dims, err)
        call close_dataset(self, name, dset, err, status)
    end procedure sink_write_integers

    !> A 1-D integer dataset /name, e.g. a node set.
    module procedure sink_write_integer_list
        integer(hsize_t) :: dims(1)
        integer(hid_t) :: dset
        integer :: err
        dims = [size(values, kind=hsize_t)]
        call new_dataset(self, name, H5T_NATIVE_INTEGER, dims, dset, err, status)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_INTEGER, values, dims, err)
        call close_dataset(self, name, dset, err, status)
    end procedure sink_write_integer_list

    !> A 1-D dataset of UTF-8 strings (variable length: h5py reads str) at
    !> `path`, e.g. the label of every component of /y.
    module procedure sink_write_strings
        character(kind=c_char, len=len(strings) + 1), allocatable, target :: text(:)
        type(c_ptr), allocatable, target :: pointers(:)
        integer(hid_t) :: str_type, dset
        integer :: err, k, close_err
        allocate (text(size(strings)), pointers(size(strings)))
        do k = 1, size(strings)
            text(k) = trim(strings(k)) // c_null_char
            pointers(k) = c_loc(text(k)(1:1))
        end do
        call utf8_string_type(str_type, err)
        if (err >= 0) call new_dataset(self, path, str_type, [size(strings, kind=hsize_t)], &
                                       dset, err, status)
        if (err >= 0 .and. size(strings) > 0) &
            call h5dwrite_f(dset, str_type, c_loc(pointers(1)), err)
        call close_dataset(self, path, dset, err, status)
        call h5tclose_f(str_type, close_err)
    end procedure sink_write_strings

    !> A string attribute `name` = `text` of the dataset or group at `path`.
    module procedure sink_annotate
        integer(hid_t) :: obj
        integer :: err, close_err
        call h5oopen_f(self%file, path, obj, err)
        if (err >= 0) then
            call write_string_attribute(obj, name, text, err)
            call h5oclose_f(obj, close_err)
        end if
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot annotate /' &
                                     // path)
    end procedure sink_annotate

    !> A new dataset `name` of type `dtype` and shape `dims`, the groups of
    !> its path made as needed; err < 0 (and `status` says why when the file
    !> is not open) when it cannot be.
    subroutine new_dataset(self, name, dtype, dims, dset, err, status)
        class(hdf5_sink_t), intent(in) :: self
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: dtype
        integer(hsize_t), intent(in) :: dims(:)
        integer(hid_t), intent(out) :: dset
        integer, intent(out) :: err
        type(status_t), intent(inout) :: status
        integer(hid_t) :: space, lcpl
        integer :: close_err
        dset = -1
        err = -1
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: /' // name // ' before create')
            return
        end if
        ! a resumed run writes its static datasets again
        call remove_link(self%file, name, err)
        if (err < 0) return
        call h5screate_simple_f(size(dims), dims, space, err)
        if (err < 0) return
        call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, name, dtype, space, dset, err, lcpl_id=lcpl)
        call h5pclose_f(lcpl, close_err)
        call h5sclose_f(space, close_err)
    end subroutine new_dataset

    !> Close a dataset new_dataset made; an HDF5 failure (err < 0) on an
    !> open file is an I/O error naming it.
    subroutine close_dataset(self, name, dset, err, status)
        class(hdf5_sink_t), intent(in) :: self
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: dset
        integer, intent(inout) :: err
        type(status_t), intent(inout) :: status
        integer :: close_err
        if (dset >= 0) then
            call h5dclose_f(dset, close_err)
            if (close_err < 0) err = close_err
        end if
        if (err < 0 .and. status%ok()) call status%set(status_io_error, self%path // &
            ': HDF5 cannot write /' // name)
    end subroutine close_dataset

    !> Delete the dataset at `path` when there is one (its groups stay);
    !> err < 0 when it cannot be.
    subroutine remove_link(file, path, err)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: path
        integer, intent(out) :: err
        logical :: exists
        integer :: start, slash
        err = 0
        ! h5lexists_f fails on a path whose group is missing: look level by level
        start = 1
        do while (start <= len(path))
            slash = index(path(start:), '/')
            if (slash == 0) exit
            slash = start + slash - 1
            if (slash > 1) then
                call h5lexists_f(file, path(1:slash - 1), exists, err)
                if (err < 0 .or. .not. exists) return
            end if
            start = slash + 1
        end do
        call h5lexists_f(file, path, exists, err)
        if (err >= 0 .and. exists) call h5ldelete_f(file, path, err)
    end subroutine remove_link
end submodule flexmbs_io_hdf5_sink_datasets
