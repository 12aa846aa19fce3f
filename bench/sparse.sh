#!/usr/bin/env bash
# `make bench` (part): the sparse path on flexible multibody scenes. Prints
# figures, asserts nothing (docs/linear_algebra.md has a measured copy).
#   1. the default five-body run (RADAU5 + GGL, TOL 1e-6, 1 s): dense LU
#      against the sparse path, side by side, best CPU of 3;
#   2. a slender soft arm on a rigid link (rigid_flexible_pendulum.nml,
#      2 x 2 cross-section, 20 .. 320 elements along it, 0.02 s) with RADAU5,
#      DDASSL and IDA: CPU per step and peak memory against n, exponents;
#   3. KLU against MUMPS on the formulations' full iteration matrices
#      (newton_system = 'full': the figures behind linear_solver = 'auto''s
#      choice between them there).
# The condensed Newton systems, the refinement of the coupler and the
# profile of the fine five-body run are bench/newton.sh's.
# One BLAS thread throughout (ratios on a shared 2-core machine).
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
[ -x "$BIN" ] || { echo "bench/sparse.sh: could not build flexmbs" >&2; exit 1; }
OUT=build/bench/sparse
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1
TIME=$(command -v /usr/bin/time || true)

. bench/lib.sh

echo "== 1. default five-body run (RADAU5 + GGL, TOL 1e-6, t_end 1 s), best CPU of 3"
for ls in dense auto; do
    variant "$OUT/five_body_$ls.nml" inputs/five_body.nml radau5 $ls ""
    r=$(best_cpu "$OUT/five_body_$ls.nml" 3)
    echo "  linear_solver = '$ls': CPU ${r%% *} s, NST $(echo $r | cut -d' ' -f2)"
    eval "cpu_$ls=${r%% *}"
done
awk -v d="$cpu_dense" -v s="$cpu_auto" 'BEGIN { if (s > 0) printf "  sparse is %.1f x faster in CPU (goal: >= 5)\n", d / s }'

echo
echo "== 2. slender soft arm on a rigid link (2 x 2 cross-section, t_end 0.02 s, 'auto')"
for solver in radau5 ddassl ida; do
    : > "$OUT/arm_$solver.txt"; : > "$OUT/arm_mem_$solver.txt"
    echo "  $solver: elements  n_FE  CPU/step[s]  peak[MiB]"
    for ne in 20 40 80 160 320; do
        f="$OUT/arm_${solver}_$ne.nml"
        variant "$f" inputs/rigid_flexible_pendulum.nml $solver auto "s/t_end   = 0.5/t_end = 0.02/; s/divisions = 4, 1, 1/divisions = $ne, 2, 2/"
        nfe=$(( 27 * (ne + 1) ))
        r=$(best_cpu "$f" 2)
        cpu=${r%% *}; nst=$(echo $r | cut -d' ' -f2); peak=$(echo $r | cut -d' ' -f3)
        per=$(awk -v c="$cpu" -v n="$nst" 'BEGIN { if (n > 0) printf "%.5f", c / n; else print "-" }')
        mib=$(awk -v k="$peak" 'BEGIN { if (k ~ /^[0-9]+$/) printf "%.0f", k / 1024; else print "-" }')
        printf "    %8d %6d %12s %10s\n" "$ne" "$nfe" "$per" "$mib"
        [ "$per" != "-" ] && echo "$nfe $per" >> "$OUT/arm_$solver.txt"
        [ "$mib" != "-" ] && echo "$nfe $mib" >> "$OUT/arm_mem_$solver.txt"
    done
    echo "    exponents against n_FE: CPU/step $(slope < "$OUT/arm_$solver.txt") (goal: <= 1.2)," \
         "peak memory $(slope < "$OUT/arm_mem_$solver.txt") (includes the fixed start-up memory)"
done

echo
echo "== 3. KLU against MUMPS on the formulations' full iteration matrices (RADAU5, CPU)"
for c in "coupler 4x8x4:five_body:s/divisions = 2, 4, 2/divisions = 4, 8, 4/; s/t_end   = 1.0/t_end = 0.02/" \
         "coupler 6x12x6:five_body:s/divisions = 2, 4, 2/divisions = 6, 12, 6/; s/t_end   = 1.0/t_end = 0.02/" \
         "cube 12x12x12:flexible_cantilever:s/divisions = 8, 1, 1/divisions = 12, 12, 12/; s/lengths   = 0.4, 0.05, 0.05/lengths = 0.4, 0.4, 0.4/; s/t_end   = 0.2/t_end = 0.005/"; do
    label=${c%%:*}; rest=${c#*:}; scene=${rest%%:*}; edits=${rest#*:}
    for ls in klu mumps; do
        variant "$OUT/lu_${ls}.nml" "inputs/$scene.nml" radau5 $ls "$edits" full
        r=$(run "$OUT/lu_${ls}.nml"); eval "lu_$ls=${r%% *}"
    done
    awk -v l="$label" -v k="$lu_klu" -v m="$lu_mumps" 'BEGIN {
        printf "  %-15s KLU %8s s  MUMPS %8s s  KLU/MUMPS %.2f\n", l, k, m, (m > 0 ? k / m : 0) }'
done
