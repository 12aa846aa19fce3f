!> The coloured element assembly: a valid colouring, equality with a plain
!> element-order assembly, and bitwise-identical results for any number of
!> OpenMP threads (built with OPENMP=1; without OpenMP two runs compare).
module test_fe_assembly
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t
    use flexmbs_fe_hexahedron, only: hex8, hex27
    use flexmbs_fe_neo_hooke, only: neo_hooke_t
    use flexmbs_fe_mesh, only: mesh_t
    use flexmbs_fe_box_mesh, only: box_mesh
    use flexmbs_fe_element, only: element_forces
    use flexmbs_fe_flexible_body, only: flexible_body_t, new_flexible_body
    use test_problems, only: fill_random
    use test_fe, only: paper_material
    use testing, only: test_case_t, new_test, error_t, check
    !$ use omp_lib, only: omp_get_max_threads, omp_set_num_threads
    implicit none
    private
    public :: collect_fe_assembly

    integer, parameter :: kinds(2) = [hex8, hex27]

contains

    function collect_fe_assembly() result(tests)
        type(test_case_t), allocatable :: tests(:)
        tests = [new_test('colouring_valid', test_colouring), &
                 new_test('equals_element_order', test_reference), &
                 new_test('threads_bitwise_identical', test_threads)]
    end function collect_fe_assembly

    !> A clamped 4 × 3 × 2 box at a random deformed, moving state.
    subroutine make_state(kind, body, q, v, status)
        integer, intent(in) :: kind
        type(flexible_body_t), intent(out) :: body
        real(wp), allocatable, intent(out) :: q(:), v(:)
        type(status_t), intent(out) :: status
        type(mesh_t) :: mesh
        type(neo_hooke_t) :: mat(2)
        integer, allocatable :: fixed(:), material(:), tip(:)
        real(wp), allocatable :: dq(:)
        integer(i8) :: seed
        call paper_material(mat(1))
        mat(2) = mat(1)
        mat(2)%mu = 10 * mat(1)%mu
        call box_mesh(mesh, kind, [4, 3, 2], [0.4_wp, 0.3_wp, 0.2_wp], status)
        if (status%ok()) call mesh%node_set('xmin', fixed, status)
        if (status%ok()) call mesh%element_set('xmax_layer', tip, status)
        if (.not. status%ok()) return
        allocate (material(mesh%element_count()), source=1)
        material(tip) = 2
        call new_flexible_body(body, mesh, mat, fixed, status, element_material=material)
        if (.not. status%ok()) return
        q = body%free_positions()
        allocate (dq(body%nq), v(body%nv))
        seed = 7_i8
        call fill_random(dq, seed, -0.01_wp, 0.01_wp)
        call fill_random(v, seed, -0.5_wp, 0.5_wp)
        q = q + dq
    end subroutine make_state

    !> Every element exactly once; no two elements of a colour share a node.
    subroutine test_colouring(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:)
        integer, allocatable :: seen(:), owner(:)
        integer :: k, c, i, e
        do k = 1, 2
            call make_state(kinds(k), body, q, v, status)
            call check(error, status%ok(), 'colouring: ' // status%text())
            if (allocated(error)) return
            allocate (seen(body%mesh%element_count()), source=0)
            allocate (owner(body%mesh%node_count()))
            do c = 1, size(body%colour_start) - 1
                owner = 0
                do i = body%colour_start(c), body%colour_start(c + 1) - 1
                    e = body%colour_elements(i)
                    seen(e) = seen(e) + 1
                    call check(error, all(owner(body%mesh%connectivity(:, e)) == 0), &
                               'colouring: two elements of one colour share a node')
                    owner(body%mesh%connectivity(:, e)) = e
                end do
            end do
            call check(error, all(seen == 1), 'colouring: an element missing or repeated')
            ! a structured box needs exactly 8 colours
            call check(error, size(body%colour_start) - 1 == 8, 'colouring: not 8 colours')
            deallocate (seen, owner)
            if (allocated(error)) return
        end do
    end subroutine test_colouring

    !> Force, stiffness and damping equal a plain assembly in element order
    !> (element_forces summed by dense scatter) to round-off.
    subroutine test_reference(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), k(:), k_ref(:), kd(:, :), cd(:, :), kd_ref(:, :), &
            cd_ref(:, :), x(:, :), w(:, :), ke(:, :), ce(:, :), k_el(:, :), k_v(:, :)
        integer, allocatable :: dofs(:)
        integer :: kind, e, a, nn, i, j, n
        do kind = 1, 2
            call make_state(kinds(kind), body, q, v, status)
            if (.not. status%ok()) return
            n = body%nv
            allocate (k(n), k_ref(n), kd(n, n), cd(n, n), kd_ref(n, n), cd_ref(n, n))
            call body%tangents(q, v, k, status)
            call check(error, status%ok(), 'reference: ' // status%text())
            if (allocated(error)) return
            call body%stiffness%to_dense(kd)
            call body%damping%to_dense(cd)
            nn = body%hex%nnode
            x = body%mesh%x
            allocate (w(3, size(x, 2)), source=0.0_wp)
            do i = 1, size(x, 2)
                do j = 1, 3
                    if (body%dof(j, i) > 0) then
                        x(j, i) = q(body%dof(j, i))
                        w(j, i) = v(body%dof(j, i))
                    end if
                end do
            end do
            allocate (ke(3 * nn, 3 * nn), ce(3 * nn, 3 * nn), k_el(3, nn), k_v(3, nn), &
                      dofs(3 * nn))
            k_ref = 0.0_wp
            kd_ref = 0.0_wp
            cd_ref = 0.0_wp
            do e = 1, body%mesh%element_count()
                call element_forces(body%hex, body%materials(body%element_material(e)), &
                                    body%dndx(:, :, :, e), body%wdv(:, e), &
                                    x(:, body%mesh%connectivity(:, e)), &
                                    w(:, body%mesh%connectivity(:, e)), k_el, k_v, status, ke, ce)
                do a = 1, nn
                    dofs(3 * a - 2:3 * a) = body%dof(:, body%mesh%connectivity(a, e))
                end do
                do i = 1, 3 * nn
                    if (dofs(i) == 0) cycle
                    k_ref(dofs(i)) = k_ref(dofs(i)) + k_el(mod(i - 1, 3) + 1, (i - 1) / 3 + 1) &
                                     + k_v(mod(i - 1, 3) + 1, (i - 1) / 3 + 1)
                    do j = 1, 3 * nn
                        if (dofs(j) == 0) cycle
                        kd_ref(dofs(i), dofs(j)) = kd_ref(dofs(i), dofs(j)) + ke(i, j)
                        cd_ref(dofs(i), dofs(j)) = cd_ref(dofs(i), dofs(j)) + ce(i, j)
                    end do
                end do
            end do
            call check(error, maxval(abs(k - k_ref)) <= 1.0e-13_wp * maxval(abs(k_ref)), &
                       'reference: force differs')
            call check(error, maxval(abs(kd - kd_ref)) <= 1.0e-13_wp * maxval(abs(kd_ref)), &
                       'reference: stiffness differs')
            call check(error, maxval(abs(cd - cd_ref)) <= 1.0e-13_wp * maxval(abs(cd_ref)), &
                       'reference: damping differs')
            deallocate (k, k_ref, kd, cd, kd_ref, cd_ref, w, ke, ce, k_el, k_v, dofs)
            if (allocated(error)) return
        end do
    end subroutine test_reference

    !> One thread against two (OpenMP builds) or two runs (serial builds):
    !> force and both tangent matrices bit for bit.
    subroutine test_threads(error)
        type(error_t), allocatable, intent(out) :: error
        type(flexible_body_t) :: body
        type(status_t) :: status
        real(wp), allocatable :: q(:), v(:), k1(:), k2(:), s1(:), d1(:)
        integer :: kind, threads
        threads = 1
        !$ threads = omp_get_max_threads()
        do kind = 1, 2
            call make_state(kinds(kind), body, q, v, status)
            if (.not. status%ok()) return
            allocate (k1(body%nv), k2(body%nv))
            !$ call omp_set_num_threads(1)
            call body%tangents(q, v, k1, status)
            s1 = body%stiffness%values
            d1 = body%damping%values
            !$ call omp_set_num_threads(max(2, threads))
            call body%tangents(q, v, k2, status)
            !$ call omp_set_num_threads(threads)
            call check(error, status%ok(), 'threads: ' // status%text())
            call check(error, all(k1 == k2) .and. all(s1 == body%stiffness%values) .and. &
                       all(d1 == body%damping%values), 'threads: results differ in bits')
            deallocate (k1, k2)
            if (allocated(error)) return
        end do
    end subroutine test_threads
end module test_fe_assembly
