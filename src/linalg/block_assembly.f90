!> A global CSC matrix assembled from sparse blocks, each placed once at an
!> offset (optionally transposed) and refilled by scattering its values
!> through a slot map: the formulations' Jacobians and saddle-point matrices.
!>
!> Use: `add_block`/`add_diagonal` register the blocks' patterns, `build`
!> makes the global pattern (their union) and every block's map from its
!> slots to global slots, once. Afterwards `zero`, `scatter` and
!> `scatter_diagonal` refill the values in place without allocating.
!> Also the sparse product C = A B on fixed patterns (`product_pattern`
!> once, `product_values` per evaluation) and the transpose with its slot map.
module flexmbs_linalg_block_assembly
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    implicit none
    private

    !> One registered block: a pattern (or a diagonal of length n) at an offset.
    type :: placed_block_t
        integer :: row0 = 0, col0 = 0
        logical :: transposed = .false.
        logical :: diagonal = .false.
        integer :: n = 0                      !! diagonal length
        type(csc_matrix_t) :: pattern         !! values unused
        integer(i8), allocatable :: slot(:)   !! block slot (or diagonal entry) -> global slot
    end type placed_block_t

    !> The global matrix and its blocks (module header).
    type, public :: block_assembly_t
        private
        type(placed_block_t), allocatable :: blocks(:)
        integer :: nblocks = 0
        type(csc_matrix_t), public :: matrix   !! global pattern and values
    contains
        procedure :: add_block => assembly_add_block
        procedure :: add_diagonal => assembly_add_diagonal
        procedure :: build => assembly_build
        procedure :: zero => assembly_zero
        procedure :: scatter => assembly_scatter
        procedure :: scatter_diagonal => assembly_scatter_diagonal
        procedure :: scatter_full => assembly_scatter_full
    end type block_assembly_t

    public :: product_pattern, product_positions, product_values, transpose_pattern, transpose_values

