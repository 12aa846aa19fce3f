!> Sparse LU through KLU (SuiteSparse), real and complex on one pattern.
!>
!> `klu_factor_t` owns a handle of the C shim `klu_shim.c`, which keeps
!> `klu_l_common`, the symbolic analysis, a copy of the CSC pattern and the
!> real and complex numeric factorisations. The pattern is analysed once;
!> `factor` chooses a new pivot order, `refactor` reuses the last one while
!> KLU's rcond and pivot-growth estimates say it is still good (threshold in
!> the shim, see `klu_refactor_degrade_ratio`) and factors afresh otherwise.
!>
!> The KLU objects have exactly one owner: the `klu_factor_t` that analysed
!> them, recognised by its address. A copy made by assignment (also as a
!> component of a `klu_solver_t`) owns nothing: it neither uses nor frees the
!> original's objects and reports 'not analysed' until analysed itself. So
!> copies and the compiler's temporaries can never free twice. (A defined
!> assignment that re-analyses would be nicer, but gfortran 12 bypasses it in
!> polymorphic assignment and moves its result in component assignment.)
module flexmbs_linalg_klu
    use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_associated, c_loc, c_int, &
        c_int64_t, c_double, c_double_complex
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix, reason_non_finite
    implicit none
    private

    ! Return codes of the shim (FLEXMBS_KLU_* in klu_shim.c).
    integer(c_int), parameter :: code_ok = 0
    integer(c_int), parameter :: code_singular = 1
    integer(c_int), parameter :: code_out_of_memory = -2
    integer(c_int), parameter :: code_invalid = -3
    integer(c_int), parameter :: code_too_large = -4
    integer(c_int), parameter :: code_not_analysed = -10
    ! Orderings, as in klu_shim.c.
    integer, parameter, public :: klu_ordering_amd = 0
    integer, parameter, public :: klu_ordering_nd = 1
    integer, parameter, public :: klu_ordering_auto = 2
    integer(c_int), parameter :: code_not_factored = -11
    integer(c_int), parameter :: code_not_finite = -12

    !> Which factorisation `stats` reports on.
    integer, parameter, public :: klu_part_real = 0
    integer, parameter, public :: klu_part_complex = 1

    !> Counters and estimates of one factorisation (real or complex).
    type, public :: klu_stats_t
        integer(i8) :: nfactor = 0    !! fresh factorisations (new pivot order)
        integer(i8) :: nrefactor = 0  !! accepted refactorisations (old pivot order)
        real(wp) :: rcond = 0.0_wp    !! KLU's min |U_kk| / max |U_kk| of the latest
        real(wp) :: rgrowth = 0.0_wp  !! KLU's reciprocal pivot growth of the latest fresh one
        logical :: factored = .false. !! a factorisation is alive
    end type klu_stats_t

    !> KLU factorisation of square sparse matrices sharing one CSC pattern.
    type, public :: klu_factor_t
        private
        type(c_ptr) :: handle = c_null_ptr !! the shim's object, valid only for its owner
        type(c_ptr) :: owner = c_null_ptr  !! address of the owning object's `n`
        integer :: n = 0
        integer(i8) :: nnz = 0
    contains
        procedure :: analyse => klu_analyse
        procedure :: ordering_used => klu_ordering_used
        procedure, private :: factor_real => klu_factor_real
        procedure, private :: factor_complex => klu_factor_complex
        generic :: factor => factor_real, factor_complex
        procedure, private :: refactor_real => klu_refactor_real
        procedure, private :: refactor_complex => klu_refactor_complex
        generic :: refactor => refactor_real, refactor_complex
        procedure, private :: solve_real => klu_solve_real
        procedure, private :: solve_complex => klu_solve_complex
        generic :: solve => solve_real, solve_complex
        procedure :: stats => klu_stats
        procedure :: order => klu_order
        procedure :: nonzeros => klu_nonzeros
        procedure :: predicted_fill => klu_predicted_fill
        procedure :: factor_nonzeros => klu_factor_nonzeros
        procedure :: is_analysed => klu_is_analysed
        procedure :: destroy => klu_destroy
        final :: klu_final
    end type klu_factor_t

    public :: klu_refactor_degrade_ratio, klu_ordering_name

    interface
        function shim_create() bind(C, name='flexmbs_klu_create') result(handle)
            import :: c_ptr
            type(c_ptr) :: handle
        end function shim_create

        subroutine shim_free(handle) bind(C, name='flexmbs_klu_free')
            import :: c_ptr
            type(c_ptr), intent(inout) :: handle
        end subroutine shim_free

        function shim_analyse(handle, n, colptr, rowind, ordering) &
            bind(C, name='flexmbs_klu_analyse') result(code)
            import :: c_ptr, c_int, c_int64_t
            type(c_ptr), value :: handle
            integer(c_int64_t), value :: n
            integer(c_int64_t), intent(in) :: colptr(*), rowind(*)
            integer(c_int), value :: ordering
            integer(c_int) :: code
        end function shim_analyse

        function shim_ordering_used(handle) bind(C, name='flexmbs_klu_ordering_used') &
            result(ordering)
            import :: c_ptr, c_int
            type(c_ptr), value :: handle
            integer(c_int) :: ordering
        end function shim_ordering_used

        function shim_factor(handle, values) bind(C, name='flexmbs_klu_factor') result(code)
            import :: c_ptr, c_int, c_double
            type(c_ptr), value :: handle
            real(c_double), intent(in) :: values(*)
            integer(c_int) :: code
        end function shim_factor

        function shim_refactor(handle, values) bind(C, name='flexmbs_klu_refactor') &
            result(code)
            import :: c_ptr, c_int, c_double
            type(c_ptr), value :: handle
            real(c_double), intent(in) :: values(*)
            integer(c_int) :: code
        end function shim_refactor

        function shim_zfactor(handle, values) bind(C, name='flexmbs_klu_zfactor') &
            result(code)
            import :: c_ptr, c_int, c_double_complex
            type(c_ptr), value :: handle
            complex(c_double_complex), intent(in) :: values(*)
            integer(c_int) :: code
        end function shim_zfactor

        function shim_zrefactor(handle, values) bind(C, name='flexmbs_klu_zrefactor') &
            result(code)
            import :: c_ptr, c_int, c_double_complex
            type(c_ptr), value :: handle
            complex(c_double_complex), intent(in) :: values(*)
            integer(c_int) :: code
        end function shim_zrefactor

        function shim_solve(handle, nrhs, b) bind(C, name='flexmbs_klu_solve') result(code)
            import :: c_ptr, c_int, c_int64_t, c_double
            type(c_ptr), value :: handle
            integer(c_int64_t), value :: nrhs
            real(c_double), intent(inout) :: b(*)
            integer(c_int) :: code
        end function shim_solve

        function shim_zsolve(handle, nrhs, b) bind(C, name='flexmbs_klu_zsolve') result(code)
            import :: c_ptr, c_int, c_int64_t, c_double_complex
            type(c_ptr), value :: handle
            integer(c_int64_t), value :: nrhs
            complex(c_double_complex), intent(inout) :: b(*)
            integer(c_int) :: code
        end function shim_zsolve

        function shim_stats(handle, part, nfactor, nrefactor, rcond, rgrowth, factored) &
            bind(C, name='flexmbs_klu_stats') result(code)
            import :: c_ptr, c_int, c_int64_t, c_double
            type(c_ptr), value :: handle
            integer(c_int), value :: part
            integer(c_int64_t), intent(out) :: nfactor, nrefactor
            real(c_double), intent(out) :: rcond, rgrowth
            integer(c_int), intent(out) :: factored
            integer(c_int) :: code
        end function shim_stats

        function shim_predicted_fill(handle, lnz, unz) &
            bind(C, name='flexmbs_klu_predicted_fill') result(code)
            import :: c_ptr, c_int, c_double
            type(c_ptr), value :: handle
            real(c_double), intent(out) :: lnz, unz
            integer(c_int) :: code
        end function shim_predicted_fill

        function shim_factor_nonzeros(handle, part) &
            bind(C, name='flexmbs_klu_factor_nonzeros') result(nnz)
            import :: c_ptr, c_int, c_int64_t
            type(c_ptr), value :: handle
            integer(c_int), value :: part
            integer(c_int64_t) :: nnz
        end function shim_factor_nonzeros

        function shim_degrade_ratio() bind(C, name='flexmbs_klu_refactor_degrade_ratio') &
            result(ratio)
            import :: c_double
            real(c_double) :: ratio
        end function shim_degrade_ratio
    end interface

