!> Banded LU (LAPACK gbtrf/gbtrs) of real and complex shifted matrices.
!>
!> c*M - J is held in LAPACK band storage: entry (i, j) in row
!> ml + mu + 1 + i - j of column j, with ml further rows above for the
!> fill-in that row interchanges cause (ldab = 2 ml + mu + 1). The lower and
!> upper bandwidths ml, mu are given by the caller (components `lower`,
!> `upper`, before `init`) or found by `init` as the widest of M and J:
!> identity M has bandwidth 0, a CSC matrix its pattern, a dense array its
!> nonzero entries at init (so it must then hold representative values;
!> with the bandwidths given it need not). Entries outside the band are
!> never dropped silently: a sparse pattern reaching outside is reported by
!> init, a dense array's nonzero outside by each factorisation, with
!> status_bad_input.
!> All work arrays are allocated in `init`; factor and solve allocate nothing.
module flexmbs_linalg_band
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix
    use flexmbs_linalg_matrix, only: matrix_t, storage_identity, storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_lapack, only: dgbtrf, dgbtrs, zgbtrf, zgbtrs
    implicit none
    private

    !> Band LU of c*M - J, real and complex factors kept side by side.
    type, extends(linear_solver_t), public :: band_solver_t
        !> Bandwidths given by the caller; negative: found by `init`.
        integer :: lower = -1
        integer :: upper = -1
        integer, private :: ml = 0, mu = 0, ldab = 0
        integer, private :: jac_storage = -1, mass_storage = -1 !! storages seen at init
        logical, private :: real_ready = .false., complex_ready = .false.
        real(wp), allocatable, private :: ab(:, :)
        complex(wp), allocatable, private :: zab(:, :)
        integer, allocatable, private :: ipiv(:), zipiv(:)
    contains
        procedure :: init => band_init
        procedure :: factor_real => band_factor_real
        procedure :: factor_complex => band_factor_complex
        procedure :: solve_real => band_solve_real
        procedure :: solve_complex => band_solve_complex
        procedure :: name => band_name
        procedure :: bandwidths => band_bandwidths
    end type band_solver_t

    public :: matrix_bandwidths

