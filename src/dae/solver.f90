!> The abstract DAE solver: every solver integrates a problem from (t, y)
!> to t_end with common options, feeds a sink and fills common statistics.
!>
!> `integrate` takes either a `dae_problem_t` or a mechanical problem with
!> its formulation (a `dae_problem_t` over the same bodies): a solver with
!> a mechanical core (MEXAX) integrates the mechanical form directly, every
!> other one the formulation, so no caller needs to know which is which.
module flexmbs_dae_solver
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t
    use flexmbs_dae_problem, only: dae_problem_t
    use flexmbs_dae_mechanical_problem, only: mechanical_problem_t
    use flexmbs_dae_options, only: dae_options_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_sink, only: sink_t
    use flexmbs_dae_solver_setting, only: solver_setting_t
    implicit none
    private

    !> A DAE solver: `integrate` from (t, y) to t_end on a dae_problem_t or on a
    !> mechanical problem with its formulation; `name` for messages and tables.
    type, abstract, public :: dae_solver_t
    contains
        procedure(integrate_i), deferred :: integrate_dae
        procedure :: integrate_system => default_integrate_system
        generic :: integrate => integrate_dae, integrate_system
        procedure(name_i), deferred :: name
        procedure :: step_counts => default_step_counts
        procedure :: apply_setting => default_apply_setting
    end type dae_solver_t

    abstract interface
        !> Integrate from (t, y) to t_end. On return t and y hold the last
        !> point reached (t_end on success); on failure `status` says why and
        !> at which time, and `stats` what was spent.
        subroutine integrate_i(self, problem, t, y, t_end, options, stats, status, sink, yp)
            import :: dae_solver_t, dae_problem_t, dae_options_t, dae_stats_t, &
                status_t, sink_t, wp
            class(dae_solver_t), intent(inout) :: self
            class(dae_problem_t), intent(inout) :: problem
            include 'integrate_arguments.inc'
            real(wp), intent(inout), optional :: yp(:)
        end subroutine integrate_i
        function name_i(self) result(name)
            import :: dae_solver_t
            class(dae_solver_t), intent(in) :: self
            character(len=:), allocatable :: name
        end function name_i
    end interface

contains

    !> Integrate a mechanical problem from (t, y) to t_end. y is the state
    !> of `formulation`, the mechanical problem formulated as a DAE over the
    !> same bodies; a solver with a mechanical core overrides this and reads
    !> y as (q, v, λ), the layout of the index-2 formulation with constant
    !> mass. By default the formulation is integrated. On return as
    !> `integrate` on a dae_problem_t.
    subroutine default_integrate_system(self, mechanical, formulation, t, y, t_end, options, &
                                        stats, status, sink)
        class(dae_solver_t), intent(inout) :: self
        class(mechanical_problem_t), intent(inout) :: mechanical
        class(dae_problem_t), intent(inout) :: formulation
        include 'integrate_arguments.inc'
        call self%integrate_dae(formulation, t, y, t_end, options, stats, status, sink)
    end subroutine default_integrate_system

    !> Steps attempted and accepted so far in the running integration, for
    !> a live display; 0 and 0 from a solver that does not count as it goes.
    subroutine default_step_counts(self, attempted, accepted)
        class(dae_solver_t), intent(in) :: self
        integer, intent(out) :: attempted, accepted
        attempted = 0
        accepted = 0
    end subroutine default_step_counts

    !> Take one of the solver's own settings of a scene (run/solver_factory);
    !> `applied` is false for a setting of another solver, which the scene
    !> may give and this solver ignores. A solver with settings of its own
    !> overrides this; the values are checked when the integration starts.
    subroutine default_apply_setting(self, setting, applied)
        class(dae_solver_t), intent(inout) :: self
        type(solver_setting_t), intent(in) :: setting
        logical, intent(out) :: applied
        applied = .false.
    end subroutine default_apply_setting
end module flexmbs_dae_solver
