!> What a flexible body says of its mesh: sets, centroids, dofs, counts,
!> reference positions and nodal values (module flexmbs_fe_flexible_body).
submodule (flexmbs_fe_flexible_body) flexmbs_fe_flexible_body_views
    implicit none

contains

    module procedure body_reference_mesh
        mesh = self%mesh
    end procedure body_reference_mesh

    module procedure body_node_set
        call self%mesh%node_set(name, nodes, status)
    end procedure body_node_set

    module procedure body_centroid
        if (present(nodes)) then
            c = sum(self%mesh%x(:, nodes), dim=2) / size(nodes)
        else
            c = self%mesh%centroid()
        end if
    end procedure body_centroid

    module procedure body_node_dofs
        dofs = self%dof(:, node)
    end procedure body_node_dofs

    module procedure body_node_count
        n = size(self%dof, 2)
    end procedure body_node_count

    module procedure body_element_count
        n = self%mesh%element_count()
    end procedure body_element_count

    module procedure body_nodes_per_element
        n = self%mesh%nodes_per_element()
    end procedure body_nodes_per_element

    module procedure body_element_nodes
        nodes = self%mesh%connectivity(:, k)
    end procedure body_element_nodes

    module procedure body_reference_nodes
        x = self%mesh%x
    end procedure body_reference_nodes

    module procedure body_reference_node
        x = self%mesh%reference_position(node)
    end procedure body_reference_node

    module procedure body_nodal_values
        integer :: i, j, d
        do i = 1, size(self%dof, 2)
            do j = 1, 3
                d = self%dof(j, i)
                if (d == 0) then
                    values(3 * (i - 1) + j) = 0.0_wp
                else if (displacement) then
                    values(3 * (i - 1) + j) = w(d) - self%mesh%x(j, i)
                else
                    values(3 * (i - 1) + j) = w(d)
                end if
            end do
        end do
    end procedure body_nodal_values

    module procedure body_displacements_of
        values = x - reshape(self%mesh%x, [size(values)])
    end procedure body_displacements_of
end submodule flexmbs_fe_flexible_body_views
