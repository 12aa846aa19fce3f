#!/usr/bin/env bash
# `make bench` (part): the sparse path on flexible multibody scenes. Prints
# figures, asserts nothing (docs/linear_algebra.md has a measured copy).
#   1. the default five-body run (RADAU5 + GGL, TOL 1e-6, 1 s): dense LU
#      against the sparse path, side by side, best CPU of 3;
#   2. 3-D refinement of the five-body coupler (2x4x2 .. 8x32x8 hex8, 0.02 s):
#      CPU per step against the order n of the iteration matrix, fitted
#      exponent;
#   3. a slender soft arm on a rigid link (rigid_flexible_pendulum.nml,
#      2 x 2 cross-section, 20 .. 320 elements along it, 0.02 s) with RADAU5,
#      DDASSL and IDA: CPU per step and peak memory against n, exponents;
#   4. where the time of the fine five-body run goes (perf, when installed);
#   5. KLU against MUMPS on the formulations' iteration matrices (the
#      figures behind linear_solver = 'auto''s choice between them).
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

# scene FILE -> variant with solver settings and sed edits: variant OUT SRC SOLVER LS SEDEXPR
variant() {
    # a mesh file is relative to its scene's folder: the copy names it from there
    sed -e "s/^    name = 'radau5'/    name = '$3'\n    linear_solver = '$4'/" -e "$5" \
        -e "s#mesh_file = '\([^/']\)#mesh_file = '$PWD/$(dirname "$2")/\1#" "$2" > "$1"
    grep -q "linear_solver = '$4'" "$1" || sed -i "s/^&solver/\&solver\n    name = '$3'\n    linear_solver = '$4'/" "$1"
}

# run FILE -> "CPU NST PEAK_KB" (CPU from the statistics line)
run() {
    local line peak=-
    if [ -n "$TIME" ]; then
        line=$("$TIME" -f "PEAK %M" "$BIN" run "$1" --quiet 2>&1)
        peak=$(echo "$line" | sed -n 's/^PEAK //p')
    else
        line=$("$BIN" run "$1" --quiet 2>&1)
    fi
    local stats
    stats=$(echo "$line" | grep -E '^[a-z0-9]+: NST=' | tail -1)
    [ -n "$stats" ] || { echo "failed - -"; return; }
    echo "$(echo "$stats" | sed 's/.*CPU=\([0-9.]*\).*/\1/') \
$(echo "$stats" | sed 's/.*NST=\([0-9]*\).*/\1/') $peak"
}

best_cpu() {  # FILE REPS -> best "CPU NST PEAK"
    local best="" r
    for _ in $(seq "$2"); do
        r=$(run "$1")
        if [ -z "$best" ] || awk -v a="${r%% *}" -v b="${best%% *}" 'BEGIN{exit !(a<b)}'; then
            best=$r
        fi
    done
    echo "$best"
}

# least-squares slope of log(y) on log(x) from lines "x y"
slope() {
    awk '$2 > 0 { lx = log($1); ly = log($2); n++; sx += lx; sy += ly; sxx += lx*lx; sxy += lx*ly }
         END { if (n < 2) print "-"; else printf "%.2f", (n*sxy - sx*sy) / (n*sxx - sx*sx) }'
}

echo "== 1. default five-body run (RADAU5 + GGL, TOL 1e-6, t_end 1 s), best CPU of 3"
for ls in dense auto; do
    variant "$OUT/five_body_$ls.nml" inputs/five_body.nml radau5 $ls ""
    r=$(best_cpu "$OUT/five_body_$ls.nml" 3)
    echo "  linear_solver = '$ls': CPU ${r%% *} s, NST $(echo $r | cut -d' ' -f2)"
    eval "cpu_$ls=${r%% *}"
done
awk -v d="$cpu_dense" -v s="$cpu_auto" 'BEGIN { if (s > 0) printf "  sparse is %.1f x faster in CPU (goal: >= 5)\n", d / s }'

