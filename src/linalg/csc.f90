!> Compressed sparse column matrices with a pattern fixed once.
!>
!> The pattern is built from triplets (duplicates merged); afterwards the
!> values are refilled in place, either directly or from triplet values
!> through the stored triplet-to-slot map (duplicates summed). Indices are
!> 64-bit and 0-based, the layout KLU's `klu_l_*` and SUNDIALS use.
module flexmbs_linalg_csc
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    implicit none
    private

    public :: pattern_matvec, pattern_matvec_transpose

    !> A sparse matrix in CSC form (0-based 64-bit indices).
    type, public :: csc_matrix_t
        integer :: nrow = 0
        integer :: ncol = 0
        integer(i8) :: nnz = 0
        integer(i8), allocatable :: colptr(:)    !! size ncol+1, 0-based offsets
        integer(i8), allocatable :: rowind(:)    !! size nnz, 0-based rows
        real(wp), allocatable :: values(:)       !! size nnz
        integer(i8), allocatable :: triplet_map(:) !! triplet k -> value slot (1-based)
    contains
        procedure :: build => csc_build
        procedure :: fill => csc_fill
        procedure :: matvec => csc_matvec
        procedure :: to_dense => csc_to_dense
        procedure :: find => csc_find
        procedure :: is_built => csc_is_built
        procedure :: append_positions => csc_append_positions
    end type csc_matrix_t

