!> A run's end state for people: per rigid body its position and how far it
!> has turned (degrees, about which axis), per chain link its joint
!> coordinate, per revolute or prismatic joint its angle or displacement,
!> per flexible body its largest displacement and von Mises stress. Lines
!> of text, empty for problems without bodies (their state is short: the
!> command line prints it instead).
module flexmbs_run_summary
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: real_text, int_text
    use flexmbs_mbs_rigid_body, only: rigid_body_nq
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, chain_joint_prismatic, &
        chain_joint_spherical
    use flexmbs_mbs_system, only: mbs_system_t, part_chain, part_flexible, part_modal
    use flexmbs_mbs_joint_types, only: joint_has_angle, joint_displaced_axes
    use flexmbs_mbs_formulation, only: block_q, block_v
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_scene_input, only: nonlinear_body, modal_body
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_run_plan, only: run_plan_t
    use flexmbs_run_named_output, only: joint_angle
    use flexmbs_run_chain_builder, only: link_names
    implicit none
    private

    real(wp), parameter :: degrees = 45.0_wp / atan(1.0_wp)
    character, parameter :: nl = new_line('a')

    public :: state_summary

contains

    !> The summary of state y of the plan's model (module header).
    function state_summary(plan, scene, y) result(text)
        type(run_plan_t), intent(inout), target :: plan
        type(scene_input_t), intent(in) :: scene
        real(wp), intent(in) :: y(:)
        character(len=:), allocatable :: text
        integer :: i, k, oq, ov, pq, pv
        type(rigid_chain_t), pointer :: chain
        type(flexible_body_t), pointer :: body
        type(modal_body_t), pointer :: modal
        text = ''
        if (.not. allocated(plan%mechanical)) return
        select type (f => plan%problem)
        type is (formulation_t)
            oq = f%offset(block_q)
            ov = f%offset(block_v)
            select type (m => plan%mechanical)
            type is (mbs_system_t)
                do i = 1, size(scene%rigid_bodies)
                    text = text // body_line(trim(scene%rigid_bodies(i)%name), &
                        y(oq + rigid_body_nq * (i - 1) + 1:oq + rigid_body_nq * i))
                end do
                do i = 1, m%part_count(part_chain)
                    chain => m%chain_of(i)
                    call m%part_offsets(part_chain, i, pq, pv)
                    text = text // chain_lines(chain, y(oq + pq + 1:oq + pq + chain%nq), &
                                               link_names(scene, i))
                end do
                if (allocated(plan%joint_names)) then
                    do k = 1, min(size(plan%joint_names), m%joint_count())
                        text = text // joint_line(m, k, plan%joint_names(k), &
                                                  y(oq + 1:oq + m%nq))
                    end do
                end if
                do i = 1, m%part_count(part_flexible)
                    body => m%flexible_of(i)
                    call m%part_offsets(part_flexible, i, pq, pv)
                    text = text // flexible_line(body, &
                        trim(scene%bodies(nonlinear_body(scene, i))%name), &
                        y(oq + pq + 1:oq + pq + body%nq), y(ov + pv + 1:ov + pv + body%nv))
                end do
                do i = 1, m%part_count(part_modal)
                    modal => m%modal_of(i)
                    call m%part_offsets(part_modal, i, pq, pv)
                    text = text // modal_line(modal, &
                        trim(scene%bodies(modal_body(scene, i))%name), &
                        y(oq + pq + 1:oq + pq + modal%nq), y(ov + pv + 1:ov + pv + modal%nv))
                end do
            type is (rigid_chain_t)
                text = chain_lines(m, y(oq + 1:oq + m%nq), link_names(scene, 0))
            type is (flexible_body_t)
                text = flexible_line(m, trim(scene%bodies(1)%name), y(oq + 1:oq + m%nq), &
                                     y(ov + 1:ov + m%nv))
            end select
        end select

    contains

        !> The names, those of the chain's links, in order
        function chain_lines(chain, q, names) result(lines)
            type(rigid_chain_t), intent(in) :: chain
            real(wp), intent(in) :: q(:)
            character(len=*), intent(in) :: names(:)
            character(len=:), allocatable :: lines
            character(len=:), allocatable :: name
            integer :: j, lq, nq, lv, nv
            lines = ''
            do j = 1, chain%link_count()
                name = 'link ' // int_text(j)
                if (j <= size(names)) name = trim(names(j))
                call chain%link_coordinates(j, lq, nq, lv, nv)
                associate (c => q(lq + 1:lq + nq))
                    select case (chain%link_joint(j))
                    case (chain_joint_prismatic)
                        lines = lines // '  ' // name // ': joint displacement ' // &
                            fixed(c(1), 4) // ' m' // nl
                    case (chain_joint_spherical)
                        lines = lines // '  ' // name // ': turned ' // &
                            fixed(turn_angle(c) * degrees, 2) // ' deg about (' // &
                            axis_text(c) // ') from its parent' // nl
                    case default
                        lines = lines // '  ' // name // ': joint angle ' // &
                            fixed(c(1) * degrees, 2) // ' deg' // nl
                    end select
                end associate
            end do
        end function chain_lines
    end function state_summary

    !> 'crank: at (x, y, z) m, turned A deg about (ax, ay, az)'
    function body_line(name, qb) result(line)
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: qb(7)   !! r, p
        character(len=:), allocatable :: line
        line = '  ' // name // ': at (' // fixed(qb(1), 4) // ', ' // fixed(qb(2), 4) // ', ' &
            // fixed(qb(3), 4) // ') m, turned ' // fixed(turn_angle(qb(4:7)) * degrees, 2) // &
            ' deg about (' // axis_text(qb(4:7)) // ')' // nl
    end function body_line

    !> A joint's angle and displacement as its type has them (a revolute
    !> joint's angle, a prismatic one's displacement, a planar one's angle
    !> and (x, y) in marker i's plane); nothing for the other types.
    function joint_line(sys, k, group_name, q) result(line)
        type(mbs_system_t), intent(in) :: sys
        integer, intent(in) :: k
        character(len=*), intent(in) :: group_name  !! 'joints/NAME' | 'drivers/NAME'
        real(wp), intent(in) :: q(:)
        character(len=:), allocatable :: line
        real(wp) :: xi(3), xj(3), ai(3, 3), aj(3, 3)
        logical :: angle, displaced(3)
        character(len=:), allocatable :: name, values
        integer :: a, markers(2)
        line = ''
        name = trim(group_name(index(group_name, '/') + 1:))
        angle = joint_has_angle(sys%joint_kind(k))
        displaced = joint_displaced_axes(sys%joint_kind(k))
        if (.not. (angle .or. any(displaced))) return
        markers = sys%joint_markers(k)
        call sys%marker_pose(markers(1), q, xi, ai)
        call sys%marker_pose(markers(2), q, xj, aj)
        if (angle) line = '  ' // name // ': angle ' // &
            fixed(joint_angle(ai, aj) * degrees, 2) // ' deg' // nl
        if (.not. any(displaced)) return
        values = ''
        do a = 1, 3
            if (.not. displaced(a)) cycle
            if (len(values) > 0) values = values // ', '
            values = values // fixed(dot_product(xj - xi, ai(:, a)), 4)
        end do
        if (count(displaced) > 1) values = '(' // values // ')'
        line = line // '  ' // name // ': displacement ' // values // ' m' // nl
    end function joint_line

    !> 'coupler: largest displacement D m (node N), largest von Mises stress S Pa'
    !> flexible_line of a modal body's reconstructed nodes.
    function modal_line(body, name, q, v) result(line)
        type(modal_body_t), intent(inout), target :: body
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: q(:), v(:)
        character(len=:), allocatable :: line
        type(flexible_body_t), pointer :: fe
        real(wp), allocatable :: x(:), xd(:)
        fe => body%fe_body()
        allocate (x(3 * fe%node_count()), xd(3 * fe%node_count()))
        call body%node_positions(q, x)
        call body%node_velocities(q, v, xd)
        line = flexible_line(fe, name // ' (modal)', x, xd)
    end function modal_line

    function flexible_line(body, name, q, v) result(line)
        type(flexible_body_t), intent(inout) :: body
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: q(:), v(:)
        character(len=:), allocatable :: line
        real(wp), allocatable :: sigma(:, :), mises(:)
        real(wp) :: u(3), largest, displacements(3 * body%node_count())
        type(status_t) :: status
        integer :: i, at
        largest = 0.0_wp
        at = 0
        call body%nodal_values(q, .true., displacements)
        do i = 1, body%node_count()
            u = displacements(3 * i - 2:3 * i)
            if (norm2(u) > largest .or. at == 0) then
                largest = norm2(u)
                at = i
            end if
        end do
        line = '  ' // name // ': largest displacement ' // real_text(largest) // ' m (node ' &
            // int_text(at) // ')'
        allocate (sigma(6, body%element_count()), mises(body%element_count()))
        call body%element_stress(q, v, sigma, mises, status)
        if (status%ok() .and. size(mises) > 0) line = line // ', largest von Mises stress ' // &
            real_text(maxval(mises)) // ' Pa (element ' // &
            int_text(maxloc(mises, 1)) // ')'
        line = line // nl
    end function flexible_line

    !> The rotation angle of quaternion p (normalised), in [0, π].
    pure real(wp) function turn_angle(p) result(angle)
        real(wp), intent(in) :: p(4)
        real(wp) :: s
        s = norm2(p(2:4))
        angle = 2.0_wp * atan2(s, abs(p(1)))
    end function turn_angle

    !> The unit rotation axis of p, or (0, 0, 0) for no rotation.
    function axis_text(p) result(text)
        real(wp), intent(in) :: p(4)
        character(len=:), allocatable :: text
        real(wp) :: a(3)
        a = 0.0_wp
        if (norm2(p(2:4)) > 0.0_wp) a = sign(1.0_wp, p(1)) * p(2:4) / norm2(p(2:4))
        text = fixed(a(1), 3) // ', ' // fixed(a(2), 3) // ', ' // fixed(a(3), 3)
    end function axis_text

    !> x with `digits` decimals, no blanks.
    function fixed(x, digits) result(text)
        real(wp), intent(in) :: x
        integer, intent(in) :: digits
        character(len=:), allocatable :: text
        character(len=40) :: buffer
        character(len=12) :: form
        write (form, '(a,i0,a)') '(f0.', digits, ')'
        ! no '-0.000': what rounds to zero is written as zero
        if (abs(x) < 0.5_wp * 10.0_wp**(-digits)) then
            write (buffer, form) 0.0_wp
        else
            write (buffer, form) x
        end if
        text = trim(adjustl(buffer))
        if (text(1:1) == '.') text = '0' // text
        if (len(text) > 1) then
            if (text(1:2) == '-.') text = '-0' // text(2:)
        end if
        if (text(len(text):len(text)) == '.') text = text(1:len(text) - 1)
    end function fixed
end module flexmbs_run_summary
