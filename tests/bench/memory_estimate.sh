#!/bin/sh
# The memory estimate of `lodestone run` against its measured peak resident
# memory: frame 1 of every example scene at its own resolution and at full
# resolution (domain.full_dx), with the scene's outputs and with every
# output. Prints a table and writes CSV (both from each run's stats.json,
# "memory").
#   tests/bench/memory_estimate.sh BUILD_DIR [CSV]
set -eu
build=${1:?usage: memory_estimate.sh BUILD_DIR [CSV]}
csv=${2:-memory_estimate.csv}
root="$(cd "$(dirname "$0")/../.." && pwd)"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "scene,resolution,outputs,estimated_bytes,peak_bytes,ratio,mpm_grid_bytes,field_solve_bytes,particles_bytes,process_bytes" > "$csv"
for scene in "$root"/examples/scenes/*.json; do
  for resolution in own full; do
    for outputs in scene all; do
      args="--frames 1:1"
      [ "$resolution" = full ] && args="$args --full"
      [ "$outputs" = all ] && args="$args --outputs particles,points,png,fields,surface,mesh,volume,field_lines"
      rm -rf "$work/out"
      # A scene without domain.full_dx has no full resolution.
      if ! "$build/examples/lodestone" run "$scene" --out "$work/out" $args > "$work/log" 2>&1; then
        grep -q "full_dx" "$work/log" && continue
        cat "$work/log" >&2
        exit 1
      fi
      python3 - "$work/out/stats.json" "$(basename "$scene" .json)" "$resolution" "$outputs" >> "$csv" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["memory"]
e, p = m["estimated_peak_bytes"], m["peak_resident_bytes"]
print(",".join([sys.argv[2], sys.argv[3], sys.argv[4], "%.0f" % e, "%.0f" % p, "%.3f" % (p / e),
                "%.0f" % m["estimated_mpm_grid_bytes"], "%.0f" % m["estimated_field_solve_bytes"],
                "%.0f" % m["estimated_particles_bytes"], "%.0f" % m["process_before_bytes"]]))
PY
      tail -1 "$csv"
    done
  done
done
echo "wrote $csv"
