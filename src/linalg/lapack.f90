!> Explicit interfaces to the LAPACK (and BLAS) routines flexmbs calls.
module flexmbs_linalg_lapack
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp
    implicit none
    private
    public :: dgetrf, dgetrs, zgetrf, zgetrs, dgbtrf, dgbtrs, zgbtrf, zgbtrs, dgesvd, dsyev
    public :: dggev3
    public :: dgemm, zgemm
    public :: dgesvd_quiet, dsyev_quiet, dggev3_quiet, dsygv_quiet

    interface
        !> C ← α op(A) op(B) + β C in real arithmetic (BLAS).
        subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: wp
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            real(wp), intent(in) :: alpha, beta
            real(wp), intent(in) :: a(lda, *), b(ldb, *)
            real(wp), intent(inout) :: c(ldc, *)
        end subroutine dgemm
        !> C ← α op(A) op(B) + β C in complex arithmetic (BLAS).
        subroutine zgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: wp
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            complex(wp), intent(in) :: alpha, beta
            complex(wp), intent(in) :: a(lda, *), b(ldb, *)
            complex(wp), intent(inout) :: c(ldc, *)
        end subroutine zgemm
        !> LU factorisation with partial pivoting of a real general matrix.
        subroutine dgetrf(m, n, a, lda, ipiv, info)
            import :: wp
            integer, intent(in) :: m, n, lda
            real(wp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine dgetrf
        !> Solve with the LU factors of dgetrf (trans: 'N' or 'T').
        subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: wp
            character, intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
            real(wp), intent(in) :: a(lda, *)
            real(wp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dgetrs
        !> LU factorisation with partial pivoting of a complex general matrix.
        subroutine zgetrf(m, n, a, lda, ipiv, info)
            import :: wp
            integer, intent(in) :: m, n, lda
            complex(wp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine zgetrf
        !> Solve with the LU factors of zgetrf (trans: 'N', 'T' or 'C').
        subroutine zgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: wp
            character, intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
            complex(wp), intent(in) :: a(lda, *)
            complex(wp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgetrs
        !> LU factorisation of a real band matrix (kl sub-, ku superdiagonals; ab
        !> holds kl extra rows for the fill-in).
        subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
            import :: wp
            integer, intent(in) :: m, n, kl, ku, ldab
            real(wp), intent(inout) :: ab(ldab, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine dgbtrf
        !> Solve with the band LU factors of dgbtrf.
        subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
            import :: wp
            character, intent(in) :: trans
            integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb, ipiv(*)
            real(wp), intent(in) :: ab(ldab, *)
            real(wp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dgbtrs
        !> LU factorisation of a complex band matrix (storage as in dgbtrf).
        subroutine zgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
            import :: wp
            integer, intent(in) :: m, n, kl, ku, ldab
            complex(wp), intent(inout) :: ab(ldab, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine zgbtrf
        !> Solve with the band LU factors of zgbtrf.
        subroutine zgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
            import :: wp
            character, intent(in) :: trans
            integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb, ipiv(*)
            complex(wp), intent(in) :: ab(ldab, *)
            complex(wp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgbtrs
    end interface

    ! LAPACK routines with a quiet wrapper below: each has its wrapper's
    ! characteristics, declared once, in the wrapper.
    procedure(dgesvd_quiet) :: dgesvd
    procedure(dsyev_quiet) :: dsyev
    procedure(dsygv_quiet) :: dsygv
    procedure(dggev3_quiet) :: dggev3

contains

    !> dgesvd, leaving the IEEE flags as they were: LAPACK's IEEECK
    !> (called through ILAENV) computes 1/0 and 0/0 on purpose to test the
    !> arithmetic, which would otherwise leave the divide-by-zero and
    !> invalid flags signalling after every successful run. A flag our own
    !> arithmetic raised before the call stays raised.
    subroutine dgesvd_quiet(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info)
        character, intent(in) :: jobu, jobvt
        integer, intent(in) :: m, n, lda, ldu, ldvt, lwork
        real(wp), intent(inout) :: a(lda, *)
        real(wp), intent(out) :: s(*), u(ldu, *), vt(ldvt, *), work(*)
        integer, intent(out) :: info
        type(ieee_status_type) :: saved
        call ieee_get_status(saved)
        call dgesvd(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info)
        call ieee_set_status(saved)
    end subroutine dgesvd_quiet

    !> dsyev, leaving the IEEE flags as they were (see dgesvd_quiet).
    subroutine dsyev_quiet(jobz, uplo, n, a, lda, w, work, lwork, info)
        character, intent(in) :: jobz, uplo
        integer, intent(in) :: n, lda, lwork
        real(wp), intent(inout) :: a(lda, *)
        real(wp), intent(out) :: w(*), work(*)
        integer, intent(out) :: info
        type(ieee_status_type) :: saved
        call ieee_get_status(saved)
        call dsyev(jobz, uplo, n, a, lda, w, work, lwork, info)
        call ieee_set_status(saved)
    end subroutine dsyev_quiet

    !> dsygv, leaving the IEEE flags as they were (see dgesvd_quiet).
    subroutine dsygv_quiet(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, info)
        integer, intent(in) :: itype, n, lda, ldb, lwork
        character, intent(in) :: jobz, uplo
        real(wp), intent(inout) :: a(lda, *), b(ldb, *)
        real(wp), intent(out) :: w(*), work(*)
        integer, intent(out) :: info
        type(ieee_status_type) :: saved
        call ieee_get_status(saved)
        call dsygv(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, info)
        call ieee_set_status(saved)
    end subroutine dsygv_quiet

    !> dggev3, leaving the IEEE flags as they were (see dgesvd_quiet).
    subroutine dggev3_quiet(jobvl, jobvr, n, a, lda, b, ldb, alphar, alphai, beta, vl, ldvl, &
                           vr, ldvr, work, lwork, info)
        character, intent(in) :: jobvl, jobvr
        integer, intent(in) :: n, lda, ldb, ldvl, ldvr, lwork
        real(wp), intent(inout) :: a(lda, *), b(ldb, *)
        real(wp), intent(out) :: alphar(*), alphai(*), beta(*), vl(ldvl, *), vr(ldvr, *)
        real(wp), intent(out) :: work(*)
        integer, intent(out) :: info
        type(ieee_status_type) :: saved
        call ieee_get_status(saved)
        call dggev3(jobvl, jobvr, n, a, lda, b, ldb, alphar, alphai, beta, vl, ldvl, vr, ldvr, &
                   work, lwork, info)
        call ieee_set_status(saved)
    end subroutine dggev3_quiet
end module flexmbs_linalg_lapack
