!> The sparse pattern of shifted iteration matrices A = c*M - J, shared by
!> the sparse LU solvers (KLU, MUMPS).
!>
!> `build` forms once the union pattern of M, J and the full diagonal (the
!> shift c*M must always find its slots, and the LU then sees a zero-free
!> diagonal), in CSC with 0-based indices, with maps from the CSC slots of J
!> and M into it. Afterwards `gather` puts the values of J and M on the union
!> pattern, and `real_values` / `complex_values` form c*M - J there: no
!> allocation, and one code path for a real and a complex shift.
!>
!> A dense M or J makes the union pattern full (n² slots): solvers choose a
!> sparse LU only for a sparse J, and a dense mass matrix is small in practice.
module flexmbs_linalg_shifted_pattern
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_none, storage_identity, storage_dense, &
        storage_sparse
    implicit none
    private

    !> Union pattern of M, J and the diagonal, with slot maps and the values
    !> of M and J on it.
    type, public :: shifted_pattern_t
        private
        integer :: n = 0
        logical :: full_pattern = .false.        !! union pattern is all n² slots
        integer :: jac_storage = storage_none    !! storages seen at build
        integer :: mass_storage = storage_none
        integer(i8) :: jac_nnz = 0, mass_nnz = 0 !! CSC sizes seen at build
        integer(i8), allocatable :: jac_slot(:)  !! J's CSC slot -> union slot (1-based)
        integer(i8), allocatable :: mass_slot(:) !! M's CSC slot -> union slot
        integer(i8), allocatable :: diag_slot(:) !! diagonal i -> union slot
        integer(i8), allocatable :: colptr(:)    !! union pattern, 0-based CSC
        integer(i8), allocatable :: rowind(:)
        real(wp), allocatable :: jvalues(:)      !! J on the union pattern
        real(wp), allocatable :: mvalues(:)      !! M on the union pattern
    contains
        procedure :: build => pattern_build
        procedure :: fits => pattern_fits
        procedure :: gather => pattern_gather
        procedure :: prepare => pattern_prepare
        procedure :: real_values => pattern_real_values
        procedure :: complex_values => pattern_complex_values
        procedure :: order => pattern_order
        procedure :: nonzeros => pattern_nonzeros
        procedure :: column_pointers => pattern_column_pointers
        procedure :: row_indices => pattern_row_indices
    end type shifted_pattern_t

