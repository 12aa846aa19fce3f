!> Test-only reference integrator for small stiff ODEs y' = f(t, y), written
!> to confirm tight references by a method independent of RADAU5: a stiffly
!> accurate, L-stable implicit Runge–Kutta method (Lobatto IIIC, 3 stages,
!> order 4; or Radau IIA, 2 stages, order 3 [HW96, IV.5]) whose stage system
!> is solved by full Newton with the exact Jacobian at every iteration, and
!> step-size control by step doubling (Richardson extrapolation [HNW93, II.4]).
!> Dense linear algebra of its own; meant for n ≤ ~10.
!> [HW96] Hairer, Wanner, Solving ODEs II, 2nd ed.; [HNW93] Hairer, Nørsett,
!> Wanner, Solving ODEs I, 2nd ed.
module reference_integrator
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> An ODE y' = f(t, y) with its Jacobian; extend it to carry data.
    type, abstract, public :: reference_ode_t
    contains
        procedure(rhs_i), deferred :: rhs
        procedure(jacobian_i), deferred :: jacobian
    end type reference_ode_t

    abstract interface
        !> f = f(t, y).
        subroutine rhs_i(self, t, y, f)
            import :: reference_ode_t, wp
            class(reference_ode_t), intent(in) :: self
            real(wp), intent(in) :: t      !! time
            real(wp), intent(in) :: y(:)   !! state, size n
            real(wp), intent(out) :: f(:)  !! y', size n
        end subroutine rhs_i

        !> dfdy = ∂f/∂y (t, y), exact.
        subroutine jacobian_i(self, t, y, dfdy)
            import :: reference_ode_t, wp
            class(reference_ode_t), intent(in) :: self
            real(wp), intent(in) :: t            !! time
            real(wp), intent(in) :: y(:)         !! state, size n
            real(wp), intent(out) :: dfdy(:, :)  !! n x n, dfdy(i, j) = ∂f_i/∂y_j
        end subroutine jacobian_i
    end interface

    !> Method choices.
    integer, parameter, public :: lobatto_iiic_3 = 1  !! 3 stages, order 4
    integer, parameter, public :: radau_iia_2 = 2     !! 2 stages, order 3

    integer, parameter :: max_stages = 3

    !> A stiffly accurate tableau: b = last row of a, y1 = y0 + Z_s.
    type :: tableau_t
        integer :: s = 0, p = 0
        real(wp) :: a(max_stages, max_stages) = 0.0_wp
        real(wp) :: c(max_stages) = 0.0_wp
    end type tableau_t

    ! Newton: stop when max |ΔZ| / scale ≤ newton_tol (scale = |y| + atol/rtol);
    ! once the updates stop shrinking they are round-off, accepted below
    ! newton_floor.
    real(wp), parameter :: newton_tol = 1.0e-15_wp
    real(wp), parameter :: newton_floor = 1.0e-13_wp
    integer, parameter :: newton_max_iter = 12
    ! Step-size controller.
    real(wp), parameter :: safety = 0.9_wp
    real(wp), parameter :: fac_min = 0.2_wp, fac_max = 4.0_wp
    real(wp), parameter :: fac_newton_failure = 0.25_wp
    real(wp), parameter :: stretch = 0.01_wp
    integer, parameter :: max_steps = 1000000

    !> Newton workspace, allocated once per integration.
    type :: workspace_t
        real(wp), allocatable :: z(:, :)      !! stage increments Z_i, n x s
        real(wp), allocatable :: f(:, :)      !! f at the stages, n x s
        real(wp), allocatable :: jac(:, :, :) !! ∂f/∂y at the stages, n x n x s
        real(wp), allocatable :: m(:, :)      !! Newton matrix, ns x ns, then its LU
        real(wp), allocatable :: dz(:)        !! residual, then Newton update, ns
        real(wp), allocatable :: ys(:)        !! a stage value y + Z_j, n
        integer, allocatable :: piv(:)        !! pivots, ns
    end type workspace_t

    public :: integrate_reference, integrate_fixed, reference_order

