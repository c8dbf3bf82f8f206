#!/usr/bin/env bash
# A private single-node Slurm cluster (Debian 12: slurm-wlm 22.05 + munge)
# in a state folder of its own, for the tests and for trying `clayfit batch
# --executor slurm` on one machine (docs/slurm.md).
#
#   scripts/slurm-local.sh start  [STATE_DIR]   # munged, slurmctld, slurmd; waits for the node to be idle
#   scripts/slurm-local.sh stop   [STATE_DIR]   # cancels its jobs, stops exactly the daemons it started
#   scripts/slurm-local.sh status [STATE_DIR]   # what runs (exit 0 when all three run, 3 otherwise)
#
# STATE_DIR: the argument, else $CLAYFIT_SLURM_DIR, else build/slurm.
# `start` writes STATE_DIR/env.sh and prints the same lines on stdout (all
# else goes to stderr), so `eval "$(scripts/slurm-local.sh start)"` or
# `. STATE_DIR/env.sh` point sbatch, squeue, scancel... at this cluster.
# Everything is private: slurm.conf (through SLURM_CONF), ports, state,
# spool, logs, pid files, the munge key and socket. A system-wide Slurm or
# munge (/etc/slurm, ports 6817/6818, /run/munge) is never touched.
# Exit status: 0 done, 1 failure (with the daemons' log tails), 2 usage,
# 77 Slurm or munge is not installed (the tests skip).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
usage() { echo "usage: $0 start|stop|status [STATE_DIR]" >&2; exit 2; }
(($# >= 1 && $# <= 2)) || usage
action=$1
state=${2:-${CLAYFIT_SLURM_DIR:-$here/../build/slurm}}
case $action in start|stop|status) ;; *) usage ;; esac

say() { echo "slurm-local: $*" >&2; }
die() { say "$*"; exit 1; }

for tool in munged slurmctld slurmd sinfo sbatch squeue scancel scontrol; do
  command -v "$tool" >/dev/null || { say "$tool not found: install slurm-wlm and munge (scripts/install-deps.sh)"; exit 77; }
done

