!> The counts and per-body views of an mbs_system_t that the run and io
!> layers ask for (issue 35: they keep out of the system's components).
submodule (flexmbs_mbs_system) flexmbs_mbs_system_views
    implicit none

contains

    module procedure system_chain_count
        n = 0
        if (allocated(self%chains)) n = size(self%chains)
    end procedure system_chain_count

    module procedure system_link_count
        n = size(self%chains(c)%bodies)
    end procedure system_link_count

    module procedure system_link_coordinates
        offset = self%chain_q(c) + self%chains(c)%iq(i)
        n = self%chains(c)%iq(i + 1) - self%chains(c)%iq(i)
    end procedure system_link_coordinates

    module procedure system_flexible_count
        n = 0
        if (allocated(self%flex)) n = size(self%flex)
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
end submodule flexmbs_mbs_system_views
