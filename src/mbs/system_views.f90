!> The counts and per-body views of an mbs_system_t that the run and io
!> layers ask for (issue 35: they keep out of the system's components).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_views
    implicit none

contains

    module procedure system_chain_count
        n = self%part_count(part_chain)
    end procedure system_chain_count

    module procedure system_link_count
        n = size(self%chains(c)%bodies)
    end procedure system_link_count

    module procedure system_link_coordinates
        offset = self%chain_q(c) + self%chains(c)%iq(i)
        n = self%chains(c)%iq(i + 1) - self%chains(c)%iq(i)
    end procedure system_link_coordinates

    module procedure system_flexible_count
        n = self%part_count(part_flexible)
    end procedure system_flexible_count

    module procedure system_flexible_coordinates
        offset = self%flex_q(i)
        n = self%flex(i)%nq
    end procedure system_flexible_coordinates

    module procedure system_joint_count
        n = 0
        if (allocated(self%joints)) n = size(self%joints)
    end procedure system_joint_count

    module procedure system_joint_bodies
        bodies = [self%markers(self%joints(j)%marker_i)%body, &
                  self%markers(self%joints(j)%marker_j)%body]
    end procedure system_joint_bodies

    module procedure system_joint_rows
        n = self%joints(j)%joint%nrows
    end procedure system_joint_rows

    module procedure system_element_count
        n = 0
        if (allocated(self%elements)) n = size(self%elements)
    end procedure system_element_count

    module procedure system_element_bodies
        n = merge(1, 2, self%elements(k)%marker_j == 0)
    end procedure system_element_bodies

    module procedure system_part_count
        n = 0
        select case (part)
        case (part_rigid)
            if (allocated(self%rigid%bodies)) n = size(self%rigid%bodies)
        case (part_chain)
            if (allocated(self%chains)) n = size(self%chains)
        case (part_flexible)
            if (allocated(self%flex)) n = size(self%flex)
        case (part_modal)
            if (allocated(self%modal)) n = size(self%modal)
        case (part_frame)
            if (allocated(self%frames)) n = size(self%frames)
        end select
    end procedure system_part_count

    module procedure system_part_offsets
        oq = -1
        ov = -1
        select case (part)
        case (part_chain)
            oq = self%chain_q(i)
            ov = self%chain_v(i)
        case (part_flexible)
            oq = self%flex_q(i)
            ov = self%flex_v(i)
        case (part_modal)
            oq = self%modal_q(i)
            ov = self%modal_v(i)
        end select
    end procedure system_part_offsets

    module procedure system_chain_of
        chain => self%chains(c)
    end procedure system_chain_of

    module procedure system_flexible_of
        body => self%flex(i)
    end procedure system_flexible_of

    module procedure system_modal_of
        body => self%modal(i)
    end procedure system_modal_of

    module procedure system_joint_kind
        kind = self%joints(j)%joint%kind
    end procedure system_joint_kind

    module procedure system_joint_markers
        markers = [self%joints(j)%marker_i, self%joints(j)%marker_j]
    end procedure system_joint_markers

    module procedure system_joint_primitive_count
        n = self%joints(j)%joint%nprimitives
    end procedure system_joint_primitive_count

    module procedure system_joint_primitive
        kind = self%joints(j)%joint%primitive(p)
    end procedure system_joint_primitive

    module procedure system_joint_axis
        axis = self%joints(j)%joint%axis_i(1)
    end procedure system_joint_axis

    module procedure system_marker_of
        marker = self%markers(k)
    end procedure system_marker_of

    module procedure system_rigid_body_of
        body = self%rigid%bodies(b)
    end procedure system_rigid_body_of

    module procedure system_element_of
        element = self%elements(e)
    end procedure system_element_of

    module procedure system_frame_of
        frame = self%frames(k)
    end procedure system_frame_of
end submodule flexmbs_mbs_system_views
