#!/usr/bin/env python3
"""`lodestone run --ranks N` against the same run on one process.

Usage: run_ranks_check.py LODESTONE SCENE OUT_DIR RANKS FRAMES [--srun] [LODESTONE RUN OPTIONS]

Runs the scene twice (one process; N processes through --ranks, or with
--srun as a Slurm job of N tasks started by `srun --mpi=pmix`, exit 77 when
no Slurm controller answers) with particle
PLY files per frame and compares, frame by frame: the particle count (equal),
the kinetic, gravitational and elastic energies of stats.json (within 1e-9 of
the largest energy magnitude), the number of field solves (equal) and every
coordinate column of the particle files, each sorted (the processes gather
particles in another order; within 1e-6 m, the files hold float32). Prints
the measured differences; exits 1 when one exceeds its bound.
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    count = 0
    fields = []
    sizes = {"float": "<f4", "int": "<i4", "uchar": "u1"}
    for line in header:
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count = int(words[2])
        elif words[0] == "property" and words[1] != "list":
            fields.append((words[2], sizes[words[1]]))
    return np.frombuffer(data[end:], dtype=np.dtype(fields), count=count)


def run(lodestone, scene, out, frames, extra, slurm_tasks=0):
    if os.path.exists(out):
        shutil.rmtree(out)
    cmd = [lodestone, "run", scene, "--out", out, "--frames", frames, "--outputs", "particles"] + extra
    if slurm_tasks:
        # One job of N tasks; srun starts the N processes through PMIx.
        job = "srun --mpi=pmix " + " ".join(cmd)
        cmd = ["sbatch", "--wait", "-n", str(slurm_tasks), "-o", out + ".log", "--wrap", job]
    print("$ " + " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "stats.json")) as f:
        return json.load(f)


def main():
    lodestone, scene, out, ranks, frames = sys.argv[1:6]
    extra = sys.argv[6:]
    srun = "--srun" in extra
    extra = [e for e in extra if e != "--srun"]
    if srun and subprocess.run(["sinfo"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode != 0:
        print("skipped: no Slurm controller answers (.ci/slurm/start_single_node.sh starts one)")
        return 77
    out = os.path.abspath(out)
    one = run(lodestone, scene, os.path.join(out, "one"), frames, extra)
    if srun:
        many = run(lodestone, scene, os.path.join(out, "ranks"), frames, extra, slurm_tasks=int(ranks))
    else:
        many = run(lodestone, scene, os.path.join(out, "ranks"), frames, extra + ["--ranks", ranks])
    failures = []
    worst_energy = worst_x = 0.0
    solves = 0
    if len(one["frames"]) != len(many["frames"]) or not one["frames"]:
        failures.append("the runs wrote %d and %d frames" % (len(one["frames"]), len(many["frames"])))
    for a, b in zip(one["frames"], many["frames"]):
        frame = a["frame"]
        if a["particles"] != b["particles"]:
            failures.append("frame %d: %d particles, %d with --ranks" % (frame, a["particles"], b["particles"]))
        if len(a["field_solves"]) != len(b["field_solves"]):
            failures.append("frame %d: %d field solves, %d with --ranks"
                            % (frame, len(a["field_solves"]), len(b["field_solves"])))
        solves += len(a["field_solves"])
        ea = [a["energy"][k + "_J"] for k in ("kinetic", "gravitational", "elastic")]
        eb = [b["energy"][k + "_J"] for k in ("kinetic", "gravitational", "elastic")]
        scale = max(abs(e) for e in ea) or 1.0
        worst_energy = max(worst_energy, max(abs(x - y) for x, y in zip(ea, eb)) / scale)
        name = "frame_%04d.ply" % frame
        pa = read_ply(os.path.join(out, "one", name))
        pb = read_ply(os.path.join(out, "ranks", name))
        if len(pa) != len(pb):
            failures.append("frame %d: %s holds %d and %d particles" % (frame, name, len(pa), len(pb)))
            continue
        for c in ("x", "y", "z"):
            d = np.max(np.abs(np.sort(pa[c].astype(np.float64)) - np.sort(pb[c].astype(np.float64))))
            worst_x = max(worst_x, float(d))
    print("%s, %s ranks%s, frames %s: %d frames, %d particles, %d field solves; energies differ by %.3g of the "
          "largest, sorted coordinates by %.3g m at most"
          % (os.path.basename(scene), ranks, " (srun)" if srun else "", frames, len(one["frames"]), one["frames"][-1]["particles"], solves,
             worst_energy, worst_x))
    if worst_energy > 1e-9:
        failures.append("energies differ by %.3g of the largest, more than 1e-9" % worst_energy)
    if worst_x > 1e-6:
        failures.append("particle coordinates differ by %.3g m, more than 1e-6 m" % worst_x)
    for f in failures:
        print("FAIL: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
