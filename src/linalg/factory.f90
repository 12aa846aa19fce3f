!> Choice of the linear solver for iteration matrices c*M - J by name.
module flexmbs_linalg_factory
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_linalg_matrix, only: storage_sparse, storage_dense
    use flexmbs_linalg_linear_solver, only: linear_solver_t, auto_sparse_threshold
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_klu_solver, only: klu_solver_t
    use flexmbs_linalg_band, only: band_solver_t
    use flexmbs_linalg_klu, only: klu_ordering_auto, klu_ordering_amd, klu_ordering_nd
    implicit none
    private

    public :: new_linear_solver, klu_ordering_code

contains

    !> A new, not yet initialised solver: 'dense', 'klu', 'band', or 'auto',
    !> which picks dense for n < auto_sparse_threshold or a J that is not
    !> sparse, and KLU otherwise. For 'band', `lower` and `upper` (both or
    !> neither; negative = found by init) fix the bandwidths. Call
    !> `solver%init(mass, jac, status)` next. `ordering` ('auto' | 'amd' | 'nd',
    !> default 'auto') is KLU's fill-reducing ordering.
    subroutine new_linear_solver(name, n, jac_storage, solver, status, lower, upper, ordering, &
            classic_order)
        character(len=*), intent(in) :: name        !! 'auto' | 'dense' | 'klu' | 'band'
        integer, intent(in) :: n                    !! order of the iteration matrix
        integer, intent(in) :: jac_storage          !! storage_* of the Jacobian
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: lower      !! lower bandwidth for 'band'
        integer, intent(in), optional :: upper      !! upper bandwidth for 'band'
        character(len=*), intent(in), optional :: ordering !! KLU: 'auto' | 'amd' | 'nd'
        !> dense: the classic elimination order, not LAPACK's (dense_solver_t)
        logical, intent(in), optional :: classic_order
        type(dense_solver_t), allocatable :: dense
        type(band_solver_t), allocatable :: band
        type(klu_solver_t), allocatable :: klu
        integer :: order
        character(len=160) :: msg

        if (n <= 0) then
            write (msg, '(a,i0,a)') 'linear solver: order n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        order = klu_ordering_auto
        if (present(ordering)) then
            order = klu_ordering_code(ordering)
            if (order < 0) then
                call status%set(status_bad_input, "sparse_ordering = '" // trim(ordering) // &
                    "': unknown; use 'auto', 'amd' or 'nd'")
                return
            end if
        end if
        allocate (klu)
        klu%ordering = order
        select case (trim(adjustl(name)))
        case ('auto')
            if (jac_storage == storage_sparse .and. n >= auto_sparse_threshold) then
                call move_alloc(klu, solver)
            else
                allocate (dense_solver_t :: solver)
            end if
        case ('dense')
            allocate (dense)
            if (present(classic_order)) dense%classic_order = classic_order
            call move_alloc(dense, solver)
        case ('klu')
            ! KLU factors J as given; a difference Jacobian has no storage yet.
            if (jac_storage /= storage_sparse .and. jac_storage /= storage_dense) then
                call status%set(status_bad_input, "linear_solver = 'klu' needs the " // &
                    "Jacobian in sparse (or dense) storage; use 'dense' or 'auto'")
                return
            end if
            call move_alloc(klu, solver)
        case ('band')
            allocate (band)
            if (present(lower)) band%lower = lower
            if (present(upper)) band%upper = upper
            call move_alloc(band, solver)
        case default
            call status%set(status_bad_input, "linear_solver = '" // trim(name) // &
                "': unknown; use 'auto', 'dense', 'klu' or 'band'")
        end select
    end subroutine new_linear_solver

    !> klu_ordering_* of 'auto', 'amd' or 'nd'; -1 for anything else.
    pure integer function klu_ordering_code(name) result(code)
        character(len=*), intent(in) :: name
        select case (trim(adjustl(name)))
        case ('auto'); code = klu_ordering_auto
        case ('amd'); code = klu_ordering_amd
        case ('nd'); code = klu_ordering_nd
        case default; code = -1
        end select
    end function klu_ordering_code
end module flexmbs_linalg_factory
