!> The /flexible/<name>/ part of a multibody or flexible-body scene's HDF5
!> file: the mesh of a flexible body (reference nodes, connectivity and
!> element type, node and element sets) and per record every node's
!> displacement and velocity, every element's mean Cauchy and von Mises
!> stress and the body's strain and kinetic energy (docs/output.md).
!>
!> A modal body writes the same datasets, reconstructed from its frame and
!> modal coordinates (x = r + A (X − c + Φ η); the stresses are its FE
!> body's element stresses of that field), and adds `modal_coordinates`
!> per record and its `frequencies`, so that a reduced and a nonlinear run
!> of one scene are read and drawn alike.
module flexmbs_run_flexible_output
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_fe_flexible_body, only: flexible_body_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_mbs_modal_body, only: modal_body_t
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
        !> a modal body's (body => its FE body): nodes reconstructed into x
        type(modal_body_t), pointer :: modal => null()
        real(wp), allocatable :: x(:)
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
        type(modal_body_t), pointer :: modal => null()
        real(wp), allocatable :: x(:), xd(:)
    contains
        procedure :: evaluate => stress_evaluate
    end type stress_values_t

    !> The strain and kinetic energy of a flexible body whose q start after
    !> y(oq), v after y(ov) (the work of its applied forces is not in them).
    type, extends(record_values_t) :: energy_values_t
        type(flexible_body_t), pointer :: body => null()
        integer :: oq = 0, ov = 0
        type(modal_body_t), pointer :: modal => null()
    contains
        procedure :: evaluate => energy_evaluate
    end type energy_values_t

    !> A modal body's η per record.
    type, extends(record_values_t) :: modal_values_t
        integer :: oq = 0, n = 0
    contains
        procedure :: evaluate => modal_evaluate
    end type modal_values_t

    public :: add_flexible, add_modal, xdmf_body

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
        base = 'flexible/' // path_name(name) // '/'
        call write_mesh(h5, body, base, status)
        if (.not. status%ok()) return
        nodes%body => body
        stress%body => body
        energy%body => body
        call add_body_series(h5, base, oq, ov, nodes, stress, energy, status)
    end subroutine add_flexible

    !> /flexible/<name>/ of a modal body: its FE body's mesh, the
    !> reconstructed series of add_flexible, `modal_coordinates` (η per
    !> record) and `frequencies` (its ω, rad/s). Its (r, p, η) start after
    !> y(oq), (ṙ, ω′, η̇) after y(ov).
    subroutine add_modal(h5, body, name, oq, ov, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(modal_body_t), intent(in), target :: body
        character(len=*), intent(in) :: name
        integer, intent(in) :: oq, ov
        type(status_t), intent(out) :: status
        type(node_values_t) :: nodes
        type(stress_values_t) :: stress
        type(energy_values_t) :: energy
        type(modal_values_t) :: eta
        type(flexible_body_t), pointer :: fe
        character(len=:), allocatable :: base
        integer :: n3
        base = 'flexible/' // path_name(name) // '/'
        fe => body%fe_body()
        call write_mesh(h5, fe, base, status)
        if (status%ok()) call h5%write_vector(base // 'frequencies', body%frequencies(), &
                                              status)
        if (status%ok()) call h5%annotate(base // 'frequencies', 'unit', 'rad/s', status)
        if (status%ok()) call h5%annotate(base // 'frequencies', 'description', 'the modal &
            &body''s own frequencies (its reduced K and M), one per modal coordinate', status)
        if (.not. status%ok()) return
        n3 = 3 * fe%node_count()
        nodes%body => fe
        nodes%modal => body
        allocate (nodes%x(n3), stress%x(n3), stress%xd(n3))
        stress%body => fe
        stress%modal => body
        energy%body => fe
        energy%modal => body
        call add_body_series(h5, base, oq, ov, nodes, stress, energy, status)
        if (.not. status%ok() .or. body%mode_count() == 0) return
        eta%oq = oq
        eta%n = body%mode_count()
        call h5%add_series(base // 'modal_coordinates', body%mode_count(), '1', eta, status, &
            'eta of every mode (shapes M-orthonormal: eta in sqrt(kg) m)')
    end subroutine add_modal

    !> The mesh of `body` under `base`: reference nodes, connectivity and
    !> element type, node and element sets.
    subroutine write_mesh(h5, body, base, status)
        type(hdf5_sink_t), intent(inout) :: h5
        type(flexible_body_t), intent(in) :: body
        character(len=*), intent(in) :: base
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        integer :: k
        mesh = body%reference_mesh()
        call h5%write_matrix(base // 'reference_nodes', mesh%reference_positions(), status)
        if (status%ok()) call h5%annotate(base // 'reference_nodes', 'unit', 'm', status)
        if (status%ok()) call h5%write_integers(base // 'connectivity', &
                                                mesh%element_nodes(), status)
        if (status%ok()) call h5%annotate(base // 'connectivity', 'description', 'the nodes &
            &of each element (numbered from 1, as in the mesh file)', status)
        if (status%ok()) call h5%annotate(base // 'connectivity', 'element_type', &
            element_type(mesh%nodes_per_element()), status)
        do k = 1, mesh%node_set_count()
            if (.not. status%ok()) exit
            call h5%write_integers(base // 'node_sets/' // path_name(mesh%node_set_name(k)), &
                                   mesh%node_set_nodes(k), status)
        end do
        do k = 1, mesh%element_set_count()
            if (.not. status%ok()) exit
            call h5%write_integers(base // 'element_sets/' // &
                                   path_name(mesh%element_set_name(k)), &
                                   mesh%element_set_elements(k), status)
        end do
    end subroutine write_mesh

    !> The per-record series of a body (its evaluators' bodies set).
    subroutine add_body_series(h5, base, oq, ov, nodes, stress, energy, status)
        type(hdf5_sink_t), intent(inout) :: h5
        character(len=*), intent(in) :: base
        integer, intent(in) :: oq, ov
        type(node_values_t), intent(inout) :: nodes
        type(stress_values_t), intent(inout) :: stress
        type(energy_values_t), intent(inout) :: energy
        type(status_t), intent(out) :: status
        integer :: nn, ne, stat
        nn = nodes%body%node_count()
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
        ne = nodes%body%element_count()
        allocate (stress%sigma(6, ne), stress%mises(ne), stat=stat)
        if (stat /= 0) then
            call out_of_memory(status, 'the elements'' stress for the HDF5 file', &
                7_i8 * ne, 8)
            return
        end if
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
        energy%oq = oq
        energy%ov = ov
        call h5%add_series(base // 'energy', 2, 'J', energy, status, 'strain and kinetic &
            &energy of the body')
    end subroutine add_body_series

    subroutine stress_evaluate(self, t, y, values, status)
        class(stress_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        type(status_t) :: local
        integer :: el
        if (associated(self%modal)) then
            associate (m => self%modal)
                call m%node_positions(y(self%oq + 1:self%oq + m%nq), self%x)
                call m%node_velocities(y(self%oq + 1:self%oq + m%nq), &
                                       y(self%ov + 1:self%ov + m%nv), self%xd)
                call self%body%element_stress(self%x, self%xd, self%sigma, self%mises, local)
                ! the reduced model has no det F > 0 to keep: a field that
                ! inverts an element (a diverging spin-up) has no stress there
                if (.not. local%ok()) then
                    self%sigma = ieee_value(1.0_wp, ieee_quiet_nan)
                    self%mises = ieee_value(1.0_wp, ieee_quiet_nan)
                end if
            end associate
        else
            associate (body => self%body)
                call body%element_stress(y(self%oq + 1:self%oq + body%nq), &
                                         y(self%ov + 1:self%ov + body%nv), self%sigma, &
                                         self%mises, status)
            end associate
        end if
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
        if (associated(self%modal)) then
            associate (m => self%modal)
                if (self%velocity) then
                    call m%node_velocities(y(self%oq + 1:self%oq + m%nq), &
                                           y(self%ov + 1:self%ov + m%nv), values)
                else
                    call m%node_positions(y(self%oq + 1:self%oq + m%nq), self%x)
                    call self%body%displacements_of(self%x, values)
                end if
            end associate
            return
        end if
        if (self%velocity) then
            call self%body%nodal_values(y(self%ov + 1:self%ov + self%body%nv), .false., values)
        else
            call self%body%nodal_values(y(self%oq + 1:self%oq + self%body%nq), .true., values)
        end if
    end subroutine node_evaluate

    subroutine energy_evaluate(self, t, y, values, status)
        class(energy_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        real(wp) :: kinetic, potential
        if (associated(self%modal)) then
            associate (m => self%modal)
                ! the energy of the reduced model: ½ Σ ω² η² and ½ vᵀ M v
                call m%energy(y(self%oq + 1:self%oq + m%nq), y(self%ov + 1:self%ov + m%nv), &
                              kinetic, potential)
                values(1) = m%elastic_energy(y(self%oq + 1:self%oq + m%nq))
                values(2) = kinetic
            end associate
            return
        end if
        associate (body => self%body)
            values(1) = body%strain_energy(y(self%oq + 1:self%oq + body%nq), status)
            values(2) = body%kinetic_energy(y(self%ov + 1:self%ov + body%nv))
        end associate
    end subroutine energy_evaluate

    subroutine modal_evaluate(self, t, y, values, status)
        class(modal_values_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        real(wp), intent(out) :: values(:)
        type(status_t), intent(inout) :: status
        values = y(self%oq + 8:self%oq + 7 + self%n)
    end subroutine modal_evaluate

    !> The body as add_flexible stores it, for the XDMF file beside the
    !> HDF5 result (io/xdmf_file).
    function xdmf_body(body, name) result(xdmf)
        type(flexible_body_t), intent(in) :: body
        character(len=*), intent(in) :: name
        type(xdmf_body_t) :: xdmf
        type(mesh_t) :: mesh
        xdmf%name = trim(name)
        xdmf%group = 'flexible/' // path_name(name)
        mesh = body%reference_mesh()
        xdmf%nodes = mesh%node_count()
        xdmf%elements = mesh%element_count()
        xdmf%element_nodes = mesh%nodes_per_element()
    end function xdmf_body

    pure function element_type(nodes) result(name)
        integer, intent(in) :: nodes
        character(len=:), allocatable :: name
        name = 'hex27'
        if (nodes == 8) name = 'hex8'
    end function element_type
end module flexmbs_run_flexible_output
