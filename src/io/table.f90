!> Statistics tables in Markdown, CSV and LaTeX.
!>
!> The columns are those of the paper's Table 3 (solver, TOL, stab., ERR,
!> NST, NAC, NFE, NJE, CPU) followed by NRJ, NDEC and NSOL; asked for
!> (`reasons`), NRJ by cause follows in one column a cause (the Table 2
!> layout: one row a cause). A row whose error was not measured shows '-'
!> for ERR. A table file starts with the comment line 'written by flexmbs
!> 0.1.0' of its format (table_file_ours).
module flexmbs_io_table
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_text, only: int_text
    use flexmbs_core_status, only: status_t, status_bad_input, status_io_error
    use flexmbs_core_version, only: written_by, is_written_by
    use flexmbs_core_files, only: read_first_lines
    use flexmbs_dae_stats, only: dae_stats_t
    use flexmbs_dae_rejections, only: cause_count, cause_labels
    implicit none
    private

    integer, parameter, public :: table_markdown = 1
    integer, parameter, public :: table_csv = 2
    integer, parameter, public :: table_latex = 3

    integer, parameter :: ncol = 12
    character(len=6), parameter :: headers(ncol) = [character(len=6) :: 'solver', 'TOL', &
        'stab.', 'ERR', 'NST', 'NAC', 'NFE', 'NJE', 'CPU', 'NRJ', 'NDEC', 'NSOL']
    !> Numeric columns are right-aligned.
    logical, parameter :: numeric(ncol) = [.false., .true., .false., .true., .true., .true., &
        .true., .true., .true., .true., .true., .true.]

    type :: cell_t
        character(len=:), allocatable :: s
    end type cell_t

    !> One run: what was solved how, and what it cost.
    type, public :: stats_row_t
        character(len=:), allocatable :: solver !! e.g. 'radau5'
        character(len=:), allocatable :: stab   !! formulation/stabilisation, '' if none
        real(wp) :: tol = 0.0_wp                !! the tolerance asked for
        real(wp) :: err = -1.0_wp               !! ERR of eq. (13); negative = not measured
        type(dae_stats_t) :: stats
        !> > 0: the CPU column shows stats%cpu / cpu_unit (normalised)
        real(wp) :: cpu_unit = 0.0_wp
    end type stats_row_t

    public :: new_stats_row, table_format, table_text, table2_text, layout_text, write_table, &
        table_file_ours

