#!/usr/bin/env bash
# A throw-away single-node Slurm cluster for the tests (and for trying `uq-driver slurm` by hand).
#
#   tests/slurm/slurm.sh start DIR   install slurm-wlm + munge if missing (apt-get), then start
#                                    munged, slurmctld and slurmd with everything under DIR;
#                                    prints `SLURM_CONF=DIR/etc/slurm.conf` on its last line
#   tests/slurm/slurm.sh stop DIR    cancel every job of that cluster, stop the three daemons
#                                    by their pid files (idempotent)
#
#   export SLURM_CONF=DIR/etc/slurm.conf   # then sbatch, squeue, sinfo, scontrol, scancel use it
#
# Nothing outside DIR is touched (besides the apt-get install): munged listens on its own socket
# DIR/munge/munge.socket with its own key, slurmctld and slurmd run as root on two free TCP ports
# (SlurmctldPort, SlurmdPort), with state, spool, logs and pid files under DIR. Any system Slurm
# or munge on the machine is left alone. Keep DIR short (unix socket paths are limited to 107
# bytes): the tests use mkdtemp under /tmp.
#
# Exit status of `start`: 0 cluster up (node idle); 77 Slurm cannot be had here (not root,
# no apt-get, install failed): the tests skip, or fail under CI; 1 anything else (see DIR/log/).
set -euo pipefail

die() { echo "slurm.sh: $*" >&2; exit 1; }
unavailable() { echo "slurm.sh: $*" >&2; exit 77; }

SBIN_PATH=/usr/sbin:/sbin:/usr/bin:/bin
export PATH="$PATH:$SBIN_PATH"

have_all() {
  local c
  for c in munged mungekey munge unmunge slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
    command -v "$c" >/dev/null 2>&1 || return 1
  done
}

# apt_get (the waiting apt-get) and its hook apt_installed.
. "$(dirname "${BASH_SOURCE[0]}")/../apt_get.sh"
apt_installed() { have_all; }

install_packages() {
  have_all && return 0
  [ "$(id -u)" = 0 ] || unavailable "slurm-wlm/munge are not installed and we are not root to apt-get them"
  command -v apt-get >/dev/null 2>&1 || unavailable "slurm-wlm/munge are not installed and there is no apt-get"
  echo "slurm.sh: installing slurm-wlm and munge (apt-get)" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt_get update -q || unavailable "apt-get update failed"
  have_all && return 0
  apt_get install -y -q --no-install-recommends slurm-wlm munge \
    || unavailable "apt-get install slurm-wlm munge failed"
  have_all || unavailable "slurm-wlm/munge installed but their commands are missing"
}

# Two free TCP ports (bound on all interfaces, as the daemons do).
free_ports() {
  if command -v python3 >/dev/null 2>&1 && python3 -c '' 2>/dev/null; then
    python3 - <<'EOF'
import socket
socks = []
for _ in range(2):
    s = socket.socket()
    s.bind(("", 0))
    socks.append(s)
print(" ".join(str(s.getsockname()[1]) for s in socks))
EOF
  else
    local a b
    for a in $(seq 26817 2 26999); do
      b=$((a + 1))
      if ! ss -Htln "( sport = :$a or sport = :$b )" 2>/dev/null | grep -q .; then
        echo "$a $b"; return 0
      fi
    done
    die "no free port pair found"
  fi
}

pid_alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

stop_pidfiles() {  # stop_pidfiles FILE...: TERM them all, wait up to 10 s, then KILL
  local f pid pids=() i
  for f in "$@"; do
    [ -s "$f" ] || continue
    pid=$(cat "$f")
    if kill -0 "$pid" 2>/dev/null; then
      kill -TERM "$pid" 2>/dev/null || true
      pids+=("$pid")
    fi
  done
  for i in $(seq 1 100); do
    local alive=0
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  for pid in "${pids[@]}"; do
    if kill -0 "$pid" 2>/dev/null; then
      echo "slurm.sh: pid $pid ignored SIGTERM, killing it" >&2
      kill -KILL "$pid" 2>/dev/null || true
    fi
  done
  rm -f "$@"
}

