"""Plots for the documentation, from the measured numbers in docs/ (run with
Debian's python3-matplotlib: python3 docs/plots.py). Not part of the build."""
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

here = os.path.dirname(os.path.abspath(__file__))

# Sphere in a uniform field (docs/physics.md section 6): relative error of the
# mean interior H against the closed form, by sphere radius in cells.
a_dx = [3, 4, 6, 8, 12]
errors = {
    "Langevin, H0 = 1e3 A/m (and linear)": [7.8, 5.8, 4.2, 3.3, 2.3],
    "Langevin, H0 = 1e5 A/m": [5.8, 4.1, 3.0, 2.3, 1.6],
    "Langevin, H0 = 1e6 A/m": [1.7, 0.54, 0.40, 0.32, 0.22],
}
fig, ax = plt.subplots(figsize=(6, 4.2), dpi=110)
for label, e in errors.items():
    ax.loglog(a_dx, e, "o-", label=label)
ref = [7.8 * 3 / x for x in a_dx]
ax.loglog(a_dx, ref, "k--", lw=0.8, label="first order")
ax.set_xlabel("sphere radius / dx")
ax.set_ylabel("error of interior H, % of (H0 - H_in)")
ax.set_title("Field solve: sphere in a uniform field")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "sphere_convergence.png"))

# Field-solve time (docs/data): 128^3 solves at H0 = 1e5 A/m, multigrid at
# three tolerances and Jacobi, against the 0.4 s (cold) and 0.2 s (warm) targets.
def rows(name):
    with open(os.path.join(here, "data", name)) as f:
        return list(csv.DictReader(f))

def pick(rs, body, start, tol):
    for r in rs:
        if (r["body"] == body and r["start"] == start and r["nodes_per_axis"] == "128"
                and float(r["H0_A_per_m"]) == 1e5 and float(r.get("tolerance") or 1e-8) == tol):
            return float(r["seconds_solve"])
    return float("nan")

mg = rows("bench_field_solve_multigrid.csv") + rows("bench_field_solve_tolerance.csv")
jac = rows("bench_field_solve_jacobi.csv")
cases = [(b, s) for b in ("sphere", "cube") for s in ("cold", "warm")]
series = [("Jacobi-PCG, 1e-8", jac, 1e-8), ("multigrid-PCG, 1e-8", mg, 1e-8),
          ("multigrid-PCG, 1e-6", mg, 1e-6), ("multigrid-PCG, 1e-3", mg, 1e-3)]
fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
width = 0.2
for k, (label, rs, tol) in enumerate(series):
    ax.bar([i + (k - 1.5) * width for i in range(len(cases))], [pick(rs, b, s, tol) for b, s in cases], width,
           label=label)
ax.plot([-0.5, 0.5], [0.4, 0.4], "k--", lw=0.9, label="target: 0.4 s cold, 0.2 s warm")
ax.plot([0.5, 1.5], [0.2, 0.2], "k--", lw=0.9)
ax.plot([1.5, 2.5], [0.4, 0.4], "k--", lw=0.9)
ax.plot([2.5, 3.5], [0.2, 0.2], "k--", lw=0.9)
ax.set_yscale("log")
ax.set_xticks(range(len(cases)))
ax.set_xticklabels([f"{b} 128^3\n{s}" for b, s in cases], fontsize=8)
ax.set_ylabel("nonlinear solve, s (2 cores)")
ax.set_title("Newton-PCG field solve at H0 = 1e5 A/m, by relative-residual tolerance")
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "field_solve_time.png"))

# The distributed MPM (docs/distributed.md, docs/data/dist_mpm_scaling.csv):
# seconds per substep and resident memory per rank against the ranks, on the
# 2-core machine (4 ranks oversubscribed).
dist = rows("dist_mpm_scaling.csv")
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), dpi=110)
for series, style in (("strong", "o-"), ("weak", "s-")):
    rs = [r for r in dist if r["series"] == series]
    ranks = [int(r["ranks"]) for r in rs]
    label = {"strong": "strong: 1e6 particles, 129^3", "weak": "weak: 2.5e5 particles per rank"}[series]
    ax1.plot(ranks, [float(r["substep_s"]) for r in rs], style, label=label)
    ax2.plot(ranks, [float(r["rss_mb"]) for r in rs], style, label=label)
ideal = [float(dist[0]["substep_s"]) / r for r in (1, 2, 4)]
ax1.plot([1, 2, 4], ideal, "k--", lw=0.8, label="ideal strong scaling")
ax1.axvspan(2.5, 4.3, color="0.9")
ax1.text(3.2, ax1.get_ylim()[1] * 0.9, "oversubscribed\n(2 cores)", ha="center", va="top", fontsize=8)
ax1.set_xlabel("ranks")
ax1.set_ylabel("s per substep")
ax1.set_xticks([1, 2, 4])
ax1.set_title("Time per substep")
ax1.legend(fontsize=7, loc="center left")
ax1.grid(True, alpha=0.3)
ax2.set_xlabel("ranks")
ax2.set_ylabel("resident memory per rank, MB")
ax2.set_xticks([1, 2, 4])
ax2.set_title("Memory per rank")
ax2.legend(fontsize=7)
ax2.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "dist_mpm_scaling.png"))

# The MPM grid's memory and time (docs/benchmarks.md, docs/data/scaling.csv):
# peak resident memory and ms per substep against the domain's nodes at 1e6
# particles, the current binary beside the previous one that
# docs/benchmarks.md names, measured in one run.
sc = rows("scaling.csv")
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), dpi=110)
for binary, style in (("current", "o-"), ("previous", "s--")):
    rs = [r for r in sc if r["binary"] == binary and r["series"] == "domain" and r["particles_target"] == "1e6"]
    if not rs:
        continue
    nodes = [float(r["grid_nodes"]) for r in rs]
    label = {"current": "this binary", "previous": "the previous binary"}[binary]
    ax1.loglog(nodes, [float(r["peak_bytes"]) / 1e9 for r in rs], style, label=label)
    ax2.semilogx(nodes, [float(r["ms_per_substep"]) for r in rs], style, label=label)
ax1.axhline(23.5 * 1.0737, color="r", lw=0.8, ls=":")
ax1.text(2.5e6, 23.5 * 1.0737 * 0.85, "this machine's memory (25 GB)", color="r", fontsize=8, va="top")
ax1.set_xlabel("grid nodes (129^3 to 1027^3)")
ax1.set_ylabel("peak resident memory, GB")
ax1.set_title("1e6 particles: memory against the box")
ax1.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, 0.86))
ax1.grid(True, which="both", alpha=0.3)
ax2.set_xlabel("grid nodes (129^3 to 1027^3)")
ax2.set_ylabel("ms per substep")
ax2.set_ylim(bottom=0)
ax2.set_title("1e6 particles: time against the box")
ax2.legend(fontsize=7, loc="lower left")
ax2.grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "grid_memory_scaling.png"))
