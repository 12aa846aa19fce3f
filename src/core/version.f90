!> The version of flexmbs (as in fpm.toml), and the name its files carry:
!> the HDF5 root attribute `creator` and the first comment line of the
!> ParaView and table files, by which a later run knows a file it may
!> replace (io/output_files).
module flexmbs_core_version
    implicit none
    private

    character(len=*), parameter, public :: version = '0.1.0'
    !> 'flexmbs 0.1.0'
    character(len=*), parameter, public :: creator = 'flexmbs ' // version
end module flexmbs_core_version
