#!/usr/bin/env bash
# One-node Slurm cluster for tests: `slurm.sh start STATE` installs Debian's slurm-wlm and munge when
# absent, starts munged, slurmctld and slurmd as root and waits until the node is idle;
# `slurm.sh stop STATE` stops exactly the daemons it started, by the PIDs in STATE.
# After start, `export SLURM_CONF=STATE/slurm.conf` before using srun/salloc/sinfo.
set -euo pipefail
cmd=${1:?usage: slurm.sh start|stop STATE}
state=$(mkdir -p "${2:?usage: slurm.sh start|stop STATE}" && cd "$2" && pwd)
export SLURM_CONF=$state/slurm.conf

stop_pidfile() {
  local f=$1
  [ -s "$f" ] || return 0
  local pid; pid=$(cat "$f")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  fi
  rm -f "$f"
}

case $cmd in
start)
  if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
  fi
  mkdir -p "$state/state" "$state/spool"
  ncpu=$(nproc)
  cat > "$SLURM_CONF" <<CONF
ClusterName=groove-ci
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$state/state
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
MinJobAge=300
NodeName=localhost CPUs=$ncpu RealMemory=4000 State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000
CONF
  # munge: reuse a running munged (it is machine-wide), else start one and remember its PID.
  if ! munge -n </dev/null >/dev/null 2>&1; then
    mkdir -p /run/munge && chown munge:munge /run/munge
    [ -s /etc/munge/munge.key ] || { mungekey --create 2>/dev/null || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none; chown munge:munge /etc/munge/munge.key; chmod 400 /etc/munge/munge.key; }
    runuser -u munge -- /usr/sbin/munged --pid-file=/run/munge/munged.pid
    for _ in $(seq 50); do [ -s /run/munge/munged.pid ] && break; sleep 0.1; done
    cp /run/munge/munged.pid "$state/munged.pid"
  fi
  slurmctld
  slurmd -N localhost
  for _ in $(seq 120); do
    if sinfo -h -o '%t' 2>/dev/null | grep -qx idle; then
      echo "slurm: up (SLURM_CONF=$SLURM_CONF)"; exit 0
    fi
    sleep 0.5
  done
  echo "slurm: node did not become idle; see $state/slurmctld.log and $state/slurmd.log" >&2
  exit 1
  ;;
stop)
  stop_pidfile "$state/slurmd.pid"
  stop_pidfile "$state/slurmctld.pid"
  stop_pidfile "$state/munged.pid"
  echo "slurm: stopped"
  ;;
*) echo "usage: slurm.sh start|stop STATE" >&2; exit 2 ;;
esac
