#!/usr/bin/env bash
# The example programs of examples/, built as a user builds them against
# an installed flexmbs (pkg-config's flags) and run: the pendulum through
# every solver (exits non-zero when an angle is off), a scene run from a
# program, and the Python script that plots its result by name (h5py and
# matplotlib of the system's Python).
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

flags=$(pkg-config --cflags --libs flexmbs) || { echo "FAIL programs: no flexmbs.pc in $prefix"; echo "0 passed, 1 failed"; exit 1; }
for src in examples/*.f90; do
    name=$(basename "$src" .f90)
    if out=$(gfortran -J "$work" -o "$work/$name" "$src" $flags 2>&1); then
        pass "$name-builds"
    else
        fail "$name-builds" "$out"
    fi
done

if out=$("$work/pendulum" 2>&1); then pass "pendulum-every-solver"
else fail "pendulum-every-solver" "$out"; fi
if out=$("$work/run_scene" inputs/rigid_flexible_pendulum.nml "$work/rigid_flexible.h5" 2>&1) &&
    grep -q '^  link: at (' <<<"$out"; then
    pass "run-scene-from-a-program"
else
    fail "run-scene-from-a-program" "$out"
fi
py=/usr/bin/python3
[ -x "$py" ] || py=python3
if out=$("$py" examples/plot_result.py "$work/rigid_flexible.h5" "$work/plot.png" 2>&1) &&
    [ -s "$work/plot.png" ]; then
    pass "plot-by-name"
else
    fail "plot-by-name" "$out"
fi
echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
