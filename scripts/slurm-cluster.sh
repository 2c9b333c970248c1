#!/usr/bin/env bash
# A private one-node Slurm cluster on this machine, for tests and trying out scripts/slurm-sweep.sh without a
# real cluster: its own munged (own key and socket), slurmctld and slurmd, all state, logs, sockets and PID files
# under DIR, private free TCP ports, no cgroups and no accounting. Other Slurm or munge daemons on the machine
# (a system cluster, another private one) are neither used nor touched.
#
# Usage: scripts/slurm-cluster.sh start  DIR   start the cluster (DIR is created), wait until the node is idle,
#                                              print `export SLURM_CONF=DIR/slurm.conf` on stdout
#        scripts/slurm-cluster.sh stop   DIR   cancel the cluster's jobs, stop exactly the daemons recorded in
#                                              DIR/{slurmd,slurmctld,munged}.pid and wait until they are gone
#        scripts/slurm-cluster.sh status DIR   exit 0 when all three daemons run (and print sinfo)
#
# Clients (sbatch, squeue, sinfo, scancel, ...) use the cluster with SLURM_CONF=DIR/slurm.conf in their
# environment; slurm.conf names the private munge socket (AuthInfo=socket=...), so they need no system munged.
# `start` on a running cluster does nothing; on a partly running or stale DIR it stops the leftovers and starts
# afresh (the job state is not kept across restarts). `stop` on a stopped cluster does nothing.
#
# Requirements: root (slurmd launches jobs as their user), munge and slurm-wlm (slurmctld, slurmd and the client
# commands; tested with Slurm 22.05), ss (iproute2). Environment: SLURM_CLUSTER_TIMEOUT (s, default 30) for the
# node to come up. The daemons run in the foreground (-D) in their own sessions, so their PIDs are known exactly.
set -euo pipefail

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0" >&2; exit 2; }
log() { echo "slurm-cluster: $*" >&2; }
die() { log "$*"; exit 1; }

[ $# -eq 2 ] || usage
action="$1"
case "$action" in start|stop|status) ;; *) usage ;; esac
if [ "$action" = start ]; then mkdir -p "$2"; fi
[ -d "$2" ] || { log "no cluster directory $2"; [ "$action" = stop ] && exit 0; exit 1; }
dir="$(cd "$2" && pwd -P)"
conf="$dir/slurm.conf"
node="localnode"                      # the node's name in this cluster (slurmd -N)
timeout="${SLURM_CLUSTER_TIMEOUT:-30}"
export SLURM_CONF="$conf"

# PID recorded in DIR/NAME.pid if that process still runs and is ours: its command line must name DIR (munged
# --socket=DIR/..., slurmctld/slurmd -f DIR/slurm.conf), so a recycled PID or another cluster's daemon never
# counts (and is never signalled). Prints nothing otherwise.
live_pid() {
  local f="$dir/$1.pid" pid
  [ -s "$f" ] || return 0
  pid="$(tr -dc '0-9' <"$f")"
  [ -n "$pid" ] && [ -r "/proc/$pid/cmdline" ] || return 0
  if tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null | grep -qF -- "$dir/"; then echo "$pid"; fi
}

# Stops the daemon recorded in DIR/NAME.pid: SIGNAL (default TERM), up to 10 s for it to exit, then SIGKILL.
stop_daemon() {
  local name="$1" signal="${2:-TERM}" pid i
  pid="$(live_pid "$name")"
  if [ -n "$pid" ]; then
    kill -"$signal" "$pid" 2>/dev/null || true
    for ((i = 0; i < 100; i++)); do
      [ -d "/proc/$pid" ] || break
      # A zombie child of this shell (only when start and stop run in one process) counts as gone.
      [ "$(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null)" != Z ] || break
      sleep 0.1
    done
    if [ -d "/proc/$pid" ] && [ -n "$(live_pid "$name")" ]; then
      log "$name (pid $pid) still running 10 s after SIG$signal, sending SIGKILL"
      kill -KILL "$pid" 2>/dev/null || true
      sleep 0.2
    fi
  fi
  rm -f "$dir/$name.pid"
}

