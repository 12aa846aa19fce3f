# Sourced by the command-line suites that read result files (kill.sh,
# restart.sh) as
#   . test/h5py_suite.sh SUITE [path/to/flexmbs]
# Sets $root and $exe (test/executable.sh), $py (the system's Python with
# h5py: Debian's python3-h5py, see the Makefile; a python3 earlier on PATH,
# a virtual environment, may lack it), enters a new work folder removed on
# exit (with the process $pid, when set, killed), and defines pass NAME and
# fail NAME WHY, which count into $passed and $failed. Without h5py it
# prints a FAIL line and the summary, and exits.
. "$(dirname "${BASH_SOURCE[0]}")/executable.sh" "$@"
suite=$1
py=/usr/bin/python3
[ -x "$py" ] || py=python3
if ! "$py" -c 'import h5py' 2>/dev/null; then
    echo "FAIL $suite: $py cannot import h5py (apt-get install python3-h5py)"
    echo "0 passed, 1 failed"
    exit 1
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-$suite.XXXXXX")
pid=""
trap '[ -n "$pid" ] && kill -KILL "$pid" 2>/dev/null; rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0
failed=0
pass() { passed=$((passed + 1)); echo "pass $suite/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL $suite/$1: $2"; }
