#!/usr/bin/env bash
# A single-machine Slurm cluster on loopback, for trying tools/farm/slurm_submit.sh
# and for the SlurmTiledRender test. Not for production: one node ("localhost"),
# one partition ("farm"), no accounting, no cgroups, no systemd.
#
#   tools/farm/slurm_local.sh up STATE_DIR      start munged, slurmctld, slurmd; wait for the node;
#                                               prints "export SLURM_CONF=STATE_DIR/slurm.conf"
#   tools/farm/slurm_local.sh status STATE_DIR  daemons alive?, sinfo, squeue
#   tools/farm/slurm_local.sh down STATE_DIR    cancel jobs, stop what "up" started (pid files); idempotent
#
# Everything lives under STATE_DIR: its own munge key and socket, slurm.conf with
# free ports picked at run time, spool/state dirs, logs (STATE_DIR/log/), pid files
# (STATE_DIR/run/). The daemons run as the current user (SlurmUser = SlurmdUser =
# `id -un`): root in CI; as an unprivileged user the jobs run as that user too.
# Needs Debian's slurmctld, slurmd, slurm-client and munge (tools/debian-packages.txt).
# Environment: SLURM_LOCAL_TIMEOUT (seconds to wait for the node, default 60).
set -euo pipefail

usage() {
  echo "usage: $0 up|down|status STATE_DIR" >&2
  exit 2
}
[ $# -eq 2 ] || usage
CMD=$1
case "$CMD" in up|down|status) ;; *) usage ;; esac
mkdir -p "$2" 2>/dev/null || { [ "$CMD" = down ] && exit 0; echo "slurm_local: cannot create $2" >&2; exit 1; }
STATE=$(cd "$2" && pwd -P)
CONF="$STATE/slurm.conf"
MUNGE_DIR="$STATE/munge"
SOCK="$MUNGE_DIR/munge.socket"
RUN="$STATE/run"
LOG="$STATE/log"
PART=farm
TIMEOUT=${SLURM_LOCAL_TIMEOUT:-60}

say() { echo "slurm_local: $*" >&2; }
die() { say "error: $*"; exit 1; }

# The pid in FILE if that process is alive and is the program NAME (guards
# against a pid reused since an earlier run).
live_pid() {
  local file=$1 name=$2 pid
  [ -s "$file" ] || return 1
  pid=$(tr -dc '0-9' <"$file")
  [ -n "$pid" ] && [ -r "/proc/$pid/cmdline" ] || return 1
  tr '\0' ' ' <"/proc/$pid/cmdline" | grep -q "$name" || return 1
  echo "$pid"
}

# Stops the daemon of pid file FILE (program NAME): TERM, then KILL after 10 s.
stop_pid() {
  local file=$1 name=$2 pid
  if pid=$(live_pid "$file" "$name"); then
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 1 100); do
      [ -d "/proc/$pid" ] || break
      # a zombie child of this shell counts as gone
      grep -q '^State:.*Z' "/proc/$pid/status" 2>/dev/null && break
      sleep 0.1
    done
    if [ -d "/proc/$pid" ] && ! grep -q '^State:.*Z' "/proc/$pid/status" 2>/dev/null; then
      say "$name ($pid) ignored TERM: KILL"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$file"
}

