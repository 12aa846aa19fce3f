#!/usr/bin/env bash
# The cluster test: a one-node Slurm started by test/cluster/slurm.sh runs
#  - a job array of 4 tasks, each writing its task id; task 1 runs
#    `flexmbs --version`, task 2 a small scene (the same output as run here,
#    apart from the CPU and wall times);
#  - a job array of 3 tasks: one succeeds, one exits 3, one is cancelled
#    while running (scancel JOB_3), and a job that depends on the array
#    (afterany, as a merge job will) runs once all three have ended and
#    sees which are missing;
#  - the quick five-body study submitted by `flexmbs sweep --slurm --submit`
#    (job array and merge job): its table equals `sweep -j 2`'s but for
#    CPU; submitted again held, half of its tasks cancelled: `--merge`
#    lists exactly those (exit 3), its printed sbatch command reruns only
#    them, and the merge gives the same table; a changed study text makes
#    every record stale;
#  - a task warned before its time limit (scancel --signal=TERM --batch)
#    stops its point with a checkpoint, requeues itself and resumes the
#    point, as accurate as one run uninterrupted;
# then the daemons stop and leave nothing behind.
#
#   bash test/cluster/run.sh [path/to/flexmbs]
#
# Without an argument the debug build is used (built if needed). Every wait
# is a poll with a time limit. The last line is `N passed, M failed`; the
# exit status is non-zero on failures. `make test-cluster` installs Slurm
# and munge and runs it.
set -u
. "$(dirname "$0")/../executable.sh" cluster "$@"
. "$root/test/cluster/slurm.sh"
passed=0
failed=0

pass() { passed=$((passed + 1)); echo "pass cluster/$1"; }
fail() { failed=$((failed + 1)); echo "FAIL cluster/$1: $2"; }
summary() { echo "${passed} passed, ${failed} failed"; [ "$failed" -eq 0 ]; }

# field JOB NAME: NAME's value in `scontrol show job JOB` (one task of an
# array as JOB_TASK).
field() {
    scontrol -o show job "$1" 2>/dev/null | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n 1
}

# state NAME JOB STATE EXITCODE: the job ended in STATE with EXITCODE.
state() {
    local s e
    s=$(field "$2" JobState)
    e=$(field "$2" ExitCode)
    if [ "$s" = "$3" ] && [ "$e" = "$4" ]; then
        pass "$1"
    else
        fail "$1" "job $2 is '$s' exit '$e', expected '$3' exit '$4'"
    fi
}

t0=$(date +%s)
if cluster_start 60; then
    pass "start ($(($(date +%s) - t0)) s, $FLEXMBS_SLURM_DIR)"
else
    fail start "the cluster did not come up (messages above)"
    summary
    exit 1