stop_cluster() {
  # Cancel this cluster's jobs first, while slurmctld and slurmd still run, so that no job step (slurmstepd and
  # the job's processes) outlives the daemons. scancel talks only to the cluster of SLURM_CONF.
  if [ -n "$(live_pid slurmctld)" ] && [ -n "$(live_pid slurmd)" ]; then
    local jobs i
    jobs="$(timeout 10 squeue -h -o %A 2>/dev/null | sort -u | tr '\n' ' ' || true)"
    if [ -n "${jobs// /}" ]; then
      log "cancelling jobs $jobs"
      # shellcheck disable=SC2086
      timeout 10 scancel $jobs 2>/dev/null || true
      for ((i = 0; i < 150; i++)); do   # KillWait=2 in slurm.conf, so steps end within a few seconds
        [ -z "$(timeout 10 squeue -h -o %A 2>/dev/null || true)" ] && break
        sleep 0.1
      done
    fi
  fi
  stop_daemon slurmd
  stop_daemon slurmctld
  stop_daemon munged
}

running() { [ -n "$(live_pid munged)" ] && [ -n "$(live_pid slurmctld)" ] && [ -n "$(live_pid slurmd)" ]; }

node_state() { timeout 3 sinfo -h -n "$node" -o %T 2>/dev/null | head -n 1 || true; }

# A TCP port that no socket on this machine uses (listening or not), other than $1: from 20000 up to the start
# of the kernel's ephemeral port range (32768 by default), from which outgoing connections take theirs.
free_port() {
  local p i low=32768 span
  read -r low _ </proc/sys/net/ipv4/ip_local_port_range 2>/dev/null || true
  span=$((low - 20000))
  [ "$span" -ge 1000 ] || span=40000
  for ((i = 0; i < 200; i++)); do
    p=$((20000 + (RANDOM * 32768 + RANDOM) % span))
    [ "$p" != "${1:-}" ] || continue
    if [ -z "$(ss -Htan "( sport = :$p )" 2>/dev/null)" ]; then echo "$p"; return 0; fi
  done
  die "no free TCP port found"
}

show_logs() {
  local f
  for f in munged.log slurmctld.log slurmctld.stderr slurmd.log slurmd.stderr; do
    [ -s "$dir/$f" ] || continue
    echo "----- $dir/$f (last 20 lines)" >&2
    tail -n 20 "$dir/$f" >&2
  done
}

