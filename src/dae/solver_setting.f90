!> One of a solver's own settings as a scene gives it: its name and its
!> value, already read and checked against the schema's kind and rule.
!> The scene reader makes one per own setting given, and the solver's
!> `apply_setting` takes those it knows: a new solver setting is declared
!> in the scene schema and applied in the solver's own module, nowhere else.
module flexmbs_dae_solver_setting
    use flexmbs_core_kinds, only: wp
    implicit none
    private

    !> The value in the component of its kind; the others stay unset. A
    !> string value with choices is lower case.
    type, public :: solver_setting_t
        character(len=24) :: name = ''
        real(wp) :: real_value = 0.0_wp
        integer :: integer_value = 0
        logical :: logical_value = .false.
        character(len=32) :: string_value = ''
    end type solver_setting_t
end module flexmbs_dae_solver_setting
