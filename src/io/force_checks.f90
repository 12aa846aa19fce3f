!> Checks of the `&force` groups beyond the schema's ranges: the type and
!> markers required, marker_j exactly for the two-marker elements, on
!> another body than marker_i, and the values each type reads (how many
!> stiffness and damping values, a load that is not zero). Messages name
!> file, line, group, variable, value and reason (flexmbs_io_scene_values).
module flexmbs_io_force_checks
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_io_input_errors, only: input_errors_t, at_other
    use flexmbs_io_scene_schema, only: did_you_mean, len_name
    use flexmbs_io_scene_lexer, only: entry_t, has_entry, instance_ranges
    use flexmbs_io_scene_values, only: value_error, required_error
    use flexmbs_io_scene_input, only: scene_input_t, force_input_t, marker_index
    implicit none
    private

    public :: check_forces

contains

    !> Every &force group (they come with problem = 'multibody', which
    !> check_multibody enforces).
    subroutine check_forces(scene, entries, errors)
        type(scene_input_t), intent(in) :: scene
        type(entry_t), intent(in) :: entries(:)
        type(input_errors_t), intent(inout) :: errors
        integer :: i, j
        integer, allocatable :: ranges(:, :)
        if (scene%problem /= 'multibody') return
        call instance_ranges(entries, 'force', size(scene%forces), ranges)
        do i = 1, size(scene%forces)
            associate (f => scene%forces(i), own => entries(ranges(1, i):ranges(2, i)))
                do j = 1, i - 1
                    if (scene%forces(j)%name == f%name) call bad('name', 'also the name of &
                        &the &force' // at_other(scene%forces(j)%line))
                end do
                if (.not. has_entry(own, 'force', 'type', i)) then
                    call required_error(errors, 'force', 'type', 'spring_damper, rotational, &
                        &bushing or applied', f%name, f%line)
                    cycle
                end if
                call check_markers(f, own)
                select case (f%type)
                case ('spring_damper')
                    call counts(f, 5, 1, 'k1 .. k5 of F = k1 e + k2 e^2 + ... (e = l - l0)', &
                                'c of c dl/dt')
                case ('rotational')
                    call counts(f, 1, 1, 'k of the torque -k (phi - phi0)', 'c')
                case ('bushing')
                    call bushing_values(f)
                case ('applied')
                    call load_values(f, own)
                end select
                if (f%type /= 'applied') call unused(own, ['force       ', 'torque      ', &
                    'frame       ', 'coefficients', 'amplitude   ', 'frequency   ', &
                    'phase       '])
                if (f%type /= 'bushing') call unused(own, ['stiffness_matrix', &
                                                           'damping_matrix  '])
            end associate
        end do

    contains

        subroutine bad(name, reason)
            character(len=*), intent(in) :: name, reason
            call value_error(errors, entries, 'force', name, reason, i, scene%forces(i)%name, &
                             scene%forces(i)%line)
        end subroutine bad

        !> marker_i given and known; marker_j given, known and on another
        !> body, except for a load (none).
        subroutine check_markers(f, own)
            type(force_input_t), intent(in) :: f
            type(entry_t), intent(in) :: own(:)
            integer :: ki, kj
            ki = marker_index(scene, f%marker_i)
            kj = marker_index(scene, f%marker_j)
            if (.not. has_entry(own, 'force', 'marker_i', i)) then
                call required_error(errors, 'force', 'marker_i', 'the marker it acts on', &
                                    f%name, f%line)
            else if (ki == 0) then
                call bad('marker_i', 'no &marker of that name' // &
                         did_you_mean(trim(f%marker_i), names()))
            end if
            if (f%type == 'applied') then
                if (has_entry(own, 'force', 'marker_j', i)) call bad('marker_j', 'an applied &
                    &load acts on marker_i alone')
                return
            end if
            if (.not. has_entry(own, 'force', 'marker_j', i)) then
                call required_error(errors, 'force', 'marker_j', 'the second marker', f%name, &
                                    f%line)
            else if (kj == 0) then
                call bad('marker_j', 'no &marker of that name' // &
                         did_you_mean(trim(f%marker_j), names()))
            else if (ki > 0) then
                if (scene%markers(ki)%body == scene%markers(kj)%body) call bad('marker_j', &
                    'on the same body as marker_i (''' // trim(scene%markers(ki)%body) // ''')')
            end if
        end subroutine check_markers

        pure function names() result(list)
            character(len=len_name), allocatable :: list(:)
            list = scene%markers%name
        end function names

        !> 1 .. nk stiffness values (required) and at most nc damping values.
        subroutine counts(f, nk, nc, what_k, what_c)
            type(force_input_t), intent(in) :: f
            integer, intent(in) :: nk, nc
            character(len=*), intent(in) :: what_k, what_c
            if (size(f%stiffness) == 0) then
                call required_error(errors, 'force', 'stiffness', what_k, f%name, f%line)
            else if (size(f%stiffness) > nk) then
                call bad('stiffness', int_text(size(f%stiffness)) // ' values: a ' // &
                         trim(f%type) // ' takes ' // int_text(nk) // ' at most (' // &
                         what_k // ')')
            end if
            if (size(f%damping) > nc) call bad('damping', int_text(size(f%damping)) // &
                ' values: a ' // trim(f%type) // ' takes ' // int_text(nc) // ' (' // &
                what_c // ')')
        end subroutine counts

        !> K as 6 diagonal values or as the full matrix, one of them; C
        !> likewise, or none.
        subroutine bushing_values(f)
            type(force_input_t), intent(in) :: f
            if (f%has_stiffness_matrix .and. size(f%stiffness) > 0) then
                call bad('stiffness_matrix', 'give stiffness (diagonal) or stiffness_matrix, &
                         &not both')
            else if (.not. f%has_stiffness_matrix .and. size(f%stiffness) /= 6) then
                if (size(f%stiffness) == 0) then
                    call required_error(errors, 'force', 'stiffness', 'the diagonal of K: &
                        &x, y, z in N/m, then rotations about x, y, z in N m/rad', f%name, &
                        f%line)
                else
                    call bad('stiffness', int_text(size(f%stiffness)) // ' values: a &
                             &bushing takes 6 (the diagonal of K) or stiffness_matrix')
                end if
            end if
            if (f%has_damping_matrix .and. size(f%damping) > 0) then
                call bad('damping_matrix', 'give damping (diagonal) or damping_matrix, &
                         &not both')
            else if (size(f%damping) /= 0 .and. size(f%damping) /= 6) then
                call bad('damping', int_text(size(f%damping)) // ' values: a bushing &
                         &takes 6 (the diagonal of C) or damping_matrix')
            end if
        end subroutine bushing_values

        !> A load that is not zero: F or n, and s(t).
        subroutine load_values(f, own)
            type(force_input_t), intent(in) :: f
            type(entry_t), intent(in) :: own(:)
            if (.not. maxval(abs([f%force, f%torque])) > 0.0_wp) call bad('force', 'an &
                &applied load needs force or torque (both are zero)')
            if (.not. maxval(abs([f%coefficients, f%amplitude])) > 0.0_wp) &
                call bad('coefficients', &
                's(t) is zero: give coefficients (s = c0 + c1 t + ...) or amplitude')
            if (size(f%stiffness) + size(f%damping) > 0 .or. &
                has_entry(own, 'force', 'free_length', i) .or. &
                has_entry(own, 'force', 'free_angle', i)) &
                call bad(merge('stiffness  ', 'free_length', size(f%stiffness) > 0), &
                         'an applied load has no spring or damper')
        end subroutine load_values

        !> Variables the type does not read: a mistake, not to pass silently.
        subroutine unused(own, vars)
            type(entry_t), intent(in) :: own(:)
            character(len=*), intent(in) :: vars(:)
            integer :: v
            do v = 1, size(vars)
                if (has_entry(own, 'force', trim(vars(v)), i)) call bad(trim(vars(v)), &
                    'not read by a ' // trim(scene%forces(i)%type) // ' element')
            end do
        end subroutine unused
    end subroutine check_forces
end module flexmbs_io_force_checks
