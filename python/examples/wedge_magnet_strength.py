#!/usr/bin/env python3
"""Wedge the strength of a magnet and plot the pull on a ball of ferrofluid.

A ball of the paper's material (Langevin law, radius 12 mm) sits 10 mm above
a cylindrical magnet; for each magnetization M of the magnet the magnetic
stage solves the field and gives the total force on the ball. The plot shows
the force against M next to the linearized material's force (chi = chi0),
which grows as M^2 while the Langevin material saturates. Writes a PNG and a
CSV (M in A/m, F_z in N for both materials).

    PYTHONPATH=build/python python3 python/examples/wedge_magnet_strength.py --out wedge.png
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")  # files only: no display needed (notebooks may use their own backend)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import lodestone  # noqa: E402


def ball(count=4000, radius=0.012, centre=(0.0, 0.0, 0.022), seed=1):
    """Material points uniform in a ball (m) carrying n0 times its volume in micro-particles."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    x = d * (radius * rng.uniform(size=count) ** (1 / 3))[:, None] + np.asarray(centre)
    n0 = lodestone.paper_material().number_density
    return x, np.full(count, n0 * 4 / 3 * np.pi * radius ** 3 / count)


def pull(material, magnetizations, x, n):
    """Total magnetic force on the ball (N, z component) for each magnet magnetization (A/m)."""
    grid = lodestone.Grid((-0.04, -0.04, -0.012), 0.003, (27, 27, 20))
    stage = lodestone.MagneticForceStage(grid, material)
    forces = []
    for M in magnetizations:
        magnet = lodestone.CylinderMagnet(lodestone.Pose((0, 0, -0.005)), 0.015, 0.005, (0, 0, M))
        report = stage.run(x, n, magnet)
        if not report.converged:
            raise RuntimeError(f"M = {M:g} A/m: {report.status}")
        forces.append(stage.particle_forces(x, n).sum(axis=0)[2])
    return np.array(forces)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="wedge_magnet_strength.png", help="PNG to write (the CSV goes next to it)")
    parser.add_argument("--steps", type=int, default=8, help="magnetizations in the wedge")
    args = parser.parse_args()

    magnetizations = np.linspace(1e5, 1.2e6, args.steps)
    x, n = ball()
    langevin = pull(lodestone.paper_material(), magnetizations, x, n)
    linear = pull(lodestone.linearized(lodestone.paper_material()), magnetizations, x, n)

    fig, ax = plt.subplots(figsize=(6, 4), dpi=100)
    ax.plot(magnetizations / 1e3, -langevin * 1e3, "o-", label="Langevin (paper's material)")
    ax.plot(magnetizations / 1e3, -linear * 1e3, "s--", label="linearized (chi = chi0)")
    ax.set_xlabel("magnet magnetization M (kA/m)")
    ax.set_ylabel("pull on the ball, -F_z (mN)")
    ax.set_title("Wedge of magnet strength")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out)
    csv_path = args.out.rsplit(".", 1)[0] + ".csv"
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["magnetization_A_per_m", "force_z_langevin_N", "force_z_linear_N"])
        w.writerows(zip(magnetizations, langevin, linear))
    for M, a, b in zip(magnetizations, langevin, linear):
        print(f"M = {M:9.0f} A/m: F_z = {a:+.4e} N (Langevin), {b:+.4e} N (linear)")
    print(f"wrote {args.out} and {csv_path}")


if __name__ == "__main__":
    main()
