#!/usr/bin/env bash
# A private single-node Slurm cluster in one directory, for testing examples/slurm_campaign.sh:
#
#   tools/slurm-single-node.sh start DIR   # munged, slurmctld, slurmd; prints SLURM_CONF=...
#   SLURM_CONF=DIR/slurm.conf sbatch --wait ...
#   tools/slurm-single-node.sh stop DIR
#
# Everything (configuration, munge key and socket, state, logs, pid files) lives in DIR, on
# free ports, so it runs beside any other Slurm. Needs Debian's slurm-wlm (slurmctld,
# slurmd, munge) and root (slurmd starts the jobs).
set -euo pipefail
cmd=${1:?start or stop}
dir=$(realpath -m "${2:?directory}")

stop() {
  for p in slurmd slurmctld munged; do
    if [ -f "$dir/$p.pid" ]; then kill "$(cat "$dir/$p.pid")" 2>/dev/null || true; fi
  done
  sleep 0.5
  for p in slurmd slurmctld munged; do
    if [ -f "$dir/$p.pid" ]; then kill -9 "$(cat "$dir/$p.pid")" 2>/dev/null || true; rm -f "$dir/$p.pid"; fi
  done
}

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

case "$cmd" in
stop) stop ;;
start)
  for b in munged slurmctld slurmd sbatch; do
    command -v "$b" >/dev/null || { echo "missing $b (Debian: apt-get install slurm-wlm)" >&2; exit 3; }
  done
  mkdir -p "$dir/state" "$dir/spool" "$dir/log"
  chmod 700 "$dir"
  dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge.key"
  munged --key-file="$dir/munge.key" --socket="$dir/munge.sock" \
    --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" \
    --seed-file="$dir/munge.seed" --force
  host=$(hostname -s)
  cpus=$(nproc)
  mem=$(awk '/MemTotal/ {print int($2/1024/2)}' /proc/meminfo)
  cat > "$dir/slurm.conf" <<CONF
ClusterName=tmrotor-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.sock
CredType=cred/munge
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$dir/slurm.conf" -i
  slurmd -f "$dir/slurm.conf"
  for _ in $(seq 1 60); do
    if sinfo -h -o %t 2>/dev/null | grep -q '^idle'; then echo "SLURM_CONF=$dir/slurm.conf"; exit 0; fi
    sleep 0.5
  done
  echo "the private Slurm did not come up; logs in $dir/log" >&2
  sinfo >&2 || true
  stop
  exit 4
  ;;
*) echo "usage: $0 start|stop DIR" >&2; exit 2 ;;
esac
