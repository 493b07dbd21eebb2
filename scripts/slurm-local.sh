#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for tests and for trying a job
# array before a real cluster: munged, slurmctld and slurmd, all state, logs
# and pid files in DIR, no cgroups (proctrack/linuxproc, task/none). Needs
# root (slurmd starts jobs as their user) and Debian's slurm-wlm and munge
# (scripts/install-deps.sh).
#
#   scripts/slurm-local.sh start DIR   # configure, start, wait until the node takes jobs
#   export SLURM_CONF=DIR/slurm.conf   # then sbatch, squeue, scancel, sinfo use it
#   scripts/slurm-local.sh stop DIR    # stop the three daemons started in DIR
#
# Ports: SLURM_LOCAL_PORT (default 16817) for slurmctld, the next one for slurmd.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
action=$1
dir=$2

# Stops what start left running, by the pid files in DIR only.
stop() {
  local name pid
  for name in slurmd slurmctld munged; do
    [ -f "$dir/$name.pid" ] || continue
    pid=$(cat "$dir/$name.pid")
    if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
      kill "$pid"
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -0 "$pid" 2>/dev/null && kill -9 "$pid"
    fi
    rm -f "$dir/$name.pid"
  done
}

die() {
  echo "slurm-local: $*" >&2
  for log in "$dir"/munged.log "$dir"/slurmctld.log "$dir"/slurmd.log; do
    [ -f "$log" ] && { echo "--- last lines of $log" >&2; tail -n 15 "$log" >&2; }
  done
  stop
  exit 1
}

case "$action" in
  stop) stop; exit 0 ;;
  start) ;;
  *) usage ;;
esac

[ "$(id -u)" -eq 0 ] || { echo "slurm-local: needs root (slurmd runs jobs as their user)" >&2; exit 1; }
for tool in munged mungekey slurmctld slurmd sinfo; do
  command -v "$tool" >/dev/null ||
    { echo "slurm-local: $tool not found; install slurm-wlm and munge (scripts/install-deps.sh)" >&2; exit 1; }
done

mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
# munged refuses a key or socket directory that others may write to.
chmod 700 "$dir"
mkdir -p "$dir/state" "$dir/spool"
port=${SLURM_LOCAL_PORT:-16817}

rm -f "$dir/munge.key"
mungekey --create --keyfile="$dir/munge.key"
munged --force --key-file="$dir/munge.key" --socket="$dir/munge.socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" || die "munged did not start"

# The node as slurmd sees it (sockets, cores, threads must match), reached on loopback.
node=$(slurmd -C | head -n 1 | sed -e 's/ RealMemory=[0-9]*//')
name=$(echo "$node" | sed -e 's/^NodeName=\([^ ]*\).*/\1/')
cat > "$dir/slurm.conf" <<EOF
ClusterName=comorph-local
SlurmctldHost=$name(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SchedulerParameters=sched_interval=1
MinJobAge=600
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$dir/slurm.conf

slurmctld -f "$SLURM_CONF" -i || die "slurmctld did not start"
slurmd -f "$SLURM_CONF" -N "$name" || die "slurmd did not start"

# By the clock: a sinfo that cannot reach slurmctld takes seconds itself.
deadline=$((SECONDS + 30))
while [ "$SECONDS" -lt "$deadline" ]; do
  state=$(timeout 5 sinfo -h -N -o '%T' 2>/dev/null | head -n 1 || true)
  [ "$state" = idle ] && { echo "slurm-local: node $name idle; export SLURM_CONF=$SLURM_CONF"; exit 0; }
  sleep 0.1
done
die "node $name not idle after 30 s (state: ${state:-none})"
