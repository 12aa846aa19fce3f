!> The Brusselator with diffusion: a large, sparse, stiff ODE y' = F(y) of
!> adjustable size (M = I), for the sparse linear-algebra paths of the solvers.
!>
!> Reaction with constants A, B and diffusion α:
!>
!>   u' = A + u² v - (B + 1) u + α Δu,    v' = B u - u² v + α Δv.
!>
!> dim = 1 [HW96, IV.1]: N interior points x_i = i/(N+1), Dirichlet values
!>   u = 1, v = 3 at x = 0 and x = 1, A = 1, B = 3, α = 1/50,
!>   Δw_i = (N+1)² (w_{i-1} - 2 w_i + w_{i+1});
!>   u_i(0) = 1 + sin(2π x_i), v_i(0) = 3.
!> dim = 2 (after BRUSS-2D [HW96, IV.10], without its local source term so
!>   that F is smooth and autonomous): N x N points x_i = (i-1)/N,
!>   y_j = (j-1)/N on the unit square, periodic in x and y, A = 1, B = 3.4,
!>   α = 0.1, five-point Laplacian Δw = N² (w_E + w_W + w_N + w_S - 4 w);
!>   u(x, y, 0) = 22 y (1 - y)^{3/2}, v(x, y, 0) = 27 x (1 - x)^{3/2}.
!>
!> Unknowns are interleaved by grid point, y = (u_1, v_1, u_2, v_2, ...),
!> point p = i (1-D) or p = i + (j-1) N (2-D), so n = 2 N^dim and ∂F/∂y has
!> 2x2 blocks on the diagonal plus α Δ couplings of like species. The CSC
!> pattern is built once by the constructor; the values are refilled in place
!> through the stored triplet-to-slot map (duplicates, which appear on a
!> periodic grid with N <= 2, are summed). The dense Jacobian is meant for
!> small sizes.
module flexmbs_problems_reaction_diffusion
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_matrix, only: storage_dense, storage_sparse
    use flexmbs_dae_problem, only: dae_problem_t
    implicit none
    private

    real(wp), parameter :: pi = acos(-1.0_wp)
    ! 1-D constants and boundary values [HW96, IV.1]
    real(wp), parameter :: a_1d = 1.0_wp, b_1d = 3.0_wp, alpha_1d = 1.0_wp / 50.0_wp
    real(wp), parameter :: u_boundary_1d = 1.0_wp, v_boundary_1d = 3.0_wp
    ! 2-D constants of BRUSS-2D [HW96, IV.10]
    real(wp), parameter :: a_2d = 1.0_wp, b_2d = 3.4_wp, alpha_2d = 0.1_wp
    ! At most 4 neighbours of a grid point (2-D five-point stencil).
    integer, parameter :: max_neighbours = 4

    !> The Brusselator with diffusion on a 1-D or 2-D grid.
    type, extends(dae_problem_t), public :: reaction_diffusion_t
        integer :: dim = 1                 !! space dimension, 1 or 2
        integer :: npoints = 0             !! N, grid points per direction
        integer :: npts = 0                !! N^dim grid points
        real(wp) :: a = a_1d, b = b_1d     !! reaction constants A, B
        real(wp) :: alpha = alpha_1d       !! diffusion coefficient α
        real(wp) :: coupling = 0.0_wp      !! α / h², the Laplacian's off-diagonal weight
        real(wp) :: u_boundary = 0.0_wp    !! Dirichlet values (1-D only)
        real(wp) :: v_boundary = 0.0_wp
        logical :: sparse = .true.         !! report ∂F/∂y as CSC (dense otherwise)
        type(csc_matrix_t) :: pattern      !! the fixed Jacobian pattern
        integer(i8), allocatable :: slot(:) !! triplet k -> value slot (1-based)
    contains
        procedure :: rhs => rd_rhs
        procedure :: jacobian_storage => rd_jacobian_storage
        procedure :: jacobian_dense => rd_jacobian_dense
        procedure :: jacobian_pattern => rd_jacobian_pattern
        procedure :: jacobian_sparse => rd_jacobian_sparse
    end type reaction_diffusion_t

    public :: new_reaction_diffusion, reaction_diffusion_initial