# slurmstepd processes of this cluster (they log into our slurmd.log) outlive a
# killed slurmd; they and their jobs are ours, so end them.
stop_stepds() {
  local p fd
  for p in /proc/[0-9]*; do
    [ "$(cat "$p/comm" 2>/dev/null)" = slurmstepd ] || continue
    for fd in "$p"/fd/*; do
      case "$(readlink "$fd" 2>/dev/null)" in
        "$LOG"/*)
          say "ending leftover slurmstepd ${p#/proc/}"
          kill -KILL "${p#/proc/}" 2>/dev/null || true
          break ;;
      esac
    done
  done
}

tails() {
  local f
  for f in "$LOG"/*.log "$LOG"/*.out; do
    [ -s "$f" ] || continue
    echo "----- tail $f" >&2
    tail -n 25 "$f" >&2
  done
}

do_down() {
  if [ -f "$CONF" ] && live_pid "$RUN/slurmctld.pid" slurmctld >/dev/null; then
    # cancel what is queued or running so no job process outlives the cluster
    SLURM_CONF="$CONF" timeout 10 scancel --partition="$PART" >/dev/null 2>&1 || true
    for _ in $(seq 1 50); do
      [ -z "$(SLURM_CONF="$CONF" timeout 5 squeue -h -t running,completing -o %i 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  stop_pid "$RUN/slurmd.pid" slurmd
  stop_pid "$RUN/slurmctld.pid" slurmctld
  stop_stepds
  stop_pid "$RUN/munged.pid" munged
  rm -f "$SOCK" "$SOCK.lock"
}

# Two distinct free TCP ports on 127.0.0.1 (held open together while chosen).
free_ports() {
  if command -v python3 >/dev/null; then
    python3 - <<'EOF'
import socket
s = [socket.socket() for _ in range(2)]
for x in s:
    x.bind(("127.0.0.1", 0))
print(" ".join(str(x.getsockname()[1]) for x in s))
EOF
  else
    local a b
    while :; do
      a=$((20000 + RANDOM % 30000)); b=$((a + 1))
      (exec 3<>"/dev/tcp/127.0.0.1/$a") 2>/dev/null && continue
      (exec 3<>"/dev/tcp/127.0.0.1/$b") 2>/dev/null && continue
      echo "$a $b"; return
    done
  fi
}

do_up() {
  local b t_start=$EPOCHREALTIME
  for b in munged mungekey slurmctld slurmd sinfo scontrol; do
    command -v "$b" >/dev/null || [ -x "/usr/sbin/$b" ] || die "$b not found (apt-get install slurmctld slurmd slurm-client munge)"
  done
  export PATH="$PATH:/usr/sbin:/sbin"
  # leftovers of an earlier run in this STATE_DIR: stop them, start afresh
  do_down
  rm -rf "$MUNGE_DIR" "$RUN" "$LOG" "$STATE/ctld" "$STATE/spool" "$CONF" "$STATE/env"
  mkdir -p "$MUNGE_DIR" "$RUN" "$LOG" "$STATE/ctld" "$STATE/spool"
  chmod 755 "$MUNGE_DIR"  # the socket must be reachable; the key itself is 0600
  # AF_UNIX paths are limited to 107 bytes (slurmstepd sockets live in spool/)
  if [ $((${#STATE} + 40)) -ge 107 ]; then
    die "STATE_DIR path too long for Unix sockets (keep it under 66 characters): $STATE"
  fi

  local user cpus node_hw p1 p2
  user=$(id -un)
  # --- munge: own key, socket, pid, log, seed
  if ! mungekey --create --keyfile="$MUNGE_DIR/munge.key" >/dev/null 2>&1; then
    dd if=/dev/urandom of="$MUNGE_DIR/munge.key" bs=1024 count=1 status=none
  fi
  chmod 600 "$MUNGE_DIR/munge.key"
  setsid munged --foreground --force \
    --socket="$SOCK" --key-file="$MUNGE_DIR/munge.key" --pid-file="$RUN/munged.pid" \
    --log-file="$LOG/munged.log" --seed-file="$MUNGE_DIR/munged.seed" \
    </dev/null >"$LOG/munged.log" 2>&1 &
  echo $! >"$RUN/munged.pid"
  for _ in $(seq 1 50); do [ -S "$SOCK" ] && break; sleep 0.1; done
  if [ ! -S "$SOCK" ] || ! munge -n --socket="$SOCK" | unmunge --socket="$SOCK" >/dev/null 2>&1; then
    tails; do_down; die "munged did not come up (socket $SOCK)"
  fi

  # --- slurm.conf: this machine's CPUs and memory, free ports
  node_hw=$(slurmd -C 2>/dev/null | head -n 1 | sed 's/^NodeName=[^ ]* //')
  cpus=$(sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' <<<"$node_hw")
  [ -n "$cpus" ] || { cpus=$(nproc); node_hw="CPUs=$cpus"; }
  read -r p1 p2 < <(free_ports)
  cat >"$CONF" <<EOF
# Generated by tools/farm/slurm_local.sh: a one-node Slurm cluster on loopback.
ClusterName=vdbmarch
SlurmctldHost=localhost
SlurmctldPort=$p1
SlurmdPort=$p2
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
# cred_expire also sets how long a requeued job waits before it may start
# again (default 120 s); a test cluster requeues within seconds
AuthInfo=socket=$SOCK,cred_expire=5
CredType=cred/munge
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$RUN/slurmctld.pid
SlurmdPidFile=$RUN/slurmd.pid
SlurmctldLogFile=$LOG/slurmctld.log
SlurmdLogFile=$LOG/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
# a test cluster: start the next tasks at once, not batched every few seconds,
# and look at pending jobs every second (a requeued task becomes eligible later)
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000,sched_interval=1
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
InactiveLimit=0
KillWait=5
MinJobAge=600
NodeName=localhost NodeHostname=localhost NodeAddr=127.0.0.1 $node_hw State=UNKNOWN
PartitionName=$PART Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$CONF"

  # --- daemons, in the foreground of background jobs (pids known at once)
  setsid slurmctld -D -c -f "$CONF" </dev/null >"$LOG/slurmctld.out" 2>&1 &
  echo $! >"$RUN/slurmctld.pid"
  setsid slurmd -D -f "$CONF" -N localhost </dev/null >"$LOG/slurmd.out" 2>&1 &
  echo $! >"$RUN/slurmd.pid"

  local t0=$SECONDS state=""
  while [ $((SECONDS - t0)) -lt "$TIMEOUT" ]; do
    live_pid "$RUN/slurmctld.pid" slurmctld >/dev/null || { tails; do_down; die "slurmctld exited"; }
    live_pid "$RUN/slurmd.pid" slurmd >/dev/null || { tails; do_down; die "slurmd exited"; }
    state=$(timeout 5 sinfo -h -n localhost -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.3
  done
  if [ "$state" != idle ]; then
    tails; do_down
    die "node not idle after ${TIMEOUT}s (sinfo state: '${state:-no answer}')"
  fi
  echo "export SLURM_CONF=$CONF" >"$STATE/env"
  say "cluster up in $(awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN{printf "%.1f", b-a}') s: partition $PART, node localhost ($cpus CPUs), ports $p1/$p2, logs in $LOG"
  echo "export SLURM_CONF=$CONF"
}

do_status() {
  local rc=0 d pid
  for d in munged slurmctld slurmd; do
    if pid=$(live_pid "$RUN/$d.pid" "$d"); then echo "$d: running (pid $pid)"; else echo "$d: not running"; rc=1; fi
  done
  if [ $rc -eq 0 ]; then
    SLURM_CONF="$CONF" timeout 10 sinfo || rc=1
    SLURM_CONF="$CONF" timeout 10 squeue || rc=1
    echo "export SLURM_CONF=$CONF"
  fi
  return $rc
}

case "$CMD" in
  up) do_up ;;
  down) do_down ;;
  status) do_status ;;
esac
