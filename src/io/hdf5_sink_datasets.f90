!> The static datasets and attributes of an HDF5 result (the trajectory's
!> series are the parent module's): texts, real and integer arrays, string
!> lists, attributes of any object; groups of a path created as needed.
submodule (flexmbs_io_hdf5_sink) flexmbs_io_hdf5_sink_datasets
    implicit none

contains

    !> Store a text as a string attribute of '/' (a scalar string dataset
    !> when it is too large for an attribute), replacing an earlier one.
    module subroutine sink_write_text(self, name, text, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name, text
        type(status_t), intent(out) :: status
        integer(hid_t) :: str_type, space, dset
        integer :: err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_text before create')
            return
        end if
        if (len(text) <= max_attribute_text) then
            call write_string_attribute(self%file, name, text, err)
        else
            call string_type(len(text), str_type, err)
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
    end subroutine sink_write_text

    !> A 2-D real dataset /name (rows, columns), e.g. the monitor table
    !> (groups of a path created as needed).
    module subroutine sink_write_matrix(self, name, values, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: values(:, :)
        type(status_t), intent(out) :: status
        integer(hid_t) :: space, dset, lcpl
        integer(hsize_t) :: dims(2)
        integer :: err, close_err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_matrix before create')
            return
        end if
        dims = shape(values, kind=hsize_t)
        call h5screate_simple_f(2, dims, space, err)
        if (err >= 0) call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, name, H5T_NATIVE_DOUBLE, space, dset, err, &
                                       lcpl_id=lcpl)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, values, dims, err)
        if (err >= 0) call h5dclose_f(dset, err)
        if (err >= 0) call h5sclose_f(space, err)
        call h5pclose_f(lcpl, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write ' // name)
    end subroutine sink_write_matrix

    !> A 1-D real dataset /name, e.g. the energy at each record.
    module subroutine sink_write_vector(self, name, values, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: values(:)
        type(status_t), intent(out) :: status
        integer(hid_t) :: space, dset, lcpl
        integer(hsize_t) :: dims(1)
        integer :: err, close_err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_vector before create')
            return
        end if
        dims = size(values, kind=hsize_t)
        call h5screate_simple_f(1, dims, space, err)
        if (err >= 0) call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, name, H5T_NATIVE_DOUBLE, space, dset, err, &
                                       lcpl_id=lcpl)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, values, dims, err)
        if (err >= 0) call h5dclose_f(dset, err)
        if (err >= 0) call h5sclose_f(space, err)
        call h5pclose_f(lcpl, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write ' // name)
    end subroutine sink_write_vector

    !> A 2-D integer dataset /name (rows, columns), e.g. a connectivity
    !> (groups of a path created as needed).
    module subroutine sink_write_integers(self, name, values, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        integer, intent(in) :: values(:, :)
        type(status_t), intent(out) :: status
        integer(hid_t) :: space, dset, lcpl
        integer(hsize_t) :: dims(2)
        integer :: err, close_err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_integers before create')
            return
        end if
        dims = shape(values, kind=hsize_t)
        call h5screate_simple_f(2, dims, space, err)
        if (err >= 0) call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, name, H5T_NATIVE_INTEGER, space, dset, err, &
                                       lcpl_id=lcpl)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_INTEGER, values, dims, err)
        if (err >= 0) call h5dclose_f(dset, err)
        if (err >= 0) call h5sclose_f(space, err)
        call h5pclose_f(lcpl, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write ' // name)
    end subroutine sink_write_integers

    !> A 1-D integer dataset /name, e.g. a node set.
    module subroutine sink_write_integer_list(self, name, values, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        integer, intent(in) :: values(:)
        type(status_t), intent(out) :: status
        integer(hid_t) :: space, dset, lcpl
        integer(hsize_t) :: dims(1)
        integer :: err, close_err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_integers before create')
            return
        end if
        dims = size(values, kind=hsize_t)
        call h5screate_simple_f(1, dims, space, err)
        if (err >= 0) call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, name, H5T_NATIVE_INTEGER, space, dset, err, &
                                       lcpl_id=lcpl)
        if (err >= 0) call h5dwrite_f(dset, H5T_NATIVE_INTEGER, values, dims, err)
        if (err >= 0) call h5dclose_f(dset, err)
        if (err >= 0) call h5sclose_f(space, err)
        call h5pclose_f(lcpl, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write ' // name)
    end subroutine sink_write_integer_list

    !> A 1-D dataset of UTF-8 strings (variable length: h5py reads str) at
    !> `path`, e.g. the label of every component of /y.
    module subroutine sink_write_strings(self, path, strings, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: strings(:)
        type(status_t), intent(out) :: status
        character(kind=c_char, len=len(strings) + 1), allocatable, target :: text(:)
        type(c_ptr), allocatable, target :: pointers(:)
        integer(hid_t) :: str_type, space, dset, lcpl
        integer(hsize_t) :: dims(1)
        integer :: err, k, close_err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_strings before create')
            return
        end if
        allocate (text(size(strings)), pointers(size(strings)))
        do k = 1, size(strings)
            text(k) = trim(strings(k)) // c_null_char
            pointers(k) = c_loc(text(k)(1:1))
        end do
        dims = size(strings, kind=hsize_t)
        call utf8_string_type(str_type, err)
        if (err >= 0) call h5screate_simple_f(1, dims, space, err)
        if (err >= 0) call group_creating(lcpl, err)
        if (err >= 0) call h5dcreate_f(self%file, path, str_type, space, dset, err, &
                                       lcpl_id=lcpl)
        if (err >= 0) then
            if (size(strings) > 0) call h5dwrite_f(dset, str_type, c_loc(pointers(1)), err)
            call h5dclose_f(dset, close_err)
        end if
        call h5pclose_f(lcpl, close_err)
        call h5sclose_f(space, close_err)
        call h5tclose_f(str_type, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot write /' // &
                                     path)
    end subroutine sink_write_strings

    !> A string attribute `name` = `text` of the dataset or group at `path`.
    module subroutine sink_annotate(self, path, name, text, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: path, name, text
        type(status_t), intent(out) :: status
        integer(hid_t) :: obj
        integer :: err, close_err
        call h5oopen_f(self%file, path, obj, err)
        if (err >= 0) then
            call write_string_attribute(obj, name, text, err)
            call h5oclose_f(obj, close_err)
        end if
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot annotate /' &
                                     // path)
    end subroutine sink_annotate
end submodule flexmbs_io_hdf5_sink_datasets
