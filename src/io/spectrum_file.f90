!> The spectrum of `flexmbs modes` as files: a CSV table of the finite
!> eigenvalues (headed by the comment 'written by flexmbs ...', like the
!> statistics tables, so that a later run may replace it) and the gnuplot
!> commands that draw it with the BDF sectors into a PNG beside it.
!>
!> Columns: mode (a conjugate pair shares its number; 0 for λ = 0),
!> Re λ and Im λ [1/s], |λ| [1/s], ω = |Im λ| [rad/s], f = ω/2π [Hz],
!> ζ = −Re λ/|λ| and the sector angle |arg(−λ)| [deg].
module flexmbs_io_spectrum_file
    use flexmbs_core_kinds, only: wp
    use flexmbs_core_status, only: status_t, status_io_error
    use flexmbs_core_version, only: written_by
    use flexmbs_core_text, only: real_text
    use flexmbs_dae_bdf_stability, only: sector_angle
    use flexmbs_io_table, only: table_file_ours
    implicit none
    private

    public :: write_spectrum, spectrum_plot_commands, spectrum_plot_ours

    !> The first bytes of every PNG file (PNG specification, §5.2).
    character(len=8), parameter :: png_signature = char(137) // 'PNG' // achar(13) // &
        achar(10) // achar(26) // achar(10)

