!> A few eigenvalues of a large sparse pencil J v = λ M v nearest a real
!> shift σ, by ARPACK's implicitly restarted Arnoldi method (`dnaupd`,
!> `dneupd`; Debian's libarpack2-dev) in shift-invert form.
!>
!> ARPACK sees the operator OP = (J − σM)⁻¹ M in its regular mode (bmat =
!> 'I', mode 1) and asks for its eigenvalues ν of largest magnitude: an
!> eigenpair J v = λ M v gives OP v = v / (λ − σ), so ν = 1 / (λ − σ) and
!> λ = σ + 1 / ν, and the largest |ν| are the λ nearest σ. A singular M
!> (a DAE) only adds ν = 0: its infinite eigenvalues never come back. One
!> factorisation of σM − J by a `linear_solver_t` (dense, KLU or MUMPS)
!> serves every application of OP; the starting vector is OP² applied to a
!> fixed vector, which removes its components along the algebraic
!> directions (ν = 0, Jordan chains of length ≤ 2 included).
!>
!> ARPACK is Fortran 77 and reports through `info`; the interfaces below are
!> its published calling sequences (ARPACK Users' Guide, Lehoucq, Sorensen
!> and Yang, SIAM 1998, and the headers of dnaupd.f and dneupd.f).
module flexmbs_linalg_arpack
    use, intrinsic :: ieee_exceptions, only: ieee_status_type, ieee_get_status, ieee_set_status
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_matrix, only: matrix_t
    use flexmbs_linalg_linear_solver, only: linear_solver_t
    implicit none
    private

    public :: shift_invert_eigenvalues

    !> Arnoldi basis size for nev wanted values: ARPACK's guide recommends
    !> ncv ≥ 2 nev + 1; a floor of 20 keeps restarts rare for small nev.
    integer, parameter :: min_basis = 20
    !> Restart limit (iparam(3)); when it is reached, the eigenvalues that
    !> converged come back (fewer than asked for).
    integer, parameter :: default_max_restarts = 500

    interface
        subroutine dnaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, &
                          workd, workl, lworkl, info)
            import :: wp
            integer, intent(inout) :: ido
            character(len=1), intent(in) :: bmat
            integer, intent(in) :: n
            character(len=2), intent(in) :: which
            integer, intent(in) :: nev
            real(wp), intent(in) :: tol
            real(wp), intent(inout) :: resid(n)
            integer, intent(in) :: ncv, ldv
            real(wp), intent(inout) :: v(ldv, ncv)
            integer, intent(inout) :: iparam(11)
            integer, intent(out) :: ipntr(14)
            real(wp), intent(inout) :: workd(3 * n)
            integer, intent(in) :: lworkl
            real(wp), intent(inout) :: workl(lworkl)
            integer, intent(inout) :: info
        end subroutine dnaupd
        subroutine dneupd(rvec, howmny, select, dr, di, z, ldz, sigmar, sigmai, workev, bmat, &
                          n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, workd, &
                          workl, lworkl, info)
            import :: wp
            logical, intent(in) :: rvec
            character(len=1), intent(in) :: howmny
            integer, intent(in) :: ncv, nev, ldz, n, ldv, lworkl
            logical, intent(inout) :: select(ncv)
            real(wp), intent(out) :: dr(nev + 1), di(nev + 1)
            real(wp), intent(inout) :: z(ldz, *)
            real(wp), intent(in) :: sigmar, sigmai
            real(wp), intent(inout) :: workev(3 * ncv)
            character(len=1), intent(in) :: bmat
            character(len=2), intent(in) :: which
            real(wp), intent(in) :: tol
            real(wp), intent(inout) :: resid(n)
            real(wp), intent(inout) :: v(ldv, ncv)
            integer, intent(inout) :: iparam(11)
            integer, intent(inout) :: ipntr(14)
            real(wp), intent(inout) :: workd(3 * n)
            real(wp), intent(inout) :: workl(lworkl)
            integer, intent(inout) :: info
        end subroutine dneupd
    end interface

