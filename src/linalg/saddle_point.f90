!> Saddle-point systems
!>
!>     K [x; y] = [M  Bᵀ; A  0] [x; y] = [f; g],
!>
!> M (nv x nv), A and B (nc x nv): the coordinate projection and the
!> consistent initial values of the formulations, and MEXAX's augmented
!> systems, dense or sparse.
!>
!> Dense (`init_dense`): K in an array, LAPACK's LU or, for the classic
!> faces, the classic elimination order (flexmbs_linalg_dense).
!>
!> Sparse (`init`): M, A and B on fixed CSC patterns, A and B sharing
!> one. K's pattern and
!> the maps from the blocks into it are built once (`init`), KLU analyses it
!> once (lazily: a copy made by assignment analyses again, see
!> flexmbs_linalg_klu); `assemble` refills the values and `factor` factors
!> them, reusing the last pivot order while it stays good
!> (klu_factor_t%refactor), without allocating. KLU's maximum transversal
!> and threshold pivoting find nonzero pivots for the constraint rows, so
!> the zero block needs no slots and no shift. MEXAX's augmented systems
!> [M(q̃) G(q̃)ᵀ; G(q) 0] take B ≠ A on the same pattern.
module flexmbs_linalg_saddle_point
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_singular_matrix
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_block_assembly, only: block_assembly_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_auto
    use flexmbs_linalg_dense, only: dense_lu_factor, dense_lu_solve
    implicit none
    private

    !> K = [M Bᵀ; A 0] and its sparse LU (module header).
    type, public :: saddle_point_t
        private
        integer :: nv = 0, nc = 0
        logical :: sparse = .true.
        logical :: classic_order = .false.      !! dense: the classic elimination order
        real(wp), allocatable :: kd(:, :)       !! dense K and its LU
        integer, allocatable :: ipiv(:)
        type(block_assembly_t) :: k
        integer :: id_m = 0, id_bt = 0, id_a = 0
        type(klu_factor_t) :: lu
        integer :: ordering = klu_ordering_auto
    contains
        procedure :: init => saddle_init
        procedure :: init_dense => saddle_init_dense
        procedure, private :: assemble_sparse => saddle_assemble
        procedure, private :: assemble_dense => saddle_assemble_dense
        generic :: assemble => assemble_sparse, assemble_dense
        procedure :: factor => saddle_factor
        procedure :: solve => saddle_solve
        procedure :: order => saddle_order
    end type saddle_point_t

contains

    !> The pattern of K from those of M (nv x nv) and A, B (nc x nv);
    !> `ordering` is KLU's (klu_ordering_*, default auto).
    subroutine saddle_init(self, m_pattern, a_pattern, status, ordering)
        class(saddle_point_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: m_pattern, a_pattern
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: ordering
        call default_blas_threads()
        if (present(ordering)) self%ordering = ordering
        self%nv = m_pattern%ncol
        self%nc = a_pattern%nrow
        call self%k%add_block(m_pattern, 0, 0, self%id_m)
        call self%k%add_block(a_pattern, 0, self%nv, self%id_bt, transposed=.true.)
        call self%k%add_block(a_pattern, self%nv, 0, self%id_a)
        call self%k%build(self%nv + self%nc, self%nv + self%nc, status)
        if (.not. status%ok()) status%message = 'saddle point: ' // status%message
    end subroutine saddle_init

    !> A dense K of order nv + nc; `classic_order` selects the classic
    !> elimination order instead of LAPACK's (the classic faces' counters).
    subroutine saddle_init_dense(self, nv, nc, classic_order, status)
        class(saddle_point_t), intent(inout) :: self
        integer, intent(in) :: nv, nc
        logical, intent(in), optional :: classic_order
        !> Out of memory; without it, a failed allocation stops the program.
        type(status_t), intent(out), optional :: status
        integer :: stat
        call default_blas_threads()
        self%sparse = .false.
        self%nv = nv
        self%nc = nc
        if (present(classic_order)) self%classic_order = classic_order
        if (allocated(self%kd)) deallocate (self%kd)
        if (allocated(self%ipiv)) deallocate (self%ipiv)
        if (.not. present(status)) then
            allocate (self%kd(nv + nc, nv + nc), self%ipiv(nv + nc))
            return
        end if
        allocate (self%kd(nv + nc, nv + nc), self%ipiv(nv + nc), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'dense saddle-point matrix', &
                int(nv + nc, i8) * (nv + nc), 8)
            if (allocated(self%kd)) deallocate (self%kd)
        end if
    end subroutine saddle_init_dense

    !> Dense K from M, A and B (B = A when absent).
    pure subroutine saddle_assemble_dense(self, m, a, b)
        class(saddle_point_t), intent(inout) :: self
        real(wp), intent(in) :: m(:, :), a(:, :)
        real(wp), intent(in), optional :: b(:, :)
        associate (nv => self%nv, k => self%kd)
            k(1:nv, 1:nv) = m
            if (present(b)) then
                k(1:nv, nv + 1:) = transpose(b)
            else
                k(1:nv, nv + 1:) = transpose(a)
            end if
            k(nv + 1:, 1:nv) = a
            k(nv + 1:, nv + 1:) = 0.0_wp
        end associate
    end subroutine saddle_assemble_dense

    !> K's values from those of M, A and B (B = A when absent).
    pure subroutine saddle_assemble(self, m_values, a_values, b_values)
        class(saddle_point_t), intent(inout) :: self
        real(wp), intent(in) :: m_values(:), a_values(:)
        real(wp), intent(in), optional :: b_values(:)
        call self%k%zero()
        call self%k%scatter(self%id_m, m_values)
        call self%k%scatter(self%id_a, a_values)
        if (present(b_values)) then
            call self%k%scatter(self%id_bt, b_values)
        else
            call self%k%scatter(self%id_bt, a_values)
        end if
    end subroutine saddle_assemble

    !> LU of the assembled K; a singular K fails with reason_singular_matrix.
    subroutine saddle_factor(self, status)
        class(saddle_point_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        if (.not. self%sparse) then
            call dense_lu_factor(self%kd, self%ipiv, local, self%classic_order)
            if (.not. local%ok()) status = local
            return
        end if
        if (.not. self%lu%is_analysed()) then
            call self%lu%analyse(self%nv + self%nc, self%k%matrix%colptr, &
                                 self%k%matrix%rowind, local, self%ordering)
            if (.not. local%ok()) then
                status = local
                status%message = 'saddle point: ' // status%message
                return
            end if
        end if
        call self%lu%refactor(self%k%matrix%values, local)
        if (.not. local%ok()) call status%set(status_solver_failure, 'saddle-point matrix &
            &[M G^T; G 0] is singular (redundant constraints?): ' // local%text(), &
            reason_singular_matrix)
    end subroutine saddle_factor

    !> rhs ← K⁻¹ rhs (size nv + nc).
    subroutine saddle_solve(self, rhs, status)
        class(saddle_point_t), intent(inout) :: self
        real(wp), intent(inout) :: rhs(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        if (.not. self%sparse) then
            call dense_lu_solve(self%kd, self%ipiv, rhs, self%classic_order)
            return
        end if
        call self%lu%solve(rhs, local)
        if (.not. local%ok()) then
            status = local
            status%message = 'saddle point: ' // status%message
        end if
    end subroutine saddle_solve

    !> Order nv + nc of K.
    pure integer function saddle_order(self)
        class(saddle_point_t), intent(in) :: self
        saddle_order = self%nv + self%nc
    end function saddle_order
end module flexmbs_linalg_saddle_point
