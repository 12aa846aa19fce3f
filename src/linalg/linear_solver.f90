!> Abstract linear solver for shifted iteration matrices A = c*M - J.
!>
!> Implicit DAE solvers factor c*M - J with a real shift (RADAU5's E1,
!> DDASSL's PD) and with a complex shift (RADAU5's E2); both factorisations
!> stay alive together. `init` sees the storage and pattern of M and J once;
!> afterwards only values change.
module flexmbs_linalg_linear_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
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
    !> n = 1e2..1e5 (docs/benchmarks.md).
    integer, parameter, public :: auto_sparse_threshold = 20

    !> For `linear_solver = 'auto'` with a sparse J of order n >=
    !> auto_sparse_threshold: MUMPS (multifrontal) instead of KLU when
    !> n >= auto_mumps_min_order and KLU's symbolic analysis (AMD) predicts
    !> fill (nnz(L) + nnz(U)) / nnz(A) >= auto_mumps_min_fill, A the union
    !> pattern of c*M - J. `flexmbs-bench sparse_lu` (1 BLAS thread, 2 cores),
    !> time of KLU's refactor (old pivot order, what an integrator pays) /
    !> MUMPS's numerical factorisation, with the predicted fill:
    !> hex8 node graphs (3 dofs/node): 3³ nodes (n = 81, fill 1.2) 0.35,
    !> 5³ (375, 2.4) 1.0, 6³ (648, 3.0) 1.7, 8³ (1536, 4.7) 3.1; slender
    !> 2×2×400 (4800, 1.0) 0.35, 3×3×192 (5184, 1.7) 0.7, 4×4×100 (4800, 2.7)
    !> 1.5, 6×6×200 (21600, 5.0) 2.6; 2-D Brusselator rd2d 15 (450, 7.4) 0.6,
    !> 22 (968, 9.0) 0.96, 30 (1800, 12.5) 1.8, 71 (10082, 17.8) 5.1; 1-D
    !> Brusselator (fill 1.5) 0.1 at n = 1e3 and 1e4. On those matrices MUMPS
    !> wins from a fill of about 2.5; below n ~ 1000 its solves (2-10 x slower
    !> than KLU's there) eat the gain.
    !> The formulations' iteration matrices are not node graphs: q and v (and
    !> a) of every node are unknowns of their own, which KLU's left-looking LU
    !> eliminates almost for free while MUMPS carries them into its fronts.
    !> Whole RADAU5 runs (release, 1 BLAS thread; CPU KLU / MUMPS, with the
    !> predicted fill): the five-body scene with its coupler meshed 4×8×4
    !> (n = 2167, fill 4.0) 0.53, 6×12×6 (5875, 5.5) 0.29, 5×20×5 (6946, 5.2)
    !> 0.31, 8×16×8 (12535, 7.9) 0.40; a bulky 12×12×12 hex8 cube clamped on
    !> one face (12168, 12.8) 4.0. Hence MUMPS from a predicted fill of 10:
    !> bulky 3-D meshes get it, slender and moderately refined bodies keep KLU.
    integer, parameter, public :: auto_mumps_min_order = 1000
    real(wp), parameter, public :: auto_mumps_min_fill = 10.0_wp

    !> Every value of `linear_solver`, and the same as text for messages.
    character(len=5), parameter, public :: linear_solver_names(5) = &
        [character(len=5) :: 'auto', 'dense', 'klu', 'band', 'mumps']
    character(len=*), parameter, public :: linear_solver_names_text = &
        "'auto', 'dense', 'klu', 'band' or 'mumps'"

    !> Overwrite a right-hand side with NaN: what a solver's `solve` returns
    !> without a valid factorisation, so that the failure cannot pass unseen.
    interface fill_nan
        module procedure fill_nan_real, fill_nan_complex
    end interface fill_nan
    public :: fill_nan

    !> A solver of A = c M − J for real and complex shifts c (see the module):
    !> its order n and the deferred init, factor, solve and name bindings.
    type, abstract, public :: linear_solver_t
        integer :: n = 0
    contains
        procedure(init_i), deferred :: init
        procedure(factor_real_i), deferred :: factor_real
        procedure(factor_complex_i), deferred :: factor_complex
        procedure(solve_real_i), deferred :: solve_real
        procedure(solve_complex_i), deferred :: solve_complex
        procedure(name_i), deferred :: name
        procedure :: ordering_used => linear_solver_ordering
        procedure :: description => linear_solver_description
        procedure :: report => linear_solver_report
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
        !> 'dense', 'klu', 'band' or 'mumps'.
        function name_i(self) result(name)
            import :: linear_solver_t
            class(linear_solver_t), intent(in) :: self
            character(len=:), allocatable :: name
        end function name_i
    end interface

contains

    !> The fill-reducing ordering of a sparse factorisation once analysed
    !> ('amd', 'nd', 'scotch', ...); empty for solvers without one.
    function linear_solver_ordering(self) result(name)
        class(linear_solver_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = ''
    end function linear_solver_ordering

    !> What factors the matrices, as runs report it: the name, and the
    !> ordering when there is one ('condensed mumps, ordering scotch').
    function linear_solver_description(self) result(text)
        class(linear_solver_t), intent(in) :: self
        character(len=:), allocatable :: text, order
        text = self%name()
        order = self%ordering_used()
        if (len(order) > 0) text = text // ', ordering ' // order
    end function linear_solver_description

    !> What the factorisations cost, where the solver counts it (MUMPS:
    !> processes, time per factorisation, memory), for --verbose
    !> statistics; '' by default.
    function linear_solver_report(self) result(text)
        class(linear_solver_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = ''
    end function linear_solver_report

    subroutine fill_nan_real(b)
        real(wp), intent(out) :: b(:)
        b = ieee_value(1.0_wp, ieee_quiet_nan)
    end subroutine fill_nan_real

    subroutine fill_nan_complex(b)
        complex(wp), intent(out) :: b(:)
        b = cmplx(ieee_value(1.0_wp, ieee_quiet_nan), ieee_value(1.0_wp, ieee_quiet_nan), &
            kind=wp)
    end subroutine fill_nan_complex
end module flexmbs_linalg_linear_solver
