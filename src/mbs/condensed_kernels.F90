!> The arithmetic of the condensed Newton systems (docs/theory.md §3.7), in
!> real numbers for RADAU5's real and DDASSL's and IDA's matrices and in
!> complex numbers for RADAU5's complex one: one body (condensed_kernels.inc)
!> for both. Every array is the caller's: nothing is allocated here.
module flexmbs_mbs_condensed_kernels
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_singular_matrix
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs, zgetrf, zgetrs, dgemm, zgemm
    use flexmbs_linalg_sparse_lu, only: sparse_lu_t
    use flexmbs_mbs_condensed_structure, only: condensed_structure_t
    implicit none
    private

    public :: factor_blocks, w_values, s_values, condensed_solve

    !> The dense LUs of c I − J_ee of the kinematic blocks, real or complex c.
    interface factor_blocks
        module procedure factor_blocks_real, factor_blocks_complex
    end interface factor_blocks
    !> The values of W = P J_EK, real or complex.
    interface w_values
        module procedure w_values_real, w_values_complex
    end interface w_values
    !> The values of the Schur complement S on its pattern, real or complex.
    interface s_values
        module procedure s_values_real, s_values_complex
    end interface s_values
    !> b ← A⁻¹ b through the block LUs and the factorised S, real or complex.
    interface condensed_solve
        module procedure solve_real, solve_complex
    end interface condensed_solve

contains

#define SCALAR real(wp)
#define GETRF dgetrf
#define GETRS dgetrs
#define GEMM dgemm
#define FACTOR_BLOCKS_P factor_blocks_real
#define W_VALUES_P w_values_real
#define S_VALUES_P s_values_real
#define APPLY_P_P apply_p_real
#define SOLVE_P solve_real
#include "condensed_kernels.inc"
#undef SCALAR
#undef GETRF
#undef GETRS
#undef GEMM
#undef FACTOR_BLOCKS_P
#undef W_VALUES_P
#undef S_VALUES_P
#undef APPLY_P_P
#undef SOLVE_P
#define SCALAR complex(wp)
#define GETRF zgetrf
#define GETRS zgetrs
#define GEMM zgemm
#define FACTOR_BLOCKS_P factor_blocks_complex
#define W_VALUES_P w_values_complex
#define S_VALUES_P s_values_complex
#define APPLY_P_P apply_p_complex
#define SOLVE_P solve_complex
#include "condensed_kernels.inc"
end module flexmbs_mbs_condensed_kernels
