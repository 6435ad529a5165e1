#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for make test-slurm and for measuring a sharded
# sweep (docs/scale-out.md): Debian's munged, slurmctld and slurmd, every file (munge key and
# socket, slurm.conf, state, logs) in one folder, this host with 2 CPUs, ports of its own. Needs
# root (slurmd starts jobs as their users).
#
#   scripts/slurm/local-cluster.sh COMMAND [ARGS...]
#       start a cluster in a temporary folder, run COMMAND with SLURM_CONF exported (sbatch,
#       squeue ... talk to this cluster), stop the cluster (also when COMMAND fails).
#   source scripts/slurm/local-cluster.sh; cluster_start DIR || ...; ...; cluster_stop
#       the same from a script: cluster_start returns 1 with the reason in $cluster_error when
#       the cluster cannot start; cluster_stop stops exactly the daemons it started.
cluster_pids=()
cluster_error=""

cluster_stop() {
    local pid parent job_pids=() step_pids=()
    # The jobs still on the node, and their slurmstepd, by process id (scontrol listpids of this
    # cluster's slurmd): a job stopped (suspended) when the daemons go would stay forever.
    if [ ${#cluster_pids[@]} -gt 0 ] && [ -n "${SLURM_CONF:-}" ]; then
        while read -r pid _; do
            [[ $pid =~ ^[0-9]+$ ]] || continue
            job_pids+=("$pid")
            parent=$(ps -o ppid= -p "$pid" 2>/dev/null | tr -d ' ' || true)
            if [ -n "$parent" ] && [ "$(ps -o comm= -p "$parent" 2>/dev/null)" = slurmstepd ]; then
                step_pids+=("$parent")
            fi
        done < <(scontrol listpids 2>/dev/null || true)
    fi
    for pid in "${job_pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
    [ ${#job_pids[@]} -gt 0 ] && sleep 1
    for pid in "${step_pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
    for pid in "${cluster_pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    for pid in "${cluster_pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    cluster_pids=()
}

cluster_start() {
    local work=$1 tool
    export PATH=$PATH:/usr/sbin
    for tool in munged slurmctld slurmd sbatch squeue scancel scontrol sinfo; do
        if ! command -v "$tool" >/dev/null; then
            cluster_error="$tool not found (scripts/install-deps.sh installs munge, slurmctld, slurmd, slurm-client)"
            return 1
        fi
    done
    if [ "$(id -u)" -ne 0 ]; then
        cluster_error="slurmd must run as root to start jobs as their users"
        return 1
    fi
    # munge: its own key and socket
    mkdir -p "$work/munge" "$work/state" "$work/spool"
    chmod 700 "$work/munge"
    dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$work/munge/munge.key"
    munged --foreground --force --key-file="$work/munge/munge.key" \
        --socket="$work/munge/munge.sock" --pid-file="$work/munge/munged.pid" \
        --log-file="$work/munge.log" --seed-file="$work/munge/seed" >"$work/munged.out" 2>&1 &
    cluster_pids+=($!)
    for _ in $(seq 50); do [ -S "$work/munge/munge.sock" ] && break; sleep 0.1; done
    if [ ! -S "$work/munge/munge.sock" ]; then
        cluster_error="munged did not start ($(tail -n 1 "$work/munged.out" 2>/dev/null))"
        return 1
    fi
    local host port
    host=$(hostname -s)
    port=$((20000 + RANDOM % 20000))
    cat >"$work/slurm.conf" <<CONF
ClusterName=mesolocal
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/munge.sock
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=600
NodeName=$host CPUs=2 State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF=$work/slurm.conf
    slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
    cluster_pids+=($!)
    slurmd -D -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
    cluster_pids+=($!)
    for _ in $(seq 100); do
        sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && return 0
        sleep 0.2
    done
    cluster_error="the cluster did not come up: $(tail -n 2 "$work/slurmctld.log" "$work/slurmd.log" 2>/dev/null | tr '\n' ' ')"
    return 1
}

# Wait until none of the given job ids is pending or running; 1 after `limit` seconds.
cluster_wait() {
    local limit=$1 id state left
    shift
    for _ in $(seq $((limit * 2))); do
        left=0
        for id in "$@"; do
            state=$(scontrol -o show job "$id" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | sort -u || true)
            echo "$state" | grep -qE 'PENDING|RUNNING|COMPLETING|CONFIGURING|SUSPENDED' && left=1
        done
        [ $left -eq 0 ] && return 0
        sleep 0.5
    done
    return 1
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then # run, not sourced
    set -euo pipefail
    [ $# -ge 1 ] || { echo "usage: $0 COMMAND [ARGS...]" >&2; exit 2; }
    cluster_dir=$(mktemp -d /tmp/meso-slurm.XXXXXX)
    trap 'cluster_stop; rm -rf "$cluster_dir"' EXIT INT TERM
    cluster_start "$cluster_dir" || { echo "local-cluster: $cluster_error" >&2; exit 1; }
    echo "local-cluster: up (SLURM_CONF=$SLURM_CONF)" >&2
    "$@"
fi
