#!/usr/bin/env bash
# Signals during a run of the undamped five-body mechanism
# (inputs/five_body_undamped.nml, about 13 s in the debug build): once the
# HDF5 file holds a few records, the run gets SIGKILL, SIGTERM or SIGINT.
# After each, the file must open with the HDF5 library (h5py) and /time be
# finite and strictly increasing; SIGTERM and SIGINT must stop the run
# within a step or so with exit 143 / 130, the message (time reached,
# statistics) on standard error, and the statistics and outcome on the
# file's root, as after a solver failure.
#
#   bash test/kill.sh [path/to/flexmbs]
#
# Without an argument the debug build is used (built if needed). The last
# line is `N passed, M failed`; the exit status is non-zero on failures.
set -u
. "$(dirname "$0")/h5py_suite.sh" kill "$@"

sed -e "s#^&output#\&output file = 'run.h5',#" "$root/inputs/five_body_undamped.nml" > scene.nml

# Records in run.h5 while the run writes it (HDF5 locks a file open for
# writing against readers; this reader only counts). Empty when unreadable.
records() {
    HDF5_USE_FILE_LOCKING=FALSE "$py" -c \
        "import h5py; print(len(h5py.File('run.h5', 'r')['time']))" 2>/dev/null
}

# What is wrong with run.h5 after the run ended (empty when nothing): it
# opens, /time is finite, strictly increasing, has >= 3 records, and ends
# before t_end = 1; with ATTRIBUTE, the root attribute's text contains TEXT
# and the statistics (NST) are there. A check that raises (a dataset
# missing, say) or exits non-zero is a problem too, not a silent pass.
inspect() {
    local text rc
    text=$("$py" - "$@" 2> inspect.err <<'EOF'
import math, sys
import h5py
try:
    f = h5py.File('run.h5', 'r')
    t = [float(x) for x in f['time'][:]]
except Exception as e:
    print('run.h5 does not open: %s' % e)
    sys.exit()
if len(t) < 3:
    print('only %d records in /time' % len(t))
elif not all(math.isfinite(x) for x in t):
    print('/time not finite: %s' % t)
elif not all(b > a for a, b in zip(t, t[1:])):
    print('/time not strictly increasing: %s' % t)
elif t[-1] >= 1.0:
    print('the run was not stopped: /time ends at %g' % t[-1])
elif f['y'].shape[0] < len(t):
    print('/y has %d records, /time %d' % (f['y'].shape[0], len(t)))
elif len(sys.argv) > 2:
    value = f.attrs.get(sys.argv[1], b'')
    value = value.decode() if isinstance(value, bytes) else str(value)
    if sys.argv[2] not in value:
        print('attribute %s = %r lacks %r' % (sys.argv[1], value, sys.argv[2]))
    elif 'NST' not in f.attrs:
        print('no statistics (NST) on the root')
EOF
)
    rc=$?
    if [ "$rc" -ne 0 ]; then
        echo "the check of run.h5 failed (exit $rc): ${text:+$text; }$(tail -n 1 inspect.err)"
    elif [ -n "$text" ]; then
        echo "$text"
    fi
}

# signal NAME SIGNAL CODE [PATTERN...]: start the run, wait for 3 records,
# send SIGNAL; exit CODE, each PATTERN in standard error, run.h5 sound.
# SIGINT is set to its default first: a background job of a shell without
# job control starts with SIGINT ignored, and flexmbs leaves an ignored
# signal ignored.
signal() {
    local name=$1 sig=$2 code=$3
    shift 3
    local start n rc problem="" sent waited
    rm -f run.h5
    start=$(date +%s%N)
    env --default-signal=INT,TERM "$exe" run scene.nml --quiet > out.txt 2>&1 &
    pid=$!
    n=""
    for _ in $(seq 600); do
        n=$(records)
        [ -n "$n" ] && [ "$n" -ge 3 ] && break
        if ! kill -0 "$pid" 2>/dev/null; then break; fi
        sleep 0.1
    done
    if [ -z "$n" ] || [ "$n" -lt 3 ]; then
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
        pid=""
        fail "$name" "the run did not reach 3 records (records: '${n}'): $(head -c 600 out.txt)"
        return
    fi
    sent=$(date +%s%N)
    kill -"$sig" "$pid"
    { wait "$pid"; } 2>/dev/null
    rc=$?
    pid=""
    waited=$((($(date +%s%N) - sent) / 1000000))
    if [ "$rc" -ne "$code" ]; then
        problem="exit $rc, expected $code; output: $(head -c 600 out.txt)"
    fi
    for pattern in "$@"; do
        [ -n "$problem" ] && break
        grep -qF -- "$pattern" out.txt || problem="output lacks '$pattern': $(head -c 600 out.txt)"
    done
    if [ -z "$problem" ]; then
        if [ "$sig" = KILL ]; then
            problem=$(inspect)
        else
            problem=$(inspect outcome "stopped by SIG$sig at t =")
        fi
    fi
    echo "  $name: $n records when signalled, ended ${waited} ms later," \
        "$((($(date +%s%N) - start) / 1000000)) ms in all"
    if [ -n "$problem" ]; then fail "$name" "$problem"; else pass "$name"; fi
}

# SIGKILL cannot be caught: the file holds what was flushed after each record
signal sigkill-file-opens KILL 137
signal sigterm-stops-cleanly TERM 143 "flexmbs: stopped by SIGTERM at t =" \
    "flexmbs: time reached t =" "flexmbs: statistics so far: NST=" \
    "trajectory up to there kept in run.h5"
signal sigint-stops-cleanly INT 130 "flexmbs: stopped by SIGINT at t =" \
    "flexmbs: time reached t =" "flexmbs: statistics so far: NST=" \
    "trajectory up to there kept in run.h5"

echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
