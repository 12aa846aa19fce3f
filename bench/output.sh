#!/usr/bin/env bash
# `make bench` (part): how fast results are written (docs/output.md: records
# are held in memory and written in batches, at least once a second).
# Prints figures, asserts nothing (docs/benchmarks.md has a measured copy).
#   1. a small state: van der Pol (2 unknowns) with 2e6 and 1e7 output
#      records: records/s and MB/s of the whole run, and of the writing
#      alone (the same run with file = 'none' subtracted); goal 1e6
#      records/s;
#   2. a large state: inputs/five_body_fine.nml over 0.01 s with 11 and 1001
#      records: the cost of one record (the state, the bodies' and joints'
#      series with the reactions' consistent multipliers, the coupler's
#      displacements, velocities and stresses) and the bytes a record adds.
# Best of 3 wall times, release build, one BLAS thread.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
[ -x "$BIN" ] || { echo "bench/output.sh: could not build flexmbs" >&2; exit 1; }
OUT=build/bench/output
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1

# best_wall FILE -> the least wall time of 3 runs, seconds
best_wall() {
    local best="" w
    for _ in 1 2 3; do
        /usr/bin/time -o "$OUT/time.txt" -f "%e" "$BIN" run "$1" --quiet --force \
            > /dev/null 2>&1
        w=$(tail -1 "$OUT/time.txt")
        if [ -z "$best" ] || awk -v a="$w" -v b="$best" 'BEGIN { exit !(a < b) }'; then best=$w; fi
    done
    echo "$best"
}

# scene SRC OUT N_OUTPUT FILE [SED]: SRC with n_output and the output file set
scene() {
    sed -e "s/n_output *= *[0-9]*/n_output = $3/" -e "s#^&output#\&output file = '$4',#" \
        -e "s#mesh_file = '\([^/']\)#mesh_file = '$PWD/$(dirname "$1")/\1#" \
        -e "${5:-}" "$1" > "$2"
}

echo "== 1. a small state: van der Pol (2 unknowns, 24 bytes a record)"
echo "  records     wall[s]  no file[s]  records/s (run)  records/s (writing)  MB/s (file)"
for n in 2000000 10000000; do
    scene inputs/van_der_pol.nml "$OUT/vdp_$n.nml" "$n" "$PWD/$OUT/vdp_$n.h5"
    scene inputs/van_der_pol.nml "$OUT/vdp_${n}_none.nml" "$n" none
    with=$(best_wall "$OUT/vdp_$n.nml")
    without=$(best_wall "$OUT/vdp_${n}_none.nml")
    bytes=$(stat -c %s "$OUT/vdp_$n.h5" 2>/dev/null || echo 0)
    awk -v n="$n" -v a="$with" -v b="$without" -v s="$bytes" 'BEGIN {
        w = a - b; printf "  %8d  %9.3f  %10.3f  %15.3g  %19s  %11.1f\n", n, a, b, n / a,
            (w > 0 ? sprintf("%.3g", n / w) : "-"), s / a / 1e6 }'
    rm -f "$OUT/vdp_$n.h5"
done
echo "  (goal: at least 1e6 records/s for a small state)"

echo
echo "== 2. a large state: inputs/five_body_fine.nml over 0.01 s (2268 FE coordinates)"
echo "  records  wall[s]  file[MB]"
declare -A WALL SIZE
for n in 11 1001; do
    scene inputs/five_body_fine.nml "$OUT/fine_$n.nml" "$n" "$PWD/$OUT/fine_$n.h5" \
        "s/t_end   = 1.0 /t_end   = 0.01 /"
    WALL[$n]=$(best_wall "$OUT/fine_$n.nml")
    SIZE[$n]=$(stat -c %s "$OUT/fine_$n.h5" 2>/dev/null || echo 0)
    awk -v n="$n" -v w="${WALL[$n]}" -v s="${SIZE[$n]}" \
        'BEGIN { printf "  %7d  %7.3f  %8.2f\n", n, w, s / 1e6 }'
done
awk -v w1="${WALL[11]}" -v w2="${WALL[1001]}" -v s1="${SIZE[11]}" -v s2="${SIZE[1001]}" 'BEGIN {
    per = (w2 - w1) / 990; bytes = (s2 - s1) / 990
    printf "  a record: %.2f ms and %.1f kB, %.0f records/s, %.1f MB/s\n", 1e3 * per,
        bytes / 1e3, (per > 0 ? 1 / per : 0), (per > 0 ? bytes / per / 1e6 : 0) }'
rm -f "$OUT"/fine_*.h5
