#!/usr/bin/env bash
# `make bench`: RADAU5 on van der Pol and on the sparse reaction-diffusion
# problems at 1e2..1e5 unknowns, dense and KLU (band LU too in 1-D). Prints
# figures (CPU, wall, time per step, peak memory, counters), never asserts.
# Dense LU is capped in steps where it would take minutes, and skipped where
# it cannot fit.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release --example flexmbs-bench --runner echo 2>/dev/null | tail -1)
if [ ! -x "$BIN" ]; then
    echo "bench: could not build flexmbs-bench" >&2
    exit 1
fi
OUT=build/bench
mkdir -p "$OUT"
RESULTS=$OUT/results.txt
: > "$RESULTS"

run() {  # problem size solver [max_steps]
    "$BIN" "$@" | tee -a "$RESULTS"
}

echo "problem n solver outcome t_reached NST NAC NFE NJE NDEC CPU[s] WALL[s] CPU/step[s] peak[MiB]"
run vdp 2 dense
run vdp 2 klu
for n in 100 1000 10000 100000; do
    case $n in
        100|1000) run rd1d $n dense ;;
        10000)    run rd1d $n dense 3 ;;   # ~1 GB of dense matrices: capped at 3 steps
    esac
    run rd1d $n klu
    run rd1d $n band   # bandwidths 2, 2: the case for band LU
done
# 2-D: 2·N² unknowns for N = 7, 22, 71, 224 (about 1e2, 1e3, 1e4, 1e5).
for m in 7 22 71 224; do
    case $m in
        7|22) run rd2d $m dense ;;
        71)   run rd2d $m dense 3 ;;
    esac
    run rd2d $m klu
done

echo
echo "time per step growth between successive sizes (KLU): exponent p in t ~ n^p"
for p in rd1d rd2d; do
    awk -v p=$p '$1 == p && $3 == "klu" { if (n0 > 0) printf "%s  n %d -> %d: p = %.2f\n", p, n0, $2, log($13/t0)/log($2/n0); n0 = $2; t0 = $13 }' "$RESULTS"
done
echo
echo "KLU speed-up over dense in time per step at equal size:"
awk '{ key = $1" "$2; if ($3 == "dense") d[key] = $13; else if ($3 == "klu") k[key] = $13 }
     END { for (key in d) if (key in k && k[key] > 0) printf "%s: %.1fx\n", key, d[key]/k[key] }' "$RESULTS" | sort
