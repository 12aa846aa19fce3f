!> A rigid–flexible system built through the library API (no scene file):
!> a rigid link on a revolute joint to the ground carries a soft block of
!> hexahedra whose root face is pinned to the link's end, one spherical
!> joint per node (what a scene's 'attach' joint expands into). Released at
!> rest from the horizontal, it swings down under gravity; without damping
!> the total energy (rigid kinetic and potential, the block's kinetic,
!> strain and gravity potential) is conserved. An energy sink checks that
!> at every output time, and the GGL formulation (MEXAX: its projection)
!> keeps the joints closed.
!>
!>   gfortran rigid_flexible.f90 $(pkg-config --cflags --libs flexmbs)
!>   ./a.out [SOLVER]        (radau5 by default; ddassl, ida, mexax)
!>
!> Exits non-zero when the energy drifts or a joint opens.

!> A sink that extends `sink_t` and carries what it needs: the system (for
!> its energy and its markers) and where q and v sit in the state y.
module rigid_flexible_energy
    use flexmbs, only: wp, sink_t, status_t, mbs_system_t
    implicit none
    private

    type, extends(sink_t), public :: energy_sink_t
        type(mbs_system_t), pointer :: sys => null()
        integer :: oq = 0, ov = 0     !! q = y(oq+1 : oq+nq), v = y(ov+1 : ov+nv)
        integer :: hub = 0            !! marker on the link (its axes are the link's)
        integer :: tip = 0            !! marker on a node at the block's far end
        real(wp) :: tip0(3) = 0.0_wp  !! the tip seen from the hub at the first output
        real(wp) :: e0 = 0.0_wp       !! energy at the first output
        real(wp) :: drift = 0.0_wp    !! max |E(t) - E(0)| over the outputs
        integer :: outputs = 0
    contains
        procedure :: output => energy_output
    end type energy_sink_t

    real(wp), parameter :: degree = 45.0_wp / atan(1.0_wp)

contains

    !> The link's angle, the block's deformation seen from the link (how far
    !> the tip moved in the link's frame) and the energy E(t) - E(0).
    subroutine energy_output(self, t, y, status)
        class(energy_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp) :: e, hub(3), link_axes(3, 3), tip(3), axes(3, 3), seen(3)
        associate (q => y(self%oq + 1:self%oq + self%sys%nq), &
                   v => y(self%ov + 1:self%ov + self%sys%nv))
            e = self%sys%energy(q, v)
            call self%sys%marker_pose(self%hub, q, hub, link_axes)
            call self%sys%marker_pose(self%tip, q, tip, axes)
        end associate
        seen = matmul(transpose(link_axes), tip - hub)
        self%outputs = self%outputs + 1
        if (self%outputs == 1) then
            self%e0 = e
            self%tip0 = seen
        end if
        self%drift = max(self%drift, abs(e - self%e0))
        write (*, '(a,f4.2,a,f7.1,a,f7.2,a,es9.2,a)') 't = ', t, ' s: link at', &
            atan2(link_axes(2, 1), link_axes(1, 1)) * degree, ' deg, block deformed by', &
            1000.0_wp * norm2(seen - self%tip0), ' mm at its tip, E - E0 = ', e - self%e0, ' J'
    end subroutine energy_output
end module rigid_flexible_energy

program rigid_flexible
    use flexmbs
    use rigid_flexible_energy, only: energy_sink_t
    implicit none
    real(wp), parameter :: g(3) = [0.0_wp, -9.81_wp, 0.0_wp]  ! m/s²
    real(wp), parameter :: link_length = 0.3_wp               ! m, pivot at the origin
    real(wp), parameter :: block(3) = [0.2_wp, 0.05_wp, 0.05_wp] ! m, from the link's end
    real(wp), parameter :: density = 920.0_wp                 ! kg/m³
    real(wp), parameter :: t_end = 0.5_wp, tol = 1.0e-7_wp
    ! the energy scale: total weight times the reach (link and block)
    real(wp), parameter :: reach = link_length + block(1)
    type(mesh_t) :: mesh
    type(neo_hooke_t) :: rubber
    type(flexible_body_t) :: body(1)
    type(rigid_body_t) :: link(1)
    type(marker_t), allocatable :: markers(:)
    type(mbs_joint_t), allocatable :: joints(:)
    type(mbs_system_t), target :: sys
    type(formulation_t) :: formulation
    class(dae_solver_t), allocatable :: solver
    type(energy_sink_t) :: sink
    type(solver_info_t) :: info
    type(dae_options_t) :: options
    type(dae_stats_t) :: stats
    type(status_t) :: status
    integer, allocatable :: root(:), far(:)
    real(wp), allocatable :: q0(:), y(:), yp(:), c(:)
    real(wp) :: t, weight, closure
    character(len=16) :: name
    integer :: i, n, form

    name = 'radau5'
    if (command_argument_count() >= 1) call get_command_argument(1, name)
    call new_solver(trim(name), solver, status)
    call check(status)

    ! the block: 2 x 1 x 1 hex8 elements of an undamped rubber, its root
    ! face (xmin) at the link's end, the link along x
    call box_mesh(mesh, hex8, [2, 1, 1], block, status, &
                  origin=[link_length, -block(2) / 2, -block(3) / 2])
    if (status%ok()) call new_neo_hooke(rubber, 7.0e5_wp, 0.3_wp, density, 0.0_wp, status)
    if (status%ok()) call new_flexible_body(body(1), mesh, [rubber], [integer ::], status, &
                                            gravity=g)
    if (status%ok()) call mesh%node_set('xmin', root, status)
    if (status%ok()) call mesh%node_set('xmax', far, status)
    call check(status)

    ! the link: 0.5 kg, its centre of mass halfway, inertia about the centre
    link(1)%mass = 0.5_wp
    link(1)%inertia = reshape([0.001_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.004_wp, 0.0_wp, &
                               0.0_wp, 0.0_wp, 0.004_wp], [3, 3])

    ! markers: 1 the ground pivot, 2 the link's hub (revolute about their
    ! common z axis); per root node a marker on the link at the node's
    ! place (body frame: relative to the link's centre) and one on the node;
    ! last, a node at the block's far end to watch
    n = size(root)
    allocate (markers(2 + 2 * n + 1), joints(1 + n))
    markers(1) = marker_t(0, [0.0_wp, 0.0_wp, 0.0_wp])
    markers(2) = marker_t(1, [-link_length / 2, 0.0_wp, 0.0_wp])
    joints(1) = mbs_joint_t(joint_revolute, 1, 2)
    do i = 1, n
        markers(1 + 2 * i) = marker_t(1, mesh%x(:, root(i)) - [link_length / 2, 0.0_wp, 0.0_wp])
        markers(2 + 2 * i) = marker_t(0, flexible=1, node=root(i))
        joints(1 + i) = mbs_joint_t(joint_spherical, 1 + 2 * i, 2 + 2 * i)
    end do
    markers(size(markers)) = marker_t(0, flexible=1, node=far(1))

    sys = new_mbs_system(link, markers, joints, gravity=g, status=status, flexible=body)
    call check(status)

    ! q = (link centre, unit quaternion, the block's nodal positions)
    q0 = [link_length / 2, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, &
          body(1)%free_positions()]
    ! rigid and flexible bodies have a constant mass matrix: y = (q, v, λ, μ)
    ! in the GGL formulation; a solver that integrates the mechanical form
    ! itself (MEXAX, which projects) reads y = (q, v, λ) of the index-2 one
    info = solver_info(name)
    form = merge(formulation_index2, formulation_ggl, info%mechanical_only)
    formulation = new_formulation(sys, form, q0, constant_mass=.true., status=status)
    call check(status)
    allocate (y(formulation%n), yp(formulation%n), source=0.0_wp)
    y(formulation%offset(block_q) + 1:formulation%offset(block_q) + sys%nq) = q0
    call formulation%consistent_initial(0.0_wp, y, yp, status)
    call check(status)

    options%rtol = tol
    options%atol = tol
    options%output_times = [(0.1_wp * i, i = 0, 5)]
    sink%sys => sys
    sink%oq = formulation%offset(block_q)
    sink%ov = formulation%offset(block_v)
    sink%hub = 2
    sink%tip = size(markers)
    write (*, '(a,i0,a,i0,a,i0,a)') 'rigid link + soft block: ', sys%nq, ' coordinates, ', &
        sys%nv, ' velocities, ', sys%nc, ' constraints'
    t = 0.0_wp
    call solver%integrate(sys, formulation, t, y, t_end, options, stats, status, sink)
    call check(status)

    allocate (c(sys%nc))
    call sys%constraint(t, y(formulation%offset(block_q) + 1:formulation%last(block_q)), c, &
        status)
    call check(status)
    closure = maxval(abs(c))
    weight = (link(1)%mass + density * product(block)) * norm2(g)
    write (*, '(a)') trim(name) // ': ' // stats%summary()
    write (*, '(a,es9.2,a,es9.2,a,es9.2,a)') 'energy drift ', sink%drift, ' J of ', &
        weight * reach, ' J (weight x reach); largest constraint residual ', closure
    if (sink%outputs /= 6) error stop 'not every output time reached the sink'
    if (sink%drift > 1.0e-5_wp * weight * reach) error stop 'the energy is not conserved'
    if (closure > 1.0e-8_wp) error stop 'a joint opened'

contains

    !> Stop with the library's message on any failure.
    subroutine check(status)
        type(status_t), intent(in) :: status
        if (status%ok()) return
        write (*, '(a)') status%text()
        error stop 3
    end subroutine check
end program rigid_flexible
