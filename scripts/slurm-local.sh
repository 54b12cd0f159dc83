#!/usr/bin/env bash
# A real single-node Slurm on this machine (munge, slurmctld and slurmd from Debian's
# packages), for the sharded-sweep test and for trying the examples/ scripts before a cluster.
#   bash scripts/slurm-local.sh start    # install (apt-get, as root) if missing, configure, start, wait until the node is idle
#   bash scripts/slurm-local.sh stop     # stop the daemons started by `start`
#   bash scripts/slurm-local.sh status
# Runs as root (the daemons and the jobs run as root on this test node). Configuration:
# /etc/slurm/slurm.conf (written only when absent or written by this script before); state,
# logs and pids in /var/lib/linercav-slurm. No cgroups, no accounting: process tracking by
# /proc, one partition `debug` with this node's CPUs and memory as `slurmd -C` reports them.
set -euo pipefail
state=/var/lib/linercav-slurm
conf=/etc/slurm/slurm.conf
marker="# written by linercav scripts/slurm-local.sh"

need_root() {
  if [ "$(id -u)" -ne 0 ]; then
    echo "slurm-local.sh: run as root (it installs packages and starts system daemons)" >&2
    exit 2
  fi
}

install() {
  if command -v slurmctld >/dev/null && command -v slurmd >/dev/null && command -v munged >/dev/null \
     && command -v sbatch >/dev/null; then
    return
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q >/dev/null
  apt-get install -y -q slurmctld slurmd slurm-client munge >/dev/null
}

configure() {
  mkdir -p "$state/ctld" "$state/d" /etc/slurm
  if [ -f "$conf" ] && ! grep -qF "$marker" "$conf"; then
    echo "slurm-local.sh: $conf exists and was not written by this script; leaving it (and not starting a second Slurm)" >&2
    exit 2
  fi
  local node host
  node=$(slurmd -C | head -1)
  host=$(hostname -s)
  cat > "$conf" <<EOF
$marker
ClusterName=linercav-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/d
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
MaxArraySize=10001
$node State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  # munge: a key if the package did not make one
  if [ ! -s /etc/munge/munge.key ]; then
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
  fi
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
}

running() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

start() {
  need_root
  install
  configure
  if ! munge -n >/dev/null 2>&1; then
    runuser -u munge -- /usr/sbin/munged
    for _ in $(seq 50); do munge -n >/dev/null 2>&1 && break; sleep 0.1; done
  fi
  running "$state/slurmctld.pid" || /usr/sbin/slurmctld
  running "$state/slurmd.pid" || /usr/sbin/slurmd
  # the node registers within seconds; a node left down by an earlier run is resumed
  for _ in $(seq 60); do
    s=$(sinfo -h -N -o '%t' 2>/dev/null | head -1 || true)
    case "$s" in
      idle|mix|alloc) echo "slurm-local: node $(hostname -s) $s"; return 0 ;;
      down*|drain*) scontrol update nodename="$(hostname -s)" state=resume 2>/dev/null || true ;;
    esac
    sleep 1
  done
  echo "slurm-local.sh: the node did not become idle within 60 s; logs in $state" >&2
  sinfo -N >&2 || true
  tail -5 "$state"/slurmctld.log "$state"/slurmd.log >&2 || true
  exit 1
}

stop() {
  need_root
  for d in slurmd slurmctld; do
    if running "$state/$d.pid"; then kill "$(cat "$state/$d.pid")"; fi
  done
  echo "slurm-local: stopped"
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) sinfo -N; squeue ;;
  *) echo "usage: bash scripts/slurm-local.sh start|stop|status" >&2; exit 2 ;;
esac
