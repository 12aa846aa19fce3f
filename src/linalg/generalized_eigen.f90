!> Eigenvalues of a dense matrix pencil, A v = λ B v, by LAPACK's QZ
!> algorithm (`dggev3`), B possibly singular.
!>
!> Each eigenvalue comes as a pair (α, β) with λ = α / β; a singular B gives
!> β = 0 (an infinite eigenvalue) in exact arithmetic and a β of the order of
!> round-off in floating point. The pairs are returned normalised to
!> |α|² + β² = 1 (β ≥ 0), so that β is the sine of the chordal distance of λ
!> from ∞ and one threshold separates the infinite eigenvalues from the
!> finite ones whatever the scale of λ. LAPACK returns a complex pair with
!> conjugate ratios but not always equal β; the pair is returned as exact
!> conjugates (α, β) and (ᾱ, β) of its first member.
module flexmbs_linalg_generalized_eigen
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_lapack, only: dggev3_quiet
    implicit none
    private

    public :: pencil_eigenvalues

contains

    !> The n eigenvalue pairs (α, β) of the pencil (A, B), both n x n,
    !> normalised as the module says. A complex pair of eigenvalues comes as
    !> two consecutive entries with conjugate α.
    subroutine pencil_eigenvalues(a, b, alpha, beta, status)
        real(wp), intent(in) :: a(:, :)                    !! A (not changed)
        real(wp), intent(in) :: b(:, :)                    !! B (not changed)
        complex(wp), allocatable, intent(out) :: alpha(:)  !! α of each eigenvalue
        real(wp), allocatable, intent(out) :: beta(:)      !! β ≥ 0 of each eigenvalue
        type(status_t), intent(out) :: status
        real(wp), allocatable :: aw(:, :), bw(:, :), alphar(:), alphai(:), work(:)
        real(wp) :: vl(1, 1), vr(1, 1), query(1), scale
        integer :: n, info, lwork, i, stat
        character(len=160) :: msg

        n = size(a, 1)
        if (size(a, 2) /= n .or. size(b, 1) /= n .or. size(b, 2) /= n) then
            write (msg, '(a,4(i0,a))') 'pencil eigenvalues: A is ', size(a, 1), ' x ', &
                size(a, 2), ' and B ', size(b, 1), ' x ', size(b, 2), ': need two n x n'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        allocate (alpha(n), beta(n))
        if (n == 0) return
        allocate (aw(n, n), bw(n, n), alphar(n), alphai(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'pencil eigenvalues: copies of A and B', &
                               2_i8 * n * n + 2_i8 * n, 8)
            return
        end if
        aw = a
        bw = b
        alphar = 0.0_wp
        alphai = 0.0_wp
        beta = 0.0_wp
        call dggev3_quiet('N', 'N', n, aw, n, bw, n, alphar, alphai, beta, vl, 1, vr, 1, &
                         query, -1, info)
        lwork = max(8 * n, int(query(1)))
        allocate (work(lwork), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'pencil eigenvalues: LAPACK workspace', &
                               int(lwork, i8), 8)
            return
        end if
        work = 0.0_wp
        call dggev3_quiet('N', 'N', n, aw, n, bw, n, alphar, alphai, beta, vl, 1, vr, 1, &
                         work, lwork, info)
        if (info /= 0) then
            write (msg, '(a,i0,a)') 'pencil eigenvalues: LAPACK dggev3 failed (info = ', info, &
                '): the QZ iteration did not converge'
            call status%set(status_solver_failure, trim(msg))
            return
        end if
        do i = 1, n
            alpha(i) = cmplx(alphar(i), alphai(i), kind=wp)
            scale = hypot(abs(alpha(i)), beta(i))
            if (beta(i) < 0.0_wp) scale = -scale
            if (scale /= 0.0_wp) then
                alpha(i) = alpha(i) / scale
                beta(i) = beta(i) / scale
            end if
        end do
        ! dggev3: alphai(j) > 0 opens a pair, alphai(j + 1) < 0 closes it
        do i = 1, n - 1
            if (alphai(i) > 0.0_wp .and. alphai(i + 1) < 0.0_wp) then
                alpha(i + 1) = conjg(alpha(i))
                beta(i + 1) = beta(i)
            end if
        end do
    end subroutine pencil_eigenvalues
end module flexmbs_linalg_generalized_eigen
