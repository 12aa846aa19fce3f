!> A matrix block that derivative code adds entries into, held either as a
!> dense array or as values on a fixed CSC pattern.
!>
!> The multibody derivatives (joints, node frames, bodies) are written once,
!> as sums of small contributions `add(i, j, x)`; the same code then fills
!> the dense Jacobians of small problems and the CSC values of large ones.
!> The sparse form looks each entry up in its column (binary search) and
!> counts contributions that fall outside the pattern, which `get_values`
!> reports: a pattern that misses a nonzero is a programming error that must
!> not pass silently. Nothing is allocated after the first use.
module flexmbs_linalg_accumulator
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    !> Dense or sparse target of `add` (module header).
    type, public :: accumulator_t
        private
        logical :: sparse = .false.
        integer :: nrow = 0, ncol = 0
        real(wp), allocatable :: dense(:, :)
        type(csc_matrix_t) :: csc
        integer(i8) :: misses = 0
        integer :: miss_row = 0, miss_col = 0
    contains
        procedure :: start_dense => accumulator_start_dense
        procedure :: start_sparse => accumulator_start_sparse
        procedure :: add => accumulator_add
        procedure :: add_range => accumulator_add_range
        procedure :: get_dense => accumulator_get_dense
        procedure :: get_values => accumulator_get_values
        procedure :: is_sparse => accumulator_is_sparse
    end type accumulator_t

contains

    !> Zero a dense nrow x ncol target (allocated on first use or a new shape).
    subroutine accumulator_start_dense(self, nrow, ncol)
        class(accumulator_t), intent(inout) :: self
        integer, intent(in) :: nrow, ncol
        self%sparse = .false.
        if (allocated(self%dense)) then
            if (size(self%dense, 1) /= nrow .or. size(self%dense, 2) /= ncol) &
                deallocate (self%dense)
        end if
        if (.not. allocated(self%dense)) allocate (self%dense(nrow, ncol))
        self%nrow = nrow
        self%ncol = ncol
        self%dense = 0.0_wp
        self%misses = 0
    end subroutine accumulator_start_dense

    !> Zero a sparse target on `pattern`, copied on first use: an
    !> accumulator serves one pattern (use one accumulator per block).
    subroutine accumulator_start_sparse(self, pattern)
        class(accumulator_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: pattern
        self%sparse = .true.
        if (.not. self%csc%is_built()) self%csc = pattern
        self%nrow = pattern%nrow
        self%ncol = pattern%ncol
        self%csc%values = 0.0_wp
        self%misses = 0
    end subroutine accumulator_start_sparse

    !> Entry (i, j) += x (1-based).
    pure subroutine accumulator_add(self, i, j, x)
        class(accumulator_t), intent(inout) :: self
        integer, intent(in) :: i, j
        real(wp), intent(in) :: x
        integer(i8) :: slot
        if (.not. self%sparse) then
            self%dense(i, j) = self%dense(i, j) + x
            return
        end if
        slot = self%csc%find(i, j)
        if (slot > 0) then
            self%csc%values(slot) = self%csc%values(slot) + x
        else if (x /= 0.0_wp) then
            self%misses = self%misses + 1
            self%miss_row = i
            self%miss_col = j
        end if
    end subroutine accumulator_add

    !> Entries (row0 + k, col0 + l) += block(k, l).
    pure subroutine accumulator_add_range(self, row0, col0, block)
        class(accumulator_t), intent(inout) :: self
        integer, intent(in) :: row0, col0
        real(wp), intent(in) :: block(:, :)
        integer :: k, l
        if (.not. self%sparse) then
            self%dense(row0 + 1:row0 + size(block, 1), col0 + 1:col0 + size(block, 2)) = &
                self%dense(row0 + 1:row0 + size(block, 1), col0 + 1:col0 + size(block, 2)) &
                + block
            return
        end if
        do l = 1, size(block, 2)
            do k = 1, size(block, 1)
                call self%add(row0 + k, col0 + l, block(k, l))
            end do
        end do
    end subroutine accumulator_add_range

    !> The dense result.
    pure subroutine accumulator_get_dense(self, out)
        class(accumulator_t), intent(in) :: self
        real(wp), intent(out) :: out(:, :)
        out = self%dense
    end subroutine accumulator_get_dense

    !> The sparse result's values; a contribution outside the pattern fails.
    subroutine accumulator_get_values(self, values, what, status)
        class(accumulator_t), intent(in) :: self
        real(wp), intent(out) :: values(:)
        character(len=*), intent(in) :: what !! the block's name, for the message
        type(status_t), intent(inout) :: status
        values = self%csc%values
        if (self%misses > 0) call status%set(status_bad_input, what // ': ' // &
            int_text(int(self%misses)) // ' nonzero contribution(s) outside the sparse &
            &pattern, e.g. at (' // int_text(self%miss_row) // ', ' // &
            int_text(self%miss_col) // ')')
    end subroutine accumulator_get_values

    pure logical function accumulator_is_sparse(self)
        class(accumulator_t), intent(in) :: self
        accumulator_is_sparse = self%sparse
    end function accumulator_is_sparse
end module flexmbs_linalg_accumulator
