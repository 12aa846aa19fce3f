!> The structured saddle-point solver (flexmbs_linalg_structured_saddle)
!> against LAPACK's LU of the assembled K = [M Bᵀ; A 0] on a system built
!> like a flexible multibody one: a sparse SPD block of order 120 (KLU, a
!> finite-element body), a constant 6 x 6 block (a rigid body), a 3 x 3
!> block whose values change between factorisations (a chain's M(q)), and
!> a massless block of 6 dofs (a node frame, zeros on its pattern), with
!> A ≠ B on one pattern (MEXAX's [M(q̃) G(q̃)ᵀ; G(q) 0]); and that only the
!> changed block is factored again.
module test_structured_saddle
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs
    use flexmbs_linalg_structured_saddle, only: structured_saddle_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_structured_saddle

    integer, parameter :: n_fe = 120, n_rigid = 6, n_chain = 3, n_frame = 6
    integer, parameter :: nv = n_fe + n_rigid + n_chain + n_frame, nc = 14

contains

    function collect_structured_saddle() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('equals_dense_lu', test_equals_dense)]
    end function collect_structured_saddle

    subroutine test_equals_dense(error)
        type(error_t), allocatable, intent(out) :: error
        type(csc_matrix_t) :: m, a
        type(structured_saddle_t) :: k
        type(status_t) :: status
        real(wp), allocatable :: md(:, :), ad(:, :), bd(:, :), bv(:), rhs(:), x(:)
        integer :: round, total, massive, factorizations, last
        real(wp) :: dev
        call build_mass(m, md)
        call build_constraints(a, ad)
        allocate (bd(nc, nv), bv(a%nnz), rhs(nv + nc), x(nv + nc))
        call k%init(m, a, status)
        call check(error, status%ok(), 'init: ' // status%text())
        if (allocated(error)) return
        last = 0
        do round = 1, 3
            ! B: A's pattern, other values; the chain block's values change
            call values_of(a, ad, 0.3_wp * round)
            bv = a%values
            call dense_of(a, bd)
            call values_of(a, ad, 0.0_wp)
            call chain_values(m, md, round)
            call k%assemble(m%values, a%values, bv)
            call k%factor(status)
            call check(error, status%ok(), 'factor: ' // status%text())
            if (allocated(error)) return
            call right_hand_side(rhs, round)
            x = rhs
            call k%solve(x, status)
            dev = difference(md, ad, bd, rhs, x)
            call check(error, dev <= 1.0e-12_wp, 'round ' // int_text(round) // &
                ': structured vs dense LU ' // real_text(dev))
            call k%block_counts(total, massive, factorizations)
            ! blocks: FE, the rigid body's three masses and its inertia, chain,
            ! frame; first the six with mass are factored, later the chain's
            call check(error, total == 7 .and. massive == 6 .and. factorizations - last == &
                merge(6, 1, round == 1), 'round ' // int_text(round) // ': ' // &
                int_text(factorizations - last) // ' block factorisations')
            if (allocated(error)) return
            last = factorizations
        end do
        print '(4x,a,es9.2)', 'structured [M B^T; A 0] vs dense LU: last difference ', dev
    end subroutine test_equals_dense

    !> M: FE-like SPD band block (a 1-D Laplacian plus a coupling at distance
    !> 3, diagonally dominant), rigid m I and inertia, chain 3 x 3, a frame's
    !> 6 x 6 pattern of zeros.
    subroutine build_mass(m, md)
        type(csc_matrix_t), intent(inout) :: m
        real(wp), allocatable, intent(out) :: md(:, :)
        integer, allocatable :: rows(:), cols(:)
        integer :: i, j, n0
        type(status_t) :: status
        allocate (md(nv, nv), source=0.0_wp)
        do i = 1, n_fe
            md(i, i) = 4.0_wp + 0.01_wp * i
            if (i > 1) md(i, i - 1) = -1.0_wp
            if (i < n_fe) md(i, i + 1) = -1.0_wp
            if (i > 3) md(i, i - 3) = 0.5_wp
            if (i <= n_fe - 3) md(i, i + 3) = 0.5_wp
        end do
        n0 = n_fe
        do i = 1, 3
            md(n0 + i, n0 + i) = 2.5_wp
        end do
        md(n0 + 4:n0 + 6, n0 + 4:n0 + 6) = reshape([0.3_wp, 0.01_wp, 0.0_wp, 0.01_wp, &
            0.2_wp, 0.02_wp, 0.0_wp, 0.02_wp, 0.4_wp], [3, 3])
        ! chain and frame: pattern only here (chain values per round)
        n0 = n_fe + n_rigid
        md(n0 + 1:n0 + n_chain, n0 + 1:n0 + n_chain) = 1.0_wp
        allocate (rows(0), cols(0))
        do j = 1, nv
            do i = 1, nv
                if (md(i, j) /= 0.0_wp .or. (i > n_fe + n_rigid + n_chain .and. &
                    j > n_fe + n_rigid + n_chain)) then
                    rows = [rows, i]
                    cols = [cols, j]
                end if
            end do
        end do
        call m%build(nv, nv, rows, cols, status)
        do i = 1, size(rows)
            m%values(m%triplet_map(i)) = md(rows(i), cols(i))
        end do
    end subroutine build_mass

    !> The chain's SPD block of round r into M (CSC and dense).
    subroutine chain_values(m, md, r)
        type(csc_matrix_t), intent(inout) :: m
        real(wp), intent(inout) :: md(:, :)
        integer, intent(in) :: r
        integer :: i, j, n0
        n0 = n_fe + n_rigid
        do j = 1, n_chain
            do i = 1, n_chain
                md(n0 + i, n0 + j) = 0.1_wp * cos(real(r + i + j, wp))
                if (i == j) md(n0 + i, n0 + j) = 1.0_wp + 0.2_wp * r + md(n0 + i, n0 + j)
                m%values(m%find(n0 + i, n0 + j)) = md(n0 + i, n0 + j)
            end do
        end do
    end subroutine chain_values

    !> A pattern over every kind of block: each constraint row touches a few
    !> FE dofs, the rigid or chain dofs, and the frame's dofs (so that the
    !> frame is held: rows 1..6 take its 6 dofs).
    subroutine build_constraints(a, ad)
        type(csc_matrix_t), intent(inout) :: a
        real(wp), allocatable, intent(out) :: ad(:, :)
        integer, allocatable :: rows(:), cols(:)
        integer :: i, j
        type(status_t) :: status
        allocate (ad(nc, nv), source=0.0_wp)
        do i = 1, nc
            ad(i, 1 + mod(7 * i, n_fe)) = 1.0_wp
            ad(i, 1 + mod(7 * i + 5, n_fe)) = 1.0_wp
            ad(i, n_fe + 1 + mod(i, n_rigid + n_chain)) = 1.0_wp
            if (i <= n_frame) ad(i, n_fe + n_rigid + n_chain + i) = 1.0_wp
            if (i > n_frame) ad(i, n_fe + n_rigid + n_chain + 1 + mod(i, n_frame)) = 1.0_wp
        end do
        allocate (rows(0), cols(0))
        do j = 1, nv
            do i = 1, nc
                if (ad(i, j) /= 0.0_wp) then
                    rows = [rows, i]
                    cols = [cols, j]
                end if
            end do
        end do
        call a%build(nc, nv, rows, cols, status)
    end subroutine build_constraints

    !> Values on A's pattern: sin-based, shifted by `phase`; also into ad.
    subroutine values_of(a, ad, phase)
        type(csc_matrix_t), intent(inout) :: a
        real(wp), intent(inout) :: ad(:, :)
        real(wp), intent(in) :: phase
        integer :: j, i
        integer(8) :: p
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                i = int(a%rowind(p)) + 1
                a%values(p) = 1.0_wp + 0.5_wp * sin(1.3_wp * i + 0.7_wp * j + phase)
                ad(i, j) = a%values(p)
            end do
        end do
    end subroutine values_of

    subroutine dense_of(a, d)
        type(csc_matrix_t), intent(in) :: a
        real(wp), intent(out) :: d(:, :)
        call a%to_dense(d)
    end subroutine dense_of

    subroutine right_hand_side(rhs, r)
        real(wp), intent(out) :: rhs(:)
        integer, intent(in) :: r
        integer :: i
        do i = 1, size(rhs)
            rhs(i) = cos(0.9_wp * i + r)
        end do
    end subroutine right_hand_side

    !> max |x − x_dense| / max |x_dense| with x_dense from LAPACK's LU of K.
    real(wp) function difference(md, ad, bd, rhs, x)
        real(wp), intent(in) :: md(:, :), ad(:, :), bd(:, :), rhs(:), x(:)
        real(wp), allocatable :: kd(:, :), xd(:)
        integer, allocatable :: piv(:)
        integer :: info
        allocate (kd(nv + nc, nv + nc), source=0.0_wp)
        allocate (piv(nv + nc))
        kd(1:nv, 1:nv) = md
        kd(1:nv, nv + 1:) = transpose(bd)
        kd(nv + 1:, 1:nv) = ad
        xd = rhs
        call dgetrf(nv + nc, nv + nc, kd, nv + nc, piv, info)
        call dgetrs('N', nv + nc, 1, kd, nv + nc, piv, xd, nv + nc, info)
        difference = maxval(abs(x - xd)) / maxval(abs(xd))
    end function difference
end module test_structured_saddle