contains

    !> Build the union pattern of M, J and the diagonal with its slot maps;
    !> with `values` and `zvalues`, also the solver's real and complex arrays
    !> of one value per slot for c*M - J (allocated once, here).
    !> `who` starts every message ('klu solver', 'mumps solver').
    subroutine pattern_build(self, mass, jac, who, status, values, zvalues)
        class(shifted_pattern_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        character(len=*), intent(in) :: who
        type(status_t), intent(out) :: status
        real(wp), allocatable, intent(out), optional :: values(:)
        complex(wp), allocatable, intent(out), optional :: zvalues(:)
        integer :: n, stat

        n = jac%n
        call check_operands(n, mass, jac, who, status)
        if (.not. status%ok()) return
        self%n = 0
        self%jac_storage = jac%storage
        self%mass_storage = mass%storage
        self%jac_nnz = 0
        self%mass_nnz = 0
        if (jac%storage == storage_sparse) self%jac_nnz = jac%csc%nnz
        if (mass%storage == storage_sparse) self%mass_nnz = mass%csc%nnz
        self%full_pattern = jac%storage == storage_dense .or. mass%storage == storage_dense
        if (allocated(self%jac_slot)) deallocate (self%jac_slot)
        if (allocated(self%mass_slot)) deallocate (self%mass_slot)
        if (allocated(self%diag_slot)) deallocate (self%diag_slot)
        if (allocated(self%jvalues)) deallocate (self%jvalues)
        if (allocated(self%mvalues)) deallocate (self%mvalues)
        allocate (self%jac_slot(self%jac_nnz), self%mass_slot(self%mass_nnz), self%diag_slot(n), &
            stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' slot maps', self%jac_nnz + self%mass_nnz + n, 8)
            return
        end if

        if (self%full_pattern) then
            call full_union(self, n, mass, jac, who, status)
        else
            call sparse_union(self, n, mass, jac, status)
        end if
        if (.not. status%ok()) return
        allocate (self%jvalues(self%colptr(n + 1)), self%mvalues(self%colptr(n + 1)), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' values of J and M', 2 * self%colptr(n + 1), 8)
            return
        end if
        self%n = n
        if (present(values) .and. present(zvalues)) &
            call value_arrays(self, values, zvalues, who, status)
    end subroutine pattern_build

    !> Orders and storages must agree; a sparse LU needs J itself, not a
    !> difference quotient to come. A missing M (storage_none) counts as
    !> zero, as in the dense solver.
    subroutine check_operands(n, mass, jac, who, status)
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        character(len=*), intent(in) :: who
        type(status_t), intent(inout) :: status
        character(len=200) :: msg
        if (n <= 0) then
            write (msg, '(a,i0,a)') who // ': order of J n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        select case (jac%storage)
        case (storage_dense, storage_sparse)
        case default
            call status%set(status_bad_input, who // ': J must be given in dense or ' // &
                "sparse storage; use linear_solver = 'dense' for a difference Jacobian")
            return
        end select
        if (.not. operand_fits(n, jac)) then
            write (msg, '(a,i0)') who // ': J storage does not have order n = ', n
            call status%set(status_bad_input, trim(msg))
        else if (.not. operand_fits(n, mass)) then
            write (msg, '(a,i0)') who // ': M storage does not have the order of J, n = ', n
            call status%set(status_bad_input, trim(msg))
        end if
    end subroutine check_operands

    logical function operand_fits(n, a)
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: a
        select case (a%storage)
        case (storage_dense)
            operand_fits = .false.
            if (allocated(a%dense)) operand_fits = all(shape(a%dense) == [n, n])
        case (storage_sparse)
            operand_fits = a%csc%is_built() .and. a%csc%nrow == n .and. a%csc%ncol == n
        case default
            operand_fits = .true.
        end select
    end function operand_fits

    !> All n² slots, column by column; slot of (i, j) is (j-1)*n + i.
    subroutine full_union(self, n, mass, jac, who, status)
        type(shifted_pattern_t), intent(inout) :: self
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        character(len=*), intent(in) :: who
        type(status_t), intent(inout) :: status
        integer :: i, j, stat
        if (allocated(self%colptr)) deallocate (self%colptr)
        if (allocated(self%rowind)) deallocate (self%rowind)
        allocate (self%colptr(n + 1), self%rowind(int(n, i8) * n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' full pattern', n + 1_i8 + int(n, i8) * n, 8)
            return
        end if
        do j = 1, n
            self%colptr(j) = int(j - 1, i8) * n
            do i = 1, n
                self%rowind(self%colptr(j) + i) = i - 1
            end do
            self%diag_slot(j) = self%colptr(j) + j
        end do
        self%colptr(n + 1) = int(n, i8) * n
        if (jac%storage == storage_sparse) call map_full(jac%csc, n, self%jac_slot)
        if (mass%storage == storage_sparse) call map_full(mass%csc, n, self%mass_slot)
    end subroutine full_union

    subroutine map_full(a, n, slot)
        type(csc_matrix_t), intent(in) :: a
        integer, intent(in) :: n
        integer(i8), intent(out) :: slot(:)
        integer :: j
        integer(i8) :: p
        do j = 1, n
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                slot(p) = int(j - 1, i8) * n + a%rowind(p) + 1
            end do
        end do
    end subroutine map_full

    !> Union of sparse J, sparse or identity M and the diagonal: the entries
    !> are listed as triplets (diagonal, then J's slots, then M's) and merged
    !> by csc_matrix_t%build, whose triplet map is exactly the slot maps.
    subroutine sparse_union(self, n, mass, jac, status)
        type(shifted_pattern_t), intent(inout) :: self
        integer, intent(in) :: n
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        type(csc_matrix_t) :: union
        integer, allocatable :: rows(:), cols(:)
        integer(i8) :: nt, k
        integer :: i, stat

        nt = n + self%jac_nnz + self%mass_nnz
        allocate (rows(nt), cols(nt), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'union pattern positions', 2 * nt, 4)
            return
        end if
        do i = 1, n
            rows(i) = i
            cols(i) = i
        end do
        k = n
        call jac%csc%append_positions(rows, cols, k)
        if (mass%storage == storage_sparse) call mass%csc%append_positions(rows, cols, k)
        call union%build(n, n, rows, cols, status)
        if (.not. status%ok()) return
        self%diag_slot = union%triplet_map(1:n)
        self%jac_slot = union%triplet_map(n + 1:n + self%jac_nnz)
        self%mass_slot = union%triplet_map(n + self%jac_nnz + 1:nt)
        call move_alloc(union%colptr, self%colptr)
        call move_alloc(union%rowind, self%rowind)
    end subroutine sparse_union

    !> True when M and J keep the storages and CSC sizes they had at build
    !> (the slot maps were built for those); otherwise a message in status.
    logical function pattern_fits(self, mass, jac, who, status)
        class(shifted_pattern_t), intent(in) :: self
        type(matrix_t), intent(in) :: mass, jac
        character(len=*), intent(in) :: who
        type(status_t), intent(inout) :: status
        pattern_fits = .false.
        if (self%n <= 0) then
            call status%set(status_bad_input, who // ': factor called before init')
        else if (jac%storage /= self%jac_storage .or. mass%storage /= self%mass_storage) then
            call status%set(status_bad_input, &
                who // ': storage of M or J changed since init; call init again')
        else if (jac%n /= self%n) then
            call status%set(status_bad_input, &
                who // ': order of J changed since init; call init again')
        else if (.not. csc_size_is(jac, self%jac_nnz) &
                 .or. .not. csc_size_is(mass, self%mass_nnz)) then
            call status%set(status_bad_input, &
                who // ': sparsity pattern of M or J changed since init; call init again')
        else
            pattern_fits = .true.
        end if
    end function pattern_fits

    pure logical function csc_size_is(a, nnz)
        type(matrix_t), intent(in) :: a
        integer(i8), intent(in) :: nnz
        csc_size_is = .true.
        if (a%storage == storage_sparse) csc_size_is = a%csc%nnz == nnz
    end function csc_size_is

    !> Put the values of J and M on the union pattern (M = 0 for storage_none).
    !> Call `fits` first.
    subroutine pattern_gather(self, mass, jac)
        class(shifted_pattern_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        call gather_one(self, jac, self%jac_slot, self%jvalues)
        call gather_one(self, mass, self%mass_slot, self%mvalues)
    end subroutine pattern_gather

    subroutine gather_one(self, a, slot, values)
        type(shifted_pattern_t), intent(in) :: self
        type(matrix_t), intent(in) :: a
        integer(i8), intent(in) :: slot(:)
        real(wp), intent(out) :: values(:)
        integer :: i, j
        integer(i8) :: p
        values = 0.0_wp
        select case (a%storage)
        case (storage_identity)
            do i = 1, self%n
                values(self%diag_slot(i)) = 1.0_wp
            end do
        case (storage_dense)
            do j = 1, self%n
                do i = 1, self%n
                    values(int(j - 1, i8) * self%n + i) = a%dense(i, j)
                end do
            end do
        case (storage_sparse)
            do p = 1, size(slot, kind=i8)
                values(slot(p)) = a%csc%values(p)
            end do
        end select
    end subroutine gather_one

    !> Before a factorisation: true when the solver's LU objects are
    !> `analysed` and M, J still `fit`; their values are then gathered.
    logical function pattern_prepare(self, mass, jac, who, analysed, status)
        class(shifted_pattern_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        character(len=*), intent(in) :: who
        logical, intent(in) :: analysed !! the solver's LU objects exist
        type(status_t), intent(inout) :: status
        pattern_prepare = .false.
        if (.not. analysed) then
            call status%set(status_bad_input, who // ': factor called before init ' // &
                '(a copy made by assignment holds no LU objects: call init on it)')
        else if (self%fits(mass, jac, who, status)) then
            call self%gather(mass, jac)
            pattern_prepare = .true.
        end if
    end function pattern_prepare

    !> values = c*M - J on the union pattern (after `gather`).
    pure subroutine pattern_real_values(self, c, values)
        class(shifted_pattern_t), intent(in) :: self
        real(wp), intent(in) :: c
        real(wp), intent(out) :: values(:) !! one per union slot
        values = c * self%mvalues - self%jvalues
    end subroutine pattern_real_values

    !> values = c*M - J with a complex shift c (after `gather`).
    pure subroutine pattern_complex_values(self, c, values)
        class(shifted_pattern_t), intent(in) :: self
        complex(wp), intent(in) :: c
        complex(wp), intent(out) :: values(:) !! one per union slot
        values = c * self%mvalues - self%jvalues
    end subroutine pattern_complex_values

    !> Matrix order (0 before build).
    pure integer function pattern_order(self)
        class(shifted_pattern_t), intent(in) :: self
        pattern_order = self%n
    end function pattern_order

    ! Real and complex arrays of one value per slot, for the solvers' c*M - J.
    subroutine value_arrays(self, values, zvalues, who, status)
        class(shifted_pattern_t), intent(in) :: self
        real(wp), allocatable, intent(out) :: values(:)
        complex(wp), allocatable, intent(out) :: zvalues(:)
        character(len=*), intent(in) :: who
        type(status_t), intent(inout) :: status
        integer :: stat
        allocate (values(self%nonzeros()), zvalues(self%nonzeros()), stat=stat)
        if (stat /= 0) then
            ! real and complex: 3 values of 8 bytes a slot
            call out_of_memory(status, who // ' values', 3 * self%nonzeros(), 8)
            if (allocated(values)) deallocate (values)
        end if
    end subroutine value_arrays

    !> Slots of the union pattern (0 before build).
    pure integer(i8) function pattern_nonzeros(self)
        class(shifted_pattern_t), intent(in) :: self
        pattern_nonzeros = 0
        if (self%n > 0) pattern_nonzeros = self%colptr(self%n + 1)
    end function pattern_nonzeros

    !> The union pattern's column pointers (size n+1, 0-based offsets).
    pure function pattern_column_pointers(self) result(colptr)
        class(shifted_pattern_t), intent(in) :: self
        integer(i8), allocatable :: colptr(:)
        colptr = self%colptr
    end function pattern_column_pointers

    !> The union pattern's row indices (0-based, sorted in each column).
    pure function pattern_row_indices(self) result(rowind)
        class(shifted_pattern_t), intent(in) :: self
        integer(i8), allocatable :: rowind(:)
        rowind = self%rowind
    end function pattern_row_indices
end module flexmbs_linalg_shifted_pattern
