#!/usr/bin/env bash
# Strong scaling of one scene over MPI ranks (docs/large_scenes.md): the
# soft cantilever of inputs/flexible_cantilever.nml on box meshes of
# 16x2x2, 32x4x4 and 64x8x8 hex8 elements (459, 2 025 and 15 795 FE
# coordinates), RADAU5 at rtol = atol = 1e-6 over the first T_END seconds
# (a few dozen factorisations), linear_solver = 'mumps', by the sequential
# release build and by the MPI build (make build-mpi) on 1 and 2 ranks.
# Per run, the best of REPS: the wall time, and from --verbose's
# factorisation line the seconds per real factorisation, the factor
# entries and the memory of the process that used most. One BLAS thread
# per process. Never asserts.
#
#   bash bench/mpi_scaling.sh [MESHES ...]     (default: 16x2x2 32x4x4 64x8x8)
#
# Writes build/bench/mpi_scaling.txt.
set -u
cd "$(dirname "$0")/.."
FPM=${FPM:-fpm}
SEQ=$($FPM run --profile release flexmbs --runner echo 2>/dev/null | tail -1)
MPI=$(readlink -f build/bin/flexmbs-mpi 2>/dev/null)
[ -x "$SEQ" ] || { echo "bench/mpi_scaling.sh: no sequential release build (make build)" >&2; exit 1; }
[ -x "$MPI" ] || { echo "bench/mpi_scaling.sh: no MPI build (make build-mpi)" >&2; exit 1; }
SEQ=$(realpath "$SEQ")
OUT=build/bench
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
REPS=${REPS:-2}
T_END=${T_END:-0.002}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
meshes=${*:-16x2x2 32x4x4 64x8x8}

# one run: wall ms, then the factorisation line's numbers (s per real
# factorisation, factor entries, MB of the process that used most)
measure() {
    local start out
    start=$(date +%s%N)
    out=$("$@" 2>&1) || { echo "failed: $(head -c 300 <<<"$out")" >&2; echo "- - - -"; return; }
    echo "$((($(date +%s%N) - start) / 1000000)) $(sed -n 's/^factorisations: real: MUMPS on [0-9]* process[es]*: [0-9]* factorisations of \([0-9]*\) factor entries, \([^ ]*\) s each (wall), memory \([0-9]*\) MB on the process.*/\2 \1 \3/p' <<<"$out")"
}

{
    echo "# bench/mpi_scaling.sh, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc --all) cores, T_END = $T_END s, best of $REPS"
    printf '%-8s %7s %-12s %9s %12s %13s %8s\n' mesh coords run wall_s factor_s entries MB_most
} | tee "$OUT/mpi_scaling.txt"
for mesh in $meshes; do
    IFS=x read -r nx ny nz <<<"$mesh"
    sed -e "s/divisions = .*/divisions = $nx, $ny, $nz/" \
        -e "s/t_end   = [0-9.]*/t_end = $T_END/" \
        -e "s/^&solver/\&solver linear_solver = 'mumps',/" \
        -e "s/^&output/\&output file = 'none', progress = .false.,/" \
        inputs/flexible_cantilever.nml > "$work/c.nml"
    n=$(( 3 * (nx + 1) * (ny + 1) * (nz + 1) ))
    for run in sequential mpi-1 mpi-2; do
        best=""
        for ((r = 1; r <= REPS; r++)); do
            case $run in
            sequential) line=$(measure "$SEQ" run "$work/c.nml" --quiet --verbose) ;;
            mpi-1) line=$(measure mpirun -n 1 "$MPI" run "$work/c.nml" --quiet --verbose) ;;
            mpi-2) line=$(measure mpirun -n 2 "$MPI" run "$work/c.nml" --quiet --verbose) ;;
            esac
            if [ -z "$best" ] || [ "${line%% *}" -lt "${best%% *}" ] 2>/dev/null; then best=$line; fi
        done
        read -r ms fs entries mb <<<"$best"
        printf '%-8s %7s %-12s %9s %12s %13s %8s\n' "$mesh" "$n" "$run" \
            "$(awk -v m="$ms" 'BEGIN { printf "%.2f", m / 1000 }')" "$fs" "$entries" "$mb" \
            | tee -a "$OUT/mpi_scaling.txt"
    done
done
