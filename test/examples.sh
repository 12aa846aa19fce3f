#!/usr/bin/env bash
# Every example scene of inputs/ runs, cut to its first instants, with exit 0
# and nothing at all on standard error: no progress (--quiet), no warning,
# and no note on floating-point exceptions (LAPACK's IEEECK raises
# divide-by-zero and invalid on purpose; linalg/lapack keeps the flags, and
# app/ reports only invalid, divide-by-zero and overflow; a non-finite
# value in a model or solver is a solver failure, exit 3, anyway). Then the
# named series of every multibody result (/bodies, /joints, /drivers,
# /flexible) are checked against its /y, and `flexmbs columns` by name
# against them (test/result_names.py), the five-body result read by name
# and unit (test/five_body_names.py), and every dataset that is zero at
# every record explained by physics (test/zero_datasets.py).
#
#   bash test/examples.sh [path/to/flexmbs]
#
# The last line is `N passed, M failed`; the exit status is non-zero on
# failures.
set -u
. "$(dirname "$0")/executable.sh" examples "$@"

work=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-examples.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
cp -r "$root/inputs/meshes" .
passed=0
failed=0
pass() { passed=$((passed + 1)); echo "pass examples/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL examples/$1: $2"; }

for scene in "$root"/inputs/*.nml; do
    name=$(basename "$scene" .nml)
    # the first 10 ms (van der Pol: its first 0.1 s), every output in here
    sed -E -e "s/^([[:space:]]*t_end[[:space:]]*=[[:space:]]*)[0-9.eEdD+-]+/\10.01/" \
        -e "s/(,[[:space:]]*t_end[[:space:]]*=[[:space:]]*)[0-9.eEdD+-]+/\10.01/" \
        "$scene" > "$name.nml"
    "$exe" run "$name.nml" --quiet > "$name.out" 2> "$name.err"
    rc=$?
    if [ "$rc" -ne 0 ]; then
        fail "$name" "exit $rc: $(head -c 400 "$name.err")"
    elif [ -s "$name.err" ]; then
        fail "$name" "standard error not empty: $(head -c 400 "$name.err")"
    elif ! grep -q '^t = *1.0*E-02' "$name.out"; then
        fail "$name" "did not stop at t = 0.01: $(grep '^t =' "$name.out")"
    else
        pass "$name-clean-stderr"
    fi
done

# The run summary for people: the five-body mechanism's bodies, joints
# and coupler by name, not its 2268... components; --verbose adds them.
out=$(cat five_body.out)
if grep -q '^  rocker: at (' <<<"$out" && grep -q '^  rocker pivot: angle ' <<<"$out" &&
    grep -q '^  flail: joint angle ' <<<"$out" &&
    grep -q '^  coupler: largest displacement .* largest von Mises stress ' <<<"$out" &&
    grep -q '^energy \[J\]: at t_start' <<<"$out" && ! grep -q '^y(1) =' <<<"$out"; then
    pass summary-by-name
else
    fail summary-by-name "$out"
fi
if "$exe" run five_body.nml --quiet --verbose 2>&1 | grep -q '^y(1) ='; then
    pass summary-verbose-state
else
    fail summary-verbose-state "--verbose printed no y(1)"
fi

# The Python checks below print pass and FAIL lines: counted here, the
# prefix PREFIX taken off their names (h5py of the system's Python, see the
# Makefile).
py=/usr/bin/python3
[ -x "$py" ] || py=python3
relay() {  # PREFIX < lines
    local line
    while read -r line; do
        case $line in
            pass\ *) pass "${line#pass $1}" ;;
            FAIL\ *) fail "${line#FAIL $1}" "" ;;
        esac
    done
}

# The five-body result as a user reads it, by name and unit, against /y
# (test/five_body_names.py: the rocker pivot's angle, coupler node 23's x,
# the rocker pivot's reaction, the coupler's stress against the summary)
relay "" < <("$py" "$root/test/five_body_names.py" five_body.h5 five_body.out 2>&1 ||
             echo "FAIL five_body_names: test/five_body_names.py failed")

# The named series of each multibody result against its /y (test/result_names.py)
for h5 in *.h5; do
    relay result_names/ < <("$py" "$root/test/result_names.py" "$h5" "$exe" 2>&1 ||
                            echo "FAIL $h5: result_names.py failed")
done

# No silent zeros: a dataset zero at every record must be so by physics,
# each case with its reason (test/zero_datasets.py)
relay "" < <("$py" "$root/test/zero_datasets.py" *.h5 2>&1 ||
             echo "FAIL zero_datasets: test/zero_datasets.py found a failure or failed")

echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
