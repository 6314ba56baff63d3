#!/bin/sh
# Stops what .ci/slurm/start_single_node.sh started: slurmd, slurmctld, and
# munged when that script started it. Jobs still running are killed with
# slurmd. Leaves the configuration and state for the next start.
set -eu
STATE=/var/lib/lodestone-slurm
stop() {
  if [ -f "$1" ] && pid=$(cat "$1") && kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    i=0
    while kill -0 "$pid" 2>/dev/null && [ $i -lt 50 ]; do sleep 0.2; i=$((i + 1)); done
    echo "stopped $2 (pid $pid)"
  fi
  rm -f "$1"
}
stop "$STATE/slurmd.pid" slurmd
stop "$STATE/slurmctld.pid" slurmctld
if [ -f "$STATE/munged.started" ]; then
  stop /run/munge/munged.pid munged
  rm -f "$STATE/munged.started"
fi
