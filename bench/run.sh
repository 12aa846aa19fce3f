#!/usr/bin/env bash
# `make bench`: RADAU5, DDASSL (maximal order 5, and 2 where cheap) and IDA
# on the same problems with the same tolerances (rtol = atol = 1e-6): van der
# Pol, the planar pendulum (index 3, index 2, GGL) and the sparse
# reaction-diffusion problems at 1e2..1e5 unknowns, dense LU and KLU (band LU
# too in 1-D, where the integrator offers it). Prints one row per run:
# counters, CPU, wall, time per step, peak memory and the error ERR at t_end
# against a reference; never asserts. Runs that would take minutes are capped
# in steps (outcome 'capped', ERR '-'); runs that cannot fit or would take far
# too long are listed as 'skipped' with the reason. A run that fails prints
# its row with outcome 'failed' (the reason goes to build/bench/errors.txt).
# Last, sparse LU alone (flexmbs-bench sparse_lu): KLU against MUMPS on 3-D,
# slender and Brusselator patterns, the figures behind linear_solver = 'auto'.
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
ERRORS=$OUT/errors.txt
RTOL=1e-6
: > "$RESULTS"
: > "$ERRORS"

run() {  # integrator problem size solver [max_steps]
    local line rc
    line=$("$BIN" "$1" "$2" "$3" "$4" "${5:-100000}" "$RTOL" "$OUT/ref-$2-$3.txt" \
        2>>"$ERRORS")
    rc=$?
    # A crash (not a failed integration, which prints its row) still gets a row.
    [ -n "$line" ] || line="$1 $2 $3 $4 crashed(exit=$rc)"
    echo "$line" | tee -a "$RESULTS"
}

skip() {  # integrator problem n solver reason
    echo "$1 $2 $3 $4 skipped: $5" | tee -a "$RESULTS"
}

echo "references at t_end (RADAU5, rtol = atol = 1e-10):"
for p in "rd1d 100" "rd1d 1000" "rd1d 10000" "rd1d 100000" "rd2d 7" "rd2d 22" "rd2d 71"; do
    set -- $p
    "$BIN" reference "$1" "$2" "$OUT/ref-$1-$2.txt" 2>>"$ERRORS" || rm -f "$OUT/ref-$1-$2.txt"
done
echo
echo "integrator problem n solver outcome t_reached NST NAC NFE NJE NDEC CPU[s] WALL[s] CPU/step[s] peak[MiB] ERR"

for integ in radau5 ddassl ddassl-p2 ida; do
    for p in vdp pend2 pendggl; do
        run $integ $p 2 dense
        run $integ $p 2 klu
    done
    # Index 3 is RADAU5's; the BDF codes are run to show what they make of it.
    run $integ pend3 2 dense
done
# MEXAX integrates the mechanical form of the same pendulum directly, and
# the planar chain, MEXAX's published test (docs/solvers.md) (8 bars: ERR against the original's
# reference; 100 and 1000 bars: dense against KLU on [M Gᵀ; G 0]).
for integ in mexax mexax-euler; do
    run $integ pendmech 2 dense
    run $integ chain 8 dense
    run $integ chain 8 klu
    run $integ chain 100 dense 20    # ~0.4 s a step: capped at 20 steps
    run $integ chain 100 klu
    skip $integ chain 1000 dense "order 5000: ~2 s an LU, ~100 s a step"
    run $integ chain 1000 klu 300    # ~25 ms a step: capped at 300 steps
done

# The paper's AD comparison: constraint derivatives and whole runs, hand-coded
# against dual-number AD, on the driven four-bar and slider-crank.
echo
for mech in fourbar slidercrank; do
    "$BIN" ad $mech 2>>"$ERRORS" | tee -a "$RESULTS"
done

# Rigid chains: M(q), f, ∂(M w)/∂q, ∂f/∂(q, v) per evaluation for 4..64 links.
echo
CHAIN_BIN=$($FPM run --profile release --example flexmbs-bench-chain --runner echo 2>/dev/null | tail -1)
if [ -x "$CHAIN_BIN" ]; then
    "$CHAIN_BIN" 2>>"$ERRORS" | tee -a "$RESULTS"
else
    echo "bench: could not build flexmbs-bench-chain" | tee -a "$ERRORS"
fi

# Finite-element assembly: clamped cubes of 1e3..1e5 free dofs, both elements.
echo
echo "assembly element ndof elements nnz repeats t_tangent[s] us/element t_force[s] us/element bytes/dof threads"
for kind in hex8 hex27; do
    for n in 1000 10000 100000; do
        "$BIN" assembly $kind $n 2>>"$ERRORS" | tee -a "$RESULTS"
    done
done
echo "assembly cost growth with the number of elements (1 = linear): p in t ~ elements^p"
awk '$1 == "assembly" { if ($2 == kind && e0 > 0)
         printf "%-5s elements %d -> %d: tangent p = %.2f, force p = %.2f\n", $2, e0, $4,
                log($7/t0)/log($4/e0), log($9/f0)/log($4/e0)
     kind = $2; e0 = $4; t0 = $7; f0 = $9 }' "$RESULTS"
