!> A rigid chain (flexmbs_mbs_rigid_chain) from the `&rigid_chain` groups of
!> a validated scene (one group per body, parents by name) and the gravity
!> of `&multibody`; joint frames are aligned with the parent's frame
!> (R0 = I), so joint_axis is given in the parent's frame. A spherical
!> joint's coordinates are the unit quaternion of rotation_axis and
!> rotation_angle, its rates the angular_rate in the child's frame.
module flexmbs_run_chain_builder
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_mbs_inertia, only: inertia_tensor, inertia_defect
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        chain_joint_revolute, chain_joint_prismatic, chain_joint_spherical
    use flexmbs_mbs_rotation, only: quat_from_axis_angle
    use flexmbs_io_namelist, only: scene_input_t
    implicit none
    private

    public :: build_rigid_chain

contains

    !> The chain of the scene and its initial coordinates q0 and rates v0.
    subroutine build_rigid_chain(scene, chain, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        type(rigid_chain_t), intent(out) :: chain
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        type(chain_body_t), allocatable :: bodies(:)
        character(len=:), allocatable :: defect
        integer :: i, j
        allocate (bodies(size(scene%chain)), q0(0), v0(0))
        do i = 1, size(bodies)
            associate (c => scene%chain(i))
                bodies(i)%parent = 0
                do j = 1, i - 1
                    if (scene%chain(j)%name == c%parent) bodies(i)%parent = j
                end do
                select case (trim(c%joint))
                case ('prismatic'); bodies(i)%joint = chain_joint_prismatic
                case ('spherical'); bodies(i)%joint = chain_joint_spherical
                case default; bodies(i)%joint = chain_joint_revolute
                end select
                bodies(i)%joint_position = c%joint_position
                bodies(i)%axis = c%joint_axis / norm2(c%joint_axis)
                bodies(i)%centre = c%centre
                bodies(i)%mass = c%mass
                bodies(i)%inertia = inertia_tensor(c%inertia, c%inertia_products)
                defect = inertia_defect(bodies(i)%inertia)
                if (len(defect) > 0) then
                    call status%set(status_bad_input, scene%path // ': &rigid_chain ''' // &
                        trim(c%name) // ''': inertia, inertia_products: ' // defect // &
                        ' (line ' // int_text(c%line) // ')')
                    return
                end if
                if (bodies(i)%joint == chain_joint_spherical) then
                    q0 = [q0, quat_from_axis_angle(c%rotation_axis / norm2(c%rotation_axis), &
                                                   c%rotation_angle)]
                    v0 = [v0, c%angular_rate]
                else
                    q0 = [q0, c%coordinate]
                    v0 = [v0, c%rate]
                end if
            end associate
        end do
        chain = new_rigid_chain(bodies, status, gravity=scene%multibody%gravity)
        if (.not. status%ok()) call status%set(status_bad_input, scene%path // ': ' // &
                                               status%text())
    end subroutine build_rigid_chain
end module flexmbs_run_chain_builder
