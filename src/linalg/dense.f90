!> Dense LU (LAPACK getrf/getrs) of real and complex shifted matrices, and
!> the real LU in the classic elimination order for the classic faces.
module flexmbs_linalg_dense
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix
    use flexmbs_linalg_matrix, only: matrix_t, storage_identity, storage_dense, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs, zgetrf, zgetrs
    implicit none
    private

    !> Dense LU of c*M - J, real and complex factors kept side by side.
    type, extends(linear_solver_t), public :: dense_solver_t
        real(wp), allocatable :: a(:, :)
        complex(wp), allocatable :: za(:, :)
        integer, allocatable :: ipiv(:), zipiv(:)
        !> Dense copies of sparse M or J, refreshed at each factorisation.
        real(wp), allocatable :: mass_work(:, :), jac_work(:, :)
        !> Real factor by `classic_lu_factor` instead of LAPACK (see there).
        logical :: classic_order = .false.
    contains
        procedure :: init => dense_init
        procedure :: factor_real => dense_factor_real
        procedure :: factor_complex => dense_factor_complex
        procedure :: solve_real => dense_solve_real
        procedure :: solve_complex => dense_solve_complex
        procedure :: name => dense_name
    end type dense_solver_t

    public :: dense_lu_factor, dense_lu_solve, classic_lu_factor, classic_lu_solve

