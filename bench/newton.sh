#!/usr/bin/env bash
# `make bench` (part): the condensed Newton systems (docs/theory.md §3.7)
# against the full first-order iteration matrices, side by side in one run
# (release build, one BLAS thread). Prints figures, asserts nothing
# (docs/benchmarks.md and docs/linear_algebra.md have a measured copy).
#   1. the Newton matrices themselves (flexmbs-bench-newton): order, nonzeros,
#      fill and the time of a real and a complex factorisation and solve, per
#      path and LU, and what linear_solver = 'auto' picks on each path;
#   2. the 64 x 8 x 8 clamped cantilever (bench/scenes/cantilever_64x8x8.nml,
#      15 552 coordinates), RADAU5, DDASSL and IDA at 1e-5 over 0.2 s;
#   3. inputs/five_body_fine.nml over 1 s at 1e-6, the same three;
#      (2 and 3: one row per path and LU, KLU and MUMPS; then each path with
#      its own 'auto' and their ratio: goals 4 (2) and 2.5 (3) for RADAU5,
#      2 (2) and 1.5 (3) for DDASSL and IDA. IDA's full path with KLU is
#      SUNDIALS' own KLU, with MUMPS ours behind its SUNLinearSolver;)
#   4. 3-D refinement of the five-body coupler (RADAU5, 2x4x2 .. 8x32x8, 0.02 s):
#      CPU per step of both paths and their fitted exponents (goal: the
#      condensed path 8 x cheaper per step at 8x32x8; 'auto' best of 3);
#   5. MEXAX on the five-body mechanism at 1e-6 (coarse 1 s, fine 0.2 s)
#      against DDASSL: CPU per function evaluation against DDASSL's CPU per
#      residual (goal: at most 3 x), and the total against DDASSL's beside
#      the paper's 2.9-5 x;
#   6. a mechanism with 16 335 FE coordinates (bench/scenes/
#      five_body_coupler_10x44x10.nml), RADAU5 over 0.01 s, condensed;
#   7. where the fine five-body run's time goes now (perf, when installed;
#      the scene's 1 s, the whole process).
# BENCH_NEWTON_SECTIONS="1 4" runs those sections only.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
MATRICES=$($FPM run --profile release --example flexmbs-bench-newton --runner echo \
    2>/dev/null | tail -1)
[ -x "$BIN" ] && [ -x "$MATRICES" ] ||
    { echo "bench/newton.sh: could not build flexmbs and flexmbs-bench-newton" >&2; exit 1; }
OUT=build/bench/newton
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1
TIME=$(command -v /usr/bin/time || true)
SECTIONS=" ${BENCH_NEWTON_SECTIONS:-1 2 3 4 5 6 7} "
. bench/lib.sh
LARGE=bench/scenes/five_body_coupler_10x44x10.nml
bash bench/scenes/meshes.sh || exit 1

want() { [[ "$SECTIONS" == *" $1 "* ]]; }

# CPU per step of a run's "CPU NST ..." ("-" when it failed)
per_step() {
    awk -v c="${1%% *}" -v n="$(echo $1 | cut -d' ' -f2)" \
        'BEGIN { if (n > 0 && c > 0) printf "%.4f", c / n; else print "-" }'
}

# the LU 'auto' picks on each path of SCENE (from flexmbs-bench-newton's rows),
# as "full_lu condensed_lu" (klu | mumps)
declare -A AUTO
auto_picks() {  # SCENE LABEL
    local log="$OUT/matrices_$2.txt"
    [ -s "$log" ] || "$MATRICES" "$1" > "$log" 2>&1
    local full cond
    full=$(grep -E '^newton +full +auto ' "$log" | tail -1 | awk '{ print $4 }')
    cond=$(grep -E '^newton +condensed +auto ' "$log" | tail -1 | awk '{ print $5 }')
    AUTO[$2]="$full $cond"
}