fi
cluster_dir=$FLEXMBS_SLURM_DIR
daemons=$(cat "$cluster_dir"/run/*.child)
node=$(sinfo -h -N -o '%N %T %c' 2>&1)
if [ "$node" = "$(hostname -s) idle 2" ]; then pass node-idle-2-cpus; else fail node-idle-2-cpus "$node"; fi

work=$cluster_dir/work
mkdir -p "$work/a" "$work/b" && cd "$work" || exit 1

# the small scene of test/cli.sh
printf '%s\n%s\n%s\n' "&simulation problem = 'van_der_pol', t_end = 2 /" \
    "&solver rtol = 1e-4, atol = 1e-4, h0 = 1e-6 /" "&output file = 'vdp.h5' /" > vdp.nml

# Array A: every task writes its id and its exit status to a/N.txt.
cat > a.sh <<EOF
#!/bin/bash
t=\$SLURM_ARRAY_TASK_ID
cd $(printf %q "$work/a") || exit 1
echo "task \$t of \$SLURM_ARRAY_JOB_ID" > \$t.txt
status=0
case \$t in
    1) $(printf %q "$exe") --version > version.txt 2>&1 || status=\$? ;;
    2) mkdir -p scene && cd scene && cp ../../vdp.nml . \\
           && $(printf %q "$exe") run vdp.nml --quiet > ../scene.txt 2>&1 || status=\$?
       cd .. ;;
esac
echo "status \$status" >> \$t.txt
exit \$status
EOF

# Array B: task 1 succeeds, task 2 fails (exit 3), task 3 waits (at most
# 2 minutes) for the scancel.
cat > b.sh <<EOF
#!/bin/bash
t=\$SLURM_ARRAY_TASK_ID
cd $(printf %q "$work/b") || exit 1
case \$t in
    2) exit 3 ;;
    3) touch started.3
       for i in \$(seq 1200); do sleep 0.1; done ;;
esac
echo done > done.\$t
EOF

# The dependent job: what it finds when it starts.
cat > dep.sh <<EOF
#!/bin/bash
cd $(printf %q "$work") || exit 1
{ echo "queue: [\$(squeue -h -j \$1 -o %i)]"; ls b; } > dep.txt
EOF

a=$(sbatch --parsable --array=1-4 -J a -o "$work/a/slurm-%A_%a.out" a.sh 2>&1)
b=$(sbatch --parsable --array=1-3 -J b -o "$work/b/slurm-%A_%a.out" b.sh 2>&1)
dep=$(sbatch --parsable --dependency=afterany:"$b" -J dep -o "$work/dep.out" dep.sh "$b" 2>&1)
if [[ "$a" =~ ^[0-9]+$ && "$b" =~ ^[0-9]+$ && "$dep" =~ ^[0-9]+$ ]]; then
    pass submit
else
    fail submit "sbatch answered '$a', '$b', '$dep'"
    summary
    exit 1
fi
if [ "$(field "$dep" JobState)" = PENDING ]; then pass dependent-pending; else
    fail dependent-pending "job $dep is '$(field "$dep" JobState)' before the array ended"; fi

# cancel task 3 of B once it runs
deadline=$(( $(date +%s) + 90 ))
until [ -e b/started.3 ] || [ "$(date +%s)" -ge "$deadline" ]; do sleep 0.2; done
if [ -e b/started.3 ]; then
    scancel "${b}_3"
    pass cancel-running-task
else
    fail cancel-running-task "task ${b}_3 did not start within 90 s: $(squeue 2>&1)"
fi

if cluster_wait 90 "$a" "$b" "$dep"; then pass "all-ended ($(($(date +%s) - t0)) s)"; else
    fail all-ended "time limit"; fi

# A: every task completed, wrote its id and status 0
for t in 1 2 3 4; do
    state "array-task-$t" "${a}_$t" COMPLETED 0:0
    got=$(cat "a/$t.txt" 2>&1)
    want=$(printf 'task %s of %s\nstatus 0' "$t" "$a")
    if [ "$got" = "$want" ]; then pass "array-task-$t-output"; else
        fail "array-task-$t-output" "a/$t.txt is '$got'; slurm output: $(cat "a/slurm-${a}_$t.out" 2>&1)"
    fi
done
if grep -q "^flexmbs 0\." a/version.txt 2>/dev/null; then pass flexmbs-version; else
    fail flexmbs-version "$(cat a/version.txt 2>&1)"; fi
# the scene run in the job equals the one here, but for the times
here=$(mkdir -p here && cd here && cp ../vdp.nml . && "$exe" run vdp.nml --quiet 2>&1)
strip() { sed -E 's/ (CPU|WALL)=[^ ]*//g; s|trajectory: .*|trajectory|'; }
if [ -s a/scene/vdp.h5 ] && grep -q 'y(1) =  1.7061611' a/scene.txt \
    && [ "$(strip < a/scene.txt)" = "$(strip <<<"$here")" ]; then
    pass flexmbs-scene-as-here
else
    fail flexmbs-scene-as-here "in the job: $(cat a/scene.txt 2>&1); here: $here"
fi

# B: the outcome of each task is visible to Slurm and in the files
state array-ok "${b}_1" COMPLETED 0:0
state array-failed "${b}_2" FAILED 3:0
state array-cancelled "${b}_3" CANCELLED 0:15
missing=""
for t in 1 2 3; do [ -e "b/done.$t" ] || missing="$missing $t"; done
if [ "$missing" = " 2 3" ]; then pass missing-tasks-detected; else
    fail missing-tasks-detected "tasks without output:$missing, expected 2 3"; fi

# the dependent job ran after all of B, and saw task 1's output only
state dependent-ran "$dep" COMPLETED 0:0
if [ "$(head -n 1 dep.txt 2>&1)" = "queue: []" ] && grep -qx done.1 dep.txt \
    && ! grep -qE '^done\.[23]$' dep.txt; then
    pass dependent-after-array
else
    fail dependent-after-array "dep.txt: $(cat dep.txt 2>&1); $(cat dep.out 2>&1)"
fi

# A study on the cluster (docs/studies_on_a_cluster.md): the quick
# five-body study (6 grid points) submitted by `sweep --slurm --submit` in
# tasks of 2 points, its merge job, and the same study by `sweep -j 2`:
# the same table but for CPU.
study_from() {  # study_from DIR: the quick study in DIR, its paths absolute
    mkdir -p "$1"
    sed -e "s#'../five_body.nml'#'$root/inputs/five_body.nml'#" \
        -e "s#'../../build/five_body_quick_reference.h5'#'$work/q_reference.h5', table = 'q.md'#" \
        "$root/inputs/paper/five_body_quick.nml" > "$1/q.nml"
}
# table FILE: a table's rows without the CPU column
table() { grep '^|' "$1" | cut -d'|' -f1-9,11-; }
study_from "$work/s1"
if "$exe" reference "$work/s1/q.nml" --quiet > reference.txt 2>&1; then pass study-reference; else
    fail study-reference "$(cat reference.txt)"; fi
submitted=$("$exe" sweep "$work/s1/q.nml" --slurm --chunk 2 --submit 2>&1)
ids=$(sed -n 's/^submitted: array job \([0-9]*\), merge job \([0-9]*\) .*/\1 \2/p' <<<"$submitted")
read -r arr mrg <<<"$ids"
if [ -n "$mrg" ] && grep -q '(6 points in 3 tasks)' <<<"$submitted"; then pass study-submit; else
    fail study-submit "$submitted"; fi
if [ -n "$mrg" ] && cluster_wait 120 "$arr" "$mrg"; then pass "study-array-ended ($(($(date +%s) - t0)) s)"
else fail study-array-ended "time limit or no jobs: $submitted"; fi
for t in 1 3 5; do state "study-task-$t" "${arr}_$t" COMPLETED 0:0; done
state study-merge-job "$mrg" COMPLETED 0:0
merged_out=$work/s1/q_points/slurm_merge_$mrg.out
if grep -q '^6 runs finished, 0 failed$' "$merged_out" 2>/dev/null && [ -s s1/q.md ]; then
    pass study-merged; cp s1/q.md slurm_q.md
else fail study-merged "$(cat "$merged_out" 2>&1)"; fi
"$exe" sweep "$work/s1/q.nml" -j 2 --quiet > parallel.txt 2>&1
if [ -s slurm_q.md ] && [ -n "$(table s1/q.md)" ] && [ "$(table slurm_q.md)" = "$(table s1/q.md)" ] \
    && [ "$(table "$merged_out")" = "$(table parallel.txt)" ]; then pass study-slurm-as-parallel
else fail study-slurm-as-parallel "$(diff <(table slurm_q.md) <(table s1/q.md)) $(cat parallel.txt)"; fi

# Again in a fresh results folder, held, half of the tasks cancelled
# before they run: --merge names exactly those, exits 3, and its command
# for Slurm runs only them; the merge then gives the same table.
study_from "$work/s2"
"$exe" sweep "$work/s2/q.nml" --slurm > slurm2.txt 2>&1
held=$(sbatch --parsable --hold "$work/s2/q_points/array.sbatch" 2>&1)
scancel "${held}_2" "${held}_4" "${held}_6" && scontrol release "$held" > /dev/null 2>&1
if [[ "$held" =~ ^[0-9]+$ ]] && cluster_wait 120 "$held"; then pass study-held-array-ended; else
    fail study-held-array-ended "$held $(cat slurm2.txt)"; fi
for t in 1 3 5; do state "study-held-task-$t" "${held}_$t" COMPLETED 0:0; done
# a task cancelled while pending never ran: no output, no record
never=""
for t in 2 4 6; do
    [ -e "s2/q_points/slurm_${held}_$t.out" ] || [ -e "s2/q_points/point_$t.rec" ] && never="$never $t"
done
if [ -z "$never" ] && [ -s s2/q_points/point_5.rec ]; then pass study-cancelled-never-ran; else
    fail study-cancelled-never-ran "tasks$never ran: $(ls s2/q_points)"; fi
(cd s2 && "$exe" sweep q.nml --merge > ../merge2.txt 2>&1)
rc=$?
if [ "$rc" = 3 ] && grep -q '^missing: 3 of 6 points have no current record in .*: 2,4,6$' merge2.txt \
    && grep -q '^3 runs finished, 0 failed$' merge2.txt && [ ! -e s2/q.md ]; then pass study-merge-lists-missing
else fail study-merge-lists-missing "exit $rc: $(cat merge2.txt)"; fi
again=$(sed -n 's/^resubmit (Slurm): sbatch //p' merge2.txt)
if [ "${again%% *}" = "--array=2,4,6" ]; then pass study-resubmit-command; else
    fail study-resubmit-command "'$again' in: $(cat merge2.txt)"; fi
# shellcheck disable=SC2086 # the printed command's words
rerun=$(sbatch --parsable $again 2>&1)
if [[ "$rerun" =~ ^[0-9]+$ ]] && cluster_wait 120 "$rerun"; then pass study-resubmitted-ended; else
    fail study-resubmitted-ended "$rerun"; fi
for t in 2 4 6; do state "study-resubmitted-$t" "${rerun}_$t" COMPLETED 0:0; done
if "$exe" sweep "$work/s2/q.nml" --merge > merge3.txt 2>&1 \
    && [ "$(table s2/q.md)" = "$(table s1/q.md)" ] && [ -n "$(table s2/q.md)" ]; then
    pass study-resumed-as-parallel
else fail study-resumed-as-parallel "$(cat merge3.txt; diff <(table s2/q.md) <(table s1/q.md))"; fi
# another text of the study (a comment): every record is stale, none used
echo "! the tolerances were checked" >> s2/q.nml
"$exe" sweep "$work/s2/q.nml" --merge > merge4.txt 2>&1
rc=$?
if [ "$rc" = 3 ] && [ "$(grep -c '^stale: point [1-6]: computed from another text of the study file' merge4.txt)" = 6 ] \
    && grep -q '^0 runs finished' merge4.txt; then pass study-stale-refused
else fail study-stale-refused "exit $rc: $(cat merge4.txt)"; fi

# A task warned before its time limit (here by `scancel --signal=TERM
# --batch`, as `#SBATCH --signal=B:TERM@120` would: Slurm's own warning
# has a resolution of about a minute): its batch shell passes the signal
# on to the running point, which stops after its step with its checkpoint;
# the task requeues itself and, run again, resumes the point from there.
# Its ERR is within max(10 TOL, 2 x) that of the point run uninterrupted.
for d in s3 s3u; do
    study_from "$work/$d"
    sed -i -e "s#t_end *= *[0-9.e-]*#t_end = 1.0#" -e "s#q_reference.h5#q3_reference.h5#" \
        -e "s#solvers *=.*#solvers = 'radau5'#" -e "s#tolerances *=.*#tolerances = 1.0e-6#" \
        "$work/$d/q.nml"
done
"$exe" reference "$work/s3/q.nml" --quiet > reference3.txt 2>&1 || fail study-requeue-reference \
    "$(cat reference3.txt)"
"$exe" sweep "$work/s3/q.nml" --slurm > slurm3.txt 2>&1
job=$(sbatch --parsable "$work/s3/q_points/array.sbatch" 2>&1)
deadline=$(($(date +%s) + 60))
while [ ! -e s3/q_points/point_1.h5 ] && [ "$(date +%s)" -lt "$deadline" ]; do sleep 0.2; done
sleep 1
warned=$(date +%s)
scancel --signal=TERM --batch "${job}_1" 2>&1
if [[ "$job" =~ ^[0-9]+$ ]] && cluster_wait 300 "$job"; then
    pass "study-requeued-ended ($(($(date +%s) - warned)) s after the warning)"
else fail study-requeued-ended "$job $(cat slurm3.txt)"; fi
state study-requeued-task "${job}_1" COMPLETED 0:0
out=s3/q_points/slurm_${job}_1.out
restarts=$(field "${job}_1" Restarts)
if [ "$restarts" = 1 ] && grep -q 'point 1: stopped by SIGTERM' "$out" \
    && grep -q "resumed at t = .* from $work/s3/q_points/point_1.h5" "$out" \
    && [ -s s3/q_points/point_1.rec ] && [ ! -e s3/q_points/point_1.h5 ]; then
    pass study-requeued-resumed
else fail study-requeued-resumed "Restarts=$restarts; $(cat "$out" 2>&1); $(ls s3/q_points)"; fi
"$exe" sweep "$work/s3u/q.nml" --point 1 > uninterrupted3.txt 2>&1
tols() { sed -n 's/.*: ERR [^ ]* = \([^ ]*\) TOL.*/\1/p' "$1" | head -n 1; }
e_run=$(tols "$out")
e_full=$(tols uninterrupted3.txt)
if [ -n "$e_run" ] && [ -n "$e_full" ] && awk -v a="$e_run" -v b="$e_full" \
    'BEGIN { exit !(a + 0 <= (10 > 2 * b ? 10 : 2 * b)) }'; then
    pass "study-requeued-accuracy (ERR $e_run TOL, uninterrupted $e_full TOL)"
else fail study-requeued-accuracy "ERR '$e_run' TOL, uninterrupted '$e_full' TOL"; fi

# the stop leaves no daemon and no folder (but with FLEXMBS_SLURM_KEEP=1)
cd "$root" || exit 1
cluster_stop
left=""
for pid in $daemons; do _cluster_alive "$pid" && left="$left $pid"; done
if [ -z "$left" ] && { [ ! -e "$cluster_dir" ] || [ "${FLEXMBS_SLURM_KEEP:-0}" = 1 ]; }; then pass "stop ($(($(date +%s) - t0)) s in all)"; else
    fail stop "still running:$left; folder: $(ls -d "$cluster_dir" 2>&1)"; fi
summary
