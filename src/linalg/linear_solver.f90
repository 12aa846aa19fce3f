!> Abstract linear solver for shifted iteration matrices A = c*M - J.
!>
!> Implicit DAE solvers factor c*M - J with a real shift (RADAU5's E1,
!> DDASSL's PD) and with a complex shift (RADAU5's E2); both factorisations
!> stay alive together. `init` sees the storage and pattern of M and J once;
!> afterwards only values change.
module flexmbs_linalg_linear_solver
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_linalg_matrix, only: matrix_t
    implicit none
    private

    !> Dense below this order, KLU from it on (when J is sparse), for
    !> `linear_solver = 'auto'`. `make bench` (RADAU5, OpenBLAS, 2 cores):
    !> CPU per step dense/KLU on the 1-D Brusselator is 1.3 at n = 10, 3.5 at
    !> 20, 5.3 at 60, 18 at 100, 256 at 1000; below ~20 the two are equal
    !> within noise and dense is the more robust choice. Band LU is never
    !> chosen: on the same banded problem it is 10-20 % slower than KLU at
    !> n = 1e2..1e5 (README, Benchmarks).
    integer, parameter, public :: auto_sparse_threshold = 20

    type, abstract, public :: linear_solver_t
        integer :: n = 0
    contains
        procedure(init_i), deferred :: init
        procedure(factor_real_i), deferred :: factor_real
        procedure(factor_complex_i), deferred :: factor_complex
        procedure(solve_real_i), deferred :: solve_real
        procedure(solve_complex_i), deferred :: solve_complex
        procedure(name_i), deferred :: name
    end type linear_solver_t

    abstract interface
        !> Prepare for matrices with the storage and pattern of `mass` and `jac`.
        subroutine init_i(self, mass, jac, status)
            import :: linear_solver_t, matrix_t, status_t
            class(linear_solver_t), intent(inout) :: self
            type(matrix_t), intent(in) :: mass, jac
            type(status_t), intent(out) :: status
        end subroutine init_i
        !> Factor A = c*M - J; a singular A is reported in `status`.
        subroutine factor_real_i(self, c, mass, jac, status)
            import :: linear_solver_t, matrix_t, status_t, wp
            class(linear_solver_t), intent(inout) :: self
            real(wp), intent(in) :: c
            type(matrix_t), intent(in) :: mass, jac
            type(status_t), intent(out) :: status
        end subroutine factor_real_i
        !> Factor A = c*M - J with a complex shift c.
        subroutine factor_complex_i(self, c, mass, jac, status)
            import :: linear_solver_t, matrix_t, status_t, wp
            class(linear_solver_t), intent(inout) :: self
            complex(wp), intent(in) :: c
            type(matrix_t), intent(in) :: mass, jac
            type(status_t), intent(out) :: status
        end subroutine factor_complex_i
        !> Overwrite b with A⁻¹ b using the real factorisation.
        subroutine solve_real_i(self, b)
            import :: linear_solver_t, wp
            class(linear_solver_t), intent(inout) :: self
            real(wp), intent(inout) :: b(:)
        end subroutine solve_real_i
        !> Overwrite b with A⁻¹ b using the complex factorisation.
        subroutine solve_complex_i(self, b)
            import :: linear_solver_t, wp
            class(linear_solver_t), intent(inout) :: self
            complex(wp), intent(inout) :: b(:)
        end subroutine solve_complex_i
        !> 'dense', 'klu' or 'band'.
        function name_i(self) result(name)
            import :: linear_solver_t
            class(linear_solver_t), intent(in) :: self
            character(len=:), allocatable :: name
        end function name_i
    end interface
end module flexmbs_linalg_linear_solver