contains

    !> Register `pattern` at (row0, col0) (as its transpose when `transposed`);
    !> `id` names it for `scatter`.
    subroutine assembly_add_block(self, pattern, row0, col0, id, transposed)
        class(block_assembly_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: pattern
        integer, intent(in) :: row0, col0
        integer, intent(out) :: id
        logical, intent(in), optional :: transposed
        call grow(self)
        id = self%nblocks
        associate (b => self%blocks(id))
            b%row0 = row0
            b%col0 = col0
            b%pattern%nrow = pattern%nrow
            b%pattern%ncol = pattern%ncol
            b%pattern%nnz = pattern%nnz
            b%pattern%colptr = pattern%colptr
            b%pattern%rowind = pattern%rowind
            if (present(transposed)) b%transposed = transposed
        end associate
    end subroutine assembly_add_block

    !> Register the diagonal entries (row0 + k, col0 + k), k = 1 .. n.
    subroutine assembly_add_diagonal(self, n, row0, col0, id)
        class(block_assembly_t), intent(inout) :: self
        integer, intent(in) :: n, row0, col0
        integer, intent(out) :: id
        call grow(self)
        id = self%nblocks
        self%blocks(id)%diagonal = .true.
        self%blocks(id)%n = n
        self%blocks(id)%row0 = row0
        self%blocks(id)%col0 = col0
    end subroutine assembly_add_diagonal

    subroutine grow(self)
        type(block_assembly_t), intent(inout) :: self
        type(placed_block_t), allocatable :: tmp(:)
        if (.not. allocated(self%blocks)) allocate (self%blocks(8))
        if (self%nblocks == size(self%blocks)) then
            allocate (tmp(2 * size(self%blocks)))
            tmp(1:self%nblocks) = self%blocks(1:self%nblocks)
            call move_alloc(tmp, self%blocks)
        end if
        self%nblocks = self%nblocks + 1
    end subroutine grow

    !> The global nrow x ncol pattern (union of the blocks) and the maps.
    subroutine assembly_build(self, nrow, ncol, status)
        class(block_assembly_t), intent(inout) :: self
        integer, intent(in) :: nrow, ncol
        type(status_t), intent(out) :: status
        integer, allocatable :: rows(:), cols(:)
        integer(i8) :: nt, k, p
        integer :: id, j, i, r, c, stat
        nt = 0
        do id = 1, self%nblocks
            if (self%blocks(id)%diagonal) then
                nt = nt + self%blocks(id)%n
            else
                nt = nt + self%blocks(id)%pattern%nnz
            end if
        end do
        allocate (rows(nt), cols(nt), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'block assembly positions', 2 * nt, 4)
            return
        end if
        k = 0
        do id = 1, self%nblocks
            associate (b => self%blocks(id))
                if (b%diagonal) then
                    do i = 1, b%n
                        k = k + 1
                        rows(k) = b%row0 + i
                        cols(k) = b%col0 + i
                    end do
                    cycle
                end if
                do j = 1, b%pattern%ncol
                    do p = b%pattern%colptr(j) + 1, b%pattern%colptr(j + 1)
                        k = k + 1
                        call position(b, int(b%pattern%rowind(p)) + 1, j, rows(k), cols(k))
                    end do
                end do
            end associate
        end do
        call self%matrix%build(nrow, ncol, rows, cols, status)
        if (.not. status%ok()) then
            status%message = 'block assembly: ' // status%message
            return
        end if
        deallocate (rows, cols)
        do id = 1, self%nblocks
            associate (b => self%blocks(id))
                if (b%diagonal) then
                    allocate (b%slot(b%n), stat=stat)
                    if (stat /= 0) then
                        call out_of_memory(status, 'block assembly slots', int(b%n, i8), 8)
                        return
                    end if
                    do i = 1, b%n
                        b%slot(i) = self%matrix%find(b%row0 + i, b%col0 + i)
                    end do
                    cycle
                end if
                allocate (b%slot(b%pattern%nnz), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'block assembly slots', b%pattern%nnz, 8)
                    return
                end if
                do j = 1, b%pattern%ncol
                    do p = b%pattern%colptr(j) + 1, b%pattern%colptr(j + 1)
                        call position(b, int(b%pattern%rowind(p)) + 1, j, r, c)
                        b%slot(p) = self%matrix%find(r, c)
                    end do
                end do
            end associate
        end do
    contains
        pure subroutine position(b, i, j, r, c)
            type(placed_block_t), intent(in) :: b
            integer, intent(in) :: i, j
            integer, intent(out) :: r, c
            if (b%transposed) then
                r = b%row0 + j
                c = b%col0 + i
            else
                r = b%row0 + i
                c = b%col0 + j
            end if
        end subroutine position
    end subroutine assembly_build

    !> All global values to zero.
    pure subroutine assembly_zero(self)
        class(block_assembly_t), intent(inout) :: self
        self%matrix%values = 0.0_wp
    end subroutine assembly_zero

    !> Global values += scale * block id's values (one per slot of its pattern).
    pure subroutine assembly_scatter(self, id, values, scale)
        class(block_assembly_t), intent(inout) :: self
        integer, intent(in) :: id
        real(wp), intent(in) :: values(:)
        real(wp), intent(in), optional :: scale
        real(wp) :: s
        integer(i8) :: p
        s = 1.0_wp
        if (present(scale)) s = scale
        associate (slot => self%blocks(id)%slot, v => self%matrix%values)
            do p = 1, size(slot, kind=i8)
                v(slot(p)) = v(slot(p)) + s * values(p)
            end do
        end associate
    end subroutine assembly_scatter

    !> Global values += w for block id registered with a full pattern of w's
    !> shape (its slots in column-major order).
    pure subroutine assembly_scatter_full(self, id, w)
        class(block_assembly_t), intent(inout) :: self
        integer, intent(in) :: id
        real(wp), intent(in) :: w(:, :)
        integer :: i, j
        integer(i8) :: k
        k = 0
        associate (slot => self%blocks(id)%slot, v => self%matrix%values)
            do j = 1, size(w, 2)
                do i = 1, size(w, 1)
                    k = k + 1
                    v(slot(k)) = v(slot(k)) + w(i, j)
                end do
            end do
        end associate
    end subroutine assembly_scatter_full

    !> Global values += value on diagonal block id.
    pure subroutine assembly_scatter_diagonal(self, id, value)
        class(block_assembly_t), intent(inout) :: self
        integer, intent(in) :: id
        real(wp), intent(in) :: value
        integer :: i
        associate (slot => self%blocks(id)%slot, v => self%matrix%values)
            do i = 1, size(slot)
                v(slot(i)) = v(slot(i)) + value
            end do
        end associate
    end subroutine assembly_scatter_diagonal

    !> Pattern of C = A B (values zero).
    subroutine product_pattern(a, b, c, status)
        type(csc_matrix_t), intent(in) :: a, b
        type(csc_matrix_t), intent(inout) :: c
        type(status_t), intent(out) :: status
        integer, allocatable :: rows(:), cols(:), mark(:)
        integer(i8) :: nt
        integer :: pass, stat
        if (a%ncol /= b%nrow) then
            call status%set(status_bad_input, 'sparse product: A is ' // int_text(a%nrow) // &
                ' x ' // int_text(a%ncol) // ', B is ' // int_text(b%nrow) // ' x ' // &
                int_text(b%ncol))
            return
        end if
        allocate (mark(a%nrow), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'sparse product marks', int(a%nrow, i8), 4)
            return
        end if
        mark = 0
        allocate (rows(0), cols(0))
        ! pass 1 counts the entries of each column, pass 2 lists them
        nt = 0
        do pass = 1, 2
            if (pass == 2) then
                deallocate (rows, cols)
                allocate (rows(nt), cols(nt), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'sparse product positions', 2 * nt, 4)
                    return
                end if
                mark = 0
                nt = 0
            end if
            call product_positions(a, b, mark, nt, pass == 2, rows, cols)
        end do
        call c%build(a%nrow, b%ncol, rows, cols, status)
    end subroutine product_pattern

    !> The positions of A B, column by column of B, each row once a column:
    !> counted on in nt and, with `list`, stored at rows(nt), cols(nt) (pass
    !> 2 of a two-pass listing, pass 1 counting). mark(i) == j says that row
    !> i is in column j already; on entry mark (A's rows) holds no column of
    !> B (0 does).
    pure subroutine product_positions(a, b, mark, nt, list, rows, cols)
        type(csc_matrix_t), intent(in) :: a, b
        integer, intent(inout) :: mark(:)
        integer(i8), intent(inout) :: nt
        logical, intent(in) :: list
        integer, intent(inout) :: rows(:), cols(:)
        integer(i8) :: p, q
        integer :: j, k, i
        do j = 1, b%ncol
            do p = b%colptr(j) + 1, b%colptr(j + 1)
                k = int(b%rowind(p)) + 1
                do q = a%colptr(k) + 1, a%colptr(k + 1)
                i = int(a%rowind(q)) + 1
                if (mark(i) == j) cycle
                mark(i) = j
                nt = nt + 1
                if (list) then
                    rows(nt) = i
                    cols(nt) = j
                end if
                end do
            end do
        end do
    end subroutine product_positions

    !> Values of C = A B on the pattern from product_pattern.
    pure subroutine product_values(a, b, c)
        type(csc_matrix_t), intent(in) :: a, b
        type(csc_matrix_t), intent(inout) :: c
        integer(i8) :: p, q, slot
        integer :: j, k, i
        c%values = 0.0_wp
        do j = 1, b%ncol
            do p = b%colptr(j) + 1, b%colptr(j + 1)
                k = int(b%rowind(p)) + 1
                do q = a%colptr(k) + 1, a%colptr(k + 1)
                    i = int(a%rowind(q)) + 1
                    slot = c%find(i, j)
                    c%values(slot) = c%values(slot) + a%values(q) * b%values(p)
                end do
            end do
        end do
    end subroutine product_values

    !> Pattern of Aᵀ and the map from its slots to A's (values zero).
    subroutine transpose_pattern(a, at, map, status)
        type(csc_matrix_t), intent(in) :: a
        type(csc_matrix_t), intent(inout) :: at
        integer(i8), allocatable, intent(out) :: map(:)
        type(status_t), intent(out) :: status
        integer, allocatable :: rows(:), cols(:)
        integer(i8) :: p
        integer :: j, stat
        allocate (rows(a%nnz), cols(a%nnz), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'transpose positions', 2 * a%nnz, 4)
            return
        end if
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                rows(p) = j
                cols(p) = int(a%rowind(p)) + 1
            end do
        end do
        call at%build(a%ncol, a%nrow, rows, cols, status)
        if (.not. status%ok()) return
        allocate (map(at%nnz), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'transpose slot map', at%nnz, 8)
            return
        end if
        do p = 1, a%nnz
            map(at%triplet_map(p)) = p
        end do
    end subroutine transpose_pattern

    !> Aᵀ's values from A's through the map of transpose_pattern.
    pure subroutine transpose_values(a, at, map)
        type(csc_matrix_t), intent(in) :: a
        type(csc_matrix_t), intent(inout) :: at
        integer(i8), intent(in) :: map(:)
        integer(i8) :: p
        do p = 1, at%nnz
            at%values(p) = a%values(map(p))
        end do
    end subroutine transpose_values
end module flexmbs_linalg_block_assembly