contains

    !> Lower and upper bandwidth [ml, mu] of a matrix: its CSC pattern, the
    !> nonzero entries of a dense array, 0 for the identity.
    pure function matrix_bandwidths(a) result(widths)
        type(matrix_t), intent(in) :: a
        integer :: widths(2)
        integer :: i, j
        integer(i8) :: p
        widths = 0
        select case (a%storage)
        case (storage_sparse)
            do j = 1, a%csc%ncol
                do p = a%csc%colptr(j) + 1, a%csc%colptr(j + 1)
                    i = int(a%csc%rowind(p)) + 1
                    widths(1) = max(widths(1), i - j)
                    widths(2) = max(widths(2), j - i)
                end do
            end do
        case (storage_dense)
            do j = 1, size(a%dense, 2)
                do i = 1, size(a%dense, 1)
                    if (a%dense(i, j) /= 0.0_wp) then
                        widths(1) = max(widths(1), i - j)
                        widths(2) = max(widths(2), j - i)
                    end if
                end do
            end do
        end select
    end function matrix_bandwidths

    !> Fix ml and mu (given, or the widest of M and J) and allocate the band
    !> arrays.
    subroutine band_init(self, mass, jac, status)
        class(band_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: n, wj(2), wm(2), stat
        character(len=200) :: msg

        n = jac%n
        if (n <= 0) then
            write (msg, '(a,i0,a)') 'band solver: order of J n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (.not. (fits(n, jac) .and. fits(n, mass))) then
            write (msg, '(a,i0)') 'band solver: storage of M or J does not have order n = ', n
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if ((self%lower < 0) .neqv. (self%upper < 0)) then
            write (msg, '(a,i0,a,i0,a)') 'band solver: bandwidths lower = ', self%lower, &
                ', upper = ', self%upper, ': give both or neither'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (self%lower < 0) then
            if (jac%storage /= storage_sparse .and. jac%storage /= storage_dense) then
                call status%set(status_bad_input, 'band solver: J has no storage to find ' // &
                    'its bandwidths in; set lower and upper before init')
                return
            end if
            wj = matrix_bandwidths(jac)
            wm = matrix_bandwidths(mass)
            self%ml = max(wj(1), wm(1))
            self%mu = max(wj(2), wm(2))
        else
            ! Wider than n - 1 means full: the band then holds the whole matrix.
            self%ml = min(self%lower, n - 1)
            self%mu = min(self%upper, n - 1)
            ! Dense arrays may hold no values yet: they are checked at each
            ! factorisation instead.
            wj = 0
            wm = 0
            if (jac%storage == storage_sparse) wj = matrix_bandwidths(jac)
            if (mass%storage == storage_sparse) wm = matrix_bandwidths(mass)
            if (max(wj(1), wm(1)) > self%ml .or. max(wj(2), wm(2)) > self%mu) then
                write (msg, '(6(a,i0))') 'band solver: M (', wm(1), ', ', wm(2), ') or J (', &
                    wj(1), ', ', wj(2), ') reaches outside the bandwidths given, ', self%ml, &
                    ', ', self%mu
                call status%set(status_bad_input, trim(msg) // '; widen them')
                return
            end if
        end if
        self%n = n
        self%jac_storage = jac%storage
        self%mass_storage = mass%storage
        self%ldab = 2 * self%ml + self%mu + 1
        self%real_ready = .false.
        self%complex_ready = .false.
        call release(self)
        allocate (self%ab(self%ldab, n), self%zab(self%ldab, n), self%ipiv(n), self%zipiv(n), &
            stat=stat)
        if (stat /= 0) then
            ! ab real, zab complex: 3 values of 8 bytes a band entry
            call out_of_memory(status, 'band solver storage', 3 * int(self%ldab, i8) * n, 8)
            call release(self)
        end if
    end subroutine band_init

    ! What init allocates; a failed init leaves none of it (check_layout then
    ! says 'factor called before init', the next init starts clean).
    subroutine release(self)
        type(band_solver_t), intent(inout) :: self
        if (allocated(self%ab)) deallocate (self%ab)
        if (allocated(self%zab)) deallocate (self%zab)
        if (allocated(self%ipiv)) deallocate (self%ipiv)
        if (allocated(self%zipiv)) deallocate (self%zipiv)
    end subroutine release

    logical function fits(n, a)
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: a
        select case (a%storage)
        case (storage_dense)
            fits = .false.
            if (allocated(a%dense)) fits = all(shape(a%dense) == [n, n])
        case (storage_sparse)
            fits = a%csc%is_built() .and. a%csc%nrow == n .and. a%csc%ncol == n
        case default
            fits = .true.
        end select
    end function fits

    !> The bandwidths in use [ml, mu] (after init).
    pure function band_bandwidths(self) result(widths)
        class(band_solver_t), intent(in) :: self
        integer :: widths(2)
        widths = [self%ml, self%mu]
    end function band_bandwidths

    !> Storages must be those seen at init: the band was sized for them.
    subroutine check_layout(self, mass, jac, status)
        class(band_solver_t), intent(in) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        if (.not. allocated(self%ab)) then
            call status%set(status_bad_input, 'band solver: factor called before init')
        else if (jac%storage /= self%jac_storage .or. mass%storage /= self%mass_storage &
                 .or. jac%n /= self%n) then
            call status%set(status_bad_input, &
                'band solver: storage or order of M or J changed since init; call init again')
        end if
    end subroutine check_layout

    ! add_real and add_complex: one body (band_add.inc) for both types.
#define SCALAR real(wp)
#define ADD_NAME add_real
#include "band_add.inc"
#undef SCALAR
#undef ADD_NAME
#define SCALAR complex(wp)
#define ADD_NAME add_complex
#include "band_add.inc"
#undef SCALAR
#undef ADD_NAME

    subroutine outside(self, i, j, status)
        class(band_solver_t), intent(in) :: self
        integer, intent(in) :: i, j
        type(status_t), intent(inout) :: status
        character(len=200) :: msg
        write (msg, '(5(a,i0),a)') 'band solver: entry (', i, ', ', j, &
            ') of M or J lies outside the bandwidths (', self%ml, ', ', self%mu, &
            ') fixed at init'
        call status%set(status_bad_input, trim(msg) // '; call init again or widen them')
    end subroutine outside

    subroutine band_factor_real(self, c, mass, jac, status)
        class(band_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: info
        self%real_ready = .false.
        call check_layout(self, mass, jac, status)
        if (.not. status%ok()) return
        self%ab = 0.0_wp
        call add_real(self, -1.0_wp, jac, self%ab, status)
        if (status%ok()) call add_real(self, c, mass, self%ab, status)
        if (.not. status%ok()) return
        call dgbtrf(self%n, self%n, self%ml, self%mu, self%ab, self%ldab, self%ipiv, info)
        if (info /= 0) then
            call status%set(status_solver_failure, &
                'band LU: real iteration matrix is singular', reason_singular_matrix)
            return
        end if
        self%real_ready = .true.
    end subroutine band_factor_real

    subroutine band_factor_complex(self, c, mass, jac, status)
        class(band_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: info
        self%complex_ready = .false.
        call check_layout(self, mass, jac, status)
        if (.not. status%ok()) return
        self%zab = (0.0_wp, 0.0_wp)
        call add_complex(self, (-1.0_wp, 0.0_wp), jac, self%zab, status)
        if (status%ok()) call add_complex(self, c, mass, self%zab, status)
        if (.not. status%ok()) return
        call zgbtrf(self%n, self%n, self%ml, self%mu, self%zab, self%ldab, self%zipiv, info)
        if (info /= 0) then
            call status%set(status_solver_failure, &
                'band LU: complex iteration matrix is singular', reason_singular_matrix)
            return
        end if
        self%complex_ready = .true.
    end subroutine band_factor_complex

    !> Overwrite b with A⁻¹ b; NaN without a valid factorisation, so that a
    !> failure cannot pass unseen.
    subroutine band_solve_real(self, b)
        class(band_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        integer :: info
        if (.not. self%real_ready) then
            b = ieee_value(1.0_wp, ieee_quiet_nan)
            return
        end if
        call dgbtrs('N', self%n, self%ml, self%mu, 1, self%ab, self%ldab, self%ipiv, b, &
            self%n, info)
    end subroutine band_solve_real

    subroutine band_solve_complex(self, b)
        class(band_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        integer :: info
        real(wp) :: nan
        if (.not. self%complex_ready) then
            nan = ieee_value(1.0_wp, ieee_quiet_nan)
            b = cmplx(nan, nan, kind=wp)
            return
        end if
        call zgbtrs('N', self%n, self%ml, self%mu, 1, self%zab, self%ldab, self%zipiv, b, &
            self%n, info)
    end subroutine band_solve_complex

    function band_name(self) result(name)
        class(band_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'band'
    end function band_name
end module flexmbs_linalg_band
