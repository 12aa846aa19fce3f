#!/usr/bin/env bash
# `make bench` (part): the cost of modular assemblies. Prints figures,
# asserts nothing (docs/benchmarks.md has a measured copy).
#   Several flexible bodies: a soft bar of n x 2 x 2 hex8 elements hanging
#   from the ground by a spherical joint at its xmin face and falling under
#   gravity, against the same elements as two bars of n/2 x 2 x 2, the
#   upper hanging the same way, the lower from the upper by a spherical
#   joint between the faces they share (markers at the sets' centroids:
#   linear rows on the nodes, no node frame). CPU per step of both, best of
#   7 runs taken in turn, and their ratio (goal: two bodies at most 1.3 x one body's per
#   step), for RADAU5 and DDASSL (GGL, TOL 1e-6, 0.2 s, the sparse path,
#   one BLAS thread). Then the same scenes with every marker given its
#   centroid as `position`, which joins through node frames (massless
#   bodies: the acceleration layout), and the two bars against the bar
#   clamped at xmin (no joint), which prices the joints.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
[ -x "$BIN" ] || { echo "bench/assemblies.sh: could not build flexmbs" >&2; exit 1; }
OUT=build/bench/assemblies
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1
. bench/lib.sh

# bar NAME N X0 [CLAMP] -> a &flexible_body of N x 2 x 2 elements, 0.025 m each
# (CLAMP = 1: fixed at xmin when it starts at x = 0)
bar() {
    awk -v name="$1" -v n="$2" -v x0="$3" -v clamp="${4:-0}" 'BEGIN {
        printf "&flexible_body name = '\''%s'\'', divisions = %d, 2, 2,\n", name, n
        printf "    lengths = %.6f, 0.05, 0.05, origin = %.6f, -0.025, -0.025,\n", 0.025 * n, x0
        printf "    gravity = 0, -9.81, 0%s /\n", (x0 == 0 && clamp ? ", fixed = '\''xmin'\''" : "")
        printf "&material name = '\''%s soft'\'', body = '\''%s'\'', youngs_modulus = 7e5,\n", name, name
        printf "    density = 920, viscosity = 1000 /\n" }'
}

# scene FILE SOLVER N BODIES [FRAMED] -> the bar (BODIES = 1), the two halves
# (2), both hanging from the ground by their root face; or the bar clamped
# (BODIES = 0). FRAMED = 1: the node-set markers have a position (node frames)
scene() {
    FRAMED=${5:-0}
    local mid
    mid=$(awk -v n="$3" 'BEGIN { printf "%.6f", 0.0125 * n }')
    {
        echo "&simulation problem = 'multibody', t_end = 0.2 /"
        echo "&multibody formulation = 'ggl', gravity = 0, -9.81, 0 /"
        case "$4" in
        0) bar one "$3" 0 1 ;;
        1) bar one "$3" 0
           hang one ;;
        2) bar upper $(($3 / 2)) 0
           hang upper
           bar lower $(($3 / 2)) "$mid"
           echo "&marker name = 'upper tip', body = 'upper', node_set = 'xmax'$(at "$mid") /"
           echo "&marker name = 'lower root', body = 'lower', node_set = 'xmin'$(at "$mid") /"
           echo "&joint type = 'spherical', marker_i = 'upper tip', marker_j = 'lower root' /" ;;
        esac
        echo "&solver name = '$2', rtol = 1e-6, atol = 1e-6 /"
        echo "&output file = 'none' /"
    } > "$1"
}

# hang NAME -> a spherical joint from the ground to body NAME's xmin face
hang() {
    echo "&marker name = 'pivot', body = 'ground' /"
    echo "&marker name = '$1 root', body = '$1', node_set = 'xmin'$(at 0) /"
    echo "&joint type = 'spherical', marker_i = 'pivot', marker_j = '$1 root' /"
}

# at X -> ", position = X, 0, 0" when FRAMED (the face's centroid: a node frame)
at() {
    [ "$FRAMED" = 1 ] && printf ", position = %s, 0, 0" "$1"
}

# per_step FILE -> "CPU/step NST" of one run (CPU from the statistics line)
per_step() {
    local line cpu nst
    line=$(in_scene_folder "$1" "$(realpath "$BIN")" run "$(basename "$1")" --quiet 2>&1 | grep -E '^[a-z0-9]+: NST=' | tail -1)
    [ -n "$line" ] || { echo "failed -"; return; }
    cpu=$(echo "$line" | sed 's/.*CPU=\([0-9.]*\).*/\1/')
    nst=$(echo "$line" | sed 's/.*NST=\([0-9]*\).*/\1/')
    awk -v c="$cpu" -v n="$nst" 'BEGIN { printf "%.3e %d", c / n, n }'
}

# best_pair FILE1 FILE2 -> "CPU/step NST CPU/step NST": the best of RUNS runs
# of each, the two taken in turn (so that a slow spell of the shared machine
# falls on both)
RUNS=7
best_pair() {
    local b1="" b2="" r
    for _ in $(seq "$RUNS"); do
        r=$(per_step "$1")
        if [ -z "$b1" ] || awk -v a="${r%% *}" -v b="${b1%% *}" 'BEGIN { exit !(a < b) }'; then b1=$r; fi
        r=$(per_step "$2")
        if [ -z "$b2" ] || awk -v a="${r%% *}" -v b="${b2%% *}" 'BEGIN { exit !(a < b) }'; then b2=$r; fi
    done
    echo "$b1 $b2"
}

# compare TITLE BASE [FRAMED]: rows of one body (scene kind BASE) against two
compare() {
    echo "== $1, best CPU per step of $RUNS, in turn (GGL, TOL 1e-6, 0.2 s)"
    echo "  solver  n   elements  one: CPU/step[s] NST  two: CPU/step[s] NST  ratio (goal <= 1.3)"
    for solver in radau5 ddassl; do
        for n in 16 32 64; do
            scene "$OUT/one${2}${3:-0}_${solver}_$n.nml" "$solver" "$n" "$2" "${3:-0}"
            scene "$OUT/two${3:-0}_${solver}_$n.nml" "$solver" "$n" 2 "${3:-0}"
            pair=$(best_pair "$OUT/one${2}${3:-0}_${solver}_$n.nml" \
                "$OUT/two${3:-0}_${solver}_$n.nml")
            awk -v s="$solver" -v n="$n" -v p="$pair" 'BEGIN {
                split(p, a, " ")
                r = (a[1] > 0 && a[3] > 0) ? sprintf("%.2f", a[3] / a[1]) : "-"
                printf "  %-7s %-3d %-9d %-16s %-4s %-16s %-4s %s\n", s, n, 4 * n, a[1], a[2], a[3], a[4], r }'
        done
    done
}

compare "one bar of n x 2 x 2 hex8 hanging by a spherical joint against two of n/2 x 2 x 2" 1
echo
compare "the same through node frames (markers given a position)" 1 1
echo
compare "the two bars (set markers) against one bar clamped at xmin (no joint)" 0
