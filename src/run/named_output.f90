!> The named part of a multibody scene's HDF5 file: series beside /y that
!> say what the numbers are, so that a reader needs no index arithmetic.
!>
!>   /bodies/<name>/position          (3)  m      the body's reference point
!>   /bodies/<name>/orientation       (4)  1      unit quaternion (p0, p1, p2, p3)
!>   /bodies/<name>/rotation_matrix   (9)  1      R, column by column (body to world)
!>   /bodies/<name>/velocity          (3)  m/s
!>   /bodies/<name>/angular_velocity  (3)  rad/s  in the world frame (R ω')
!>   /joints/<name>/reaction_force    (3)  N      exerted by the joint on the body
!>   /joints/<name>/reaction_torque   (3)  N m    of marker i, world frame, about
!>                                                 the marker (also /drivers/<name>/)
!>   /joints/<name>/reaction_force_j, reaction_torque_j: the same on marker j's body
!>   /joints/<name>/angle             (1)  rad    revolute, cylindrical, planar: x_j from x_i
!>                                                 about z_i
!>   /joints/<name>/displacement      (1)  m      prismatic, cylindrical: along z_i;
!>                                    (2)         planar: along x_i and y_i
!>                                                 (as flexmbs_mbs_joint_types says)
!>   /forces/<name>/force_i, torque_i (3)  N, N m the force element's on marker i's
!>                                                 body (world frame, about the marker);
!>                                                 force_j, torque_j: on marker j's
!>
!>   /chains/<link>/position, rotation_matrix, velocity, angular_velocity: as
!>                                  bodies; coordinate, rate: the joint to its
!>                                  parent (rad or m; a spherical's quaternion)
!>   /flexible/<name>/reference_nodes (3, nodes) m; connectivity (nodes of an
!>                                  element, attribute element_type); node_sets/<set>,
!>                                  element_sets/<set>
!>   /flexible/<name>/displacement    (3, nodes) m    x - X of every node
!>   /flexible/<name>/velocity        (3, nodes) m/s
!>   /flexible/<name>/stress          (6, elements) Pa  Cauchy, mean over the element
!>   /flexible/<name>/von_mises       (elements)    Pa
!>   /flexible/<name>/energy          (2)           J   strain, kinetic (src/run/flexible_output)
!>
!>   /y_labels, /y_units               every component of y by name, and its unit
!>                                  (src/run/y_labels)
!>
!> Python: `f['bodies/crank/position'][:, 2]` is the crank's z at every
!> record of /time (h5py shows the series as records × rows), and
!> `f['flexible/coupler/displacement'][:, k - 1, 0]` node k's x displacement.
module flexmbs_run_named_output
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_mbs_rotation, only: rotation_matrix
    use flexmbs_mbs_rigid_body, only: rigid_body_nq, rigid_body_nv
    use flexmbs_mbs_system, only: mbs_system_t, part_chain, part_flexible, part_modal
    use flexmbs_mbs_joint_types, only: joint_has_angle, joint_displaced_axes
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, chain_joint_prismatic, &
        chain_joint_spherical
    use flexmbs_mbs_formulation, only: formulation_t, block_q, block_v, block_lambda
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_record_values, only: record_values_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_run_plan, only: run_plan_t
    use flexmbs_run_force_output, only: add_force_output, wrench_values_t
    use flexmbs_run_flexible_output, only: add_flexible, add_modal
    use flexmbs_io_scene_input, only: nonlinear_body, modal_body
    use flexmbs_io_hdf5_text, only: path_name
    use flexmbs_run_chain_builder, only: link_names
    use flexmbs_run_y_labels, only: add_y_labels
    implicit none
    private

    integer, parameter :: body_position = 1, body_orientation = 2, body_rotation = 3, &
        body_velocity = 4, body_angular_velocity = 5

    !> A quantity of rigid body whose (r, p) start after y(iq), (ṙ, ω') after y(iv).
    type, extends(record_values_t) :: body_values_t
        integer :: what = 0, iq = 0, iv = 0
    contains
        procedure :: evaluate => body_evaluate
    end type body_values_t

    !> The reaction of joint `joint` of the system on the body of marker i
    !> (side 1) or j (side 2): force (torque = .false.) or torque, from the
    !> multipliers consistent with the record's q and v (the formulation's
    !> consistent_multipliers: more accurate than y's λ of index 2 or 3).
    type, extends(wrench_values_t) :: reaction_values_t
        type(mbs_system_t), pointer :: system => null()
        type(formulation_t), pointer :: formulation => null()
        integer :: joint = 0, oq = 0
    contains
        procedure :: evaluate => reaction_evaluate
    end type reaction_values_t


    integer, parameter :: link_position = 1, link_rotation = 2, link_velocity = 3, &
        link_angular_velocity = 4, link_coordinate = 5, link_rate = 6

    !> A quantity of link `link` of a chain whose q start after y(oq), v
    !> after y(ov). The chain's workspace holds its frames: a pointer to
    !> the plan's own chain (evaluations recompute them for their q).
    type, extends(record_values_t) :: link_values_t
        type(rigid_chain_t), pointer :: chain => null()
        integer :: what = 0, link = 0, oq = 0, ov = 0
    contains
        procedure :: evaluate => link_evaluate
    end type link_values_t

    !> The coordinates of joint `joint` between its markers, as its type has
    !> them: the angle (marker j's x axis from marker i's, about marker i's
    !> z, continued from record to record), or the displacement x_j - x_i
    !> along marker i's axes (`displaced`).
    type, extends(record_values_t) :: coordinate_values_t
        type(mbs_system_t), pointer :: system => null()
        integer :: joint = 0, oq = 0
        logical :: angle = .true.
        !> the displacement's components: along marker i's axis k where displaced(k)
        logical :: displaced(3) = .false.
        logical :: started = .false.
        real(wp) :: last = 0.0_wp
    contains
        procedure :: evaluate => coordinate_evaluate
    end type coordinate_values_t

    public :: add_named_output, joint_angle

contains

    !> The named series of a multibody plan (module header); nothing for
    !> other problems. Call before the first record.
    subroutine add_named_output(h5, plan, scene, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        type(status_t), intent(out) :: status
        type(body_values_t) :: body
        type(reaction_values_t) :: reaction
        type(coordinate_values_t) :: coordinate
        character(len=:), allocatable :: base, groups(:)
        integer :: i, k, oq, ov
        call add_y_labels(h5, plan, scene, status)
        if (.not. status%ok()) return
        if (.not. allocated(plan%mechanical)) return
        select type (sys => plan%mechanical)
        type is (flexible_body_t)
            call add_standalone(sys)
            return
        type is (rigid_chain_t)
            select type (f => plan%problem)
            type is (formulation_t)
                call add_chain(h5, sys, link_names(scene, 0), f%offset(block_q), &
                               f%offset(block_v), status)
            end select
            return
        type is (mbs_system_t)
            select type (f => plan%problem)
            type is (formulation_t)
                do i = 1, size(scene%rigid_bodies)
                    base = 'bodies/' // path_name(scene%rigid_bodies(i)%name) // '/'
                    body%iq = f%offset(block_q) + rigid_body_nq * (i - 1)
                    body%iv = f%offset(block_v) + rigid_body_nv * (i - 1)
                    call add_body(body_position, 'position', 3, 'm', 'the body''s &
                        &reference point (its centre of mass)')
                    call add_body(body_orientation, 'orientation', 4, '1', 'unit quaternion &
                        &(p0, p1, p2, p3) of the rotation body -> world')
                    call add_body(body_rotation, 'rotation_matrix', 9, '1', 'R (body -> &
                        &world), column by column: R(:,1), R(:,2), R(:,3)')
                    call add_body(body_velocity, 'velocity', 3, 'm/s', 'of the reference point')
                    call add_body(body_angular_velocity, 'angular_velocity', 3, 'rad/s', &
                        'in the world frame')
                    if (.not. status%ok()) return
                end do
                do i = 1, sys%chain_count()
                    call sys%part_offsets(part_chain, i, oq, ov)
                    call add_chain(h5, sys%chain_of(i), link_names(scene, i), &
                                   f%offset(block_q) + oq, f%offset(block_v) + ov, status)
                    if (.not. status%ok()) return
                end do
                do i = 1, sys%flexible_count()
                    call sys%part_offsets(part_flexible, i, oq, ov)
                    call add_flexible(h5, sys%flexible_of(i), &
                                      scene%bodies(nonlinear_body(scene, i))%name, &
                                      f%offset(block_q) + oq, f%offset(block_v) + ov, status)
                    if (.not. status%ok()) return
                end do
                do i = 1, sys%part_count(part_modal)
                    call sys%part_offsets(part_modal, i, oq, ov)
                    call add_modal(h5, sys%modal_of(i), scene%bodies(modal_body(scene, i))%name, &
                                   f%offset(block_q) + oq, f%offset(block_v) + ov, status)
                    if (.not. status%ok()) return
                end do
                allocate (character(len=80) :: groups(size(scene%forces)))
                do i = 1, size(scene%forces)
                    groups(i) = 'forces/' // path_name(scene%forces(i)%name) // '/'
                end do
                call add_force_output(h5, sys, groups, f%offset(block_q), f%offset(block_v), &
                                      status)
                if (.not. status%ok()) return
                if (.not. allocated(plan%joint_names) .or. f%block_size(block_lambda) == 0) &
                    return
                reaction%system => sys
                reaction%formulation => f
                reaction%oq = f%offset(block_q)
                do k = 1, min(size(plan%joint_names), sys%joint_count())
                    reaction%joint = k
                    base = group_path(plan%joint_names(k)) // '/'
                    call add_reaction(1, .false., 'reaction_force', 'N', 'marker i')
                    call add_reaction(1, .true., 'reaction_torque', 'N m', 'marker i')
                    call add_reaction(2, .false., 'reaction_force_j', 'N', 'marker j')
                    call add_reaction(2, .true., 'reaction_torque_j', 'N m', 'marker j')
                    if (.not. status%ok()) return
                    call add_coordinates(sys%joint_kind(k))
                end do
            end select
        end select

    contains

        !> A flexible body alone: its formulation's y = (q, v[, λ]).
        subroutine add_standalone(b)
            type(flexible_body_t), intent(in), target :: b
            select type (f => plan%problem)
            type is (formulation_t)
                call add_flexible(h5, b, scene%bodies(1)%name, f%offset(block_q), &
                                  f%offset(block_v), status)
            end select
        end subroutine add_standalone

        !> angle and/or displacement of joint k as its type has them
        subroutine add_coordinates(kind)
            integer, intent(in) :: kind
            logical :: displaced(3)
            if (.not. status%ok()) return
            displaced = joint_displaced_axes(kind)
            coordinate%system => reaction%system
            coordinate%joint = k
            coordinate%oq = reaction%oq
            coordinate%displaced = displaced
            if (joint_has_angle(kind)) then
                coordinate%angle = .true.
                call h5%add_series(base // 'angle', 1, 'rad', coordinate, status, 'marker &
                    &j''s x axis from marker i''s, about marker i''s z axis (continued past &
                    &+-pi)')
            end if
            if (.not. status%ok()) return
            if (any(displaced)) then
                coordinate%angle = .false.
                call h5%add_series(base // 'displacement', count(displaced), 'm', &
                    coordinate, status, 'of marker j from marker i along marker i''s ' // &
                    axes_text(displaced))
            end if
        end subroutine add_coordinates

        subroutine add_body(what, name, rows, unit, description)
            integer, intent(in) :: what, rows
            character(len=*), intent(in) :: name, unit, description
            if (.not. status%ok()) return
            body%what = what
            call h5%add_series(base // name, rows, unit, body, status, description)
        end subroutine add_body

        subroutine add_reaction(side, torque, name, unit, marker)
            integer, intent(in) :: side
            logical, intent(in) :: torque
            character(len=*), intent(in) :: name, unit, marker
            character(len=:), allocatable :: description
            if (.not. status%ok()) return
            reaction%side = side
            reaction%torque = torque
            description = 'exerted by the joint on the body of its ' // marker // ', world frame'
            if (torque) description = description // ', about the marker'
            call h5%add_series(base // name, 3, unit, reaction, status, description)
        end subroutine add_reaction
    end subroutine add_named_output


    !> The angle of marker j's x axis from marker i's, about marker i's z
    !> axis (axes as columns), in (-π, π].
    pure real(wp) function joint_angle(ai, aj) result(angle)
        real(wp), intent(in) :: ai(3, 3), aj(3, 3)
        real(wp) :: c(3)
        c = [ai(2, 1) * aj(3, 1) - ai(3, 1) * aj(2, 1), ai(3, 1) * aj(1, 1) - &
             ai(1, 1) * aj(3, 1), ai(1, 1) * aj(2, 1) - ai(2, 1) * aj(1, 1)]
        angle = atan2(dot_product(c, ai(:, 3)), dot_product(ai(:, 1), aj(:, 1)))
    end function joint_angle



    !> /chains/<link>/: each link of a rigid chain (relative coordinates)
    !> whose q start after y(oq), v after y(ov); `names` in the chain's order.
    subroutine add_chain(h5, chain, names, oq, ov, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(rigid_chain_t), intent(in), target :: chain
        character(len=*), intent(in) :: names(:)
        integer, intent(in) :: oq, ov
        type(status_t), intent(out) :: status
        type(link_values_t) :: link
        character(len=:), allocatable :: base, unit, rate_unit
        integer :: i, nc, o, nv, ov_link
        link%chain => chain
        link%oq = oq
        link%ov = ov
        do i = 1, min(size(names), chain%link_count())
            base = 'chains/' // path_name(names(i)) // '/'
            link%link = i
            call add_link(link_position, 'position', 3, 'm', 'its centre of mass')
            call add_link(link_rotation, 'rotation_matrix', 9, '1', 'R (link -> world), &
                &column by column')
            call add_link(link_velocity, 'velocity', 3, 'm/s', 'of its centre of mass')
            call add_link(link_angular_velocity, 'angular_velocity', 3, 'rad/s', &
                'in the world frame')
            call chain%link_coordinates(i, o, nc, ov_link, nv)
            select case (chain%link_joint(i))
            case (chain_joint_prismatic)
                unit = 'm'
                rate_unit = 'm/s'
            case (chain_joint_spherical)
                unit = '1'
                rate_unit = 'rad/s'
            case default
                unit = 'rad'
                rate_unit = 'rad/s'
            end select
            call add_link(link_coordinate, 'coordinate', nc, unit, 'of the joint to its &
                &parent (angle, displacement, or quaternion of a spherical joint)')
            call add_link(link_rate, 'rate', nv, rate_unit, &
                'of the joint to its parent')
            if (.not. status%ok()) return
        end do

    contains

        subroutine add_link(what, name, rows, unit, description)
            integer, intent(in) :: what, rows
            character(len=*), intent(in) :: name, unit, description
            if (.not. status%ok()) return
            link%what = what
            call h5%add_series(base // name, rows, unit, link, status, description)
        end subroutine add_link
    end subroutine add_chain

    subroutine link_evaluate(self, t, y, values, status)
        class(link_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: o(3), r(3, 3), vc(3), omega(3), centre(3)
        integer :: oq, nq, ov, nv
        associate (chain => self%chain, i => self%link)
            associate (q => y(self%oq + 1:self%oq + chain%nq), &
                       v => y(self%ov + 1:self%ov + chain%nv))
                select case (self%what)
                case (link_position)
                    call chain%body_frame(q, i, o, r)
                    centre = chain%link_centre(i)
                    values = o + matmul(r, centre)
                case (link_rotation)
                    call chain%body_frame(q, i, o, r)
                    values = reshape(r, [9])
                case (link_velocity, link_angular_velocity)
                    call chain%body_velocity(q, v, i, vc, omega)
                    if (self%what == link_velocity) then
                        values = vc
                    else
                        values = omega
                    end if
                case (link_coordinate)
                    call chain%link_coordinates(i, oq, nq, ov, nv)
                    values = q(oq + 1:oq + nq)
                case (link_rate)
                    call chain%link_coordinates(i, oq, nq, ov, nv)
                    values = v(ov + 1:ov + nv)
                end select
            end associate
        end associate
    end subroutine link_evaluate

    subroutine coordinate_evaluate(self, t, y, values, status)
        class(coordinate_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: xi(3), xj(3), ai(3, 3), aj(3, 3), angle
        integer :: k, markers(2)
        real(wp), parameter :: two_pi = 8.0_wp * atan(1.0_wp)
        associate (sys => self%system)
            markers = sys%joint_markers(self%joint)
            call sys%marker_pose(markers(1), y(self%oq + 1:self%oq + sys%nq), xi, ai)
            call sys%marker_pose(markers(2), y(self%oq + 1:self%oq + sys%nq), xj, aj)
        end associate
        if (self%angle) then
            ! continued past ±π from the record before
            angle = joint_angle(ai, aj)
            if (self%started) angle = angle + two_pi * anint((self%last - angle) / two_pi)
            self%last = angle
            self%started = .true.
            values(1) = angle
        else
            values = pack([(dot_product(xj - xi, ai(:, k)), k=1, 3)], self%displaced)
        end if
    end subroutine coordinate_evaluate

    !> 'z axis', 'x and y axes': the axes where `along` is true.
    pure function axes_text(along) result(text)
        logical, intent(in) :: along(3)
        character(len=:), allocatable :: text
        character(len=1), parameter :: xyz(3) = ['x', 'y', 'z']
        integer :: k
        text = ''
        do k = 1, 3
            if (.not. along(k)) cycle
            if (len(text) > 0) text = text // ' and '
            text = text // xyz(k)
        end do
        text = text // merge(' axes', ' axis', count(along) > 1)
    end function axes_text

    subroutine body_evaluate(self, t, y, values, status)
        class(body_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: r(3, 3)
        select case (self%what)
        case (body_position)
            values = y(self%iq + 1:self%iq + 3)
        case (body_orientation)
            values = y(self%iq + 4:self%iq + 7)
        case (body_rotation)
            r = rotation_matrix(y(self%iq + 4:self%iq + 7))
            values = reshape(r, [9])
        case (body_velocity)
            values = y(self%iv + 1:self%iv + 3)
        case (body_angular_velocity)
            r = rotation_matrix(y(self%iq + 4:self%iq + 7))
            values = matmul(r, y(self%iv + 4:self%iv + 6))
        end select
    end subroutine body_evaluate

    subroutine reaction_evaluate(self, t, y, values, status)
        class(reaction_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: force(3, 2), torque(3, 2), lambda(self%system%nc)
        call self%formulation%consistent_multipliers(t, y, lambda, status)
        if (.not. status%ok()) return
        associate (sys => self%system)
            call sys%joint_reaction(self%joint, t, y(self%oq + 1:self%oq + sys%nq), lambda, &
                                    force, torque)
        end associate
        call self%part(force, torque, values)
    end subroutine reaction_evaluate



    !> 'joints/NAME' with NAME made one path component.
    pure function group_path(joint_name) result(path)
        character(len=*), intent(in) :: joint_name
        character(len=:), allocatable :: path
        integer :: slash
        slash = index(joint_name, '/')
        path = joint_name(1:slash) // path_name(joint_name(slash + 1:))
    end function group_path
end module flexmbs_run_named_output
