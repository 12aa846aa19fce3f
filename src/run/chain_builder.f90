!> Rigid chains (flexmbs_mbs_rigid_chain) from the `&rigid_chain` groups of
!> a validated scene (one group per body, parents by name) and the gravity
!> of `&multibody`: every tree (the links hanging, through their parents,
!> from one link on the ground) is a chain of its own, a substructure in
!> relative coordinates; trees are numbered by their root's place in the
!> scene, links within a tree in scene order. Joint frames are aligned with the parent's frame
!> (R0 = I), so joint_axis is given in the parent's frame. A spherical
!> joint's coordinates are the unit quaternion of rotation_axis and
!> rotation_angle, its rates the angular_rate in the child's frame.
module flexmbs_run_chain_builder
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: int_text
    use flexmbs_mbs_inertia, only: inertia_tensor, inertia_defect
    use flexmbs_mbs_rigid_chain, only: rigid_chain_t, new_rigid_chain, chain_body_t, &
        new_chain_body, chain_joint_revolute, chain_joint_prismatic, chain_joint_spherical
    use flexmbs_mbs_rotation, only: quat_from_axis_angle
    use flexmbs_io_namelist, only: scene_input_t
    implicit none
    private

    public :: build_rigid_chain, build_rigid_chains, chain_link, tree_links, link_names, &
        tree_count

contains

    !> The chains of the scene, one per tree, and their initial coordinates
    !> q0 and rates v0 (the chains' in turn).
    subroutine build_rigid_chains(scene, chains, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        type(rigid_chain_t), allocatable, intent(out) :: chains(:)
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        real(wp), allocatable :: qc(:), vc(:)
        integer :: t
        allocate (chains(tree_count(scene)), q0(0), v0(0))
        do t = 1, size(chains)
            call build_tree(scene, tree_links(scene, t), chains(t), qc, vc, status)
            if (.not. status%ok()) return
            q0 = [q0, qc]
            v0 = [v0, vc]
        end do
    end subroutine build_rigid_chains

    !> All the scene's links as one chain (a forest: the `rigid_chain`
    !> problem's), in scene order, and its q0 and v0.
    subroutine build_rigid_chain(scene, chain, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        type(rigid_chain_t), intent(out) :: chain
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        integer :: i
        call build_tree(scene, [(i, i = 1, size(scene%chain))], chain, q0, v0, status)
    end subroutine build_rigid_chain

    !> The names of tree t's links in its order; t = 0: of all links, in
    !> scene order (build_rigid_chain's).
    function link_names(scene, t) result(names)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: t
        character(len=len(scene%chain%name)), allocatable :: names(:)
        if (t == 0) then
            names = scene%chain%name
        else
            names = scene%chain(tree_links(scene, t))%name
        end if
    end function link_names

    !> The chain (tree number) and link (place in its tree) of the link
    !> called `name`; chain = link = 0 if no link has that name.
    subroutine chain_link(scene, name, chain, link)
        type(scene_input_t), intent(in) :: scene
        character(len=*), intent(in) :: name
        integer, intent(out) :: chain, link
        integer :: root(size(scene%chain))
        integer :: k, j
        chain = 0
        link = 0
        root = root_of(scene)
        do k = 1, size(scene%chain)
            if (scene%chain(k)%name /= name) cycle
            chain = count([(root(j) == j, j = 1, root(k))])
            link = count(root(1:k) == root(k))
            return
        end do
    end subroutine chain_link

    !> The number of trees (links on the ground).
    pure integer function tree_count(scene)
        type(scene_input_t), intent(in) :: scene
        integer :: t
        integer :: root(size(scene%chain))
        root = root_of(scene)
        tree_count = count(root == [(t, t = 1, size(root))])
    end function tree_count

    !> The scene's link numbers of tree t, in scene order.
    function tree_links(scene, t) result(links)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: t
        integer, allocatable :: links(:)
        ! explicit shape: gfortran's reallocation of an unallocated array from
        ! this function result reads its bounds uninitialised (valgrind)
        integer :: root(size(scene%chain))
        integer :: i, j, r
        root = root_of(scene)
        r = 0
        do j = 1, size(root)
            if (root(j) == j) r = r + 1
            if (r == t) exit
        end do
        ! j: the root of tree t
        links = pack([(i, i = 1, size(root))], root == j)
    end function tree_links

    !> Each link's root (the link of its tree whose parent is the ground);
    !> parents come before their children (the scene checks see to it).
    pure function root_of(scene) result(root)
        type(scene_input_t), intent(in) :: scene
        integer :: root(size(scene%chain))
        integer :: i, j
        do i = 1, size(scene%chain)
            root(i) = i
            do j = 1, i - 1
                if (scene%chain(j)%name == scene%chain(i)%parent) root(i) = root(j)
            end do
        end do
    end function root_of

    !> The chain of the scene's links `links` (one tree, in scene order)
    !> and its initial coordinates q0 and rates v0.
    subroutine build_tree(scene, links, chain, q0, v0, status)
        type(scene_input_t), intent(in) :: scene
        integer, intent(in) :: links(:)
        type(rigid_chain_t), intent(out) :: chain
        real(wp), allocatable, intent(out) :: q0(:), v0(:)
        type(status_t), intent(out) :: status
        type(chain_body_t), allocatable :: bodies(:)
        character(len=:), allocatable :: defect
        real(wp) :: inertia(3, 3)
        integer :: i, j, parent, joint
        allocate (bodies(size(links)), q0(0), v0(0))
        do i = 1, size(bodies)
            associate (c => scene%chain(links(i)))
                parent = 0
                do j = 1, i - 1
                    if (scene%chain(links(j))%name == c%parent) parent = j
                end do
                select case (trim(c%joint))
                case ('prismatic'); joint = chain_joint_prismatic
                case ('spherical'); joint = chain_joint_spherical
                case default; joint = chain_joint_revolute
                end select
                inertia = inertia_tensor(c%inertia, c%inertia_products)
                bodies(i) = new_chain_body(parent, joint, c%joint_position, &
                    c%joint_axis / norm2(c%joint_axis), c%centre, c%mass, inertia)
                defect = inertia_defect(inertia)
                if (len(defect) > 0) then
                    call status%set(status_bad_input, scene%path // ': &rigid_chain ''' // &
                        trim(c%name) // ''': inertia, inertia_products: ' // defect // &
                        ' (line ' // int_text(c%line) // ')')
                    return
                end if
                if (joint == chain_joint_spherical) then
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
    end subroutine build_tree
end module flexmbs_run_chain_builder