echo

DENSE_IDA="SUNDIALS' unblocked dense LU: over 5 min for 10 steps on the periodic grid"
for integ in radau5 ddassl ddassl-p2 ida; do
    for n in 100 1000 10000 100000; do
        case $integ:$n in
            *:100|*:1000)     run $integ rd1d $n dense ;;
            radau5:10000)     run $integ rd1d $n dense 1 ;;   # 3.1 GB, ~60 s an LU pair
            ddassl:10000)     run $integ rd1d $n dense 2 ;;   # one LAPACK LU ~20 s
            ida:10000)        run $integ rd1d $n dense 10 ;;  # ~1.5 s a step
            ddassl-p2:10000)  ;;                              # same first steps as ddassl
            *:100000)         skip $integ rd1d $n dense "80 GB a matrix" ;;
        esac
        run $integ rd1d $n klu
        run $integ rd1d $n band   # bandwidths 2, 2; IDA: 'unsupported'
    done
done

# 2-D: 2·N² unknowns for N = 7, 22, 71, 224 (about 1e2, 1e3, 1e4, 1e5).
for integ in radau5 ddassl ddassl-p2 ida; do
    for m in 7 22 71 224; do
        n=$((2 * m * m))
        case $integ:$m in
            *:7|*:22)         run $integ rd2d $m dense ;;
            radau5:71)        run $integ rd2d $m dense 1 ;;
            ddassl:71)        run $integ rd2d $m dense 2 ;;
            ida:71)           skip $integ rd2d $n dense "$DENSE_IDA" ;;
            *:224)            [ $integ = ddassl-p2 ] || skip $integ rd2d $n dense "80 GB a matrix" ;;
        esac
        case $integ:$m in
            ddassl-p2:224)    ;;                              # same first step as ddassl
            *:224)            run $integ rd2d $m klu 1 ;;     # KLU fill-in: 10-70 s a step
            *)                run $integ rd2d $m klu ;;
        esac
    done
done

echo
echo "time per step growth between successive sizes (KLU, runs that reached t_end): p in t ~ n^p"
for integ in radau5 ddassl ddassl-p2 ida; do
    for p in rd1d rd2d; do
        awk -v i=$integ -v p=$p '$1 == i && $2 == p && $4 == "klu" && $5 == "done" {
            if (n0 > 0) printf "%-7s %s  n %d -> %d: p = %.2f\n", i, p, n0, $3, log($14/t0)/log($3/n0)
            n0 = $3; t0 = $14 }' "$RESULTS"
    done
done
echo
echo "KLU speed-up over dense in time per step at equal size:"
awk '$5 == "done" || $5 == "capped" { key = $1" "$2" "$3
         if ($4 == "dense") d[key] = $14; else if ($4 == "klu") k[key] = $14 }
     END { for (key in d) if (key in k && k[key] > 0) printf "%s: %.1fx\n", key, d[key]/k[key] }' \
    "$RESULTS" | sort -k1,1 -k2,2 -k3,3n
echo
echo "CPU time relative to RADAU5 (same problem, size and linear solver, runs that reached t_end"
echo "and took RADAU5 at least 0.01 s; below that the ratios are timer noise):"
awk '$5 == "done" { key = $2" "$3" "$4; cpu[$1" "key] = $12; keys[key] = 1 }
     END { for (key in keys) if (("radau5 " key) in cpu && cpu["radau5 " key] >= 0.01) {
               line = key ":"
               split("ddassl ddassl-p2 ida", ii, " ")
               for (j = 1; j <= 3; j++) if ((ii[j] " " key) in cpu)
                   line = line sprintf("  %s %.2f", ii[j], cpu[ii[j] " " key] / cpu["radau5 " key])
               print line } }' "$RESULTS" | sort -k1,1 -k2,2n -k3,3
echo
echo "sparse LU of A = M - J: KLU (AMD, ND) and MUMPS (its automatic ordering) on the node"
echo "graph of a 3-D hex8 block (20x20x20 nodes, n = 24000), a slender one (6x6x200) and the"
echo "Brusselator; first per matrix its size, nnz(A), KLU's predicted fill and the choice of"
echo "linear_solver = 'auto'; times best of 3 in seconds (KLU at minutes a factorisation: once)"
echo "mesh n solver ordering analyse factor refactor solve nnz(L+U) nnz(L+U)/nnz(A)"
for m in "hex 20 20 20" "hex 6 6 200" "hex 3 3 192" "hex 8 8 8" "rd2d 71" "rd1d 10000"; do
    OPENBLAS_NUM_THREADS=1 "$BIN" sparse_lu $m 2>>"$ERRORS" | tee -a "$OUT/sparse_lu.txt"
done
if [ -s "$ERRORS" ]; then
    echo
    echo "messages of failed runs: $ERRORS"
fi
