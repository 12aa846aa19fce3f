!> Coordinate projection (eqs. 11-12) and consistent values: the positions by
!> the simplified Newton iteration with K = [M Gᵀ; G 0], the velocities by one
!> solve, consistent (y, y') at the start, the multipliers consistent with a
!> state for the reactions, and a state's drift (module header of
!> flexmbs_mbs_formulation).
submodule (flexmbs_mbs_formulation) flexmbs_mbs_formulation_projection
    implicit none

contains

    module procedure formulation_project
        self%projection_calls = self%projection_calls + 1
        call self%mechanical%normalize(y(self%oq + 1:self%oq + self%nq))
        call project_positions(self, t, y(self%oq + 1:self%oq + self%nq), projection_epsreq, &
                               status)
        if (.not. status%ok()) return
        if (mod(self%projection_calls, max(1, self%velocity_interval)) == 0) &
            call project_velocities(self, t, y(self%oq + 1:self%oq + self%nq), &
                                    y(self%ov + 1:self%ov + self%nv), status)
    end procedure formulation_project

    !> Factor K = [M Gᵀ; G 0] at q into self%kkt (or the sparse one).
    subroutine factor_kkt(self, t, q, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        if (self%sparse) then
            call self%sp%factor_kkt(self%mechanical, t, q, status)
            self%kkt_factored = status%ok()
            return
        end if
        call self%mechanical%mass(t, q, self%m, status)
        call self%mechanical%constraint_jacobian(t, q, self%gmat, status)
        call self%kkt%assemble(self%m, self%gmat)
        call self%kkt%factor(local)
        self%kkt_factored = local%ok()
        if (.not. local%ok()) call status%set(status_solver_failure, &
            'formulation: projection matrix [M Gᵀ; G 0] is singular (redundant constraints?)', &
            reason_singular_matrix)
    end subroutine factor_kkt

    !> self%kkt_rhs ← K⁻¹ self%kkt_rhs.
    subroutine solve_kkt(self)
        class(formulation_t), intent(inout) :: self
        type(status_t) :: status
        if (self%sparse) then
            call self%sp%solve_kkt(self%kkt_rhs, status)
        else
            call self%kkt%solve(self%kkt_rhs, status)
        end if
    end subroutine solve_kkt

    !> Simplified Newton for g(t, q) = 0 with K at the starting q̃ (§3.6 step 1).
    subroutine project_positions(self, t, q, epsreq, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, epsreq
        real(wp), intent(inout) :: q(:)
        type(status_t), intent(inout) :: status
        real(wp) :: eps, eps_old
        integer :: it
        character(len=120) :: msg
        if (self%nc == 0) return
        self%q0 = q
        call factor_kkt(self, t, q, status)
        if (.not. status%ok()) return
        eps_old = huge(1.0_wp)
        do it = 0, projection_itmax - 1
            call self%mechanical%constraint(t, q, self%c, status)
            if (.not. status%ok()) return
            self%kkt_rhs(1:self%nv) = 0.0_wp
            self%kkt_rhs(self%nv + 1:) = -self%c
            call solve_kkt(self)
            call self%mechanical%kinematics(t, self%q0, self%kkt_rhs(1:self%nv), self%tq, status)
            q = q + self%tq
            eps = sqrt(sum((self%tq / (self%projection_rtol * abs(self%q0) &
                + self%projection_atol))**2) / self%nq)
            if (eps <= epsreq) return
            if (.not. (eps == eps)) exit
            ! (separate tests: Fortran does not short-circuit, and 2 huge overflows)
            if (it >= 1) then
                if (eps > 2.0_wp * eps_old) exit
            end if
            eps_old = eps
        end do
        write (msg, '(a,es10.3,a,es10.3)') 'formulation: position projection did not &
            &converge at t = ', t, ', last correction norm ', eps
        call status%set(status_solver_failure, trim(msg), reason_projection)
    end subroutine project_positions

    !> Eq. (12): v ← v + Δv with K [Δv; μ] = [0; -(G v + g_I)] at q.
    subroutine project_velocities(self, t, q, v, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        real(wp), intent(inout) :: v(:)
        type(status_t), intent(inout) :: status
        if (self%nc == 0) return
        call factor_kkt(self, t, q, status)
        if (.not. status%ok()) return
        call velocity_constraint(self, t, q, v, self%c, status)
        self%kkt_rhs(1:self%nv) = 0.0_wp
        self%kkt_rhs(self%nv + 1:) = -self%c
        call solve_kkt(self)
        v = v + self%kkt_rhs(1:self%nv)
    end subroutine project_velocities

    module procedure formulation_consistent_initial
        ! Three simplified-Newton projections, each with K refactored at its
        ! start (an outer Newton iteration), reach round-off from any start
        ! the iteration converges from.
        integer, parameter :: restarts = 3
        integer :: nv, nc, k
        nv = self%nv
        nc = self%nc
        associate (q => y(self%oq + 1:self%oq + self%nq), v => y(self%ov + 1:self%ov + nv))
            call self%mechanical%normalize(q)
            do k = 1, restarts
                call project_positions(self, t, q, projection_epsreq, status)
                if (.not. status%ok()) return
            end do
            call project_velocities(self, t, q, v, status)
            if (.not. status%ok()) return
            call solve_accelerations(self, t, q, v, status)
            if (.not. status%ok()) return
            yp = 0.0_wp
            call self%mechanical%kinematics(t, q, v, yp(self%oq + 1:self%oq + self%nq), status)
            yp(self%ov + 1:self%ov + nv) = self%kkt_rhs(1:nv)
            if (self%accelerations) y(self%oa + 1:self%oa + nv) = self%kkt_rhs(1:nv)
            y(self%ol + 1:self%ol + nc) = self%kkt_rhs(nv + 1:)
            if (self%form == formulation_ggl) y(self%om + 1:self%om + nc) = 0.0_wp
        end associate
    end procedure formulation_consistent_initial

    !> [M Gᵀ; G 0] [a; λ] = [f; -γ] at (t, q, v): a and λ in self%kkt_rhs.
    subroutine solve_accelerations(self, t, q, v, status)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        type(status_t), intent(inout) :: status
        call self%mechanical%forces(t, q, v, self%force, status)
        self%kkt_rhs(1:self%nv) = self%force
        if (self%nc > 0) then
            call self%mechanical%constraint_curvature(t, q, v, self%c, status)
            self%kkt_rhs(self%nv + 1:) = -self%c
        end if
        if (.not. status%ok()) return
        call factor_kkt(self, t, q, status)
        if (.not. status%ok()) return
        call solve_kkt(self)
    end subroutine solve_accelerations

    module procedure formulation_consistent_multipliers
        type(ieee_status_type) :: flags
        integer :: stat
        if (self%nc == 0) return
        associate (state => y(self%oq + 1:self%ov + self%nv), &
                   q => y(self%oq + 1:self%oq + self%nq), v => y(self%ov + 1:self%ov + self%nv))
            if (allocated(self%multipliers)) then
                if (t == self%multipliers_t .and. all(state == self%multipliers_state)) then
                    lambda = self%multipliers
                    return
                end if
            else
                allocate (self%multipliers_state(self%nq + self%nv), self%multipliers(self%nc), &
                          self%kkt_b(self%nv + self%nc), self%kkt_x(self%nv + self%nc), stat=stat)
                if (stat /= 0) then
                    call out_of_memory(status, 'formulation multipliers', &
                                       int(self%nq + 3 * self%nv + 3 * self%nc, i8), 8)
                    return
                end if
            end if
            self%multipliers_t = huge(1.0_wp)
            call self%mechanical%forces(t, q, v, self%force, status)
            call self%mechanical%constraint_curvature(t, q, v, self%c, status)
            if (.not. status%ok()) return
            self%kkt_b = [self%force, -self%c]
            call ieee_get_status(flags)
            if (.not. refined(self, t, q, status)) then
                if (.not. status%ok()) return
                ! a refinement given up may have overflowed on its way (a huge
                ! mass): its flags must not outlive it
                call ieee_set_status(flags)
                call factor_kkt(self, t, q, status)
                if (.not. status%ok()) return
                self%kkt_rhs = self%kkt_b
                call solve_kkt(self)
                self%kkt_x = self%kkt_rhs
            end if
            lambda = self%kkt_x(self%nv + 1:)
            self%multipliers = lambda
            self%multipliers_state = state
            self%multipliers_t = t
        end associate
    end procedure formulation_consistent_multipliers

    !> Iterative refinement of K(t, q) x = self%kkt_b into self%kkt_x with
    !> the factorization of K held: x ← x + K₀⁻¹ (b − K x). False when there
    !> is none or the corrections do not shrink fast enough to reach
    !> round-off in a few solves (then factoring K costs less).
    logical function refined(self, t, q, status) result(converged)
        class(formulation_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:)
        type(status_t), intent(inout) :: status
        ! correction relative to the solution that counts as round-off, the
        ! most solves, and the least shrinking per solve that is worth them
        real(wp), parameter :: converged_below = 1.0e-13_wp, slowest = 0.25_wp
        integer, parameter :: max_solves = 8
        real(wp) :: size_x, correction, previous
        integer :: k
        converged = .false.
        if (.not. self%kkt_factored) return
        associate (nv => self%nv, x => self%kkt_x, r => self%kkt_rhs)
            self%kkt_rhs = self%kkt_b
            call solve_kkt(self)
            x = self%kkt_rhs
            call eval_g(self, t, q, status)
            if (.not. status%ok()) return
            previous = huge(1.0_wp)
            do k = 2, max_solves
                ! r = b − K x, K = [M Gᵀ; G 0] at (t, q)
                call mass_times(self, t, q, x(1:nv), r(1:nv), status)
                if (.not. status%ok()) return
                call gt_times(self, x(nv + 1:), self%b)
                r(1:nv) = self%kkt_b(1:nv) - r(1:nv) - self%b
                call g_times(self, x(1:nv), self%c)
                r(nv + 1:) = self%kkt_b(nv + 1:) - self%c
                call solve_kkt(self)
                x = x + r
                size_x = maxval(abs(x))
                correction = maxval(abs(r))
                ! overflow (a huge mass) or NaN: not for refinement
                if (.not. (size_x <= huge(1.0_wp))) return
                if (correction <= converged_below * size_x) then
                    converged = .true.
                    return
                end if
                if (.not. (correction < slowest * previous)) return
                ! too slow to reach round-off within max_solves at this rate
                if (k > 2 .and. real(k, wp) + log(converged_below * size_x / correction) &
                    / log(correction / previous) > max_solves) return
                previous = correction
            end do
        end associate
    end function refined

    module procedure formulation_drift
        position = 0.0_wp
        velocity = 0.0_wp
        if (self%nc == 0) return
        associate (q => y(self%oq + 1:self%oq + self%nq), v => y(self%ov + 1:self%ov + self%nv))
            call self%mechanical%constraint(t, q, self%c, status)
            position = maxval(abs(self%c))
            call eval_g(self, t, q, status)
            call velocity_constraint(self, t, q, v, self%c, status)
            velocity = maxval(abs(self%c))
        end associate
    end procedure formulation_drift
end submodule flexmbs_mbs_formulation_projection
