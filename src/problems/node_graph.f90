!> Model sparse matrices on the node graph of a structured hex8 mesh, for
!> testing and timing sparse LU.
!>
!> nx × ny × nz nodes, `dofs` unknowns per node, each unknown coupled to
!> every unknown of the (up to) 27 nodes of the 3 × 3 × 3 block around its
!> node: the pattern of an assembled hex8 stiffness matrix. J has
!> deterministic unsymmetric values in [-1, 1] off the diagonal and a
!> negative diagonal that dominates its row (|J_ii| = row sum + 1), so that
!> c*M - J with the positive diagonal M of `node_graph_mass` is strictly
!> diagonally dominant for every shift c with Re(c) >= 0. 3-D blocks
!> (nx ≈ ny ≈ nz) fill heavily under LU; slender ones (nx, ny ≪ nz) do not.
module flexmbs_problems_node_graph
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse
    implicit none
    private

    public :: node_graph_jacobian, node_graph_mass

contains

    !> J on the node graph of nx × ny × nz nodes with `dofs` unknowns each
    !> (order n = nx ny nz dofs); `seed` varies the values, not the pattern.
    subroutine node_graph_jacobian(nx, ny, nz, dofs, jac, status, seed)
        integer, intent(in) :: nx, ny, nz, dofs
        type(matrix_t), intent(out) :: jac
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: seed
        integer, allocatable :: rows(:), cols(:)
        real(wp), allocatable :: values(:)
        real(wp) :: offsum
        integer :: n, s, i, j, k, a, b, di, dj, dk, row, col, diag
        integer(i8) :: nt

        if (min(nx, ny, nz, dofs) < 1) then
            call status%set(status_bad_input, 'node graph: nx, ny, nz and dofs must be positive')
            return
        end if
        s = 0
        if (present(seed)) s = seed
        n = nx * ny * nz * dofs
        allocate (rows(int(n, i8) * 27 * dofs), cols(int(n, i8) * 27 * dofs), &
            values(int(n, i8) * 27 * dofs))
        nt = 0
        do k = 1, nz
            do j = 1, ny
                do i = 1, nx
                    do a = 1, dofs
                        row = unknown(i, j, k, a)
                        offsum = 0.0_wp
                        diag = 0
                        do dk = max(k - 1, 1), min(k + 1, nz)
                            do dj = max(j - 1, 1), min(j + 1, ny)
                                do di = max(i - 1, 1), min(i + 1, nx)
                                    do b = 1, dofs
                                        col = unknown(di, dj, dk, b)
                                        nt = nt + 1
                                        rows(nt) = row
                                        cols(nt) = col
                                        if (col == row) then
                                            diag = int(nt)
                                        else
                                            values(nt) = pseudo_random(row, col, s)
                                            offsum = offsum + abs(values(nt))
                                        end if
                                    end do
                                end do
                            end do
                        end do
                        values(diag) = -(offsum + 1.0_wp)
                    end do
                end do
            end do
        end do
        jac%storage = storage_sparse
        jac%n = n
        call jac%csc%build(n, n, rows(1:nt), cols(1:nt), status)
        if (.not. status%ok()) return
        call jac%csc%fill(values(1:nt))

    contains

        pure integer function unknown(ii, jj, kk, dof)
            integer, intent(in) :: ii, jj, kk, dof
            unknown = (((kk - 1) * ny + (jj - 1)) * nx + (ii - 1)) * dofs + dof
        end function unknown
    end subroutine node_graph_jacobian

    !> A positive diagonal M of order n in sparse storage (values in [1, 2]).
    subroutine node_graph_mass(n, mass, status)
        integer, intent(in) :: n
        type(matrix_t), intent(out) :: mass
        type(status_t), intent(out) :: status
        integer :: i
        mass%storage = storage_sparse
        mass%n = n
        call mass%csc%build(n, n, [(i, i = 1, n)], [(i, i = 1, n)], status)
        if (.not. status%ok()) return
        call mass%csc%fill([(1.5_wp + 0.5_wp * pseudo_random(i, i, 1), i = 1, n)])
    end subroutine node_graph_mass

    !> A deterministic value in [-1, 1] for entry (i, j) and a seed.
    elemental real(wp) function pseudo_random(i, j, seed)
        integer, intent(in) :: i, j, seed
        pseudo_random = sin(real(i, wp) * 12.9898_wp + real(j, wp) * 78.233_wp &
            + real(seed, wp) * 37.719_wp)
    end function pseudo_random
end module flexmbs_problems_node_graph