contains

    !> A row from a run's statistics; `err` omitted when not measured.
    function new_stats_row(solver, tol, stab, stats, err) result(row)
        character(len=*), intent(in) :: solver, stab
        real(wp), intent(in) :: tol
        type(dae_stats_t), intent(in) :: stats
        real(wp), intent(in), optional :: err
        type(stats_row_t) :: row
        row%solver = solver
        row%stab = stab
        row%tol = tol
        row%stats = stats
        if (present(err)) row%err = err
    end function new_stats_row

    !> The format a path's extension asks for (.md, .csv, .tex); 0 otherwise.
    pure integer function table_format(path)
        character(len=*), intent(in) :: path
        integer :: dot
        character(len=:), allocatable :: ext
        table_format = 0
        dot = index(path, '.', back=.true.)
        if (dot == 0) return
        ext = path(dot + 1:)
        select case (ext)
        case ('md', 'MD'); table_format = table_markdown
        case ('csv', 'CSV'); table_format = table_csv
        case ('tex', 'TEX'); table_format = table_latex
        end select
    end function table_format

    !> The whole table as text, lines ended by newlines; with `reasons`, NRJ
    !> by cause in one more column a cause.
    function table_text(rows, format, reasons) result(text)
        type(stats_row_t), intent(in) :: rows(:)
        integer, intent(in) :: format !! table_markdown, table_csv or table_latex
        logical, intent(in), optional :: reasons
        character(len=:), allocatable :: text
        type(cell_t), allocatable :: cells(:, :)
        integer :: i, j, n

        n = ncol
        if (present(reasons)) then
            if (reasons) n = ncol + cause_count
        end if
        allocate (cells(n, 0:size(rows)))
        do j = 1, ncol
            cells(j, 0)%s = trim(headers(j))
        end do
        do j = ncol + 1, n
            cells(j, 0)%s = trim(cause_labels(j - ncol))
        end do
        do i = 1, size(rows)
            call fill_cells(rows(i), format, cells(1:ncol, i))
            call fill_causes(rows(i), cells(ncol + 1:n, i))
        end do
        text = render(cells, [numeric, spread(.true., 1, n - ncol)], format)
    end function table_text

    !> The paper's Table 2 layout: one column per run (its solver label),
    !> rows ERR, NST, rejected/NST, NJE and CPU; with `reasons`, NRJ by
    !> cause in one more row a cause.
    function table2_text(rows, format, reasons) result(text)
        type(stats_row_t), intent(in) :: rows(:)
        integer, intent(in) :: format
        logical, intent(in), optional :: reasons
        character(len=:), allocatable :: text
        character(len=12), parameter :: names(5) = [character(len=12) :: 'ERR', 'NST', &
            'rejected/NST', 'NJE', 'CPU']
        type(cell_t), allocatable :: cells(:, :), run(:)
        logical :: flags(size(rows) + 1)
        character(len=32) :: buf
        integer :: i, k, nrow, counts(cause_count)
        nrow = 5
        if (present(reasons)) then
            if (reasons) nrow = 5 + cause_count
        end if
        allocate (cells(size(rows) + 1, 0:nrow), run(ncol))
        cells(1, 0)%s = ''
        do k = 1, 5
            cells(1, k)%s = trim(names(k))
        end do
        do k = 6, nrow
            cells(1, k)%s = trim(cause_labels(k - 5))
        end do
        do i = 1, size(rows)
            ! fill_cells' columns: 1 solver, 4 ERR, 5 NST, 8 NJE, 9 CPU
            call fill_cells(rows(i), format, run)
            cells(i + 1, 0)%s = run(1)%s
            cells(i + 1, 1)%s = run(4)%s
            cells(i + 1, 2)%s = run(5)%s
            write (buf, '(f0.1,a)') 100.0_wp * rows(i)%stats%nrj / max(rows(i)%stats%nst, 1), &
                merge(' \%', ' % ', format == table_latex)
            if (buf(1:1) == '.') buf = '0' // trim(buf)
            cells(i + 1, 3)%s = trim(buf)
            cells(i + 1, 4)%s = run(8)%s
            cells(i + 1, 5)%s = run(9)%s
            counts = rows(i)%stats%rejections%counts_by_cause()
            do k = 6, nrow
                cells(i + 1, k)%s = int_text(counts(k - 5))
            end do
        end do
        flags = .true.
        flags(1) = .false.
        text = render(cells, flags, format)
    end function table2_text

    !> The table in a study's layout: 'table2' (table2_text), otherwise the
    !> row per run of table_text; with `reasons`, NRJ by cause as well.
    function layout_text(rows, format, layout, reasons) result(text)
        type(stats_row_t), intent(in) :: rows(:)
        integer, intent(in) :: format
        character(len=*), intent(in) :: layout !! 'table3' | 'table2'
        logical, intent(in), optional :: reasons
        character(len=:), allocatable :: text
        if (layout == 'table2') then
            text = table2_text(rows, format, reasons)
        else
            text = table_text(rows, format, reasons)
        end if
    end function layout_text

    !> Cells (column, row 0 = header) as Markdown, CSV or LaTeX; numeric
    !> columns right-aligned.
    function render(cells, numeric, format) result(text)
        type(cell_t), intent(in) :: cells(:, 0:)
        logical, intent(in) :: numeric(:)
        integer, intent(in) :: format
        character(len=:), allocatable :: text
        integer :: i, j, width(size(cells, 1)), ncol, nrow
        character, parameter :: nl = new_line('a')
        ncol = size(cells, 1)
        nrow = size(cells, 2) - 1
        text = ''
        select case (format)
        case (table_markdown)
            do j = 1, ncol
                width(j) = max(3, maxval([(len(cells(j, i)%s), i=0, nrow)]))
            end do
            text = md_line(cells(:, 0), width)
            text = text // '|'
            do j = 1, ncol
                if (numeric(j)) then
                    text = text // ' ' // repeat('-', width(j) - 1) // ': |'
                else
                    text = text // ' ' // repeat('-', width(j)) // ' |'
                end if
            end do
            text = text // nl
            do i = 1, nrow
                text = text // md_line(cells(:, i), width)
            end do
        case (table_csv)
            do i = 0, nrow
                do j = 1, ncol
                    if (j > 1) text = text // ','
                    text = text // csv_field(cells(j, i)%s)
                end do
                text = text // nl
            end do
        case (table_latex)
            text = '\begin{tabular}{'
            do j = 1, ncol
                text = text // merge('r', 'l', numeric(j))
            end do
            text = text // '}' // nl // '\hline' // nl
            do i = 0, nrow
                do j = 1, ncol
                    if (j > 1) text = text // ' & '
                    text = text // cells(j, i)%s
                end do
                text = text // ' \\' // nl
                if (i == 0) text = text // '\hline' // nl
            end do
            text = text // '\hline' // nl // '\end{tabular}' // nl
        end select

    contains

        function md_line(row, width) result(line)
            type(cell_t), intent(in) :: row(:)
            integer, intent(in) :: width(:)
            character(len=:), allocatable :: line
            integer :: k, pad
            line = '|'
            do k = 1, size(row)
                pad = width(k) - len(row(k)%s)
                if (numeric(k)) then
                    line = line // ' ' // repeat(' ', pad) // row(k)%s // ' |'
                else
                    line = line // ' ' // row(k)%s // repeat(' ', pad) // ' |'
                end if
            end do
            line = line // nl
        end function md_line
    end function render

    !> Write the table to `path` in the format of its extension; `reasons`
    !> adds NRJ by cause (default: the paper's columns only); a `note` (not
    !> '') is a line after the table (CSV and LaTeX: a comment), such as
    !> that the reference was stale and used all the same.
    subroutine write_table(path, rows, status, layout, reasons, note)
        character(len=*), intent(in) :: path
        type(stats_row_t), intent(in) :: rows(:)
        type(status_t), intent(out) :: status
        character(len=*), intent(in), optional :: layout !! layout_text's; default 'table3'
        logical, intent(in), optional :: reasons
        character(len=*), intent(in), optional :: note
        integer :: format, unit, ios
        character(len=256) :: msg
        format = table_format(path)
        if (format == 0) then
            call status%set(status_bad_input, path // ': table format unknown: ' // &
                'the name must end in .md, .csv or .tex')
            return
        end if
        open (newunit=unit, file=path, access='stream', form='unformatted', &
              status='replace', action='write', iostat=ios, iomsg=msg)
        if (ios == 0) write (unit, iostat=ios, iomsg=msg) comment(format) // new_line('a')
        if (ios == 0) then
            if (present(layout)) then
                write (unit, iostat=ios, iomsg=msg) layout_text(rows, format, layout, reasons)
            else
                write (unit, iostat=ios, iomsg=msg) table_text(rows, format, reasons)
            end if
            if (present(note) .and. ios == 0) then
                if (len(note) > 0) write (unit, iostat=ios, iomsg=msg) note_line(note, format)
            end if
            close (unit)
        end if
        if (ios /= 0) call status%set(status_io_error, path // ': cannot write: ' // trim(msg))
    end subroutine write_table

    !> Whether `path` is a table of flexmbs in the format of its extension
    !> (its first line the comment that write_table writes).
    logical function table_file_ours(path)
        character(len=*), intent(in) :: path
        character(len=256) :: lines(1)
        integer :: format, count
        table_file_ours = .false.
        format = table_format(path)
        if (format == 0) return
        call read_first_lines(path, lines, count)
        if (count == 1) table_file_ours = is_written_by(lines(1), opening(format))
    end function table_file_ours

    !> The first line of a table file: 'written by flexmbs ...' as a comment.
    function comment(format) result(line)
        integer, intent(in) :: format
        character(len=:), allocatable :: line
        line = opening(format) // written_by
        if (format == table_markdown) line = line // ' -->'
    end function comment

    !> A note after a table: in Markdown a paragraph of its own (shown),
    !> in CSV and LaTeX a comment (read by no program).
    function note_line(note, format) result(line)
        character(len=*), intent(in) :: note
        integer, intent(in) :: format
        character(len=:), allocatable :: line
        if (format == table_markdown) then
            line = new_line('a') // note // new_line('a')
        else
            line = opening(format) // note // new_line('a')
        end if
    end function note_line

    !> How a comment opens in the format (Markdown: an HTML comment, hidden
    !> when rendered; CSV: '#', which gnuplot and numpy skip; LaTeX: '%').
    pure function opening(format) result(text)
        integer, intent(in) :: format
        character(len=:), allocatable :: text
        select case (format)
        case (table_markdown); text = '<!-- '
        case (table_csv); text = '# '
        case default; text = '% '
        end select
    end function opening

    ! ------------------------------------------------------------------

    subroutine fill_cells(row, format, cells)
        type(stats_row_t), intent(in) :: row
        integer, intent(in) :: format
        type(cell_t), intent(out) :: cells(:)
        character(len=32) :: buf
        cells(1)%s = text_cell(row%solver, format)
        cells(2)%s = sci(row%tol, format)
        if (allocated(row%stab)) then
            cells(3)%s = text_cell(row%stab, format)
        else
            cells(3)%s = ''
        end if
        if (len(cells(3)%s) == 0) cells(3)%s = '-'
        if (row%err < 0.0_wp .or. .not. ieee_is_finite(row%err)) then
            cells(4)%s = '-'
        else
            cells(4)%s = sci(row%err, format)
        end if
        cells(5)%s = int_text(row%stats%nst)
        cells(6)%s = int_text(row%stats%nac)
        cells(7)%s = int_text(row%stats%nfe)
        cells(8)%s = int_text(row%stats%nje)
        if (row%cpu_unit > 0.0_wp) then
            write (buf, '(f0.2)') row%stats%cpu / row%cpu_unit
        else
            write (buf, '(f0.3)') row%stats%cpu
        end if
        if (buf(1:1) == '.') buf = '0' // trim(buf)
        cells(9)%s = trim(buf)
        cells(10)%s = int_text(row%stats%nrj)
        cells(11)%s = int_text(row%stats%ndec)
        cells(12)%s = int_text(row%stats%nsol)
    end subroutine fill_cells

    !> NRJ by cause, in the order of the cause_* constants.
    subroutine fill_causes(row, cells)
        type(stats_row_t), intent(in) :: row
        type(cell_t), intent(out) :: cells(:)
        integer :: counts(cause_count), c
        counts = row%stats%rejections%counts_by_cause()
        do c = 1, size(cells)
            cells(c)%s = int_text(counts(c))
        end do
    end subroutine fill_causes

    !> 1.0e-04 (Markdown, CSV) or $1.0\cdot 10^{-4}$ (LaTeX).
    function sci(x, format) result(s)
        real(wp), intent(in) :: x
        integer, intent(in) :: format
        character(len=:), allocatable :: s
        character(len=32) :: buf
        integer :: e
        if (x == 0.0_wp) then
            s = '0'
            return
        end if
        write (buf, '(es9.1e2)') x
        s = trim(adjustl(buf))
        if (format /= table_latex) then
            s = lower_e(s)
            return
        end if
        ! exponent from the rounded text, so 9.96e-5 gives 10^{-4}
        read (s(index(s, 'E') + 1:), *) e
        write (buf, '(i0)') e
        if (s(1:index(s, 'E') - 1) == '1.0') then
            s = '$10^{' // trim(buf) // '}$'
        else
            s = '$' // s(1:index(s, 'E') - 1) // '\cdot 10^{' // trim(buf) // '}$'
        end if
    end function sci

    pure function lower_e(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: k
        t = s
        k = index(t, 'E')
        if (k > 0) t(k:k) = 'e'
    end function lower_e

    !> A text cell, with LaTeX's special characters escaped.
    pure function text_cell(s, format) result(t)
        character(len=*), intent(in) :: s
        integer, intent(in) :: format
        character(len=:), allocatable :: t
        integer :: i
        if (format /= table_latex) then
            t = s
            return
        end if
        t = ''
        do i = 1, len(s)
            if (index('_&%#$', s(i:i)) > 0) then
                t = t // '\' // s(i:i)
            else
                t = t // s(i:i)
            end if
        end do
    end function text_cell

    !> Quote a CSV field when it holds a comma, a quote or a newline.
    pure function csv_field(s) result(t)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        integer :: i
        if (scan(s, ',"' // new_line('a')) == 0) then
            t = s
            return
        end if
        t = '"'
        do i = 1, len(s)
            t = t // s(i:i)
            if (s(i:i) == '"') t = t // '"'
        end do
        t = t // '"'
    end function csv_field
end module flexmbs_io_table
