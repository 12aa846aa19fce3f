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
# then `N passed, M failed` last; the exit status is non-zero on failures.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root" || exit 1

# Suites by filter of the test driver (a substring of 'suite/test'): the
# trailing slash selects exactly the suite of that name, fe_ the fe_* suites
# (elements, bodies, statics, dynamics, meshes, det F, assembly).
suites=(linalg/ radau5/ ddassl/ ida/ mexax/ fe/ fe_ mbs_system/ force_elements/ set_markers/ structured_saddle/)
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

passed=0
failed=0
pass() { passed=$((passed + 1)); echo "pass $1 ($2 s)"; }
fail() { failed=$((failed + 1)); echo "FAIL $1 ($2 s): $3"; }

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

for filter in "${suites[@]}"; do
    name=suite/$filter
    wanted "$name" || continue
    out=$logs/${name//\//_}.out
    if check "$name" "$out" "$tests" "$filter"; then
        # a filter that selects nothing would pass silently
        if ! grep -qE '^[1-9][0-9]* passed, 0 failed$' "$out"; then
            passed=$((passed - 1))
            fail "$name" 0 "no test ran: $(tail -n 1 "$out")"
        fi
    fi
done

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

for scene in "$root"/inputs/*.nml; do
    base=$(basename "$scene" .nml)
    name=scene/$base
    wanted "$name" || continue
    # studies (inputs/paper/) are not scenes; a study here would be refused
    grep -qiE '^[[:space:]]*&study' "$scene" && continue
    copy=$work/$base.nml
    if ! cut "$scene" "$copy"; then
        fail "$name" 0 "no t_end to cut in $scene"
        continue
    fi
    check "$name" "$logs/$base.out" "$exe" run "$copy" --quiet
done

echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
