!> The lowest eigenpairs of a symmetric definite pencil K φ = λ M φ, K
!> symmetric positive (semi)definite and M symmetric positive definite, both
!> CSC on one pattern or on two: the natural frequencies ω = √λ and mode
!> shapes of a linear elastic structure.
!>
!> Dense (LAPACK `dsygv`: Cholesky of M, then the symmetric QR algorithm)
!> gives every pair; it serves small orders and the all-modes tests.
!> ARPACK (`dsaupd`, `dseupd`; Debian's libarpack2-dev) serves large ones in
!> its symmetric generalised shift-invert mode (mode 3, bmat = 'G'): OP =
!> (K − σM)⁻¹ M, self-adjoint in the M inner product, whose eigenvalues of
!> largest magnitude ν = 1/(λ − σ) are the λ nearest σ; with σ at or below
!> the spectrum's bottom these are the lowest. One factorisation of K − σM
!> (a `linear_solver_t` of the factory: KLU or MUMPS on 3-D meshes) serves
!> every application of OP. The vectors come back M-orthonormal in both
!> methods, the values ascending. The calling sequences are ARPACK's
!> published ones (ARPACK Users' Guide, Lehoucq, Sorensen and Yang, SIAM
!> 1998, §3.3 and the headers of dsaupd.f and dseupd.f).
module flexmbs_linalg_symmetric_modes
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    use flexmbs_linalg_factory, only: new_linear_solver
    use flexmbs_linalg_lapack, only: dsygv_quiet
    implicit none
    private

    public :: lowest_modes

    !> `method = 'auto'` solves pencils up to this order densely. dsygv costs
    !> about 9 n³ flops: 1 s near n = 1500 on this machine's one BLAS thread.
    integer, parameter, public :: symmetric_dense_limit = 1200
    !> Lanczos basis for nev wanted pairs (the guide's ncv ≥ 2 nev), at
    !> least 20 so that restarts stay rare for small nev.
    integer, parameter :: min_basis = 20
    integer, parameter :: max_restarts = 300

    interface
        subroutine dsaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, &
                          workd, workl, lworkl, info)
            import :: wp
            integer, intent(inout) :: ido, info
            character, intent(in) :: bmat
            character(len=2), intent(in) :: which
            integer, intent(in) :: n, nev, ncv, ldv, lworkl
            real(wp), intent(inout) :: tol
            real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
            integer, intent(inout) :: iparam(11), ipntr(11)
        end subroutine dsaupd
        subroutine dseupd(rvec, howmny, select, d, z, ldz, sigma, bmat, n, which, nev, tol, &
                          resid, ncv, v, ldv, iparam, ipntr, workd, workl, lworkl, info)
            import :: wp
            logical, intent(in) :: rvec
            character, intent(in) :: howmny, bmat
            logical, intent(inout) :: select(*)
            real(wp), intent(out) :: d(*), z(ldz, *)
            integer, intent(in) :: ldz, n, nev, ncv, ldv, lworkl
            real(wp), intent(in) :: sigma
            real(wp), intent(inout) :: tol
            character(len=2), intent(in) :: which
            real(wp), intent(inout) :: resid(*), v(ldv, *), workd(*), workl(*)
            integer, intent(inout) :: iparam(11), ipntr(11)
            integer, intent(out) :: info
        end subroutine dseupd
    end interface

contains

    !> The `count` lowest eigenpairs of K φ = λ M φ: values(1:count)
    !> ascending, vectors(:, j) M-orthonormal. `method` is 'dense',
    !> 'arpack' or 'auto' (dense up to symmetric_dense_limit); `shift` is
    !> ARPACK's σ (default 0: K must then be nonsingular), below the lowest
    !> λ wanted; `linear_solver` names the factory's LU for K − σM
    !> (default 'auto').
    subroutine lowest_modes(stiffness, mass, count, method, values, vectors, status, shift, &
                            linear_solver, used)
        type(csc_matrix_t), intent(in) :: stiffness   !! K (n x n)
        type(csc_matrix_t), intent(in) :: mass        !! M (n x n)
        integer, intent(in) :: count
        character(len=*), intent(in) :: method
        real(wp), allocatable, intent(out) :: values(:)
        real(wp), allocatable, intent(out) :: vectors(:, :)
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: shift
        character(len=*), intent(in), optional :: linear_solver
        !> the method that ran: 'dense' or 'arpack' ('' for none asked)
        character(len=:), allocatable, intent(out), optional :: used
        character(len=:), allocatable :: chosen
        integer :: n
        real(wp) :: sigma
        character(len=:), allocatable :: lu

        n = stiffness%nrow
        if (stiffness%ncol /= n .or. mass%nrow /= n .or. mass%ncol /= n) then
            call status%set(status_bad_input, 'symmetric modes: K and M must be square and &
                &of one order (K ' // int_text(stiffness%nrow) // ' x ' // &
                int_text(stiffness%ncol) // ', M ' // int_text(mass%nrow) // ' x ' // &
                int_text(mass%ncol) // ')')
            return
        end if
        if (count < 0 .or. count > n) then
            call status%set(status_bad_input, 'symmetric modes: ' // int_text(count) // &
                ' modes asked of a pencil of order ' // int_text(n))
            return
        end if
        allocate (values(count), vectors(n, count))
        if (present(used)) used = ''
        if (count == 0) return
        sigma = 0.0_wp
        if (present(shift)) sigma = shift
        lu = 'auto'
        if (present(linear_solver)) lu = linear_solver
        chosen = method
        ! 'auto': ARPACK needs count < n; the dense method takes any count
        if (method == 'auto') chosen = merge('dense ', 'arpack', n <= symmetric_dense_limit &
                                             .or. count >= n - 1)
        select case (trim(chosen))
        case ('dense')
            call dense_modes(stiffness, mass, count, values, vectors, status)
        case ('arpack')
            call arpack_modes(stiffness, mass, count, sigma, lu, values, vectors, status)
        case default
            call status%set(status_bad_input, "symmetric modes: method '" // method // &
                "': use 'auto', 'dense' or 'arpack'")
            return
        end select
        if (present(used)) used = trim(chosen)
    end subroutine lowest_modes

    !> Every pair by dsygv (itype 1: K φ = λ M φ), the lowest `count` kept.
    subroutine dense_modes(stiffness, mass, count, values, vectors, status)
        type(csc_matrix_t), intent(in) :: stiffness, mass
        integer, intent(in) :: count
        real(wp), intent(out) :: values(:), vectors(:, :)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: a(:, :), b(:, :), w(:), work(:)
        real(wp) :: query(1)
        integer :: n, info, lwork, stat

        n = stiffness%nrow
        allocate (a(n, n), b(n, n), w(n), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'dense modes: copies of K and M', 2_i8 * n * n, 8)
            return
        end if
        call stiffness%to_dense(a)
        call mass%to_dense(b)
        call dsygv_quiet(1, 'V', 'U', n, a, n, b, n, w, query, -1, info)
        lwork = max(3 * n, int(query(1)))
        allocate (work(lwork), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'dense modes: LAPACK workspace', int(lwork, i8), 8)
            return
        end if
        call dsygv_quiet(1, 'V', 'U', n, a, n, b, n, w, work, lwork, info)
        if (info > n) then
            call status%set(status_bad_input, 'symmetric modes: M is not positive definite &
                &(LAPACK dsygv: leading minor ' // int_text(info - n) // ')')
            return
        else if (info /= 0) then
            call status%set(status_solver_failure, 'symmetric modes: LAPACK dsygv failed &
                &(info = ' // int_text(info) // '): the QR iteration did not converge')
            return
        end if
        values = w(1:count)
        vectors = a(:, 1:count)
    end subroutine dense_modes

    !> The lowest `count` pairs by ARPACK's shift-invert Lanczos (mode 3).
    subroutine arpack_modes(stiffness, mass, count, sigma, lu, values, vectors, status)
        type(csc_matrix_t), intent(in) :: stiffness, mass
        integer, intent(in) :: count
        real(wp), intent(in) :: sigma
        character(len=*), intent(in) :: lu
        real(wp), intent(out) :: values(:), vectors(:, :)
        type(status_t), intent(inout) :: status
        class(linear_solver_t), allocatable :: solver
        type(matrix_t) :: k_mat, m_mat
        real(wp), allocatable :: resid(:), v(:, :), workd(:), workl(:), d(:), x(:), y(:)
        logical, allocatable :: select(:)
        integer :: iparam(11), ipntr(11), n, ncv, lworkl, ido, info, stat, k
        ! 0 asks for ARPACK's default, machine precision; dsaupd writes it
        ! back, so a variable, never a constant.
        real(wp) :: tol

        n = stiffness%nrow
        tol = 0.0_wp
        if (count >= n) then
            call status%set(status_bad_input, 'symmetric modes: ARPACK finds at most n - 1 = ' &
                // int_text(n - 1) // ' of ' // int_text(n) // ' pairs; use the dense method')
            return
        end if
        ncv = min(n, max(2 * count + 1, min_basis))
        lworkl = ncv * (ncv + 8)
        allocate (resid(n), v(n, ncv), workd(3 * n), workl(lworkl), d(ncv), x(n), y(n), &
                  select(ncv), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'symmetric modes: ARPACK workspace', &
                               int(n, i8) * (ncv + 6), 8)
            return
        end if
        k_mat%storage = storage_sparse
        k_mat%n = n
        k_mat%csc = stiffness
        m_mat%storage = storage_sparse
        m_mat%n = n
        m_mat%csc = mass
        call new_linear_solver(lu, n, storage_sparse, solver, status, mass=m_mat, jac=k_mat)
        if (status%ok()) call solver%init(m_mat, k_mat, status)
        ! factor_real factors c M − J: with J = K and c = σ, −(K − σM).
        if (status%ok()) call solver%factor_real(sigma, m_mat, k_mat, status)
        if (.not. status%ok()) then
            status%message = 'symmetric modes: K - sigma M cannot be factored (a body held &
                &nowhere, or sigma an eigenvalue): ' // status%message
            return
        end if
        ! A fixed start that no mode of a regular mesh is orthogonal to.
        do k = 1, n
            resid(k) = 1.0_wp + 0.5_wp * sin(real(k, wp))
        end do
        iparam = 0
        iparam(1) = 1                 ! exact shifts
        iparam(3) = max_restarts
        iparam(7) = 3                 ! shift-invert, B = M
        ido = 0
        info = 1                      ! resid holds the start
        do
            call dsaupd_quiet()
            select case (ido)
            case (-1)                 ! y = OP x = (K − σM)⁻¹ M x
                call mass%matvec(workd(ipntr(1):ipntr(1) + n - 1), y)
                call solver%solve_real(y)
                workd(ipntr(2):ipntr(2) + n - 1) = -y
            case (1)                  ! y = (K − σM)⁻¹ (M x), M x given
                y = workd(ipntr(3):ipntr(3) + n - 1)
                call solver%solve_real(y)
                workd(ipntr(2):ipntr(2) + n - 1) = -y
            case (2)                  ! y = M x
                call mass%matvec(workd(ipntr(1):ipntr(1) + n - 1), y)
                workd(ipntr(2):ipntr(2) + n - 1) = y
            case default
                exit
            end select
        end do
        if (info /= 0 .and. info /= 1) then
            call status%set(status_solver_failure, 'symmetric modes: ARPACK dsaupd failed &
                &(info = ' // int_text(info) // '; ARPACK Users'' Guide, dsaupd.f)')
            return
        end if
        if (iparam(5) < count) then
            call status%set(status_solver_failure, 'symmetric modes: ARPACK converged on ' // &
                int_text(iparam(5)) // ' of ' // int_text(count) // ' modes in ' // &
                int_text(iparam(3)) // ' restarts')
            return
        end if
        call dseupd_quiet()
        if (info /= 0) then
            call status%set(status_solver_failure, 'symmetric modes: ARPACK dseupd failed &
                &(info = ' // int_text(info) // '; ARPACK Users'' Guide, dseupd.f)')
            return
        end if
        call sort_ascending(d(1:count), vectors)
        values = d(1:count)

    contains

        !> ARPACK's own LAPACK calls probe the arithmetic: keep the IEEE flags.
        subroutine dsaupd_quiet()
            type(ieee_status_type) :: saved
            call ieee_get_status(saved)
            call dsaupd(ido, 'G', n, 'LM', count, tol, resid, ncv, v, n, iparam, ipntr, &
                        workd, workl, lworkl, info)
            call ieee_set_status(saved)
        end subroutine dsaupd_quiet

        subroutine dseupd_quiet()
            type(ieee_status_type) :: saved
            call ieee_get_status(saved)
            call dseupd(.true., 'A', select, d, vectors, n, sigma, 'G', n, 'LM', count, tol, &
                        resid, ncv, v, n, iparam, ipntr, workd, workl, lworkl, info)
            call ieee_set_status(saved)
        end subroutine dseupd_quiet
    end subroutine arpack_modes

    !> Values ascending, their vectors with them (insertion sort: few pairs).
    pure subroutine sort_ascending(values, vectors)
        real(wp), intent(inout) :: values(:), vectors(:, :)
        real(wp) :: tv
        integer :: i, j
        do i = 2, size(values)
            j = i
            do while (j > 1)
                if (values(j - 1) <= values(j)) exit
                tv = values(j - 1)
                values(j - 1) = values(j)
                values(j) = tv
                call swap_columns(vectors, j - 1, j)
                j = j - 1
            end do
        end do
    end subroutine sort_ascending

    pure subroutine swap_columns(a, i, j)
        real(wp), intent(inout) :: a(:, :)
        integer, intent(in) :: i, j
        real(wp) :: t(size(a, 1))
        t = a(:, i)
        a(:, i) = a(:, j)
        a(:, j) = t
    end subroutine swap_columns
end module flexmbs_linalg_symmetric_modes
