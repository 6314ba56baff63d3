#!/bin/sh
# Starts a single-node Slurm cluster on this machine (run as root): munged
# with this machine's key, slurmctld and slurmd from a minimal slurm.conf
# naming this host with its CPUs and memory, one partition "lodestone".
# Waits until `sinfo` shows the node idle. Idempotent: daemons already
# running are kept. .ci/slurm/stop_single_node.sh stops them.
#
# Needs the Debian packages slurm-wlm and munge (.ci/deps installs them).
# State, logs and pid files: /var/lib/lodestone-slurm, /var/log/lodestone-slurm.
# The configuration is /etc/slurm/slurm.conf, where Slurm's commands look;
# one this script did not write is left alone (the script stops with an error).
set -eu
if [ "$(id -u)" != 0 ]; then echo "$0: run as root" >&2; exit 1; fi
for c in munged slurmctld slurmd sinfo scontrol; do
  command -v "$c" >/dev/null 2>&1 || { echo "$0: $c not found: apt-get install slurm-wlm munge" >&2; exit 1; }
done
STATE=/var/lib/lodestone-slurm
LOGS=/var/log/lodestone-slurm
CONF=/etc/slurm/slurm.conf
MARK="# Written by lodestone .ci/slurm/start_single_node.sh"
HOST=$(hostname -s)
mkdir -p "$STATE/ctld" "$STATE/d" "$LOGS" /etc/slurm

# munge: one key (a real cluster copies the same key to every node).
if [ ! -s /etc/munge/munge.key ]; then
  mkdir -p /etc/munge
  dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
fi
chown munge:munge /etc/munge/munge.key 2>/dev/null || true
chmod 400 /etc/munge/munge.key
mkdir -p /run/munge /var/lib/munge /var/log/munge
chown munge:munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  if id munge >/dev/null 2>&1; then
    runuser -u munge -- /usr/sbin/munged
  else
    /usr/sbin/munged --force
  fi
  touch "$STATE/munged.started"
  i=0
  until munge -n 2>/dev/null | unmunge >/dev/null 2>&1; do
    i=$((i + 1)); [ $i -lt 50 ] || { echo "$0: munged did not start" >&2; exit 1; }
    sleep 0.2
  done
fi

# slurm.conf from this machine: CPUs and memory as slurmd sees them.
CPUS=$(nproc)
MEM=$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
[ -n "$MEM" ] || MEM=$(awk '/MemTotal/ { print int($2 / 1024) }' /proc/meminfo)
if [ -f "$CONF" ] && ! grep -q "^$MARK" "$CONF"; then
  echo "$0: $CONF exists and was not written by this script; not touching it" >&2
  exit 1
fi
NEW=$(mktemp)
cat > "$NEW" <<CONF
$MARK
ClusterName=lodestone
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
JobRequeue=1
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$LOGS/slurmctld.log
SlurmdLogFile=$LOGS/slurmd.log
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=lodestone Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
changed=1
if [ -f "$CONF" ] && cmp -s "$NEW" "$CONF"; then changed=0; fi
if [ $changed = 1 ]; then mv "$NEW" "$CONF"; chmod 644 "$CONF"; else rm -f "$NEW"; fi

running() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }
if [ $changed = 1 ]; then
  # A new configuration: restart what runs.
  for p in slurmd slurmctld; do
    if running "$STATE/$p.pid"; then kill "$(cat "$STATE/$p.pid")"; sleep 1; fi
  done
fi
running "$STATE/slurmctld.pid" || slurmctld
running "$STATE/slurmd.pid" || slurmd

# Wait for the node to be idle (or mixed/allocated when jobs already run).
i=0
while :; do
  state=$(sinfo -h -N -n "$HOST" -o %T 2>/dev/null | head -n 1 || true)
  case "$state" in
    idle*|mixed*|allocated*) break ;;
    down*|drain*) scontrol update NodeName="$HOST" State=RESUME 2>/dev/null || true ;;
  esac
  i=$((i + 1))
  if [ $i -ge 60 ]; then
    echo "$0: node $HOST is '${state:-unknown}' after 60 s; see $LOGS/slurmctld.log and $LOGS/slurmd.log" >&2
    exit 1
  fi
  sleep 1
done
echo "Slurm up: node $HOST ($CPUS CPUs, $MEM MB) $state in partition lodestone"
