#!/usr/bin/env bash
# Memory check of the debug build under valgrind's memcheck: the root test
# suites of the numerical core, then `flexmbs run` on every scene of inputs/
# cut to a few steps. An item fails on any invalid read or write, use of an
# uninitialised value, definite leak (library-internal ones are suppressed
# by test/valgrind.supp), on a non-zero exit of the program itself, or on a
# failed test.
#
#   bash test/memory.sh [--origins] [ITEM ...]
#
# ITEM selects items by substring of their names (`suite/radau5/`,
# `scene/five_body`); none = all. --origins adds --track-origins=yes (where
# an uninitialised value came from; about twice slower). Each item's
# valgrind log is kept in build/memory/. One line per item, pass or FAIL,
# in the order the items finish, then `N passed, M failed` last; the exit
# status is non-zero on failures. MEMORY_JOBS items run at a time (default
# 2, one a core here: valgrind runs a program on one thread).
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root" || exit 1

# Suites by filter of the test driver (a substring of 'suite/test'): the
# trailing slash selects exactly the suite of that name, fe_ the fe_* suites
# (elements, bodies, statics, dynamics, meshes, det F, assembly).
# Longest first (under valgrind: mexax 6.5 min, fe_ 3, force_elements 2,
# set_markers 1.4, mumps 1), so that the workers end about together.
suites=(mexax/ fe_ force_elements/ set_markers/ mumps/ ida/ radau5/ mbs_system/ ddassl/ structured_saddle/ fe/ linalg/ modal_basis/ modal_frame/ modal_system/ restart/)
# A scene's end time is cut to t_start + this fraction of its span: two to
# five steps with their Jacobian, decompositions and output. The fine
# five-body mesh still takes about 90 s under valgrind, mostly its setup.
span_fraction=${MEMORY_SPAN_FRACTION:-1e-5}

origins=""
selected=()
for arg in "$@"; do
    case $arg in
        --origins) origins="--track-origins=yes" ;;
        *) selected+=("$arg") ;;
    esac
done

if ! command -v valgrind >/dev/null 2>&1; then
    echo "FAIL memory: valgrind is not installed (make check-memory installs it)"
    echo "0 passed, 1 failed"
    exit 1
fi

# the Makefile's flags: other flags would make fpm rebuild everything
export FPM_FFLAGS=${FPM_FFLAGS:-"-I/usr/include/hdf5/serial -I/usr/include/sundials/fortran -I/usr/include -I/usr/include/mumps_seq"}
export FPM_CFLAGS=${FPM_CFLAGS:-"-I/usr/include/suitesparse -fPIC"}
fpm=${FPM:-fpm}
# `fpm test` builds the library, the tests and the executable in one go;
# after a plain `fpm build` it leaves the tests linked against the old
# library ("up to date"), so a test binary older than the executable is
# removed and linked again.
locate() {
    tests=$($fpm test --profile debug --runner echo flexmbs-tests 2>/dev/null | tail -n 1)
    exe=$($fpm run --profile debug --runner echo flexmbs 2>/dev/null | tail -n 1)
}
if ! $fpm test --profile debug --runner true >/dev/null 2>&1; then
    echo "FAIL memory: the debug build failed ($fpm test --profile debug)"
    echo "0 passed, 1 failed"
    exit 1
fi
locate
if [ -x "$tests" ] && [ -x "$exe" ] && [ "$tests" -ot "$exe" ]; then
    rm -f "$tests"
    locate
fi
for f in "$tests" "$exe"; do
    if [ -z "$f" ] || [ ! -x "$f" ]; then
        echo "FAIL memory: no debug executable (got '$f')"
        echo "0 passed, 1 failed"
        exit 1
    fi
done

logs=$root/build/memory
mkdir -p "$logs"
work=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-memory.XXXXXX")
trap 'rm -rf "$work"' EXIT

# A finding exits with this code, which the programs never use themselves.
vg_code=99
# One BLAS thread: OpenBLAS's thread pool only slows valgrind down.
export OPENBLAS_NUM_THREADS=1
vg=(valgrind --tool=memcheck --error-exitcode=$vg_code --leak-check=full
    --show-leak-kinds=definite --errors-for-leak-kinds=definite
    --suppressions="$root/test/valgrind.supp" --num-callers=40 $origins)

# Each item writes its line to stdout and to a file of its own in $results;
# the tally reads the files once every item has ended.
results=$work/results
mkdir -p "$results"
jobs_max=${MEMORY_JOBS:-2}
items=0
pass() { echo "pass $1 ($2 s)"; }
fail() { echo "FAIL $1 ($2 s): $3"; }

# launch FUNCTION ARGS...: run the item in the background, at most
# jobs_max at a time, its line into its result file and to stdout
launch() {
    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do
        wait -n
    done
    items=$((items + 1))
    ( "$@" | tee "$results/$(printf '%03d' "$items")" ) &
}