start_cluster() {
  [ "$(id -u)" = 0 ] || die "must run as root (slurmd launches the jobs)"
  local tool
  for tool in munged munge slurmctld slurmd sinfo squeue scancel ss; do
    command -v "$tool" >/dev/null || die "'$tool' not found (install munge, slurm-wlm, iproute2)"
  done
  if running; then
    log "already running in $dir"
    echo "export SLURM_CONF=$conf"
    return 0
  fi
  stop_cluster                        # leftovers of a partly running or crashed cluster
  rm -rf "$dir/state" "$dir/spool"
  mkdir -p "$dir/state" "$dir/spool"
  rm -f "$dir"/*.log "$dir"/*.stderr "$dir/munge.sock" "$dir/munge.sock.lock"

  # munge: a fresh random key for this cluster only; munged daemonizes once its socket is ready. --force: munged
  # refuses a socket below a directory that not everyone may search (a mktemp -d folder is 0700); here the
  # daemons and clients all run as root, which reaches the socket anyway.
  if [ ! -s "$dir/munge.key" ]; then
    (umask 077 && head -c 1024 /dev/urandom >"$dir/munge.key")
  fi
  chmod 0400 "$dir/munge.key"
  munged --force --socket="$dir/munge.sock" --key-file="$dir/munge.key" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" \
    || { show_logs; stop_cluster; die "munged did not start"; }
  munge -n -S "$dir/munge.sock" | unmunge -S "$dir/munge.sock" >/dev/null \
    || { show_logs; stop_cluster; die "munge credentials do not round-trip through $dir/munge.sock"; }

  # slurmctld and slurmd on two free ports. Another program may take a port between the check and the bind:
  # then a daemon exits with "Address already in use", and the next attempt uses other ports.
  local attempt rc
  for attempt in 1 2 3; do
    rc=0
    launch_slurm || rc=$?
    [ "$rc" != 0 ] || break
    if [ "$rc" = 2 ] && [ "$attempt" -lt 3 ]; then
      log "port taken, retrying with other ports"
      stop_daemon slurmd KILL           # (a slurmd without controller takes seconds to obey SIGTERM)
      stop_daemon slurmctld KILL
      continue
    fi
    show_logs
    stop_cluster
    [ "$rc" = 3 ] && die "node $node not idle after ${timeout} s (see the logs above)"
    die "a daemon exited during start-up (see the logs above)"
  done
  log "cluster up in $dir (slurmctld port $ctld_port, slurmd port $slurmd_port, node $node idle)"
  echo "export SLURM_CONF=$conf"
}

# Writes slurm.conf with two free ports (sets ctld_port, slurmd_port), starts slurmctld and slurmd and waits
# until the node is idle. Returns 0 then; 2 if a daemon could not bind its port, 1 if a daemon exited for
# another reason, 3 after the time-out.
launch_slurm() {
  local host
  host="$(hostname -s)"
  ctld_port="$(free_port)"
  slurmd_port="$(free_port "$ctld_port")"
  cat >"$conf" <<EOF
# Private one-node test cluster written by scripts/slurm-cluster.sh; everything lives in $dir.
ClusterName=jointsim-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
# No cgroups, no accounting, no MPI: nothing the test machine has to provide.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
# CPUs are the only consumable resource: a 1-CPU task does not reserve the node's memory.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
# Start batch jobs at the next scheduler pass (about every second) instead of batching them for up to 3 s.
SchedulerParameters=batch_sched_delay=0
# Short timeouts: a test cluster reacts in seconds. Finished jobs stay visible to squeue for MinJobAge.
ReturnToService=2
SlurmctldTimeout=10
SlurmdTimeout=30
MessageTimeout=10
InactiveLimit=0
KillWait=2
MinJobAge=300
# The node as configured (CPUs=nproc, modest memory), whatever the hardware detection says.
SlurmdParameters=config_overrides
NodeName=$node NodeHostname=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1024 State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
  : >"$dir/plugstack.conf"            # no SPANK plugins (not the system's /etc/slurm/plugstack.conf)

  # The daemons in the foreground (-D), each in its own session (setsid: a Ctrl-C meant for the caller does not
  # reach them), detached from the caller's terminal and pipes. In this non-interactive shell a background job
  # is no process group leader, so setsid execs without forking: $! is the daemon itself (which also writes the
  # same PID to its PidFile).
  setsid slurmctld -D -f "$conf" </dev/null >"$dir/slurmctld.stderr" 2>&1 &
  echo $! >"$dir/slurmctld.pid"
  disown $!                           # (no "Killed" notice from this shell if it is stopped by SIGKILL)
  setsid slurmd -D -f "$conf" -N "$node" </dev/null >"$dir/slurmd.stderr" 2>&1 &
  echo $! >"$dir/slurmd.pid"
  disown $!

  local deadline=$((SECONDS + timeout))
  while :; do
    # A taken port shows at once on stderr (slurmctld may keep trying for a while: no need to wait for it).
    running || sleep 0.2                # (a daemon that just exited: its last words)
    if grep -qi "address already in use" "$dir/slurmctld.stderr" "$dir/slurmd.stderr"; then return 2; fi
    running || return 1
    [ "$(node_state)" != idle ] || return 0
    [ "$SECONDS" -lt "$deadline" ] || return 3
    sleep 0.2
  done
}

case "$action" in
  start) start_cluster ;;
  stop) stop_cluster; log "stopped (daemons of $dir)" ;;
  status)
    if running; then
      log "running: munged $(live_pid munged), slurmctld $(live_pid slurmctld), slurmd $(live_pid slurmd)"
      sinfo
    else
      log "not running in $dir"; exit 1
    fi ;;
esac
