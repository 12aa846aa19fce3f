#!/usr/bin/env bash
# A one-node Slurm on this machine, for the tests: munged, slurmctld and
# slurmd (Debian's `munge` and `slurm-wlm`; `make test-cluster` installs
# them) with 2 CPUs, no cgroups, no accounting, all in a private temporary
# folder with ports of its own, so that two clusters on one machine do not
# collide and nothing global (/etc/slurm, /etc/munge, /run/munge) is read
# or changed. See docs/cluster.md.
#
# Sourced (the tests):
#   . test/cluster/slurm.sh
#   cluster_start      # exports SLURM_CONF and FLEXMBS_SLURM_DIR; stops on EXIT, INT, TERM
#   sbatch ...; cluster_wait 60 JOBID...; cluster_stop
# Called (by hand):
#   eval "$(bash test/cluster/slurm.sh start)"   # prints the two exports
#   bash test/cluster/slurm.sh status [DIR]      # exit 0 when all three daemons are up
#   bash test/cluster/slurm.sh stop [DIR]        # DIR defaults to $FLEXMBS_SLURM_DIR
#   bash test/cluster/slurm.sh run CMD [ARGS...] # start, run CMD, stop; CMD's exit status
# FLEXMBS_SLURM_KEEP=1 keeps the folder (logs) after the stop.
#
# Folder layout: slurm.conf, munge/ (key, log, seed; 0700), run/ (munge
# socket, pid files; 0755, as munged requires), state/, spool/, log/ (the
# daemons' logs), and whatever the caller puts there (the tests put their
# jobs' files in work/). Every daemon runs in the foreground as a child
# started here, with FLEXMBS_SLURM_DAEMON=<folder> in its environment: the
# stop signals only processes that carry it (the daemons and the slurmstepd
# they start), by process id.

# The daemons' programs, and the client commands the tests use.
_cluster_commands="munged mungekey munge slurmctld slurmd sbatch squeue sinfo scontrol scancel"

_cluster_say() { echo "slurm.sh: $*" >&2; }

# _cluster_alive PID: the process exists and is not a zombie.
_cluster_alive() {
    local state
    [ -r "/proc/$1/stat" ] || return 1
    state=$(sed -E 's/^[0-9]+ \(.*\) ([A-Za-z]).*/\1/' "/proc/$1/stat" 2>/dev/null) || return 1
    [ -n "$state" ] && [ "$state" != Z ] && [ "$state" != X ]
}

# _cluster_ours DIR PID: the process was started by the cluster of DIR.
_cluster_ours() {
    tr '\0' '\n' 2>/dev/null < "/proc/$2/environ" | grep -qxF "FLEXMBS_SLURM_DAEMON=$1"
}

# _cluster_free_port VAR: set VAR to a TCP port below the ephemeral range
# that nothing on this machine has bound (any state, IPv4 or IPv6) and that
# this cluster has not picked already.
_cluster_free_port() {
    local port hex _
    for _ in $(seq 200); do
        port=$((10000 + RANDOM % 22000))
        hex=$(printf '%04X' "$port")
        if ! grep -qE "^ *[0-9]+: [0-9A-F]+:$hex " /proc/net/tcp /proc/net/tcp6 2>/dev/null \
            && [[ " ${_cluster_ports:-} " != *" $port "* ]]; then
            _cluster_ports="${_cluster_ports:-} $port"
            printf -v "$1" %s "$port"
            return 0
        fi
    done
    return 1
}

# _cluster_log NAME: the tail of a daemon's log files, for a failure message.
_cluster_log() {
    local f
    for f in "$FLEXMBS_SLURM_DIR/log/$1.log" "$FLEXMBS_SLURM_DIR/log/$1.out" \
             "$FLEXMBS_SLURM_DIR/munge/$1.log"; do
        [ -s "$f" ] || continue
        echo "---- last lines of $f" >&2
        tail -n 25 "$f" >&2
    done
}

# _cluster_spawn NAME CMD...: start a daemon in the foreground, in the
# background, marked; its pid goes to run/NAME.child.
_cluster_spawn() {
    local name=$1
    shift
    FLEXMBS_SLURM_DAEMON=$FLEXMBS_SLURM_DIR SLURM_CONF=$FLEXMBS_SLURM_DIR/slurm.conf \
        "$@" < /dev/null > "$FLEXMBS_SLURM_DIR/log/$name.out" 2>&1 &
    echo $! > "$FLEXMBS_SLURM_DIR/run/$name.child"
}

# _cluster_await NAME DEADLINE TEST...: poll TEST (a command) until it
# succeeds; fail when the daemon dies or DEADLINE (epoch seconds) passes.
_cluster_await() {
    local name=$1 deadline=$2 pid
    shift 2
    pid=$(cat "$FLEXMBS_SLURM_DIR/run/$name.child")
    until "$@" >/dev/null 2>&1; do
        if ! _cluster_alive "$pid"; then
            wait "$pid" 2>/dev/null
            _cluster_say "$name did not come up: it exited (status $?)"
            return 1
        fi
        if [ "$(date +%s)" -ge "$deadline" ]; then
            _cluster_say "$name did not come up within ${_cluster_limit:-?} s"
            return 1
        fi
        sleep 0.1
    done
}

