#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, for the tests of `gi-lab study|sweep
# --emit-jobs slurm` (issue #55, docs/cli.md "Scaling out"): munge, slurmctld and slurmd with a
# slurm.conf written for this host (its real cores and memory; a GPU resource only where
# nvidia-smi lists GPUs), everything in one folder.
#
#   bash scripts/slurm-local.sh start DIR [--owner PID]
#       Installs slurmctld, slurmd, slurm-client and munge when missing (as root with apt-get;
#       otherwise it says how), starts the daemons and waits until the node is idle. Then
#       `SLURM_CONF=DIR/etc/slurm.conf sbatch …` submits to it. With --owner, a watchdog stops
#       the cluster (and removes DIR) as soon as process PID ends, however it ends.
#   bash scripts/slurm-local.sh stop DIR
#       Cancels every job, stops the daemons and removes DIR.
#
# The cluster listens on 127.0.0.1 only, on the first free pair of ports from 16817.
set -euo pipefail

usage() {
  echo "usage: bash scripts/slurm-local.sh start DIR [--owner PID] | stop DIR" >&2
  exit 2
}
[ $# -ge 2 ] || usage
cmd="$1"
dir="$2"
shift 2
owner=""
if [ "${1:-}" = --owner ]; then
  owner="${2:?--owner needs a PID}"
fi
case "$dir" in
  /*) ;;
  *) dir="$PWD/$dir" ;;
esac
conf="$dir/etc/slurm.conf"
self="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"

pid_of() { [ -s "$1" ] && cat "$1" || true; }

# Kills the process of pid file $1 and waits (5 s at most) until it has gone.
stop_pid() {
  local pid
  pid="$(pid_of "$1")"
  [ -n "$pid" ] || return 0
  kill "$pid" 2>/dev/null || return 0
  for _ in $(seq 50); do
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.1
  done
  kill -9 "$pid" 2>/dev/null || true
}

stop() {
  [ -d "$dir" ] || return 0
  if [ -f "$conf" ] && [ -s "$dir/run/slurmctld.pid" ]; then
    # The jobs first (their slurmstepd outlive slurmd by design), then the daemons.
    SLURM_CONF="$conf" scancel --quiet --full --user="$(id -un)" 2>/dev/null || true
    for _ in $(seq 50); do
      [ -z "$(SLURM_CONF="$conf" squeue -h -t running,completing -o %i 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  stop_pid "$dir/run/slurmd.pid"
  stop_pid "$dir/run/slurmctld.pid"
  stop_pid "$dir/run/munged.pid"
  # The watchdog, unless it is the one stopping the cluster.
  [ "$(pid_of "$dir/run/watchdog.pid")" = "$$" ] || stop_pid "$dir/run/watchdog.pid"
  rm -rf "$dir"
}

install_if_missing() {
  local need=()
  command -v slurmctld >/dev/null 2>&1 || need+=(slurmctld)
  command -v slurmd >/dev/null 2>&1 || need+=(slurmd)
  command -v sbatch >/dev/null 2>&1 || need+=(slurm-client)
  command -v munged >/dev/null 2>&1 || need+=(munge)
  [ ${#need[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "scripts/slurm-local.sh: installing ${need[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${need[@]}" >&2
  else
    echo "scripts/slurm-local.sh: Slurm is missing (${need[*]})." >&2
    echo "Install it with: sudo apt-get install -y --no-install-recommends ${need[*]}" >&2
    exit 1
  fi
}

# Is TCP port $1 of 127.0.0.1 taken?
taken() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

start() {
  install_if_missing
  if [ -e "$dir/run/slurmctld.pid" ]; then
    echo "scripts/slurm-local.sh: a cluster already runs in $dir (stop it first)" >&2
    exit 1
  fi
  mkdir -p "$dir"
  chmod 700 "$dir"
  mkdir -p "$dir"/etc "$dir"/state "$dir"/spool "$dir"/log "$dir"/run
  chmod 700 "$dir"/etc "$dir"/run "$dir"/log

  # munge: a key of our own and a socket in DIR (the system's munged is left alone).
  head -c 1024 /dev/urandom >"$dir/etc/munge.key"
  chmod 600 "$dir/etc/munge.key"
  munged --force --key-file="$dir/etc/munge.key" --socket="$dir/run/munge.socket" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/state/munged.seed"

  local port=16817
  while taken "$port" || taken $((port + 1)); do
    port=$((port + 2))
    [ "$port" -lt 17817 ] || { echo "scripts/slurm-local.sh: no free port pair in 16817…17817" >&2; stop; exit 1; }
  done

  # This host as slurmd sees it: its cores, sockets, threads and memory.
  local node hw gres_types="" gres="" gpus=0
  hw="$(slurmd -C | head -1)"
  node="$(printf '%s\n' "$hw" | sed -E 's/^NodeName=([^ ]+).*/\1/')"
  hw="$(printf '%s\n' "$hw" | sed -E 's/^NodeName=[^ ]+ //')"
  if command -v nvidia-smi >/dev/null 2>&1; then
    gpus="$(nvidia-smi -L 2>/dev/null | grep -c '^GPU' || true)"
  fi
  if [ "${gpus:-0}" -gt 0 ]; then
    gres_types="GresTypes=gpu"
    gres="Gres=gpu:$gpus"
    echo "Name=gpu File=/dev/nvidia[0-$((gpus - 1))]" >"$dir/etc/gres.conf"
  fi
  local user
  user="$(id -un)"
  cat >"$conf" <<EOF
# A one-node Slurm for GI Lab's tests, written by scripts/slurm-local.sh.
ClusterName=gilab
SlurmctldHost=$node(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/run/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.txt
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MinJobAge=600
$gres_types
NodeName=$node NodeAddr=127.0.0.1 $hw $gres State=UNKNOWN
PartitionName=lab Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
  slurmctld -f "$conf"
  slurmd -f "$conf" -N "$node"

  if [ -n "$owner" ]; then
    setsid nohup bash -c "while kill -0 $owner 2>/dev/null; do sleep 1; done; exec bash '$self' stop '$dir'" \
      >/dev/null 2>&1 </dev/null &
    echo $! >"$dir/run/watchdog.pid"
  fi

  local state=""
  for _ in $(seq 300); do
    state="$(SLURM_CONF="$conf" sinfo -h -N -o %t 2>/dev/null || true)"
    [ "$state" = idle ] && break
    sleep 0.2
  done
  if [ "$state" != idle ]; then
    echo "scripts/slurm-local.sh: the node did not become idle in 60 s (state '${state:-none}'); logs:" >&2
    tail -n 20 "$dir"/log/*.log >&2 || true
    stop
    exit 1
  fi
  echo "scripts/slurm-local.sh: Slurm runs in $dir (node $node, ports $port-$((port + 1)), $gpus GPU(s)); SLURM_CONF=$conf"
}

case "$cmd" in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
