!> Attributes and strings in HDF5 files and the paths to them: scalar
!> integer and real attributes, variable-length UTF-8
!> string attributes and types (h5py reads them as str), reading back both
!> these and the fixed-length ones of earlier files, and the link creation
!> property that makes the missing groups of a path.
module flexmbs_io_hdf5_text
    use hdf5
    use flexmbs_core_kinds, only: wp
    use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_null_char, c_null_ptr, &
        c_associated, c_f_pointer, c_size_t, c_int
    implicit none
    private

    public :: read_string_attribute, read_stored_text, write_string_attribute, &
        delete_attribute, string_type, utf8_string_type, group_creating, path_name, &
        write_int_attribute, write_real_attribute, read_int_attribute, read_real_attribute

    interface
        !> The length of a C string (a variable-length HDF5 string read back).
        pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
            import :: c_ptr, c_size_t
            type(c_ptr), value, intent(in) :: s
        end function c_strlen
        !> Memory the HDF5 library allocated (a variable-length string read).
        integer(c_int) function h5_free_memory(buffer) bind(C, name='H5free_memory')
            import :: c_ptr, c_int
            type(c_ptr), value, intent(in) :: buffer
        end function h5_free_memory
    end interface

contains

    !> The text of a scalar string attribute of `obj`: variable-length (as
    !> flexmbs writes them) or fixed-length (files of earlier versions).
    subroutine read_string_attribute(obj, name, text, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        character(len=:), allocatable, intent(out) :: text
        integer, intent(out) :: err
        integer(hid_t) :: attr, file_type, mem_type
        integer(size_t) :: length
        integer :: close_err, stat
        logical :: variable
        text = ''
        call h5aopen_f(obj, name, attr, err)
        if (err < 0) return
        call h5aget_type_f(attr, file_type, err)
        if (err >= 0) call h5tis_variable_str_f(file_type, variable, err)
        if (err >= 0 .and. variable) then
            call read_variable(err)
        else if (err >= 0) then
            call h5tget_size_f(file_type, length, err)
            if (err >= 0) call string_type(int(length), mem_type, err)
            if (err >= 0) then
                ! the length is the file's word: a damaged one is a failed read
                deallocate (text)
                allocate (character(len=max(int(length), 1)) :: text, stat=stat)
                if (stat /= 0) err = -1
                if (err >= 0) call h5aread_f(attr, mem_type, text, [1_hsize_t], err)
                call h5tclose_f(mem_type, close_err)
                if (err >= 0) text = trim(text)
            end if
        end if
        if (err < 0) text = ''
        call h5tclose_f(file_type, close_err)
        call h5aclose_f(attr, close_err)

    contains

        subroutine read_variable(err)
            integer, intent(inout) :: err
            type(c_ptr), target :: pointer(1)
            type(c_ptr) :: buffer
            character(kind=c_char), pointer :: chars(:)
            integer :: n
            call utf8_string_type(mem_type, err)
            if (err < 0) return
            pointer(1) = c_null_ptr
            buffer = c_loc(pointer(1))
            call h5aread_f(attr, mem_type, buffer, err)
            call h5tclose_f(mem_type, close_err)
            if (err < 0 .or. .not. c_associated(pointer(1))) return
            n = int(c_strlen(pointer(1)))
            call c_f_pointer(pointer(1), chars, [max(n, 1)])
            deallocate (text)
            allocate (character(len=n) :: text, stat=stat)
            if (stat == 0) then
                text = transfer(chars(1:n), text)
            else
                err = -1
            end if
            close_err = int(h5_free_memory(pointer(1)))
        end subroutine read_variable
    end subroutine read_string_attribute

    !> A text of the file `file` as hdf5_sink_t%write_text stores it: the
    !> attribute `name`, or the dataset /name when the attribute says the
    !> text is there (a text too long for an attribute). err < 0 when
    !> neither reads.
    subroutine read_stored_text(file, name, text, err)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        character(len=:), allocatable, intent(out) :: text
        integer, intent(out) :: err
        integer(hid_t) :: dset, file_type, mem_type
        integer(size_t) :: length
        integer :: close_err, stat
        logical :: exists
        text = ''
        ! asked first: HDF5 would print its error stack for a missing one
        call h5aexists_f(file, name, exists, err)
        if (err >= 0 .and. .not. exists) err = -1
        if (err < 0) return
        call read_string_attribute(file, name, text, err)
        if (err < 0 .or. text /= 'stored in dataset /' // name) return
        call h5dopen_f(file, name, dset, err)
        if (err < 0) return
        call h5dget_type_f(dset, file_type, err)
        if (err >= 0) call h5tget_size_f(file_type, length, err)
        if (err >= 0) call string_type(int(length), mem_type, err)
        if (err >= 0) then
            deallocate (text)
            allocate (character(len=max(int(length), 1)) :: text, stat=stat)
            if (stat /= 0) err = -1
            if (err >= 0) call h5dread_f(dset, mem_type, text, [1_hsize_t], err)
            call h5tclose_f(mem_type, close_err)
        end if
        if (err >= 0) call h5tclose_f(file_type, close_err)
        call h5dclose_f(dset, close_err)
        if (err < 0) text = ''
    end subroutine read_stored_text

    !> A scalar string attribute, variable-length UTF-8 (h5py reads a str),
    !> replacing one of that name.
    subroutine write_string_attribute(obj, name, text, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name, text
        integer, intent(out) :: err
        integer(hid_t) :: str_type, space, attr
        character(kind=c_char, len=len(text) + 1), target :: buf
        type(c_ptr), target :: pointer(1)
        integer :: close_err
        buf = text // c_null_char
        pointer(1) = c_loc(buf(1:1))
        call delete_attribute(obj, name, err)
        if (err < 0) return
        call utf8_string_type(str_type, err)
        if (err < 0) return
        call h5screate_f(H5S_SCALAR_F, space, err)
        if (err >= 0) then
            call h5acreate_f(obj, name, str_type, space, attr, err)
            if (err >= 0) then
                call h5awrite_f(attr, str_type, c_loc(pointer(1)), err)
                call h5aclose_f(attr, close_err)
            end if
            call h5sclose_f(space, close_err)
        end if
        call h5tclose_f(str_type, close_err)
    end subroutine write_string_attribute

    !> Delete the attribute `name` of `obj` when it exists, so that it can be
    !> written again with another type or size; err < 0 on an HDF5 failure.
    subroutine delete_attribute(obj, name, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        integer, intent(out) :: err
        logical :: exists
        call h5aexists_f(obj, name, exists, err)
        if (err >= 0 .and. exists) call h5adelete_f(obj, name, err)
    end subroutine delete_attribute

    !> A fixed-length string type of `n` characters (at least 1).
    subroutine string_type(n, str_type, err)
        integer, intent(in) :: n
        integer(hid_t), intent(out) :: str_type
        integer, intent(out) :: err
        call h5tcopy_f(H5T_FORTRAN_S1, str_type, err)
        if (err >= 0) call h5tset_size_f(str_type, int(max(n, 1), size_t), err)
    end subroutine string_type

    !> Variable-length UTF-8 strings.
    subroutine utf8_string_type(str_type, err)
        integer(hid_t), intent(out) :: str_type
        integer, intent(out) :: err
        call h5tcopy_f(H5T_STRING, str_type, err)
        if (err >= 0) call h5tset_cset_f(str_type, H5T_CSET_UTF8_F, err)
    end subroutine utf8_string_type

    !> A link-creation property list that creates missing groups of a path.
    subroutine group_creating(lcpl, err)
        integer(hid_t), intent(out) :: lcpl
        integer, intent(out) :: err
        call h5pcreate_f(H5P_LINK_CREATE_F, lcpl, err)
        if (err >= 0) call h5pset_create_inter_group_f(lcpl, 1, err)
    end subroutine group_creating

    !> A scene name as one HDF5 path component ('/' would open a group).
    pure function path_name(name) result(part)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: part
        integer :: i
        part = trim(name)
        do i = 1, len(part)
            if (part(i:i) == '/') part(i:i) = '_'
        end do
        if (part == '.' .or. len(part) == 0) part = '_' // part
    end function path_name

    !> A scalar integer attribute `name` of obj, replacing an earlier one;
    !> nothing when err < 0 on entry.
    subroutine write_int_attribute(obj, name, value, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        integer, intent(in) :: value
        integer, intent(inout) :: err
        integer, target :: held
        held = value
        call write_scalar(obj, name, H5T_NATIVE_INTEGER, c_loc(held), err)
    end subroutine write_int_attribute

    !> A scalar real attribute `name` of obj (as write_int_attribute).
    subroutine write_real_attribute(obj, name, value, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: value
        integer, intent(inout) :: err
        real(wp), target :: held
        held = value
        call write_scalar(obj, name, H5T_NATIVE_DOUBLE, c_loc(held), err)
    end subroutine write_real_attribute

    !> The scalar integer attribute `name` of obj; 0 when there is none;
    !> nothing when err < 0 on entry.
    subroutine read_int_attribute(obj, name, value, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        integer, intent(out), target :: value
        integer, intent(inout) :: err
        value = 0
        call read_scalar(obj, name, H5T_NATIVE_INTEGER, c_loc(value), err)
    end subroutine read_int_attribute

    !> The scalar real attribute `name` of obj (as read_int_attribute).
    subroutine read_real_attribute(obj, name, value, err)
        integer(hid_t), intent(in) :: obj
        character(len=*), intent(in) :: name
        real(wp), intent(out), target :: value
        integer, intent(inout) :: err
        value = 0.0_wp
        call read_scalar(obj, name, H5T_NATIVE_DOUBLE, c_loc(value), err)
    end subroutine read_real_attribute

    !> A scalar attribute of type `dtype` from the value at `buffer`.
    subroutine write_scalar(obj, name, dtype, buffer, err)
        integer(hid_t), intent(in) :: obj, dtype
        character(len=*), intent(in) :: name
        type(c_ptr), intent(in) :: buffer
        integer, intent(inout) :: err
        integer(hid_t) :: space, attr
        integer :: close_err
        if (err < 0) return
        call delete_attribute(obj, name, err)
        if (err >= 0) call h5screate_f(H5S_SCALAR_F, space, err)
        if (err < 0) return
        call h5acreate_f(obj, name, dtype, space, attr, err)
        if (err >= 0) then
            call h5awrite_f(attr, dtype, buffer, err)
            call h5aclose_f(attr, close_err)
        end if
        call h5sclose_f(space, close_err)
    end subroutine write_scalar

    !> A scalar attribute of type `dtype` into `buffer`, left as it is when
    !> there is none.
    subroutine read_scalar(obj, name, dtype, buffer, err)
        integer(hid_t), intent(in) :: obj, dtype
        character(len=*), intent(in) :: name
        type(c_ptr), intent(in) :: buffer
        integer, intent(inout) :: err
        integer(hid_t) :: attr
        type(c_ptr) :: into  ! HDF5 takes the pointer intent(inout)
        integer :: close_err
        logical :: exists
        if (err < 0) return
        call h5aexists_f(obj, name, exists, err)
        if (err < 0 .or. .not. exists) return
        call h5aopen_f(obj, name, attr, err)
        if (err < 0) return
        into = buffer
        call h5aread_f(attr, dtype, into, err)
        call h5aclose_f(attr, close_err)
    end subroutine read_scalar
end module flexmbs_io_hdf5_text
