!> Bodies, delegated of flexmbs_mbs_system
!> (the type and the procedures' interfaces are there).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_bodies
    implicit none

contains

    ! ------------------------------------------------ bodies (delegated)

    module procedure system_kinematics
        integer :: f
        call self%rigid%kinematics(t, q(1:self%nq_rigid), w(1:self%nv_rigid), &
                                   qdot(1:self%nq_rigid), status)
        do f = 1, size(self%chains)
            call chain_rates(self, f, q(self%chain_q(f) + 1:self%chain_q(f) + self%chains(f)%nq), &
                             w(self%chain_v(f) + 1:self%chain_v(f) + self%chains(f)%nv), &
                             qdot(self%chain_q(f) + 1:self%chain_q(f) + self%chains(f)%nq))
        end do
        ! flexible bodies: q' = v
        do f = 1, size(self%flex)
            qdot(self%flex_q(f) + 1:self%flex_q(f) + self%flex(f)%nq) = &
                w(self%flex_v(f) + 1:self%flex_v(f) + self%flex(f)%nv)
        end do
        do f = 1, size(self%modal)
            associate (iq => self%modal_q(f), iv => self%modal_v(f), nq => self%modal(f)%nq, &
                       nv => self%modal(f)%nv)
                call self%modal(f)%kinematics(t, q(iq + 1:iq + nq), w(iv + 1:iv + nv), &
                                              qdot(iq + 1:iq + nq), status)
            end associate
        end do
    end procedure system_kinematics

    module procedure system_kinematics_derivative
        integer :: f
        dq = 0.0_wp
        call self%rigid%kinematics_derivative(t, q(1:self%nq_rigid), w(1:self%nv_rigid), &
                                              dq(1:self%nq_rigid, 1:self%nq_rigid), status)
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), nq => self%chains(f)%nq, &
                       nv => self%chains(f)%nv)
                call self%chains(f)%kinematics_derivative(t, q(iq + 1:iq + nq), &
                    w(iv + 1:iv + nv), dq(iq + 1:iq + nq, iq + 1:iq + nq), status)
            end associate
        end do
        do f = 1, size(self%modal)
            associate (iq => self%modal_q(f), iv => self%modal_v(f), nq => self%modal(f)%nq, &
                       nv => self%modal(f)%nv)
                call self%modal(f)%kinematics_derivative(t, q(iq + 1:iq + nq), &
                    w(iv + 1:iv + nv), dq(iq + 1:iq + nq, iq + 1:iq + nq), status)
            end associate
        end do
    end procedure system_kinematics_derivative

    module procedure system_mass
        integer :: f
        m = 0.0_wp
        call self%rigid%mass(t, q(1:self%nq_rigid), m(1:self%nv_rigid, 1:self%nv_rigid), status)
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), n => self%chains(f)%nv, &
                       nq => self%chains(f)%nq)
                call self%chains(f)%mass(t, q(iq + 1:iq + nq), m(iv + 1:iv + n, iv + 1:iv + n), &
                                         status)
            end associate
        end do
        do f = 1, size(self%flex)
            associate (i0 => self%flex_v(f), n => self%flex(f)%nv)
                call self%flex(f)%mass_matrix%to_dense(m(i0 + 1:i0 + n, i0 + 1:i0 + n))
            end associate
        end do
        do f = 1, size(self%modal)
            associate (iq => self%modal_q(f), iv => self%modal_v(f), n => self%modal(f)%nv, &
                       nq => self%modal(f)%nq)
                call self%modal(f)%mass(t, q(iq + 1:iq + nq), m(iv + 1:iv + n, iv + 1:iv + n), &
                                        status)
            end associate
        end do
    end procedure system_mass

    module procedure system_mass_derivative
        call self%acc(block_fq)%start_dense(self%nv, self%nq)
        call mass_derivative_into(self, t, q, w, self%acc(block_fq), status)
        call self%acc(block_fq)%get_dense(dq)
    end procedure system_mass_derivative

    !> ∂(M w)/∂q added into dq: zero for rigid and flexible bodies (constant
    !> M), the chains' analytic blocks (differentiated RNEA), the modal
    !> bodies' (through η).
    module procedure mass_derivative_into
        integer :: f
        do f = 1, size(self%chains)
            associate (iq => self%chain_q(f), iv => self%chain_v(f), n => self%chains(f)%nv, &
                       nq => self%chains(f)%nq)
                call self%chains(f)%mass_derivative(t, q(iq + 1:iq + nq), w(iv + 1:iv + n), &
                                                    self%chain_vq(1:n, 1:nq), status)
                call dq%add_range(iv, iq, self%chain_vq(1:n, 1:nq))
            end associate
        end do
        do f = 1, size(self%modal)
            associate (iq => self%modal_q(f), iv => self%modal_v(f), n => self%modal(f)%nv, &
                       nq => self%modal(f)%nq)
                call self%modal(f)%mass_derivative(t, q(iq + 1:iq + nq), w(iv + 1:iv + n), &
                                                   self%modal_vq(1:n, 1:nq), status)
                ! M depends on η alone: its columns (the pattern's)
                if (nq > 7) call dq%add_range(iv, iq + 7, self%modal_vq(1:n, 8:nq))
            end associate
        end do
    end procedure mass_derivative_into

    module procedure system_forces
        integer :: b
        call self%rigid%forces(t, q(1:self%nq_rigid), v(1:self%nv_rigid), &
                               f(1:self%nv_rigid), status)
        do b = 1, size(self%chains)
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%forces(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                                           f(iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%flex)
            if (.not. status%ok()) return
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%forces(t, q(iq + 1:iq + n), v(iv + 1:iv + n), &
                                         f(iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%modal)
            associate (iq => self%modal_q(b), iv => self%modal_v(b), n => self%modal(b)%nv, &
                       nq => self%modal(b)%nq)
                call self%modal(b)%forces(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                                          f(iv + 1:iv + n), status)
            end associate
        end do
        if (status%ok()) call add_element_forces(self, t, q, v, f, status)
    end procedure system_forces

    module procedure system_force_derivatives
        integer :: b
        fq = 0.0_wp
        fv = 0.0_wp
        call self%rigid%force_derivatives(t, q(1:self%nq_rigid), v(1:self%nv_rigid), &
                                          fq(1:self%nv_rigid, 1:self%nq_rigid), &
                                          fv(1:self%nv_rigid, 1:self%nv_rigid), status)
        do b = 1, size(self%chains)
            ! the chains' analytic derivatives (differentiated RNEA)
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%force_derivatives(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                    fq(iv + 1:iv + n, iq + 1:iq + nq), fv(iv + 1:iv + n, iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%flex)
            if (.not. status%ok()) return
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%force_derivatives(t, q(iq + 1:iq + n), v(iv + 1:iv + n), &
                    fq(iv + 1:iv + n, iq + 1:iq + n), fv(iv + 1:iv + n, iv + 1:iv + n), status)
            end associate
        end do
        do b = 1, size(self%modal)
            associate (iq => self%modal_q(b), iv => self%modal_v(b), n => self%modal(b)%nv, &
                       nq => self%modal(b)%nq)
                call self%modal(b)%force_derivatives(t, q(iq + 1:iq + nq), v(iv + 1:iv + n), &
                    fq(iv + 1:iv + n, iq + 1:iq + nq), fv(iv + 1:iv + n, iv + 1:iv + n), status)
            end associate
        end do
        if (size(self%elements) == 0 .or. .not. status%ok()) return
        ! the force elements add through the dense accumulators
        associate (aq => self%acc(block_fq), av => self%acc(block_fv))
            call aq%start_dense(self%nv, self%nq)
            call av%start_dense(self%nv, self%nv)
            call aq%add_range(0, 0, fq)
            call av%add_range(0, 0, fv)
            call add_element_derivatives(self, t, q, v, aq, av, status)
            call aq%get_dense(fq)
            call av%get_dense(fv)
        end associate
    end procedure system_force_derivatives

    !> det F > 0 in every flexible body (see dae_problem_t%admissible).
    module procedure system_admissible
        integer :: b
        call status%clear()
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), n => self%flex(b)%nq)
                call self%flex(b)%admissible(q(iq + 1:iq + n), status)
            end associate
            if (.not. status%ok()) return
        end do
    end procedure system_admissible

    module procedure system_normalize
        integer :: f
        call self%rigid%normalize(q(1:self%nq_rigid))
        do f = 1, size(self%chains)
            call self%chains(f)%normalize(q(self%chain_q(f) + 1:self%chain_q(f) + &
                                            self%chains(f)%nq))
        end do
        do f = 1, size(self%modal)
            call self%modal(f)%normalize(q(self%modal_q(f) + 1:self%modal_q(f) + &
                                           self%modal(f)%nq))
        end do
    end procedure system_normalize

    !> Kinetic plus potential energy; flexible bodies add kinetic and strain
    !> energy and the potential −g·(q − X) of their constant applied forces,
    !> the force elements their springs' energy.
    module procedure system_energy
        type(status_t) :: st
        integer :: b
        real(wp) :: ek, ep
        e = rigid_body_energy(self%rigid, q(1:self%nq_rigid), v(1:self%nv_rigid))
        do b = 1, size(self%chains)
            associate (iq => self%chain_q(b), iv => self%chain_v(b), n => self%chains(b)%nv, &
                       nq => self%chains(b)%nq)
                call self%chains(b)%energy(q(iq + 1:iq + nq), v(iv + 1:iv + n), ek, ep)
            end associate
            e = e + ek + ep
        end do
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                e = e + self%flex(b)%kinetic_energy(v(iv + 1:iv + n)) &
                    + self%flex(b)%strain_energy(q(iq + 1:iq + n), st) &
                    - dot_product(self%flex(b)%applied_force, &
                                  q(iq + 1:iq + n) - self%flex(b)%free_positions())
            end associate
        end do
        do b = 1, size(self%modal)
            associate (iq => self%modal_q(b), iv => self%modal_v(b), n => self%modal(b)%nv, &
                       nq => self%modal(b)%nq)
                call self%modal(b)%energy(q(iq + 1:iq + nq), v(iv + 1:iv + n), ek, ep)
            end associate
            e = e + ek + ep
        end do
        e = e + elements_energy(self, q, v)
    end procedure system_energy

    !> The energy through the mechanical problem's binding (the reference
    !> of the flexible bodies' loads is their reference configuration).
    module procedure system_total_energy
        e = self%energy(q, v)
    end procedure system_total_energy

    !> Total linear momentum and angular momentum about the global origin.
    module procedure system_momenta
        real(wp) :: lf(3), af(3)
        integer :: b
        call rigid_body_momenta(self%rigid, q(1:self%nq_rigid), v(1:self%nv_rigid), linear, &
                                angular)
        do b = 1, size(self%flex)
            associate (iq => self%flex_q(b), iv => self%flex_v(b), n => self%flex(b)%nv)
                call self%flex(b)%momenta(q(iq + 1:iq + n), v(iv + 1:iv + n), lf, af)
            end associate
            linear = linear + lf
            angular = angular + af
        end do
        do b = 1, size(self%modal)
            associate (iq => self%modal_q(b), iv => self%modal_v(b), n => self%modal(b)%nv, &
                       nq => self%modal(b)%nq)
                call self%modal(b)%momenta(q(iq + 1:iq + nq), v(iv + 1:iv + n), lf, af)
            end associate
            linear = linear + lf
            angular = angular + af
        end do
    end procedure system_momenta
end submodule flexmbs_mbs_system_bodies
