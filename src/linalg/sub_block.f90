!> A block of a CSC matrix picked by rows and columns, as a CSC matrix of
!> its own whose slots map back to the parent's: the pattern is found once,
!> afterwards `gather` copies the values (no search, no allocation).
module flexmbs_linalg_sub_block
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    !> A[rows, cols] of a parent A: its own pattern and the parent's slots.
    type, public :: sub_block_t
        type(csc_matrix_t) :: a                !! the block (values by gather)
        integer(i8), allocatable :: parent(:)  !! block slot -> parent slot (1-based)
    contains
        procedure :: pick => block_pick
        procedure :: gather => block_gather
    end type sub_block_t

contains

    !> The block of `parent` in the rows with row_of(i) > 0 and the columns
    !> with col_of(j) > 0, placed at (row_of(i), col_of(j)) of an nrow x
    !> ncol matrix.
    subroutine block_pick(self, parent, row_of, col_of, nrow, ncol, status)
        class(sub_block_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: parent
        integer, intent(in) :: row_of(:)   !! size parent%nrow
        integer, intent(in) :: col_of(:)   !! size parent%ncol
        integer, intent(in) :: nrow, ncol
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        integer(i8), allocatable :: from(:)
        integer(i8) :: p, k, nt
        integer :: j, i, stat
        nt = 0
        do j = 1, parent%ncol
            if (col_of(j) == 0) cycle
            do p = parent%colptr(j) + 1, parent%colptr(j + 1)
                if (row_of(parent%rowind(p) + 1) > 0) nt = nt + 1
            end do
        end do
        allocate (rows(nt), cols(nt), from(nt), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sub-block positions', 2 * nt, 8)
            return
        end if
        k = 0
        do j = 1, parent%ncol
            if (col_of(j) == 0) cycle
            do p = parent%colptr(j) + 1, parent%colptr(j + 1)
                i = row_of(parent%rowind(p) + 1)
                if (i == 0) cycle
                k = k + 1
                rows(k) = i
                cols(k) = col_of(j)
                from(k) = p
            end do
        end do
        call self%a%build(nrow, ncol, rows, cols, status)
        if (.not. status%ok()) return
        if (allocated(self%parent)) deallocate (self%parent)
        allocate (self%parent(self%a%nnz), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sub-block slot map', self%a%nnz, 8)
            return
        end if
        do k = 1, nt
            self%parent(self%a%triplet_map(k)) = from(k)
        end do
    end subroutine block_pick

    !> The block's values from the parent's values.
    pure subroutine block_gather(self, parent_values)
        class(sub_block_t), intent(inout) :: self
        real(wp), intent(in) :: parent_values(:)
        integer(i8) :: p
        do p = 1, self%a%nnz
            self%a%values(p) = parent_values(self%parent(p))
        end do
    end subroutine block_gather
end module flexmbs_linalg_sub_block