_cluster_ctld_up() { scontrol ping 2>/dev/null | grep -q 'is UP'; }
_cluster_node_idle() { [ "$(sinfo -h -N -n "$_cluster_node" -o %T 2>/dev/null)" = idle ]; }

# _cluster_write_conf: slurm.conf for this host, on two new ports.
_cluster_write_conf() {
    local d=$FLEXMBS_SLURM_DIR ctld_port slurmd_port
    _cluster_free_port ctld_port && _cluster_free_port slurmd_port || {
        _cluster_say "no free TCP port found"
        return 1
    }
    : > "$d/plugstack.conf"
    cat > "$d/slurm.conf" <<EOF
# written by test/cluster/slurm.sh: a one-node test cluster in $d
ClusterName=flexmbs$(basename "$d" | tr -cd 'a-z0-9' | tail -c 8)
SlurmctldHost=$_cluster_node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$d/run/munge.socket
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/run/slurmctld.pid
SlurmdPidFile=$d/run/slurmd.pid
SlurmctldLogFile=$d/log/slurmctld.log
SlurmdLogFile=$d/log/slurmd.log
PlugStackConfig=$d/plugstack.conf
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
MinJobAge=900
KillWait=5
NodeName=$_cluster_node NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=test Nodes=$_cluster_node Default=YES MaxTime=INFINITE State=UP
EOF
}