contains

    !> The table at `path` (a .csv), replacing a file there.
    subroutine write_spectrum(path, lambda, mode, status)
        character(len=*), intent(in) :: path
        complex(wp), intent(in) :: lambda(:)     !! finite eigenvalues
        integer, intent(in) :: mode(:)           !! the mode of each
        type(status_t), intent(out) :: status
        real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)
        character(len=256) :: msg
        character(len=200) :: line
        integer :: unit, ios, i
        real(wp) :: zeta
        open (newunit=unit, file=path, status='replace', action='write', iostat=ios, &
              iomsg=msg)
        if (ios == 0) write (unit, '(a)', iostat=ios, iomsg=msg) '# ' // written_by, &
            '# mode,re_lambda,im_lambda,modulus,omega_rad_s,f_hz,zeta,angle_deg'
        do i = 1, size(lambda)
            if (ios /= 0) exit
            zeta = 0.0_wp
            if (abs(lambda(i)) > 0.0_wp) zeta = -real(lambda(i), wp) / abs(lambda(i))
            write (line, '(i0,7(",",es23.15e3))') mode(i), real(lambda(i), wp), &
                aimag(lambda(i)), abs(lambda(i)), abs(aimag(lambda(i))), &
                abs(aimag(lambda(i))) / two_pi, zeta, sector_angle(lambda(i))
            write (unit, '(a)', iostat=ios, iomsg=msg) trim(line)
        end do
        if (ios == 0) close (unit, iostat=ios, iomsg=msg)
        if (ios /= 0) call status%set(status_io_error, path // ': cannot write: ' // trim(msg))
    end subroutine write_spectrum

    !> gnuplot commands (one line, `;`-separated, for `gnuplot -e`) that
    !> draw the table `csv` into `png`: on the left λ in the complex plane
    !> with the sector boundaries of BDF-3..5, on the right each mode's
    !> sector angle against |λ| with the angles α_k and the stiffness bounds
    !> |λ| = 1/h of the steps `h` (none when empty).
    function spectrum_plot_commands(csv, png, title, alpha, h, h_names, radius, right) &
        result(text)
        character(len=*), intent(in) :: csv, png, title
        real(wp), intent(in) :: alpha(:)          !! α_k [deg], k = 1, 2, ...
        real(wp), intent(in) :: h(:)              !! step sizes marked [s]
        character(len=*), intent(in) :: h_names(:) !! their labels
        real(wp), intent(in) :: radius            !! largest |λ| shown [1/s]
        real(wp), intent(in) :: right             !! largest Re λ shown [1/s]
        character(len=:), allocatable :: text
        real(wp), parameter :: degree = acos(-1.0_wp) / 180.0_wp
        character(len=:), allocatable :: label
        real(wp) :: r, a
        integer :: k, i
        r = 1.05_wp * radius
        text = 'set terminal pngcairo size 1300,560 font '',10''; set output ' // &
            quoted(png) // '; set datafile separator '',''; set grid; ' // &
            'set multiplot layout 1,2 title ' // quoted(title) // ' noenhanced; ' // &
            'set title ''eigenvalues and the sectors of BDF-3, 4, 5''; ' // &
            'set xlabel ''Re lambda [1/s]''; set ylabel ''Im lambda [1/s]''; ' // &
            'set size ratio -1; unset key; set xrange [' // &
            interval(-r, max(0.1_wp * r, 1.05_wp * right)) // ']; set yrange [' // interval(-r, r) &
            // ']; '
        ! the sector boundaries arg(−λ) = ±α_k, dashed differently per order
        do k = 3, min(5, size(alpha))
            a = alpha(k) * degree
            do i = -1, 1, 2
                text = text // 'set arrow from 0,0 to ' // point(-r * cos(a), i * r * sin(a)) &
                    // ' nohead dt ' // achar(iachar('0') + k - 1) // '; '
            end do
            text = text // 'set label ''BDF-' // achar(iachar('0') + k) // ''' at ' // &
                point(-0.9_wp * r * cos(a), 0.9_wp * r * sin(a)) // ' front; '
        end do
        text = text // 'plot ' // quoted(csv) // ' using 2:3 with points pt 7 ps 0.5 ' // &
            'notitle; unset arrow; unset label; set size noratio; ' // &
            'set title ''sector angle against |lambda|: above alpha_k, outside BDF-k''''s &
            &sector''; set xlabel ''|lambda| [1/s]''; set ylabel ''|arg(-lambda)| [deg]''; ' &
            // 'set logscale x; set autoscale x; set yrange [0:180]; '
        ! α_1 = α_2 = 90°: one line for both
        do k = 2, size(alpha)
            label = 'alpha_' // achar(iachar('0') + k)
            if (k == 2) label = 'alpha_{1,2}'
            text = text // 'set arrow from graph 0, first ' // real_text(alpha(k)) // &
                ' to graph 1, first ' // real_text(alpha(k)) // ' nohead dt 2; set label ''' // &
                label // ''' at graph 0.01, first ' // real_text(alpha(k) + 2.0_wp) // '; '
        end do
        do i = 1, size(h)
            text = text // 'set arrow from first ' // real_text(1.0_wp / h(i)) // ', graph 0 to &
                &first ' // real_text(1.0_wp / h(i)) // ', graph 1 nohead lc rgb ''red''; ' // &
                'set label ''1/h ' // trim(h_names(i)) // ''' at first ' // &
                real_text(1.05_wp / h(i)) // ', graph 0.95 textcolor rgb ''red''; '
        end do
        text = text // 'plot ' // quoted(csv) // ' using ($1 > 0 ? $4 : 1/0):8 with points ' &
            // 'pt 7 ps 0.5; unset multiplot'
    contains
        function point(x, y) result(pair)
            real(wp), intent(in) :: x, y
            character(len=:), allocatable :: pair
            pair = real_text(x) // ',' // real_text(y)
        end function point
        function interval(low, high) result(pair)
            real(wp), intent(in) :: low, high
            character(len=:), allocatable :: pair
            pair = real_text(low) // ':' // real_text(high)
        end function interval
    end function spectrum_plot_commands

    !> A single-quoted gnuplot string ('' stands for ').
    pure function quoted(text) result(q)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: q
        integer :: i
        q = ''''
        do i = 1, len(text)
            q = q // text(i:i)
            if (text(i:i) == '''') q = q // ''''
        end do
        q = q // ''''
    end function quoted

    !> Whether the PNG at `path` is a spectrum plot of flexmbs: a PNG whose
    !> table (the same name ending in .csv) flexmbs wrote. gnuplot's PNG
    !> itself carries no mark to tell.
    logical function spectrum_plot_ours(path)
        character(len=*), intent(in) :: path
        character(len=8) :: head
        integer :: unit, ios, dot
        spectrum_plot_ours = .false.
        dot = index(path, '.', back=.true.)
        if (dot == 0) return
        open (newunit=unit, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=ios)
        if (ios /= 0) return
        read (unit, iostat=ios) head
        close (unit)
        if (ios /= 0 .or. head /= png_signature) return
        spectrum_plot_ours = table_file_ours(path(1:dot) // 'csv')
    end function spectrum_plot_ours
end module flexmbs_io_spectrum_file