start() {
  local dir=$1
  [ "$(id -u)" = 0 ] || unavailable "a test Slurm needs root (slurmd runs jobs as root here); we are $(id -un)"
  install_packages
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  # A start that fails half-way stops what it had started.
  trap 'rc=$?; if [ $rc -ne 0 ]; then stop "'"$dir"'" || true; fi; exit $rc' EXIT
  [ ${#dir} -le 60 ] || die "DIR is too long for unix sockets: $dir"
  mkdir -p "$dir"/{etc,munge,state,spool,log,run}
  # munged wants its socket's folders searchable by everyone, the key's folder private.
  chmod 0755 "$dir" "$dir/munge"
  chmod 0700 "$dir"/{etc,state,spool,log,run}

  # munge: own key, socket, pid, log and seed.
  local sock=$dir/munge/munge.socket
  if ! pid_alive "$dir/run/munged.pid"; then
    [ -s "$dir/etc/munge.key" ] || mungekey --create --keyfile="$dir/etc/munge.key" >/dev/null 2>&1 \
      || dd if=/dev/urandom of="$dir/etc/munge.key" bs=1024 count=1 status=none
    chmod 0400 "$dir/etc/munge.key"
    munged --socket="$sock" --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" \
      --key-file="$dir/etc/munge.key" --seed-file="$dir/munge/munged.seed" \
      || die "munged did not start: $(tail -5 "$dir/log/munged.log" 2>/dev/null)"
  fi
  munge -n -S "$sock" | unmunge -S "$sock" >/dev/null \
    || die "munge round trip on $sock failed: $(tail -5 "$dir/log/munged.log" 2>/dev/null)"

  # slurm.conf: one node (this machine, as `slurmd -C` sees it) on loopback, one partition.
  local conf=$dir/etc/slurm.conf host ports ctld_port d_port nodeline
  host=$(hostname -s)
  if [ ! -s "$conf" ]; then
    read -r ctld_port d_port <<<"$(free_ports)"
    nodeline=$(slurmd -C 2>/dev/null | sed -n 's/^NodeName=[^ ]* //p' | head -1)
    [ -n "$nodeline" ] || nodeline="CPUs=$(nproc) RealMemory=$(awk '/MemTotal/ {print int($2/1024)}' /proc/meminfo)"
    # Leave some memory to the OS, else slurmd sees less than configured and drains the node.
    nodeline=$(echo "$nodeline" | awk '{for (i = 1; i <= NF; i++) if ($i ~ /^RealMemory=/) { split($i, a, "="); m = int(a[2] * 0.9); if (m < 1) m = 1; $i = "RealMemory=" m } print}')
    cat >"$conf" <<EOF
# Written by tests/slurm/slurm.sh: a single-node test cluster under $dir
ClusterName=railuq-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
# Schedule at once (the default delays batch jobs by up to 3 s): the tests wait less.
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=600
MaxArraySize=10001
NodeName=$host NodeAddr=127.0.0.1 $nodeline State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
  fi
  export SLURM_CONF=$conf

  if ! pid_alive "$dir/run/slurmctld.pid"; then
    slurmctld -f "$conf" || die "slurmctld did not start: $(tail -20 "$dir/log/slurmctld.log" 2>/dev/null)"
  fi
  if ! pid_alive "$dir/run/slurmd.pid"; then
    slurmd -f "$conf" -N "$host" || die "slurmd did not start: $(tail -20 "$dir/log/slurmd.log" 2>/dev/null)"
  fi

  # Wait (60 s at most) for the node to be idle; resume it if it came up down or drained.
  local i state=""
  for i in $(seq 1 120); do
    state=$(sinfo -h -n "$host" -o '%T' 2>/dev/null | head -1 || true)
    case "$state" in
      idle) break ;;
      down*|drain*|fail*) scontrol update NodeName="$host" State=RESUME >/dev/null 2>&1 || true ;;
    esac
    pid_alive "$dir/run/slurmctld.pid" || die "slurmctld died: $(tail -20 "$dir/log/slurmctld.log" 2>/dev/null)"
    pid_alive "$dir/run/slurmd.pid" || die "slurmd died: $(tail -20 "$dir/log/slurmd.log" 2>/dev/null)"
    sleep 0.5
  done
  [ "$state" = idle ] || die "node $host is '$state', not idle, after 60 s: $(tail -20 "$dir/log/slurmctld.log" 2>/dev/null)"
  echo "slurm.sh: cluster up: node $host idle, slurmctld on port $(sed -n 's/^SlurmctldPort=//p' "$conf")" >&2
  echo "SLURM_CONF=$conf"
  trap - EXIT
}

stop() {
  local dir=$1 i
  [ -d "$dir" ] || return 0
  dir=$(cd "$dir" && pwd)
  export SLURM_CONF=$dir/etc/slurm.conf
  if pid_alive "$dir/run/slurmctld.pid" && [ -s "$SLURM_CONF" ]; then
    # Cancel every job and give the steps a moment to go, so no job outlives the cluster.
    scancel --full --quiet --user=root 2>/dev/null || true
    for i in $(seq 1 40); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
      sleep 0.25
    done
  fi
  stop_pidfiles "$dir/run/slurmd.pid" "$dir/run/slurmctld.pid"
  stop_pidfiles "$dir/run/munged.pid"
}

case "${1:-}" in
  start) [ $# -eq 2 ] || die "usage: $0 start DIR"; start "$2" ;;
  stop) [ $# -eq 2 ] || die "usage: $0 stop DIR"; stop "$2" ;;
  *) echo "usage: $0 start|stop DIR" >&2; exit 2 ;;
esac
