!> The /flexible/<name>/ part of a multibody or flexible-body scene's HDF5
!> file: the mesh of a flexible body (reference nodes, connectivity and
!> element type, node and element sets) and per record every node's
!> displacement and velocity, every element's mean Cauchy and von Mises
!> stress and the body's strain and kinetic energy (docs/output.md).
module flexmbs_run_flexible_output
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_io_record_values, only: record_values_t
    use flexmbs_io_hdf5_sink, only: hdf5_sink_t
    use flexmbs_io_hdf5_text, only: path_name
    use flexmbs_io_xdmf_file, only: xdmf_body_t
    implicit none
    private

    !> Displacements (or velocities) of every node of a flexible body whose
    !> free q start after y(oq), v after y(ov).
    type, extends(record_values_t) :: node_values_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
        logical :: velocity = .false.
    contains
        procedure :: evaluate => node_evaluate
    end type node_values_t

    !> The Cauchy stress of every element (the mean over its quadrature
    !> points, as ParaView shows it), or its von Mises value, of a flexible
    !> body whose q start after y(oq), v after y(ov). The work arrays are
    !> allocated when the series is added, not per record.
    type, extends(record_values_t) :: stress_values_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
        logical :: von_mises = .false.
        real(wp), allocatable :: sigma(:, :), mises(:)
    contains
        procedure :: evaluate => stress_evaluate
    end type stress_values_t

    !> The strain and kinetic energy of a flexible body whose q start after
    !> y(oq), v after y(ov) (the work of its applied forces is not in them).
    type, extends(record_values_t) :: energy_values_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
    contains
        procedure :: evaluate => energy_evaluate
    end type energy_values_t

    public :: add_flexible, xdmf_body

contains

    !> /flexible/<name>/: the mesh (reference nodes, connectivity, element
    !> type, node sets) and every node's displacement and velocity per
    !> record, (3, nodes, records): node k of the mesh file is index k - 1
    !> in Python, f['flexible/coupler/displacement'][:, k - 1, 0] its x.
    subroutine add_flexible(h5, body, name, oq, ov, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(flexible_body_t), intent(in), target :: body
        character(len=*), intent(in) :: name
        integer, intent(in) :: oq, ov  !! the body's free q and v start after y(oq), y(ov)
        type(status_t), intent(out) :: status
        type(node_values_t) :: nodes
        type(stress_values_t) :: stress
        type(energy_values_t) :: energy
        character(len=:), allocatable :: base
        integer :: k, nn, ne, stat
        base = 'flexible/' // path_name(name) // '/'
        nn = body%mesh%node_count()
        call h5%write_matrix(base // 'reference_nodes', body%mesh%x, status)
        if (status%ok()) call h5%annotate(base // 'reference_nodes', 'unit', 'm', status)
        if (status%ok()) call h5%write_integers(base // 'connectivity', &
                                                body%mesh%connectivity, status)
        if (status%ok()) call h5%annotate(base // 'connectivity', 'description', 'the nodes &
            &of each element (numbered from 1, as in the mesh file)', status)
        if (status%ok()) call h5%annotate(base // 'connectivity', 'element_type', &
            element_type(body%mesh%nnode_element), status)
        if (allocated(body%mesh%node_sets)) then
            do k = 1, size(body%mesh%node_sets)
                if (.not. status%ok()) exit
                associate (set => body%mesh%node_sets(k))
                    call h5%write_integers(base // 'node_sets/' // path_name(set%name), &
                                           set%nodes, status)
                end associate
            end do
        end if
        if (allocated(body%mesh%element_sets)) then
            do k = 1, size(body%mesh%element_sets)
                if (.not. status%ok()) exit
                associate (set => body%mesh%element_sets(k))
                    call h5%write_integers(base // 'element_sets/' // path_name(set%name), &
                                           set%elements, status)
                end associate
            end do
        end if
        if (.not. status%ok()) return
        nodes%body => body
        nodes%oq = oq
        nodes%ov = ov
        nodes%velocity = .false.
        call h5%add_series(base // 'displacement', 3, 'm', nodes, status, 'x - X of every &
            &node (fixed ones 0), world frame', columns=nn)
        if (.not. status%ok()) return
        nodes%velocity = .true.
        call h5%add_series(base // 'velocity', 3, 'm/s', nodes, status, 'of every node', &
            columns=nn)
        if (.not. status%ok()) return
        ne = body%mesh%element_count()
        allocate (stress%sigma(6, ne), stress%mises(ne), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'the elements'' stress for the HDF5 file', &
                7_i8 * ne, 8)
            return
        end if
        stress%body => body
        stress%oq = oq
        stress%ov = ov
        call h5%add_series(base // 'stress', 6, 'Pa', stress, status, 'Cauchy stress of &
            &every element, mean over its quadrature points: xx, yy, zz, xy, yz, xz', &
            columns=ne)
        if (.not. status%ok()) return
        stress%von_mises = .true.
        call h5%add_series(base // 'von_mises', ne, 'Pa', stress, status, 'von Mises &
            &stress of every element, from its mean Cauchy stress')
        if (.not. status%ok()) return
        energy%body => body
        energy%oq = oq
        energy%ov = ov
        call h5%add_series(base // 'energy', 2, 'J', energy, status, 'strain and kinetic &
            &energy of the body')
    end subroutine add_flexible

    subroutine stress_evaluate(self, t, y, values, status)
        class(stress_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: el
        associate (body => self%body)
            call body%element_stress(y(self%oq + 1:self%oq + body%nq), &
                                     y(self%ov + 1:self%ov + body%nv), self%sigma, &
                                     self%mises, status)
        end associate
        if (self%von_mises) then
            values = self%mises
        else
            do el = 1, size(self%sigma, 2)
                values(6 * el - 5:6 * el) = self%sigma(:, el)
            end do
        end if
    end subroutine stress_evaluate

    subroutine node_evaluate(self, t, y, values, status)
        class(node_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        integer :: i, j, d
        associate (dof => self%body%dof)
            do i = 1, size(dof, 2)
                do j = 1, 3
                    d = dof(j, i)
                    if (d == 0) then
                        values(3 * (i - 1) + j) = 0.0_wp
                    else if (self%velocity) then
                        values(3 * (i - 1) + j) = y(self%ov + d)
                    else
                        values(3 * (i - 1) + j) = y(self%oq + d) - self%body%mesh%x(j, i)
                    end if
                end do
            end do
        end associate
    end subroutine node_evaluate

    subroutine energy_evaluate(self, t, y, values, status)
        class(energy_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        associate (body => self%body)
            values(1) = body%strain_energy(y(self%oq + 1:self%oq + body%nq), status)
            values(2) = body%kinetic_energy(y(self%ov + 1:self%ov + body%nv))
        end associate
    end subroutine energy_evaluate

    !> The body as add_flexible stores it, for the XDMF file beside the
    !> HDF5 result (io/xdmf_file).
    function xdmf_body(body, name) result(xdmf)
        type(flexible_body_t), intent(in) :: body
        character(len=*), intent(in) :: name
        type(xdmf_body_t) :: xdmf
        xdmf%name = trim(name)
        xdmf%group = 'flexible/' // path_name(name)
        xdmf%nodes = body%mesh%node_count()
        xdmf%elements = body%mesh%element_count()
        xdmf%element_nodes = body%mesh%nnode_element
    end function xdmf_body

    pure function element_type(nodes) result(name)
        integer, intent(in) :: nodes
        character(len=:), allocatable :: name
        name = 'hex27'
        if (nodes == 8) name = 'hex8'
    end function element_type
end module flexmbs_run_flexible_output
