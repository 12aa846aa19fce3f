#!/usr/bin/env bash
# make test's share of the fuzzer: test/fuzz/fuzz.py (see its header) on the
# debug build, run by a python3 that has h5py (Debian's python3-h5py, which
# the Makefile installs, serves /usr/bin/python3, which may not be the first
# python3 on PATH). Arguments go to fuzz.py; its last line is
# `N passed, M failed`.
set -u
here=$(cd "$(dirname "$0")" && pwd)
py=python3
if ! "$py" -c 'import h5py' 2>/dev/null && [ -x /usr/bin/python3 ] \
    && /usr/bin/python3 -c 'import h5py' 2>/dev/null; then
    py=/usr/bin/python3
fi
exec "$py" "$here/fuzz.py" "$@"
