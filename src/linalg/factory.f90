!> Choice of the linear solver for iteration matrices c*M - J by name.
module flexmbs_linalg_factory
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_bad_input
    use flexmbs_core_threads, only: default_blas_threads
    use flexmbs_linalg_matrix, only: matrix_t, storage_sparse, storage_dense, storage_identity
    use flexmbs_linalg_linear_solver, only: linear_solver_t, auto_sparse_threshold, &
        auto_mumps_min_order, auto_mumps_min_fill, linear_solver_names_text
    use flexmbs_linalg_dense, only: dense_solver_t
    use flexmbs_linalg_klu_solver, only: klu_solver_t
    use flexmbs_linalg_mumps_solver, only: mumps_solver_t
    use flexmbs_linalg_band, only: band_solver_t
    use flexmbs_linalg_shifted_pattern, only: shifted_pattern_t
    use flexmbs_linalg_klu, only: klu_factor_t, klu_ordering_auto, klu_ordering_amd, &
        klu_ordering_nd
    use flexmbs_linalg_mumps, only: mumps_ordering_auto, mumps_ordering_amd, &
        mumps_ordering_scotch
    implicit none
    private

    public :: new_linear_solver, klu_ordering_code, predicted_fill_ratio

contains

    !> A new, not yet initialised solver: 'dense', 'klu', 'band', 'mumps', or
    !> 'auto', which picks dense for n < auto_sparse_threshold or a J that is
    !> not sparse, and a sparse LU otherwise: KLU, or MUMPS when the pattern
    !> of J (and M) is given and KLU's analysis predicts much fill on a large
    !> matrix (auto_mumps_min_order, auto_mumps_min_fill). For 'band', `lower`
    !> and `upper` (both or neither; negative = found by init) fix the
    !> bandwidths. Call `solver%init(mass, jac, status)` next. `ordering`
    !> ('auto' | 'amd' | 'nd', default 'auto') is the fill-reducing ordering
    !> of KLU, and of MUMPS with 'nd' meaning SCOTCH's nested dissection.
    subroutine new_linear_solver(name, n, jac_storage, solver, status, lower, upper, ordering, &
            classic_order, mass, jac)
        character(len=*), intent(in) :: name        !! 'auto' | 'dense' | 'klu' | 'band' | 'mumps'
        integer, intent(in) :: n                    !! order of the iteration matrix
        integer, intent(in) :: jac_storage          !! storage_* of the Jacobian
        class(linear_solver_t), allocatable, intent(out) :: solver
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: lower      !! lower bandwidth for 'band'
        integer, intent(in), optional :: upper      !! upper bandwidth for 'band'
        character(len=*), intent(in), optional :: ordering !! KLU: 'auto' | 'amd' | 'nd'
        !> dense LU: the classic elimination order, not LAPACK's (dense_solver_t)
        logical, intent(in), optional :: classic_order
        !> M (default: identity) and J with their patterns, for 'auto'
        type(matrix_t), intent(in), optional :: mass, jac
        type(dense_solver_t), allocatable :: dense
        type(band_solver_t), allocatable :: band
        type(klu_solver_t), allocatable :: klu
        type(mumps_solver_t), allocatable :: mumps
        integer :: order
        real(wp) :: fill
        character(len=160) :: msg

        call default_blas_threads()
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
        allocate (klu, mumps)
        klu%ordering = order
        mumps%ordering = mumps_ordering_auto
        if (order == klu_ordering_amd) mumps%ordering = mumps_ordering_amd
        if (order == klu_ordering_nd) mumps%ordering = mumps_ordering_scotch
        select case (trim(adjustl(name)))
        case ('auto')
            if (jac_storage == storage_sparse .and. n >= auto_sparse_threshold) then
                fill = 0.0_wp
                if (present(jac) .and. n >= auto_mumps_min_order) then
                    call predicted_fill_ratio(jac, fill, status, mass)
                    if (.not. status%ok()) return
                end if
                if (fill >= auto_mumps_min_fill) then
                    call move_alloc(mumps, solver)
                else
                    call move_alloc(klu, solver)
                end if
            else
                allocate (dense_solver_t :: solver)
            end if
        case ('dense')
            allocate (dense)
            if (present(classic_order)) dense%classic_order = classic_order
            call move_alloc(dense, solver)
        case ('klu', 'mumps')
            ! A sparse LU factors J as given; a difference Jacobian has no storage yet.
            if (jac_storage /= storage_sparse .and. jac_storage /= storage_dense) then
                call status%set(status_bad_input, "linear_solver = '" // trim(adjustl(name)) &
                    // "' needs the Jacobian in sparse (or dense) storage; use 'dense' or 'auto'")
                return
            end if
            if (trim(adjustl(name)) == 'klu') then
                call move_alloc(klu, solver)
            else
                call move_alloc(mumps, solver)
            end if
        case ('band')
            allocate (band)
            if (present(lower)) band%lower = lower
            if (present(upper)) band%upper = upper
            call move_alloc(band, solver)
        case default
            call status%set(status_bad_input, "linear_solver = '" // trim(name) // &
                "': unknown; use " // linear_solver_names_text)
        end select
    end subroutine new_linear_solver

    !> (nnz(L) + nnz(U)) / nnz(A) that KLU's symbolic analysis with AMD
    !> predicts for A = c*M - J on the union pattern of M (default: identity),
    !> J and the diagonal: the fill measure of `linear_solver = 'auto'`. Costs
    !> one AMD ordering of the pattern, no factorisation.
    subroutine predicted_fill_ratio(jac, fill, status, mass)
        type(matrix_t), intent(in) :: jac
        real(wp), intent(out) :: fill          !! predicted fill ratio
        type(status_t), intent(out) :: status
        type(matrix_t), intent(in), optional :: mass
        type(matrix_t) :: identity
        type(shifted_pattern_t) :: pattern
        type(klu_factor_t) :: lu
        real(wp) :: lnz, unz

        fill = 0.0_wp
        identity%storage = storage_identity
        identity%n = jac%n
        if (present(mass)) then
            call pattern%build(mass, jac, 'linear solver auto', status)
        else
            call pattern%build(identity, jac, 'linear solver auto', status)
        end if
        if (.not. status%ok()) return
        call lu%analyse(pattern%order(), pattern%column_pointers(), pattern%row_indices(), &
            status, klu_ordering_amd)
        if (.not. status%ok()) return
        call lu%predicted_fill(lnz, unz)
        fill = (lnz + unz) / real(pattern%nonzeros(), wp)
    end subroutine predicted_fill_ratio

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