# cluster_start [SECONDS]: start the three daemons (within SECONDS, 60 by
# default) and wait until the node is idle. Exports SLURM_CONF and
# FLEXMBS_SLURM_DIR; when sourced, the daemons stop on EXIT, INT and TERM.
cluster_start() {
    local limit=${1:-60} c deadline attempt d failed
    for c in $_cluster_commands; do
        command -v "$c" >/dev/null 2>&1 || {
            _cluster_say "$c not found: install Debian's slurm-wlm and munge (make test-cluster does)"
            return 1
        }
    done
    _cluster_node=$(hostname -s)
    d=$(mktemp -d "${TMPDIR:-/tmp}/flexmbs-slurm.XXXXXX") || return 1
    export FLEXMBS_SLURM_DIR=$d SLURM_CONF=$d/slurm.conf
    if [ -z "${_cluster_called:-}" ]; then
        trap cluster_stop EXIT
        trap 'exit 130' INT
        trap 'exit 143' TERM
    fi
    # munged wants its socket's folders searchable by all, its key private
    chmod 755 "$d"
    mkdir -m 755 "$d/run" && mkdir -m 700 "$d/munge" && mkdir "$d/state" "$d/spool" "$d/log" \
        || { cluster_stop; return 1; }
    if [ ${#d} -gt 80 ]; then
        _cluster_say "folder $d too long for a socket path: set TMPDIR to a shorter one"
        cluster_stop
        return 1
    fi
    deadline=$(( $(date +%s) + limit ))
    _cluster_limit=$limit
    mungekey --create --keyfile="$d/munge/munge.key" >/dev/null 2>&1 \
        || { _cluster_say "mungekey could not create a key"; cluster_stop; return 1; }
    _cluster_spawn munged munged --foreground --socket="$d/run/munge.socket" \
        --key-file="$d/munge/munge.key" --pid-file="$d/run/munged.pid" \
        --log-file="$d/munge/munged.log" --seed-file="$d/munge/munged.seed"
    if ! _cluster_await munged "$deadline" munge --socket="$d/run/munge.socket" --no-input; then
        _cluster_log munged
        cluster_stop
        return 1
    fi
    # A port taken between the pick and the bind: pick two others.
    for attempt in 1 2 3; do
        _cluster_write_conf || { cluster_stop; return 1; }
        : > "$d/log/slurmctld.log"
        : > "$d/log/slurmd.log"
        _cluster_spawn slurmctld slurmctld -D -i -f "$SLURM_CONF"
        if _cluster_await slurmctld "$deadline" _cluster_ctld_up; then
            _cluster_spawn slurmd slurmd -D -f "$SLURM_CONF"
            if _cluster_await slurmd "$deadline" _cluster_node_idle; then
                return 0
            fi
            failed=slurmd
        else
            failed=slurmctld
        fi
        if [ "$attempt" -lt 3 ] && [ "$(date +%s)" -lt "$deadline" ] \
            && grep -qi 'address already in use' "$d"/log/slurm*.log "$d"/log/slurm*.out 2>/dev/null
        then
            _cluster_say "a port was taken meanwhile; trying two others"
            _cluster_stop_daemons slurmd slurmctld
            continue
        fi
        _cluster_log "$failed"
        [ "$failed" = slurmd ] && sinfo -N >&2 2>&1
        cluster_stop
        return 1
    done
}

# _cluster_stop_daemons NAME...: TERM each named daemon of this cluster,
# wait up to 10 s, then KILL.
_cluster_stop_daemons() {
    local d=$FLEXMBS_SLURM_DIR name pid pids="" deadline
    for name in "$@"; do
        [ -f "$d/run/$name.child" ] || continue
        pid=$(cat "$d/run/$name.child")
        rm -f "$d/run/$name.child"
        _cluster_alive "$pid" && _cluster_ours "$d" "$pid" && kill -TERM "$pid" 2>/dev/null \
            && pids="$pids $pid"
    done
    deadline=$(( $(date +%s) + 10 ))
    for pid in $pids; do
        while _cluster_alive "$pid" && [ "$(date +%s)" -lt "$deadline" ]; do sleep 0.1; done
        _cluster_alive "$pid" && _cluster_ours "$d" "$pid" && kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    return 0
}

# _cluster_descendants PID: the process ids below PID, deepest last.
_cluster_descendants() {
    local child
    for child in $(pgrep -P "$1"); do
        echo "$child"
        _cluster_descendants "$child"
    done
}

# cluster_stop [DIR]: cancel the cluster's jobs, stop its daemons (and any
# slurmstepd left with its job's processes), remove its folder. Safe to
# call twice.
cluster_stop() {
    local d=${1:-${FLEXMBS_SLURM_DIR:-}} pid p deadline
    trap - EXIT INT TERM
    [ -n "$d" ] && [ -d "$d" ] || return 0
    FLEXMBS_SLURM_DIR=$d
    export SLURM_CONF=$d/slurm.conf
    if [ -f "$d/run/slurmctld.child" ] && _cluster_ctld_up; then
        scancel --quiet --user="$(id -un)" 2>/dev/null
        deadline=$(( $(date +%s) + 10 ))
        while [ -n "$(squeue -h -o %i 2>/dev/null)" ] && [ "$(date +%s)" -lt "$deadline" ]; do
            sleep 0.2
        done
    fi
    _cluster_stop_daemons slurmd slurmctld
    # slurmstepd outlives slurmd: its processes and their job's, by id
    for pid in /proc/[0-9]*; do
        pid=${pid#/proc/}
        _cluster_ours "$d" "$pid" || continue
        [ "$pid" = "$(cat "$d/run/munged.child" 2>/dev/null)" ] && continue
        for p in $(_cluster_descendants "$pid") "$pid"; do kill -KILL "$p" 2>/dev/null; done
    done
    _cluster_stop_daemons munged
    if [ "${FLEXMBS_SLURM_KEEP:-0}" = 1 ]; then
        _cluster_say "kept $d"
    else
        rm -rf "$d"
    fi
    unset SLURM_CONF
    return 0
}

# cluster_status [DIR]: the daemons' process ids, ping, and the node; exit
# 0 when all three are up and the node answers.
cluster_status() {
    local d=${1:-${FLEXMBS_SLURM_DIR:-}} name pid ok=0
    [ -n "$d" ] && [ -f "$d/slurm.conf" ] || { _cluster_say "no cluster in '$d'"; return 1; }
    export SLURM_CONF=$d/slurm.conf FLEXMBS_SLURM_DIR=$d
    for name in munged slurmctld slurmd; do
        pid=$(cat "$d/run/$name.child" 2>/dev/null)
        if [ -n "$pid" ] && _cluster_alive "$pid" && _cluster_ours "$d" "$pid"; then
            echo "$name: running (pid $pid)"
        else
            echo "$name: not running"
            ok=1
        fi
    done
    scontrol ping 2>&1 | head -n 1
    sinfo -N -o '%N %T %C' 2>&1 || ok=1
    return $ok
}

# cluster_wait SECONDS JOBID...: wait until none of the jobs is pending,
# running or completing; on time-out print the queue and return 1.
cluster_wait() {
    local deadline=$(( $(date +%s) + $1 )) ids
    shift
    ids=$(IFS=,; echo "$*")
    while [ -n "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ]; do
        if [ "$(date +%s)" -ge "$deadline" ]; then
            _cluster_say "jobs $ids not finished in time:"
            squeue -j "$ids" >&2
            return 1
        fi
        sleep 0.2
    done
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    _cluster_called=1
    case ${1:-} in
        start)
            trap 'cluster_stop; exit 130' INT
            trap 'cluster_stop; exit 143' TERM
            cluster_start "${2:-60}" || exit 1
            trap - INT TERM
            printf 'export SLURM_CONF=%q FLEXMBS_SLURM_DIR=%q\n' "$SLURM_CONF" "$FLEXMBS_SLURM_DIR"
            ;;
        stop) cluster_stop "${2:-}" ;;
        status) cluster_status "${2:-}" ;;
        run)
            shift
            [ $# -gt 0 ] || { echo "usage: $0 run CMD [ARGS...]" >&2; exit 2; }
            trap 'exit 130' INT
            trap 'exit 143' TERM
            trap cluster_stop EXIT
            cluster_start || exit 1
            "$@"
            ;;
        *)
            echo "usage: $0 start [SECONDS] | status [DIR] | stop [DIR] | run CMD [ARGS...]" >&2
            exit 2
            ;;
    esac
fi