wanted() {
    [ ${#selected[@]} -eq 0 ] && return 0
    local s
    for s in "${selected[@]}"; do
        [[ $1 == *"$s"* ]] && return 0
    done
    return 1
}

# What valgrind found, in one phrase, from its log.
findings() {
    local log=$1 errors leaked
    errors=$(sed -nE 's/.*ERROR SUMMARY: ([0-9]+) errors.*/\1/p' "$log" | tail -n 1)
    leaked=$(sed -nE 's/.*definitely lost: ([0-9,]+) bytes in ([0-9,]+) blocks.*/\1 bytes/p' \
        "$log" | tail -n 1)
    echo "${errors:-?} errors (definitely lost: ${leaked:-0 bytes}), see $log"
}

# check NAME OUTPUT CMD...: run CMD under valgrind from the repository's
# root (scenes name their mesh files from there), judge exit code and log.
check() {
    local name=$1 out=$2
    shift 2
    local log=$logs/${name//\//_}.log start rc seconds
    start=$SECONDS
    "${vg[@]}" --log-file="$log" "$@" >"$out" 2>&1
    rc=$?
    seconds=$((SECONDS - start))
    if [ "$rc" -eq "$vg_code" ]; then
        fail "$name" "$seconds" "$(findings "$log")"
    elif [ "$rc" -ne 0 ]; then
        fail "$name" "$seconds" "exit $rc; $(tail -n 3 "$out" | tr '\n' ' ')"
    else
        pass "$name" "$seconds"
        return 0
    fi
    return 1
}

# suite FILTER: one test suite of the debug build under valgrind
suite() {
    local filter=$1 name=suite/$1 out line
    out=$logs/${name//\//_}.out
    line=$(check "$name" "$out" "$tests" "$filter")
    # a filter that selects nothing would pass silently
    if [ "${line%% *}" = pass ] && ! grep -qE '^[1-9][0-9]* passed, 0 failed$' "$out"; then
        line=$(fail "$name" 0 "no test ran: $(tail -n 1 "$out")")
    fi
    echo "$line"
}

# cut SCENE COPY: the scene with its end time cut, three output times, its
# trajectory in the work folder, and for multibody and flexible-body scenes
# a ParaView collection too (its writer is checked as well).
cut() {
    local scene=$1 copy=$2 base vtk=""
    base=$(basename "$scene" .nml)
    # (a chain alone has no bodies to draw; it may still give &multibody)
    if grep -qiE '^[[:space:]]*&(multibody|flexible_body)' "$scene" &&
        ! grep -qiE "problem[[:space:]]*=[[:space:]]*'rigid_chain'" "$scene"; then
        vtk="    vtk = '$work/$base'"
    fi
    # a mesh file is relative to the scene's folder: the copy names it absolutely
    awk -v fraction="$span_fraction" -v file="$work/$base.h5" -v vtk="$vtk" \
        -v folder="$(dirname "$scene")" '
        function value(line) {
            sub(/^[^=]*=[[:space:]]*/, "", line); sub(/[[:space:]!\/].*$/, "", line)
            gsub(/[dD]/, "e", line)
            return line + 0
        }
        tolower($0) ~ /^[[:space:]]*t_start[[:space:]]*=/ { t_start = value($0) }
        tolower($0) ~ /^[[:space:]]*t_end[[:space:]]*=/ {
            lines[++n] = "T_END " value($0); has_end = 1; next
        }
        tolower($0) ~ /^[[:space:]]*(n_output|file|every_step|vtk)[[:space:]]*=/ { next }
        tolower($0) ~ /mesh_file[[:space:]]*=[[:space:]]*'\''[^\/]/ {
            sub(/mesh_file[[:space:]]*=[[:space:]]*'\''/, "mesh_file = '\''" folder "/")
        }
        { lines[++n] = $0 }
        tolower($0) ~ /^[[:space:]]*&output/ { output(); has_output = 1 }
        function output() {
            lines[++n] = "    n_output = 3"
            lines[++n] = "    file = '\''" file "'\''"
            if (vtk != "") lines[++n] = vtk
        }
        END {
            if (!has_output) { lines[++n] = "&output"; output(); lines[++n] = "/" }
            for (i = 1; i <= n; i++) {
                if (lines[i] ~ /^T_END /) {
                    t_end = substr(lines[i], 7) + 0
                    printf "    t_end = %.17g\n", t_start + fraction * (t_end - t_start)
                } else print lines[i]
            }
            if (!has_end) exit 1
        }' "$scene" >"$copy"
}

# scene SCENE: flexmbs run on the cut copy of SCENE under valgrind
scene() {
    local scene=$1 base copy
    base=$(basename "$scene" .nml)
    copy=$work/$base.nml
    if ! cut "$scene" "$copy"; then
        fail "scene/$base" 0 "no t_end to cut in $scene"
        return
    fi
    check "scene/$base" "$logs/$base.out" "$exe" run "$copy" --quiet
}

# launch_scene SCENE: a scene of inputs/ when selected (studies are not
# scenes; a study here would be refused)
launch_scene() {
    wanted "scene/$(basename "$1" .nml)" || return 0
    grep -qiE '^[[:space:]]*&study' "$1" && return 0
    launch scene "$1"
}

# the fine five-body scenes (over 2 minutes each) right after the two
# longest suites, the other scenes (seconds) last
for filter in "${suites[@]:0:2}"; do
    wanted "suite/$filter" && launch suite "$filter"
done
for scene in "$root"/inputs/*fine*.nml; do
    launch_scene "$scene"
done
for filter in "${suites[@]:2}"; do
    wanted "suite/$filter" && launch suite "$filter"
done
for scene in "$root"/inputs/*.nml; do
    [[ $scene == *fine* ]] || launch_scene "$scene"
done
wait

passed=$(cat "$results"/* 2>/dev/null | grep -c '^pass ')
failed=$(cat "$results"/* 2>/dev/null | grep -c '^FAIL ')
if [ $((passed + failed)) -ne "$items" ]; then
    echo "FAIL memory: $items items launched, $((passed + failed)) reported"
    failed=$((failed + items - passed - failed))
fi
echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
