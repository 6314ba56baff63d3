#!/bin/sh
# Memory and time per substep of the MPM grid against particle count (1e5 to
# 1e7 particles on a 129^3 grid) and against domain size at fixed material
# (1e6 particles in boxes of 129^3 to 1027^3 nodes; 1e7 particles in the
# 1027^3 box; 1e6 particles in two blocks at opposite corners of the 1027^3
# box, series `apart`), without magnetism: an elastic block (Neo-Hookean, 8 particles
# per cell, dx = 7.8 mm) falling for 25 substeps of 5e-5 s (one particle
# reordering among them, as in any longer run). Each case is one
# `lodestone run` of one frame; its stats.json gives the substep's phases and
# the estimated and measured peak memory. With PREV_BUILD_DIR, every case is
# run by both binaries in turn (column `binary`); a case a binary refuses is
# printed and left out of the CSV. Prints a table and writes CSV.
#   tests/bench/scaling.sh BUILD_DIR [CSV] [THREADS] [PREV_BUILD_DIR]
set -eu
. "$(dirname "$0")/run_case.sh"
build=${1:?usage: scaling.sh BUILD_DIR [CSV] [THREADS] [PREV_BUILD_DIR]}
csv=${2:-scaling.csv}
threads=${3:-2}
prev=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "binary,series,particles_target,particles,grid_nodes,substeps,ms_per_substep,p2g_ms,grid_ms,g2p_ms,estimated_bytes,peak_bytes" > "$csv"
# series, particles, box side (m): the grid has side/0.0078 + 1 nodes an axis
cases="particles 1e5 1.0
particles 1e6 1.0
particles 1e7 1.0
domain 1e6 1.0
domain 1e6 2.0
domain 1e6 3.0
domain 1e6 4.0
domain 1e6 8.0
domain 1e7 8.0
apart 1e6 8.0"
binaries="current:$build"
[ -n "$prev" ] && binaries="$binaries previous:$prev"
echo "$cases" | while read -r series n side; do
  python3 - "$n" "$side" "$series" > "$work/scene.json" <<'PY'
import json, sys
n, side, apart = float(sys.argv[1]), float(sys.argv[2]), sys.argv[3] == "apart"
dx = side / round(side / 0.0078)
half = 0.5 * dx * round((n / (2 if apart else 1) / 8) ** (1 / 3))
corners = [[0.5, 0.5, 0.1 + half + 2 * dx]]
if apart:
    corners = [[0.2 + half, 0.2 + half, 0.1 + half + 2 * dx], [side - 0.2 - half, side - 0.2 - half, side - 0.2 - half]]
print(json.dumps({
    "name": "scaling", "domain": {"min": [0, 0, 0], "max": [side, side, side], "dx": dx},
    "time": {"frames": 1, "fps": 800, "dt": 5e-5},
    "materials": [{"name": "jelly", "model": "solid", "density": 1000, "youngs_modulus": 2e4, "poisson_ratio": 0.4}],
    "bodies": [{"name": "block%d" % b, "material": "jelly", "shape": "box",
                "center": c, "half_size": [half, half, half]} for b, c in enumerate(corners)],
    "output": {"png": False, "ply": False}}))
PY
  for b in $binaries; do
    name=${b%%:*}
    dir=${b#*:}
    run_case "$dir" "$work/scene.json" "$work/out" "$work/log" "$threads" "$name $series $n $side" || continue
    python3 - "$work/out/stats.json" "$name" "$series" "$n" >> "$csv" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f, m, g = d["frames"][-1], d["memory"], d["grid"]["dims"]
s, n = f["stages"], f["substeps"]
per = lambda k: 1e3 * s[k] / n
print(",".join([sys.argv[2], sys.argv[3], sys.argv[4], str(f["particles"]), str(g[0] * g[1] * g[2]), str(n),
                "%.2f" % (per("p2g_s") + per("grid_update_s") + per("g2p_s")), "%.2f" % per("p2g_s"),
                "%.2f" % per("grid_update_s"), "%.2f" % per("g2p_s"), "%.0f" % m["estimated_peak_bytes"],
                "%.0f" % m["peak_resident_bytes"]]))
PY
    tail -1 "$csv"
  done
done
echo "wrote $csv"
