# Sourced by the command-line test scripts (cli.sh, kill.sh) as
#   . test/executable.sh SUITE [path/to/flexmbs]
# Sets $root (the repository) and $exe (the flexmbs to test: the argument,
# or the debug build, built if needed); without one, prints a FAIL line
# and the summary, and exits.
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ $# -ge 2 ]; then
    exe=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
else
    # the Makefile's flags: other flags would make fpm rebuild everything
    export FPM_FFLAGS=${FPM_FFLAGS:-"-I/usr/include/hdf5/serial -I/usr/include/sundials/fortran -I/usr/include -I/usr/include/mumps_seq"}
    export FPM_CFLAGS=${FPM_CFLAGS:-"-I/usr/include/suitesparse -fPIC"}
    exe=$(cd "$root" && ${FPM:-fpm} run --profile debug --runner echo flexmbs 2>/dev/null | tail -n 1)
    [ -n "$exe" ] && exe="$root/$exe"
fi
if [ -z "$exe" ] || [ ! -x "$exe" ]; then
    echo "FAIL $1: no executable (got '$exe')"
    echo "0 passed, 1 failed"
    exit 1
fi
