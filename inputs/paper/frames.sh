#!/usr/bin/env bash
# Frames of the five-body mechanism (docs/paper.md, like the paper's Figure 4):
# the reference trajectory at t = 0, 0.5 and 1 s drawn by gnuplot.
#   frames.sh FLEXMBS REFERENCE.h5 OUT.png
# y of inputs/five_body.nml: rocker r 1-3, slider r 8-10, the node frames'
# origins 15-17 (crank pin) and 22-24 (rocker pin), crank and flail angles
# 29-30, then the coupler's 45 nodes (x fastest on its 3 x 5 x 3 grid).
set -eu
exe=$1 ref=$2 out=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$exe" columns "$ref" $(seq 1 165) > "$tmp/all.txt"
for row in 1 51 101; do
    sed -n "${row}p" "$tmp/all.txt" | awk -v dir="$tmp" -v row="$row" '{
        t = $1
        for (k = 1; k <= 165; k++) y[k] = $(k + 1)
        # coupler wireframe: lines along x, y and z of the node grid
        f = dir "/mesh" row ".txt"
        for (kk = 0; kk < 3; kk++) for (j = 0; j < 5; j++) {
            for (i = 0; i < 3; i++) { n = i + 3 * j + 15 * kk; b = 31 + 3 * n
                print y[b], y[b + 1], y[b + 2] > f }
            print "\n" > f }
        for (kk = 0; kk < 3; kk++) for (i = 0; i < 3; i++) {
            for (j = 0; j < 5; j++) { n = i + 3 * j + 15 * kk; b = 31 + 3 * n
                print y[b], y[b + 1], y[b + 2] > f }
            print "\n" > f }
        for (j = 0; j < 5; j++) for (i = 0; i < 3; i++) {
            for (kk = 0; kk < 3; kk++) { n = i + 3 * j + 15 * kk; b = 31 + 3 * n
                print y[b], y[b + 1], y[b + 2] > f }
            print "\n" > f }
        # rigid parts as segments: crank, flail, rocker, rod to the slider
        g = dir "/rigid" row ".txt"
        th = y[29]; ph = y[30]
        print 0, 0, 0 > g; print y[15], y[16], y[17] > g; print "\n" > g
        px = 0.1 * cos(th); py = 0.1 * sin(th)
        # flail: 0.1 below its pivot, turned by ph about the crank axis
        lx = 0; ly = 0.1 * sin(ph); lz = -0.1 * cos(ph)
        print px, py, 0 > g
        print px + lx * cos(th) - ly * sin(th), py + lx * sin(th) + ly * cos(th), lz > g
        print "\n" > g
        print 0.2, 0.4, -0.3 > g; print y[22], y[23], y[24] > g; print "\n" > g
        print 0.2, 0.15, -0.2 > g; print y[8], y[9], y[10] > g; print "\n" > g
        printf "%.2f\n", t > (dir "/time" row ".txt")
    }'
done
gnuplot <<GP
set terminal pngcairo size 1350,480 font ',10'
set output '$out'
set multiplot layout 1,3 title 'Five-body mechanism (damped): crank and flail (chain), coupler (flexible), rocker, slider with its rod'
set view 70, 20
set xyplane 0
set xrange [-0.25:0.3]; set yrange [-0.25:0.5]; set zrange [-0.45:0.2]
set xlabel 'x'; set ylabel 'y'; set zlabel 'z'
unset key
set ticslevel 0
do for [r in "1 51 101"] {
    t = system('cat $tmp/time'.r.'.txt')
    set title 't = '.t.' s'
    splot '$tmp/mesh'.r.'.txt' with lines lc rgb '#1f77b4', \
          '$tmp/rigid'.r.'.txt' with linespoints lw 3 pt 7 ps 0.8 lc rgb '#d62728'
}
unset multiplot
GP
