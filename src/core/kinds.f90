!> Kind parameters used throughout flexmbs.
module flexmbs_core_kinds
    use, intrinsic :: iso_fortran_env, only: real64, int64
    implicit none
    private

    !> Working precision: IEEE double.
    integer, parameter, public :: wp = real64
    !> 64-bit integers: CSC indices shared with KLU (klu_l_*) and SUNDIALS.
    integer, parameter, public :: i8 = int64
    !> Unit roundoff of working precision.
    real(wp), parameter, public :: uround_wp = epsilon(1.0_wp)
end module flexmbs_core_kinds
