!> det F <= 0 is a distinct failure in every solver: a trial state with an
!> inverted element is rejected (the step shrinks), never accepted; a run
!> that cannot avoid it fails with reason_det_f.
!>
!> The crushed cube: one 8-node element on a fixed base, its top driven
!> down at 20 m/s, undamped. The neo-Hookean energy grows without bound as
!> J -> 0 (−μ ln J), so the exact motion bounces back with det F > 0, while
!> a first step of 0.05 s would carry the top 1 m through the base.
module test_fe_detf
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_solver_failure, reason_det_f
    use flexmbs_fe_hexahedron, only: hex8
    use flexmbs_fe_neo_hooke, only: neo_hooke_t, new_neo_hooke
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use flexmbs_mbs_formulation, only: formulation_t, new_formulation, formulation_index2
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_solver, only: dae_solver_t
    use flexmbs_dae_radau5, only: radau5_t
    use flexmbs_dae_ddassl, only: ddassl_t
    use flexmbs_dae_ida, only: ida_t
    use flexmbs_dae_mexax, only: mexax_t
    use testing, only: test_case_t, new_test, error_t, check
    implicit none
    private
    public :: collect_fe_detf

    !> The body, counting the trial states it refuses (det F <= 0) in
    !> forces and in the acceptance test.
    type, extends(flexible_body_t) :: counting_body_t
        integer :: refusals = 0
    contains
        procedure :: forces => counting_forces
        procedure :: admissible => counting_admissible
    end type counting_body_t

    !> Checks every accepted state and output: the body must admit it.
    type, extends(sink_t) :: admit_sink_t
        type(counting_body_t), pointer :: body => null()
        integer :: nq = 0
        integer :: states = 0, refused = 0
        real(wp) :: min_height = huge(1.0_wp)
    contains
        procedure :: output => admit_output
        procedure :: wants_steps => admit_wants_steps
        procedure :: step => admit_step
    end type admit_sink_t

    real(wp), parameter :: speed = 20.0_wp   !! m/s, downwards, of the top face
    !> RADAU5's first Newton steps are damped by the stiffness; a harder
    !> blow makes it meet inverted stage values too.
    real(wp), parameter :: radau5_speed = 100.0_wp
    real(wp), parameter :: t_end = 0.05_wp

