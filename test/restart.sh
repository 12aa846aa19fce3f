#!/usr/bin/env bash
# Restart from the result file (`flexmbs run SCENE --resume`, docs/output.md
# "Restart"): runs killed at random times, with SIGTERM (a clean stop) or
# SIGKILL (no warning: the file holds what its last checkpoint flushed),
# each resumed to t_end. For every resumed run:
#   - the records are continuous: /time is the scene's output times, all of
#     them, strictly increasing (every accepted step with every_step);
#   - the records up to the restart are bitwise those of the uninterrupted
#     run (the run is deterministic up to the kill);
#   - ERR of the positions against a tight reference of another solver
#     (docs/theory.md section 9) is at most max(10 TOL, 2 x the
#     uninterrupted run's ERR);
#   - the file says it was resumed (restart_times, statistics, outcome ok).
# Then what must be refused (exit 2, the message naming why): a resume
# with a changed scene, of a file flexmbs did not write, of a missing file;
# and a finished run is left alone (exit 0, "nothing to resume").
#
#   bash test/restart.sh [path/to/flexmbs]
#
# Without an argument the debug build is used (built if needed). The last
# line is `N passed, M failed`; the exit status is non-zero on failures.
set -u
. "$(dirname "$0")/h5py_suite.sh" restart "$@"
# the kill times: reproducible, from the seed given or 1
RANDOM=${RESTART_SEED:-1}

# scene IN OUT GROUP NAME=VALUE ...: IN with the variables of its first
# &GROUP set (replaced where given, added where not)
scene() {
    "$py" - "$@" <<'EOF'
import re, sys
source, target, group = sys.argv[1:4]
text = open(source).read()
head = re.search(r'(?m)^&' + group + r'\b', text)
start = head.end()
end = start + re.search(r'(?m)^\s*/\s*$', text[start:]).start()
body = text[start:end]
for pair in sys.argv[4:]:
    name, value = pair.split('=', 1)
    line = re.compile(r'(?m)^(\s*)' + name + r'\s*=\s*[^,\n!]*')
    if line.search(body):
        body = line.sub(lambda m: m.group(1) + name + ' = ' + value, body, count=1)
    else:
        body = '\n    ' + name + ' = ' + value + ',' + body
open(target, 'w').write(text[:start] + body + text[end:])
EOF
}

# make NAME BASE SOLVER TOL T_END [every_step]: NAME.nml writing NAME.h5,
# with a checkpoint at least every 20 ms of wall time
make() {
    local name=$1 base=$2 solver=$3 tol=$4 t_end=$5 every=${6:-.false.}
    scene "$root/inputs/$base.nml" "$name.nml" solver "name='$solver'" "rtol=$tol" "atol=$tol" \
        && scene "$name.nml" "$name.nml" simulation "t_end=$t_end" \
        && scene "$name.nml" "$name.nml" output "file='$name.h5'" "checkpoint_interval=0.02" \
            "progress=.false." "every_step=$every"
}

# ERR REF RESULT TOL: ERR of RESULT's positions against REF (eq. 13 with
# rtol = atol = TOL); fails when the output times differ
err() {
    "$py" - "$@" <<'EOF'
import sys
import h5py
import numpy as np
ref, run, tol = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r'), float(sys.argv[3])
tr, t = ref['time'][:], run['time'][:]
if len(t) != len(tr) or np.abs(t - tr).max() > 1e-12 * max(1.0, np.abs(tr).max()):
    sys.exit('output times differ: %d records against %d' % (len(t), len(tr)))
key = 'q' if 'q' in run else 'y'
x, xr = run[key][:], ref[key][:]
print('%.6e' % (tol * np.sqrt(np.mean(((x - xr) / (tol * np.abs(xr) + tol)) ** 2))))
EOF
}

# What is wrong with a resumed RESULT (empty when nothing), against the
# uninterrupted run FULL: continuous records, those up to the restart
# bitwise FULL's, resumed RESTARTS times, outcome ok, statistics summed
inspect() {
    "$py" - "$@" 2>&1 <<'EOF'
import sys
import h5py
import numpy as np
run, full, restarts, every = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4] == 'every'
try:
    f, g = h5py.File(run, 'r'), h5py.File(full, 'r')
    t, tf = f['time'][:], g['time'][:]
    outcome = f.attrs.get('outcome', b'')
    outcome = outcome.decode() if isinstance(outcome, bytes) else str(outcome)
    starts = np.atleast_1d(f.attrs.get('restart_times', []))
    if outcome != 'ok':
        print('outcome %r' % outcome)
    elif len(starts) != restarts:
        print('restart_times %s: %d restarts expected' % (starts, restarts))
    elif not np.all(np.isfinite(f['y'][:])) or not np.all(np.diff(t) > 0):
        print('/time not strictly increasing or /y not finite')
    elif f['y'].shape[0] != len(t):
        print('/y has %d records, /time %d' % (f['y'].shape[0], len(t)))
    elif not every and len(t) != len(tf):
        print('%d records, the uninterrupted run %d' % (len(t), len(tf)))
    elif not every and np.abs(t - tf).max() > 1e-12 * max(1.0, np.abs(tf).max()):
        print('output times differ from the uninterrupted run')
    elif every and (t[0] != tf[0] or t[-1] != tf[-1]):
        print('every step: from %g to %g, the uninterrupted run %g to %g' % (t[0], t[-1], tf[0], tf[-1]))
    elif 'sums over the %d pieces' % (restarts + 1) not in str(f.attrs.get('statistics', '')):
        print('statistics attribute %r' % f.attrs.get('statistics'))
    else:
        kept = int(np.sum(t <= starts[0]))
        same = np.array_equal(f['y'][:kept], g['y'][:kept]) and np.array_equal(t[:kept], tf[:kept])
        if kept < 1 or not same:
            print('the %d records up to the first restart (t = %g) differ from the '
                  'uninterrupted run' % (kept, starts[0]))
