!> A sink writing the trajectory to an HDF5 file as it is computed.
!>
!> Layout (Fortran dimension order; C and Python readers see it reversed):
!>   /time           (steps)        extendible, chunked
!>   /y              (n, steps)     extendible, chunked: y(:, k) at time(k)
!>   /<block>        (m, steps)     optional named slices of y (/q, /v, /lambda)
!>   /<path>         (m, steps)     optional named series computed from each
!>                                  record (add_series: /bodies/<name>/position
!>                                  ...), with a `unit` attribute
!>   attributes on / creator ('flexmbs 0.1.0'), flexmbs_version, created (ISO
!>                   8601), input_text, solver, outcome, NST ... NPRJ, CPU,
!>                   WALL, t_reached
!> Records are held in memory and written in batches (flexmbs_io_hdf5_series):
!> when a batch is full (batch_bytes), when flush_interval seconds of wall
!> time have passed since the last write, and when the run ends in any way
!> it can report (finish, statistics, close: also after a solver failure or
!> SIGINT/SIGTERM). Each batch ends with /time and a flush, so a file whose
!> writer was killed outright (SIGKILL, power) opens without repair and
!> misses at most the records of the last interval; the number of complete
!> records is the length of /time.
!> The file uses HDF5's default (not 'latest') library-version bounds.
!> An input text too large for a compact attribute goes to the scalar
!> string dataset /input_text instead.
module flexmbs_io_hdf5_sink
    use hdf5
    use flexmbs_core_kinds, only: wp, i8
    use flexmbs_core_status, only: status_t, status_io_error, status_bad_input
    use flexmbs_dae_sink, only: sink_t, dense_output_t
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_core_version, only: creator, version
    use flexmbs_core_timer, only: iso_now
    use flexmbs_core_text, only: int_text
    use flexmbs_io_checkpoint, only: checkpoint_t, write_checkpoint, add_restart_time, put_stats
    use flexmbs_io_record_values, only: record_values_t
    use flexmbs_io_hdf5_text, only: read_string_attribute, write_string_attribute, &
        write_real_attribute, &
        string_type, utf8_string_type, group_creating
    use flexmbs_io_hdf5_series, only: series_batch_t, create_series, open_series
    use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_null_char
    implicit none
    private

    public :: hdf5_result_check

    !> Attributes stay in the object header below about 64 KiB; larger text
    !> goes to a dataset.
    integer, parameter :: max_attribute_text = 32768
    !> Target bytes of one chunk of /y (records per chunk = this / (8 n)).
    integer, parameter :: chunk_bytes = 65536
    integer, parameter :: time_chunk = 1024
    !> Memory for the records held between two writes (all series together),
    !> and the most records one batch holds.
    integer, parameter :: batch_bytes = 16 * 1024 * 1024
    integer, parameter :: max_batch_records = 1000000
    !> Wall seconds after which held records are written even if the batch
    !> is not full: what a killed run may lose.
    real(wp), parameter, public :: flush_interval = 1.0_wp

    !> A named slice y(first:last) written as its own dataset.
    type :: block_t
        character(len=:), allocatable :: name
        integer :: first = 0, last = 0
        type(series_batch_t) :: batch
    end type block_t

    !> A series computed from each record (add_series).
    type :: series_t
        character(len=:), allocatable :: path
        integer :: rows = 0, columns = 1
        type(series_batch_t) :: batch
        class(record_values_t), allocatable :: source
        real(wp), allocatable :: buffer(:)  !! one record's values
    end type series_t

    !> The HDF5 sink (the module's layout): the open file, its batches of
    !> pending records, the named blocks of y and the derived series.
    type, extends(sink_t), public :: hdf5_sink_t
        character(len=:), allocatable :: path
        integer :: n = 0                 !! length of y
        integer :: records = 0           !! records written to the file so far
        integer :: pending = 0           !! records held, not yet written
        integer :: capacity = 0          !! records a batch holds (set at the first)
        integer(i8) :: last_write = 0    !! system_clock count of the last write
        logical :: every_step = .false.  !! record accepted steps instead of output times
        logical :: is_open = .false.
        !> records an earlier run left that this one continues (reopen); -1
        !> for a new file
        integer :: kept = -1
        integer(hid_t) :: file = -1
        real(wp), allocatable :: checkpoint_buffer(:)
        type(series_batch_t) :: time_batch, y_batch
        type(block_t), allocatable :: blocks(:)
        type(series_t), allocatable :: series(:)
    contains
        procedure :: create => sink_create
        procedure :: add_block => sink_add_block
        procedure :: add_series => sink_add_series
        procedure :: write_strings => sink_write_strings
        procedure :: annotate => sink_annotate
        procedure :: output => sink_output
        procedure :: wants_steps => sink_wants_steps
        procedure :: step => sink_step
        procedure :: finish => sink_finish
        procedure :: write_text => sink_write_text
        procedure :: write_statistics => sink_write_statistics
        procedure :: write_matrix => sink_write_matrix
        procedure :: write_vector => sink_write_vector
        procedure :: write_integer_matrix => sink_write_integers
        procedure :: write_integer_list => sink_write_integer_list
        generic :: write_integers => write_integer_matrix, write_integer_list
        procedure :: close => sink_close
        procedure :: record_times => sink_record_times
        procedure :: reopen => sink_reopen
        procedure :: keep_checkpoint => sink_keep_checkpoint
        procedure :: read_records => sink_read_records
    end type hdf5_sink_t

    logical, save :: library_open = .false.

    interface
        !> Store a text as a string attribute of '/' (a scalar string dataset
        !> when it is too large for an attribute), replacing an earlier one.
        module subroutine sink_write_text(self, name, text, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: name, text
            type(status_t), intent(out) :: status
        end subroutine sink_write_text

        !> A 2-D real dataset /name (rows, columns), e.g. the monitor table
        !> (groups of a path created as needed).
        module subroutine sink_write_matrix(self, name, values, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: name
            real(wp), intent(in) :: values(:, :)
            type(status_t), intent(out) :: status
        end subroutine sink_write_matrix

        !> A 1-D real dataset /name, e.g. the energy at each record.
        module subroutine sink_write_vector(self, name, values, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: name
            real(wp), intent(in) :: values(:)
            type(status_t), intent(out) :: status
        end subroutine sink_write_vector

        !> A 2-D integer dataset /name (rows, columns), e.g. a connectivity
        !> (groups of a path created as needed).
        module subroutine sink_write_integers(self, name, values, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: name
            integer, intent(in) :: values(:, :)
            type(status_t), intent(out) :: status
        end subroutine sink_write_integers

        !> A 1-D integer dataset /name, e.g. a node set.
        module subroutine sink_write_integer_list(self, name, values, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: name
            integer, intent(in) :: values(:)
            type(status_t), intent(out) :: status
        end subroutine sink_write_integer_list

        !> A 1-D dataset of UTF-8 strings (variable length: h5py reads str) at
        !> `path`, e.g. the label of every component of /y.
        module subroutine sink_write_strings(self, path, strings, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: path
            character(len=*), intent(in) :: strings(:)
            type(status_t), intent(out) :: status
        end subroutine sink_write_strings

        !> A string attribute `name` = `text` of the dataset or group at `path`.
        module subroutine sink_annotate(self, path, name, text, status)
            class(hdf5_sink_t), intent(inout) :: self
            character(len=*), intent(in) :: path, name, text
            type(status_t), intent(out) :: status
        end subroutine sink_annotate
    end interface


contains

    !> Create (or truncate) the file with empty /time and /y for n unknowns.
    subroutine sink_create(self, path, n, status, input_text, every_step)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: path
        integer, intent(in) :: n                   !! length of y
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: input_text !! stored as attribute
        logical, intent(in), optional :: every_step !! record steps, not output times
        integer :: err, per_chunk

        if (self%is_open) then
            call status%set(status_bad_input, path // ': HDF5 sink already open on ' // self%path)
            return
        end if
        if (n < 1) then
            call status%set(status_bad_input, path // ': HDF5 sink needs n >= 1')
            return
        end if
        self%path = path
        self%n = n
        self%records = 0
        self%every_step = .false.
        if (present(every_step)) self%every_step = every_step
        allocate (self%blocks(0), self%series(0))
        call open_library(err)
        if (check(err, 'initialise the HDF5 library')) return
        call h5fcreate_f(path, H5F_ACC_TRUNC_F, self%file, err)
        if (check(err, 'create the file')) return
        self%is_open = .true.
        self%pending = 0
        self%capacity = 0
        call create_series(self%file, 'time', 0, time_chunk, self%time_batch, err)
        if (check(err, 'create /time')) return
        ! the unit and meaning, as every named series has them
        call write_string_attribute(self%time_batch%dset, 'unit', 's', err)
        if (err >= 0) call write_string_attribute(self%time_batch%dset, 'description', &
            'the time of each record (row of /y and of every series)', err)
        if (check(err, 'write the attributes of /time')) return
        per_chunk = max(1, min(time_chunk, chunk_bytes / (8 * n)))
        call create_series(self%file, 'y', n, per_chunk, self%y_batch, err)
        if (check(err, 'create /y')) return
        call write_string_attribute(self%file, 'creator', creator, err)
        if (err >= 0) call write_string_attribute(self%file, 'flexmbs_version', version, err)
        if (err >= 0) call write_string_attribute(self%file, 'created', iso_now(), err)
        if (check(err, 'write the attributes creator, flexmbs_version, created')) return
        if (present(input_text)) then
            call self%write_text('input_text', input_text, status)
            if (.not. status%ok()) return
        end if
        call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (check(err, 'flush')) return

    contains

        logical function check(code, what)
            integer, intent(in) :: code
            character(len=*), intent(in) :: what
            check = code < 0
            if (check) call status%set(status_io_error, path // ': HDF5 cannot ' // what)
        end function check
    end subroutine sink_create

    !> Continue the result `path` that an earlier run of the same scene
    !> wrote (run/resume has checked it): its records up to the checkpoint
    !> `cp` are kept, the later ones dropped, and cp%t is added to the root
    !> attribute restart_times. Blocks and series are then added as for a
    !> new file and continue theirs; static datasets written again replace
    !> their old selves.
    subroutine sink_reopen(self, path, n, cp, status, every_step)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: path
        integer, intent(in) :: n                   !! length of y
        type(checkpoint_t), intent(in) :: cp
        type(status_t), intent(out) :: status
        logical, intent(in), optional :: every_step !! record steps, not output times
        integer :: err
        if (self%is_open) then
            call status%set(status_bad_input, path // ': HDF5 sink already open on ' // self%path)
            return
        end if
        self%path = path
        self%n = n
        self%records = cp%records
        self%kept = cp%records
        self%every_step = .false.
        if (present(every_step)) self%every_step = every_step
        allocate (self%blocks(0), self%series(0))
        call open_library(err)
        if (err >= 0) call h5fopen_f(path, H5F_ACC_RDWR_F, self%file, err)
        if (err < 0) then
            call status%set(status_io_error, path // ': HDF5 cannot open the result to &
                &continue it (another program writing it?)')
            return
        end if
        self%is_open = .true.
        self%pending = 0
        self%capacity = 0
        call open_series(self%file, 'time', 0, cp%records, self%time_batch, err)
        if (err >= 0) call open_series(self%file, 'y', n, cp%records, self%y_batch, err)
        if (err >= 0) call add_restart_time(self%file, cp%t, err)
        if (err >= 0) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (err < 0) call status%set(status_io_error, path // ': HDF5 cannot cut /time and /y &
            &to the ' // int_text(cp%records) // ' records of the checkpoint')
    end subroutine sink_reopen

    !> Write the records held, then `cp` as the file's checkpoint
    !> (io/checkpoint), then flush: the checkpoint never counts a record the
    !> file lacks. cp%records is set here.
    subroutine sink_keep_checkpoint(self, cp, status)
        class(hdf5_sink_t), intent(inout) :: self
        type(checkpoint_t), intent(inout) :: cp
        type(status_t), intent(inout) :: status
        integer :: err
        if (.not. self%is_open) return
        call write_pending(self, err)
        if (err >= 0) then
            cp%records = self%records
            if (.not. allocated(self%checkpoint_buffer)) &
                allocate (self%checkpoint_buffer(size(cp%y) + 4))
            call write_checkpoint(self%file, cp, self%checkpoint_buffer, err)
        end if
        if (err >= 0) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (err < 0 .and. status%ok()) call status%set(status_io_error, self%path // &
            ': HDF5 cannot write the checkpoint')
    end subroutine sink_keep_checkpoint

    !> Records first .. first + size(t) - 1 (from 1) of /time and /y as the
    !> file holds them (records held in memory are not among them).
    subroutine sink_read_records(self, first, t, y, status)
        class(hdf5_sink_t), intent(inout) :: self
        integer, intent(in) :: first
        real(wp), intent(out) :: t(:), y(:, :)   !! y(n, size(t))
        type(status_t), intent(inout) :: status
        integer(hid_t) :: space, memspace
        integer(hsize_t) :: count(2)
        integer :: err, close_err, k
        integer(hid_t) :: dsets(2)
        count = [int(self%n, hsize_t), size(t, kind=hsize_t)]
        dsets = [self%time_batch%dset, self%y_batch%dset]
        do k = 1, 2
            call h5dget_space_f(dsets(k), space, err)
            if (err < 0) exit
            if (k == 1) then
                call h5sselect_hyperslab_f(space, H5S_SELECT_SET_F, [int(first - 1, hsize_t)], &
                                           count(2:2), err)
                if (err >= 0) call h5screate_simple_f(1, count(2:2), memspace, err)
                if (err >= 0) call h5dread_f(dsets(k), H5T_NATIVE_DOUBLE, t, count(2:2), err, &
                                             mem_space_id=memspace, file_space_id=space)
            else
                call h5sselect_hyperslab_f(space, H5S_SELECT_SET_F, &
                                           [0_hsize_t, int(first - 1, hsize_t)], count, err)
                if (err >= 0) call h5screate_simple_f(2, count, memspace, err)
                if (err >= 0) call h5dread_f(dsets(k), H5T_NATIVE_DOUBLE, y, count, err, &
                                             mem_space_id=memspace, file_space_id=space)
            end if
            call h5sclose_f(memspace, close_err)
            call h5sclose_f(space, close_err)
            if (err < 0) exit
        end do
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot read the &
            &records from ' // int_text(first))
    end subroutine sink_read_records

    !> Also write y(first:last) as dataset /name (call before the first record).
    subroutine sink_add_block(self, name, first, last, status)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: name !! e.g. 'q', 'v', 'lambda'
        integer, intent(in) :: first, last  !! index range in y
        type(status_t), intent(out) :: status
        type(block_t) :: block
        integer :: err, m
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: add_block before create')
            return
        end if
        if (self%records - max(self%kept, 0) + self%pending > 0) then
            call status%set(status_bad_input, self%path // ': block /' // name // &
                ' added after records were written')
            return
        end if
        if (first < 1 .or. last > self%n .or. last < first) then
            call status%set(status_bad_input, self%path // ': block /' // name // &
                ': index range outside 1..n')
            return
        end if
        if (name == 'time' .or. name == 'y' .or. name == 'input_text') then
            call status%set(status_bad_input, self%path // ': block /' // name // &
                ': name is taken')
            return
        end if
        m = last - first + 1
        block%name = name
        block%first = first
        block%last = last
        if (self%kept >= 0) then
            call open_series(self%file, name, m, self%kept, block%batch, err)
        else
            call create_series(self%file, name, m, max(1, min(time_chunk, &
                               chunk_bytes / (8 * m))), block%batch, err)
        end if
        if (err < 0) then
            call status%set(status_io_error, self%path // ': HDF5 cannot create /' // name)
            return
        end if
        self%blocks = [self%blocks, block]
    end subroutine sink_add_block

    subroutine sink_output(self, t, y, status)
        class(hdf5_sink_t), intent(inout) :: self
        include '../dae/sink_output_arguments.inc'
        if (self%every_step) return
        call append(self, t, y, status)
    end subroutine sink_output

    logical function sink_wants_steps(self)
        class(hdf5_sink_t), intent(in) :: self
        sink_wants_steps = self%every_step
    end function sink_wants_steps

    subroutine sink_step(self, nr, t_old, t, y, dense, stop, status)
        class(hdf5_sink_t), intent(inout) :: self
        include '../dae/sink_step_arguments.inc'
        if (.not. self%every_step) return
        ! a resumed run's t0 is the checkpoint's step, recorded already
        if (nr == 1 .and. self%kept >= 0) return
        call append(self, t, y, status)
    end subroutine sink_step

    !> A named series beside /y: `rows` values per record at `path` (groups
    !> created as needed, e.g. 'bodies/crank/position'), computed from each
    !> record by `source`, with the string attributes `unit` (SI) and, when
    !> given, `description`. Call before the first record.
    subroutine sink_add_series(self, path, rows, unit, source, status, description, columns)
        class(hdf5_sink_t), intent(inout) :: self
        character(len=*), intent(in) :: path, unit
        integer, intent(in) :: rows
        class(record_values_t), intent(in) :: source
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: description
        !> a (rows, columns) matrix per record, e.g. (3, nodes): the dataset
        !> is (rows, columns, records); the source gives rows x columns values
        integer, intent(in), optional :: columns
        type(series_t), allocatable :: grown(:)
        integer :: err, k
        if (.not. self%is_open .or. self%records - max(self%kept, 0) + self%pending > 0 .or. &
            rows < 1) then
            call status%set(status_bad_input, 'HDF5 sink: series /' // path // &
                ' needs an open file without records and rows >= 1')
            return
        end if
        allocate (grown(size(self%series) + 1))
        do k = 1, size(self%series)
            call move_series(self%series(k), grown(k))
        end do
        call move_alloc(grown, self%series)
        k = size(self%series)
        associate (s => self%series(k))
            s%path = path
            s%rows = rows
            s%columns = 1
            if (present(columns)) s%columns = max(columns, 1)
            allocate (s%source, source=source)
            allocate (s%buffer(rows * s%columns))
            if (self%kept >= 0) then
                call open_series(self%file, path, rows, self%kept, s%batch, err, &
                                 columns=s%columns)
            else
                call create_series(self%file, path, rows, max(1, min(time_chunk, &
                    chunk_bytes / (8 * rows * s%columns))), s%batch, err, groups=.true., &
                    columns=s%columns)
            end if
            if (err >= 0) call write_string_attribute(s%batch%dset, 'unit', unit, err)
            if (err >= 0 .and. present(description)) &
                call write_string_attribute(s%batch%dset, 'description', description, err)
        end associate
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot create /' // &
                                     path)
    end subroutine sink_add_series



    !> Move a series (its source is polymorphic: no intrinsic assignment).
    subroutine move_series(from, to)
        type(series_t), intent(inout) :: from
        type(series_t), intent(out) :: to
        call move_alloc(from%path, to%path)
        to%rows = from%rows
        to%columns = from%columns
        to%batch = from%batch
        call move_alloc(from%source, to%source)
        call move_alloc(from%buffer, to%buffer)
    end subroutine move_series



    !> Write the records held and flush; the file stays open for the
    !> statistics.
    subroutine sink_finish(self, status)
        class(hdf5_sink_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer :: err
        if (.not. self%is_open) return
        call write_pending(self, err)
        if (err >= 0) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (err < 0 .and. status%ok()) &
            call status%set(status_io_error, self%path // ': HDF5 cannot write the last records')
    end subroutine sink_finish





    !> Store the statistics (and optionally solver name and outcome) as
    !> attributes of '/'; call after the integration, before `close`.
    subroutine sink_write_statistics(self, stats, status, solver, outcome)
        class(hdf5_sink_t), intent(inout) :: self
        type(dae_stats_t), intent(in) :: stats
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: solver  !! solver name
        character(len=*), intent(in), optional :: outcome !! 'ok' or the failure message
        integer :: err
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: write_statistics before create')
            return
        end if
        ! records still held go first: a caller may skip `finish`
        call write_pending(self, err)
        ! NST .. WALL, with NRJ by cause (NRJ_ERROR_TEST, ...; they add up to NRJ)
        if (err >= 0) call put_stats(self%file, '', stats, err)
        ! the reason of the last model refusal, when there was one
        if (err >= 0 .and. len(stats%rejections%refusal_reason()) > 0) &
            call write_string_attribute(self%file, 'refusal', &
                                        stats%rejections%refusal_reason(), err)
        call write_real_attribute(self%file, 't_reached', stats%t_reached, err)
        if (allocated(stats%linear_solver) .and. err >= 0) &
            call write_string_attribute(self%file, 'linear_solver', stats%linear_solver, err)
        if (present(solver) .and. err >= 0) &
            call write_string_attribute(self%file, 'solver', solver, err)
        if (present(outcome) .and. err >= 0) &
            call write_string_attribute(self%file, 'outcome', outcome, err)
        if (err >= 0) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (err < 0) call status%set(status_io_error, self%path // &
            ': HDF5 cannot write the statistics')
    end subroutine sink_write_statistics

    !> The rows (from 0) and times of the records an index of the file lists
    !> (the XDMF file): every record when there are at most `most`, else
    !> every k-th (k the least that keeps them to `most`) and the last.
    !> Read back from /time (the records held are written first; HDF5 counts
    !> the selected elements from 1 in Fortran); call
    !> before `close`. `total` is the number of records.
    subroutine sink_record_times(self, most, rows, times, total, status)
        class(hdf5_sink_t), intent(inout) :: self
        integer, intent(in) :: most
        integer, allocatable, intent(out) :: rows(:)
        real(wp), allocatable, intent(out) :: times(:)
        integer, intent(out) :: total
        type(status_t), intent(inout) :: status
        integer(hid_t) :: filespace, memspace
        integer :: err, stride, n, j, close_err
        total = 0
        allocate (rows(0), times(0))
        if (.not. self%is_open) return
        call write_pending(self, err)
        if (err < 0) then
            call status%set(status_io_error, self%path // ': HDF5 cannot write the last records')
            return
        end if
        total = self%records
        if (total == 0) return
        stride = max(1, (total + most - 1) / max(most, 1))
        n = (total - 1) / stride + 1
        rows = [((j - 1) * stride, j = 1, n)]
        if (rows(n) /= total - 1) rows = [rows, total - 1]
        deallocate (times)
        allocate (times(size(rows)))
        call h5dget_space_f(self%time_batch%dset, filespace, err)
        if (err >= 0) call h5sselect_elements_f(filespace, H5S_SELECT_SET_F, 1, &
            size(rows, kind=size_t), reshape(int(rows, hsize_t) + 1_hsize_t, [1, size(rows)]), err)
        if (err >= 0) call h5screate_simple_f(1, [size(rows, kind=hsize_t)], memspace, err)
        if (err >= 0) then
            call h5dread_f(self%time_batch%dset, H5T_NATIVE_DOUBLE, times, &
                [size(rows, kind=hsize_t)], err, mem_space_id=memspace, file_space_id=filespace)
            call h5sclose_f(memspace, close_err)
        end if
        call h5sclose_f(filespace, close_err)
        if (err < 0) call status%set(status_io_error, self%path // ': HDF5 cannot read /time')
    end subroutine sink_record_times

    !> Close every dataset and the file. Safe to call twice.
    subroutine sink_close(self, status)
        class(hdf5_sink_t), intent(inout) :: self
        type(status_t), intent(out) :: status
        integer :: err, worst, i
        if (.not. self%is_open) return
        call write_pending(self, worst)
        worst = min(worst, 0)
        if (allocated(self%blocks)) then
            do i = 1, size(self%blocks)
                call self%blocks(i)%batch%close(err)
                worst = min(worst, err)
            end do
            ! the sink may create or reopen a file again
            deallocate (self%blocks)
        end if
        if (allocated(self%series)) then
            do i = 1, size(self%series)
                call self%series(i)%batch%close(err)
                worst = min(worst, err)
            end do
            deallocate (self%series)
        end if
        call self%y_batch%close(err)
        worst = min(worst, err)
        call self%time_batch%close(err)
        worst = min(worst, err)
        call h5fclose_f(self%file, err)
        worst = min(worst, err)
        self%is_open = .false.
        self%file = -1
        if (worst < 0) call status%set(status_io_error, self%path // ': HDF5 cannot close')
    end subroutine sink_close

    !> Whether `path` is a result of flexmbs, which a run may replace: an
    !> HDF5 file whose root attribute `creator` starts with 'flexmbs', or
    !> one from before that attribute (a root attribute `input_text` and a
    !> dataset /time). Otherwise `reason` says what it is.
    subroutine hdf5_result_check(path, ours, reason)
        character(len=*), intent(in) :: path
        logical, intent(out) :: ours
        character(len=:), allocatable, intent(out) :: reason
        integer(hid_t) :: file
        integer :: err, close_err
        logical :: is_hdf5, exists, time_exists
        character(len=:), allocatable :: text
        ours = .false.
        reason = 'is not an HDF5 file'
        call open_library(err)
        if (err < 0) return
        call h5fis_hdf5_f(path, is_hdf5, err)
        if (err < 0 .or. .not. is_hdf5) return
        reason = 'is an HDF5 file that cannot be opened (another program writing it?)'
        call h5fopen_f(path, H5F_ACC_RDONLY_F, file, err)
        if (err < 0) return
        reason = 'is an HDF5 file not written by flexmbs (no root attribute creator = ''' // &
            'flexmbs ...'')'
        call h5aexists_f(file, 'creator', exists, err)
        if (err >= 0 .and. exists) then
            call read_string_attribute(file, 'creator', text, err)
            ours = err >= 0 .and. index(text, 'flexmbs') == 1
        else if (err >= 0) then
            call h5aexists_f(file, 'input_text', exists, err)
            time_exists = .false.
            if (err >= 0 .and. exists) call h5lexists_f(file, 'time', time_exists, err)
            ours = err >= 0 .and. time_exists
        end if
        call h5fclose_f(file, close_err)
    end subroutine hdf5_result_check

    ! ------------------------------------------------------------------


    !> Hold one record (the series evaluated now, at its t and y); write the
    !> batch when it is full or flush_interval has passed since the last
    !> write.
    subroutine append(self, t, y, status)
        class(hdf5_sink_t), intent(inout) :: self
        real(wp), intent(in) :: t, y(:)
        type(status_t), intent(inout) :: status
        integer :: err, i
        integer(i8) :: now, rate
        if (.not. status%ok()) return
        if (.not. self%is_open) then
            call status%set(status_bad_input, 'HDF5 sink: record before create')
            return
        end if
        if (size(y) /= self%n) then
            call status%set(status_bad_input, self%path // ': record of wrong length')
            return
        end if
        if (self%capacity == 0) then
            call reserve_batches(self, status)
            if (.not. status%ok()) return
        end if
        call self%y_batch%add(y)
        do i = 1, size(self%blocks)
            associate (b => self%blocks(i))
                call b%batch%add(y(b%first:b%last))
            end associate
        end do
        do i = 1, size(self%series)
            associate (sr => self%series(i))
                call sr%source%evaluate(t, y, sr%buffer, status)
                if (.not. status%ok()) then
                    call drop_record(self)
                    return
                end if
                call sr%batch%add(sr%buffer)
            end associate
        end do
        call self%time_batch%add([t])
        self%pending = self%pending + 1
        call system_clock(now, rate)
        if (self%pending < self%capacity .and. &
            real(now - self%last_write, wp) < flush_interval * real(rate, wp)) return
        call write_pending(self, err)
        if (err < 0) call status%set(status_io_error, self%path // &
                                     ': HDF5 cannot append the records held')
    end subroutine append

    !> Forget the record being added (a series could not be evaluated): the
    !> series already given it drop it again, so every series stays aligned.
    subroutine drop_record(self)
        class(hdf5_sink_t), intent(inout) :: self
        integer :: i
        self%y_batch%count = min(self%y_batch%count, self%pending)
        do i = 1, size(self%blocks)
            self%blocks(i)%batch%count = min(self%blocks(i)%batch%count, self%pending)
        end do
        do i = 1, size(self%series)
            self%series(i)%batch%count = min(self%series(i)%batch%count, self%pending)
        end do
    end subroutine drop_record

    !> The batch capacity from the values of a record (all series known now:
    !> none is added after the first record), and the room for it.
    subroutine reserve_batches(self, status)
        class(hdf5_sink_t), intent(inout) :: self
        type(status_t), intent(inout) :: status
        integer :: i, stat, worst
        real(wp) :: values
        integer(i8) :: rate
        values = real(self%y_batch%width() + self%time_batch%width(), wp)
        do i = 1, size(self%blocks)
            values = values + real(self%blocks(i)%batch%width(), wp)
        end do
        do i = 1, size(self%series)
            values = values + real(self%series(i)%batch%width(), wp)
        end do
        self%capacity = int(max(1.0_wp, min(real(max_batch_records, wp), &
            real(batch_bytes, wp) / (8.0_wp * values))))
        call self%y_batch%reserve(self%capacity, worst)
        call self%time_batch%reserve(self%capacity, stat)
        worst = max(worst, stat)
        do i = 1, size(self%blocks)
            call self%blocks(i)%batch%reserve(self%capacity, stat)
            worst = max(worst, stat)
        end do
        do i = 1, size(self%series)
            call self%series(i)%batch%reserve(self%capacity, stat)
            worst = max(worst, stat)
        end do
        if (worst /= 0) then
            self%capacity = 0
            call status%set(status_io_error, self%path // ': no memory for the records &
                &held between two writes (' // bytes_held(values) // ')')
            return
        end if
        call system_clock(self%last_write, rate)
    contains
        function bytes_held(per_record) result(text)
            real(wp), intent(in) :: per_record
            character(len=:), allocatable :: text
            character(len=32) :: buf
            write (buf, '(es9.2,a)') 8.0_wp * per_record * self%capacity, ' bytes'
            text = trim(adjustl(buf))
        end function bytes_held
    end subroutine reserve_batches

    !> Write the records held: /y, the blocks and series first, /time last,
    !> then flush, so that /time never counts a record not wholly written.
    subroutine write_pending(self, err)
        class(hdf5_sink_t), intent(inout) :: self
        integer, intent(out) :: err
        integer :: i
        integer(i8) :: rate
        err = 0
        if (self%pending == 0) return
        call self%y_batch%write_pending(self%records, err)
        do i = 1, size(self%blocks)
            if (err < 0) exit
            call self%blocks(i)%batch%write_pending(self%records, err)
        end do
        do i = 1, size(self%series)
            if (err < 0) exit
            call self%series(i)%batch%write_pending(self%records, err)
        end do
        if (err >= 0) call self%time_batch%write_pending(self%records, err)
        if (err >= 0) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
        if (err < 0) return
        self%records = self%records + self%pending
        self%pending = 0
        call system_clock(self%last_write, rate)
    end subroutine write_pending

    !> Initialise the Fortran HDF5 library once and silence its own error
    !> printing: every failure is reported through status_t instead.
    subroutine open_library(err)
        integer, intent(out) :: err
        err = 0
        if (library_open) return
        call h5open_f(err)
        if (err < 0) return
        call h5eset_auto_f(0, err)
        library_open = err >= 0
    end subroutine open_library
end module flexmbs_io_hdf5_sink
