#!/usr/bin/env bash
# flexmbs as an fpm dependency (docs/packaging.md): test/fpm_dependency/ is
# a project of its own whose fpm.toml depends on flexmbs by path; it is
# built and run with fpm as its user would, with the include directories of
# the system modules and headers flexmbs uses (HDF5, SUNDIALS, MUMPS) in
# FPM_FFLAGS — the Makefile's, which make test exports — and nothing else
# (no FPM_CFLAGS). Its build directory is its own (test/fpm_dependency/build):
# the first run compiles flexmbs there (about half a minute in the debug
# profile), later runs only what changed.
#
#   bash test/dependency.sh
#
# The last line is `N passed, M failed`; the exit status is non-zero on failures.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
FPM=${FPM:-fpm}
# the Makefile's flags when run on its own
export FPM_FFLAGS=${FPM_FFLAGS:-"-I/usr/include/hdf5/serial -I/usr/include/sundials/fortran -I/usr/include -I/usr/include/mumps_seq"}
unset FPM_CFLAGS
passed=0
failed=0
pass() { passed=$((passed + 1)); echo "pass dependency/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL dependency/$1: $2"; }
err=$(mktemp "${TMPDIR:-/tmp}/flexmbs-dependency.XXXXXX")
trap 'rm -f "$err"' EXIT

cd "$root/test/fpm_dependency" || exit 1
start=$SECONDS
if out=$($FPM build --profile debug 2>&1); then
    pass "builds-with-fpm ($((SECONDS - start)) s)"
    exe=$($FPM run --profile debug --runner echo uses-flexmbs 2>/dev/null | tail -n 1)
    if out=$("./$exe" 2>"$err") && [ ! -s "$err" ] &&
        grep -q '^flexmbs as an fpm dependency: pendulum angle' <<<"$out"; then
        echo "$out"
        pass runs
    else
        fail runs "$out $(cat "$err")"
    fi
else
    fail builds-with-fpm "$(tail -n 20 <<<"$out")"
fi
echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
