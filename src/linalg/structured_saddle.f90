!> Saddle-point systems K [x; y] = [M Bᵀ; A 0] [x; y] = [f; g] solved by
!> the structure of M (docs/theory.md §7.8): M is block diagonal after a
!> permutation, its blocks the connected components of its pattern (a
!> finite-element body, a rigid body, a chain), and some blocks are zero
!> (massless node frames). With m the dofs of the blocks with mass and z
!> those without,
!>
!>     x_m = M_m⁻¹ (f_m − B_mᵀ y) = u − Z y,   u = M_m⁻¹ f_m,  Z = M_m⁻¹ B_mᵀ,
!>     [0    B_zᵀ] [x_z]   [f_z       ]
!>     [A_z  −C  ] [ y ] = [g − A_m u ],        C = A_m Z,
!>
!> the second a dense system of order (massless dofs + constraints). What is
!> constant is factored once: a block whose values have not changed since
!> its last factorisation keeps it (the finite-element mass of a total
!> Lagrangian body, a rigid body's m and inertia), one whose values changed
!> (a chain's M(q)) is factored again. Blocks up to dense_block_limit are
!> factored by LAPACK, larger ones by KLU on their own pattern. Z needs one
!> solve per constraint row that touches a block, in that block only.
!>
!> The interface is flexmbs_linalg_saddle_point's sparse one: `init` with
!> the patterns of M and of A (B shares it), `assemble` the values, `factor`,
!> `solve`. Which blocks are massless is decided at the first factorisation
!> (all values zero); a massive block whose values later vanish fails as a
!> singular matrix.
module flexmbs_linalg_structured_saddle
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_text, only: int_text
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_linalg_csc, only: csc_matrix_t
    use flexmbs_linalg_sub_block, only: sub_block_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_auto
    use flexmbs_linalg_lapack, only: dgetrf, dgetrs
    implicit none
    private

    !> Blocks of M of at most this order get a dense LU; larger ones KLU.
    integer, parameter, public :: dense_block_limit = 64

    !> One diagonal block of M and its factorisation.
    type :: mass_block_t
        integer :: m = 0                       !! order
        logical :: massless = .false.
        logical :: factored = .false.
        logical :: sparse = .false.            !! KLU (else dense LAPACK)
        integer, allocatable :: dofs(:)        !! its velocity dofs
        integer(i8), allocatable :: slots(:)   !! M's slots inside the block
        integer, allocatable :: slot_col(:)    !! their block-local columns
        real(wp), allocatable :: last(:)       !! their values at the last factorisation
        real(wp), allocatable :: lu(:, :)      !! dense LU
        integer, allocatable :: piv(:)
        type(sub_block_t) :: pattern           !! KLU: the block's own pattern
        type(klu_factor_t) :: klu
        integer, allocatable :: rows(:)        !! constraint rows touching the block
        real(wp), allocatable :: z(:, :)       !! M_b⁻¹ B_bᵀ for those rows (m x size(rows))
        real(wp), allocatable :: work(:)       !! a vector of order m
    end type mass_block_t

    !> K = [M Bᵀ; A 0] by the structure of M (module header).
    type, public :: structured_saddle_t
        private
        integer :: nv = 0, nc = 0, nz = 0
        type(csc_matrix_t) :: mpat, apat
        real(wp), allocatable :: mv(:), av(:), bv(:)  !! values of M, A, B
        integer, allocatable :: block_of(:), local_of(:), zpos(:)
        type(mass_block_t), allocatable :: blocks(:)
        logical :: first = .true.
        integer :: block_factorizations = 0    !! mass blocks factored so far
        real(wp), allocatable :: t(:, :), c(:, :), u(:), s(:)
        integer, allocatable :: tpiv(:)
    contains
        procedure :: init => saddle_init
        procedure :: assemble => saddle_assemble
        procedure :: factor => saddle_factor
        procedure :: solve => saddle_solve
        procedure :: order => saddle_order
        procedure :: block_counts => saddle_blocks_factored
    end type structured_saddle_t

contains

    !> The blocks of M (components of its pattern) and the constraint rows
    !> touching each, from the patterns of M (nv x nv) and A (nc x nv).
    subroutine saddle_init(self, m_pattern, a_pattern, status)
        class(structured_saddle_t), intent(inout) :: self
        type(csc_matrix_t), intent(in) :: m_pattern, a_pattern
        type(status_t), intent(out) :: status
        integer, allocatable :: root(:), count(:), fill(:), ident(:)
        integer :: nv, j, i, k, b, nb, stat
        integer(i8) :: p
        call default_blas_threads()
        nv = m_pattern%ncol
        if (m_pattern%nrow /= nv .or. a_pattern%ncol /= nv) then
            call status%set(status_bad_input, 'structured saddle point: M is ' // &
                int_text(m_pattern%nrow) // ' x ' // int_text(nv) // ', A has ' // &
                int_text(a_pattern%ncol) // ' columns')
            return
        end if
        self%nv = nv
        self%nc = a_pattern%nrow
        self%mpat = m_pattern
        self%apat = a_pattern
        allocate (root(nv), self%block_of(nv), self%local_of(nv), ident(nv), &
            self%mv(m_pattern%nnz), self%av(a_pattern%nnz), self%bv(a_pattern%nnz), &
            self%u(nv), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'structured saddle point maps', 6_i8 * nv, 8)
            return
        end if
        ! components of M's pattern (union-find)
        root = [(i, i=1, nv)]
        do j = 1, nv
            do p = m_pattern%colptr(j) + 1, m_pattern%colptr(j + 1)
                call join(int(m_pattern%rowind(p)) + 1, j)
            end do
        end do
        nb = 0
        ident = 0
        do i = 1, nv
            k = find(i)
            if (ident(k) == 0) then
                nb = nb + 1
                ident(k) = nb
            end if
            self%block_of(i) = ident(k)
        end do
        allocate (self%blocks(nb), count(nb), fill(nb))
        count = 0
        do i = 1, nv
            count(self%block_of(i)) = count(self%block_of(i)) + 1
        end do
        do b = 1, nb
            allocate (self%blocks(b)%dofs(count(b)))
            self%blocks(b)%m = count(b)
        end do
        fill = 0
        do i = 1, nv
            b = self%block_of(i)
            fill(b) = fill(b) + 1
            self%blocks(b)%dofs(fill(b)) = i
            self%local_of(i) = fill(b)
        end do
        ! M's slots per block
        count = 0
        do j = 1, nv
            b = self%block_of(j)
            count(b) = count(b) + int(m_pattern%colptr(j + 1) - m_pattern%colptr(j))
        end do
        do b = 1, nb
            allocate (self%blocks(b)%slots(count(b)), self%blocks(b)%last(count(b)), &
                self%blocks(b)%slot_col(count(b)))
        end do
        fill = 0
        do j = 1, nv
            b = self%block_of(j)
            do p = m_pattern%colptr(j) + 1, m_pattern%colptr(j + 1)
                fill(b) = fill(b) + 1
                self%blocks(b)%slots(fill(b)) = p
                self%blocks(b)%slot_col(fill(b)) = self%local_of(j)
            end do
        end do
        call rows_per_block(self, status)
    contains
        integer function find(x)
            integer, intent(in) :: x
            find = x
            do while (root(find) /= find)
                root(find) = root(root(find))
                find = root(find)
            end do
        end function find
        subroutine join(x, y)
            integer, intent(in) :: x, y
            integer :: rx, ry
            rx = find(x)
            ry = find(y)
            if (rx /= ry) root(max(rx, ry)) = min(rx, ry)
        end subroutine join
    end subroutine saddle_init

    !> The constraint rows that touch each block (sorted, each once).
    subroutine rows_per_block(self, status)
        type(structured_saddle_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        logical, allocatable :: touches(:)
        integer :: b, l, j, stat
        integer(i8) :: p
        allocate (touches(self%nc), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'structured saddle point rows', int(self%nc, i8), 4)
            return
        end if
        do b = 1, size(self%blocks)
            touches = .false.
            associate (blk => self%blocks(b))
                do l = 1, blk%m
                    j = blk%dofs(l)
                    do p = self%apat%colptr(j) + 1, self%apat%colptr(j + 1)
                        touches(self%apat%rowind(p) + 1) = .true.
                    end do
                end do
                blk%rows = pack([(j, j=1, self%nc)], touches)
                allocate (blk%work(blk%m))
            end associate
        end do
    end subroutine rows_per_block

    !> The values of M, A and B (B = A when absent) for the next `factor`.
    pure subroutine saddle_assemble(self, m_values, a_values, b_values)
        class(structured_saddle_t), intent(inout) :: self
        real(wp), intent(in) :: m_values(:), a_values(:)
        real(wp), intent(in), optional :: b_values(:)
        self%mv = m_values
        self%av = a_values
        if (present(b_values)) then
            self%bv = b_values
        else
            self%bv = a_values
        end if
    end subroutine saddle_assemble

    !> Factor the blocks whose values changed, form Z and C, factor the
    !> small system; a singular block or system fails with
    !> reason_singular_matrix.
    subroutine saddle_factor(self, status)
        class(structured_saddle_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer :: b, info
        if (self%first) then
            call first_factor(self, status)
            if (.not. status%ok()) return
        end if
        do b = 1, size(self%blocks)
            if (self%blocks(b)%massless) cycle
            call factor_block(self, self%blocks(b), status)
            if (.not. status%ok()) return
            call block_z(self, self%blocks(b))
        end do
        call small_system(self)
        if (size(self%t, 1) == 0) return
        call dgetrf(size(self%t, 1), size(self%t, 1), self%t, size(self%t, 1), self%tpiv, info)
        if (info /= 0) call status%set(status_solver_failure, 'saddle-point matrix ' // &
            '[M G^T; G 0] is singular (redundant constraints, or a massless body held by ' // &
            'too few): pivot ' // int_text(info) // ' of the system in the multipliers', &
            reason_singular_matrix)
    end subroutine saddle_factor

    !> Massless blocks (all values zero) and the small system's workspace.
    subroutine first_factor(self, status)
        type(structured_saddle_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer :: b, l, nt, stat
        allocate (self%zpos(self%nv))
        self%zpos = 0
        self%nz = 0
        do b = 1, size(self%blocks)
            associate (blk => self%blocks(b))
                blk%massless = all(self%mv(blk%slots) == 0.0_wp)
                if (blk%massless) then
                    do l = 1, blk%m
                        self%nz = self%nz + 1
                        self%zpos(blk%dofs(l)) = self%nz
                    end do
                    cycle
                end if
                blk%sparse = blk%m > dense_block_limit
                if (blk%sparse) then
                    call blk%pattern%pick(self%mpat, block_map(blk), block_map(blk), blk%m, &
                        blk%m, status)
                    if (status%ok()) call blk%klu%analyse(blk%m, blk%pattern%a%colptr, &
                        blk%pattern%a%rowind, status, klu_ordering_auto)
                else
                    allocate (blk%lu(blk%m, blk%m), blk%piv(blk%m), stat=stat)
                end if
                if (.not. status%ok()) return
                allocate (blk%z(blk%m, size(blk%rows)), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'structured saddle point Z', &
                        int(blk%m, i8) * size(blk%rows), 8)
                    return
                end if
            end associate
        end do
        nt = self%nz + self%nc
        allocate (self%t(nt, nt), self%tpiv(nt), self%c(self%nc, self%nc), self%s(nt), &
            stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'structured saddle point small system', &
                int(nt, i8)**2 + int(self%nc, i8)**2, 8)
            return
        end if
        self%first = .false.
    contains
        function block_map(blk) result(map)
            type(mass_block_t), intent(in) :: blk
            integer, allocatable :: map(:)
            integer :: i
            allocate (map(self%nv), source=0)
            do i = 1, blk%m
                map(blk%dofs(i)) = i
            end do
        end function block_map
    end subroutine first_factor

    !> The block's LU, unless its values are those of the last one.
    subroutine factor_block(self, blk, status)
        type(structured_saddle_t), intent(inout) :: self
        type(mass_block_t), intent(inout) :: blk
        type(status_t), intent(inout) :: status
        integer :: k, info
        integer(i8) :: p
        if (blk%factored) then
            if (all(self%mv(blk%slots) == blk%last)) return
        end if
        blk%last = self%mv(blk%slots)
        blk%factored = .false.
        if (blk%sparse) then
            call blk%pattern%gather(self%mv)
            call blk%klu%factor(blk%pattern%a%values, status)
            if (.not. status%ok()) then
                call status%set(status_solver_failure, 'saddle-point matrix: the mass ' // &
                    'block of ' // int_text(blk%m) // ' dofs is singular: ' // status%text(), &
                    reason_singular_matrix)
                return
            end if
        else
            blk%lu = 0.0_wp
            do k = 1, size(blk%slots)
                p = blk%slots(k)
                blk%lu(self%local_of(self%mpat%rowind(p) + 1), blk%slot_col(k)) = self%mv(p)
            end do
            call dgetrf(blk%m, blk%m, blk%lu, blk%m, blk%piv, info)
            if (info /= 0) then
                call status%set(status_solver_failure, 'saddle-point matrix: the mass ' // &
                    'block of ' // int_text(blk%m) // ' dofs is singular', &
                    reason_singular_matrix)
                return
            end if
        end if
        blk%factored = .true.
        self%block_factorizations = self%block_factorizations + 1
    end subroutine factor_block

    !> Z_b = M_b⁻¹ B_bᵀ for the rows touching the block.
    subroutine block_z(self, blk)
        type(structured_saddle_t), intent(inout) :: self
        type(mass_block_t), intent(inout) :: blk
        integer :: l, k, j, info
        integer(i8) :: p
        type(status_t) :: st
        if (size(blk%rows) == 0) return
        blk%z = 0.0_wp
        do l = 1, blk%m
            j = blk%dofs(l)
            do p = self%apat%colptr(j) + 1, self%apat%colptr(j + 1)
                k = row_position(blk, int(self%apat%rowind(p)) + 1)
                blk%z(l, k) = self%bv(p)
            end do
        end do
        if (blk%sparse) then
            do k = 1, size(blk%rows)
                call blk%klu%solve(blk%z(:, k), st)
            end do
        else
            call dgetrs('N', blk%m, size(blk%rows), blk%lu, blk%m, blk%piv, blk%z, blk%m, info)
        end if
    end subroutine block_z

    !> Position of constraint row i among the block's rows (binary search).
    pure integer function row_position(blk, i) result(k)
        type(mass_block_t), intent(in) :: blk
        integer, intent(in) :: i
        integer :: lo, hi
        lo = 1
        hi = size(blk%rows)
        k = 0
        do while (lo <= hi)
            k = (lo + hi) / 2
            if (blk%rows(k) == i) return
            if (blk%rows(k) < i) then
                lo = k + 1
            else
                hi = k - 1
            end if
        end do
        k = 0
    end function row_position

    !> T = [0 B_zᵀ; A_z −C] with C = A_m Z.
    subroutine small_system(self)
        type(structured_saddle_t), intent(inout) :: self
        integer :: j, i, b, k, nz
        integer(i8) :: p
        nz = self%nz
        self%c = 0.0_wp
        do j = 1, self%nv
            b = self%block_of(j)
            if (self%blocks(b)%massless) cycle
            associate (blk => self%blocks(b))
                do p = self%apat%colptr(j) + 1, self%apat%colptr(j + 1)
                    i = int(self%apat%rowind(p)) + 1
                    do k = 1, size(blk%rows)
                        self%c(i, blk%rows(k)) = self%c(i, blk%rows(k)) + self%av(p) &
                            * blk%z(self%local_of(j), k)
                    end do
                end do
            end associate
        end do
        self%t = 0.0_wp
        self%t(nz + 1:, nz + 1:) = -self%c
        do j = 1, self%nv
            if (self%zpos(j) == 0) cycle
            do p = self%apat%colptr(j) + 1, self%apat%colptr(j + 1)
                i = int(self%apat%rowind(p)) + 1
                self%t(self%zpos(j), nz + i) = self%bv(p)
                self%t(nz + i, self%zpos(j)) = self%av(p)
            end do
        end do
    end subroutine small_system

    !> rhs = [f; g] ← K⁻¹ rhs (size nv + nc).
    subroutine saddle_solve(self, rhs, status)
        class(structured_saddle_t), intent(inout) :: self
        real(wp), intent(inout) :: rhs(:)
        type(status_t), intent(inout) :: status
        integer :: b, l, j, i, k, info, nz
        integer(i8) :: p
        type(status_t) :: st
        nz = self%nz
        ! u = M_m⁻¹ f_m, block by block
        do b = 1, size(self%blocks)
            associate (blk => self%blocks(b))
                if (blk%massless) cycle
                do l = 1, blk%m
                    blk%work(l) = rhs(blk%dofs(l))
                end do
                if (blk%sparse) then
                    call blk%klu%solve(blk%work, st)
                    if (.not. st%ok()) status = st
                else
                    call dgetrs('N', blk%m, 1, blk%lu, blk%m, blk%piv, blk%work, blk%m, info)
                end if
                do l = 1, blk%m
                    self%u(blk%dofs(l)) = blk%work(l)
                end do
            end associate
        end do
        ! the small system's right-hand side [f_z; g − A_m u]
        do j = 1, self%nv
            if (self%zpos(j) > 0) self%s(self%zpos(j)) = rhs(j)
        end do
        self%s(nz + 1:) = rhs(self%nv + 1:)
        do j = 1, self%nv
            if (self%zpos(j) > 0) cycle
            do p = self%apat%colptr(j) + 1, self%apat%colptr(j + 1)
                i = nz + int(self%apat%rowind(p)) + 1
                self%s(i) = self%s(i) - self%av(p) * self%u(j)
            end do
        end do
        if (size(self%s) > 0) call dgetrs('N', size(self%s), 1, self%t, size(self%t, 1), &
            self%tpiv, self%s, size(self%s), info)
        ! x_m = u − Z y, x_z and y from the small system
        do b = 1, size(self%blocks)
            associate (blk => self%blocks(b))
                if (blk%massless) cycle
                do k = 1, size(blk%rows)
                    associate (y => self%s(nz + blk%rows(k)))
                        do l = 1, blk%m
                            self%u(blk%dofs(l)) = self%u(blk%dofs(l)) - blk%z(l, k) * y
                        end do
                    end associate
                end do
            end associate
        end do
        do j = 1, self%nv
            if (self%zpos(j) > 0) then
                rhs(j) = self%s(self%zpos(j))
            else
                rhs(j) = self%u(j)
            end if
        end do
        rhs(self%nv + 1:) = self%s(nz + 1:)
    end subroutine saddle_solve

    !> Order nv + nc of K.
    pure integer function saddle_order(self)
        class(structured_saddle_t), intent(in) :: self
        saddle_order = self%nv + self%nc
    end function saddle_order

    !> Mass blocks, those with mass, and the block factorisations made so
    !> far (a constant block is factored once).
    pure subroutine saddle_blocks_factored(self, total, massive, factorizations)
        class(structured_saddle_t), intent(in) :: self
        integer, intent(out) :: total, massive, factorizations
        total = size(self%blocks)
        massive = count(.not. self%blocks(:)%massless)
        factorizations = self%block_factorizations
    end subroutine saddle_blocks_factored
end module flexmbs_linalg_structured_saddle