except Exception as e:
    print('cannot check %s: %s' % (run, e))
EOF
}

# interrupt NAME SIGNAL DELAY_MS: start NAME.nml (its file NAME.h5 anew or
# resumed with RESUME=1), send SIGNAL after DELAY_MS; prints the exit code
interrupt() {
    local name=$1 sig=$2 delay=$3 rc
    env --default-signal=INT,TERM "$exe" run "$name.nml" --quiet ${RESUME:+--resume} \
        > "$name.out" 2>&1 &
    pid=$!
    sleep "$(printf '%d.%03d' $((delay / 1000)) $((delay % 1000)))"
    kill -"$sig" "$pid" 2>/dev/null
    { wait "$pid"; } 2>/dev/null
    rc=$?
    pid=""
    echo "$rc"
}

# wall milliseconds of a command
millis() {
    local start=$(date +%s%N)
    "$@" > /dev/null 2>&1
    echo $((($(date +%s%N) - start) / 1000000))
}

# run_case LABEL NAME TOL SIGNAL...: NAME.nml interrupted once per SIGNAL,
# each at a random 15..85 % of its uninterrupted time (the first piece
# fresh, each later one a resume of the file), then resumed to t_end and
# checked. A first piece that ends before its signal, or is killed before
# its first checkpoint or even before its file was whole (the resume then
# says so), starts again.
run_case() {
    local label=$1 name=$2 tol=$3
    shift 3
    local full_ms=${times[$name]} rc delay attempt sig problem="" every=steps e_run e_full
    local pieces=0 resumes=0 finished=0 killed="" round
    grep -q 'every_step = .true.' "$name.nml" && every=every
    for round in 1 2 3 4; do
        problem=""
        pieces=0
        resumes=0
        finished=0
        killed=""
        rm -f "$name.h5" "$name.resume"
        for sig in "$@"; do
            delay=$((full_ms * (15 + RANDOM % 71) / 100 + 5))
            for attempt in 1 2 3 4 5 6; do
                if [ $pieces -gt 0 ]; then
                    rc=$(RESUME=1 interrupt "$name" "$sig" "$delay")
                    if [ "$rc" -eq 2 ] && grep -qE 'no checkpoint|no such file|nothing to resume from' "$name.out"; then
                        pieces=0
                        rm -f "$name.h5"
                        continue
                    fi
                    [ "$rc" -ne 2 ] && resumes=$((resumes + 1))
                else
                    rc=$(interrupt "$name" "$sig" "$delay")
                    if [ "$rc" -eq 0 ]; then
                        rm -f "$name.h5"
                        delay=$((delay / 2))
                        continue
                    fi
                fi
                break
            done
            pieces=$((pieces + 1))
            killed="$killed SIG$sig at $delay ms"
            if [ "$rc" -eq 0 ] && [ $pieces -gt 1 ]; then finished=1; break; fi
            case "$sig:$rc" in
            TERM:143 | KILL:137) ;;
            *) problem="SIG$sig: exit $rc: $(head -c 400 "$name.out")"; break ;;
            esac
        done
        if [ -z "$problem" ] && [ $finished -eq 0 ]; then
            if "$exe" run "$name.nml" --quiet --resume > "$name.resume" 2>&1; then
                resumes=$((resumes + 1))
                grep -q "resumed at t =" "$name.resume" \
                    || problem="no 'resumed at t =' line: $(head -c 300 "$name.resume")"
            else
                problem="resume after${killed}: $(head -c 400 "$name.resume")"
            fi
        fi
        # the last signal came before the first checkpoint: the case again
        if [ $finished -eq 0 ] && [ $round -lt 4 ] \
            && grep -qE 'no checkpoint|no such file|nothing to resume from' "$name.resume" 2>/dev/null; then
            continue
        fi
        break
    done
    [ -z "$problem" ] && problem=$(inspect "$name.h5" "full_$name.h5" "$resumes" "$every")
    if [ -z "$problem" ] && [ "$every" = steps ]; then
        e_run=$(err "ref_$name.h5" "$name.h5" "$tol") || problem="ERR: $e_run"
        e_full=${errs[$name]}
        if [ -z "$problem" ] && ! "$py" -c \
            "import sys; sys.exit(not $e_run <= max(10 * $tol, 2 * $e_full))"; then
            problem="ERR $e_run > max(10 TOL, 2 x $e_full) (TOL $tol)"
        fi
    fi
    echo "  $label:$killed of ${full_ms} ms, $resumes resumes, ERR ${e_run:--}" \
        "(uninterrupted ${errs[$name]}, TOL $tol)"
    if [ -n "$problem" ]; then fail "$label" "$problem"; else pass "$label"; fi
}

