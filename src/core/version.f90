!> The version of flexmbs (as in fpm.toml), and the name its files carry:
!> the HDF5 root attribute `creator` and the comment line 'written by
!> flexmbs 0.1.0' that heads its ParaView and table files, by which a later
!> run knows a file of its own that it may replace (io/output_files).
module flexmbs_core_version
    implicit none
    private

    character(len=*), parameter, public :: version = '0.1.0'
    !> 'flexmbs 0.1.0'
    character(len=*), parameter, public :: creator = 'flexmbs ' // version
    !> the text of the comment line, after the format's comment opening
    character(len=*), parameter, public :: written_by = 'written by ' // creator

    public :: is_written_by

contains

    !> True when `line` is the comment `opening` // 'written by flexmbs ...'
    !> of any version.
    pure logical function is_written_by(line, opening)
        character(len=*), intent(in) :: line, opening
        character(len=*), parameter :: stem = 'written by flexmbs '
        is_written_by = index(line, opening // stem) == 1
    end function is_written_by
end module flexmbs_core_version
