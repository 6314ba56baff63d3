#!/usr/bin/env python3
"""Overhead of the Python layer per stage run and per MPM substep at 1e5
particles, against the same work through the C++ API
(lodestone_python_bench, bench_overhead.cpp).

Two measures:
  in-call:    the wall time of the Python call minus the C++ time the call's
              own report gives, relative (stage.run against its
              seconds_total; MPM step against the substep's seconds_total);
  vs C++:     the fastest of ROUNDS x REPEATS Python calls (stage: run plus
              particle_forces) against the fastest of ROUNDS x REPEATS C++
              calls of the same set-up in the C++ program; the rounds
              alternate the two, so that a slow spell of a shared machine
              does not fall on one side only.
Prints a table and writes CSV (kind, measure, seconds or percent).

    PYTHONPATH=build/python python3 python/bench/bench_python_overhead.py \
        --cpp build/python/bench/lodestone_python_bench --repeats 10 --csv python_overhead.csv
"""
import argparse
import csv
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import lodestone


def particles(count, seed=7):
    """count points uniform in a ball of radius 20 mm at (0, 0, 5) mm with the paper's n0."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = 0.02 * rng.uniform(size=count) ** (1.0 / 3.0)
    x = np.ascontiguousarray(d * r[:, None] + np.array([0.0, 0.0, 0.005]))
    n = np.full(count, lodestone.paper_material().number_density * 4.0 / 3.0 * np.pi * 0.02 ** 3 / count)
    return x, n


def stage_times(x, n, repeats):
    sources = lodestone.FieldSourceSet([lodestone.CylinderMagnet(lodestone.Pose((0, 0, -0.03)), 0.02, 0.01, (0, 0, 8e5))])
    stage = lodestone.MagneticForceStage(lodestone.Grid((-0.05, -0.05, -0.03), 0.0025, (41, 41, 33)),
                                         lodestone.paper_material())
    out = np.empty((len(x), 3))
    wall, inner = [], []
    for r in range(-1, repeats):
        t0 = time.perf_counter()
        report = stage.run(x, n, sources)
        t_run = time.perf_counter() - t0
        stage.particle_forces(x, n, out=out)
        t = time.perf_counter() - t0
        if r >= 0:
            wall.append(t)  # run + particle forces, as the C++ program times them
            inner.append((t_run, report.seconds_total))  # the run alone against its own C++ total
    return wall, inner


def mpm_times(repeats):
    settings = lodestone.MpmSettings(lodestone.Grid((-0.05, -0.05, -0.05), 0.0025, (41, 41, 41)))
    settings.fixed_dt = 2e-5
    solver = lodestone.MpmSolver(settings)
    m = solver.add_material(lodestone.neo_hookean_solid(2e5, 0.3, 1000.0, lodestone.paper_material()))
    solver.emit(lodestone.Shape.box(lodestone.Pose((0, 0, 0.005)), (0.029, 0.029, 0.029)), m)
    solver.add_magnet(lodestone.CylinderMagnet(lodestone.Pose((0, 0, -0.04)), 0.02, 0.005, (0, 0, 8e5)),
                      boundary="separate")
    wall, inner = [], []
    for r in range(-1, repeats):
        t0 = time.perf_counter()
        report = solver.step(2e-5)
        t = time.perf_counter() - t0
        if r >= 0:
            wall.append(t)
            inner.append((t, report["seconds_total"]))
    return wall, inner, solver.particle_count


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cpp", required=True, help="path of lodestone_python_bench")
    parser.add_argument("--particles", type=int, default=100000)
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--csv", default="python_overhead.csv")
    args = parser.parse_args()

    x, n = particles(args.particles)
    cpp_times = {}
    stage_wall, stage_inner, mpm_wall, mpm_inner = [], [], [], []
    for _ in range(args.rounds):
        with tempfile.TemporaryDirectory() as tmp:
            x.tofile(f"{tmp}/x.f64")
            n.tofile(f"{tmp}/n.f64")
            cpp = subprocess.run([args.cpp, f"{tmp}/x.f64", f"{tmp}/n.f64", str(args.repeats)], check=True,
                                 capture_output=True, text=True)
        for line in cpp.stdout.splitlines():
            kind, _, seconds = line.split(",")
            cpp_times.setdefault(kind, []).append(float(seconds))
        wall, inner = stage_times(x, n, args.repeats)
        stage_wall += wall
        stage_inner += inner
        wall, inner, mpm_count = mpm_times(args.repeats)
        mpm_wall += wall
        mpm_inner += inner

    rows = []
    print(f"{args.particles} stage particles, {mpm_count} MPM particles, {args.rounds} x {args.repeats} repeats (fastest and median)")
    print(f"{'':10} {'C++ s':>10} {'Python s':>10} {'vs C++':>8} {'in-call':>8}")
    for kind, wall, inner in (("stage_run", stage_wall, stage_inner), ("mpm_step", mpm_wall, mpm_inner)):
        c = cpp_times[kind]
        vs_cpp = 100.0 * (min(wall) - min(c)) / min(c)
        in_call = 100.0 * statistics.median([(w - i) / i for w, i in inner])
        print(f"{kind:10} {min(c):10.4f} {min(wall):10.4f} {vs_cpp:7.2f}% {in_call:7.3f}%   "
              f"(median C++ {statistics.median(c):.4f} s, Python {statistics.median(wall):.4f} s)")
        rows += [(kind, "cpp_fastest_s", min(c)), (kind, "python_fastest_s", min(wall)),
                 (kind, "cpp_median_s", statistics.median(c)), (kind, "python_median_s", statistics.median(wall)),
                 (kind, "overhead_vs_cpp_percent", vs_cpp), (kind, "overhead_in_call_percent", in_call)]
    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["kind", "measure", "value"])
        w.writerows(rows)
    print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
