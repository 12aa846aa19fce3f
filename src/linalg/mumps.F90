!> Multifrontal sparse LU through MUMPS, real and complex: its sequential
!> build, or its MPI build (`make MPI=1`), whose other ranks make every call
!> with rank 0 (linalg/mumps_service).
!>
!> A binding over MUMPS's native Fortran interface: `mumps_real_t` holds a
!> DMUMPS_STRUC, `mumps_complex_t` a ZMUMPS_STRUC, both unsymmetric (SYM = 0)
!> with the host working (PAR = 1) on the communicator kept in the object
!> (default: MPI_COMM_WORLD of the mpif.h of the MUMPS build linked). The
!> life of an object: `configure` (optional), `analyse` once on a fixed CSC pattern
!> (JOB = -1 the first time, then JOB = 1 on the centralised assembled
!> matrix, 1-based IRN/JCN built once from the CSC), `factor` for every new
!> set of values (JOB = 2), `solve` with one or several right-hand sides
!> (JOB = 3), and `destroy` or finalisation (JOB = -2).
!>
!> What is checked:
!> - Every negative INFO(1) becomes a status naming the MUMPS error code and
!>   its meaning (users' guide, "Error diagnostics"). Workspace errors of the
!>   factorisation (-8, -9, -17, -20) are retried with ICNTL(14), the
!>   percentage by which MUMPS enlarges its estimated workspace, multiplied
!>   by `memory_growth`, at most `max_memory_retries` times; the larger value
!>   stays for later factorisations.
!> - The real/complex workspace is ours (WK_USER, LWK_USER), sized by the
!>   analysis' estimate INFO(8) and kept across factorisations: MUMPS would
!>   otherwise allocate its array S afresh at each one, and the kernel's
!>   zeroing of new pages cost 12 % of a refined coupler's run (RADAU5,
!>   condensed, 8x32x8; 684 k page faults against 216 k). Error -9 grows it
!>   to the largest of the estimate, `memory_growth` times its size and its
!>   size plus the entries MUMPS reports missing (INFO(2)).
!> - Null pivots: ICNTL(24) = 1 makes MUMPS detect null pivots instead of
!>   dividing by them; their count INFOG(28) > 0 is reported as a singular
!>   matrix, like INFO(1) = -10. The threshold is absolute and tiny
!>   (CNTL(3) = null_pivot_threshold < 0): as with KLU, only a pivot that is
!>   zero counts. MUMPS's default, a multiple of eps times the norm of the
!>   matrix, flags the legitimate pivots of the formulations' iteration
!>   matrices, whose constraint rows pivot at O(h²) against O(1/h) entries
!>   (measured: RADAU5 stopped at t0 on the fine five-body scene).
!> - On request (`error_analysis`), ICNTL(11) = 1: after each single
!>   right-hand-side solve MUMPS estimates the componentwise backward errors
!>   ω1, ω2 (RINFOG(7:8)), the condition numbers cond1, cond2 (RINFOG(10:11))
!>   and a forward error bound (RINFOG(9)); `accuracy` returns them with
!>   rcond = 1 / max(cond1, cond2). This costs about as much as a few solves.
!>
!> MUMPS's own printing is off (ICNTL(1:4)) unless `verbose` is set.
!>
!> Each object is owned by the variable that initialised its MUMPS instance,
!> recognised by address (as in flexmbs_linalg_klu): a copy made by
!> assignment shares the instance's pointers but never uses or terminates
!> them, and reports 'not analysed' until analysed itself.
module flexmbs_linalg_mumps
    use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_loc, c_associated
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_bad_input, status_solver_failure, &
        reason_singular_matrix, reason_none
    use flexmbs_core_resources, only: out_of_memory
    use flexmbs_linalg_mumps_service, only: mumps_announce, take_instance, free_instance, &
        call_real, call_complex, process_count
    use flexmbs_core_text, only: int_text
    implicit none
    private

    include 'dmumps_struc.h'
    include 'zmumps_struc.h'

    !> CNTL(3) of the null-pivot detection: |pivot| <= 1e-200 (absolute).
    real(wp), parameter :: null_pivot_threshold = -1.0e-200_wp

    !> Fill-reducing orderings: MUMPS's ICNTL(7) codes. Debian's sequential
    !> build has AMD, AMF, QAMD, SCOTCH and PORD, not METIS; MUMPS falls back
    !> to another ordering when the one asked for is missing, and
    !> `ordering_used` reports what it did.
    integer, parameter, public :: mumps_ordering_amd = 0
    integer, parameter, public :: mumps_ordering_amf = 2
    integer, parameter, public :: mumps_ordering_scotch = 3
    integer, parameter, public :: mumps_ordering_pord = 4
    integer, parameter, public :: mumps_ordering_metis = 5
    integer, parameter, public :: mumps_ordering_qamd = 6
    integer, parameter, public :: mumps_ordering_auto = 7

    !> Retries of a factorisation that ran out of workspace (INFO(1) = -8,
    !> -9, -17, -20), each with ICNTL(14) times `memory_growth`: 20 % (the
    !> default) becomes 40, 80, 160, 320 %, beyond which the estimate, not
    !> the slack, is wrong.
    integer, parameter, public :: mumps_max_memory_retries = 4
    integer, parameter :: memory_growth = 2

    ! JOB values (users' guide, "JOB").
    integer, parameter :: job_init = -1, job_end = -2, job_analyse = 1, job_factor = 2, &
        job_solve = 3
    ! Stages of an object.
    integer, parameter :: stage_none = 0, stage_initialised = 1, stage_analysed = 2, &
        stage_factored = 3

    !> MUMPS's accuracy estimates of the latest solve (ICNTL(11) = 1).
    type, public :: mumps_accuracy_t
        logical :: available = .false. !! estimates were computed
        real(wp) :: residual = 0.0_wp  !! scaled residual ‖Ax-b‖∞ / (‖A‖∞ ‖x‖∞), RINFOG(6)
        real(wp) :: omega1 = 0.0_wp    !! componentwise backward error ω1, RINFOG(7)
        real(wp) :: omega2 = 0.0_wp    !! componentwise backward error ω2, RINFOG(8)
        real(wp) :: forward_error = 0.0_wp !! bound ω1 cond1 + ω2 cond2, RINFOG(9)
        real(wp) :: cond1 = 0.0_wp     !! condition number for ω1, RINFOG(10)
        real(wp) :: cond2 = 0.0_wp     !! condition number for ω2, RINFOG(11)
        real(wp) :: rcond = 0.0_wp     !! 1 / max(cond1, cond2)
    end type mumps_accuracy_t

    !> What the real and the complex factorisations share: settings, stage,
    !> the control and information arrays of the latest MUMPS call.
    type, abstract, public :: mumps_factor_t
        private
        integer :: comm = 0                !! MPI communicator (0: the default)
        integer :: ordering = mumps_ordering_auto
        logical :: verbose = .false.
        logical :: error_analysis = .false.
        integer :: stage = stage_none
        type(c_ptr) :: owner = c_null_ptr  !! address of the owning object's `stage`
        integer :: n = 0
        integer(i8) :: nnz = 0
        integer :: icntl(60) = 0           !! controls passed to every call
        integer :: info(80) = 0            !! INFO, INFOG, RINFOG of the latest call
        integer :: infog(80) = 0
        real(wp) :: rinfog(40) = 0.0_wp
        integer :: memory_retries = 0      !! workspace retries so far
        integer(i8) :: workspace = 0       !! entries of WK_USER allocated
        integer(i8) :: workspace_start = 0 !! first WK_USER size asked (0: INFO(8))
        integer(i8) :: workspace_estimate = 0 !! the analysis' estimate INFO(8)
        integer :: instance = 0            !! its number among the MPI ranks' instances
        integer(i8) :: workspace_needed = 0 !! entries the next factorisation asks for
        integer :: last_nrhs = 0           !! right-hand sides of the latest solve
        !> factorisations so far, their wall seconds (on rank 0), and the
        !> most memory one took, MB: on the process that used most (INFOG(21))
        !> and on all together (INFOG(22))
        integer :: factorisations = 0
        real(wp) :: factor_seconds = 0.0_wp
        integer :: memory_most = 0, memory_all = 0
    contains
        procedure :: configure => mumps_configure
        procedure :: analyse => mumps_analyse
        procedure :: ordering_used => mumps_ordering_used
        procedure :: factor_nonzeros => mumps_factor_nonzeros
        procedure :: null_pivots => mumps_null_pivots
        procedure :: accuracy => mumps_accuracy
        procedure :: memory_percent => mumps_memory_percent
        procedure :: workspace_entries => mumps_workspace_entries
        procedure :: order => mumps_order
        procedure :: is_analysed => mumps_is_analysed
        procedure :: is_factored => mumps_is_factored
        procedure :: destroy => mumps_destroy
        procedure :: report => mumps_report
        procedure(run_i), deferred, private :: run
        procedure(attach_i), deferred, private :: attach
        procedure(release_i), deferred, private :: release
        procedure(reserve_i), deferred, private :: reserve
    end type mumps_factor_t

    abstract interface
        !> One MUMPS call with JOB = job; copies INFO, INFOG, RINFOG back.
        subroutine run_i(self, job)
            import :: mumps_factor_t
            class(mumps_factor_t), intent(inout) :: self
            integer, intent(in) :: job
        end subroutine run_i
        !> Allocate IRN, JCN, A of the MUMPS structure and fill IRN, JCN from
        !> the 0-based CSC pattern.
        subroutine attach_i(self, colptr, rowind, status)
            import :: mumps_factor_t, i8, status_t
            class(mumps_factor_t), intent(inout) :: self
            integer(i8), intent(in) :: colptr(:), rowind(:)
            type(status_t), intent(inout) :: status
        end subroutine attach_i
        !> Deallocate the arrays `attach` and `reserve` allocated.
        subroutine release_i(self)
            import :: mumps_factor_t
            class(mumps_factor_t), intent(inout) :: self
        end subroutine release_i
        !> Make WK_USER hold at least `entries` entries and tell MUMPS its size.
        subroutine reserve_i(self, entries, status)
            import :: mumps_factor_t, i8, status_t
            class(mumps_factor_t), intent(inout) :: self
            integer(i8), intent(in) :: entries
            type(status_t), intent(inout) :: status
        end subroutine reserve_i
    end interface

    !> MUMPS LU of real unsymmetric matrices (DMUMPS).
#include "mumps_real.inc"
#define SPECIFICATION
#include "mumps_factor.inc"
#undef SPECIFICATION

    !> MUMPS LU of complex unsymmetric matrices (ZMUMPS).
#include "mumps_complex.inc"
#define SPECIFICATION
#include "mumps_factor.inc"
#undef SPECIFICATION

    public :: mumps_ordering_code, mumps_ordering_name, mumps_default_comm, mumps_reports

contains

    !> MPI_COMM_WORLD of the MPI library linked (the sequential library's
    !> stub value with libmpiseq).
    integer function mumps_default_comm()
        include 'mpif.h'
        mumps_default_comm = MPI_COMM_WORLD
    end function mumps_default_comm

    !> The mumps_ordering_* code of 'auto', 'amd', 'amf', 'scotch', 'pord',
    !> 'metis' or 'qamd'; -1 for anything else.
    pure integer function mumps_ordering_code(name) result(code)
        character(len=*), intent(in) :: name
        select case (trim(adjustl(name)))
        case ('auto'); code = mumps_ordering_auto
        case ('amd'); code = mumps_ordering_amd
        case ('amf'); code = mumps_ordering_amf
        case ('scotch'); code = mumps_ordering_scotch
        case ('pord'); code = mumps_ordering_pord
        case ('metis'); code = mumps_ordering_metis
        case ('qamd'); code = mumps_ordering_qamd
        case default; code = -1
        end select
    end function mumps_ordering_code

    !> Name of a mumps_ordering_* code (INFOG(7) after analysis).
    pure function mumps_ordering_name(code) result(name)
        integer, intent(in) :: code
        character(len=:), allocatable :: name
        select case (code)
        case (mumps_ordering_auto); name = 'auto'
        case (mumps_ordering_amd); name = 'amd'
        case (1); name = 'user'
        case (mumps_ordering_amf); name = 'amf'
        case (mumps_ordering_scotch); name = 'scotch'
        case (mumps_ordering_pord); name = 'pord'
        case (mumps_ordering_metis); name = 'metis'
        case (mumps_ordering_qamd); name = 'qamd'
        case default; name = 'none'
        end select
    end function mumps_ordering_name

    !> Settings for the next analysis (each optional; unset ones keep their
    !> value). `comm` takes effect when the MUMPS instance is created, at the
    !> first analysis or the first after `destroy`.
    subroutine mumps_configure(self, status, ordering, verbose, error_analysis, comm, &
                               workspace)
        class(mumps_factor_t), intent(inout) :: self
        type(status_t), intent(out) :: status
        integer, intent(in), optional :: ordering     !! mumps_ordering_*
        logical, intent(in), optional :: verbose      !! MUMPS prints to standard output
        logical, intent(in), optional :: error_analysis !! ICNTL(11) = 1 at each solve
        integer, intent(in), optional :: comm         !! MPI communicator
        !> entries of the first workspace WK_USER (0, the default: MUMPS's
        !> estimate INFO(8)); a smaller one grows on demand
        integer(i8), intent(in), optional :: workspace
        character(len=160) :: msg
        if (present(ordering)) then
            if (mumps_ordering_name(ordering) == 'none' .or. ordering == 1) then
                write (msg, '(a,i0,a)') 'mumps configure: ordering = ', ordering, &
                    ': unknown; use a mumps_ordering_* code (ICNTL(7) 0, 2..7)'
                call status%set(status_bad_input, trim(msg))
                return
            end if
            self%ordering = ordering
        end if
        if (present(verbose)) self%verbose = verbose
        if (present(error_analysis)) self%error_analysis = error_analysis
        if (present(comm)) self%comm = comm
        if (present(workspace)) self%workspace_start = max(workspace, 0_i8)
    end subroutine mumps_configure

    !> Analyse the pattern of n x n matrices in CSC form (0-based, no
    !> duplicates). Replaces any earlier pattern and factorisation.
    subroutine mumps_analyse(self, n, colptr, rowind, status)
        class(mumps_factor_t), intent(inout) :: self
        integer, intent(in) :: n                  !! matrix order
        integer(i8), intent(in) :: colptr(:)      !! size n+1, 0-based offsets
        integer(i8), intent(in) :: rowind(:)      !! size >= colptr(n+1), 0-based rows
        type(status_t), intent(out) :: status
        character(len=160) :: msg

        if (n <= 0) then
            write (msg, '(a,i0,a)') 'mumps analyse: n = ', n, ': must be positive'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (size(colptr) /= n + 1) then
            write (msg, '(a,i0,a,i0)') 'mumps analyse: colptr has size ', size(colptr), &
                ', expected n+1 = ', n + 1
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (colptr(1) /= 0 .or. colptr(n + 1) > size(rowind, kind=i8) &
            .or. colptr(n + 1) < 1) then
            write (msg, '(a,i0,a,i0,a)') 'mumps analyse: colptr(n+1) = ', colptr(n + 1), &
                ' nonzeros, rowind has ', size(rowind), ' entries (colptr must start at 0)'
            call status%set(status_bad_input, trim(msg))
            return
        end if
        if (any(rowind(1:colptr(n + 1)) < 0 .or. rowind(1:colptr(n + 1)) >= n)) then
            write (msg, '(a,i0)') 'mumps analyse: a row index is outside 0..n-1, n = ', n
            call status%set(status_bad_input, trim(msg))
            return
        end if
        ! A new pattern: a fresh MUMPS instance (JOB = -1) on the object's
        ! communicator, with its own coordinate arrays.
        call self%destroy()
        if (self%comm == 0) self%comm = mumps_default_comm()
        call take_instance(self%instance, status)
        if (.not. status%ok()) return
        call self%run(job_init)
        if (self%info(1) < 0) then
            call free_instance(self%instance)
            self%instance = 0
            call set_error(self, status, 'mumps initialise')
            return
        end if
        self%stage = stage_initialised
        self%owner = address_of(self)
        call set_controls(self)
        call self%attach(colptr, rowind, status)
        if (.not. status%ok()) return
        self%n = n
        self%nnz = colptr(n + 1)
        call execute(self, job_analyse, 'mumps analyse', status)
        if (.not. status%ok()) return
        ! INFO(8): MUMPS's estimate of the in-core workspace, ICNTL(14) included
        self%workspace_estimate = counted(self%info(8))
        self%workspace_needed = self%workspace_estimate
        if (self%workspace_start > 0) self%workspace_needed = self%workspace_start
        self%stage = stage_analysed
    end subroutine mumps_analyse

    !> Controls after JOB = -1 has set MUMPS's defaults.
    subroutine set_controls(self)
        class(mumps_factor_t), intent(inout) :: self
        integer, parameter :: silent = -1
        integer, parameter :: standard_output = 6, all_messages = 2
        if (self%verbose) then
            self%icntl(1:3) = standard_output
            self%icntl(4) = all_messages
        else
            self%icntl(1:3) = silent
            self%icntl(4) = 0
        end if
        self%icntl(5) = 0                 ! assembled input
        self%icntl(18) = 0                ! centralised on the host
        self%icntl(7) = self%ordering
        self%icntl(24) = 1                ! detect null pivots (INFOG(28))
        self%memory_retries = 0
    end subroutine set_controls

    !> Run one JOB, retrying workspace failures of the factorisation with a
    !> larger ICNTL(14); a negative INFO(1) becomes a status.
    subroutine execute(self, job, where, status)
        class(mumps_factor_t), intent(inout) :: self
        integer, intent(in) :: job
        character(len=*), intent(in) :: where
        type(status_t), intent(inout) :: status
        do
            if (job == job_factor) then
                call self%reserve(self%workspace_needed, status)
                if (.not. status%ok()) return
            end if
            call self%run(job)
            if (self%info(1) >= 0) return
            if (.not. (job == job_factor .and. is_workspace_error(self%info(1)) &
                       .and. self%memory_retries < mumps_max_memory_retries)) exit
            self%memory_retries = self%memory_retries + 1
            self%icntl(14) = memory_growth * max(self%icntl(14), 1)
            ! -9: WK_USER, the real/complex workspace, lacked INFO(2) entries
            ! at the moment of the error (more may follow): at least the
            ! analysis' estimate, twice the old size, or what was missing
            if (self%info(1) == -9) self%workspace_needed = max(self%workspace_estimate, &
                memory_growth * self%workspace_needed, &
                self%workspace_needed + counted(self%info(2)))
        end do
        call set_error(self, status, where)
    end subroutine execute

    pure logical function is_workspace_error(code)
        integer, intent(in) :: code
        is_workspace_error = any(code == [-8, -9, -17, -20])
    end function is_workspace_error

    !> A status for a negative INFO(1): the MUMPS code, INFO(2) and what the
    !> users' guide says it means.
    subroutine set_error(self, status, where)
        class(mumps_factor_t), intent(in) :: self
        type(status_t), intent(inout) :: status
        character(len=*), intent(in) :: where
        character(len=320) :: msg
        integer :: reason
        reason = reason_none
        if (self%info(1) == -10) reason = reason_singular_matrix
        write (msg, '(a,i0,a,i0,a)') where // ': MUMPS error INFO(1) = ', self%info(1), &
            ' (INFO(2) = ', self%info(2), '): ' // error_meaning(self%info(1))
        if (is_workspace_error(self%info(1))) write (msg, '(a,i0,a,i0,a)') trim(msg) // &
            ' (after ', self%memory_retries, ' retries, ICNTL(14) = ', self%icntl(14), ' %)'
        call status%set(status_solver_failure, trim(msg), reason)
    end subroutine set_error

    !> Meaning of MUMPS's error codes (users' guide 5.5, "Error diagnostics").
    pure function error_meaning(code) result(text)
        integer, intent(in) :: code
        character(len=:), allocatable :: text
        select case (code)
        case (-1); text = 'an error occurred on the processor INFO(2)'
        case (-2); text = 'NNZ out of range'
        case (-3); text = 'invalid JOB (e.g. solve before factorisation, or analysis redone)'
        case (-5, -7); text = 'out of memory allocating the workspace of the analysis'
        case (-6); text = 'the matrix is structurally singular (INFO(2) = structural rank)'
        case (-8); text = 'integer workspace IS too small for the factorisation'
        case (-9); text = 'real/complex workspace S too small for the factorisation'
        case (-10); text = 'the matrix is numerically singular (INFO(2) pivots eliminated)'
        case (-11); text = 'real/complex workspace S too small for the solution'
        case (-12); text = 'real/complex workspace S too small for iterative refinement'
        case (-13); text = 'out of memory (a Fortran ALLOCATE of INFO(2) entries failed)'
        case (-14); text = 'integer workspace IS too small for the solution'
        case (-15); text = 'integer workspace IS too small for iterative refinement'
        case (-16); text = 'N out of range'
        case (-17); text = 'internal send buffer too small'
        case (-19); text = 'the working memory limit ICNTL(23) is too small'
        case (-20); text = 'internal reception buffer too small'
        case (-21); text = 'PAR = 0 is not allowed with one processor'
        case (-22); text = 'a pointer array of the structure is wrong (INFO(2) says which)'
        case (-23); text = 'MPI was not initialised'
        case (-26); text = 'LRHS out of range'
        case (-32); text = 'NRHS incompatible with the other solve options'
        case (-44); text = 'the factors were discarded (ICNTL(31)), cannot solve'
        case (-45); text = 'NRHS <= 0'
        case (-50); text = 'the fill-reducing ordering failed during the analysis'
        case (-53); text = 'internal error, possibly the pattern changed between calls'
        case (-90); text = 'out-of-core error'
        case default; text = 'see the MUMPS users'' guide, section "Error diagnostics"'
        end select
    end function error_meaning

    !> The ordering MUMPS used in the last analysis (INFOG(7)): 'amd', 'amf',
    !> 'scotch', 'pord', 'metis', 'qamd'; 'none' before an analysis.
    function mumps_ordering_used(self) result(name)
        class(mumps_factor_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = 'none'
        if (self%is_analysed()) name = mumps_ordering_name(self%infog(7))
    end function mumps_ordering_used

    !> Entries of the LU factors: INFOG(29) after a factorisation, the
    !> analysis' estimate INFOG(20) before (negative values count millions).
    integer(i8) function mumps_factor_nonzeros(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_factor_nonzeros = 0
        if (self%is_factored()) then
            mumps_factor_nonzeros = counted(self%infog(29))
        else if (self%is_analysed()) then
            mumps_factor_nonzeros = counted(self%infog(20))
        end if
    end function mumps_factor_nonzeros

    !> LWK_USER for a workspace of `entries` entries: the count, or minus
    !> the millions beyond the default integer's range (`reserve` allocates
    !> whole millions there).
    pure integer function workspace_code(entries) result(code)
        integer(i8), intent(in) :: entries
        integer(i8), parameter :: million = 1000000_i8
        if (entries <= huge(code)) then
            code = int(entries)
        else
            code = -int(entries / million)
        end if
    end function workspace_code

    pure integer(i8) function counted(value)
        integer, intent(in) :: value
        integer(i8), parameter :: million = 1000000_i8
        counted = value
        if (value < 0) counted = -int(value, i8) * million
    end function counted

    !> Null pivots found by the latest factorisation (INFOG(28)).
    integer function mumps_null_pivots(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_null_pivots = 0
        if (self%is_analysed()) mumps_null_pivots = self%infog(28)
    end function mumps_null_pivots

    !> Accuracy estimates of the latest solve: available after a solve with
    !> one right-hand side when `error_analysis` is configured.
    function mumps_accuracy(self) result(accuracy)
        class(mumps_factor_t), intent(in) :: self
        type(mumps_accuracy_t) :: accuracy
        if (.not. (self%is_factored() .and. self%error_analysis .and. self%last_nrhs == 1)) &
            return
        accuracy%available = .true.
        accuracy%residual = self%rinfog(6)
        accuracy%omega1 = self%rinfog(7)
        accuracy%omega2 = self%rinfog(8)
        accuracy%forward_error = self%rinfog(9)
        accuracy%cond1 = self%rinfog(10)
        accuracy%cond2 = self%rinfog(11)
        if (max(accuracy%cond1, accuracy%cond2) > 0.0_wp) &
            accuracy%rcond = 1.0_wp / max(accuracy%cond1, accuracy%cond2)
    end function mumps_accuracy

    !> ICNTL(14) in use: MUMPS's workspace slack in percent of its estimate.
    integer function mumps_memory_percent(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_memory_percent = self%icntl(14)
    end function mumps_memory_percent

    !> Entries of the workspace WK_USER given to MUMPS (0 before the first
    !> factorisation).
    integer(i8) function mumps_workspace_entries(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_workspace_entries = 0
        if (owns(self)) mumps_workspace_entries = self%workspace
    end function mumps_workspace_entries

    !> Matrix order (0 before analysis).
    pure integer function mumps_order(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_order = self%n
    end function mumps_order

    !> True once a pattern has been analysed by this object.
    logical function mumps_is_analysed(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_is_analysed = self%stage >= stage_analysed .and. owns(self)
    end function mumps_is_analysed

    !> True while a factorisation of the latest values is alive.
    logical function mumps_is_factored(self)
        class(mumps_factor_t), intent(in) :: self
        mumps_is_factored = self%stage == stage_factored .and. owns(self)
    end function mumps_is_factored

    !> Terminate the MUMPS instance (JOB = -2) and free the coordinate
    !> arrays; the object may be analysed again afterwards.
    subroutine mumps_destroy(self)
        class(mumps_factor_t), intent(inout) :: self
        if (self%stage >= stage_initialised .and. owns(self)) then
            call self%run(job_end)
            call free_instance(self%instance)
            self%instance = 0
            call self%release()
        end if
        self%stage = stage_none
        self%owner = c_null_ptr
        self%n = 0
        self%nnz = 0
        self%last_nrhs = 0
    end subroutine mumps_destroy

    !> The address that identifies an object as the owner of its instance.
    function address_of(self) result(address)
        class(mumps_factor_t), intent(in), target :: self
        type(c_ptr) :: address
        address = c_loc(self%stage)
    end function address_of

    logical function owns(self)
        class(mumps_factor_t), intent(in) :: self
        owns = c_associated(self%owner, address_of(self))
    end function owns

    !> Checks before a factorisation with nvalues values.
    logical function can_factor(self, nvalues, status)
        class(mumps_factor_t), intent(in) :: self
        integer(i8), intent(in) :: nvalues
        type(status_t), intent(inout) :: status
        character(len=160) :: msg
        can_factor = .false.
        if (.not. self%is_analysed()) then
            call status%set(status_bad_input, 'mumps factor: no pattern analysed; call ' // &
                'analyse (a copy made by assignment holds no MUMPS instance)')
        else if (nvalues /= self%nnz) then
            write (msg, '(a,i0,a,i0,a)') 'mumps factor: ', nvalues, ' values for a pattern of ', &
                self%nnz, ' slots'
            call status%set(status_bad_input, trim(msg))
        else
            can_factor = .true.
        end if
    end function can_factor

    !> JOB = 2 on the values now in the structure; null pivots count as a
    !> singular matrix.
    subroutine factor_values(self, status)
        class(mumps_factor_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        character(len=200) :: msg
        integer(i8) :: start, finish, rate
        self%stage = stage_analysed
        self%last_nrhs = 0
        call system_clock(start, rate)
        call execute(self, job_factor, 'mumps factor', status)
        call system_clock(finish)
        self%factorisations = self%factorisations + 1
        self%factor_seconds = self%factor_seconds + real(finish - start, wp) / real(rate, wp)
        self%memory_most = max(self%memory_most, self%infog(21))
        self%memory_all = max(self%memory_all, self%infog(22))
        if (.not. status%ok()) return
        if (self%infog(28) > 0) then
            write (msg, '(a,i0,a,i0,a)') 'mumps factor: matrix is singular: ', self%infog(28), &
                ' null pivots of ', self%n, ' (INFOG(28), null pivot detection ICNTL(24) = 1)'
            call status%set(status_solver_failure, trim(msg), reason_singular_matrix)
            return
        end if
        self%stage = stage_factored
    end subroutine factor_values

    !> What the factorisations cost, for --verbose statistics: 'MUMPS on 2
    !> processes: 18 factorisations of 91234 factor entries, 0.012 s each
    !> (wall), memory 9 MB on the process that used most, 16 MB on all'; ''
    !> before the first.
    function mumps_report(self) result(text)
        class(mumps_factor_t), intent(in) :: self
        character(len=:), allocatable :: text
        character(len=32) :: each
        text = ''
        if (self%factorisations == 0) return
        write (each, '(es9.2)') self%factor_seconds / self%factorisations
        text = 'MUMPS on ' // int_text(process_count()) // ' process' // &
            trim(merge('  ', 'es', process_count() == 1)) // ': ' // &
            int_text(self%factorisations) // ' factorisations of ' // &
            int_text(self%factor_nonzeros()) // ' factor entries, ' // trim(adjustl(each)) // &
            ' s each (wall), memory ' // int_text(self%memory_most) // ' MB on the process &
            &that used most, ' // int_text(self%memory_all) // ' MB on all'
    end function mumps_report

    !> The reports of a real and a complex factorisation of one solver: each
    !> that factored, 'real: ...; complex: ...' when both did.
    function mumps_reports(real_lu, complex_lu) result(text)
        class(mumps_factor_t), intent(in) :: real_lu, complex_lu
        character(len=:), allocatable :: text, a, b
        a = real_lu%report()
        b = complex_lu%report()
        if (len(a) > 0 .and. len(b) > 0) then
            text = 'real: ' // a // '; complex: ' // b
        else
            text = a // b
        end if
    end function mumps_reports

    !> Checks before a solve of nrhs right-hand sides of leading size nb.
    logical function can_solve(self, nb, nrhs, status)
        class(mumps_factor_t), intent(inout) :: self
        integer, intent(in) :: nb, nrhs
        type(status_t), intent(inout) :: status
        character(len=160) :: msg
        can_solve = .false.
        if (.not. self%is_factored()) then
            call status%set(status_bad_input, 'mumps solve: nothing factored; call factor')
        else if (nb /= self%n .or. nrhs < 1) then
            write (msg, '(a,i0,a,i0,a,i0)') 'mumps solve: ', nrhs, &
                ' right-hand side(s) of size ', nb, ' for a matrix of order ', self%n
            call status%set(status_bad_input, trim(msg))
        else
            can_solve = .true.
            self%last_nrhs = nrhs
            self%icntl(11) = 0
            ! MUMPS's error analysis covers one right-hand side only.
            if (self%error_analysis .and. nrhs == 1) self%icntl(11) = 1
        end if
    end function can_solve

    ! ---- DMUMPS, ZMUMPS: one body (mumps_factor.inc), the names set by the
    ! macros of mumps_real.inc and mumps_complex.inc ----

#include "mumps_real.inc"
#include "mumps_factor.inc"

#include "mumps_complex.inc"
#include "mumps_factor.inc"

    !> 1-based coordinates (IRN, JCN) of the slots of a 0-based CSC pattern.
    pure subroutine coordinates(colptr, rowind, irn, jcn)
        integer(i8), intent(in) :: colptr(:), rowind(:)
        integer, intent(out) :: irn(:), jcn(:)
        integer :: j
        integer(i8) :: p
        do j = 1, size(colptr) - 1
            do p = colptr(j) + 1, colptr(j + 1)
                irn(p) = int(rowind(p)) + 1
                jcn(p) = j
            end do
        end do
    end subroutine coordinates
end module flexmbs_linalg_mumps