contains

    !> Append the 1-based (row, column) of every slot, in slot order, to
    !> (rows, cols) after their first k entries; k becomes the last filled
    !> (the triplets of a union pattern: dae/ida_setup, linalg/shifted_pattern).
    pure subroutine csc_append_positions(self, rows, cols, k)
        class(csc_matrix_t), intent(in) :: self
        integer, intent(inout) :: rows(:), cols(:)
        integer(i8), intent(inout) :: k
        integer :: j
        integer(i8) :: p
        do j = 1, self%ncol
            do p = self%colptr(j) + 1, self%colptr(j + 1)
                k = k + 1
                rows(k) = int(self%rowind(p)) + 1
                cols(k) = j
            end do
        end do
    end subroutine csc_append_positions

    !> Build the pattern from triplets (1-based rows and columns). Duplicate
    !> positions share one slot. Values are zeroed.
    subroutine csc_build(self, nrow, ncol, rows, cols, status)
        class(csc_matrix_t), intent(inout) :: self
        integer, intent(in) :: nrow, ncol      !! matrix shape
        integer, intent(in) :: rows(:), cols(:) !! 1-based triplet positions
        type(status_t), intent(out) :: status
        integer(i8), allocatable :: count(:), start(:), tmp_row(:), tmp_k(:), by_row(:)
        integer(i8) :: k, nt, p
        integer :: j, i, stat
        character(len=160) :: msg

        nt = size(rows, kind=i8)
        if (size(cols, kind=i8) /= nt) then
            call status%set(status_bad_input, 'csc build: rows and cols differ in length')
            return
        end if
        do k = 1, nt
            if (rows(k) < 1 .or. rows(k) > nrow .or. cols(k) < 1 .or. cols(k) > ncol) then
                write (msg, '(a,i0,a,i0,a,i0,a,i0,a,i0)') 'csc build: triplet ', k, &
                    ' at (', rows(k), ',', cols(k), ') outside ', nrow, ' x ', ncol
                call status%set(status_bad_input, trim(msg))
                return
            end if
        end do
        self%nrow = nrow
        self%ncol = ncol
        ! Two stable counting sorts, by row and then by column, leave each
        ! column's rows ascending in O(triplets + nrow + ncol): a column of
        ! an assembled FE pattern holds hundreds of duplicates, which an
        ! insertion sort per column paid for quadratically.
        allocate (count(max(nrow, ncol) + 1), start(ncol + 1), tmp_row(nt), tmp_k(nt), &
                  by_row(nt), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sparse pattern work arrays', 3 * nt + ncol + &
                               max(nrow, ncol) + 2_i8, 8)
            return
        end if
        count = 0
        do k = 1, nt
            count(rows(k) + 1) = count(rows(k) + 1) + 1
        end do
        count(1) = 1
        do i = 1, nrow
            count(i + 1) = count(i + 1) + count(i)
        end do
        do k = 1, nt
            by_row(count(rows(k))) = k
            count(rows(k)) = count(rows(k)) + 1
        end do
        count = 0
        do k = 1, nt
            count(cols(k) + 1) = count(cols(k) + 1) + 1
        end do
        start(1) = 1
        do j = 1, ncol
            start(j + 1) = start(j) + count(j + 1)
        end do
        count(:ncol) = start(:ncol)
        do p = 1, nt
            k = by_row(p)
            j = cols(k)
            tmp_row(count(j)) = rows(k)
            tmp_k(count(j)) = k
            count(j) = count(j) + 1
        end do
        ! Merge duplicates.
        if (allocated(self%colptr)) deallocate (self%colptr)
        if (allocated(self%rowind)) deallocate (self%rowind)
        if (allocated(self%values)) deallocate (self%values)
        if (allocated(self%triplet_map)) deallocate (self%triplet_map)
        allocate (self%colptr(ncol + 1), self%rowind(nt), self%triplet_map(nt), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sparse pattern', ncol + 1_i8 + 2 * nt, 8)
            call forget()
            return
        end if
        self%nnz = 0
        self%colptr(1) = 0
        do j = 1, ncol
            i = -1
            do p = start(j), start(j + 1) - 1
                if (tmp_row(p) /= i) then
                    self%nnz = self%nnz + 1
                    self%rowind(self%nnz) = tmp_row(p) - 1
                    i = int(tmp_row(p))
                end if
                self%triplet_map(tmp_k(p)) = self%nnz
            end do
            self%colptr(j + 1) = self%nnz
        end do
        self%rowind = self%rowind(:self%nnz)
        allocate (self%values(self%nnz), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sparse matrix values', self%nnz, 8)
            call forget()
            return
        end if
        self%values = 0.0_wp
    contains
        ! A pattern half built is no pattern: is_built must stay false.
        subroutine forget()
            if (allocated(self%colptr)) deallocate (self%colptr)
            if (allocated(self%rowind)) deallocate (self%rowind)
            if (allocated(self%triplet_map)) deallocate (self%triplet_map)
            self%nnz = 0
        end subroutine forget
    end subroutine csc_build

    !> Refill the values from triplet values (same order as at build time),
    !> summing duplicates. Allocates nothing.
    pure subroutine csc_fill(self, triplet_values)
        class(csc_matrix_t), intent(inout) :: self
        real(wp), intent(in) :: triplet_values(:) !! one value per triplet
        integer(i8) :: k
        self%values = 0.0_wp
        do k = 1, size(triplet_values, kind=i8)
            self%values(self%triplet_map(k)) = self%values(self%triplet_map(k)) + triplet_values(k)
        end do
    end subroutine csc_fill

    !> y = A x.
    pure subroutine csc_matvec(self, x, y)
        class(csc_matrix_t), intent(in) :: self
        real(wp), intent(in) :: x(:)   !! size ncol
        real(wp), intent(out) :: y(:)  !! size nrow
        integer :: j
        integer(i8) :: p
        y = 0.0_wp
        do j = 1, self%ncol
            do p = self%colptr(j) + 1, self%colptr(j + 1)
                y(self%rowind(p) + 1) = y(self%rowind(p) + 1) + self%values(p) * x(j)
            end do
        end do
    end subroutine csc_matvec

    !> Scatter into a dense array (zeroed first).
    pure subroutine csc_to_dense(self, a)
        class(csc_matrix_t), intent(in) :: self
        real(wp), intent(out) :: a(:, :) !! nrow x ncol
        integer :: j
        integer(i8) :: p
        a = 0.0_wp
        do j = 1, self%ncol
            do p = self%colptr(j) + 1, self%colptr(j + 1)
                a(self%rowind(p) + 1, j) = self%values(p)
            end do
        end do
    end subroutine csc_to_dense

    !> Slot (1-based) of entry (i, j), or 0 when outside the pattern.
    pure function csc_find(self, i, j) result(slot)
        class(csc_matrix_t), intent(in) :: self
        integer, intent(in) :: i, j !! 1-based row and column
        integer(i8) :: slot
        integer(i8) :: lo, hi, mid
        slot = 0
        lo = self%colptr(j) + 1
        hi = self%colptr(j + 1)
        do while (lo <= hi)
            mid = (lo + hi) / 2
            if (self%rowind(mid) + 1 == i) then
                slot = mid
                return
            else if (self%rowind(mid) + 1 < i) then
                lo = mid + 1
            else
                hi = mid - 1
            end if
        end do
    end function csc_find

    !> y = A x, A the pattern `a` with the given slot values (a's own values
    !> unused): for patterns shared by several value arrays.
    pure subroutine pattern_matvec(a, values, x, y)
        type(csc_matrix_t), intent(in) :: a
        real(wp), intent(in) :: values(:) !! one per slot
        real(wp), intent(in) :: x(:)      !! size ncol
        real(wp), intent(out) :: y(:)     !! size nrow
        integer :: j
        integer(i8) :: p
        y = 0.0_wp
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                y(a%rowind(p) + 1) = y(a%rowind(p) + 1) + values(p) * x(j)
            end do
        end do
    end subroutine pattern_matvec

    !> y = Aᵀ x, A the pattern `a` with the given slot values.
    pure subroutine pattern_matvec_transpose(a, values, x, y)
        type(csc_matrix_t), intent(in) :: a
        real(wp), intent(in) :: values(:) !! one per slot
        real(wp), intent(in) :: x(:)      !! size nrow
        real(wp), intent(out) :: y(:)     !! size ncol
        integer :: j
        integer(i8) :: p
        do j = 1, a%ncol
            y(j) = 0.0_wp
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                y(j) = y(j) + values(p) * x(a%rowind(p) + 1)
            end do
        end do
    end subroutine pattern_matvec_transpose

    !> True once a pattern exists.
    pure logical function csc_is_built(self)
        class(csc_matrix_t), intent(in) :: self
        csc_is_built = allocated(self%colptr)
    end function csc_is_built
end module flexmbs_linalg_csc
