#!/usr/bin/env bash
# `make bench`, part: modal bodies (floating frame, Craig-Bampton) against
# nonlinear ones (docs/modal.md). Release build, one BLAS thread, RADAU5.
#   1. the five-body coupler, soft (the paper's material): nonlinear on the
#      coarse (2x4x2) and the fine (5x20x5) mesh, modal with k = 4, 8, 16, 32
#      on both, at rtol = atol = 1e-4, 1e-5, 1e-6; the error is the largest
#      distance over the records between the coupler's centre (the mean of
#      its mid-plane nodes, y = 0.2 m in the reference) and that of the fine
#      nonlinear run at 1e-8; the cost the whole process's CPU (the modal
#      basis included) and the solver's;
#   2. the same with a steel coupler (E = 2.1e11 Pa, rho = 7850 kg/m^3) over
#      0.3 s, the reference the fine nonlinear run at 1e-7;
#   3. the spin-up (bench/scenes/spin_up_modal.nml, the spin ramped towards
#      8 rad/s over 40 s, 29 s): the modal and the nonlinear beam of one mesh.
# Writes build/bench/modal/*.txt and, with matplotlib, the plots
# build/bench/modal/work_precision.png and spin_up.png (copy them to docs/
# as modal_work_precision.png and modal_spin_up.png when docs/modal.md's
# figures are updated). Never asserts. BENCH_MODAL_SECTIONS="1 3" runs those.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
BIN=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
[ -x "$BIN" ] || { echo "bench/modal.sh: could not build flexmbs" >&2; exit 1; }
BIN=$(realpath "$BIN")
OUT=build/bench/modal
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1
SECTIONS=" ${BENCH_MODAL_SECTIONS:-1 2 3} "
want() { [[ "$SECTIONS" == *" $1 "* ]]; }
ROOT=$PWD

# scene SRC OUT.nml MODEL K TOL T_END [steel]: SRC as OUT.nml (result OUT.h5)
scene() {
    local src=$1 out=$2 model=$3 k=$4 tol=$5 t_end=$6 steel=${7:-}
    local edits=(-e "s/^    t_end   = [0-9.]*/    t_end   = $t_end/"
                 -e "s/^    rtol = .*/    rtol = $tol/" -e "s/^    atol = .*/    atol = $tol/"
                 -e "s#mesh_file = '\\([^/']\\)#mesh_file = '$ROOT/inputs/\\1#")
    if [ "$model" = modal ]; then
        edits+=(-e "s#^\\(    \\(origin\\|mesh_file\\) .*\\)#\\1\\n    model = 'modal'\\n    modes = $k#")
    fi
    if [ -n "$steel" ]; then
        edits+=(-e "s/youngs_modulus = [0-9.e]*/youngs_modulus = 2.1e11/g"
                -e "s/density = [0-9.]*/density = 7850.0/g")
    fi
    sed "${edits[@]}" "$src" > "$out"
}

# run OUT.nml -> "process_cpu solver_cpu NST" (or "failed")
run() {
    local stats
    stats=$( { /usr/bin/time -f "PROCESS %U %S" "$BIN" run "$(basename "$1")" --quiet --force; } \
        2>&1 < /dev/null)
    local line
    line=$(echo "$stats" | grep -E '^[a-z0-9]+: NST=' | tail -1)
    [ -n "$line" ] || { echo "failed"; return; }
    echo "$(echo "$stats" | awk '/^PROCESS/ {printf "%.3f", $2 + $3}') \
$(echo "$line" | sed 's/.*CPU=\([0-9.]*\).*/\1/') $(echo "$line" | sed 's/.*NST=\([0-9]*\).*/\1/')"
}

# work_precision NAME T_END REF_TOL [steel]: section 1 or 2 into OUT/NAME.txt
work_precision() {
    local name=$1 t_end=$2 ref_tol=$3 steel=${4:-}
    local dir=$OUT/$name
    mkdir -p "$dir"
    (
        cd "$dir" || exit 1
        scene "$ROOT/inputs/five_body_fine.nml" ref.nml nonlinear 0 "$ref_tol" "$t_end" "$steel"
        echo "reference: fine nonlinear at $ref_tol: $(run ref.nml)"
        echo "# mesh model k tol process_cpu solver_cpu nst result"
        for mesh in coarse fine; do
            src=$ROOT/inputs/five_body.nml
            [ $mesh = fine ] && src=$ROOT/inputs/five_body_fine.nml
            for tol in 1.0e-4 1.0e-5 1.0e-6; do
                for k in 0 4 8 16 32; do
                    model=modal
                    [ $k = 0 ] && model=nonlinear
                    f=${mesh}_${model}_${k}_$tol
                    scene "$src" "$f.nml" $model $k $tol "$t_end" "$steel"
                    echo "$mesh $model $k $tol $(run "$f.nml") $f.h5"
                done
            done
        done
    ) | tee "$OUT/$name.txt"
}

PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3  # h5py, matplotlib: the system's
if want 1; then
    echo "== 1. five-body coupler, soft: work and precision (1 s)"
    work_precision soft 1.0 1.0e-8
fi
if want 2; then
    echo "== 2. five-body coupler, steel: work and precision (0.3 s)"
    work_precision steel 0.3 1.0e-7 steel
fi
if want 3; then
    echo "== 3. spin-up towards 8 rad/s over 40 s (29 s): modal and nonlinear beam"
    mkdir -p "$OUT/spin"
    (
        cd "$OUT/spin" || exit 1
        cp "$ROOT/bench/scenes/spin_up_modal.nml" modal.nml
        sed -e "s/    model     = 'modal'/    model     = 'nonlinear'/" -e "/    modes     = /d" \
            modal.nml > nonlinear.nml
        echo "modal: $(run modal.nml)"
        echo "nonlinear: $(run nonlinear.nml)"
    ) | tee "$OUT/spin.txt"
fi
"$PY" bench/modal_plot.py "$OUT" || echo "bench: no plots (h5py or matplotlib missing?)"