mkdir -p "$state"
state="$(cd "$state" && pwd)"
conf=$state/slurm.conf
munge_dir=$state/munge
socket=$munge_dir/munge.socket
# A Unix socket path holds at most 107 bytes.
((${#socket} <= 100)) || die "state folder path too long for munge's socket ($socket): use a shorter STATE_DIR"

pid_munged=$munge_dir/munged.pid
pid_ctld=$state/run/slurmctld.pid
pid_slurmd=$state/run/slurmd.pid
startup_timeout=${CLAYFIT_SLURM_TIMEOUT:-60}

# running PID: the process exists and is not a zombie (a container's pid 1
# may never reap the daemons it inherits).
running() {
  local stat
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
  stat=${stat##*) }
  [ "${stat%% *}" != Z ]
}

# alive PIDFILE NAME: the pid in PIDFILE runs and is the program NAME (a pid
# file left from a crash may name a recycled pid).
alive() {
  local pid
  [ -s "$1" ] || return 1
  pid=$(<"$1")
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$2" ] && running "$pid"
}

# daemon COMMAND...: starts a daemon detached from this script's output and
# lock (a caller such as ctest waits until its pipes close); what it says
# before it logs to its own file goes to log/daemons.out.
daemon() { "$@" 9>&- </dev/null >>"$state/log/daemons.out" 2>&1; }

log_tails() {
  local f
  for f in "$state/log/daemons.out" "$munge_dir/munged.log" "$state/log/slurmctld.log" "$state/log/slurmd.log"; do
    [ -f "$f" ] || continue
    echo "---- last lines of $f" >&2
    tail -n 15 "$f" >&2
  done
}

# port_free PORT: nothing on this machine uses the TCP port (any state).
port_free() { ! ss -Htan "( sport = :$1 )" | grep -q .; }

# pick_ports: two consecutive free ports, away from Slurm's defaults (6817,
# 6818) and below Linux's ephemeral range (32768+); the start is derived from
# the state folder so two clusters (two build trees) rarely probe the same.
pick_ports() {
  local start p i
  start=$(( 20000 + $(printf '%s' "$state" | cksum | cut -d' ' -f1) % 6000 * 2 ))
  for ((i = 0; i < 500; i++)); do
    p=$(( 20000 + (start - 20000 + 2 * i) % 12000 ))
    if port_free "$p" && port_free $((p + 1)); then
      ctld_port=$p
      slurmd_port=$((p + 1))
      return 0
    fi
  done
  die "no two free TCP ports found in 20000-31999"
}

write_conf() {
  local host cpus mem_mb
  host=$(hostname -s)
  cpus=$(nproc)
  mem_mb=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.8 }' /proc/meminfo)
  mkdir -p "$state/log" "$state/run" "$state/ctld" "$state/spool"
  : >"$state/plugstack.conf"
  cat >"$conf" <<EOF
# Written by scripts/slurm-local.sh: a private single-node cluster.
ClusterName=clayfitlocal
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$pid_ctld
SlurmdPidFile=$pid_slurmd
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$state/plugstack.conf
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# Schedules on each job event instead of at most every 3 s (the default):
# 20 one-line array tasks on 2 CPUs take 7-10 s instead of 21-23 s.
SchedulerParameters=batch_sched_delay=0
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$state/log/jobcomp.txt
ReturnToService=2
KillWait=5
MaxArraySize=100001
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

# The munge key is made once per state folder; munged runs as the munge
# user when started by root (as Debian's service does), else as the caller.
start_munged() {
  local owner=$user run=()
  if [ "$(id -u)" -eq 0 ] && getent passwd munge >/dev/null; then
    owner=munge
    run=(runuser -u munge --)
  fi
  mkdir -p "$munge_dir"
  if [ ! -s "$munge_dir/munge.key" ]; then
    (umask 077; dd if=/dev/urandom of="$munge_dir/munge.key" bs=1024 count=1 status=none)
  fi
  chown -R "$owner:" "$munge_dir"
  chmod 0755 "$munge_dir"
  chmod 0600 "$munge_dir/munge.key"
  rm -f "$socket" "$socket.lock" "$pid_munged"
  daemon "${run[@]}" munged --socket="$socket" --key-file="$munge_dir/munge.key" \
    --pid-file="$pid_munged" --log-file="$munge_dir/munged.log" \
    --seed-file="$munge_dir/munged.seed" \
    || { log_tails; die "munged did not start"; }
  alive "$pid_munged" munged || { log_tails; die "munged did not start"; }
}

# wait_until SECONDS WHAT COMMAND...: runs COMMAND every 0.2 s until it
# succeeds; on timeout prints the logs, stops what started and fails.
wait_until() {
  local seconds=$1 what=$2 i
  shift 2
  for ((i = 0; i < seconds * 5; i++)); do
    "$@" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  say "timed out after ${seconds} s waiting for $what"
  log_tails
  stop_daemons
  exit 1
}

node_idle() { [ "$(sinfo -h -N -o '%T' 2>/dev/null)" = idle ]; }

print_env() {
  cat >"$state/env.sh" <<EOF
export SLURM_CONF=$conf
EOF
  cat "$state/env.sh"
}

start() {
  if alive "$pid_munged" munged && alive "$pid_ctld" slurmctld && alive "$pid_slurmd" slurmd; then
    say "already running in $state"
    print_env
    return 0
  fi
  stop_daemons # whatever half of a previous cluster is left
  user=$(id -un)
  pick_ports
  write_conf
  export SLURM_CONF=$conf
  start_munged
  # -c: a fresh controller, without the jobs of a previous run.
  daemon slurmctld -c -f "$conf" || { log_tails; stop_daemons; die "slurmctld did not start"; }
  wait_until "$startup_timeout" "slurmctld to answer" scontrol ping
  daemon slurmd -f "$conf" || { log_tails; stop_daemons; die "slurmd did not start"; }
  wait_until "$startup_timeout" "node $(hostname -s) to be idle in sinfo" node_idle
  say "running in $state (slurmctld port $ctld_port, slurmd port $slurmd_port)"
  print_env
}

# stop_pid PIDFILE NAME: SIGTERM, wait up to 30 s, then SIGKILL.
stop_pid() {
  local pid i
  alive "$1" "$2" || { rm -f "$1"; return 0; }
  pid=$(<"$1")
  kill "$pid" 2>/dev/null || true
  for ((i = 0; i < 150; i++)); do
    running "$pid" || { rm -f "$1"; return 0; }
    sleep 0.2
  done
  say "$2 ($pid) still runs after 30 s: SIGKILL"
  kill -KILL "$pid" 2>/dev/null || true
  rm -f "$1"
}

# cancel_jobs: this cluster's jobs end before its slurmd does (slurmstepd
# would outlive it).
cancel_jobs() {
  local i jobs
  alive "$pid_ctld" slurmctld && [ -f "$conf" ] || return 0
  export SLURM_CONF=$conf
  mapfile -t jobs < <(squeue -h -o %A 2>/dev/null)
  ((${#jobs[@]} > 0)) || return 0
  scancel "${jobs[@]}" 2>/dev/null || true
  for ((i = 0; i < 100; i++)); do
    squeue -h -t PD,CF,R,CG,S,ST -o %A 2>/dev/null | grep -q . || return 0
    sleep 0.2
  done
  say "jobs still ending after 20 s; stopping the daemons anyway"
}

stop_daemons() {
  alive "$pid_slurmd" slurmd && cancel_jobs
  stop_pid "$pid_slurmd" slurmd
  stop_pid "$pid_ctld" slurmctld
  stop_pid "$pid_munged" munged
}

status() {
  local name file up=0
  for name in munged slurmctld slurmd; do
    case $name in
      munged) file=$pid_munged ;; slurmctld) file=$pid_ctld ;; slurmd) file=$pid_slurmd ;;
    esac
    if alive "$file" "$name"; then
      echo "$name: running (pid $(<"$file"))"
      up=$((up + 1))
    else
      echo "$name: not running"
    fi
  done
  if ((up == 3)); then
    export SLURM_CONF=$conf
    echo "SLURM_CONF=$conf"
    sinfo -N -o '%N %T %c %m %P' 2>&1 || true
    return 0
  fi
  return 3
}

# One action at a time per state folder.
exec 9>"$state/.lock"
flock 9
case $action in
  start) start ;;
  stop) stop_daemons; say "stopped ($state)" ;;
  status) status ;;
esac
