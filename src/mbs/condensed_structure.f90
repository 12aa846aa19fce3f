!> The structure of the condensed Newton matrix of a mechanical formulation
!> (docs/theory.md §3.7): which unknowns are eliminated, the blocks of J and
!> of the DAE mass matrix that the condensed matrix S is made of, and the
!> patterns and slot maps of S and of W = P J_EK, all found once.
!>
!> The iteration matrix A = c M_dae − J of flexmbs_mbs_formulation has, in
!> its kinematic rows, q rows c δq − J_qq δq − J_qK δx_K (q' = T w) and, in
!> the acceleration layout, v rows c δv − δa (v' = a). The eliminated
!> unknowns E are the positions of the eliminated set Q_e and the
!> accelerations; they are eliminated with the q rows of Q_e and the v rows,
!> whose block A[E rows, E] = diag(c I − J_ee, −I) is block diagonal: J_ee
!> decomposes into the connected components of the pattern of J_qq (a
!> coordinate without an entry is a component of its own with P = 1/c; a
!> rigid body's quaternion is a block of 4; GGL's T ∂(Gᵀμ)/∂q joins the
!> coordinates a nonlinear joint touches). Components larger than the
!> caller's limit (max_eliminated_block_*), or not of the kinematic form,
!> stay among the kept unknowns K. With P = (c I − J_ee)⁻¹ per component,
!>
!>     S = c M_KK − J_KK − c J_KA E_AV − J_KE P J_EK,
!>
!> E_AV mapping acceleration a_i to velocity v_i, and the eliminated
!> increments follow by back-substitution: δq_e = P (r_e + J_EK δx_K),
!> δa = c δv − r_v. Kept rows and unknowns are listed in the same order
!> (q_k with q_k, a-row i with v_i, λ with λ), so S has the diagonal of the
!> mechanics (c M on the velocities).
module flexmbs_mbs_condensed_structure
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_block_assembly, only: product_positions
    use flexmbs_linalg_sub_block, only: sub_block_t
    implicit none
    private

    !> The largest component of J_qq eliminated by a dense LU of its own,
    !> by the LU that factors S; larger components stay in S. Quaternions
    !> are blocks of 4; GGL joins a node frame, the nodes of its set and the
    !> bodies jointed to it: up to 48 positions in the five-body mechanism,
    !> 129 with its coupler at 5x20x5, 264 at 8x32x8. Kept in S, those rows
    !> with their dense coupling made KLU's factors of the 5x20x5 S 3.5x
    !> larger (2.5e6 against 7.1e5 entries) and its factorisation 10x slower,
    !> and the coarse run slower than on the full matrix (1.26 s against
    !> 0.95 s CPU; eliminated: 0.96 s). MUMPS does better with them kept: at
    !> 8x32x8 eliminating them cost 0.06 s more per factorisation in S's
    !> values (the block's dense W against its neighbours' rows) and made a
    !> 14-step RADAU5 run 9.6 s against 8.5 s (flexmbs-bench-newton, one
    !> BLAS thread).
    integer, parameter, public :: max_eliminated_block_klu = 512
    integer, parameter, public :: max_eliminated_block_mumps = 16
    !> Components of at least this order add their share of J_KE W to S as
    !> one dense product (product_plan); the smaller ones (quaternions) in
    !> s_values' sparse loop.
    integer, parameter, public :: dense_product_min = 8

    !> Offsets of the formulation's blocks in y (flexmbs_mbs_formulation).
    type, public :: condensed_layout_t
        integer :: n = 0, nq = 0, nv = 0
        integer :: oq = 0, ov = 0, oa = 0, ol = 0
        logical :: accelerations = .true.
    end type condensed_layout_t

    !> Index sets, blocks and patterns of the condensed system (header).
    type, public :: condensed_structure_t
        integer :: n = 0, nv = 0, ov = 0, oa = 0
        integer :: ne = 0           !! eliminated positions
        integer :: nk = 0           !! kept unknowns = order of S
        logical :: accelerations = .true.
        integer, allocatable :: elim(:)        !! eliminated positions (indices in y)
        integer, allocatable :: krow(:), kcol(:) !! kept rows and unknowns (indices in y)
        integer, allocatable :: vcol(:)        !! kept index of v_i (acceleration layout)
        type(sub_block_t) :: jee, jek, jke, jkk, jka, mkk
        integer :: ncomp = 0                   !! components with a dense LU
        integer :: max_block = 0               !! their largest order
        integer, allocatable :: comp_of(:)     !! eliminated e -> component (0: P = 1/c)
        integer, allocatable :: comp_ptr(:), comp_rows(:) !! rows (e) of each component
        integer, allocatable :: local_of(:)    !! e -> position in its component
        integer(i8), allocatable :: lu_ptr(:)  !! offset of a component's m x m block
        integer(i8), allocatable :: jee_to_lu(:) !! J_ee slot -> LU array index
        type(csc_matrix_t) :: w                !! pattern of W = P J_EK (ne x nk)
        integer(i8), allocatable :: jek_to_w(:)  !! J_EK slot in a P = 1/c row -> W slot
        integer(i8), allocatable :: jek_to_rhs(:) !! J_EK slot in a component row -> rhs index
        integer, allocatable :: rhs_ncol(:)    !! columns of a component's right-hand sides
        integer(i8), allocatable :: rhs_ptr(:) !! offset of its m x ncol block
        integer(i8), allocatable :: rhs_to_w(:) !! rhs index -> W slot
        integer, allocatable :: rhs_col_ptr(:), rhs_cols(:) !! S column of each rhs column
        !> J_KE W of the large components as dense products (product_plan)
        logical, allocatable :: in_product(:)  !! eliminated e in such a component
        integer, allocatable :: g_rows(:)      !! kept rows its J_KE columns touch (0: none)
        integer(i8), allocatable :: g_ptr(:)   !! offset of its g_rows x m block of J_KE
        integer(i8), allocatable :: p_ptr(:)   !! offset of its g_rows x ncol product
        integer(i8), allocatable :: jke_to_g(:) !! J_KE slot -> index in the gathered blocks
        integer(i8), allocatable :: prod_to_s(:) !! product index -> S slot
        type(csc_matrix_t) :: s                !! pattern of S (nk x nk)
        integer(i8), allocatable :: jkk_to_s(:), jka_to_s(:), mkk_to_s(:)
    contains
        procedure :: build => structure_build
        procedure :: lu_size => structure_lu_size
        procedure :: rhs_size => structure_rhs_size
        procedure :: gather_size => structure_gather_size
        procedure :: product_size => structure_product_size
    end type condensed_structure_t

    character(len=*), parameter :: who = 'condensed Newton system'

contains

    !> Index sets, blocks and patterns for the DAE mass `mass` and the
    !> Jacobian pattern `jac` (both CSC, order lay%n) of a formulation with
    !> layout `lay`. Refuses matrices that are not of the kinematic form.
    subroutine structure_build(self, lay, mass, jac, max_block, status)
        class(condensed_structure_t), intent(inout) :: self
        type(condensed_layout_t), intent(in) :: lay
        type(csc_matrix_t), intent(in) :: mass, jac
        integer, intent(in) :: max_block !! the largest component eliminated
        type(status_t), intent(inout) :: status
        integer, allocatable :: comp(:), rowpos(:), colpos(:), epos(:), apos(:)
        logical, allocatable :: eliminable(:)
        integer :: stat, n
        n = lay%n
        if (jac%nrow /= n .or. jac%ncol /= n .or. mass%nrow /= n .or. mass%ncol /= n) then
            call status%set(status_bad_input, who // ': J and M must have order n = ' // &
                int_text(n))
            return
        end if
        self%n = n
        self%nv = lay%nv
        self%ov = lay%ov
        self%oa = lay%oa
        self%accelerations = lay%accelerations
        allocate (comp(lay%nq), eliminable(lay%nq), rowpos(n), colpos(n), epos(n), apos(n), &
            stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' index maps', 6_i8 * n, 4)
            return
        end if
        if (lay%accelerations) then
            call check_velocity_rows(lay, mass, jac, status)
            if (.not. status%ok()) return
        end if
        call position_components(lay, jac, comp)
        call choose_eliminated(lay, mass, jac, comp, max_block, eliminable)
        call index_sets(self, lay, eliminable, rowpos, colpos, epos, apos, status)
        if (.not. status%ok()) return
        call self%jee%pick(jac, epos, epos, self%ne, self%ne, status)
        if (status%ok()) call self%jek%pick(jac, epos, colpos, self%ne, self%nk, status)
        if (status%ok()) call self%jke%pick(jac, rowpos, epos, self%nk, self%ne, status)
        if (status%ok()) call self%jkk%pick(jac, rowpos, colpos, self%nk, self%nk, status)
        if (status%ok()) call self%jka%pick(jac, rowpos, apos, self%nk, max(lay%nv, 1), status)
        if (status%ok()) call self%mkk%pick(mass, rowpos, colpos, self%nk, self%nk, status)
        if (.not. status%ok()) return
        call eliminated_components(self, comp, lay, status)
        if (status%ok()) call w_pattern(self, status)
        if (status%ok()) call s_pattern(self, status)
        if (status%ok()) call product_plan(self, status)
    end subroutine structure_build

    !> Acceleration layout: the v rows must read v' = a (J: only (v_i, a_i);
    !> M: only (v_i, v_i) = 1) and no DAE mass may sit in the a columns.
    subroutine check_velocity_rows(lay, mass, jac, status)
        type(condensed_layout_t), intent(in) :: lay
        type(csc_matrix_t), intent(in) :: mass, jac
        type(status_t), intent(inout) :: status
        integer :: j, i
        integer(i8) :: p
        do j = 1, lay%n
            do p = jac%colptr(j) + 1, jac%colptr(j + 1)
                i = int(jac%rowind(p)) + 1
                if (i <= lay%ov .or. i > lay%ov + lay%nv) cycle
                if (j /= i - lay%ov + lay%oa) then
                    call refuse('J', i, j)
                    return
                end if
            end do
            do p = mass%colptr(j) + 1, mass%colptr(j + 1)
                i = int(mass%rowind(p)) + 1
                if (j > lay%oa .and. j <= lay%oa + lay%nv .and. mass%values(p) /= 0.0_wp) then
                    call refuse('M', i, j)
                    return
                end if
                if (i <= lay%ov .or. i > lay%ov + lay%nv) cycle
                if (i /= j .or. mass%values(p) /= 1.0_wp) then
                    call refuse('M', i, j)
                    return
                end if
            end do
        end do
    contains
        subroutine refuse(what, i, j)
            character(len=*), intent(in) :: what
            integer, intent(in) :: i, j
            call status%set(status_bad_input, who // ': ' // what // ' has an entry at (' // &
                int_text(i) // ', ' // int_text(j) // ') where v'' = a allows none')
        end subroutine refuse
    end subroutine check_velocity_rows

    !> Connected components of the pattern of J_qq (union-find); comp(i) is
    !> the root of position i.
    subroutine position_components(lay, jac, comp)
        type(condensed_layout_t), intent(in) :: lay
        type(csc_matrix_t), intent(in) :: jac
        integer, intent(out) :: comp(:)
        integer :: j, i, a, b
        integer(i8) :: p
        comp = [(i, i=1, lay%nq)]
        do j = lay%oq + 1, lay%oq + lay%nq
            do p = jac%colptr(j) + 1, jac%colptr(j + 1)
                i = int(jac%rowind(p)) + 1
                if (i <= lay%oq .or. i > lay%oq + lay%nq) cycle
                a = root(i - lay%oq)
                b = root(j - lay%oq)
                if (a /= b) comp(max(a, b)) = min(a, b)
            end do
        end do
        do i = 1, lay%nq
            comp(i) = root(i)
        end do
    contains
        integer function root(k)
            integer, intent(in) :: k
            root = k
            do while (comp(root) /= root)
                comp(root) = comp(comp(root))
                root = comp(root)
            end do
        end function root
    end subroutine position_components

    !> A component is eliminated when it is at most max_block large, its q
    !> rows hold no acceleration column of J, and the DAE mass is the
    !> identity in its rows and columns.
    subroutine choose_eliminated(lay, mass, jac, comp, max_block, eliminable)
        type(condensed_layout_t), intent(in) :: lay
        type(csc_matrix_t), intent(in) :: mass, jac
        integer, intent(in) :: comp(:), max_block
        logical, intent(out) :: eliminable(:)
        integer, allocatable :: size_of(:)
        logical, allocatable :: fits(:)
        integer :: i, j, r, k
        integer(i8) :: p
        allocate (size_of(lay%nq), fits(lay%nq))
        size_of = 0
        do i = 1, lay%nq
            size_of(comp(i)) = size_of(comp(i)) + 1
        end do
        fits = .true.
        do j = 1, lay%n
            do p = jac%colptr(j) + 1, jac%colptr(j + 1)
                i = int(jac%rowind(p)) + 1
                if (.not. in_q(i)) cycle
                if (lay%accelerations .and. j > lay%oa .and. j <= lay%oa + lay%nv) &
                    fits(comp(i - lay%oq)) = .false.
            end do
            do p = mass%colptr(j) + 1, mass%colptr(j + 1)
                i = int(mass%rowind(p)) + 1
                if (mass%values(p) == 0.0_wp .or. .not. (in_q(i) .or. in_q(j))) cycle
                if (i /= j .or. mass%values(p) /= 1.0_wp) then
                    do r = 1, 2
                        k = merge(i, j, r == 1)
                        if (in_q(k)) fits(comp(k - lay%oq)) = .false.
                    end do
                end if
            end do
        end do
        do i = 1, lay%nq
            eliminable(i) = fits(comp(i)) .and. size_of(comp(i)) <= max_block
        end do
    contains
        logical function in_q(k)
            integer, intent(in) :: k
            in_q = k > lay%oq .and. k <= lay%oq + lay%nq
        end function in_q
    end subroutine choose_eliminated

    !> The eliminated positions and the kept rows and unknowns, in matching
    !> order: kept q with itself, a-row i (or v-row i) with v_i, then λ, μ.
    subroutine index_sets(self, lay, eliminable, rowpos, colpos, epos, apos, status)
        type(condensed_structure_t), intent(inout) :: self
        type(condensed_layout_t), intent(in) :: lay
        logical, intent(in) :: eliminable(:)
        integer, intent(out) :: rowpos(:), colpos(:), epos(:), apos(:)
        type(status_t), intent(inout) :: status
        integer :: i, k, nk, first_row, stat
        self%ne = count(eliminable)
        nk = lay%n - self%ne
        if (lay%accelerations) nk = nk - lay%nv
        self%nk = nk
        if (allocated(self%elim)) deallocate (self%elim, self%krow, self%kcol, self%vcol)
        allocate (self%elim(self%ne), self%krow(nk), self%kcol(nk), self%vcol(lay%nv), &
            stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' index sets', int(self%ne + 2 * nk, i8), 4)
            return
        end if
        rowpos = 0
        colpos = 0
        epos = 0
        apos = 0
        k = 0
        do i = 1, lay%nq
            if (eliminable(i)) then
                k = k + 1
                self%elim(k) = lay%oq + i
                epos(lay%oq + i) = k
            end if
        end do
        k = 0
        do i = 1, lay%nq
            if (eliminable(i)) cycle
            k = k + 1
            self%krow(k) = lay%oq + i
            self%kcol(k) = lay%oq + i
        end do
        ! the rows paired with v: the force rows (a rows, or v rows of M v' = ...)
        first_row = merge(lay%oa, lay%ov, lay%accelerations)
        do i = 1, lay%nv
            k = k + 1
            self%krow(k) = first_row + i
            self%kcol(k) = lay%ov + i
            self%vcol(i) = k
            if (lay%accelerations) apos(lay%oa + i) = i
        end do
        do i = lay%ol + 1, lay%n
            k = k + 1
            self%krow(k) = i
            self%kcol(k) = i
        end do
        do k = 1, nk
            rowpos(self%krow(k)) = k
            colpos(self%kcol(k)) = k
        end do
    end subroutine index_sets

    !> The components among the eliminated positions that need a dense LU
    !> (more than one position, or an entry of J_qq), their rows, and the
    !> map of J_ee's slots into their blocks.
    subroutine eliminated_components(self, comp, lay, status)
        type(condensed_structure_t), intent(inout) :: self
        integer, intent(in) :: comp(:)
        type(condensed_layout_t), intent(in) :: lay
        type(status_t), intent(inout) :: status
        integer, allocatable :: id_of_root(:)
        logical, allocatable :: touched(:)
        integer :: e, r, k, m, stat, j
        integer(i8) :: p
        allocate (id_of_root(lay%nq), touched(self%ne), self%comp_of(self%ne), &
            self%local_of(self%ne), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' components', 4_i8 * self%ne, 4)
            return
        end if
        ! a position with an entry of J_ee, or sharing its root with another
        touched = .false.
        associate (jee => self%jee%a)
            do j = 1, jee%ncol
                if (jee%colptr(j + 1) > jee%colptr(j)) touched(j) = .true.
                do p = jee%colptr(j) + 1, jee%colptr(j + 1)
                    touched(jee%rowind(p) + 1) = .true.
                end do
            end do
        end associate
        id_of_root = 0
        self%ncomp = 0
        do e = 1, self%ne
            self%comp_of(e) = 0
            if (.not. touched(e)) cycle
            r = comp(self%elim(e) - lay%oq)
            if (id_of_root(r) == 0) then
                self%ncomp = self%ncomp + 1
                id_of_root(r) = self%ncomp
            end if
            self%comp_of(e) = id_of_root(r)
        end do
        allocate (self%comp_ptr(self%ncomp + 1), self%comp_rows(count(self%comp_of > 0)), &
            self%lu_ptr(self%ncomp + 1))
        self%comp_ptr = 0
        do e = 1, self%ne
            k = self%comp_of(e)
            if (k > 0) self%comp_ptr(k + 1) = self%comp_ptr(k + 1) + 1
        end do
        self%comp_ptr(1) = 1
        do k = 1, self%ncomp
            self%comp_ptr(k + 1) = self%comp_ptr(k) + self%comp_ptr(k + 1)
        end do
        self%lu_ptr(1) = 0
        self%max_block = 0
        do k = 1, self%ncomp
            m = self%comp_ptr(k + 1) - self%comp_ptr(k)
            self%max_block = max(self%max_block, m)
            self%lu_ptr(k + 1) = self%lu_ptr(k) + int(m, i8)**2
        end do
        ! rows of each component, in increasing e
        id_of_root = 0
        do e = 1, self%ne
            k = self%comp_of(e)
            self%local_of(e) = 0
            if (k == 0) cycle
            id_of_root(k) = id_of_root(k) + 1
            self%local_of(e) = id_of_root(k)
            self%comp_rows(self%comp_ptr(k) + id_of_root(k) - 1) = e
        end do
        allocate (self%jee_to_lu(self%jee%a%nnz))
        associate (jee => self%jee%a)
            do j = 1, jee%ncol
                do p = jee%colptr(j) + 1, jee%colptr(j + 1)
                    e = int(jee%rowind(p)) + 1
                    k = self%comp_of(e)
                    m = self%comp_ptr(k + 1) - self%comp_ptr(k)
                    self%jee_to_lu(p) = self%lu_ptr(k) + int(self%local_of(j) - 1, i8) * m &
                        + self%local_of(e)
                end do
            end do
        end associate
    end subroutine eliminated_components

    !> W = P J_EK: a P = 1/c row keeps J_EK's pattern; a component's rows
    !> are full in every column any of them has. The right-hand-side blocks
    !> of the component solves and their maps.
    subroutine w_pattern(self, status)
        type(condensed_structure_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:), mark(:), cols_ptr(:), comp_cols(:), fill(:)
        integer(i8), allocatable :: colpos_of(:)
        integer :: j, e, k, m, c, l, stat
        integer(i8) :: p, nt, idx
        associate (a => self%jek%a, nc => self%ncomp)
            allocate (mark(max(nc, 1)), self%rhs_ncol(max(nc, 1)), colpos_of(a%nnz), &
                self%jek_to_w(a%nnz), self%jek_to_rhs(a%nnz), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, who // ' W maps', 3 * a%nnz, 8)
                return
            end if
            ! columns of each component (first pass: count, and the column's place)
            mark = 0
            self%rhs_ncol = 0
            colpos_of = 0
            do j = 1, a%ncol
                do p = a%colptr(j) + 1, a%colptr(j + 1)
                    k = self%comp_of(a%rowind(p) + 1)
                    if (k == 0) cycle
                    if (mark(k) /= j) then
                        mark(k) = j
                        self%rhs_ncol(k) = self%rhs_ncol(k) + 1
                    end if
                    colpos_of(p) = self%rhs_ncol(k)
                end do
            end do
            allocate (cols_ptr(nc + 1), self%rhs_ptr(nc + 1), fill(max(nc, 1)))
            cols_ptr(1) = 1
            self%rhs_ptr(1) = 0
            nt = count(self%comp_of(a%rowind(1:a%nnz) + 1) == 0)
            do k = 1, nc
                m = self%comp_ptr(k + 1) - self%comp_ptr(k)
                cols_ptr(k + 1) = cols_ptr(k) + self%rhs_ncol(k)
                self%rhs_ptr(k + 1) = self%rhs_ptr(k) + int(m, i8) * self%rhs_ncol(k)
                nt = nt + int(m, i8) * self%rhs_ncol(k)
            end do
            allocate (comp_cols(cols_ptr(nc + 1) - 1), rows(nt), cols(nt), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, who // ' W pattern', 2 * nt, 4)
                return
            end if
            fill = 0
            nt = 0
            do j = 1, a%ncol
                do p = a%colptr(j) + 1, a%colptr(j + 1)
                    e = int(a%rowind(p)) + 1
                    k = self%comp_of(e)
                    if (k == 0) then
                        nt = nt + 1
                        rows(nt) = e
                        cols(nt) = j
                    else if (colpos_of(p) > fill(k)) then
                        fill(k) = colpos_of(p)
                        comp_cols(cols_ptr(k) + fill(k) - 1) = j
                    end if
                end do
            end do
            do k = 1, nc
                do c = 1, self%rhs_ncol(k)
                    do l = self%comp_ptr(k), self%comp_ptr(k + 1) - 1
                        nt = nt + 1
                        rows(nt) = self%comp_rows(l)
                        cols(nt) = comp_cols(cols_ptr(k) + c - 1)
                    end do
                end do
            end do
            call self%w%build(self%ne, self%nk, rows, cols, status)
            if (.not. status%ok()) return
            call move_alloc(cols_ptr, self%rhs_col_ptr)
            call move_alloc(comp_cols, self%rhs_cols)
            allocate (self%rhs_to_w(self%rhs_ptr(nc + 1)))
            self%jek_to_w = 0
            self%jek_to_rhs = 0
            do j = 1, a%ncol
                do p = a%colptr(j) + 1, a%colptr(j + 1)
                    e = int(a%rowind(p)) + 1
                    k = self%comp_of(e)
                    if (k == 0) then
                        self%jek_to_w(p) = self%w%find(e, j)
                    else
                        m = self%comp_ptr(k + 1) - self%comp_ptr(k)
                        self%jek_to_rhs(p) = self%rhs_ptr(k) + int(colpos_of(p) - 1, i8) * m &
                            + self%local_of(e)
                    end if
                end do
            end do
            do k = 1, nc
                m = self%comp_ptr(k + 1) - self%comp_ptr(k)
                do c = 1, self%rhs_ncol(k)
                    do l = 1, m
                        idx = self%rhs_ptr(k) + int(c - 1, i8) * m + l
                        self%rhs_to_w(idx) = self%w%find(self%comp_rows(self%comp_ptr(k) + l &
                            - 1), self%rhs_cols(self%rhs_col_ptr(k) + c - 1))
                    end do
                end do
            end do
        end associate
    end subroutine w_pattern

    !> The dense products of J_KE W for the components of at least
    !> dense_product_min positions: a component's J_KE columns gathered into
    !> a block over the kept rows R they touch (column l: the component's
    !> l-th position), times its right-hand-side block (W's rows there,
    !> dense), subtracted from S through prod_to_s. Every (r, column) pair
    !> of R and the block's columns is in S's pattern, which holds J_KE W.
    subroutine product_plan(self, status)
        type(condensed_structure_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer, allocatable :: rowpos(:), rlist(:)
        integer :: k, m, l, e, r, nr, c, i, stat
        integer(i8) :: q, idx
        associate (a => self%jke%a, nc => self%ncomp)
            allocate (self%in_product(max(self%ne, 1)), self%g_rows(max(nc, 1)), &
                self%g_ptr(nc + 1), self%p_ptr(nc + 1), self%jke_to_g(a%nnz), &
                rowpos(self%nk), rlist(self%nk), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, who // ' product maps', a%nnz + 2_i8 * self%nk, 8)
                return
            end if
            self%in_product = .false.
            self%g_rows = 0
            self%jke_to_g = 0
            self%g_ptr(1) = 0
            self%p_ptr(1) = 0
            rowpos = 0
            ! pass 1: rows, positions in the gathered blocks
            do k = 1, nc
                m = self%comp_ptr(k + 1) - self%comp_ptr(k)
                nr = 0
                if (m >= dense_product_min .and. self%rhs_ncol(k) > 0) then
                    call component_rows(k, nr)
                    do i = 1, nr
                        rowpos(rlist(i)) = 0
                    end do
                end if
                self%g_rows(k) = nr
                self%g_ptr(k + 1) = self%g_ptr(k) + int(nr, i8) * m
                self%p_ptr(k + 1) = self%p_ptr(k) + int(nr, i8) * self%rhs_ncol(k)
            end do
            allocate (self%prod_to_s(self%p_ptr(nc + 1)), stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, who // ' product map', self%p_ptr(nc + 1), 8)
                return
            end if
            ! pass 2: the maps
            do k = 1, nc
                if (self%g_rows(k) == 0) cycle
                call component_rows(k, nr)
                do l = self%comp_ptr(k), self%comp_ptr(k + 1) - 1
                    e = self%comp_rows(l)
                    self%in_product(e) = .true.
                    do q = a%colptr(e) + 1, a%colptr(e + 1)
                        r = int(a%rowind(q)) + 1
                        self%jke_to_g(q) = self%g_ptr(k) + int(self%local_of(e) - 1, i8) * nr &
                            + rowpos(r)
                    end do
                end do
                do c = 1, self%rhs_ncol(k)
                    do i = 1, nr
                        idx = self%p_ptr(k) + int(c - 1, i8) * nr + i
                        self%prod_to_s(idx) = self%s%find(rlist(i), &
                            self%rhs_cols(self%rhs_col_ptr(k) + c - 1))
                        if (self%prod_to_s(idx) <= 0) then
                            call status%set(status_bad_input, who // ': S''s pattern misses ' // &
                                'an entry of J_KE W (component ' // int_text(k) // ')')
                            return
                        end if
                    end do
                end do
                do i = 1, nr
                    rowpos(rlist(i)) = 0
                end do
            end do
        end associate
    contains
        !> Kept rows touched by component k's J_KE columns: rlist(1:nr), and
        !> their places rowpos(r).
        subroutine component_rows(k, nr)
            integer, intent(in) :: k
            integer, intent(out) :: nr
            integer :: ll, ee, rr
            integer(i8) :: qq
            nr = 0
            do ll = self%comp_ptr(k), self%comp_ptr(k + 1) - 1
                ee = self%comp_rows(ll)
                do qq = self%jke%a%colptr(ee) + 1, self%jke%a%colptr(ee + 1)
                    rr = int(self%jke%a%rowind(qq)) + 1
                    if (rowpos(rr) /= 0) cycle
                    nr = nr + 1
                    rlist(nr) = rr
                    rowpos(rr) = nr
                end do
            end do
        end subroutine component_rows
    end subroutine product_plan

    !> Size of the gathered J_KE blocks and of the products (product_plan).
    pure integer(i8) function structure_gather_size(self)
        class(condensed_structure_t), intent(in) :: self
        structure_gather_size = 0
        if (allocated(self%g_ptr)) structure_gather_size = self%g_ptr(self%ncomp + 1)
    end function structure_gather_size

    pure integer(i8) function structure_product_size(self)
        class(condensed_structure_t), intent(in) :: self
        structure_product_size = 0
        if (allocated(self%p_ptr)) structure_product_size = self%p_ptr(self%ncomp + 1)
    end function structure_product_size

    !> S's pattern: J_KK, M_KK, J_KA moved to the v columns, and J_KE W;
    !> the slot maps of the first three.
    subroutine s_pattern(self, status)
        type(condensed_structure_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer, allocatable :: rows(:), cols(:), mark(:)
        integer(i8) :: nt
        integer :: pass, stat
        allocate (mark(self%nk), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, who // ' S marks', int(self%nk, i8), 4)
            return
        end if
        nt = self%jkk%a%nnz + self%mkk%a%nnz + self%jka%a%nnz
        allocate (rows(0), cols(0))
        ! pass 1 counts the product's entries, pass 2 lists everything
        do pass = 1, 2
            if (pass == 2) then
                deallocate (rows, cols)
                allocate (rows(nt), cols(nt), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, who // ' S positions', 2 * nt, 4)
                    return
                end if
                nt = 0
                call add_block(self%jkk%a, .false.)
                call add_block(self%mkk%a, .false.)
                call add_block(self%jka%a, .true.)
            end if
            mark = 0
            call product_positions(self%jke%a, self%w, mark, nt, pass == 2, rows, cols)
        end do
        call self%s%build(self%nk, self%nk, rows, cols, status)
        if (.not. status%ok()) return
        call slot_map(self%jkk%a, .false., self%jkk_to_s)
        call slot_map(self%mkk%a, .false., self%mkk_to_s)
        call slot_map(self%jka%a, .true., self%jka_to_s)
    contains
        subroutine add_block(b, accelerations)
            type(csc_matrix_t), intent(in) :: b
            logical, intent(in) :: accelerations
            integer :: jj
            integer(i8) :: pp
            do jj = 1, b%ncol
                do pp = b%colptr(jj) + 1, b%colptr(jj + 1)
                    nt = nt + 1
                    rows(nt) = int(b%rowind(pp)) + 1
                    cols(nt) = jj
                    if (accelerations) cols(nt) = self%vcol(jj)
                end do
            end do
        end subroutine add_block
        subroutine slot_map(b, accelerations, map)
            type(csc_matrix_t), intent(in) :: b
            logical, intent(in) :: accelerations
            integer(i8), allocatable, intent(out) :: map(:)
            integer :: jj, col
            integer(i8) :: pp
            allocate (map(b%nnz))
            do jj = 1, b%ncol
                col = jj
                if (accelerations) col = self%vcol(jj)
                do pp = b%colptr(jj) + 1, b%colptr(jj + 1)
                    map(pp) = self%s%find(int(b%rowind(pp)) + 1, col)
                end do
            end do
        end subroutine slot_map
    end subroutine s_pattern

    !> Size of the array of the components' dense LUs.
    pure integer(i8) function structure_lu_size(self)
        class(condensed_structure_t), intent(in) :: self
        structure_lu_size = 0
        if (allocated(self%lu_ptr)) structure_lu_size = self%lu_ptr(self%ncomp + 1)
    end function structure_lu_size

    !> Size of the array of the components' right-hand sides.
    pure integer(i8) function structure_rhs_size(self)
        class(condensed_structure_t), intent(in) :: self
        structure_rhs_size = 0
        if (allocated(self%rhs_ptr)) structure_rhs_size = self%rhs_ptr(self%ncomp + 1)
    end function structure_rhs_size
end module flexmbs_mbs_condensed_structure
