!> The HDF5 file that keeps a modal body's basis between runs
!> (`&flexible_body modes_cache`): the shapes, frequencies, reduced
!> damping and interface motions of flexmbs_fe_modal_basis under a
!> fingerprint of what they were computed from (mesh, materials,
!> interfaces, k). A run reuses the file when the fingerprint matches and
!> replaces it otherwise; a file that is not such a cache is never
!> replaced.
!>
!> Layout: root attributes `fingerprint`, `eigen_method`, `written_by`,
!> `kind` = 'flexmbs modal basis'; datasets `shapes` (3 nodes × n),
!> `frequencies` (n, rad/s), `damping` (n × n, 1/s), `interface_motion`
!> (6 × n × interfaces), `interface_centre` (3 × interfaces, m) and
!> `fixed_frequencies` (k, rad/s).
module flexmbs_io_modal_cache
    use hdf5
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_io_error, status_bad_input
    use flexmbs_core_version, only: written_by
    use flexmbs_fe_modal_basis, only: modal_basis_t
    use flexmbs_io_hdf5_text, only: read_string_attribute, write_string_attribute
    implicit none
    private

    public :: read_modal_cache, write_modal_cache

    character(len=*), parameter :: cache_kind = 'flexmbs modal basis'

contains

    !> The basis kept at `path` under `fingerprint`: found = .false. when
    !> there is no file or it was made from something else.
    subroutine read_modal_cache(path, fingerprint, basis, found, status)
        character(len=*), intent(in) :: path, fingerprint
        type(modal_basis_t), intent(inout) :: basis
        logical, intent(out) :: found
        type(status_t), intent(out) :: status
        integer(hid_t) :: file
        character(len=:), allocatable :: text, method
        real(wp), allocatable :: flat(:), frequencies(:), shapes(:, :), damping(:, :), &
            centre(:, :), motion(:, :, :), fixed(:)
        integer(hsize_t) :: dims(3)
        integer :: err, close_err, n, ni
        logical :: exists, is_hdf5, known_method
        found = .false.
        inquire (file=path, exist=exists)
        if (.not. exists) return
        call h5open_f(err)
        ! asked first, so that HDF5 prints no error stack for another file
        call h5fis_hdf5_f(path, is_hdf5, err)
        if (err >= 0 .and. is_hdf5) call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0 .or. .not. is_hdf5) then
            call status%set(status_bad_input, path // ': modes_cache: not an HDF5 file; &
                &refused (it would be replaced)')
            return
        end if
        call read_string_attribute(file, 'kind', text, err)
        if (err < 0 .or. text /= cache_kind) then
            call status%set(status_bad_input, path // ': modes_cache: an HDF5 file that is &
                &not a flexmbs modal basis; refused (it would be replaced)')
            call h5fclose_f(file, close_err)
            return
        end if
        call read_string_attribute(file, 'fingerprint', text, err)
        if (err < 0 .or. text /= fingerprint) then
            call h5fclose_f(file, close_err)
            return
        end if
        call read_string_attribute(file, 'eigen_method', method, err)
        known_method = err >= 0
        call read_real(file, 'frequencies', frequencies, dims, err)
        n = int(dims(1))
        if (err >= 0) call read_real(file, 'shapes', flat, dims, err)
        if (err >= 0) shapes = reshape(flat, [int(dims(1)), n])
        if (err >= 0) call read_real(file, 'damping', flat, dims, err)
        if (err >= 0) damping = reshape(flat, [n, n])
        if (err >= 0) call read_real(file, 'interface_centre', flat, dims, err)
        ni = int(dims(2))
        if (err >= 0) centre = reshape(flat, [3, ni])
        if (err >= 0) call read_real(file, 'interface_motion', flat, dims, err)
        if (err >= 0) motion = reshape(flat, [6, n, ni])
        if (err >= 0) call read_real(file, 'fixed_frequencies', fixed, dims, err)
        call h5fclose_f(file, close_err)
        if (err < 0) then
            call status%set(status_io_error, path // ': modes_cache: cannot read the basis')
            return
        end if
        if (known_method) then
            call basis%import_parts(frequencies, shapes, damping, centre, motion, fixed, &
                                    eigen_method=method)
        else
            call basis%import_parts(frequencies, shapes, damping, centre, motion, fixed)
        end if
        found = .true.
    end subroutine read_modal_cache

    !> `basis` under `fingerprint` at `path`, replacing a cache there.
    subroutine write_modal_cache(path, fingerprint, basis, status)
        character(len=*), intent(in) :: path, fingerprint
        type(modal_basis_t), intent(in) :: basis
        type(status_t), intent(out) :: status
        integer(hid_t) :: file
        integer :: err, close_err, n, ni
        character(len=:), allocatable :: method
        real(wp), allocatable :: frequencies(:), shapes(:, :), damping(:, :), &
            centre(:, :), motion(:, :, :), fixed(:)
        call basis%export_parts(method, frequencies, shapes, damping, centre, motion, fixed)
        n = size(frequencies)
        ni = size(centre, 2)
        call h5open_f(err)
        call h5fcreate_f(path, H5F_ACC_TRUNC_F, file, err)
        if (err < 0) then
            call status%set(status_io_error, path // ': modes_cache: cannot create the file')
            return
        end if
        call write_string_attribute(file, 'kind', cache_kind, err)
        if (err >= 0) call write_string_attribute(file, 'fingerprint', fingerprint, err)
        if (err >= 0) call write_string_attribute(file, 'eigen_method', method, err)
        if (err >= 0) call write_string_attribute(file, 'written_by', written_by, err)
        if (err >= 0) call write_real(file, 'frequencies', frequencies, [int(n, hsize_t)], err)
        if (err >= 0) call write_real(file, 'shapes', reshape(shapes, [size(shapes)]), &
                                      [int(size(shapes, 1), hsize_t), int(n, hsize_t)], err)
        if (err >= 0) call write_real(file, 'damping', reshape(damping, [n * n]), &
                                      [int(n, hsize_t), int(n, hsize_t)], err)
        if (err >= 0) call write_real(file, 'interface_centre', &
            reshape(centre, [3 * ni]), [3_hsize_t, int(ni, hsize_t)], err)
        if (err >= 0) call write_real(file, 'interface_motion', &
            reshape(motion, [6 * n * ni]), &
            [6_hsize_t, int(n, hsize_t), int(ni, hsize_t)], err)
        if (err >= 0) call write_real(file, 'fixed_frequencies', fixed, &
                                      [int(size(fixed), hsize_t)], err)
        call h5fclose_f(file, close_err)
        if (err < 0 .or. close_err < 0) call status%set(status_io_error, path // &
            ': modes_cache: cannot write the basis')
    end subroutine write_modal_cache

    !> A dataset of doubles of shape dims (rank = size(dims)) from `values`.
    subroutine write_real(file, name, values, dims, err)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: values(:)
        integer(hsize_t), intent(in) :: dims(:)
        integer, intent(out) :: err
        integer(hid_t) :: space, dset
        integer :: close_err
        call h5screate_simple_f(size(dims), dims, space, err)
        if (err < 0) return
        call h5dcreate_f(file, name, H5T_NATIVE_DOUBLE, space, dset, err)
        if (err >= 0) then
            call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, values, dims, err)
            call h5dclose_f(dset, close_err)
        end if
        call h5sclose_f(space, close_err)
    end subroutine write_real

    !> A dataset of doubles, flattened, with its shape (unused ranks 1).
    subroutine read_real(file, name, values, dims, err)
        integer(hid_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), allocatable, intent(out) :: values(:)
        integer(hsize_t), intent(out) :: dims(3)
        integer, intent(out) :: err
        integer(hid_t) :: space, dset
        integer(hsize_t) :: maxdims(3)
        integer :: rank, close_err
        dims = 1
        call h5dopen_f(file, name, dset, err)
        if (err < 0) return
        call h5dget_space_f(dset, space, err)
        if (err >= 0) call h5sget_simple_extent_ndims_f(space, rank, err)
        if (err >= 0 .and. (rank < 1 .or. rank > 3)) err = -1
        if (err >= 0) call h5sget_simple_extent_dims_f(space, dims(1:rank), maxdims(1:rank), err)
        if (err >= 0) then
            allocate (values(product(dims)))
            call h5dread_f(dset, H5T_NATIVE_DOUBLE, values, [product(dims)], err)
        end if
        call h5sclose_f(space, close_err)
        call h5dclose_f(dset, close_err)
    end subroutine read_real
end module flexmbs_io_modal_cache