contains

    !> The Brusselator on `npoints` (N) points per direction in `dim` (1 or 2)
    !> dimensions, n = 2 N^dim. `sparse` (default true) chooses CSC over dense
    !> Jacobian storage. On bad arguments `status` says why and n = 0.
    function new_reaction_diffusion(dim, npoints, sparse, status) result(problem)
        integer, intent(in) :: dim      !! 1 or 2
        integer, intent(in) :: npoints  !! N >= 1
        logical, intent(in), optional :: sparse
        type(status_t), intent(out), optional :: status
        type(reaction_diffusion_t) :: problem
        type(status_t) :: local
        character(len=120) :: msg

        if (present(sparse)) problem%sparse = sparse
        if (dim /= 1 .and. dim /= 2) then
            write (msg, '(a,i0,a)') 'reaction_diffusion: dim = ', dim, ': must be 1 or 2'
            call local%set(status_bad_input, trim(msg))
        else if (npoints < 1) then
            write (msg, '(a,i0,a)') 'reaction_diffusion: npoints = ', npoints, &
                ': must be at least 1'
            call local%set(status_bad_input, trim(msg))
        else if (12_i8 * int(npoints, i8)**dim > huge(1)) then
            ! 12 N^dim bounds the number of Jacobian triplets (default integers)
            write (msg, '(a,i0,a,i0,a)') 'reaction_diffusion: npoints = ', npoints, &
                ' in ', dim, '-D: too large, reduce it'
            call local%set(status_bad_input, trim(msg))
        end if
        if (local%ok()) then
            problem%dim = dim
            problem%npoints = npoints
            problem%npts = npoints**dim
            if (dim == 1) then
                problem%a = a_1d
                problem%b = b_1d
                problem%alpha = alpha_1d
                problem%coupling = alpha_1d * real(npoints + 1, wp)**2
                problem%u_boundary = u_boundary_1d
                problem%v_boundary = v_boundary_1d
            else
                problem%a = a_2d
                problem%b = b_2d
                problem%alpha = alpha_2d
                problem%coupling = alpha_2d * real(npoints, wp)**2
            end if
            call build_pattern(problem, local)
        end if
        if (local%ok()) problem%n = 2 * problem%npts
        if (present(status)) status = local
    end function new_reaction_diffusion

    !> Triplets in the order the Jacobian fills them: per point the 2x2
    !> block (column-major), then (u_p, u_nb), (v_p, v_nb) per neighbour.
    subroutine build_pattern(self, status)
        type(reaction_diffusion_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:)
        integer :: nb(max_neighbours), nnb, p, q, k, nt
        nt = 0
        do p = 1, self%npts
            call neighbours(self, p, nb, nnb)
            nt = nt + 4 + 2 * nnb
        end do
        allocate (rows(nt), cols(nt))
        k = 0
        do p = 1, self%npts
            rows(k + 1:k + 4) = [2 * p - 1, 2 * p, 2 * p - 1, 2 * p]
            cols(k + 1:k + 4) = [2 * p - 1, 2 * p - 1, 2 * p, 2 * p]
            k = k + 4
            call neighbours(self, p, nb, nnb)
            do q = 1, nnb
                rows(k + 1:k + 2) = [2 * p - 1, 2 * p]
                cols(k + 1:k + 2) = [2 * nb(q) - 1, 2 * nb(q)]
                k = k + 2
            end do
        end do
        call self%pattern%build(2 * self%npts, 2 * self%npts, rows, cols, status)
        if (status%ok()) self%slot = self%pattern%triplet_map
    end subroutine build_pattern

    !> Grid neighbours of point p: W, E (1-D: only those inside, the others are
    !> Dirichlet boundary values), then S, N in 2-D (periodic wrap-around).
    pure subroutine neighbours(self, p, nb, nnb)
        type(reaction_diffusion_t), intent(in) :: self
        integer, intent(in) :: p
        integer, intent(out) :: nb(max_neighbours), nnb
        integer :: i, j, n
        n = self%npoints
        nnb = 0
        nb = 0
        if (self%dim == 1) then
            if (p > 1) then
                nnb = nnb + 1
                nb(nnb) = p - 1
            end if
            if (p < n) then
                nnb = nnb + 1
                nb(nnb) = p + 1
            end if
        else
            i = modulo(p - 1, n) + 1
            j = (p - 1) / n + 1
            nb(1) = modulo(i - 2, n) + 1 + (j - 1) * n
            nb(2) = modulo(i, n) + 1 + (j - 1) * n
            nb(3) = i + modulo(j - 2, n) * n
            nb(4) = i + modulo(j, n) * n
            nnb = 4
        end if
    end subroutine neighbours

    !> Initial values of the module header.
    subroutine reaction_diffusion_initial(problem, y0)
        class(reaction_diffusion_t), intent(in) :: problem
        real(wp), intent(out) :: y0(:) !! size problem%n
        real(wp) :: x, yc
        integer :: p, i, j, n
        n = problem%npoints
        do p = 1, problem%npts
            if (problem%dim == 1) then
                x = real(p, wp) / real(n + 1, wp)
                y0(2 * p - 1) = 1.0_wp + sin(2.0_wp * pi * x)
                y0(2 * p) = 3.0_wp
            else
                i = modulo(p - 1, n) + 1
                j = (p - 1) / n + 1
                x = real(i - 1, wp) / real(n, wp)
                yc = real(j - 1, wp) / real(n, wp)
                y0(2 * p - 1) = 22.0_wp * yc * (1.0_wp - yc)**1.5_wp
                y0(2 * p) = 27.0_wp * x * (1.0_wp - x)**1.5_wp
            end if
        end do
    end subroutine reaction_diffusion_initial

    subroutine rd_rhs(self, t, y, f, status)
        class(reaction_diffusion_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        integer :: nb(max_neighbours), nnb, p, q, nmissing
        real(wp) :: u, v, lap_u, lap_v
        do p = 1, self%npts
            u = y(2 * p - 1)
            v = y(2 * p)
            call neighbours(self, p, nb, nnb)
            ! stencil: sum of the 2 dim neighbours minus 2 dim times the centre;
            ! neighbours outside the 1-D grid take the Dirichlet values
            nmissing = 2 * self%dim - nnb
            lap_u = nmissing * self%u_boundary - 2 * self%dim * u
            lap_v = nmissing * self%v_boundary - 2 * self%dim * v
            do q = 1, nnb
                lap_u = lap_u + y(2 * nb(q) - 1)
                lap_v = lap_v + y(2 * nb(q))
            end do
            f(2 * p - 1) = self%a + u**2 * v - (self%b + 1.0_wp) * u + self%coupling * lap_u
            f(2 * p) = self%b * u - u**2 * v + self%coupling * lap_v
        end do
    end subroutine rd_rhs

    !> The diagonal 2x2 block of ∂F/∂y at one point (reaction plus the
    !> Laplacian's centre weight), shared by the dense and sparse paths so
    !> that both produce identical numbers.
    pure subroutine point_block(self, u, v, duu, dvu, duv, dvv)
        class(reaction_diffusion_t), intent(in) :: self
        real(wp), intent(in) :: u, v
        real(wp), intent(out) :: duu, dvu, duv, dvv
        real(wp) :: centre
        centre = 2 * self%dim * self%coupling
        duu = 2.0_wp * u * v - (self%b + 1.0_wp) - centre
        dvu = self%b - 2.0_wp * u * v
        duv = u**2
        dvv = -u**2 - centre
    end subroutine point_block

    integer function rd_jacobian_storage(self)
        class(reaction_diffusion_t), intent(in) :: self
        rd_jacobian_storage = merge(storage_sparse, storage_dense, self%sparse)
    end function rd_jacobian_storage

    !> Dense ∂F/∂y (n x n; for small sizes). The grid couplings are written
    !> from the index arithmetic directly, independently of the sparse path.
    subroutine rd_jacobian_dense(self, t, y, jac, status)
        class(reaction_diffusion_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: jac(:, :)
        type(status_t), intent(inout) :: status
        integer :: p, i, j, n, nb(max_neighbours), nnb, q
        real(wp) :: c
        if (size(jac, 1) /= self%n .or. size(jac, 2) /= self%n) then
            call status%set(status_bad_input, 'reaction_diffusion: dense Jacobian array &
                &is not n x n')
            return
        end if
        jac = 0.0_wp
        n = self%npoints
        c = self%coupling
        do p = 1, self%npts
            call point_block(self, y(2 * p - 1), y(2 * p), jac(2 * p - 1, 2 * p - 1), &
                             jac(2 * p, 2 * p - 1), jac(2 * p - 1, 2 * p), jac(2 * p, 2 * p))
            ! neighbours in the order W, E, S, N as in the sparse path
            nnb = 0
            if (self%dim == 1) then
                if (p > 1) call add(p - 1)
                if (p < n) call add(p + 1)
            else
                i = modulo(p - 1, n) + 1
                j = (p - 1) / n + 1
                call add(merge(n, i - 1, i == 1) + (j - 1) * n)
                call add(merge(1, i + 1, i == n) + (j - 1) * n)
                call add(i + (merge(n, j - 1, j == 1) - 1) * n)
                call add(i + (merge(1, j + 1, j == n) - 1) * n)
            end if
            do q = 1, nnb
                jac(2 * p - 1, 2 * nb(q) - 1) = jac(2 * p - 1, 2 * nb(q) - 1) + c
                jac(2 * p, 2 * nb(q)) = jac(2 * p, 2 * nb(q)) + c
            end do
        end do
    contains
        subroutine add(point)
            integer, intent(in) :: point
            nnb = nnb + 1
            nb(nnb) = point
        end subroutine add
    end subroutine rd_jacobian_dense

    subroutine rd_jacobian_pattern(self, pattern, status)
        class(reaction_diffusion_t), intent(inout) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        type(status_t), intent(inout) :: status
        if (.not. self%pattern%is_built()) then
            call status%set(status_bad_input, 'reaction_diffusion: problem not constructed &
                &by new_reaction_diffusion')
            return
        end if
        pattern = self%pattern
    end subroutine rd_jacobian_pattern

    !> Values in the slots of the pattern, refilled in place (no allocation).
    subroutine rd_jacobian_sparse(self, t, y, values, status)
        class(reaction_diffusion_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: nb(max_neighbours), nnb, p, q
        integer(i8) :: k
        real(wp) :: duu, dvu, duv, dvv
        if (size(values, kind=i8) /= self%pattern%nnz) then
            call status%set(status_bad_input, 'reaction_diffusion: values array does not &
                &match the Jacobian pattern')
            return
        end if
        values = 0.0_wp
        k = 0
        do p = 1, self%npts
            call point_block(self, y(2 * p - 1), y(2 * p), duu, dvu, duv, dvv)
            call accumulate(duu)
            call accumulate(dvu)
            call accumulate(duv)
            call accumulate(dvv)
            call neighbours(self, p, nb, nnb)
            do q = 1, nnb
                call accumulate(self%coupling)
                call accumulate(self%coupling)
            end do
        end do
    contains
        subroutine accumulate(value)
            real(wp), intent(in) :: value
            k = k + 1
            values(self%slot(k)) = values(self%slot(k)) + value
        end subroutine accumulate
    end subroutine rd_jacobian_sparse
end module flexmbs_problems_reaction_diffusion
