!> Columns of a result file by name, for `flexmbs columns`: what the named
!> series of a run (run/named_output) hold, without index arithmetic.
!>
!>   rocker/position/z            /bodies/rocker/position, row z (x y z or 1..)
!>   flail/coordinate/1           /chains/flail/coordinate: its joint's angle
!>   rocker pivot/angle           /joints/rocker pivot/angle (one row: no component)
!>   motor/reaction_torque/z      /joints/... or /drivers/... likewise
!>   coupler/node 23/x            node 23's x: reference_nodes + displacement
!>   coupler/node 23/velocity/x   node 23's velocity (displacement likewise)
!>   17                           component 17 of /y
module flexmbs_io_result_columns
    use hdf5
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_text, only: int_text, lower
    use flexmbs_core_resources, only: out_of_memory
    implicit none
    private

    !> The groups a name's first part is looked up in, in this order.
    character(len=*), parameter :: groups(5) = [character(len=8) :: 'bodies', 'chains', &
        'joints', 'drivers', 'flexible']

    public :: read_column, open_result

contains

    !> The values of column `name` of the result `path` at every record
    !> (the length of /time). Bad input names the file, the column and why.
    subroutine read_column(path, name, values, status)
        character(len=*), intent(in) :: path, name
        real(wp), allocatable, intent(out) :: values(:)
        type(status_t), intent(out) :: status
        integer(hid_t) :: file
        integer :: k, ios, close_err
        character(len=:), allocatable :: parts(:)
        call open_result(path, file, status)
        if (.not. status%ok()) return
        read (name, *, iostat=ios) k
        if (ios == 0 .and. verify(trim(adjustl(name)), '0123456789') == 0) then
            call read_row(file, 'y', k, values, status)
        else
            call split(name, parts)
            if (size(parts) >= 2 .and. index(parts(min(2, size(parts))), 'node ') == 1) then
                call node_column(file, parts, values, status)
            else if (size(parts) == 3 .or. size(parts) == 2) then
                call series_column(file, parts, values, status)
            else
                call status%set(status_bad_input, 'a column is a number of /y or NAME/QUANTITY[/&
                    &COMPONENT] (rocker/position/z, rocker pivot/angle, coupler/node 23/x)')
            end if
        end if
        call h5fclose_f(file, close_err)
        if (.not. status%ok()) status%message = path // ': column ''' // name // ''': ' // &
            status%text()
    end subroutine read_column

    !> BODY/QUANTITY/COMPONENT in one of `groups`.
    subroutine series_column(file, parts, values, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: parts(:)
        real(wp), allocatable, intent(out) :: values(:)
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: dataset
        integer :: row
        row = 1   ! NAME/QUANTITY: a series of one row (a joint's angle)
        if (size(parts) == 3) row = component(parts(3))
        call find_dataset(file, trim(parts(1)) // '/' // trim(parts(2)), dataset, status)
        if (status%ok()) call read_row(file, dataset, row, values, status)
    end subroutine series_column

    !> BODY/node N/x (position), BODY/node N/displacement/x, .../velocity/x.
    subroutine node_column(file, parts, values, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: parts(:)
        real(wp), allocatable, intent(out) :: values(:)
        type(status_t), intent(out) :: status
        character(len=:), allocatable :: base, quantity
        real(wp), allocatable :: reference(:)
        integer :: node, ios, c
        read (parts(2)(6:), *, iostat=ios) node
        if (ios /= 0 .or. size(parts) < 3 .or. size(parts) > 4) then
            call status%set(status_bad_input, 'a node column is BODY/node N/x or BODY/node N/&
                &displacement/x or BODY/node N/velocity/x')
            return
        end if
        base = 'flexible/' // trim(parts(1)) // '/'
        quantity = 'position'
        if (size(parts) == 4) quantity = lower(trim(parts(3)))
        c = component(parts(size(parts)))
        if (c < 1 .or. c > 3) then
            call status%set(status_bad_input, 'the component of a node is x, y or z')
            return
        end if
        select case (quantity)
        case ('position')
            call read_node(file, base // 'displacement', node, c, values, status)
            if (status%ok()) call read_row_at(file, base // 'reference_nodes', c, node, &
                                              reference, status)
            if (status%ok()) values = values + reference(1)
        case ('displacement', 'velocity')
            call read_node(file, base // quantity, node, c, values, status)
        case default
            call status%set(status_bad_input, '''' // quantity // ''': a node has displacement &
                &and velocity (and its position: BODY/node N/x)')
        end select
    end subroutine node_column

    !> The group of `groups` that holds dataset `name` ('rocker/position').
    subroutine find_dataset(file, name, dataset, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        character(len=:), allocatable, intent(out) :: dataset
        type(status_t), intent(out) :: status
        logical :: exists
        integer :: g
        do g = 1, size(groups)
            dataset = trim(groups(g)) // '/' // name
            call link_exists(file, dataset, exists)
            if (exists) return
        end do
        call status%set(status_bad_input, 'no dataset ' // name // ' under /bodies, /chains, &
            &/joints, /drivers or /flexible')
    end subroutine find_dataset

    !> Whether every link of `path` exists (H5Lexists checks the last only).
    subroutine link_exists(file, path, exists)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: path
        logical, intent(out) :: exists
        integer :: i, err
        do i = 2, len(path)
            if (path(i:i) /= '/') cycle
            call h5lexists_f(file, path(1:i - 1), exists, err)
            if (.not. exists .or. err < 0) then
                exists = .false.
                return
            end if
        end do
        call h5lexists_f(file, path, exists, err)
        exists = exists .and. err >= 0
    end subroutine link_exists

    !> Row `row` of the 2-D series `name` (rows, records): its values.
    subroutine read_row(file, name, row, values, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: row
        real(wp), allocatable, intent(out) :: values(:)
        type(status_t), intent(out) :: status
        integer(hsize_t) :: dims(2), maxdims(2), offset(2), count(2)
        integer(hid_t) :: dset, space
        integer :: err, rank, close_err, stat
        call open_dataset(file, name, dset, space, status)
        if (.not. status%ok()) return
        call h5sget_simple_extent_ndims_f(space, rank, err)
        if (rank /= 2) then
            call status%set(status_bad_input, '/' // name // ' is not a series of rows')
        else
            call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
            if (row < 1 .or. row > dims(1)) then
                call status%set(status_bad_input, 'component ' // int_text(row) // &
                    ' outside 1 .. ' // int_text(int(dims(1))) // ' of /' // name)
            else
                allocate (values(dims(2)), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, name, int(dims(2), i8), 8)
                else
                    offset = [int(row - 1, hsize_t), 0_hsize_t]
                    count = [1_hsize_t, dims(2)]
                    call read_slab(dset, space, offset, count, name, values, status)
                end if
            end if
        end if
        call h5sclose_f(space, close_err)
        call h5dclose_f(dset, close_err)
    end subroutine read_row

    !> Component c of node `node` of a (3, nodes, records) series.
    subroutine read_node(file, name, node, c, values, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: node, c
        real(wp), allocatable, intent(out) :: values(:)
        type(status_t), intent(out) :: status
        integer(hsize_t) :: dims(3), maxdims(3), offset(3), count(3)
        integer(hid_t) :: dset, space
        integer :: err, rank, close_err, stat
        logical :: exists
        call link_exists(file, name, exists)
        if (.not. exists) then
            call status%set(status_bad_input, 'no flexible body''s /' // name)
            return
        end if
        call h5dopen_f(file, name, dset, err)
        call h5dget_space_f(dset, space, err)
        call h5sget_simple_extent_ndims_f(space, rank, err)
        if (rank == 3) then
            call h5sget_simple_extent_dims_f(space, dims, maxdims, err)
            if (node < 1 .or. node > dims(2)) then
                call status%set(status_bad_input, 'node ' // int_text(node) // ' outside 1 .. ' &
                    // int_text(int(dims(2))))
            else
                allocate (values(dims(3)), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, name, int(dims(3), i8), 8)
                else
                    offset = [int(c - 1, hsize_t), int(node - 1, hsize_t), 0_hsize_t]
                    count = [1_hsize_t, 1_hsize_t, dims(3)]
                    call read_slab(dset, space, offset, count, name, values, status)
                end if
            end if
        else
            call status%set(status_bad_input, '/' // name // ' is not a (3, nodes) series')
        end if
        call h5sclose_f(space, close_err)
        call h5dclose_f(dset, close_err)
    end subroutine read_node

    !> Entry (row, column) of a 2-D dataset, as a one-element array.
    subroutine read_row_at(file, name, row, column, value, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: row, column
        real(wp), allocatable, intent(out) :: value(:)
        type(status_t), intent(out) :: status
        integer(hsize_t) :: offset(2), count(2)
        integer(hid_t) :: dset, space
        integer :: close_err
        allocate (value(1))
        call open_dataset(file, name, dset, space, status)
        if (.not. status%ok()) return
        offset = [int(row - 1, hsize_t), int(column - 1, hsize_t)]
        count = [1_hsize_t, 1_hsize_t]
        call read_slab(dset, space, offset, count, name, value, status)
        call h5sclose_f(space, close_err)
        call h5dclose_f(dset, close_err)
    end subroutine read_row_at

    !> Open the result `path` for reading (the HDF5 library opened first); a
    !> file that is not HDF5 is an I/O error naming the path.
    subroutine open_result(path, file, status)
        character(len=*), intent(in) :: path
        integer(hid_t), intent(out) :: file
        type(status_t), intent(inout) :: status
        integer :: err
        call h5open_f(err)
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0) call status%set(status_io_error, path // ': not an HDF5 file')
    end subroutine open_result

    !> The dataset `name` of `file` and its dataspace, or bad input when
    !> there is none.
    subroutine open_dataset(file, name, dset, space, status)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hid_t), intent(out) :: dset, space
        type(status_t), intent(inout) :: status
        integer :: err
        call h5dopen_f(file, name, dset, err)
        if (err < 0) then
            call status%set(status_bad_input, 'no dataset /' // name)
            return
        end if
        call h5dget_space_f(dset, space, err)
    end subroutine open_dataset

    !> The hyperslab (offset, count) of the dataset `name` (dset, its
    !> dataspace `space`) into values, of the slab's size.
    subroutine read_slab(dset, space, offset, count, name, values, status)
        integer(hid_t), intent(in) :: dset, space
        integer(hsize_t), intent(in) :: offset(:), count(:)
        character(len=*), intent(in) :: name
        real(wp), intent(inout) :: values(:)
        type(status_t), intent(inout) :: status
        integer(hid_t) :: memspace
        integer :: err, close_err
        call h5sselect_hyperslab_f(space, H5S_SELECT_SET_F, offset, count, err)
        call h5screate_simple_f(size(count), count, memspace, err)
        call h5dread_f(dset, H5T_NATIVE_DOUBLE, values, count, err, mem_space_id=memspace, &
                       file_space_id=space)
        call h5sclose_f(memspace, close_err)
        if (err < 0) call status%set(status_io_error, 'cannot read /' // name)
    end subroutine read_slab

    !> x, y, z (or p0 .. p3) as 1, 2, 3 (1 .. 4), or a number from 1; 0 if neither.
    integer function component(text) result(c)
        character(len=*), intent(in) :: text
        integer :: ios
        select case (lower(trim(adjustl(text))))
        case ('x', 'p0'); c = 1
        case ('y', 'p1'); c = 2
        case ('z', 'p2'); c = 3
        case ('p3'); c = 4
        case default
            read (text, *, iostat=ios) c
            if (ios /= 0) c = 0
        end select
    end function component

    !> The parts of a name between '/'.
    subroutine split(name, parts)
        character(len=*), intent(in) :: name
        character(len=:), allocatable, intent(out) :: parts(:)
        integer :: n, start, i, k
        n = count([(name(i:i) == '/', i=1, len(name))]) + 1
        allocate (character(len=len(name)) :: parts(n))
        start = 1
        k = 0
        do i = 1, len(name) + 1
            if (i <= len(name)) then
                if (name(i:i) /= '/') cycle
            end if
            k = k + 1
            parts(k) = name(start:i - 1)
            start = i + 1
        end do
    end subroutine split
end module flexmbs_io_result_columns