if want 1; then
    echo "== 1. the Newton matrices at t0 (c = gamma/h, h = 1e-3; best of 3, CPU seconds)"
    for s in inputs/five_body.nml inputs/five_body_fine.nml bench/scenes/cantilever_64x8x8.nml \
             "$LARGE"; do
        label=$(basename "$s" .nml)
        "$MATRICES" "$s" > "$OUT/matrices_$label.txt" 2>&1
        sed -n '1,2p' "$OUT/matrices_$label.txt" | sed 's/^newton /  /'
        grep -E '^newton +(full|condensed)[ :]' "$OUT/matrices_$label.txt" | sed 's/^newton /  /'
        auto_picks "$s" "$label"
        echo "  'auto' picks: full ${AUTO[$label]% *}, condensed ${AUTO[$label]#* }"
    done
fi

# compare LABEL SCENE SEDEXPR SOLVERS: one row per solver, path and LU, then
# each path with its own 'auto' and the ratio full / condensed
compare() {
    local label=$1 scene=$2 edits=$3 solvers=$4 solver path ls r cpu
    auto_picks "$scene" "$label"
    echo "  solver  path       LU      CPU[s]    NST    NFE  CPU/step[s]"
    for solver in $solvers; do
        declare -A CPU=()
        for path in full condensed; do
            for ls in klu mumps; do
                f="$OUT/${label}_${solver}_${path}_$ls.nml"
                variant "$f" "$scene" "$solver" "$ls" "$edits" "$path"
                r=$(run "$f")
                cpu=${r%% *}
                CPU[$path$ls]=$cpu
                printf "  %-7s %-10s %-6s %8s %6s %6s %12s\n" "$solver" "$path" "$ls" "$cpu" \
                    "$(echo $r | cut -d' ' -f2)" "$(echo $r | cut -d' ' -f4)" \
                    "$(ratio "$cpu" "$(echo $r | cut -d' ' -f2)")"
            done
        done
        local fa=${AUTO[$label]% *} ca=${AUTO[$label]#* }
        [ "$solver" = ida ] && fa=klu   # IDA's full path: SUNDIALS' KLU
        echo "  $solver with 'auto': full ($fa) ${CPU[full$fa]} s, condensed ($ca)" \
             "${CPU[condensed$ca]} s: full / condensed = $(ratio "${CPU[full$fa]}" \
             "${CPU[condensed$ca]}")"
    done
}

if want 2; then
    echo
    echo "== 2. clamped cantilever 64 x 8 x 8 hex8 (15 552 coordinates), TOL 1e-5, 0.2 s"
    echo "     (goal: full / condensed >= 4 for RADAU5, >= 2 for DDASSL and IDA)"
    compare cantilever_64x8x8 bench/scenes/cantilever_64x8x8.nml "" "radau5 ddassl ida"
fi

if want 3; then
    echo
    echo "== 3. inputs/five_body_fine.nml (2268 FE coordinates), GGL, TOL 1e-6, 1 s"
    echo "     (goal: full / condensed >= 2.5 for RADAU5, >= 1.5 for DDASSL and IDA)"
    compare five_body_fine inputs/five_body_fine.nml "" "radau5 ddassl ida"
fi

if want 4; then
    echo
    echo "== 4. 3-D refinement of the coupler (RADAU5 + GGL, TOL 1e-6, 0.02 s; n_output = 2: the"
    echo "     steps' cost, not that of 101 records, whose reactions cost both paths alike)"
    echo "  divisions      n_FE  path       LU     CPU/step[s]   (* = 'auto' picks it: best of 3 runs;"
    echo "                                                         the other LU: one run)"
    : > "$OUT/refine_full.txt"
    : > "$OUT/refine_condensed.txt"
    for d in "2, 4, 2" "3, 6, 3" "4, 8, 4" "6, 12, 6" "8, 16, 8" "8, 32, 8"; do
        set -- ${d//,/}
        nfe=$(( 3 * ($1 + 1) * ($2 + 1) * ($3 + 1) ))
        declare -A PER=([fullklu]=- [fullmumps]=- [condensedklu]=- [condensedmumps]=-)
        for path in full condensed; do
            # 'auto' first: the statistics name the LU it took; the other LU after
            f="$OUT/refine_$1x$2x$3_${path}_auto.nml"
            variant "$f" inputs/five_body.nml radau5 auto \
                "s/t_end   = 1.0/t_end = 0.02/; s/divisions = 2, 4, 2/divisions = $d/; s/n_output = 101/n_output = 2/" "$path"
            r=$(best_cpu "$f" 3)
            picked=$(echo $r | cut -d' ' -f5)
            [ "$picked" = mumps ] || picked=klu   # a failed run names none
            PER[$path$picked]=$(per_step "$r")
            other=$([ "$picked" = klu ] && echo mumps || echo klu)
            f="$OUT/refine_$1x$2x$3_${path}_$other.nml"
            variant "$f" inputs/five_body.nml radau5 "$other" \
                "s/t_end   = 1.0/t_end = 0.02/; s/divisions = 2, 4, 2/divisions = $d/; s/n_output = 101/n_output = 2/" "$path"
            PER[$path$other]=$(per_step "$(run "$f")")
            for ls in klu mumps; do
                printf "  %-12s %6d  %-10s %-6s %11s %s\n" "${d//, /x}" "$nfe" "$path" "$ls" \
                    "${PER[$path$ls]}" "$([ "$ls" = "$picked" ] && echo '*')"
            done
            [ "${PER[$path$picked]}" != "-" ] && echo "$nfe ${PER[$path$picked]}" >> "$OUT/refine_$path.txt"
            PER[${path}auto]=${PER[$path$picked]}
        done
        echo "  ${d//, /x} with 'auto': full / condensed = $(ratio "${PER[fullauto]}" "${PER[condensedauto]}")"
    done
    echo "  fitted exponents of CPU/step ('auto') against n_FE: full $(slope < "$OUT/refine_full.txt")," \
         "condensed $(slope < "$OUT/refine_condensed.txt")"
    # the per-step cost without the set-up both paths pay once (patterns,
    # analyses, the first factorisations): the difference of a 0.1 s and a
    # 0.02 s run at 8x32x8 (best of 3 each)
    row=""
    for path in full condensed; do
        cpu=""; nst=""
        for te in 0.02 0.1; do
            f="$OUT/marginal_${path}_$te.nml"
            variant "$f" inputs/five_body.nml radau5 auto \
                "s/t_end   = 1.0/t_end = $te/; s/divisions = 2, 4, 2/divisions = 8, 32, 8/; s/n_output = 101/n_output = 2/" "$path"
            r=$(best_cpu "$f" 3)
            cpu="$cpu ${r%% *}"; nst="$nst $(echo $r | cut -d' ' -f2)"
        done
        set -- $cpu $nst
        per=$(awk -v c1="$1" -v c2="$2" -v n1="$3" -v n2="$4" \
            'BEGIN { if (n2 > n1) printf "%.4f", (c2 - c1) / (n2 - n1); else print "-" }')
        echo "  8x32x8 $path ('auto'): 0.02 s in $3 steps, 0.1 s in $4 steps: $per s per further step"
        row="$row $per"
    done
    set -- $row
    echo "  per further step at 8x32x8: full / condensed = $(ratio "$1" "$2") (goal >= 8)"
fi

if want 5; then
    echo
    echo "== 5. MEXAX against DDASSL on the five-body mechanism (GGL for DDASSL, TOL 1e-6)"
    echo "  scene   t_end  solver  CPU[s]  NST  NFE  CPU/NFE[ms]"
    for c in "coarse:inputs/five_body.nml:1.0" "fine:inputs/five_body_fine.nml:0.2"; do
        label=${c%%:*}; rest=${c#*:}; scene=${rest%%:*}; tend=${rest#*:}
        declare -A PER=() TOT=()
        for solver in ddassl mexax; do
            f="$OUT/mexax_${label}_$solver.nml"
            variant "$f" "$scene" "$solver" auto "s/t_end   = 1.0 /t_end = $tend /"
            r=$(run "$f")
            cpu=${r%% *}; nst=$(echo $r | cut -d' ' -f2); nfe=$(echo $r | cut -d' ' -f4)
            PER[$solver]=$(awk -v c="$cpu" -v n="$nfe" 'BEGIN { if (n > 0) printf "%.3f", 1000 * c / n; else print "-" }')
            TOT[$solver]=$cpu
            printf "  %-7s %5s  %-7s %7s %5s %6s %10s\n" "$label" "$tend" "$solver" "$cpu" \
                "$nst" "$nfe" "${PER[$solver]}"
        done
        echo "  $label: MEXAX CPU/NFE / DDASSL CPU/NFE = $(ratio "${PER[mexax]}" "${PER[ddassl]}")" \
             "(goal <= 3); total MEXAX / DDASSL = $(ratio "${TOT[mexax]}" "${TOT[ddassl]}")" \
             "(the paper: 2.9-5)"
    done
fi

if want 6; then
    echo
    echo "== 6. the five-body mechanism with its coupler at 10 x 44 x 10 hex8 (16 335 FE"
    echo "     coordinates), RADAU5 + GGL, TOL 1e-6, 0.01 s, condensed ('auto')"
    f="$OUT/large.nml"
    variant "$f" "$LARGE" radau5 auto "s/t_end   = 0.2 /t_end = 0.01 /"
    r=$(run "$f")
    echo "  CPU ${r%% *} s, NST $(echo $r | cut -d' ' -f2), CPU/step" \
         "$(ratio "${r%% *}" "$(echo $r | cut -d' ' -f2)") s, peak $(echo $r | cut -d' ' -f3) KiB"
fi

if want 7; then
    echo
    echo "== 7. where the fine five-body run goes (RADAU5 + GGL, TOL 1e-6, its 1 s, condensed;"
    echo "     the whole process, set-up and outputs included)"
    if command -v perf >/dev/null 2>&1; then
        f="$OUT/fine_profile.nml"
        variant "$f" inputs/five_body_fine.nml radau5 auto ""
        # each sample goes by its call stack: a memset or memcpy inside MUMPS
        # is linear algebra, the same call in the Jacobian's assembly is not
        in_scene_folder "$f" perf record -q --call-graph dwarf,16384 -F 200 \
            -o "$(realpath "$OUT")/perf.data" "$(realpath "$BIN")" run "$(basename "$f")" \
            --quiet >/dev/null 2>&1
        perf script -i "$OUT/perf.data" 2>/dev/null | awk -v rest="$OUT/profile_rest.txt" '
            BEGIN { RS = ""; FS = "\n"
                    la = "klu|mumps|amd_|colamd|btf|gemm|trsm|gemv|scotch|SCOTCH|pord|condensed_kernels|sub_block|saddle|sparse_lu|factor_kkt|solve_kkt|liblapack|libopenblas|libblas"
                    fe = "element_forces|neo_hooke|hexahedron|fe_tensor|element_contribution|flexible_body_MOD_assemble|nodal_gradient|deformation_gradient|stress_at|inverse3"
                    outer = "runner|plan_integrate|default_integrate|radau5_integrate|MAIN|run_scene|attempt_block|multi_output|sink_output|newton_iteration" }
            { n++; kind = ""
              for (i = 2; i <= NF; i++) if ($i ~ la) { kind = "la"; break }
              if (kind == "") for (i = 2; i <= NF; i++) if ($i ~ fe) { kind = "fe"; break }
              if (kind != "") { count[kind]++; next }
              count["rest"]++; path = ""; depth = 0
              # the two outermost of our own procedures below the driver loop
              for (i = NF; i >= 2; i--) {
                  name = $i; sub(/^[ \t]*[0-9a-f]+ /, "", name); sub(/\+0x.*/, "", name)
                  sub(/ \(.*/, "", name)
                  if (name ~ /flexmbs_/ && name !~ outer) {
                      sub(/^__flexmbs_/, "", name); path = path " > " name
                      if (++depth == 2) break } }
              where[path == "" ? " (outside our code)" : path]++ }
            END { if (n == 0) { print "  perf recorded no samples"; exit }
                  printf "  %d samples: element kernels %.1f %%, linear algebra (S, factor and solve) %.1f %%, the rest %.1f %% (goal: <= 10)\n", n, 100 * count["fe"] / n, 100 * count["la"] / n, 100 * count["rest"] / n
                  print "    the rest by where it is spent, above 0.3 %:"
                  printf "" > rest
                  for (w in where) if (where[w] / n > 0.003)
                      printf "      %6.2f%%%s\n", 100 * where[w] / n, w > rest }'
        sort -rn "$OUT/profile_rest.txt"
    else
        echo "  skipped: perf is not installed"
    fi
fi
