!> /y_labels and /y_units of a scene's HDF5 file: every component of y by
!> name and SI unit, from the formulation's blocks and the system's parts
!> (the rigid bodies and node frames, the chains' links, the flexible
!> bodies' nodes, the modal bodies' frames and modes, the joints' rows).
module flexmbs_run_y_labels
    use flexmbs_core_status, only: status_t
    use flexmbs_core_text, only: int_text
    use flexmbs_mbs_system, only: mbs_system_t, part_rigid, part_chain, part_flexible, &
        part_modal, part_frame
    use flexmbs_mbs_primitive_kinds, only: primitive_rows, primitive_dot1, &
        primitive_angle_driver, primitive_distance
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, chain_joint_prismatic, &
        chain_joint_spherical
    use flexmbs_mbs_formulation, only: formulation_t, block_q, block_v, block_a, &
        block_lambda, block_mu
    use flexmbs_mbs_modal_body, only: modal_body_t
    use flexmbs_io_namelist, only: scene_input_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_scene_input, only: nonlinear_body, modal_body
    use flexmbs_run_plan, only: run_plan_t
    use flexmbs_run_chain_builder, only: link_names
    implicit none
    private

    !> The name and unit of every component of y, filled part by part.
    type :: y_labels_t
        character(len=120), allocatable :: labels(:)
        character(len=12), allocatable :: units(:)
    end type y_labels_t

    public :: add_y_labels

contains

    !> /y_labels and /y_units: every component of y by name and SI unit
    !> ('crank/position/x' m, 'coupler/node 23/velocity/z' m/s,
    !> 'joints/pivot/lambda 4' N m, ...). GGL's μ has no physical unit: '-'.
    subroutine add_y_labels(h5, plan, scene, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(run_plan_t), intent(in), target :: plan
        type(scene_input_t), intent(in) :: scene
        type(status_t), intent(out) :: status
        type(y_labels_t) :: out
        integer :: n, k
        n = plan%problem%n
        allocate (out%labels(n), out%units(n))
        do k = 1, n
            write (out%labels(k), '(a,i0,a)') 'y(', k, ')'
        end do
        out%units = ''
        if (allocated(plan%mechanical)) then
            select type (f => plan%problem)
            type is (formulation_t)
                select type (m => plan%mechanical)
                type is (mbs_system_t)
                    call system_labels(out, m, f, scene, plan%joint_names)
                type is (rigid_chain_t)
                    call chain_labels(out, m, link_names(scene, 0), f%offset(block_q), &
                                      f%offset(block_v), accelerations(f))
                type is (flexible_body_t)
                    call flexible_labels(out, m, trim(scene%bodies(1)%name), f%offset(block_q), &
                                         f%offset(block_v), accelerations(f))
                end select
                if (f%block_size(block_mu) > 0) then   ! GGL: μ after λ
                    do k = 1, f%block_size(block_lambda)
                        out%labels(f%offset(block_mu) + k) = &
                            trim(out%labels(f%offset(block_lambda) + k)) // ' (mu)'
                        out%units(f%offset(block_mu) + k) = '-'
                    end do
                end if
            end select
        end if
        call h5%write_strings('y_labels', out%labels, status)
        if (status%ok()) call h5%write_strings('y_units', out%units, status)
    end subroutine add_y_labels

    !> A multibody system's: its rigid bodies and node frames, chains,
    !> flexible and modal bodies, and its joints' and frames' multipliers.
    subroutine system_labels(out, sys, f, scene, joint_names)
        type(y_labels_t), intent(inout) :: out
        type(mbs_system_t), intent(in), target :: sys
        type(formulation_t), intent(in) :: f
        type(scene_input_t), intent(in) :: scene
        !> the system's joints by name ('joints/NAME', ...; not allocated: 'joint K')
        character(len=:), allocatable, intent(in) :: joint_names(:)
        character(len=:), allocatable :: name
        integer :: i, j, r, row, row0, oq, ov, oa, ol, nc, bq, bv
        logical :: with_a
        oq = f%offset(block_q)
        ov = f%offset(block_v)
        oa = f%offset(block_a)
        ol = f%offset(block_lambda)
        nc = f%block_size(block_lambda)
        with_a = f%block_size(block_a) > 0
        do i = 1, sys%part_count(part_rigid)
            if (i <= size(scene%rigid_bodies)) then
                name = trim(scene%rigid_bodies(i)%name)
            else
                name = 'node frame ' // int_text(i - size(scene%rigid_bodies))
            end if
            call put3(out, oq + 7 * (i - 1), name // '/position', 'm')
            do j = 1, 4
                out%labels(oq + 7 * (i - 1) + 3 + j) = name // '/orientation/p' // &
                    int_text(j - 1)
                out%units(oq + 7 * (i - 1) + 3 + j) = '1'
            end do
            call put3(out, ov + 6 * (i - 1), name // '/velocity', 'm/s')
            call put3(out, ov + 6 * (i - 1) + 3, name // '/angular_velocity (body)', 'rad/s')
            if (with_a) then
                call put3(out, oa + 6 * (i - 1), name // '/acceleration', 'm/s^2')
                call put3(out, oa + 6 * (i - 1) + 3, name // '/angular_acceleration (body)', &
                          'rad/s^2')
            end if
        end do
        do i = 1, sys%chain_count()
            call sys%part_offsets(part_chain, i, bq, bv)
            call chain_labels(out, sys%chain_of(i), link_names(scene, i), oq + bq, ov + bv, &
                merge(oa + bv, -1, with_a))
        end do
        do i = 1, sys%flexible_count()
            call sys%part_offsets(part_flexible, i, bq, bv)
            call flexible_labels(out, sys%flexible_of(i), &
                trim(scene%bodies(nonlinear_body(scene, i))%name), oq + bq, ov + bv, &
                merge(oa + bv, -1, with_a))
        end do
        do i = 1, sys%part_count(part_modal)
            call sys%part_offsets(part_modal, i, bq, bv)
            call modal_labels(out, sys%modal_of(i), trim(scene%bodies(modal_body(scene, i))%name), &
                oq + bq, ov + bv, merge(oa + bv, -1, with_a))
        end do
        ! multipliers: a row's unit is the force its constraint exerts
        do i = 1, sys%joint_count()
            name = 'joint ' // int_text(i)
            if (allocated(joint_names)) then
                if (i <= size(joint_names)) name = trim(joint_names(i))
            end if
            row0 = sys%joint_first_row(i) - 1
            row = row0
            do j = 1, sys%joint_primitive_count(i)
                do r = 1, primitive_rows(sys%joint_primitive(i, j))
                    row = row + 1
                    if (row > nc) exit
                    out%labels(ol + row) = name // '/lambda ' // int_text(row - row0)
                    out%units(ol + row) = multiplier_unit(sys%joint_primitive(i, j))
                end do
            end do
        end do
        do i = 1, sys%part_count(part_frame)
            row0 = sys%joint_first_row(sys%joint_count() + i) - 1
            do r = 1, 6
                row = row0 + r
                if (row > nc) exit
                out%labels(ol + row) = 'node frame ' // int_text(i) // '/lambda ' // int_text(r)
                out%units(ol + row) = merge('N  ', 'N m', r <= 3)
            end do
        end do
    end subroutine system_labels

    !> A rigid chain's links: coordinates after y(oq), rates after y(ov),
    !> their derivatives after y(oa).
    subroutine chain_labels(out, chain, names, oq, ov, oa)
        type(y_labels_t), intent(inout) :: out
        type(rigid_chain_t), intent(in) :: chain
        character(len=*), intent(in) :: names(:) !! the chain's links'
        integer, intent(in) :: oq, ov, oa   !! oa < 0: no accelerations in y
        character(len=:), allocatable :: name, unit
        integer :: i, j, lq, nq, lv, nv
        do i = 1, chain%link_count()
            name = 'link ' // int_text(i)
            if (i <= size(names)) name = trim(names(i))
            unit = 'rad'
            if (chain%link_joint(i) == chain_joint_prismatic) unit = 'm'
            if (chain%link_joint(i) == chain_joint_spherical) unit = '1'
            call chain%link_coordinates(i, lq, nq, lv, nv)
            do j = lq + 1, lq + nq
                out%labels(oq + j) = name // '/coordinate ' // int_text(j - lq)
                out%units(oq + j) = unit
            end do
            if (unit == '1') unit = 'rad'
            do j = lv + 1, lv + nv
                out%labels(ov + j) = name // '/rate ' // int_text(j - lv)
                out%units(ov + j) = unit // '/s'
                if (oa >= 0) then
                    out%labels(oa + j) = name // '/rate derivative ' // int_text(j - lv)
                    out%units(oa + j) = unit // '/s^2'
                end if
            end do
        end do
    end subroutine chain_labels

    !> A flexible body's free node coordinates, velocities and accelerations.
    subroutine flexible_labels(out, body, name, oq, ov, oa)
        type(y_labels_t), intent(inout) :: out
        type(flexible_body_t), intent(in) :: body
        character(len=*), intent(in) :: name
        integer, intent(in) :: oq, ov, oa   !! oa < 0: no accelerations in y
        character(len=1), parameter :: xyz(3) = ['x', 'y', 'z']
        integer :: i, j, d, dofs(3)
        do i = 1, body%node_count()
            dofs = body%node_dofs(i)
            do j = 1, 3
                d = dofs(j)
                if (d == 0) cycle
                out%labels(oq + d) = name // '/node ' // int_text(i) // '/' // xyz(j)
                out%units(oq + d) = 'm'
                out%labels(ov + d) = name // '/node ' // int_text(i) // '/velocity/' // xyz(j)
                out%units(ov + d) = 'm/s'
                if (oa >= 0) then
                    out%labels(oa + d) = name // '/node ' // int_text(i) // '/acceleration/' // &
                        xyz(j)
                    out%units(oa + d) = 'm/s^2'
                end if
            end do
        end do
    end subroutine flexible_labels

    !> (r, p, η), (ṙ, ω′, η̇) and their rates of a modal body.
    subroutine modal_labels(out, body, name, oq, ov, oa)
        type(y_labels_t), intent(inout) :: out
        type(modal_body_t), intent(in) :: body
        character(len=*), intent(in) :: name
        integer, intent(in) :: oq, ov, oa   !! oa < 0: no accelerations in y
        integer :: j
        call put3(out, oq, name // '/frame/position', 'm')
        do j = 1, 4
            out%labels(oq + 3 + j) = name // '/frame/orientation/p' // int_text(j - 1)
            out%units(oq + 3 + j) = '1'
        end do
        call put3(out, ov, name // '/frame/velocity', 'm/s')
        call put3(out, ov + 3, name // '/frame/angular_velocity (body)', 'rad/s')
        if (oa >= 0) then
            call put3(out, oa, name // '/frame/acceleration', 'm/s^2')
            call put3(out, oa + 3, name // '/frame/angular_acceleration (body)', 'rad/s^2')
        end if
        do j = 1, body%mode_count()
            out%labels(oq + 7 + j) = name // '/eta ' // int_text(j)
            out%units(oq + 7 + j) = 'sqrt(kg) m'
            out%labels(ov + 6 + j) = name // '/eta ' // int_text(j) // '/rate'
            out%units(ov + 6 + j) = 'sqrt(kg) m/s'
            if (oa >= 0) then
                out%labels(oa + 6 + j) = name // '/eta ' // int_text(j) // '/acceleration'
                out%units(oa + 6 + j) = 'sqrt(kg) m/s^2'
            end if
        end do
    end subroutine modal_labels

    !> Three components x, y, z of `base` after y(offset).
    subroutine put3(out, offset, base, unit)
        type(y_labels_t), intent(inout) :: out
        integer, intent(in) :: offset
        character(len=*), intent(in) :: base, unit
        character(len=1), parameter :: xyz(3) = ['x', 'y', 'z']
        integer :: j
        do j = 1, 3
            out%labels(offset + j) = base // '/' // xyz(j)
            out%units(offset + j) = unit
        end do
    end subroutine put3

    !> Where the accelerations start in y, -1 when y has none.
    pure integer function accelerations(f) result(oa)
        type(formulation_t), intent(in) :: f
        oa = -1
        if (f%block_size(block_a) > 0) oa = f%offset(block_a)
    end function accelerations

    !> The unit of the multiplier of a constraint row of primitive `kind`:
    !> the generalised force of a position (m) or direction (1) constraint.
    pure function multiplier_unit(kind) result(unit)
        integer, intent(in) :: kind
        character(len=12) :: unit
        select case (kind)
        case (primitive_dot1, primitive_angle_driver)
            unit = 'N m'      ! a direction or angle: a torque
        case (primitive_distance)
            unit = 'N/m'      ! |d|^2 - s^2 (m^2)
        case default
            unit = 'N'        ! a position (spherical, dot2, translation)
        end select
    end function multiplier_unit
end module flexmbs_run_y_labels
