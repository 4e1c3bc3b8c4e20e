#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying the job scripts and for the tests: munged,
# slurmctld and slurmd run as root with their configuration, state, sockets and logs in DIR, on
# the loopback address and on free ports. Needs Debian's slurmctld, slurmd, slurm-client and munge.
#
#   scripts/slurm/local-cluster.sh start DIR   # prints the SLURM_CONF to export for sbatch, squeue ...
#   scripts/slurm/local-cluster.sh stop DIR
#
# Exit status of start: 0 when the node is idle, 77 when it cannot start here (a message says why).
set -euo pipefail
command=${1:-} dir=${2:-}
[ -n "$command" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR" >&2; exit 1; }

cannot() { echo "local-cluster: Slurm cannot start here: $*" >&2; exit 77; }

stop() {
  for pidFile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
    [ -f "$pidFile" ] && kill "$(cat "$pidFile")" 2>/dev/null || true
  done
  # Job steps outlive slurmd for a moment.
  pkill -f "slurmstepd.*$dir" 2>/dev/null || true
  for pidFile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
    for _ in $(seq 50); do
      [ -f "$pidFile" ] && kill -0 "$(cat "$pidFile")" 2>/dev/null || break
      sleep 0.1
    done
  done
}

if [ "$command" = stop ]; then stop; exit 0; fi
[ "$command" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || cannot "it runs the daemons as root, and this is user $(id -un)"
for program in munged slurmctld slurmd sbatch sinfo python3; do
  command -v "$program" > /dev/null || cannot "'$program' is not installed (Debian: slurmctld slurmd slurm-client munge)"
done
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
chmod 711 "$dir" "$dir/munge"

# munge: a fresh key, a socket of its own.
head -c 1024 /dev/urandom > "$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.sock" \
       --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed" \
  || cannot "munged did not start ($(tail -n 3 "$dir/log/munged.log" 2>/dev/null))"

# Two free TCP ports on the loopback.
read -r ctldPort nodePort < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
host=$(hostname -s)
cat > "$dir/slurm.conf" <<CONF
ClusterName=lucent
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctldPort
SlurmdPort=$nodePort
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1024 State=UNKNOWN
PartitionName=lucent Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$SLURM_CONF" || { stop; cannot "slurmctld did not start ($(tail -n 3 "$dir/log/slurmctld.log" 2>/dev/null))"; }
slurmd -f "$SLURM_CONF" || { stop; cannot "slurmd did not start ($(tail -n 3 "$dir/log/slurmd.log" 2>/dev/null))"; }
for _ in $(seq 300); do
  if [ "$(sinfo -h -o %T 2>/dev/null)" = idle ]; then echo "$SLURM_CONF"; exit 0; fi
  sleep 0.1
done
stop
cannot "the node did not come up in 30 s ($(tail -n 3 "$dir/log/slurmctld.log" 2>/dev/null))"
