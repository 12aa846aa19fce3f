!> Sparse saddle-point systems
!>
!>     K [x; y] = [M  Bᵀ; A  0] [x; y] = [f; g],
!>
!> M (nv x nv), A and B (nc x nv) on fixed CSC patterns, A and B sharing
!> one: the acceleration layout's [M Gᵀ; G 0], the coordinate projection
!> and the consistent initial values of the formulations. K's pattern and
!> the maps from the blocks into it are built once (`init`), KLU analyses it
!> once (lazily: a copy made by assignment analyses again, see
!> flexmbs_linalg_klu), and each `factor` refills values and factors
!> without allocating. KLU's maximum transversal and threshold pivoting
!> find nonzero pivots for the constraint rows, so the zero block needs no
!> slots and no shift.
module flexmbs_linalg_saddle_point
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_singular_matrix
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_block_assembly, only: block_assembly_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_auto
    implicit none
    private

    !> K = [M Bᵀ; A 0] and its sparse LU (module header).
    type, public :: saddle_point_t
        private
        integer :: nv = 0, nc = 0
        type(block_assembly_t) :: k
        integer :: id_m = 0, id_bt = 0, id_a = 0
        type(klu_factor_t) :: lu
        logical :: factored = .false.
    contains
        procedure :: init => saddle_init
        procedure :: factor => saddle_factor
        procedure :: solve => saddle_solve
        procedure :: order => saddle_order
    end type saddle_point_t

contains

    !> The pattern of K from those of M (nv x nv) and A, B (nc x nv).
    subroutine saddle_init(self, m_pattern, a_pattern, status)
        class(saddle_point_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: m_pattern, a_pattern
        type(status_t), intent(out) :: status
        self%nv = m_pattern%ncol
        self%nc = a_pattern%nrow
        call self%k%add_block(m_pattern, 0, 0, self%id_m)
        call self%k%add_block(a_pattern, 0, self%nv, self%id_bt, transposed=.true.)
        call self%k%add_block(a_pattern, self%nv, 0, self%id_a)
        call self%k%build(self%nv + self%nc, self%nv + self%nc, status)
        if (.not. status%ok()) status%message = 'saddle point: ' // status%message
    end subroutine saddle_init

    !> Factor K with the values of M, A and B (B = A when absent).
    subroutine saddle_factor(self, m_values, a_values, status, b_values)
        class(saddle_point_t), intent(inout) :: self
        real(wp), intent(in) :: m_values(:), a_values(:)
        type(status_t), intent(inout) :: status
        real(wp), intent(in), optional :: b_values(:)
        type(status_t) :: local
        if (.not. self%lu%is_analysed()) then
            call self%lu%analyse(self%nv + self%nc, self%k%matrix%colptr, &
                                 self%k%matrix%rowind, local, klu_ordering_auto)
            if (.not. local%ok()) then
                status = local
                status%message = 'saddle point: ' // status%message
                return
            end if
        end if
        call self%k%zero()
        call self%k%scatter(self%id_m, m_values)
        call self%k%scatter(self%id_a, a_values)
        if (present(b_values)) then
            call self%k%scatter(self%id_bt, b_values)
        else
            call self%k%scatter(self%id_bt, a_values)
        end if
        call self%lu%factor(self%k%matrix%values, local)
        self%factored = local%ok()
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