contains

    subroutine dense_init(self, mass, jac, status)
        class(dense_solver_t), intent(inout) :: self
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: n, stat
        integer(i8) :: entries
        n = jac%n
        if (n <= 0) then
            call status%set(status_bad_input, 'dense solver: matrix order must be positive')
            return
        end if
        self%n = n
        call release(self)
        ! a (real), za (complex) and, for sparse M or J, their dense copies
        entries = 3 * int(n, i8) * n
        if (mass%storage == storage_sparse) entries = entries + int(n, i8) * n
        if (jac%storage == storage_sparse) entries = entries + int(n, i8) * n
        allocate (self%a(n, n), self%za(n, n), self%ipiv(n), self%zipiv(n), stat=stat)
        if (stat == 0 .and. mass%storage == storage_sparse) &
            allocate (self%mass_work(n, n), stat=stat)
        if (stat == 0 .and. jac%storage == storage_sparse) allocate (self%jac_work(n, n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'dense solver matrices of order ' // int_text(n), &
                entries, 8)
            call release(self)
            self%n = 0
        end if
    end subroutine dense_init

    ! What init allocates; a failed init leaves none of it, so that the next
    ! init starts clean.
    subroutine release(self)
        type(dense_solver_t), intent(inout) :: self
        if (allocated(self%a)) deallocate (self%a)
        if (allocated(self%za)) deallocate (self%za)
        if (allocated(self%ipiv)) deallocate (self%ipiv)
        if (allocated(self%zipiv)) deallocate (self%zipiv)
        if (allocated(self%mass_work)) deallocate (self%mass_work)
        if (allocated(self%jac_work)) deallocate (self%jac_work)
    end subroutine release

    !> Write c*M - J (real part of the shift only) into a.
    subroutine shifted(self, c, mass, jac, a)
        class(dense_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        real(wp), intent(out) :: a(:, :)
        integer :: i
        select case (jac%storage)
        case (storage_dense)
            a = -jac%dense
        case (storage_sparse)
            call jac%csc%to_dense(self%jac_work)
            a = -self%jac_work
        case default
            a = 0.0_wp
        end select
        select case (mass%storage)
        case (storage_dense)
            a = a + c * mass%dense
        case (storage_sparse)
            call mass%csc%to_dense(self%mass_work)
            a = a + c * self%mass_work
        case (storage_identity)
            do i = 1, self%n
                a(i, i) = a(i, i) + c
            end do
        end select
    end subroutine shifted

    subroutine dense_factor_real(self, c, mass, jac, status)
        class(dense_solver_t), intent(inout) :: self
        real(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: info
        call shifted(self, c, mass, jac, self%a)
        if (self%classic_order) then
            call classic_lu_factor(self%a, self%ipiv, info)
        else
            call dgetrf(self%n, self%n, self%a, self%n, self%ipiv, info)
        end if
        if (info /= 0) call status%set(status_solver_failure, &
            'dense LU: real iteration matrix is singular', reason_singular_matrix)
    end subroutine dense_factor_real

    subroutine dense_factor_complex(self, c, mass, jac, status)
        class(dense_solver_t), intent(inout) :: self
        complex(wp), intent(in) :: c
        type(matrix_t), intent(in) :: mass, jac
        type(status_t), intent(out) :: status
        integer :: info, i
        ! c*M - J, built in za: a holds the live real factorisation.
        select case (jac%storage)
        case (storage_dense)
            self%za = cmplx(-jac%dense, 0.0_wp, kind=wp)
        case (storage_sparse)
            call jac%csc%to_dense(self%jac_work)
            self%za = cmplx(-self%jac_work, 0.0_wp, kind=wp)
        case default
            self%za = (0.0_wp, 0.0_wp)
        end select
        select case (mass%storage)
        case (storage_dense)
            self%za = self%za + c * mass%dense
        case (storage_sparse)
            call mass%csc%to_dense(self%mass_work)
            self%za = self%za + c * self%mass_work
        case (storage_identity)
            do i = 1, self%n
                self%za(i, i) = self%za(i, i) + c
            end do
        end select
        call zgetrf(self%n, self%n, self%za, self%n, self%zipiv, info)
        if (info /= 0) call status%set(status_solver_failure, &
            'dense LU: complex iteration matrix is singular', reason_singular_matrix)
    end subroutine dense_factor_complex

    subroutine dense_solve_real(self, b)
        class(dense_solver_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:)
        call dense_lu_solve(self%a, self%ipiv, b, self%classic_order)
    end subroutine dense_solve_real

    subroutine dense_solve_complex(self, b)
        class(dense_solver_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:)
        integer :: info
        call zgetrs('N', self%n, 1, self%za, self%n, self%zipiv, b, self%n, info)
    end subroutine dense_solve_complex

    function dense_name(self) result(name)
        class(dense_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'dense'
    end function dense_name

    !> Plain LU of a general dense matrix in place (pivots in ipiv); with
    !> `classic_order`, by `classic_lu_factor` instead of LAPACK.
    subroutine dense_lu_factor(a, ipiv, status, classic_order)
        real(wp), intent(inout) :: a(:, :)
        integer, intent(out) :: ipiv(:)
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: classic_order
        integer :: info
        if (optional_true(classic_order)) then
            call classic_lu_factor(a, ipiv, info)
        else
            call dgetrf(size(a, 1), size(a, 2), a, size(a, 1), ipiv, info)
        end if
        if (info /= 0) call status%set(status_solver_failure, 'dense LU: matrix is singular', &
            reason_singular_matrix)
    end subroutine dense_lu_factor

    !> Solve with a factor from dense_lu_factor (the same `classic_order`),
    !> b overwritten.
    subroutine dense_lu_solve(a, ipiv, b, classic_order)
        real(wp), intent(in) :: a(:, :)
        integer, intent(in) :: ipiv(:)
        real(wp), intent(inout) :: b(:)
        logical, intent(in), optional :: classic_order
        integer :: info
        if (optional_true(classic_order)) then
            call classic_lu_solve(a, ipiv, b)
        else
            call dgetrs('N', size(a, 1), 1, a, size(a, 1), ipiv, b, size(a, 1), info)
        end if
    end subroutine dense_lu_solve

    pure logical function optional_true(flag)
        logical, intent(in), optional :: flag
        optional_true = .false.
        if (present(flag)) optional_true = flag
    end function optional_true

    !> Gaussian elimination with partial pivoting in the classic column
    !> order (Golub & Van Loan's kji form, as LINPACK's factoriser): at step
    !> k the pivot is the first largest |a(i,k)|, the column is scaled by
    !> −1/pivot, and each later column j gets a(:,j) + a(k,j)·a(:,k), one
    !> column at a time. No blocking, no fused multiply-add: every entry
    !> sees the same operations in the same order on every machine, whereas
    !> an optimised BLAS reorders and fuses them per CPU. On problems whose
    !> step sequence is round-off sensitive (Robertson with DDAINI: one ulp
    !> moves NJE by 20 %), this is what reproduces the original counters.
    !> The multipliers are stored negated; use `classic_lu_solve`. info > 0
    !> names the first zero pivot (the factorisation still completes).
    subroutine classic_lu_factor(a, ipiv, info)
        real(wp), intent(inout) :: a(:, :)
        integer, intent(out) :: ipiv(:)
        integer, intent(out) :: info
        integer :: n, k, p, i, j
        real(wp) :: t
        n = size(a, 1)
        info = 0
        do k = 1, n - 1
            p = k
            do i = k + 1, n
                if (abs(a(i, k)) > abs(a(p, k))) p = i
            end do
            ipiv(k) = p
            if (a(p, k) == 0.0_wp) then
                info = k
                cycle
            end if
            if (p /= k) then
                t = a(p, k)
                a(p, k) = a(k, k)
                a(k, k) = t
            end if
            t = -1.0_wp / a(k, k)
            a(k + 1:n, k) = t * a(k + 1:n, k)
            do j = k + 1, n
                t = a(p, j)
                if (p /= k) then
                    a(p, j) = a(k, j)
                    a(k, j) = t
                end if
                do i = k + 1, n
                    a(i, j) = a(i, j) + t * a(i, k)
                end do
            end do
        end do
        ipiv(n) = n
        if (a(n, n) == 0.0_wp) info = n
    end subroutine classic_lu_factor

    !> Solve A x = b with a factor from `classic_lu_factor`; b is overwritten.
    subroutine classic_lu_solve(a, ipiv, b)
        real(wp), intent(in) :: a(:, :)
        integer, intent(in) :: ipiv(:)
        real(wp), intent(inout) :: b(:)
        integer :: n, k, p, i
        real(wp) :: t
        n = size(a, 1)
        do k = 1, n - 1
            p = ipiv(k)
            t = b(p)
            if (p /= k) then
                b(p) = b(k)
                b(k) = t
            end if
            do i = k + 1, n
                b(i) = b(i) + t * a(i, k)
            end do
        end do
        do k = n, 1, -1
            b(k) = b(k) / a(k, k)
            t = -b(k)
            do i = 1, k - 1
                b(i) = b(i) + t * a(i, k)
            end do
        end do
    end subroutine classic_lu_solve
end module flexmbs_linalg_dense
