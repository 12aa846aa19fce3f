!> A growing list of matrix positions from which a CSC pattern is built
!> once: the patterns of the multibody derivative blocks are collected
!> block by block without counting them first.
module flexmbs_linalg_triplets
    use flexmbs_core_kinds, only: i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    !> Positions (1-based rows and columns), duplicates allowed.
    type, public :: triplets_t
        private
        integer, allocatable :: rows(:), cols(:)
        integer :: n = 0
        !> Entries a failed growth asked for (0: none failed); `add` has no
        !> status (it is called per entry), so `build` reports the failure.
        integer(i8) :: failed = 0
    contains
        procedure :: add => triplets_add
        procedure :: add_range => triplets_add_range
        procedure :: add_pattern => triplets_add_pattern
        procedure :: build => triplets_build
    end type triplets_t

contains

    !> Position (i, j).
    subroutine triplets_add(self, i, j)
        class(triplets_t), intent(inout) :: self
        integer, intent(in) :: i, j
        integer, allocatable :: tmp_rows(:), tmp_cols(:)
        integer :: stat
        if (self%failed > 0) return
        if (.not. allocated(self%rows)) allocate (self%rows(256), self%cols(256))
        if (self%n == size(self%rows)) then
            ! Past huge(n) / 2 the doubled size is no default integer.
            stat = 1
            if (self%n <= huge(self%n) / 2) &
                allocate (tmp_rows(2 * self%n), tmp_cols(2 * self%n), stat=stat)
            if (stat /= 0) then
                self%failed = 4_i8 * self%n
                return
            end if
            tmp_rows(1:self%n) = self%rows
            call move_alloc(tmp_rows, self%rows)
            tmp_cols(1:self%n) = self%cols
            call move_alloc(tmp_cols, self%cols)
        end if
        self%n = self%n + 1
        self%rows(self%n) = i
        self%cols(self%n) = j
    end subroutine triplets_add

    !> The full block of rows row0 + 1 .. row0 + nr, columns col0 + 1 .. col0 + nc.
    subroutine triplets_add_range(self, row0, col0, nr, nc)
        class(triplets_t), intent(inout) :: self
        integer, intent(in) :: row0, col0, nr, nc
        integer :: i, j
        do j = 1, nc
            do i = 1, nr
                call self%add(row0 + i, col0 + j)
            end do
        end do
    end subroutine triplets_add_range

    !> The positions of a's pattern shifted by (row0, col0).
    subroutine triplets_add_pattern(self, row0, col0, a)
        class(triplets_t), intent(inout) :: self
        integer, intent(in) :: row0, col0
        type(csc_matrix_t), intent(in) :: a
        integer :: j
        integer(i8) :: p
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                call self%add(row0 + int(a%rowind(p)) + 1, col0 + j)
            end do
        end do
    end subroutine triplets_add_pattern

    !> The nrow x ncol pattern of the positions (values zero).
    subroutine triplets_build(self, nrow, ncol, pattern, status)
        class(triplets_t), intent(in) :: self
        integer, intent(in) :: nrow, ncol
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(out) :: status
        integer :: empty(0)
        if (self%failed > 0) then
            call out_of_memory(status, 'sparse pattern positions', self%failed, 4)
        else if (self%n == 0) then
            call pattern%build(nrow, ncol, empty, empty, status)
        else
            call pattern%build(nrow, ncol, self%rows(1:self%n), self%cols(1:self%n), status)
        end if
    end subroutine triplets_build
end module flexmbs_linalg_triplets
