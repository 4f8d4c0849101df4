#!/bin/bash
# A one-node SLURM cluster on this machine, for trying the templates in this folder and for
# lustre's tests: munged, slurmctld and slurmd on localhost with their configuration, keys, state,
# logs and sockets in one private folder; nothing under /etc is read or changed.
#
#   eval "$(deploy/slurm/test-cluster.sh start DIR)"   # exports SLURM_CONF for sbatch, squeue, …
#   deploy/slurm/bake-array.sh …
#   deploy/slurm/test-cluster.sh stop DIR
#
# Needs Debian's `slurm-wlm` and `munge` (apt-get install slurm-wlm munge) and root (slurmd
# starts jobs as the submitting user). The node is this machine as `slurmd -C` sees it (all its
# CPUs and memory) in the default partition `lustre` and in `short` (a 10-minute limit); ports
# are picked free. `start` waits until the node is idle (at most 60 s) and fails with the
# daemons' logs otherwise; `stop` stops every daemon it started (their pid files are in DIR) and
# leaves DIR with the logs.
set -euo pipefail

usage() {
  echo "usage: $0 start DIR | stop DIR" >&2
  exit 2
}
[ $# -eq 2 ] || usage
cmd=$1 dir=$2

stop() {
  for d in slurmd slurmctld munged; do
    local pidf="$dir/$d.pid"
    if [ -f "$pidf" ]; then
      local pid
      pid=$(cat "$pidf")
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
      rm -f "$pidf"
    fi
  done
}

# A TCP port nobody listens on (from the kernel's ephemeral range).
free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

case "$cmd" in
stop)
  stop
  ;;
start)
  for tool in munged mungekey slurmctld slurmd sbatch; do
    command -v "$tool" >/dev/null || PATH="$PATH:/usr/sbin" command -v "$tool" >/dev/null || {
      echo "$0: $tool not found: apt-get install slurm-wlm munge" >&2
      exit 1
    }
  done
  export PATH="$PATH:/usr/sbin"
  if [ "$(id -u)" != 0 ]; then
    echo "$0: slurmd must run as root to start jobs (running as $(id -un))" >&2
    exit 1
  fi
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  case "$dir" in
  *[[:space:]]* | *'"'* | *"'"*)
    echo "$0: $dir: slurm.conf cannot hold a path with spaces or quotes; give another DIR" >&2
    exit 2
    ;;
  esac
  # A daemon that fails to start stops the ones started before it.
  trap 'echo "$0: starting the cluster failed; logs in $dir" >&2; stop' ERR
  chmod 700 "$dir"
  mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
  chmod 700 "$dir/munge"
  # munge: a fresh key, its socket in DIR (a system munged, if any, is left alone).
  rm -f "$dir/munge/munge.key"
  mungekey --create --keyfile="$dir/munge/munge.key" >/dev/null 2>&1 \
    || dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge/munge.key"
  sock="$dir/munge/munge.socket"
  munged --force --key-file="$dir/munge/munge.key" --socket="$sock" \
    --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munge/seed"
  node=$(slurmd -C | head -1)
  name=$(hostname -s)
  cpus=$(echo "$node" | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p')
  ctl_port=$(free_port)
  d_port=$(free_port)
  cat >"$dir/slurm.conf" <<EOF
# Written by $0: a one-node test cluster.
ClusterName=lustre-test
SlurmctldHost=$name(127.0.0.1)
SlurmctldPort=$ctl_port
SlurmdPort=$d_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1
ReturnToService=2
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=300
$node
PartitionName=lustre Nodes=$name Default=YES MaxTime=INFINITE State=UP
# A partition with a time limit, for trying a request longer than it.
PartitionName=short Nodes=$name MaxTime=00:10:00 State=UP
EOF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$SLURM_CONF" -i
  slurmd -f "$SLURM_CONF"
  for _ in $(seq 600); do
    state=$(sinfo -h -n "$name" -o %t 2>/dev/null || true)
    if [ "$state" = idle ]; then
      trap - ERR
      echo "export SLURM_CONF=$SLURM_CONF"
      echo "# one-node SLURM cluster up: node $name, $cpus CPUs, partition lustre" >&2
      exit 0
    fi
    sleep 0.1
  done
  echo "$0: the node did not become idle in 60 s (state: ${state:-none}); logs:" >&2
  tail -n 20 "$dir"/*.log >&2 || true
  stop
  exit 1
  ;;
*)
  usage
  ;;
esac