contains

    !> Analyse the pattern of n x n matrices in CSC form (0-based, no
    !> duplicates). Replaces any earlier pattern and factorisations.
    !> `ordering`: klu_ordering_amd, _nd (nested dissection by METIS) or
    !> _auto (the default: ND for large matrices on which AMD predicts much
    !> fill, see klu_shim.c).
    subroutine klu_analyse(self, n, colptr, rowind, status, ordering)
        class(klu_factor_t), intent(inout) :: self
        integer, intent(in) :: n                  !! matrix order
        integer(i8), intent(in) :: colptr(:)      !! size n+1, 0-based offsets
        integer(i8), intent(in) :: rowind(:)      !! size >= colptr(n+1), 0-based rows
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: ordering
        integer(c_int) :: code, order
        character(len=160) :: msg

        order = klu_ordering_auto
        if (present(ordering)) order = int(ordering, c_int)
        if (order < klu_ordering_amd .or. order > klu_ordering_auto) then
            write (msg, '(a,i0,a)') 'klu analyse: ordering = ', order, ': unknown'
            call status%set(status_bad_input, trim(msg))
            return
        end if

        if (n <= 0) then
            write (msg, '(a,i0,a)') 'klu analyse: n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (size(colptr) /= n + 1) then
            write (msg, '(a,i0,a,i0)') 'klu analyse: colptr has size ', size(colptr), &
                ', expected n+1 = ', n + 1
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (colptr(n + 1) > size(rowind, kind=i8)) then
            write (msg, '(a,i0,a,i0,a)') 'klu analyse: colptr(n+1) = ', colptr(n + 1), &
                ' nonzeros but rowind has ', size(rowind), ' entries'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (.not. owns(self)) then
            ! Never touch a handle copied from another object.
            self%handle = shim_create()
            self%owner = address_of(self)
        end if
        if (.not. c_associated(self%handle)) then
            call status%set(status_solver_failure, 'klu analyse: out of memory')
            return
        end if
        self%n = 0
        self%nnz = 0
        code = shim_analyse(self%handle, int(n, c_int64_t), colptr, rowind, order)
        if (code /= code_ok) then
            call set_error(status, code, 'klu analyse')
            return
        end if
        self%n = n
        self%nnz = colptr(n + 1)
    end subroutine klu_analyse

    !> 'amd' or 'nd' for klu_ordering_amd or _nd, '' for anything else (-1:
    !> not analysed).
    pure function klu_ordering_name(code) result(name)
        integer, intent(in) :: code
        character(len=:), allocatable :: name
        select case (code)
        case (klu_ordering_amd); name = 'amd'
        case (klu_ordering_nd); name = 'nd'
        case default; name = ''
        end select
    end function klu_ordering_name

    !> The ordering the last analysis used: klu_ordering_amd or _nd (-1: none).
    integer function klu_ordering_used(self)
        class(klu_factor_t), intent(in) :: self
        klu_ordering_used = -1
        if (self%is_analysed()) klu_ordering_used = int(shim_ordering_used(self%handle))
    end function klu_ordering_used

    !> Factor afresh (new pivot order) the matrix with the analysed pattern.
    subroutine klu_factor_real(self, values, status)
        class(klu_factor_t), intent(inout) :: self
        real(wp), intent(in) :: values(:) !! one value per pattern slot
        type(status_t), intent(out) :: status
        if (.not. values_fit(self, size(values, kind=i8), 'klu factor', status)) return
        call set_error(status, shim_factor(handle_of(self), values), 'klu factor (real)')
    end subroutine klu_factor_real

    !> Factor afresh a complex matrix with the analysed pattern.
    subroutine klu_factor_complex(self, values, status)
        class(klu_factor_t), intent(inout) :: self
        complex(wp), intent(in) :: values(:) !! one value per pattern slot
        type(status_t), intent(out) :: status
        if (.not. values_fit(self, size(values, kind=i8), 'klu factor', status)) return
        call set_error(status, shim_zfactor(handle_of(self), values), 'klu factor (complex)')
    end subroutine klu_factor_complex

    !> Factor new values reusing the last pivot order when it is still good;
    !> the first call, or a degraded pivot order, factors afresh.
    subroutine klu_refactor_real(self, values, status)
        class(klu_factor_t), intent(inout) :: self
        real(wp), intent(in) :: values(:) !! one value per pattern slot
        type(status_t), intent(out) :: status
        if (.not. values_fit(self, size(values, kind=i8), 'klu refactor', status)) return
        call set_error(status, shim_refactor(handle_of(self), values), 'klu refactor (real)')
    end subroutine klu_refactor_real

    !> Complex counterpart of the real refactor.
    subroutine klu_refactor_complex(self, values, status)
        class(klu_factor_t), intent(inout) :: self
        complex(wp), intent(in) :: values(:) !! one value per pattern slot
        type(status_t), intent(out) :: status
        if (.not. values_fit(self, size(values, kind=i8), 'klu refactor', status)) return
        call set_error(status, shim_zrefactor(handle_of(self), values), 'klu refactor (complex)')
    end subroutine klu_refactor_complex

    !> Overwrite b with A⁻¹ b using the real factorisation.
    subroutine klu_solve_real(self, b, status)
        class(klu_factor_t), intent(inout) :: self
        real(wp), intent(inout) :: b(:) !! size n
        type(status_t), intent(out) :: status
        if (.not. rhs_fits(self, size(b), status)) return
        call set_error(status, shim_solve(handle_of(self), 1_c_int64_t, b), 'klu solve (real)')
    end subroutine klu_solve_real

    !> Overwrite b with A⁻¹ b using the complex factorisation.
    subroutine klu_solve_complex(self, b, status)
        class(klu_factor_t), intent(inout) :: self
        complex(wp), intent(inout) :: b(:) !! size n
        type(status_t), intent(out) :: status
        if (.not. rhs_fits(self, size(b), status)) return
        call set_error(status, shim_zsolve(handle_of(self), 1_c_int64_t, b), 'klu solve (complex)')
    end subroutine klu_solve_complex

    !> Counters and estimates of the real (klu_part_real) or complex
    !> (klu_part_complex) factorisation.
    function klu_stats(self, part) result(stats)
        class(klu_factor_t), intent(in) :: self
        integer, intent(in) :: part !! klu_part_real or klu_part_complex
        type(klu_stats_t) :: stats
        integer(c_int64_t) :: nfactor, nrefactor
        real(c_double) :: rcond, rgrowth
        integer(c_int) :: factored, code
        code = shim_stats(handle_of(self), int(part, c_int), nfactor, nrefactor, rcond, rgrowth, &
            factored)
        if (code /= code_ok) return
        stats%nfactor = nfactor
        stats%nrefactor = nrefactor
        stats%rcond = rcond
        stats%rgrowth = rgrowth
        stats%factored = factored /= 0
    end function klu_stats

    !> Matrix order (0 before analysis).
    pure integer function klu_order(self)
        class(klu_factor_t), intent(in) :: self
        klu_order = self%n
    end function klu_order

    !> Number of pattern slots (0 before analysis).
    pure integer(i8) function klu_nonzeros(self)
        class(klu_factor_t), intent(in) :: self
        klu_nonzeros = self%nnz
    end function klu_nonzeros

    !> KLU's estimates of the nonzeros of L and U under the analysed
    !> ordering (symbolic analysis, before any factorisation): the fill that
    !> `linear_solver = 'auto'` compares with the pattern's own nonzeros.
    !> Both are -1 before an analysis.
    subroutine klu_predicted_fill(self, lnz, unz)
        class(klu_factor_t), intent(in) :: self
        real(wp), intent(out) :: lnz !! predicted nonzeros of L
        real(wp), intent(out) :: unz !! predicted nonzeros of U
        real(c_double) :: l, u
        integer(c_int) :: code
        code = shim_predicted_fill(handle_of(self), l, u)
        lnz = l
        unz = u
    end subroutine klu_predicted_fill

    !> Nonzeros of L + U of the real (klu_part_real) or complex
    !> (klu_part_complex) factorisation; -1 when none is alive.
    integer(i8) function klu_factor_nonzeros(self, part)
        class(klu_factor_t), intent(in) :: self
        integer, intent(in) :: part !! klu_part_real or klu_part_complex
        klu_factor_nonzeros = shim_factor_nonzeros(handle_of(self), int(part, c_int))
    end function klu_factor_nonzeros

    !> True once a pattern has been analysed.
    logical function klu_is_analysed(self)
        class(klu_factor_t), intent(in) :: self
        klu_is_analysed = self%n > 0 .and. owns(self)
    end function klu_is_analysed

    !> Free the KLU objects; the object may be analysed again afterwards.
    subroutine klu_destroy(self)
        class(klu_factor_t), intent(inout) :: self
        if (owns(self)) call shim_free(self%handle)
        self%handle = c_null_ptr
        self%owner = c_null_ptr
        self%n = 0
        self%nnz = 0
    end subroutine klu_destroy

    subroutine klu_final(self)
        type(klu_factor_t), intent(inout) :: self
        call self%destroy()
    end subroutine klu_final

    !> Fraction of the fresh rcond below which a refactorisation
    !> is rejected in favour of a fresh one (a named constant in the shim).
    real(wp) function klu_refactor_degrade_ratio()
        klu_refactor_degrade_ratio = shim_degrade_ratio()
    end function klu_refactor_degrade_ratio

    !> The address that identifies an object as the owner of its handle.
    function address_of(self) result(address)
        class(klu_factor_t), intent(in), target :: self
        type(c_ptr) :: address
        address = c_loc(self%n)
    end function address_of

    !> True when self holds a handle it created (not a bitwise copy's).
    logical function owns(self)
        class(klu_factor_t), intent(in) :: self
        owns = c_associated(self%handle) .and. c_associated(self%owner, address_of(self))
    end function owns

    !> The handle if self owns it, else a null pointer (which the shim
    !> reports as 'not analysed').
    function handle_of(self) result(handle)
        class(klu_factor_t), intent(in) :: self
        type(c_ptr) :: handle
        handle = c_null_ptr
        if (owns(self)) handle = self%handle
    end function handle_of

    logical function values_fit(self, nvalues, where, status)
        type(klu_factor_t), intent(in) :: self
        integer(i8), intent(in) :: nvalues
        character(len=*), intent(in) :: where
        type(status_t), intent(inout) :: status
        character(len=160) :: msg
        values_fit = .false.
        if (.not. self%is_analysed()) then
            call status%set(status_bad_input, where // ': no pattern analysed; call analyse')
        else if (nvalues /= self%nnz) then
            write (msg, '(a,i0,a,i0,a)') where // ': ', nvalues, ' values for a pattern of ', &
                self%nnz, ' slots'
            call status%set(status_bad_input, trim(msg))
        else
            values_fit = .true.
        end if
    end function values_fit

    logical function rhs_fits(self, nb, status)
        type(klu_factor_t), intent(in) :: self
        integer, intent(in) :: nb
        type(status_t), intent(inout) :: status
        character(len=160) :: msg
        rhs_fits = nb == self%n .and. self%n > 0
        if (.not. rhs_fits) then
            write (msg, '(a,i0,a,i0)') 'klu solve: right-hand side of size ', nb, &
                ' for a matrix of order ', self%n
            call status%set(status_bad_input, trim(msg))
        end if
    end function rhs_fits

    !> Map a shim code to a status (nothing on success).
    subroutine set_error(status, code, where)
        type(status_t), intent(inout) :: status
        integer(c_int), intent(in) :: code
        character(len=*), intent(in) :: where
        select case (code)
        case (code_ok)
        case (code_singular)
            call status%set(status_solver_failure, where // ': matrix is singular', &
                reason_singular_matrix)
        case (code_not_finite)
            call status%set(status_solver_failure, where // ': a matrix value is Inf or NaN', &
                reason_non_finite)
        case (code_out_of_memory)
            call status%set(status_solver_failure, where // ': out of memory')
        case (code_too_large)
            call status%set(status_solver_failure, where // ': matrix too large for KLU')
        case (code_not_analysed)
            call status%set(status_bad_input, where // ': no pattern analysed; call analyse')
        case (code_not_factored)
            call status%set(status_bad_input, where // ': nothing factored; call factor')
        case (code_invalid)
            call status%set(status_bad_input, where // &
                ': invalid pattern or values (check colptr, rowind: 0-based, no duplicates)')
        case default
            call status%set(status_solver_failure, where // ': unexpected KLU error')
        end select
    end subroutine set_error
end module flexmbs_linalg_klu
