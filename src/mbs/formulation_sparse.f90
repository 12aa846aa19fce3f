!> The sparse form of a formulation's matrices (flexmbs_mbs_formulation):
!> ∂F/∂y and the DAE mass matrix as values on CSC patterns built once from
!> the mechanical problem's sparse derivative blocks (mechanical_patterns_t),
!> the saddle-point matrix [M Gᵀ; G 0] of the projection and the consistent
!> initial values, and the products with G and M that F needs.
!>
!> The blocks of ∂F/∂y are those of the dense Jacobian (formulation.f90's
!> header): the rows q' = T w take ∂(T w)/∂q and T, and for GGL the products
!> −T ∂(Gᵀμ)/∂q and −T Gᵀ (sparse products on fixed patterns); the force rows
!> take ∂f/∂q − ∂(Gᵀλ)/∂q (− ∂(M a)/∂q), ∂f/∂v, −M, −Gᵀ; the constraint rows
!> the derivatives of c, of G v + g_I, or of G a + γ, all of which share the
!> pattern of g_q in q and of G in v. Blocks that share a pattern are summed
!> before one scatter. No array of order n x n exists on this path.
!>
!> Index 1 in the constant-mass layout: its constraint rows hold
!> G M⁻¹ (∂f/∂q − ∂(Gᵀλ)/∂q), G M⁻¹ ∂f/∂v and −G M⁻¹ Gᵀ, dense over the q, v
!> and λ columns (nc rows, never n x n): Z = M⁻¹ Gᵀ by nc sparse solves with
!> the constant M (KLU, factored once), then Zᵀ times the sparse blocks.
module flexmbs_mbs_formulation_sparse
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_csc, only: csc_matrix_t, pattern_matvec, pattern_matvec_transpose
    use flexmbs_linalg_block_assembly, only: block_assembly_t, product_pattern, &
        product_values, transpose_pattern
    use flexmbs_linalg_saddle_point, only: saddle_point_t
    use flexmbs_linalg_structured_saddle, only: structured_saddle_t
    use flexmbs_linalg_klu, only: klu_factor_t
    use flexmbs_linalg_triplets, only: triplets_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t, mechanical_patterns_t
    implicit none
    private

    !> The layout of the formulation's y (offsets as in formulation_t).
    type, public :: sparse_layout_t
        integer :: form = 0            !! formulation_index1/2/3, formulation_ggl
        logical :: accelerations = .true.
        logical :: ggl = .false.
        integer :: n = 0, nq = 0, nv = 0, nc = 0
        integer :: oq = 0, ov = 0, oa = 0, ol = 0, om = 0
        real(wp) :: baumgarte_zeta = 0.0_wp, baumgarte_omega = 0.0_wp
    end type sparse_layout_t

    !> Patterns, maps and value workspaces of the sparse path.
    type, public :: sparse_formulation_t
        private
        type(sparse_layout_t) :: lay
        !> allocatable, as mbs_system_t%patterns: gfortran 12's finalization
        !> wrapper frees such a non-allocatable component only in part
        type(mechanical_patterns_t), allocatable :: pat
        type(block_assembly_t) :: jac, mass
        type(saddle_point_t) :: kkt
        !> [M Gᵀ; G 0] by the structure of M instead (use_structure: with the
        !> condensed Newton systems), set up at its first factorisation
        logical :: structured = .false.
        !> allocatable (gfortran 12's finalization wrapper frees a
        !> non-allocatable derived-type component only in part)
        type(structured_saddle_t), allocatable :: skkt
        ! block ids in jac
        integer :: id_tq = 0, id_t = 0, id_ggl_rq = 0, id_ggl_gt = 0
        integer :: id_va = 0, id_fq = 0, id_rq = 0, id_fv = 0, id_m = 0, id_gt = 0
        integer :: id_cq = 0, id_cv = 0, id_ca = 0, id_mq = 0
        ! block ids in mass
        integer :: id_mass_q = 0, id_mass_v = 0
        ! block values
        real(wp), allocatable :: t(:), tq(:), fq(:), fv(:), mq(:), m(:), g(:), gv(:)
        real(wp), allocatable :: cq(:), cq2(:), rq(:), m0(:)
        real(wp), allocatable :: wv(:), zc(:) !! a velocity-space vector, nc zeros
        ! GGL: T, ∂(Gᵀμ)/∂q, Gᵀ and the products T·∂(Gᵀμ)/∂q, T·Gᵀ
        type(csc_matrix_t) :: tmat, rmat, gtmat, trq, tgt
        integer(i8), allocatable :: gt_map(:)
        ! index 1, constant mass: M's LU, Z = M⁻¹ Gᵀ and the dense row blocks
        logical :: mass_rows = .false.
        type(klu_factor_t) :: mlu
        integer :: id_iq = 0, id_iv = 0, id_il = 0
        real(wp), allocatable :: zmat(:, :), wq(:, :), wvv(:, :), wl(:, :), f(:)
    contains
        procedure :: init => sparse_init
        procedure :: jacobian => sparse_jacobian
        procedure :: mass_matrix => sparse_mass_matrix
        procedure :: jacobian_pattern => sparse_jacobian_pattern
        procedure :: constraint_jacobian => sparse_constraint_jacobian
        procedure :: g_times => sparse_g_times
        procedure :: gt_times => sparse_gt_times
        procedure :: m_times => sparse_m_times
        procedure :: factor_kkt => sparse_factor_kkt
        procedure :: solve_kkt => sparse_solve_kkt
        procedure :: solve_mass => sparse_solve_mass
        procedure :: use_structure => sparse_use_structure
    end type sparse_formulation_t

    ! formulation codes (flexmbs_mbs_formulation's values)
    integer, parameter :: index1 = 1, index2 = 2, index3 = 3, ggl = 4

contains

    !> Patterns from the mechanical problem, the global patterns of ∂F/∂y and
    !> of the DAE mass matrix with their block maps, K's pattern.
    subroutine sparse_init(self, mech, lay, q_mass, status)
        class(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        type(sparse_layout_t), intent(in) :: lay
        real(wp), intent(in) :: q_mass(:) !! where the constant M is evaluated
        type(status_t), intent(inout) :: status
        integer :: rf, ios
        self%lay = lay
        if (.not. allocated(self%pat)) allocate (self%pat)
        call mech%derivative_patterns(self%pat, status)
        if (.not. status%ok()) return
        associate (p => self%pat, j => self%jac, oq => lay%oq, ov => lay%ov, oa => lay%oa, &
                   ol => lay%ol, om => lay%om)
            ! rows q
            call j%add_block(p%kinematics_q, oq, oq, self%id_tq)
            call j%add_block(p%kinematics, oq, ov, self%id_t)
            if (lay%ggl) then
                self%tmat = p%kinematics
                self%rmat = p%reaction_q
                call product_pattern(self%tmat, self%rmat, self%trq, status)
                if (status%ok()) call transpose_pattern(p%constraint_v, self%gtmat, &
                                                        self%gt_map, status)
                if (status%ok()) call product_pattern(self%tmat, self%gtmat, self%tgt, status)
                if (.not. status%ok()) return
                call j%add_block(self%trq, oq, oq, self%id_ggl_rq)
                call j%add_block(self%tgt, oq, om, self%id_ggl_gt)
            end if
            ! force rows
            rf = ov
            if (lay%accelerations) then
                call j%add_diagonal(lay%nv, ov, oa, self%id_va)
                rf = oa
                call j%add_block(p%mass, rf, oa, self%id_m)
            end if
            call j%add_block(p%force_q, rf, oq, self%id_fq)
            call j%add_block(p%reaction_q, rf, oq, self%id_rq)
            call j%add_block(p%force_v, rf, ov, self%id_fv)
            call j%add_block(p%constraint_v, rf, ol, self%id_gt, transposed=.true.)
            ! constraint rows: q columns share g_q's pattern, v columns G's
            call j%add_block(p%constraint_q, ol, oq, self%id_cq)
            select case (lay%form)
            case (index2, ggl)
                call j%add_block(p%constraint_v, ol, ov, self%id_cv)
                if (lay%ggl) call j%add_block(p%constraint_q, om, oq, self%id_mq)
            case (index1)
                call j%add_block(p%constraint_v, ol, ov, self%id_cv)
                if (lay%accelerations) then
                    call j%add_block(p%constraint_v, ol, oa, self%id_ca)
                else
                    self%mass_rows = .true.
                    call add_full_block(j, lay%nc, lay%nq, ol, oq, self%id_iq, status)
                    call add_full_block(j, lay%nc, lay%nv, ol, ov, self%id_iv, status)
                    call add_full_block(j, lay%nc, lay%nc, ol, ol, self%id_il, status)
                    if (.not. status%ok()) return
                    ! nc dense rows (index 1, constant mass)
                    allocate (self%zmat(lay%nv, lay%nc), self%wq(lay%nc, lay%nq), &
                              self%wvv(lay%nc, lay%nv), self%wl(lay%nc, lay%nc), &
                              self%f(lay%nv), stat=ios)
                    if (ios /= 0) then
                        call out_of_memory(status, 'index-1 constraint rows', &
                            int(lay%nc, i8) * int(2 * lay%nv + lay%nq + lay%nc, i8), 8)
                        return
                    end if
                end if
            end select
            call j%build(lay%n, lay%n, status)
            if (.not. status%ok()) return
            ! DAE mass: I on q (and v), M on v in the constant-mass layout
            call self%mass%add_diagonal(lay%nq, oq, oq, self%id_mass_q)
            if (lay%accelerations) then
                call self%mass%add_diagonal(lay%nv, ov, ov, self%id_mass_v)
            else
                call self%mass%add_block(p%mass, ov, ov, self%id_mass_v)
            end if
            call self%mass%build(lay%n, lay%n, status)
            if (.not. status%ok()) return
        end associate
        call self%kkt%init(self%pat%mass, self%pat%constraint_v, status)
        if (.not. status%ok()) return
        associate (p => self%pat)
            allocate (self%t(p%kinematics%nnz), self%tq(p%kinematics_q%nnz), &
                      self%fq(p%force_q%nnz), self%mq(p%force_q%nnz), self%fv(p%force_v%nnz), &
                      self%m(p%mass%nnz), self%m0(p%mass%nnz), self%g(p%constraint_v%nnz), &
                      self%gv(p%constraint_v%nnz), self%cq(p%constraint_q%nnz), &
                      self%cq2(p%constraint_q%nnz), self%rq(p%reaction_q%nnz), &
                      self%wv(lay%nv), self%zc(lay%nc), stat=ios)
            if (ios /= 0) then
                call out_of_memory(status, 'sparse formulation values', int(p%force_q%nnz, i8) &
                    * 3_i8 + int(p%mass%nnz, i8) * 2_i8 + int(p%constraint_q%nnz, i8) * 2_i8, 8)
                return
            end if
            self%zc = 0.0_wp
        end associate
        ! constant M of the constant-mass layout
        call mech%mass_sparse(0.0_wp, q_mass, self%m0, status)
        if (.not. status%ok()) return
        call self%mass%zero()
        call self%mass%scatter_diagonal(self%id_mass_q, 1.0_wp)
        if (lay%accelerations) then
            call self%mass%scatter_diagonal(self%id_mass_v, 1.0_wp)
        else
            call self%mass%scatter(self%id_mass_v, self%m0)
        end if
    end subroutine sparse_init

    !> ∂F/∂y at (t, y) into values (one per slot of self%jac%matrix).
    subroutine sparse_jacobian(self, mech, t, y, values, status)
        class(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: kz
        associate (lay => self%lay, j => self%jac, nq => self%lay%nq, nv => self%lay%nv, &
                   nc => self%lay%nc)
            associate (q => y(lay%oq + 1:lay%oq + nq), v => y(lay%ov + 1:lay%ov + nv), &
                       lam => y(lay%ol + 1:lay%ol + nc), &
                       mu => y(lay%om + 1:lay%om + merge(nc, 0, lay%ggl)))
                call j%zero()
                call mech%constraint_jacobian_sparse(t, q, self%g, status)
                call mech%kinematics_sparse(t, q, self%t, status)
                call j%scatter(self%id_t, self%t)
                ! ∂(T w)/∂q with w = v (- Gᵀμ)
                if (lay%ggl) then
                    call self%gt_times(mu, self%wv)
                    self%wv = v - self%wv
                    call mech%kinematics_derivative_sparse(t, q, self%wv, self%tq, status)
                else
                    call mech%kinematics_derivative_sparse(t, q, v, self%tq, status)
                end if
                call j%scatter(self%id_tq, self%tq)
                if (lay%ggl) then
                    ! -T ∂(Gᵀμ)/∂q and -T Gᵀ
                    call mech%constraint_jacobian_derivatives_sparse(t, q, v, mu, self%cq, &
                                                                     self%rq, status)
                    self%tmat%values = self%t
                    self%rmat%values = self%rq
                    call product_values(self%tmat, self%rmat, self%trq)
                    call j%scatter(self%id_ggl_rq, self%trq%values, -1.0_wp)
                    self%gtmat%values = self%g(self%gt_map)
                    call product_values(self%tmat, self%gtmat, self%tgt)
                    call j%scatter(self%id_ggl_gt, self%tgt%values, -1.0_wp)
                end if
                ! force rows
                call mech%force_derivatives_sparse(t, q, v, self%fq, self%fv, status)
                call mech%constraint_jacobian_derivatives_sparse(t, q, v, lam, self%cq, &
                                                                 self%rq, status)
                call j%scatter(self%id_fq, self%fq)
                call j%scatter(self%id_rq, self%rq, -1.0_wp)
                call j%scatter(self%id_fv, self%fv)
                call j%scatter(self%id_gt, self%g, -1.0_wp)
                if (lay%accelerations) then
                    call j%scatter_diagonal(self%id_va, 1.0_wp)
                    associate (a => y(lay%oa + 1:lay%oa + nv))
                        call mech%mass_derivative_sparse(t, q, a, self%mq, status)
                        call j%scatter(self%id_fq, self%mq, -1.0_wp)
                        call mech%mass_sparse(t, q, self%m, status)
                        call j%scatter(self%id_m, self%m, -1.0_wp)
                    end associate
                end if
                ! constraint rows
                select case (lay%form)
                case (index3)
                    call mech%constraint_position_jacobian_sparse(t, q, self%cq, status)
                    call j%scatter(self%id_cq, self%cq)
                case (index2, ggl)
                    call velocity_constraint_q(self, mech, t, q, v, status)
                    call j%scatter(self%id_cq, self%cq)
                    call j%scatter(self%id_cv, self%g)
                    if (lay%ggl) then
                        call mech%constraint_position_jacobian_sparse(t, q, self%cq, status)
                        call j%scatter(self%id_mq, self%cq)
                    end if
                case (index1)
                    call mech%constraint_curvature_derivatives_sparse(t, q, v, self%cq, &
                                                                      self%gv, status)
                    call j%scatter(self%id_cq, self%cq)
                    call j%scatter(self%id_cv, self%gv)
                    if (self%mass_rows) then
                        call index1_mass_rows(self, mech, t, q, v, lam, status)
                    else
                        associate (a => y(lay%oa + 1:lay%oa + nv))
                            call mech%constraint_jacobian_derivatives_sparse(t, q, a, lam, &
                                self%cq, self%rq, status)
                        end associate
                        call j%scatter(self%id_cq, self%cq)
                        call j%scatter(self%id_ca, self%g)
                    end if
                    if (lay%baumgarte_omega > 0.0_wp) then
                        kz = 2.0_wp * lay%baumgarte_zeta * lay%baumgarte_omega
                        call velocity_constraint_q(self, mech, t, q, v, status)
                        call j%scatter(self%id_cq, self%cq, kz)
                        call j%scatter(self%id_cv, self%g, kz)
                        call mech%constraint_position_jacobian_sparse(t, q, self%cq, status)
                        call j%scatter(self%id_cq, self%cq, lay%baumgarte_omega**2)
                    end if
                end select
                values = j%matrix%values
            end associate
        end associate
    end subroutine sparse_jacobian

    !> Index 1, constant mass: the G M⁻¹ (f - Gᵀλ) part of the constraint rows
    !> (module header), with self%fq, self%fv and self%g of this evaluation.
    subroutine index1_mass_rows(self, mech, t, q, v, lam, status)
        type(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, q(:), v(:), lam(:)
        type(status_t), intent(inout) :: status
        integer :: k, j
        integer(i8) :: p
        associate (nc => self%lay%nc, gp => self%pat%constraint_v)
            ! b = M⁻¹(f - Gᵀλ); ∂(G b)/∂q at fixed b, and ∂(Gᵀλ)/∂q
            call mech%forces(t, q, v, self%f, status)
            call self%gt_times(lam, self%wv)
            self%wv = self%f - self%wv
            call self%solve_mass(self%wv, status)
            call mech%constraint_jacobian_derivatives_sparse(t, q, self%wv, lam, self%cq, &
                                                             self%rq, status)
            call self%jac%scatter(self%id_cq, self%cq)
            ! Z = M⁻¹ Gᵀ, column k from row k of G
            self%zmat = 0.0_wp
            do j = 1, gp%ncol
                do p = gp%colptr(j) + 1, gp%colptr(j + 1)
                    self%zmat(j, gp%rowind(p) + 1) = self%g(p)
                end do
            end do
            do k = 1, nc
                call self%solve_mass(self%zmat(:, k), status)
            end do
            if (.not. status%ok()) return
            call add_zt_times(self%zmat, self%pat%force_q, self%fq, 1.0_wp, .true., self%wq)
            call add_zt_times(self%zmat, self%pat%reaction_q, self%rq, -1.0_wp, .false., &
                              self%wq)
            call add_zt_times(self%zmat, self%pat%force_v, self%fv, 1.0_wp, .true., self%wvv)
            call add_zt_times(self%zmat, gp, self%g, -1.0_wp, .true., self%wl, transposed=.true.)
            call self%jac%scatter_full(self%id_iq, self%wq)
            call self%jac%scatter_full(self%id_iv, self%wvv)
            call self%jac%scatter_full(self%id_il, self%wl)
        end associate
    end subroutine index1_mass_rows

    !> w (+)= scale Zᵀ A for A a pattern with values (nv x ncol); with
    !> `transposed`, w (+)= scale A Z (A nc x nv, as G Z).
    pure subroutine add_zt_times(z, a, values, scale, fresh, w, transposed)
        real(wp), intent(in) :: z(:, :), values(:), scale
        type(csc_matrix_t), intent(in) :: a
        logical, intent(in) :: fresh   !! overwrite w instead of adding
        real(wp), intent(inout) :: w(:, :)
        logical, intent(in), optional :: transposed
        integer :: j, i
        integer(i8) :: p
        if (fresh) w = 0.0_wp
        if (present(transposed)) then
            ! w(k, :) += scale A(k, i) Z(i, :) for A's slots (k = row, i = column)
            do i = 1, a%ncol
                do p = a%colptr(i) + 1, a%colptr(i + 1)
                    w(a%rowind(p) + 1, :) = w(a%rowind(p) + 1, :) + scale * values(p) * z(i, :)
                end do
            end do
            return
        end if
        do j = 1, a%ncol
            do p = a%colptr(j) + 1, a%colptr(j + 1)
                w(:, j) = w(:, j) + scale * values(p) * z(a%rowind(p) + 1, :)
            end do
        end do
    end subroutine add_zt_times

    !> A full nrow x ncol block at (row0, col0): its slots in column-major order.
    subroutine add_full_block(j, nrow, ncol, row0, col0, id, status)
        type(block_assembly_t), intent(inout) :: j
        integer, intent(in) :: nrow, ncol, row0, col0
        integer, intent(out) :: id
        type(status_t), intent(inout) :: status
        type(triplets_t) :: t
        type(csc_matrix_t) :: full
        call t%add_range(0, 0, nrow, ncol)
        call t%build(nrow, ncol, full, status)
        call j%add_block(full, row0, col0, id)
    end subroutine add_full_block

    !> x ← M⁻¹ x with the constant M (KLU, analysed and factored at first use).
    subroutine sparse_solve_mass(self, x, status)
        class(sparse_formulation_t), intent(inout) :: self
        real(wp), intent(inout) :: x(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        if (.not. self%mlu%is_analysed()) then
            call self%mlu%analyse(self%lay%nv, self%pat%mass%colptr, self%pat%mass%rowind, local)
            if (local%ok()) call self%mlu%factor(self%m0, local)
            if (.not. local%ok()) then
                status = local
                status%message = 'formulation: mass matrix: ' // status%message
                return
            end if
        end if
        call self%mlu%solve(x, local)
        if (.not. local%ok()) status = local
    end subroutine sparse_solve_mass

    !> self%cq = ∂(G v + g_I)/∂q (self%rq, self%cq2 overwritten).
    subroutine velocity_constraint_q(self, mech, t, q, v, status)
        type(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, q(:), v(:)
        type(status_t), intent(inout) :: status
        call mech%constraint_jacobian_derivatives_sparse(t, q, v, self%zc, self%cq, self%rq, &
                                                         status)
        call mech%constraint_time_derivative_jacobian_sparse(t, q, self%cq2, status)
        self%cq = self%cq + self%cq2
    end subroutine velocity_constraint_q
    !> The DAE mass matrix (pattern and constant values).
    subroutine sparse_mass_matrix(self, m)
        class(sparse_formulation_t), intent(in) :: self
        type(csc_matrix_t), intent(inout) :: m
        m = self%mass%matrix
    end subroutine sparse_mass_matrix

    !> The pattern of ∂F/∂y (values zero).
    subroutine sparse_jacobian_pattern(self, pattern)
        class(sparse_formulation_t), intent(in) :: self
        type(csc_matrix_t), intent(inout) :: pattern
        pattern = self%jac%matrix
    end subroutine sparse_jacobian_pattern

    !> G(t, q) into self%g (for g_times, gt_times and the KKT matrix).
    subroutine sparse_constraint_jacobian(self, mech, t, q, status)
        class(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, q(:)
        type(status_t), intent(inout) :: status
        call mech%constraint_jacobian_sparse(t, q, self%g, status)
    end subroutine sparse_constraint_jacobian

    !> y = G x with the G of the last constraint_jacobian or jacobian call.
    pure subroutine sparse_g_times(self, x, y)
        class(sparse_formulation_t), intent(in) :: self
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: y(:)
        call pattern_matvec(self%pat%constraint_v, self%g, x, y)
    end subroutine sparse_g_times

    !> y = Gᵀ x.
    pure subroutine sparse_gt_times(self, x, y)
        class(sparse_formulation_t), intent(in) :: self
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: y(:)
        call pattern_matvec_transpose(self%pat%constraint_v, self%g, x, y)
    end subroutine sparse_gt_times

    !> y = M(t, q) x (values refreshed from the mechanical problem).
    subroutine sparse_m_times(self, mech, t, q, x, y, status)
        class(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, q(:), x(:)
        real(wp), intent(out) :: y(:)
        type(status_t), intent(inout) :: status
        call mech%mass_sparse(t, q, self%m, status)
        call pattern_matvec(self%pat%mass, self%m, x, y)
    end subroutine sparse_m_times

    !> Factor K = [M Gᵀ; G 0] at q (M and G evaluated there).
    subroutine sparse_factor_kkt(self, mech, t, q, status)
        class(sparse_formulation_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mech
        real(wp), intent(in) :: t, q(:)
        type(status_t), intent(inout) :: status
        call mech%mass_sparse(t, q, self%m, status)
        call mech%constraint_jacobian_sparse(t, q, self%g, status)
        if (.not. status%ok()) return
        if (self%structured) then
            if (.not. allocated(self%skkt)) then
                allocate (self%skkt)
                call self%skkt%init(self%pat%mass, self%pat%constraint_v, status)
                if (.not. status%ok()) then
                    deallocate (self%skkt)
                    return
                end if
            end if
            call self%skkt%assemble(self%m, self%g)
            call self%skkt%factor(status)
            return
        end if
        call self%kkt%assemble(self%m, self%g)
        call self%kkt%factor(status)
    end subroutine sparse_factor_kkt

    !> rhs ← K⁻¹ rhs.
    subroutine sparse_solve_kkt(self, rhs, status)
        class(sparse_formulation_t), intent(inout) :: self
        real(wp), intent(inout) :: rhs(:)
        type(status_t), intent(inout) :: status
        if (self%structured) then
            call self%skkt%solve(rhs, status)
        else
            call self%kkt%solve(rhs, status)
        end if
    end subroutine sparse_solve_kkt

    !> From now on [M Gᵀ; G 0] by the structure of M (flexmbs_linalg_
    !> structured_saddle): the constant mass blocks factored once, massless
    !> frames in a small system; the next factorisation starts it.
    subroutine sparse_use_structure(self)
        class(sparse_formulation_t), intent(inout) :: self
        self%structured = .true.
    end subroutine sparse_use_structure
end module flexmbs_mbs_formulation_sparse