contains

    function collect_fe_detf() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('crushed_cube_radau5', test_radau5), &
                 new_test('crushed_cube_ddassl', test_ddassl), &
                 new_test('crushed_cube_ida', test_ida), &
                 new_test('crushed_cube_mexax', test_mexax), &
                 new_test('inverted_start_fails', test_inverted_start)]
    end function collect_fe_detf

    !> The cube [0, 0.1]³ of a soft undamped material, base (zmin) fixed;
    !> q0 = X, v0 = −v_top on the top nodes (z) and 0 elsewhere.
    subroutine make_cube(body, q0, v0, status, v_top)
        type(counting_body_t), target, intent(out) :: body
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        real(wp), intent(in) :: v_top !! downwards speed of the top face
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat
        integer, allocatable :: base(:), top(:)
        integer :: i
        call new_neo_hooke(mat, 7.0e5_wp, 0.3_wp, 920.0_wp, 0.0_wp, status)
        if (status%ok()) call box_mesh(mesh, hex8, [1, 1, 1], [0.1_wp, 0.1_wp, 0.1_wp], status)
        if (status%ok()) call mesh%node_set('zmin', base, status)
        if (status%ok()) call mesh%node_set('zmax', top, status)
        if (status%ok()) call new_flexible_body(body%flexible_body_t, mesh, [mat], base, status)
        if (.not. status%ok()) return
        q0 = body%free_positions()
        allocate (v0(body%nv), source=0.0_wp)
        do i = 1, size(top)
            v0(body%dof(3, top(i))) = -v_top
        end do
    end subroutine make_cube

    subroutine counting_forces(self, t, q, v, f, status)
        class(counting_body_t), intent(inout) :: self
        real(wp), intent(in) :: t, q(:), v(:)
        real(wp), intent(out) :: f(:)
        type(status_t), intent(inout) :: status
        call self%flexible_body_t%forces(t, q, v, f, status)
        if (status%reason == reason_det_f) self%refusals = self%refusals + 1
    end subroutine counting_forces

    subroutine counting_admissible(self, q, status)
        class(counting_body_t), intent(inout) :: self
        real(wp), intent(in) :: q(:)
        type(status_t), intent(out) :: status
        call self%flexible_body_t%admissible(q, status)
        if (status%reason == reason_det_f) self%refusals = self%refusals + 1
    end subroutine counting_admissible

    subroutine admit(self, y)
        class(admit_sink_t), intent(inout) :: self
        real(wp), intent(in) :: y(:)
        type(status_t) :: st
        self%states = self%states + 1
        call self%body%flexible_body_t%admissible(y(1:self%nq), st)
        if (.not. st%ok()) self%refused = self%refused + 1
        self%min_height = min(self%min_height, minval(y(3:self%nq:3)))
    end subroutine admit

    subroutine admit_output(self, t, y, status)
        class(admit_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        call admit(self, y)
    end subroutine admit_output

    logical function admit_wants_steps(self)
        class(admit_sink_t), intent(in) :: self
        admit_wants_steps = .true.
    end function admit_wants_steps

    subroutine admit_step(self, nr, t_old, t, y, dense, stop, status)
        class(admit_sink_t), intent(inout) :: self
        integer, intent(in) :: nr
        real(wp), intent(in) :: t_old, t, y(:)
        class(dense_output_t), intent(in) :: dense
        logical, intent(inout) :: stop
        type(status_t), intent(inout) :: status
        call admit(self, y)
    end subroutine admit_step

    !> Run `solver` through the formulation (or MEXAX directly) from a first
    !> step of t_end; every state it reports must be admissible, and it
    !> either finishes with refused trial steps behind it (rejections) and
    !> the top bounced back up, or fails with reason_det_f.
    subroutine crush(error, solver, name, v_top)
        type(error_t), allocatable, intent(inout) :: error
        class(dae_solver_t), intent(inout) :: solver
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: v_top
        type(counting_body_t), target :: body
        type(formulation_t) :: dae
        type(admit_sink_t) :: sink
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), y(:)
        real(wp) :: t
        integer :: nq
        call make_cube(body, q0, v0, status, v_top)
        call check(error, status%ok(), name // ': setup: ' // status%text())
        if (allocated(error)) return
        nq = body%nq
        options%rtol = 1.0e-5_wp
        options%atol = 1.0e-7_wp
        options%h0 = t_end
        options%output_times = [0.0_wp, t_end]
        sink%body => body
        sink%nq = nq
        t = 0.0_wp
        select type (solver)
        type is (mexax_t)
            y = [q0, v0]
            call solver%integrate_mechanical(body, t, y(1:nq), y(nq + 1:), t_end, options, &
                                             stats, status, sink)
        class default
            dae = new_formulation(body, formulation_index2, q0, constant_mass=.true., &
                                  status=status)
            call check(error, status%ok(), name // ': formulation: ' // status%text())
            if (allocated(error)) return
            allocate (y(dae%n), source=0.0_wp)
            y(1:nq) = q0
            y(nq + 1:2 * nq) = v0
            call solver%integrate(dae, t, y, t_end, options, stats, status, sink)
        end select
        print '(4x,a,a,i0,a,i0,a,i0,a,i0,a,f7.4,a,a)', name, ': NST=', stats%nst, ' NRJ=', &
            stats%nrj, ' refused trial states=', body%refusals, ' accepted=', sink%states, &
            ', lowest top z=', sink%min_height, ' m; ', &
            trim(merge('ok    ', 'failed', status%ok()))
        call check(error, body%refusals > 0, name // ': no trial state was refused')
        call check(error, sink%states > 0 .and. sink%refused == 0, &
                   name // ': an inadmissible state was accepted or output')
        if (status%ok()) then
            call check(error, stats%nrj > 0, name // ': no step was rejected')
            call check(error, sink%min_height > 0.0_wp .and. sink%min_height < 0.08_wp, &
                       name // ': the top never came near the base')
        else
            call check(error, status%code == status_solver_failure .and. &
                       status%reason == reason_det_f .and. index(status%text(), 'det F') > 0, &
                       name // ': failed for another reason: ' // status%text())
        end if
    end subroutine crush

    subroutine test_radau5(error)
        type(error_t), allocatable, intent(out) :: error
        type(radau5_t) :: solver
        call crush(error, solver, 'radau5', radau5_speed)
    end subroutine test_radau5

    subroutine test_ddassl(error)
        type(error_t), allocatable, intent(out) :: error
        type(ddassl_t) :: solver
        call crush(error, solver, 'ddassl', speed)
    end subroutine test_ddassl

    subroutine test_ida(error)
        type(error_t), allocatable, intent(out) :: error
        type(ida_t) :: solver
        call crush(error, solver, 'ida', speed)
    end subroutine test_ida

    subroutine test_mexax(error)
        type(error_t), allocatable, intent(out) :: error
        type(mexax_t) :: solver
        call crush(error, solver, 'mexax', speed)
    end subroutine test_mexax

    !> Every solver refuses an inverted initial state with reason_det_f.
    subroutine test_inverted_start(error)
        type(error_t), allocatable, intent(out) :: error
        type(counting_body_t), target :: body
        type(formulation_t) :: dae
        type(radau5_t) :: radau5
        type(ddassl_t) :: ddassl
        type(ida_t) :: ida
        type(mexax_t) :: mexax
        type(dae_options_t) :: options
        type(dae_stats_t) :: stats
        type(status_t) :: status
        real(wp), allocatable :: q0(:), v0(:), y(:)
        real(wp) :: t
        integer :: nq, k
        call make_cube(body, q0, v0, status, speed)
        if (.not. status%ok()) return
        nq = body%nq
        ! the top face pushed below the base: det F < 0 everywhere
        q0(3:nq:3) = -0.05_wp
        dae = new_formulation(body, formulation_index2, body%free_positions(), &
                              constant_mass=.true., status=status)
        options%rtol = 1.0e-5_wp
        options%atol = 1.0e-7_wp
        do k = 1, 4
            t = 0.0_wp
            y = [q0, 0.0_wp * v0]
            select case (k)
            case (1)
                call radau5%integrate(dae, t, y, t_end, options, stats, status)
            case (2)
                call ddassl%integrate(dae, t, y, t_end, options, stats, status)
            case (3)
                call ida%integrate(dae, t, y, t_end, options, stats, status)
            case (4)
                call mexax%integrate_mechanical(body, t, y(1:nq), y(nq + 1:), t_end, options, &
                                                stats, status)
            end select
            call check(error, status%code == status_solver_failure .and. &
                       status%reason == reason_det_f .and. index(status%text(), 'det F') > 0 &
                       .and. abs(t) <= 0.0_wp, 'inverted start, solver ' // achar(48 + k) // &
                       ': ' // status%text())
        end do
    end subroutine test_inverted_start
end module test_fe_detf
