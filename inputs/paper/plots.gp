# The paper's figures from `make paper`'s results (run from the repository
# root): Figure 5 (the coupler's middle node over time, damped and
# undamped, from the two references), Figure 6 (RADAU5 + GGL over TOL) and
# a work-precision diagram (ERR against CPU, every run of Table 3), each
# for the coarse coupler mesh and (files *_fine*) for the fine one.
set terminal pngcairo size 900,560 font ',11'
set grid
set key top left

set output 'results/figure5.png'
set title 'Five-body mechanism: x of the coupler''s middle node'
set xlabel 't [s]'
set ylabel 'x [m]'
plot 'results/figure5_damped.txt' using 1:2 with lines lw 2 title 'damped (eta = 1000 Pa s)', \
     'results/figure5_undamped.txt' using 1:2 with lines lw 2 title 'undamped'

set output 'results/figure5_fine.png'
set title 'Five-body mechanism, fine coupler mesh: x of the coupler''s centre'
set xrange [0:0.2]
plot 'results/figure5_fine.txt' using 1:2 with lines lw 2 title 'damped (eta = 1000 Pa s)', \
     'results/figure5_fine_undamped.txt' using 1:2 with lines lw 2 title 'undamped'
set autoscale x

do for [mesh in "coarse fine"] {
sfx = (mesh eq 'fine') ? '_fine' : ''
set output 'results/figure6'.sfx.'.png'
set datafile separator ','
set title 'RADAU5 + GGL on the five-body mechanism ('.mesh.' coupler mesh)'
set xlabel 'TOL'
set ylabel 'normalised to TOL = 1e-4'
set logscale x
set format x '10^{%L}'
set xrange [2e-4:5e-10]
set key top left
stats 'results/figure6'.sfx.'.csv' using 5 every ::1::1 nooutput name 'NST'
stats 'results/figure6'.sfx.'.csv' using 8 every ::1::1 nooutput name 'NJE'
plot 'results/figure6'.sfx.'.csv' every ::1 using 2:($5/NST_min) with linespoints lw 2 title 'NST', \
     '' every ::1 using 2:($8/NJE_min) with linespoints lw 2 title 'NJE', \
     '' every ::1 using 2:9 with linespoints lw 2 title 'CPU'

set output 'results/work_precision'.sfx.'.png'
set title 'Work-precision: five-body mechanism, damped (Table 3, '.mesh.' coupler mesh)'
set xlabel 'CPU (normalised to DDASSL, no stabilisation, TOL 1e-6)'
set ylabel 'ERR'
set autoscale x
set logscale xy
set format x '%g'
set format y '10^{%L}'
set key bottom left
sel(s, want) = (strstrt(s, want) == 1 ? 1 : NaN)
plot 'results/table3'.sfx.'.csv' every ::1 using ($9*sel(strcol(1).strcol(3), 'ddassl p_max=2none')):4 \
         with points pt 7 ps 1.5 title 'DDASSL (pmax 2)', \
     '' every ::1 using ($9*sel(strcol(1).strcol(3), 'ddassl p_max=2ggl')):4 \
         with points pt 5 ps 1.5 title 'DDASSL (pmax 2), GGL', \
     '' every ::1 using ($9*sel(strcol(1).strcol(3), 'radau5none')):4 \
         with points pt 9 ps 1.5 title 'RADAU5', \
     '' every ::1 using ($9*sel(strcol(1).strcol(3), 'radau5ggl')):4 \
         with points pt 11 ps 1.5 title 'RADAU5, GGL', \
     '' every ::1 using ($9*sel(strcol(1), 'mexax')):4 \
         with points pt 13 ps 1.5 title 'MEXAX, projection'
unset logscale
set datafile separator whitespace
}