declare -A times errs
# The scenes: a soft body and rigid links (GGL) with RADAU5, DDASSL and
# IDA; the four-bar of rigid chains with MEXAX; each has a reference of
# RADAU5 at 1e-10 (DDASSL for RADAU5's own scene).
make soft_radau5 two_soft_links radau5 1e-6 0.5
make soft_ddassl two_soft_links ddassl 1e-6 0.5
make soft_ida two_soft_links ida 1e-6 0.5
make chain_mexax four_bar_chain mexax 1e-7 10.0
make soft_steps two_soft_links radau5 1e-6 0.5 .true.
make ref_soft two_soft_links radau5 1e-10 0.5
make ref_soft_radau5 two_soft_links ddassl 1e-10 0.5
make ref_chain four_bar_chain radau5 1e-10 10.0
for name in ref_soft ref_soft_radau5 ref_chain; do
    "$exe" run "$name.nml" --quiet > "$name.out" 2>&1 || fail "$name" "$(head -c 400 "$name.out")"
done
cp ref_soft.h5 ref_soft_ddassl.h5
cp ref_soft.h5 ref_soft_ida.h5
cp ref_chain.h5 ref_chain_mexax.h5
for name in soft_radau5 soft_ddassl soft_ida chain_mexax soft_steps; do
    times[$name]=$(millis "$exe" run "$name.nml" --quiet)
    cp "$name.h5" "full_$name.h5" 2>/dev/null || fail "uninterrupted-$name" "no $name.h5"
    errs[$name]=0
    [ "$name" = soft_steps ] && continue
    errs[$name]=$(err "ref_$name.h5" "full_$name.h5" 1e-6) || fail "err-$name" "${errs[$name]}"
done
errs[chain_mexax]=$(err ref_chain_mexax.h5 full_chain_mexax.h5 1e-7)

# 20 interrupted runs: each solver, SIGTERM and SIGKILL
k=0
for name in soft_radau5 soft_ddassl soft_ida chain_mexax; do
    tol=1e-6
    [ "$name" = chain_mexax ] && tol=1e-7
    for sig in TERM KILL TERM KILL; do
        k=$((k + 1))
        run_case "$name-$k-sig${sig,,}" "$name" "$tol" "$sig"
    done
done
# killed twice (a resume resumed), and every accepted step recorded
k=$((k + 1))
run_case "soft_radau5-$k-killed-twice" soft_radau5 1e-6 KILL TERM
scene soft_steps.nml soft_steps.nml output "checkpoint_interval=0"
for sig in TERM KILL KILL; do
    k=$((k + 1))
    run_case "soft_steps-$k-sig${sig,,}" soft_steps 1e-6 "$sig"
done

# What a resume refuses, and a finished run
expect() {
    local label=$1 code=$2 pattern=$3
    shift 3
    "$exe" "$@" > out.txt 2>&1
    local rc=$?
    if [ "$rc" -ne "$code" ]; then fail "$label" "exit $rc, expected $code: $(head -c 400 out.txt)"
    elif ! grep -qF -- "$pattern" out.txt; then fail "$label" "no '$pattern' in: $(head -c 400 out.txt)"
    else pass "$label"; fi
}
expect finished-run-left-alone 0 'nothing to resume' run soft_radau5.nml --quiet --resume
scene soft_radau5.nml changed.nml solver "rtol=2e-6"
scene changed.nml changed.nml output "file='soft_radau5.h5'"
cp soft_radau5.h5 before.h5
expect changed-scene-refused 2 "&solver rtol = 1E-6 in the result, 2E-6 now" run changed.nml --resume
if ! cmp -s before.h5 soft_radau5.h5; then
    fail changed-scene-file-untouched "the refused resume changed soft_radau5.h5"
else
    pass changed-scene-file-untouched
fi
echo 'not a result' > other.h5
expect foreign-file-refused 2 "other.h5: not an HDF5 file" run soft_radau5.nml --resume other.h5
expect missing-file-refused 2 "missing.h5: no such file to resume from" run soft_radau5.nml \
    --resume missing.h5

echo "${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
