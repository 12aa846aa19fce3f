!> How far the consistent initial assembly moved each body of a multibody
!> scene from the positions the scene gives: rigid bodies (centre of mass
!> in m, rotation in rad), chain links (joint coordinate) and the flexible
!> body (largest node move in m). A move beyond `&multibody
!> assembly_tolerance` is bad input: a position typo would otherwise be
!> corrected silently. The message names the body and the joint on it
!> that the given positions violate most.
module flexmbs_run_assembly_check
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_text, only: real_text
    use flexmbs_mbs_system, only: mbs_system_t
    use flexmbs_mbs_rigid_body, only: rigid_body_nq
    use flexmbs_io_scene_input, only: scene_input_t, nonlinear_body
    use flexmbs_run_chain_builder, only: link_names
    implicit none
    private

    public :: check_assembly

contains

    !> Compare the assembled positions `q` with the given `q0`; `summary`
    !> lists each body's move; bad input (the scene's path, the body, its
    !> move, the joint) when a move exceeds the tolerance.
    subroutine check_assembly(scene, sys, labels, t, q0, q, summary, status)
        type(scene_input_t), intent(in) :: scene
        type(mbs_system_t), intent(inout) :: sys
        character(len=*), intent(in) :: labels(:)  !! per system joint
        real(wp), intent(in) :: t, q0(:), q(:)
        character(len=:), allocatable, intent(out) :: summary
        type(status_t), intent(inout) :: status
        real(wp) :: move, angle, worst, dot
        integer :: i, off, worst_body, k, c
        character(len=len(scene%chain%name)), allocatable :: names(:)
        character(len=:), allocatable :: worst_text

        summary = ''
        worst = 0.0_wp
        worst_body = 0
        worst_text = ''
        do i = 1, size(scene%rigid_bodies)
            off = rigid_body_nq * (i - 1)
            move = norm2(q(off + 1:off + 3) - q0(off + 1:off + 3))
            dot = min(1.0_wp, abs(sum(q(off + 4:off + 7) * q0(off + 4:off + 7)) / &
                (norm2(q(off + 4:off + 7)) * norm2(q0(off + 4:off + 7)))))
            angle = 2.0_wp * acos(dot)
            call note('rigid body ''' // trim(scene%rigid_bodies(i)%name) // '''', &
                      real_text(move) // ' m, ' // real_text(angle) // ' rad', max(move, angle), i)
        end do
        do c = 1, sys%chain_count()
            names = link_names(scene, c)
            do i = 1, sys%link_count(c)
                call sys%link_coordinates(c, i, off, k)
                move = maxval(abs(q(off + 1:off + k) - q0(off + 1:off + k)))
                call note('link ''' // trim(names(i)) // '''', &
                          real_text(move) // ' (joint coordinate)', move, 0)
            end do
        end do
        do i = 1, sys%flexible_count()
            call sys%flexible_coordinates(i, off, k)
            move = maxval([0.0_wp, abs(q(off + 1:off + k) - q0(off + 1:off + k))])
            call note('flexible body ''' // trim(scene%bodies(nonlinear_body(scene, i))%name) &
                      // '''', &
                      real_text(move) // ' m (largest node move)', move, 0)
        end do
        if (worst <= scene%multibody%assembly_tolerance) return
        call status%set(status_bad_input, scene%path // ': &multibody: assembly_tolerance = ' &
            // real_text(scene%multibody%assembly_tolerance) // ': the initial assembly moves ' &
            // worst_text // joint_hint(worst_body) // '; correct the given position (or raise &
            &assembly_tolerance)')

    contains

        subroutine note(name, what, size_of_move, body)
            character(len=*), intent(in) :: name, what
            real(wp), intent(in) :: size_of_move
            integer, intent(in) :: body
            if (len(summary) > 0) summary = summary // '; '
            summary = summary // name // ' ' // what
            if (.not. size_of_move <= worst) then
                worst = size_of_move
                worst_body = body
                worst_text = name // ' by ' // what
            end if
        end subroutine note

        !> ', most violated at the given positions: joint J (|c| = x)' for
        !> the joint on rigid body `body` with the largest residual.
        function joint_hint(body) result(hint)
            integer, intent(in) :: body
            character(len=:), allocatable :: hint
            real(wp), allocatable :: c(:)
            real(wp) :: r, best
            integer :: j, row, best_joint
            type(status_t) :: local
            hint = ''
            if (body == 0 .or. sys%joint_count() == 0) return
            allocate (c(sys%nc))
            call sys%constraint(t, q0, c, local)
            if (.not. local%ok()) return
            best = -1.0_wp
            best_joint = 0
            do j = 1, sys%joint_count()
                if (all(sys%joint_bodies(j) /= body)) cycle
                row = sys%joint_first_row(j)
                r = maxval([0.0_wp, abs(c(row:row + sys%joint_rows(j) - 1))])
                if (r > best) then
                    best = r
                    best_joint = j
                end if
            end do
            if (best_joint > 0 .and. best_joint <= size(labels)) hint = ', most violated at &
                &the given positions: ' // trim(labels(best_joint)) // ' (|c| = ' // &
                real_text(best) // ')'
        end function joint_hint
    end subroutine check_assembly
end module flexmbs_run_assembly_check