echo
echo "== 2. 3-D refinement of the coupler (RADAU5 + GGL, TOL 1e-6, t_end 0.02 s, 'auto')"
echo "  divisions      n_FE    CPU[s]  NST  CPU/step[s]"
: > "$OUT/refine.txt"
for d in "2, 4, 2" "3, 6, 3" "4, 8, 4" "6, 12, 6" "8, 16, 8" "8, 32, 8"; do
    set -- ${d//,/}
    nfe=$(( 3 * ($1 + 1) * ($2 + 1) * ($3 + 1) ))
    f="$OUT/refine_$1x$2x$3.nml"
    variant "$f" inputs/five_body.nml radau5 auto "s/t_end   = 1.0/t_end = 0.02/; s/divisions = 2, 4, 2/divisions = $d/"
    r=$(run "$f")
    cpu=${r%% *}; nst=$(echo $r | cut -d' ' -f2)
    per=$(awk -v c="$cpu" -v n="$nst" 'BEGIN { if (n > 0) printf "%.4f", c / n; else print "-" }')
    printf "  %-12s %6d %9s %4s %12s\n" "$1x$2x$3" "$nfe" "$cpu" "$nst" "$per"
    [ "$per" != "-" ] && echo "$nfe $per" >> "$OUT/refine.txt"
done
echo "  fitted exponent of CPU/step against n_FE: $(slope < "$OUT/refine.txt") (goal: <= 2)"

echo
echo "== 3. slender soft arm on a rigid link (2 x 2 cross-section, t_end 0.02 s, 'auto')"
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
echo "== 4. where the fine five-body run goes (RADAU5 + GGL, TOL 1e-6, t_end 0.05 s)"
if command -v perf >/dev/null 2>&1; then
    f="$OUT/fine_profile.nml"
    variant "$f" inputs/five_body_fine.nml radau5 auto "s/t_end   = 1.0/t_end = 0.05/"
    perf record -q -o "$OUT/perf.data" "$BIN" run "$f" --quiet >/dev/null 2>&1
    perf report -q -i "$OUT/perf.data" --no-children --sort dso,symbol 2>/dev/null | awk '
        /%/ { p = $1; sub("%", "", p); line = $0
              if (line ~ /element_forces|neo_hooke|hexahedron|fe_tensor|element_contribution|flexible_body_MOD_assemble|nodal_gradient|deformation_gradient|stress_at|inverse3/) fe += p
              else if (line ~ /klu|mumps|amd_|colamd|btf|gemm|trsm|libopenblas|libblas|liblapack|scotch|SCOTCH|pord|hypot/) lu += p
              else { other += p; if (p > 0.5) top = top sprintf("      %6.2f%% %s\n", p, $NF) } }
        END { printf "  element kernels %.1f %%, sparse LU (factor/solve) %.1f %%, the rest %.1f %% (goal: <= 10)\n", fe, lu, other
              printf "    the rest, entries above 0.5 %%:\n%s", top }'
else
    echo "  skipped: perf is not installed"
fi

echo
echo "== 5. KLU against MUMPS on the formulations' iteration matrices (RADAU5, CPU)"
for c in "coupler 4x8x4:five_body:s/divisions = 2, 4, 2/divisions = 4, 8, 4/; s/t_end   = 1.0/t_end = 0.02/" \
         "coupler 6x12x6:five_body:s/divisions = 2, 4, 2/divisions = 6, 12, 6/; s/t_end   = 1.0/t_end = 0.02/" \
         "cube 12x12x12:flexible_cantilever:s/divisions = 8, 1, 1/divisions = 12, 12, 12/; s/lengths   = 0.4, 0.05, 0.05/lengths = 0.4, 0.4, 0.4/; s/t_end   = 0.2/t_end = 0.005/"; do
    label=${c%%:*}; rest=${c#*:}; scene=${rest%%:*}; edits=${rest#*:}
    for ls in klu mumps; do
        variant "$OUT/lu_${ls}.nml" "inputs/$scene.nml" radau5 $ls "$edits"
        r=$(run "$OUT/lu_${ls}.nml"); eval "lu_$ls=${r%% *}"
    done
    awk -v l="$label" -v k="$lu_klu" -v m="$lu_mumps" 'BEGIN {
        printf "  %-15s KLU %8s s  MUMPS %8s s  KLU/MUMPS %.2f\n", l, k, m, (m > 0 ? k / m : 0) }'
done
