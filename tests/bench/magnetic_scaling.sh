#!/bin/sh
# Memory and time of magnetic scenes whose material fills a small part of a
# large domain: the paper's material (Langevin) as an elastic cube above a
# cylinder magnet, 8 particles per cell, dx = 7.8 mm, 5 substeps of 1e-4 s
# with a field solve each (tolerance 1e-3, the effects planner on, budget
# 1%, field reuse off so that every substep solves). Cases: 1e6 particles in boxes of 129^3 and 1027^3 nodes, 1e7 in the
# 1027^3 box, and two cubes of 5e5 particles at opposite corners of the
# 1027^3 box, each above a magnet of its own, with the planner's patches
# and without them (one active region around both). Each case is one
# `lodestone run` of one frame; its stats.json gives the phases, the first
# (cold) and the mean later (warm) magnetic stage, and the estimated and
# measured peak memory. Two cubes in a 257^3 box, with patches and
# without, price the patches where both fit. ONLY=PREFIX runs the cases
# whose name starts with PREFIX (appending to CSV). With PREV_BUILD_DIR every case is also run by that
# binary (column `binary`); a case a binary refuses is printed and left out.
#   tests/bench/magnetic_scaling.sh BUILD_DIR [CSV] [THREADS] [PREV_BUILD_DIR]
set -eu
. "$(dirname "$0")/run_case.sh"
build=${1:?usage: magnetic_scaling.sh BUILD_DIR [CSV] [THREADS] [PREV_BUILD_DIR]}
csv=${2:-magnetic_scaling.csv}
threads=${3:-2}
prev=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
only=${ONLY:-}
[ -n "$only" ] && [ -s "$csv" ] ||
  echo "binary,case,particles,grid_nodes,field_nodes,patches,mpm_ms_per_substep,magnetic_ms_per_substep,magnetic_cold_s,magnetic_warm_s,estimated_bytes,peak_bytes" > "$csv"
# case, particles, box side (m), bodies (1 or 2), patches (auto/off)
cases="one-body-129 1e6 1.0 1 auto
one-body-1027 1e6 8.0 1 auto
one-body-1027 1e7 8.0 1 auto
two-bodies-1027 1e6 8.0 2 auto
two-bodies-1027-one-box 1e6 8.0 2 off
two-bodies-257 1e6 2.0 2 auto
two-bodies-257-one-box 1e6 2.0 2 off"
binaries="current:$build"
[ -n "$prev" ] && binaries="$binaries previous:$prev"
# The first large run after a pause pays more for fresh memory (its first
# stage took up to twice as long, whichever binary it was): the binaries
# take turns at going first, case by case.
turn=0
echo "$cases" | while read -r name n side bodies patches; do
  case "$name" in "$only"*) ;; *) continue ;; esac
  order=$binaries
  if [ -n "$prev" ] && [ $((turn % 2)) -eq 1 ]; then order="previous:$prev current:$build"; fi
  turn=$((turn + 1))
  python3 - "$n" "$side" "$bodies" "$patches" > "$work/scene.json" <<'PY'
import json, sys
n, side, bodies, patches = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
dx = side / round(side / 0.0078)
half = 0.5 * dx * round((n / bodies / 8) ** (1 / 3))
centres = [(0.0, 0.0)] if bodies == 1 else [(-0.5 * side + 0.5, -0.5 * side + 0.5), (0.5 * side - 0.5, 0.5 * side - 0.5)]
z = 0.35 + half + 0.05 if side < 2 else 1.0 + half
scene = {
    "name": "magnetic-scaling",
    "domain": {"min": [-side / 2, -side / 2, 0], "max": [side / 2, side / 2, side], "dx": dx, "boundary": "separate"},
    "time": {"frames": 1, "fps": 2000, "dt": 1e-4, "field_solve_every": 1},
    "magnetic": {"boundary": "open", "tolerance": 1e-3},
    "planner": dict({"field_reuse": "off"}, **({"patches": "off"} if patches == "off" else {})),
    "materials": [{"name": "ferro", "model": "solid", "density": 2500, "youngs_modulus": 2e5, "poisson_ratio": 0.3,
                   "magnetic": {"law": "paper"}}],
    "bodies": [{"name": "cube%d" % b, "material": "ferro", "shape": "box", "center": [cx, cy, z],
                "half_size": [half, half, half]} for b, (cx, cy) in enumerate(centres)],
    "magnets": [{"shape": "cylinder", "center": [cx, cy, z - half - 0.25], "radius": 1.4 * half, "half_length": 0.15,
                 "magnetization": 2e6} for cx, cy in centres],
    "output": {"png": False, "ply": False}}
print(json.dumps(scene))
PY
  for b in $order; do
    bin=${b%%:*}
    dir=${b#*:}
    run_case "$dir" "$work/scene.json" "$work/out" "$work/log" "$threads" "$bin $name $n" || continue
    python3 - "$work/out/stats.json" "$work/log" "$bin" "$name" >> "$csv" <<'PY'
import json, re, sys
d = json.load(open(sys.argv[1]))
log = open(sys.argv[2]).read()
f, m, g = d["frames"][-1], d["memory"], d["grid"]["dims"]
s, n = f["stages"], f["substeps"]
mpm = 1e3 * (s["p2g_s"] + s["grid_update_s"] + s["g2p_s"]) / n
solves = [x["stage_s"] for x in f["field_solves"]]
warm = sum(solves[1:]) / max(1, len(solves) - 1)
nodes = re.search(r"([0-9.e+]+) field-solve nodes", log)
patches = re.search(r"patches: on \((\d+) patches\)", log)
print(",".join([sys.argv[3], sys.argv[4], str(f["particles"]), str(g[0] * g[1] * g[2]),
                "%.0f" % float(nodes.group(1)) if nodes else "0", patches.group(1) if patches else "1",
                "%.1f" % mpm, "%.1f" % (1e3 * s["magnetic_s"] / n), "%.3f" % solves[0], "%.3f" % warm,
                "%.0f" % m["estimated_peak_bytes"], "%.0f" % m["peak_resident_bytes"]]))
PY
    tail -1 "$csv"
  done
done
echo "wrote $csv"
