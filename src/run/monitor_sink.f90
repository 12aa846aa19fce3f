!> A sink that records, at the same times as the trajectory, the drift of
!> the constraints (‖g‖∞ and ‖G v + g_I‖∞) and the mechanical energy of a
!> formulated mechanical problem, for the HDF5 file (/monitor) and the run
!> summary.
!>
!> Energy: a multibody system's kinetic plus potential energy (flexible
!> bodies: kinetic, strain and the potential of their constant applied
!> forces); a rigid chain's kinetic plus potential; a flexible body's strain
!> plus kinetic energy minus the work of its applied forces from the start.
!>
!> Reactions (multibody systems): for joint k, the force and torque it
!> exerts on the body of marker i and of marker j (mbs_system_t%joint_reaction,
!> our sign of λ), 12 numbers per joint and record: F_i, n_i, F_j, n_j, from
!> the multipliers consistent with the record's q and v (the formulation's
!> consistent_multipliers), as the HDF5 file's /joints.
module flexmbs_run_monitor_sink
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_mbs_formulation, only: block_q, block_v, block_lambda
    use flexmbs_mbs_formulation, only: formulation_t
    use flexmbs_mbs_system, only: mbs_system_t
    implicit none
    private

    !> The monitor (see the module): the formulated problem it watches and its
    !> table of drift and energy, with joint reactions for multibody systems.
    type, extends(sink_t), public :: monitor_sink_t
        type(formulation_t), pointer :: formulation => null()
        class(mechanical_problem_t), pointer :: mechanical => null()
        logical :: every_step = .false.      !! as the trajectory sink
        !> a resumed run: its t0 is the checkpoint's step, recorded already
        logical :: resumed = .false.
        real(wp), allocatable :: q_start(:)  !! flexible body: the work's origin
        integer :: records = 0
        !> (4, records): t, ‖g‖∞, ‖G v + g_I‖∞, energy
        real(wp), allocatable :: table(:, :)
        !> (12 joints, records): joint reactions of a multibody system
        real(wp), allocatable :: reactions(:, :)
    contains
        procedure :: output => monitor_output
        procedure :: wants_steps => monitor_wants_steps
        procedure :: step => monitor_step
        procedure :: replay => record
    end type monitor_sink_t

contains

    subroutine monitor_output(self, t, y, status)
        class(monitor_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
        if (.not. self%every_step) call record(self, t, y, status)
    end subroutine monitor_output

    logical function monitor_wants_steps(self)
        class(monitor_sink_t), intent(in) :: self
        monitor_wants_steps = self%every_step
    end function monitor_wants_steps

    subroutine monitor_step(self, nr, t_old, t, y, dense, stop, status)
        class(monitor_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        if (nr == 1 .and. self%resumed) return
        if (self%every_step) call record(self, t, y, status)
    end subroutine monitor_step

    !> Append one row (the table doubles when full); also the records a
    !> resumed run keeps, given again.
    subroutine record(self, t, y, status)
        class(monitor_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        real(wp), allocatable :: grown(:, :), grown_reactions(:, :)
        real(wp) :: position, velocity, force(3, 2), torque(3, 2)
        real(wp), allocatable :: lambda(:)
        type(status_t) :: st
        integer :: k, nj, stat
        nj = 0
        select type (m => self%mechanical)
        type is (mbs_system_t)
            nj = m%joint_count()
        end select
        if (.not. allocated(self%table)) allocate (self%table(4, 64), &
                                                   self%reactions(12 * nj, 64))
        if (self%records == size(self%table, 2)) then
            allocate (grown(4, 2 * self%records), grown_reactions(12 * nj, 2 * self%records), &
                stat=stat)
            if (stat /= 0) then
                call out_of_memory(status, 'monitor table', (4 + 12_i8 * nj) * 2 * self%records, 8)
                return
            end if
            grown(:, 1:self%records) = self%table
            call move_alloc(grown, self%table)
            grown_reactions(:, 1:self%records) = self%reactions
            call move_alloc(grown_reactions, self%reactions)
        end if
        call self%formulation%drift(t, y, position, velocity, st)
        self%records = self%records + 1
        self%table(:, self%records) = [t, position, velocity, &
            energy(self, y(self%formulation%offset(block_q) + 1:self%formulation%last(block_q)), &
                   y(self%formulation%offset(block_v) + 1:self%formulation%last(block_v)))]
        select type (m => self%mechanical)
        type is (mbs_system_t)
            associate (f => self%formulation)
                if (nj == 0) return
                allocate (lambda(f%block_size(block_lambda)))
                call f%consistent_multipliers(t, y, lambda, status)
                if (.not. status%ok()) return
                do k = 1, nj
                    call m%joint_reaction(k, t, y(f%offset(block_q) + 1:f%last(block_q)), lambda, &
                                          force, torque)
                    self%reactions(12 * k - 11:12 * k, self%records) = [force(:, 1), &
                        torque(:, 1), force(:, 2), torque(:, 2)]
                end do
            end associate
        end select
    end subroutine record

    real(wp) function energy(self, q, v) result(e)
        class(monitor_sink_t), intent(inout) :: self
        real(wp), intent(in) :: q(:), v(:)
        ! the work of applied loads counted from the run's start
        if (allocated(self%q_start)) then
            e = self%mechanical%total_energy(q, v, self%q_start)
        else
            e = self%mechanical%total_energy(q, v)
        end if
    end function energy
end module flexmbs_run_monitor_sink