contains

    !> Order of a method.
    integer function reference_order(method)
        integer, intent(in) :: method  !! lobatto_iiic_3 or radau_iia_2
        type(tableau_t) :: tab
        tab = tableau(method)
        reference_order = tab%p
    end function reference_order

    !> Integrate from t to t_end with step doubling: each step of h is
    !> compared with two steps of h/2; (y_h/2 − y_h)/(2^p − 1) estimates the
    !> error of y_h/2, which is kept when its weighted RMS norm
    !> (weights atol + rtol·|y|, larger |y| of both step ends) is ≤ 1. The
    !> error per step is controlled, so the global error scales like
    !> tol^(p/(p+1)).
    subroutine integrate_reference(ode, t, y, t_end, rtol, atol, nsteps, ok, method, h0, &
                                   nrejected)
        class(reference_ode_t), intent(in) :: ode
        real(wp), intent(inout) :: t                !! start time; t_end on success
        real(wp), intent(inout) :: y(:)             !! initial value; y(t) on return
        real(wp), intent(in) :: t_end               !! end time (> t or < t)
        real(wp), intent(in) :: rtol, atol          !! tolerances (> 0)
        integer, intent(out) :: nsteps              !! accepted steps
        logical, intent(out) :: ok                  !! .false.: step too small or too many
        integer, intent(in), optional :: method     !! default lobatto_iiic_3
        real(wp), intent(in), optional :: h0        !! first step (default 1e-6 |t_end − t|)
        integer, intent(out), optional :: nrejected !! rejected steps (error or Newton)
        type(tableau_t) :: tab
        real(wp) :: y_full(size(y)), y_mid(size(y)), y_half(size(y)), err(size(y))
        real(wp) :: scale(size(y)), h, err_norm, fac, fac_limit, direction
        type(workspace_t) :: work
        integer :: n, nrej
        logical :: converged, last

        nsteps = 0
        nrej = 0
        ok = .false.
        if (present(nrejected)) nrejected = 0
        tab = tableau(method_or_default(method))
        if (tab%s == 0 .or. .not. (rtol > 0.0_wp .and. atol > 0.0_wp)) return
        n = size(y)
        call allocate_workspace(work, n, tab%s)
        direction = sign(1.0_wp, t_end - t)
        h = 1.0e-6_wp * abs(t_end - t)
        if (present(h0)) h = abs(h0)
        fac_limit = fac_max
        do while (abs(t_end - t) > 0.0_wp)
            if (nsteps + nrej >= max_steps) exit
            if (h < 10.0_wp * epsilon(1.0_wp) * max(abs(t), abs(t_end))) exit
            ! stretch by up to 1% rather than leave a sliver before t_end
            last = (1.0_wp + stretch) * h >= abs(t_end - t)
            if (last) h = abs(t_end - t)
            scale = abs(y) + atol / rtol
            call irk_step(ode, tab, t, y, direction * h, scale, y_full, converged, work)
            if (converged) call irk_step(ode, tab, t, y, direction * 0.5_wp * h, scale, &
                y_mid, converged, work)
            if (converged) call irk_step(ode, tab, t + direction * 0.5_wp * h, y_mid, &
                direction * 0.5_wp * h, scale, y_half, converged, work)
            if (.not. converged) then
                nrej = nrej + 1
                h = fac_newton_failure * h
                fac_limit = 1.0_wp
                cycle
            end if
            err = (y_half - y_full) / real(2**tab%p - 1, wp)
            err_norm = sqrt(sum((err / (atol + rtol * max(abs(y), abs(y_half))))**2) / n)
            if (.not. ieee_is_finite(err_norm)) then
                nrej = nrej + 1
                h = fac_newton_failure * h
                fac_limit = 1.0_wp
                cycle
            end if
            fac = min(fac_limit, max(fac_min, &
                safety * max(err_norm, tiny(1.0_wp))**(-1.0_wp / (tab%p + 1))))
            if (err_norm <= 1.0_wp) then
                nsteps = nsteps + 1
                y = y_half
                if (last) then
                    t = t_end
                else
                    t = t + direction * h
                end if
                fac_limit = fac_max
            else
                nrej = nrej + 1
                fac_limit = 1.0_wp   ! no growth right after a rejection
            end if
            h = fac * h
        end do
        ok = abs(t_end - t) == 0.0_wp
        if (present(nrejected)) nrejected = nrej
    end subroutine integrate_reference

    !> nsteps equal steps of the basic method, no error control (for orders).
    subroutine integrate_fixed(ode, t, y, t_end, nsteps, ok, method)
        class(reference_ode_t), intent(in) :: ode
        real(wp), intent(inout) :: t             !! start time; t_end on success
        real(wp), intent(inout) :: y(:)          !! initial value; y(t) on return
        real(wp), intent(in) :: t_end            !! end time
        integer, intent(in) :: nsteps            !! number of steps (≥ 1)
        logical, intent(out) :: ok               !! .false.: Newton failed
        integer, intent(in), optional :: method  !! default lobatto_iiic_3
        type(tableau_t) :: tab
        type(workspace_t) :: work
        real(wp) :: y_new(size(y)), h, t0
        integer :: k
        ok = .false.
        tab = tableau(method_or_default(method))
        if (tab%s == 0 .or. nsteps < 1) return
        call allocate_workspace(work, size(y), tab%s)
        t0 = t
        h = (t_end - t0) / nsteps
        do k = 1, nsteps
            call irk_step(ode, tab, t, y, h, abs(y) + 1.0_wp, y_new, ok, work)
            if (.not. ok) return
            y = y_new
            t = t0 + k * h
        end do
        t = t_end
    end subroutine integrate_fixed

    !> One step of the implicit RK method: solve the stage equations
    !>   Z_i = h Σ_j a_ij f(t + c_j h, y + Z_j),  i = 1..s,
    !> by full Newton on the stacked system (matrix δ_ij I − h a_ij J_j, every
    !> J_j re-evaluated at the current iterate), start Z = 0; y1 = y + Z_s.
    subroutine irk_step(ode, tab, t, y, h, scale, y1, converged, work)
        class(reference_ode_t), intent(in) :: ode
        type(tableau_t), intent(in) :: tab
        real(wp), intent(in) :: t, y(:), h
        real(wp), intent(in) :: scale(:)     !! Newton converges when max |ΔZ|/scale ≤ tol
        real(wp), intent(out) :: y1(:)
        logical, intent(out) :: converged
        type(workspace_t), intent(inout) :: work
        real(wp) :: norm, norm_old
        integer :: n, i, j, k, iter, row, col
        logical :: regular
        n = size(y)
        associate (z => work%z, f => work%f, jac => work%jac, m => work%m, dz => work%dz, &
                   ys => work%ys, piv => work%piv)
        z = 0.0_wp
        norm_old = huge(1.0_wp)
        converged = .false.
        do iter = 1, newton_max_iter
            do j = 1, tab%s
                ys = y + z(:, j)
                call ode%rhs(t + tab%c(j) * h, ys, f(:, j))
                call ode%jacobian(t + tab%c(j) * h, ys, jac(:, :, j))
            end do
            do i = 1, tab%s
                row = (i - 1) * n
                ! right-hand side: −(Z_i − h Σ_j a_ij F_j)
                dz(row + 1:row + n) = -z(:, i)
                do j = 1, tab%s
                    col = (j - 1) * n
                    dz(row + 1:row + n) = dz(row + 1:row + n) + h * tab%a(i, j) * f(:, j)
                    m(row + 1:row + n, col + 1:col + n) = -h * tab%a(i, j) * jac(:, :, j)
                    if (i == j) then
                        do k = 1, n
                            m(row + k, col + k) = m(row + k, col + k) + 1.0_wp
                        end do
                    end if
                end do
            end do
            call lu_factor(m, piv, regular)
            if (.not. regular) return
            call lu_solve(m, piv, dz)
            do i = 1, tab%s
                z(:, i) = z(:, i) + dz((i - 1) * n + 1:i * n)
            end do
            norm = 0.0_wp
            do i = 1, tab%s
                norm = max(norm, maxval(abs(dz((i - 1) * n + 1:i * n)) / scale))
            end do
            if (.not. ieee_is_finite(norm)) return
            if (norm <= newton_tol) then
                converged = .true.
                exit
            end if
            ! Full Newton converges quadratically: updates that stop shrinking
            ! are round-off (accept if small) or divergence (give up).
            if (iter >= 3 .and. norm >= 0.5_wp * norm_old) then
                converged = norm <= newton_floor
                exit
            end if
            norm_old = norm
        end do
        if (converged) y1 = y + z(:, tab%s)
        end associate
    end subroutine irk_step

    subroutine allocate_workspace(work, n, s)
        type(workspace_t), intent(out) :: work
        integer, intent(in) :: n, s
        allocate (work%z(n, s), work%f(n, s), work%jac(n, n, s), work%m(n * s, n * s), &
            work%dz(n * s), work%ys(n), work%piv(n * s))
    end subroutine allocate_workspace

    !> Gaussian elimination with partial pivoting, in place (a = P L U).
    subroutine lu_factor(a, piv, regular)
        real(wp), intent(inout) :: a(:, :)
        integer, intent(out) :: piv(:)
        logical, intent(out) :: regular
        integer :: n, k, p, j
        real(wp) :: tmp
        n = size(a, 1)
        regular = .false.
        do k = 1, n
            p = k - 1 + maxloc(abs(a(k:n, k)), dim=1)
            piv(k) = p
            if (a(p, k) == 0.0_wp) return
            do j = 1, n
                tmp = a(k, j)
                a(k, j) = a(p, j)
                a(p, j) = tmp
            end do
            a(k + 1:n, k) = a(k + 1:n, k) / a(k, k)
            do j = k + 1, n
                a(k + 1:n, j) = a(k + 1:n, j) - a(k + 1:n, k) * a(k, j)
            end do
        end do
        regular = .true.
    end subroutine lu_factor

    !> Solve (P L U) x = b with the factors of lu_factor; b is overwritten by x.
    subroutine lu_solve(a, piv, b)
        real(wp), intent(in) :: a(:, :)
        integer, intent(in) :: piv(:)
        real(wp), intent(inout) :: b(:)
        integer :: n, k
        real(wp) :: tmp
        n = size(a, 1)
        ! lu_factor swapped whole rows, L included: permute b first.
        do k = 1, n
            tmp = b(k)
            b(k) = b(piv(k))
            b(piv(k)) = tmp
        end do
        do k = 1, n
            b(k + 1:n) = b(k + 1:n) - a(k + 1:n, k) * b(k)
        end do
        do k = n, 1, -1
            b(k) = b(k) / a(k, k)
            b(1:k - 1) = b(1:k - 1) - a(1:k - 1, k) * b(k)
        end do
    end subroutine lu_solve

    integer function method_or_default(method)
        integer, intent(in), optional :: method
        method_or_default = lobatto_iiic_3
        if (present(method)) method_or_default = method
    end function method_or_default

    !> Butcher tableaux [HW96, IV.5]; an unknown method
    !> gives s = 0 (no stages).
    function tableau(method) result(tab)
        integer, intent(in) :: method
        type(tableau_t) :: tab
        select case (method)
        case (lobatto_iiic_3)
            tab%s = 3
            tab%p = 4
            tab%c(1:3) = [0.0_wp, 0.5_wp, 1.0_wp]
            tab%a(1, 1:3) = [1.0_wp, -2.0_wp, 1.0_wp] / 6.0_wp
            tab%a(2, 1:3) = [2.0_wp, 5.0_wp, -1.0_wp] / 12.0_wp
            tab%a(3, 1:3) = [1.0_wp, 4.0_wp, 1.0_wp] / 6.0_wp
        case (radau_iia_2)
            tab%s = 2
            tab%p = 3
            tab%c(1:2) = [1.0_wp / 3.0_wp, 1.0_wp]
            tab%a(1, 1:2) = [5.0_wp, -1.0_wp] / 12.0_wp
            tab%a(2, 1:2) = [3.0_wp, 1.0_wp] / 4.0_wp
        end select
    end function tableau
end module reference_integrator
