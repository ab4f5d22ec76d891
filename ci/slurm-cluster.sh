#!/usr/bin/env bash
# A one-node Slurm on this machine, for the cluster test (ci/slurm.sh) and
# for trying docs/cluster.md by hand. As root, no systemd needed:
#
#   eval "$(ci/slurm-cluster.sh up)"   # starts it; sets SLURM_CONF
#   sinfo; sbatch ...; squeue; scancel ...
#   ci/slurm-cluster.sh down           # stops it (the one $SLURM_CONF names)
#
# `up` installs Debian's slurm-wlm and munge with apt-get when missing,
# makes a private folder /tmp/ehservo-slurm.XXXXXX holding a fresh munge
# key, munged's socket, slurm.conf (free ports from 16817, the short
# hostname as the only node with all its CPUs, one default partition),
# state, spool and logs, starts munged, slurmctld and slurmd from it and
# waits until the node is idle; it prints `export SLURM_CONF=...` on
# stdout, the rest on stderr. Nothing of /etc or of a Slurm already here is
# touched. It exits 3 (after saying why) when it cannot be done here: not
# root, or the packages cannot be installed. `down [--logs]` stops the
# three daemons by their process ids, removes the folder, and with --logs
# first prints the daemons' last log lines.
set -euo pipefail

say() { echo "$*" >&2; }
cannot() {
  say "$*"
  exit 3
}

# On a failure of `up`: take down what was started, keep the exit code.
up_failed() {
  [ "$1" -eq 0 ] || down_dir "$W" --logs
  exit "$1"
}

up() {
  [ "$(id -u)" -eq 0 ] || cannot "it starts munged, slurmctld and slurmd, which needs root"
  local tools="munged munge runuser slurmctld slurmd sbatch squeue scancel scontrol sinfo"
  lacking() {
    local t
    for t in $tools; do command -v "$t" >/dev/null 2>&1 || return 0; done
    return 1
  }
  if lacking; then
    say "installing slurm-wlm and munge"
    apt_install() {
      timeout 600 env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends slurm-wlm munge >/dev/null 2>&1
    }
    apt_install || { timeout 300 apt-get update -q >/dev/null 2>&1 && apt_install; } || true
    lacking && cannot "slurm-wlm and munge are not installed and apt-get could not install them"
  fi
  id munge >/dev/null 2>&1 || cannot "the munge package did not create the munge user"

  # Two free TCP ports for slurmctld and slurmd (another Slurm may be here).
  port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
  local port="" p
  for p in 16817 17817 18817 19817 20817; do
    if port_free "$p" && port_free $((p + 1)); then port=$p; break; fi
  done
  [ -n "$port" ] || cannot "no free pair of ports for slurmctld and slurmd"

  W=$(mktemp -d /tmp/ehservo-slurm.XXXXXX)
  chmod 755 "$W"
  # From here on a failure takes down what was started.
  trap 'up_failed $?' EXIT
  mkdir -p "$W/munge" "$W/run" "$W/state" "$W/spool" "$W/log"
  : >"$W/pids"
  head -c 1024 /dev/urandom >"$W/munge/munge.key"
  chown -R munge:munge "$W/munge" "$W/run"
  chmod 700 "$W/munge"
  chmod 400 "$W/munge/munge.key"
  chmod 755 "$W/run"
  runuser -u munge -- munged --key-file="$W/munge/munge.key" \
    --socket="$W/run/munge.sock" --pid-file="$W/run/munged.pid" \
    --log-file="$W/munge/munged.log" --seed-file="$W/munge/munged.seed"
  cat "$W/run/munged.pid" >>"$W/pids"

  local host mem
  host=$(hostname -s)
  mem=$(($(free -m | awk '/^Mem:/ {print $2}') * 8 / 10))
  cat >"$W/slurm.conf" <<EOF
ClusterName=ehservo-one-node
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$W/run/munge.sock
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/run/slurmctld.pid
SlurmdPidFile=$W/run/slurmd.pid
SlurmctldLogFile=$W/log/slurmctld.log
SlurmdLogFile=$W/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MinJobAge=600
NodeName=$host CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=one Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$W/slurm.conf
  local d
  for d in slurmctld slurmd; do
    "$d"
    for _ in $(seq 100); do [ -s "$W/run/$d.pid" ] && break; sleep 0.1; done
    [ -s "$W/run/$d.pid" ] || { say "$d wrote no pid file"; exit 1; }
    cat "$W/run/$d.pid" >>"$W/pids"
  done
  for _ in $(seq 60); do
    [ "$(sinfo -h -o %t 2>/dev/null)" = idle ] && break
    sleep 1
  done
  if [ "$(sinfo -h -o %t 2>/dev/null)" != idle ]; then
    say "the node is not idle after 60 s: $(sinfo -h 2>&1)"
    exit 1
  fi
  trap - EXIT
  say "one-node Slurm up in $W (ports $port, $((port + 1))); stop it with: ci/slurm-cluster.sh down"
  sinfo >&2
  echo "export SLURM_CONF=$W/slurm.conf"
}

# Stops the daemons listed in $1/pids and removes $1 (only a folder this
# script made: /tmp/ehservo-slurm.* with a pids file).
down_dir() {
  local W=$1 p
  case "$W" in /tmp/ehservo-slurm.*) ;; *)
    say "$W: not a folder of ci/slurm-cluster.sh"
    return 1
    ;;
  esac
  [ -f "$W/pids" ] || { say "$W: no pids file: not a folder of ci/slurm-cluster.sh"; return 1; }
  if [ "${2:-}" = --logs ]; then
    say "--- the daemons' last log lines ($W/log)"
    tail -n 20 "$W"/log/*.log "$W"/munge/munged.log >&2 2>/dev/null || true
  fi
  # Jobs still queued or running are cancelled first (their steps are not
  # children of slurmd and would outlive it).
  local jobs
  jobs=$(SLURM_CONF=$W/slurm.conf squeue -h -o %A 2>/dev/null | sort -u || true)
  if [ -n "$jobs" ]; then
    # shellcheck disable=SC2086 # one argument per job id
    SLURM_CONF=$W/slurm.conf scancel $jobs 2>/dev/null || true
    for _ in $(seq 60); do
      [ -z "$(SLURM_CONF=$W/slurm.conf squeue -h 2>/dev/null)" ] && break
      sleep 1
    done
  fi
  local pids
  pids=$(cat "$W/pids")
  # slurmd, slurmctld, munged: the reverse of their start.
  for p in $(echo "$pids" | tac); do kill "$p" 2>/dev/null || true; done
  for p in $pids; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null || true
  done
  rm -rf "$W"
}

case "${1:-}" in
  up) up ;;
  down)
    [ -n "${SLURM_CONF:-}" ] || { say "SLURM_CONF is not set: which cluster?"; exit 2; }
    down_dir "$(dirname "$SLURM_CONF")" "${2:-}"
    say "stopped and removed $(dirname "$SLURM_CONF")"
    ;;
  *)
    say "usage: eval \"\$($0 up)\"  |  $0 down [--logs]"
    exit 2
    ;;
esac
