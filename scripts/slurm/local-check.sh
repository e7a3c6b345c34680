#!/bin/bash
# Brings up a throw-away one-node Slurm cluster on this machine (munge and
# slurmctld/slurmd from Debian's slurm-wlm and munge packages, all state in a
# temporary folder, on ports of its own), runs a sweep through submit.sh as a
# job array plus the dependent merge, runs the same sweep unsharded, and
# checks that the merged tables equal the unsharded ones (every column but
# time_s, which differs from run to run). The cluster is torn down on exit.
#
#   scripts/slurm/local-check.sh N COMMAND SCENE [ARGS…]
#
# Exit 0: equal; 1: they differ or a job failed; 77: Slurm cannot be started
# here (not installed, not root) — the caller may skip.
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 N COMMAND SCENE [ARGS…]" >&2
    exit 2
fi
shards=$1
shift
here=$(cd "$(dirname "$0")" && pwd)
for tool in munged slurmctld slurmd sbatch scontrol; do
    if ! command -v "$tool" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$tool" ]; then
        echo "slurm: $tool not installed (Debian: apt-get install slurm-wlm munge)" >&2
        exit 77
    fi
done
if [ "$(id -u)" != 0 ]; then
    echo "slurm: a one-node cluster of root daemons needs root" >&2
    exit 77
fi
export PATH="$PATH:/usr/sbin"
ringmesh=${RINGMESH:-./target/release/ringmesh}
[ -x "$ringmesh" ] || { echo "slurm: $ringmesh not built (cargo build --release)" >&2; exit 1; }

cluster=$(mktemp -d /tmp/ringmesh-slurm.XXXXXX)
cleanup() {
    for pid_file in "$cluster/slurmd.pid" "$cluster/slurmctld.pid" "$cluster/munge/pid"; do
        [ -f "$pid_file" ] && kill "$(cat "$pid_file")" 2>/dev/null || true
    done
    sleep 1
    [ -n "${KEEP_CLUSTER:-}" ] && echo "slurm: kept $cluster" >&2 || rm -rf "$cluster"
}
trap cleanup EXIT
mkdir -p "$cluster"/{state,spool,log,munge,runs}
chmod 700 "$cluster/munge"
head -c 128 /dev/urandom >"$cluster/munge/munge.key"
chmod 600 "$cluster/munge/munge.key"
munged -f --key-file="$cluster/munge/munge.key" --socket="$cluster/munge/sock" \
    --pid-file="$cluster/munge/pid" --log-file="$cluster/munge/log" \
    --seed-file="$cluster/munge/seed"

host=$(hostname -s)
port=$((20000 + RANDOM % 20000))
export SLURM_CONF="$cluster/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=ringmesh-check
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$cluster/munge/sock
CredType=cred/munge
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/log/slurmctld.log
SlurmdLogFile=$cluster/log/slurmd.log
SlurmctldPort=$port
SlurmdPort=$((port + 1))
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=2
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=check Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -i
slurmd
for _ in $(seq 60); do
    sinfo -h -o %t 2>/dev/null | grep -q idle && break
    sleep 1
done
sinfo -h -o %t | grep -q idle || { echo "slurm: the node never became idle" >&2; cat "$cluster/log/"*.log >&2; exit 77; }
echo "slurm: one-node cluster $host up ($(sinfo -h -o '%c CPUs'))"

sharded="$cluster/runs/sharded" whole="$cluster/runs/whole"
merge=$(LOGS="$cluster/log" "$here/submit.sh" "$shards" "$sharded" "$@")
echo "slurm: $shards-task array and merge job $merge submitted"
state=""
for _ in $(seq 1800); do
    state=$(scontrol show job "$merge" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    case $state in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;; esac
    sleep 1
done
if [ "$state" != COMPLETED ]; then
    echo "slurm: the merge job ended $state" >&2
    cat "$cluster/log/"*.out >&2 || true
    exit 1
fi
echo "slurm: merge job $merge COMPLETED"
"$ringmesh" "$@" -o "$whole" >/dev/null
python3 "$here/compare.py" "$whole" "$sharded"
