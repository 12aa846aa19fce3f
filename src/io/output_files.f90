!> Which files a run may write (docs/user_guide.md, exit codes), checked
!> before anything is computed: an output is never an input of the run,
!> two outputs of a run are never one file, and a file already there is
!> replaced only when it is a result of the same kind written by flexmbs —
!> an HDF5 file with the root attribute creator = 'flexmbs ...', a ParaView,
!> XDMF or table file headed by the comment 'written by flexmbs ...', a PNG plot
!> beside a table of flexmbs (io/spectrum_file) — anything
!> else only when the user says `--force`. Paths are compared as files
!> (device and inode) and, for files not yet written, as absolute paths
!> with links, '.' and '..' resolved.
module flexmbs_io_output_files
    use flexmbs_core_kinds, only: i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_files, only: same_file, same_path, file_kind, file_missing, file_folder, &
        file_fifo, file_device, file_other
    use flexmbs_io_hdf5_sink, only: hdf5_result_check
    use flexmbs_io_vtu_file, only: xml_file_ours
    use flexmbs_io_table, only: table_file_ours
    use flexmbs_io_spectrum_file, only: spectrum_plot_ours
    use flexmbs_io_scene_input, only: scene_input_t
    implicit none
    private

    !> Kinds of output: what a file there must be to be replaced.
    integer, parameter, public :: output_hdf5 = 1, output_vtk = 2, output_table = 3, &
        output_plot = 4, output_xdmf = 5

    !> A file of a run and how messages name it: an output
    !> ('&output: file', kind output_*) or an input ('the scene file itself').
    type, public :: named_path_t
        character(len=:), allocatable :: path
        character(len=:), allocatable :: name
        integer :: kind = 0
        !> one of a numbered series (ParaView pieces), distinct by construction
        logical :: series = .false.
    end type named_path_t

    public :: named_path, check_output_paths, scene_inputs

contains

    !> A named path (assigned component by component: gfortran 12's
    !> structure constructor mis-sizes deferred-length components).
    function named_path(path, name, kind) result(named)
        character(len=*), intent(in) :: path, name
        integer, intent(in), optional :: kind  !! output_*, for an output
        type(named_path_t) :: named
        named%path = path
        named%name = name
        if (present(kind)) named%kind = kind
    end function named_path

    !> The files a scene reads: itself and its flexible bodies' mesh files.
    function scene_inputs(scene) result(inputs)
        type(scene_input_t), intent(in) :: scene
        type(named_path_t), allocatable :: inputs(:)
        integer :: b, n
        n = 1
        if (allocated(scene%bodies)) n = n + count(len_trim(scene%bodies%mesh_file) > 0)
        ! element by element: gfortran 12 leaks the components of structure
        ! constructors inside an array constructor
        allocate (inputs(n))
        inputs(1) = named_path(scene%path, 'the scene file itself')
        if (n == 1) return
        n = 1
        do b = 1, size(scene%bodies)
            associate (file => scene%bodies(b)%mesh_file)
                if (len_trim(file) == 0) cycle
                n = n + 1
                inputs(n) = named_path(trim(file), 'the mesh file ''' // trim(file) // '''')
            end associate
        end do
    end function scene_inputs

    !> The rules of the module header for `outputs`, against `inputs`;
    !> messages start with `where` (e.g. 'scene.nml: '). Bad input names
    !> the output, its path and the reason.
    subroutine check_output_paths(where, outputs, inputs, force, status)
        character(len=*), intent(in) :: where
        type(named_path_t), intent(in) :: outputs(:), inputs(:)
        logical, intent(in) :: force  !! replace files that are not flexmbs's own
        type(status_t), intent(inout) :: status
        integer :: i, j
        integer(i8) :: bytes
        if (.not. status%ok()) return
        do i = 1, size(outputs)
            associate (out => outputs(i))
                do j = 1, size(inputs)
                    if (.not. same_file(out%path, inputs(j)%path)) cycle
                    call status%set(status_bad_input, where // out%name // ': ''' // &
                        out%path // ''' is ' // inputs(j)%name // ': refused, it would be &
                        &overwritten')
                    return
                end do
                do j = 1, i - 1
                    if (out%series .and. outputs(j)%series) cycle
                    if (.not. same_path(out%path, outputs(j)%path)) cycle
                    call status%set(status_bad_input, where // outputs(j)%name // ': ''' // &
                        outputs(j)%path // ''' and ' // out%name // ': ''' // out%path // &
                        ''' are the same file: refused, one would overwrite the other')
                    return
                end do
                ! a FIFO is never written, even with --force: opening it blocks
                if (file_kind(out%path, bytes) == file_fifo) then
                    call status%set(status_bad_input, where // out%name // ': ''' // &
                        out%path // ''' is a FIFO: refused (even with --force)')
                    return
                end if
                if (force) cycle
                call check_replace(out)
                if (.not. status%ok()) return
            end associate
        end do

    contains

        !> A file at the output's path must be flexmbs's own of that kind.
        subroutine check_replace(out)
            type(named_path_t), intent(in) :: out
            character(len=:), allocatable :: reason
            logical :: ours
            integer(i8) :: size
            select case (file_kind(out%path, size))
            case (file_missing)
                return
            case (file_folder)
                ours = .false.
                reason = 'is a folder'
            case (file_fifo, file_device, file_other)
                ! never opened: reading a FIFO blocks until a writer comes
                ours = .false.
                reason = 'is not a regular file (a FIFO, device or socket)'
            case default
                select case (out%kind)
                case (output_hdf5)
                    call hdf5_result_check(out%path, ours, reason)
                case (output_vtk)
                    ours = xml_file_ours(out%path)
                    reason = 'is not a ParaView file written by flexmbs (no comment ' // &
                        '''written by flexmbs'' on its second line)'
                case (output_xdmf)
                    ours = xml_file_ours(out%path)
                    reason = 'is not an XDMF file written by flexmbs (no comment ' // &
                        '''written by flexmbs'' on its second line)'
                case (output_plot)
                    ours = spectrum_plot_ours(out%path)
                    reason = 'is not a plot written by flexmbs (a PNG beside a table ' // &
                        'that flexmbs wrote, the same name ending in .csv)'
                case default
                    ours = table_file_ours(out%path)
                    reason = 'is not a table written by flexmbs (no comment ' // &
                        '''written by flexmbs'' on its first line)'
                end select
            end select
            if (.not. ours) call status%set(status_bad_input, where // out%name // ': ''' // &
                out%path // ''' exists and ' // reason // ': refused; --force replaces it')
        end subroutine check_replace
    end subroutine check_output_paths
end module flexmbs_io_output_files