contains

    !> The `count` eigenvalues λ of J v = λ M v nearest the real shift σ,
    !> nearest first: a complex pair counts as two, and one more comes back
    !> when it completes a pair; fewer when ARPACK converges on fewer.
    !> `solver` is a new linear solver from the factory, initialised and
    !> factored here.
    subroutine shift_invert_eigenvalues(jac, mass, sigma, count, solver, lambda, status, &
                                        tol, max_restarts, restarts, operations)
        type(matrix_t), intent(in) :: jac                !! J
        type(matrix_t), intent(in) :: mass               !! M (may be singular)
        real(wp), intent(in) :: sigma                    !! shift σ, not an eigenvalue
        integer, intent(in) :: count                     !! eigenvalues wanted, 1..n-2
        class(linear_solver_t), intent(inout) :: solver  !! factors σM − J
        complex(wp), allocatable, intent(out) :: lambda(:)
        type(status_t), intent(out) :: status
        real(wp), intent(in), optional :: tol            !! ARPACK's tol (default: ε)
        integer, intent(in), optional :: max_restarts    !! default 500
        integer, intent(out), optional :: restarts       !! Arnoldi restarts taken
        integer, intent(out), optional :: operations     !! applications of OP
        real(wp), allocatable :: resid(:), v(:, :), workd(:), workl(:), workev(:), z(:, :)
        real(wp), allocatable :: dr(:), di(:), x(:), y(:)
        logical, allocatable :: select(:)
        integer :: iparam(11), ipntr(14), n, ncv, lworkl, ido, info, stat, nconv, k, nop
        real(wp) :: arpack_tol
        character(len=200) :: msg

        allocate (lambda(0))
        n = jac%n
        if (count < 1 .or. count > n - 2) then
            write (msg, '(a,i0,a,i0,a)') 'ARPACK: ', count, ' eigenvalues asked for a pencil &
                &of order ', n, ': need 1 <= count <= n - 2 (use the dense method)'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        ncv = min(n, max(2 * count + 1, min_basis))
        lworkl = 3 * ncv**2 + 6 * ncv
        allocate (resid(n), v(n, ncv), workd(3 * n), workl(lworkl), workev(3 * ncv), &
                  z(n, count + 1), dr(count + 1), di(count + 1), x(n), y(n), select(ncv), &
                  stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'ARPACK workspace', int(n, i8) * (ncv + count + 6), 8)
            return
        end if
        call solver%init(mass, jac, status)
        if (status%ok()) call solver%factor_real(sigma, mass, jac, status)
        if (.not. status%ok()) then
            write (msg, '(a,es10.3,a)') 'ARPACK: the shift sigma = ', sigma, ': sigma M - J &
                &cannot be factored (sigma an eigenvalue? choose another shift): '
            status%message = trim(msg) // status%message
            return
        end if

        ! A fixed, non-symmetric start, then purified: resid = OP² r.
        do k = 1, n
            x(k) = 1.0_wp + 0.5_wp * sin(real(k, wp))
        end do
        call apply_op(x, y)
        call apply_op(y, resid)
        nop = 2
        arpack_tol = 0.0_wp
        if (present(tol)) arpack_tol = tol
        iparam = 0
        iparam(1) = 1                       ! exact shifts
        iparam(3) = default_max_restarts
        if (present(max_restarts)) iparam(3) = max_restarts
        iparam(7) = 1                       ! regular mode: OP is ours
        ido = 0
        info = 1                            ! resid holds the start
        do
            call dnaupd_quiet()
            if (ido /= -1 .and. ido /= 1) exit
            x = workd(ipntr(1):ipntr(1) + n - 1)
            call apply_op(x, y)
            workd(ipntr(2):ipntr(2) + n - 1) = y
            nop = nop + 1
        end do
        if (present(restarts)) restarts = iparam(3)
        if (present(operations)) operations = nop
        if (info /= 0 .and. info /= 1) then
            write (msg, '(a,i0,a)') 'ARPACK dnaupd failed (info = ', info, &
                '; ARPACK Users'' Guide, dnaupd.f)'
            call status%set(status_solver_failure, trim(msg))
            return
        end if
        nconv = iparam(5)
        if (nconv < 1) then
            write (msg, '(a,i0,a)') 'ARPACK converged on no eigenvalue in ', iparam(3), &
                ' restarts (another shift, or the dense method)'
            call status%set(status_solver_failure, trim(msg))
            return
        end if
        call dneupd_quiet()
        if (info /= 0) then
            write (msg, '(a,i0,a)') 'ARPACK dneupd failed (info = ', info, &
                '; ARPACK Users'' Guide, dneupd.f)'
            call status%set(status_solver_failure, trim(msg))
            return
        end if
        nconv = min(iparam(5), count + 1)
        call ritz_to_pencil(dr(1:nconv), di(1:nconv), sigma, lambda)

    contains

        !> y = OP x = (J − σM)⁻¹ M x = −(σM − J)⁻¹ M x.
        subroutine apply_op(xin, yout)
            real(wp), intent(in) :: xin(:)
            real(wp), intent(out) :: yout(:)
            call mass%matvec(xin, yout)
            call solver%solve_real(yout)
            yout = -yout
        end subroutine apply_op

        !> ARPACK's own LAPACK calls probe the arithmetic (dlamch, IEEECK):
        !> they keep the IEEE flags as they were (linalg/lapack).
        subroutine dnaupd_quiet()
            type(ieee_status_type) :: saved
            call ieee_get_status(saved)
            call dnaupd(ido, 'I', n, 'LM', count, arpack_tol, resid, ncv, v, n, iparam, ipntr, &
                        workd, workl, lworkl, info)
            call ieee_set_status(saved)
        end subroutine dnaupd_quiet

        subroutine dneupd_quiet()
            type(ieee_status_type) :: saved
            call ieee_get_status(saved)
            call dneupd(.false., 'A', select, dr, di, z, n, 0.0_wp, 0.0_wp, workev, 'I', n, &
                        'LM', count, arpack_tol, resid, ncv, v, n, iparam, ipntr, workd, &
                        workl, lworkl, info)
            call ieee_set_status(saved)
        end subroutine dneupd_quiet
    end subroutine shift_invert_eigenvalues

    !> λ = σ + 1/ν for the Ritz values ν = dr + i di, nearest σ (largest |ν|)
    !> first; ν = 0 (an infinite λ, which 'LM' should never return) is dropped.
    subroutine ritz_to_pencil(dr, di, sigma, lambda)
        real(wp), intent(in) :: dr(:), di(:), sigma
        complex(wp), allocatable, intent(out) :: lambda(:)
        complex(wp), allocatable :: nu(:)
        integer, allocatable :: order(:)
        integer :: i, j, m
        nu = cmplx(dr, di, kind=wp)
        nu = pack(nu, abs(nu) > 0.0_wp)
        m = size(nu)
        ! insertion sort by decreasing |ν| (m is small)
        order = [(i, i=1, m)]
        do i = 2, m
            j = i
            do while (j > 1)
                if (abs(nu(order(j - 1))) >= abs(nu(order(j)))) exit
                order([j - 1, j]) = order([j, j - 1])
                j = j - 1
            end do
        end do
        allocate (lambda(m))
        do i = 1, m
            lambda(i) = sigma + 1.0_wp / nu(order(i))
        end do
    end subroutine ritz_to_pencil
end module flexmbs_linalg_arpack
