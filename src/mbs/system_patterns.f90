!> Sparse forms and derivative blocks of flexmbs_mbs_system
!> (the type and the procedures' interfaces are there).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_patterns
    implicit none

contains

    ! ------------------------------------------------ sparse (CSC) forms

    module procedure system_has_sparse
        system_has_sparse = .true.
    end procedure system_has_sparse

    !> Pattern of M: per body m I₃ (3 slots) and the full 3 × 3 inertia block, in the
    !> triplet order mass_sparse fills.
    module procedure system_mass_pattern
        integer, allocatable :: rows(:), cols(:)
        integer :: b, i, j, n, iv, f
        integer(i8) :: p
        n = 12 * size(self%rigid%bodies)
        do f = 1, size(self%flex)
            n = n + int(self%flex(f)%mass_matrix%nnz)
        end do
        do f = 1, size(self%chains)
            n = n + self%chains(f)%nv**2
        end do
        do f = 1, size(self%modal)
            n = n + self%modal(f)%nv**2
        end do
        allocate (rows(n), cols(n))
        n = 0
        do b = 1, size(self%rigid%bodies)
            iv = rigid_body_nv * (b - 1)
            do i = 1, 3
                n = n + 1
                rows(n) = iv + i
                cols(n) = iv + i
            end do
            do j = 4, 6
                do i = 4, 6
                    n = n + 1
                    rows(n) = iv + i
                    cols(n) = iv + j
                end do
            end do
        end do
        ! chains: dense blocks M(q), column by column
        do f = 1, size(self%chains)
            do j = 1, self%chains(f)%nv
                do i = 1, self%chains(f)%nv
                    n = n + 1
                    rows(n) = self%chain_v(f) + i
                    cols(n) = self%chain_v(f) + j
                end do
            end do
        end do
        ! flexible bodies: their own mass patterns, column by column
        do f = 1, size(self%flex)
            associate (mm => self%flex(f)%mass_matrix)
                do j = 1, mm%ncol
                    do p = mm%colptr(j) + 1, mm%colptr(j + 1)
                        n = n + 1
                        rows(n) = self%flex_v(f) + int(mm%rowind(p)) + 1
                        cols(n) = self%flex_v(f) + j
                    end do
                end do
            end associate
        end do
        ! modal bodies: dense blocks M(η), column by column
        do f = 1, size(self%modal)
            do j = 1, self%modal(f)%nv
                do i = 1, self%modal(f)%nv
                    n = n + 1
                    rows(n) = self%modal_v(f) + i
                    cols(n) = self%modal_v(f) + j
                end do
            end do
        end do
        call pattern%build(self%nv, self%nv, rows, cols, status)
        if (status%ok()) self%mass_csc = pattern
    end procedure system_mass_pattern

    module procedure system_mass_sparse
        integer :: b, i, j, n, f
        integer(i8) :: p
        n = 0
        values = 0.0_wp
        do b = 1, size(self%rigid%bodies)
            do i = 1, 3
                n = n + 1
                values(self%mass_csc%triplet_map(n)) = self%rigid%bodies(b)%mass
            end do
            do j = 1, 3
                do i = 1, 3
                    n = n + 1
                    values(self%mass_csc%triplet_map(n)) = self%rigid%bodies(b)%inertia(i, j)
                end do
            end do
        end do
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), nc => self%chains(f)%nv, nq => self%chains(f)%nq)
                call self%chains(f)%mass(t, q(iq + 1:iq + nq), self%chain_vv(1:nc, 1:nc), status)
                do j = 1, nc
                    do i = 1, nc
                        n = n + 1
                        values(self%mass_csc%triplet_map(n)) = self%chain_vv(i, j)
                    end do
                end do
            end associate
        end do
        do f = 1, size(self%flex)
            associate (mm => self%flex(f)%mass_matrix)
                do p = 1, mm%nnz
                    n = n + 1
                    values(self%mass_csc%triplet_map(n)) = mm%values(p)
                end do
            end associate
        end do
        do f = 1, size(self%modal)
            associate (iq => self%modal_q(f), nc => self%modal(f)%nv, nq => self%modal(f)%nq)
                call self%modal(f)%mass(t, q(iq + 1:iq + nq), self%modal_vv(1:nc, 1:nc), status)
                do j = 1, nc
                    do i = 1, nc
                        n = n + 1
                        values(self%mass_csc%triplet_map(n)) = self%modal_vv(i, j)
                    end do
                end do
            end associate
        end do
    end procedure system_mass_sparse

    !> Pattern of G: joint k's rows times the 6 velocity columns of each of its
    !> markers' bodies (none for the ground; a set marker's 3 at each node of
    !> the set), joint by joint.
    module procedure system_constraint_jacobian_pattern
        integer, allocatable :: rows(:), cols(:)
        integer :: k, n, r, c, side, mk, b, iq, iv, nt, a
        nt = 0
        do k = 1, size(self%joints)
            do side = 1, 2
                mk = merge(self%joints(k)%marker_i, self%joints(k)%marker_j, side == 1)
                nt = nt + self%joints(k)%joint%nrows * marker_columns(self, mk, .false.) &
                    * set_size(self, mk)
            end do
        end do
        do k = 1, size(self%frames)
            nt = nt + node_frame_rows * frame_columns(self%frames(k), .false.)
        end do
        allocate (rows(nt), cols(nt))
        n = 0
        do k = 1, size(self%joints)
            do side = 1, 2
                mk = merge(self%joints(k)%marker_i, self%joints(k)%marker_j, side == 1)
                call marker_offsets(self, mk, b, iq, iv)
                do a = 1, set_size(self, mk)
                    if (is_set_marker(self, mk)) iv = set_node_offset(self, mk, a, .false.)
                    do c = 1, marker_columns(self, mk, .false.)
                        do r = 1, self%joints(k)%joint%nrows
                            n = n + 1
                            rows(n) = self%joints(k)%row0 + r
                            cols(n) = iv + c
                        end do
                    end do
                end do
            end do
        end do
        do k = 1, size(self%frames)
            do c = 1, frame_columns(self%frames(k), .false.)
                do r = 1, node_frame_rows
                    n = n + 1
                    rows(n) = self%frames(k)%row0 + r
                    cols(n) = frame_column(self%frames(k), c, .false.)
                end do
            end do
        end do
        call pattern%build(self%nc, self%nv, rows, cols, status)
        if (status%ok()) self%jacobian_csc = pattern
    end procedure system_constraint_jacobian_pattern

    module procedure system_constraint_jacobian_sparse
        real(wp) :: ct(max_rows)
        integer :: k, n, r, c, ni, nj, nr, a, ns
        n = 0
        values = 0.0_wp
        associate (ci => self%work(1)%c, cj => self%work(2)%c)
            do k = 1, size(self%joints)
                nr = self%joints(k)%joint%nrows
                call joint_first_derivatives(self, k, t, q, .false., ci, cj, ni, nj, ct)
                ! a set marker's columns once per node, weight 1/n (the pattern's order)
                ns = set_size(self, self%joints(k)%marker_i)
                do a = 1, ns
                    do c = 1, ni
                        do r = 1, nr
                            n = n + 1
                            ! added: both markers may be on one chain (one slot)
                            values(self%jacobian_csc%triplet_map(n)) = &
                                values(self%jacobian_csc%triplet_map(n)) + ci(r, c) / ns
                        end do
                    end do
                end do
                ns = set_size(self, self%joints(k)%marker_j)
                do a = 1, ns
                    do c = 1, nj
                        do r = 1, nr
                            n = n + 1
                            values(self%jacobian_csc%triplet_map(n)) = &
                                values(self%jacobian_csc%triplet_map(n)) + cj(r, c) / ns
                        end do
                    end do
                end do
            end do
        end associate
        do k = 1, size(self%frames)
            block
                real(wp) :: fb(node_frame_rows, frame_columns(self%frames(k), .false.))
                call frame_first_derivatives(self, k, q, .false., fb)
                do c = 1, size(fb, 2)
                    do r = 1, node_frame_rows
                        n = n + 1
                        values(self%jacobian_csc%triplet_map(n)) = fb(r, c)
                    end do
                end do
            end block
        end do
    end procedure system_constraint_jacobian_sparse

    ! ------------------------------------------------ sparse derivative blocks

    module procedure system_has_sparse_derivatives
        system_has_sparse_derivatives = .true.
    end procedure system_has_sparse_derivatives

    !> Patterns of the derivative blocks (mechanical_patterns_t): rigid
    !> bodies' quaternion and gyroscopic blocks, the chains' full blocks, the
    !> flexible bodies' tangent patterns, and per joint or node frame its rows
    !> times the columns of its markers' bodies.
    module procedure system_derivative_patterns
        type(triplets_t) :: cq, rq, tk, tq, fq, fv
        integer :: b, f, k, side, mk, iq, iv, nq, nv, i, other, oq, ov, bo
        integer(i8) :: p
        call self%mass_pattern(patterns%mass, status)
        if (status%ok()) call self%constraint_jacobian_pattern(patterns%constraint_v, status)
        if (.not. status%ok()) return
        do b = 1, size(self%rigid%bodies)
            iq = rigid_body_nq * (b - 1)
            iv = rigid_body_nv * (b - 1)
            do i = 1, 3
                call tk%add(iq + i, iv + i)
            end do
            call tk%add_range(iq + 3, iv + 3, 4, 3)
            call tq%add_range(iq + 3, iq + 3, 4, 4)
            call fv%add_range(iv + 3, iv + 3, 3, 3)
        end do
        do f = 1, size(self%chains)
            nq = self%chains(f)%nq
            nv = self%chains(f)%nv
            call tk%add_range(self%chain_q(f), self%chain_v(f), nq, nv)
            call tq%add_range(self%chain_q(f), self%chain_q(f), nq, nq)
            call fq%add_range(self%chain_v(f), self%chain_q(f), nv, nq)
            call fv%add_range(self%chain_v(f), self%chain_v(f), nv, nv)
        end do
        do f = 1, size(self%flex)
            do i = 1, self%flex(f)%nv
                call tk%add(self%flex_q(f) + i, self%flex_v(f) + i)
            end do
            call fq%add_pattern(self%flex_v(f), self%flex_q(f), self%flex(f)%stiffness)
            call fv%add_pattern(self%flex_v(f), self%flex_v(f), self%flex(f)%damping)
        end do
        do f = 1, size(self%modal)
            ! T: I₃, L(p)ᵀ/2, I; ∂(T w)/∂q: the quaternion's 4 x 4; f and M w
            ! depend on η alone, f on all of v
            nq = self%modal(f)%nq
            nv = self%modal(f)%nv
            iq = self%modal_q(f)
            iv = self%modal_v(f)
            do i = 1, 3
                call tk%add(iq + i, iv + i)
            end do
            call tk%add_range(iq + 3, iv + 3, 4, 3)
            do i = 1, self%modal(f)%modes
                call tk%add(iq + 7 + i, iv + 6 + i)
            end do
            call tq%add_range(iq + 3, iq + 3, 4, 4)
            if (self%modal(f)%modes > 0) call fq%add_range(iv, iq + 7, nv, self%modal(f)%modes)
            call fv%add_range(iv, iv, nv, nv)
        end do
        do k = 1, size(self%joints)
            associate (jt => self%joints(k))
                do side = 1, 2
                    ! a set marker: its c_q, spread over the set; its side of G
                    ! is constant (no second derivative rows or columns). A
                    ! linear joint's node: its c_q alone.
                    mk = merge(jt%marker_i, jt%marker_j, side == 1)
                    if (.not. is_set_marker(self, mk)) then
                        call marker_offsets(self, mk, b, iq, iv)
                        if (jt%linear .and. b < 0) call cq%add_range(jt%row0, iq, &
                                                                     jt%joint%nrows, 3)
                        cycle
                    end if
                    do i = 1, set_size(self, mk)
                        call cq%add_range(jt%row0, set_node_offset(self, mk, i, .true.), &
                                          jt%joint%nrows, 3)
                    end do
                end do
                if (jt%linear) cycle ! c_q only (constant)
                do side = 1, 2
                    mk = merge(jt%marker_i, jt%marker_j, side == 1)
                    call marker_offsets(self, mk, b, iq, iv)
                    if (marker_columns(self, mk, .true.) == 0 .or. is_set_marker(self, mk)) &
                        cycle
                    call cq%add_range(jt%row0, iq, jt%joint%nrows, &
                                      marker_columns(self, mk, .true.))
                    do other = 1, 2
                        if (is_set_marker(self, merge(jt%marker_i, jt%marker_j, other == 1))) &
                            cycle
                        call marker_offsets(self, merge(jt%marker_i, jt%marker_j, other == 1), &
                                            bo, oq, ov)
                        call rq%add_range(iv, oq, marker_columns(self, mk, .false.), &
                            marker_columns(self, merge(jt%marker_i, jt%marker_j, other == 1), &
                                           .true.))
                    end do
                end do
            end associate
        end do
        do k = 1, size(self%frames)
            associate (fr => self%frames(k))
                do i = 1, frame_columns(fr, .true.)
                    call cq%add_range(fr%row0, frame_column(fr, i, .true.) - 1, &
                                      node_frame_rows, 1)
                    do b = 1, frame_columns(fr, .false.)
                        call rq%add(frame_column(fr, b, .false.), frame_column(fr, i, .true.))
                    end do
                end do
            end associate
        end do
        call add_element_patterns(self, fq, fv)
        call cq%build(self%nc, self%nq, patterns%constraint_q, status)
        if (status%ok()) call rq%build(self%nv, self%nq, patterns%reaction_q, status)
        if (status%ok()) call tk%build(self%nq, self%nv, patterns%kinematics, status)
        if (status%ok()) call tq%build(self%nq, self%nq, patterns%kinematics_q, status)
        if (status%ok()) call fq%build(self%nv, self%nq, patterns%force_q, status)
        if (status%ok()) call fv%build(self%nv, self%nv, patterns%force_v, status)
        if (.not. status%ok()) then
            status%message = 'mbs system: derivative patterns: ' // status%message
            return
        end if
        self%patterns = patterns
        ! the flexible bodies' tangents go in by slot, without a search per entry
        if (allocated(self%flex_slots)) deallocate (self%flex_slots)
        allocate (self%flex_slots(size(self%flex)))
        do f = 1, size(self%flex)
            associate (st => self%flex(f)%stiffness, sl => self%flex_slots(f))
                allocate (sl%q(st%nnz), sl%v(st%nnz), stat=i)
                if (i /= 0) then
                    call out_of_memory(status, 'tangent slot maps', 2_i8 * st%nnz, 8)
                    return
                end if
                do i = 1, st%ncol
                    do p = st%colptr(i) + 1, st%colptr(i + 1)
                        sl%q(p) = patterns%force_q%find(self%flex_v(f) + int(st%rowind(p)) + 1, &
                                                        self%flex_q(f) + i)
                        sl%v(p) = patterns%force_v%find(self%flex_v(f) + int(st%rowind(p)) + 1, &
                                                        self%flex_v(f) + i)
                    end do
                end do
            end associate
        end do
    end procedure system_derivative_patterns

    !> Values of T: I₃ and L(p)ᵀ/2 per rigid body, the chains' columns T e_l, I for
    !> flexible bodies.
    module procedure system_kinematics_sparse
        real(wp) :: l(3, 4)
        integer :: b, f, i, k, iq, iv
        associate (acc => self%acc(block_kin))
            call acc%start_sparse(self%patterns%kinematics)
            do b = 1, size(self%rigid%bodies)
                iq = rigid_body_nq * (b - 1)
                iv = rigid_body_nv * (b - 1)
                do i = 1, 3
                    call acc%add(iq + i, iv + i, 1.0_wp)
                end do
                l = quat_l(q(iq + 4:iq + 7))
                call acc%add_range(iq + 3, iv + 3, 0.5_wp * transpose(l))
            end do
            do f = 1, size(self%chains)
                associate (cq => self%chain_q(f), nq => self%chains(f)%nq, &
                           nv => self%chains(f)%nv)
                    do i = 1, nv
                        self%chain_unit(1:nv) = 0.0_wp
                        self%chain_unit(i) = 1.0_wp
                        call self%chains(f)%kinematics(t, q(cq + 1:cq + nq), &
                            self%chain_unit(1:nv), self%chain_rate(1:nq), status)
                        do k = 1, nq
                            call acc%add(cq + k, self%chain_v(f) + i, self%chain_rate(k))
                        end do
                    end do
                end associate
            end do
            do f = 1, size(self%flex)
                do i = 1, self%flex(f)%nv
                    call acc%add(self%flex_q(f) + i, self%flex_v(f) + i, 1.0_wp)
                end do
            end do
            do f = 1, size(self%modal)
                iq = self%modal_q(f)
                iv = self%modal_v(f)
                do i = 1, 3
                    call acc%add(iq + i, iv + i, 1.0_wp)
                end do
                l = quat_l(q(iq + 4:iq + 7))
                call acc%add_range(iq + 3, iv + 3, 0.5_wp * transpose(l))
                do i = 1, self%modal(f)%modes
                    call acc%add(iq + 7 + i, iv + 6 + i, 1.0_wp)
                end do
            end do
            call acc%get_values(values, 'mbs system: T', status)
        end associate
    end procedure system_kinematics_sparse

    !> ∂(T w)/∂q: the quaternion blocks of the rigid bodies, the chains' blocks.
    module procedure system_kinematics_derivative_sparse
        integer :: b, f, iq, iv
        associate (acc => self%acc(block_kinq))
            call acc%start_sparse(self%patterns%kinematics_q)
            do b = 1, size(self%rigid%bodies)
                iq = rigid_body_nq * (b - 1)
                iv = rigid_body_nv * (b - 1)
                call acc%add_range(iq + 3, iq + 3, quaternion_rate_derivative(w(iv + 4:iv + 6)))
            end do
            do f = 1, size(self%chains)
                associate (cq => self%chain_q(f), cv => self%chain_v(f), &
                           nq => self%chains(f)%nq, nv => self%chains(f)%nv)
                    call self%chains(f)%kinematics_derivative(t, q(cq + 1:cq + nq), &
                        w(cv + 1:cv + nv), self%chain_qq(1:nq, 1:nq), status)
                    call acc%add_range(cq, cq, self%chain_qq(1:nq, 1:nq))
                end associate
            end do
            do f = 1, size(self%modal)
                iq = self%modal_q(f)
                iv = self%modal_v(f)
                call acc%add_range(iq + 3, iq + 3, quaternion_rate_derivative(w(iv + 4:iv + 6)))
            end do
            call acc%get_values(values, 'mbs system: d(T w)/dq', status)
        end associate
    end procedure system_kinematics_derivative_sparse

    module procedure system_mass_derivative_sparse
        call self%acc(block_fq)%start_sparse(self%patterns%force_q)
        call mass_derivative_into(self, t, q, w, self%acc(block_fq), status)
        call self%acc(block_fq)%get_values(values, 'mbs system: d(M w)/dq', status)
    end procedure system_mass_derivative_sparse

    !> ∂f/∂q, ∂f/∂v: gyroscopic blocks, the chains' blocks, the force
    !> elements' blocks, and −∂k/∂q, −∂k/∂v of the flexible bodies from their
    !> analytic tangents.
    module procedure system_force_derivatives_sparse
        type(status_t) :: local
        integer :: b, iv
        integer(i8) :: p
        associate (aq => self%acc(block_fq), av => self%acc(block_fv))
            call aq%start_sparse(self%patterns%force_q)
            call av%start_sparse(self%patterns%force_v)
            do b = 1, size(self%rigid%bodies)
                iv = rigid_body_nv * (b - 1)
                call av%add_range(iv + 3, iv + 3, gyroscopic_derivative( &
                    self%rigid%bodies(b)%inertia, v(iv + 4:iv + 6)))
            end do
            do b = 1, size(self%chains)
                associate (cq => self%chain_q(b), cv => self%chain_v(b), &
                           nq => self%chains(b)%nq, nv => self%chains(b)%nv)
                    call self%chains(b)%force_derivatives(t, q(cq + 1:cq + nq), &
                        v(cv + 1:cv + nv), self%chain_vq(1:nv, 1:nq), &
                        self%chain_vv(1:nv, 1:nv), status)
                    call aq%add_range(cv, cq, self%chain_vq(1:nv, 1:nq))
                    call av%add_range(cv, cv, self%chain_vv(1:nv, 1:nv))
                end associate
            end do
            do b = 1, size(self%modal)
                associate (mq => self%modal_q(b), mv => self%modal_v(b), &
                           nq => self%modal(b)%nq, nv => self%modal(b)%nv, &
                           nm => self%modal(b)%modes)
                    call self%modal(b)%force_derivatives(t, q(mq + 1:mq + nq), &
                        v(mv + 1:mv + nv), self%modal_vq(1:nv, 1:nq), &
                        self%modal_vv(1:nv, 1:nv), status)
                    ! ∂f/∂q lies in the η columns (the pattern's)
                    if (nm > 0) call aq%add_range(mv, mq + 7, self%modal_vq(1:nv, 8:nq))
                    call av%add_range(mv, mv, self%modal_vv(1:nv, 1:nv))
                end associate
            end do
            do b = 1, size(self%flex)
                associate (fq0 => self%flex_q(b), fv0 => self%flex_v(b), n => self%flex(b)%nv)
                    call self%flex(b)%assemble_tangents(q(fq0 + 1:fq0 + n), v(fv0 + 1:fv0 + n), &
                                                        local)
                    if (.not. local%ok()) then
                        status = local
                        return
                    end if
                end associate
            end do
            call add_element_derivatives(self, t, q, v, aq, av, status)
            if (.not. status%ok()) return
            call aq%get_values(fq, 'mbs system: df/dq', status)
            call av%get_values(fv, 'mbs system: df/dv', status)
        end associate
        ! −∂k/∂q, −∂k/∂v of the flexible bodies by their slot maps
        do b = 1, size(self%flex)
            associate (sl => self%flex_slots(b), st => self%flex(b)%stiffness, &
                       dm => self%flex(b)%damping)
                do p = 1, st%nnz
                    fq(sl%q(p)) = fq(sl%q(p)) - st%values(p)
                    fv(sl%v(p)) = fv(sl%v(p)) - dm%values(p)
                end do
            end associate
        end do
    end procedure system_force_derivatives_sparse

    module procedure system_constraint_position_jacobian_sparse
        call self%acc(block_cq)%start_sparse(self%patterns%constraint_q)
        call assemble_first_derivative(self, t, q, .true., self%acc(block_cq))
        call self%acc(block_cq)%get_values(values, 'mbs system: g_q', status)
    end procedure system_constraint_position_jacobian_sparse

    !> Nodes a set marker spreads its columns over; 1 for any other marker.
    pure integer function set_size(self, k) result(n)
        class(mbs_system_t), intent(in) :: self
        integer, intent(in) :: k
        n = 1
        if (is_set_marker(self, k)) n = size(self%markers(k)%nodes)
    end function set_size
end submodule flexmbs_mbs_system_patterns
