#!/bin/bash
# The farm through a real Slurm controller (.ci/slurm/start_single_node.sh).
# Usage: slurm_farm_test.sh CASE LODESTONE SCENE WORKDIR
#   wedge    a 4-wedge array runs to completion (sbatch --wait); each wedge's
#            frames (PLY bytes) equal those of `lodestone run` of its scene
#   requeue  a task requeued mid-run (scontrol requeue: SIGTERM, back to the
#            queue) resumes from its last checkpoint; its frames equal an
#            uninterrupted run's
#   post     farm-post export-fields as a Slurm array over frame ranges: each
#            frame's field file equals `lodestone export-fields --particles`
#            (every byte but the file's UUID)
# Exits 77 (ctest SKIP_RETURN_CODE) when no slurmctld answers.
set -u
CASE=$1 LODESTONE=$2 SCENE=$3 WORK=$4
if ! command -v sbatch >/dev/null 2>&1 || ! scontrol ping 2>/dev/null | grep -q "is UP"; then
  echo "SKIP: no Slurm controller answers (scontrol ping); start one with .ci/slurm/start_single_node.sh (as root)"
  exit 77
fi
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1

# Frames of run directory $1 equal those of $2, byte for byte; prints the count.
same_frames() {
  local n=0 f
  for f in "$1"/frame_*.ply; do
    [ -f "$f" ] || fail "no frames in $1"
    cmp -s "$f" "$2/$(basename "$f")" || fail "$(basename "$f") of $2 differs from $f"
    n=$((n + 1))
  done
  [ "$(ls "$2"/frame_*.ply | wc -l)" = "$n" ] || fail "$2 has another number of frames than $1 ($n)"
  echo "$n"
}

# Waits (up to $2 s) until job $1 has left the queue.
wait_job() {
  local i=0
  while squeue -h -j "$1" 2>/dev/null | grep -q .; do
    i=$((i + 1)); [ $i -lt $(($2 * 5)) ] || fail "job $1 still queued after $2 s: $(squeue -j "$1")"
    sleep 0.2
  done
}

case "$CASE" in
  wedge)
    "$LODESTONE" wedge "$SCENE" --vary 'magnets[0].magnetization=2e5,5e5' --vary materials.ferrofluid.viscosity=1,5 \
      --out wedges --slurm --wait || fail "lodestone wedge --slurm --wait failed"
    [ "$(ls -d wedges/w0?_* | wc -l)" = 4 ] || fail "expected 4 wedge directories"
    for d in wedges/w0?_*; do
      grep -q '"status": "complete"' "$d/out/lodestone_run.json" || fail "$d did not complete"
      "$LODESTONE" run "$d/scene.json" --out "direct/$(basename "$d")" --checkpoint-every 1 --threads 1 >/dev/null \
        || fail "direct run of $d failed"
      echo "$(basename "$d"): $(same_frames "direct/$(basename "$d")" "$d/out") frames identical to lodestone run"
    done
    for f in summary.csv summary.md contact_sheet.png; do [ -s "wedges/$f" ] || fail "no wedges/$f"; done
    [ "$(grep -c ',complete,' wedges/summary.csv)" = 4 ] || fail "summary.csv does not list 4 complete wedges"
    ;;
  requeue)
    # 40 frames: long enough to requeue it part-way.
    python3 - "$SCENE" long.json <<'PY' || fail "cannot write long.json"
import json, sys
s = json.load(open(sys.argv[1])); s["time"]["frames"] = 40; json.dump(s, open(sys.argv[2], "w"), indent=1)
PY
    "$LODESTONE" wedge long.json --vary 'magnets[0].magnetization=3e5' --out wedges --slurm >/dev/null \
      || fail "submission failed"
    job=$(cat wedges/wedge.jobid)
    d=$(ls -d wedges/w00_*)
    i=0
    until [ -f "$d/out/checkpoint_0005.lsck" ]; do
      i=$((i + 1)); [ $i -lt 300 ] || fail "no checkpoint_0005.lsck after 60 s"; sleep 0.2
    done
    grep -q '"status": "complete"' "$d/out/lodestone_run.json" && fail "the task finished before it was requeued"
    scontrol requeue "${job}_0" || fail "scontrol requeue failed"
    # Slurm holds a requeued job for about two minutes; let it start now.
    sleep 1
    scontrol update JobId="${job}_0" StartTime=now || fail "scontrol update StartTime=now failed"
    wait_job "$job" 120
    grep -q "restart 1" wedges/logs/wedge_0.log || fail "the task was not restarted: $(cat wedges/logs/wedge_0.log)"
    grep -q "interrupted: stopped" wedges/logs/wedge_0.log || fail "the first run was not stopped by the requeue"
    grep -q "resuming from .*checkpoint_" wedges/logs/wedge_0.log || fail "the requeued task did not resume"
    grep -q '"status": "complete"' "$d/out/lodestone_run.json" || fail "the requeued task did not complete"
    grep -E "interrupted|resuming from" wedges/logs/wedge_0.log
    "$LODESTONE" run "$d/scene.json" --out direct --checkpoint-every 1 --threads 1 >/dev/null || fail "direct run failed"
    echo "requeued task: $(same_frames direct "$d/out") frames identical to an uninterrupted lodestone run"
    ;;
  post)
    "$LODESTONE" run "$SCENE" --out cache --no-png --no-ply --threads 1 >/dev/null || fail "run failed"
    "$LODESTONE" farm-post cache --task export-fields --frames-per-task 2 --slurm --wait || fail "farm-post failed"
    n=0
    for p in cache/particles_*.vdb; do
      f=$(basename "$p" | sed 's/particles_/fields_/')
      "$LODESTONE" export-fields "$SCENE" --particles "$p" --out "direct_$f" >/dev/null || fail "export-fields $p failed"
      # Equal bytes but for the file's UUID (bytes 22-57 of an OpenVDB file).
      cmp -s -n 21 "direct_$f" "cache/post/export-fields/$f" && cmp -s -i 57 "direct_$f" "cache/post/export-fields/$f" \
        || fail "$f differs from export-fields --particles $p"
      n=$((n + 1))
    done
    [ $n -ge 5 ] || fail "expected 5 particle files, found $n"
    [ "$(ls cache/post/logs/post-export-fields_*.log | wc -l)" = 3 ] || fail "expected 3 array tasks (5 frames by 2)"
    echo "$n field files through 3 array tasks identical to export-fields --particles"
    ;;
  *) fail "unknown case $CASE" ;;
esac
echo PASS
