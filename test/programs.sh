#!/usr/bin/env bash
# The example programs of examples/, built as a user builds them against
# an installed flexmbs (pkg-config's flags: flexmbs-legacy for classic_*.f90,
# the classic faces; flexmbs for the others) and run, each with an empty
# standard error: the pendulum through every solver (exits non-zero when an
# angle is off), the rigid-flexible system built through the API with every
# solver (energy and joints), the classic RADAU5 driver (van der Pol against
# its reference), a scene run from a program and the Python script that
# plots its result by name (h5py and matplotlib of the system's Python).
# Last, the rigid-flexible system linked against libflexmbs.so
# (flexmbs-shared) and run from the install.
#
#   bash test/programs.sh PREFIX
#
# PREFIX: an install of flexmbs with lib/pkgconfig (make test uses the
# debug install it makes for the classic drivers). `N passed, M failed` last.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
prefix=$1
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
work=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-programs.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$root" || exit 1
passed=0
failed=0
pass() { passed=$((passed + 1)); echo "pass programs/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL programs/$1: $2"; }

# run NAME PATTERN COMMAND...: passes when COMMAND exits 0 with nothing on
# standard error and its standard output has a line matching PATTERN.
run() {
    local name=$1 pattern=$2 out
    shift 2
    out=$("$@" 2>"$work/stderr")
    local rc=$?
    if [ "$rc" -ne 0 ]; then
        fail "$name" "exit $rc: $out $(cat "$work/stderr")"
    elif [ -s "$work/stderr" ]; then
        fail "$name" "standard error: $(cat "$work/stderr")"
    elif ! grep -qE "$pattern" <<<"$out"; then
        fail "$name" "no line matching '$pattern' in: $out"
    else
        pass "$name"
    fi
}

for pc in flexmbs flexmbs-legacy flexmbs-shared; do
    pkg-config --exists "$pc" || { fail "pkg-config-$pc" "no $pc.pc in $prefix/lib/pkgconfig"; }
done
for src in examples/*.f90; do
    name=$(basename "$src" .f90)
    case $name in
        classic_*) pc=flexmbs-legacy ;;
        *) pc=flexmbs ;;
    esac
    if out=$(gfortran -J "$work" -o "$work/$name" "$src" $(pkg-config --cflags --libs $pc) 2>&1)
    then
        pass "$name-builds"
    else
        fail "$name-builds" "$out"
    fi
done

run pendulum-every-solver '^   mexax: angle' "$work/pendulum"
for solver in radau5 ddassl ida mexax; do
    run "rigid-flexible-$solver" '^energy drift' "$work/rigid_flexible" $solver
done
run classic-radau5-van-der-pol '^IDID = 1,' "$work/classic_radau5"
run run-scene-from-a-program '^  link: at \(' \
    "$work/run_scene" inputs/rigid_flexible_pendulum.nml "$work/rigid_flexible.h5"
py=/usr/bin/python3
[ -x "$py" ] || py=python3
if out=$("$py" examples/plot_result.py "$work/rigid_flexible.h5" "$work/plot.png" 2>&1) &&
    [ -s "$work/plot.png" ]; then
    pass "plot-by-name"
else
    fail "plot-by-name" "$out"
fi
# quantities named as the file names them, with a component; a name the
# file lacks is refused, naming it
if out=$("$py" examples/plot_result.py "$work/rigid_flexible.h5" 'link/position/y' \
        'bar/von_mises' energy "$work/plot2.png" 2>&1) && [ -s "$work/plot2.png" ] &&
    ! bad=$("$py" examples/plot_result.py "$work/rigid_flexible.h5" 'link/nowhere' \
        "$work/plot3.png" 2>&1) && grep -q "no quantity 'link/nowhere'" <<<"$bad" &&
    [ ! -e "$work/plot3.png" ]; then
    pass "plot-quantities-by-name"
else
    fail "plot-quantities-by-name" "$out ${bad:-}"
fi

# The shared library: the program names libflexmbs.so (not the archive's
# objects) and finds it in the install through the rpath of flexmbs-shared.
if out=$(gfortran -J "$work" -o "$work/rigid_flexible_shared" examples/rigid_flexible.f90 \
        $(pkg-config --cflags --libs flexmbs-shared) 2>&1); then
    if readelf -d "$work/rigid_flexible_shared" | grep -q 'NEEDED.*\[libflexmbs\.so'; then
        run shared-library '^energy drift' "$work/rigid_flexible_shared"
    else
        fail shared-library "the program does not name libflexmbs.so: $(readelf -d \
            "$work/rigid_flexible_shared" | grep NEEDED)"
    fi
else
    fail shared-library "$out"
fi
# no executable stack (a trampoline of an internal procedure passed as an
# argument would need one, and glibc refuses to dlopen such a library)
stacks=$(for f in "$prefix"/lib/libflexmbs*.so; do
    readelf -lW "$f" | grep GNU_STACK | grep -q 'RWE' && echo "$f"; done)
if [ -z "$stacks" ]; then pass no-executable-stack; else
    fail no-executable-stack "needs an executable stack: $stacks"; fi
echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
