"""Accuracy-against-time figures from the CSV files that
lodestone-bench-accuracy writes to docs/data/ (run with Debian's
python3-matplotlib: /usr/bin/python3 docs/accuracy_plots.py [DATA_DIR [IMAGE_DIR]]).
Each figure plots error against wall time, log-log, one curve per setting,
with the Pareto front (no other point both cheaper and more accurate) marked.
Not part of the build."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

here = os.path.dirname(os.path.abspath(__file__))
data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "data")
images = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "images")
os.makedirs(images, exist_ok=True)


def read(name):
    path = os.path.join(data, name)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return list(csv.DictReader(f))


def pareto(points):
    """Points (time, error) not dominated by a cheaper, more accurate one."""
    front, best = [], float("inf")
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def mark_front(ax, points):
    front = pareto([p for p in points if p[1] > 0])
    if front:
        ax.step([t for t, _ in front], [e for _, e in front], where="post", color="k", lw=1.2, alpha=0.6)
        ax.plot([t for t, _ in front], [e for _, e in front], "o", mfc="none", mec="k", ms=11, mew=1.3,
                label="Pareto front")


def bounds(ax):
    for b, s in ((0.01, ":"), (0.05, "--"), (0.10, "-.")):
        ax.axhline(b, color="grey", ls=s, lw=0.8)
        ax.text(ax.get_xlim()[0], b, f" {b:.0%}", va="bottom", ha="left", fontsize=7, color="grey")


def finish(ax, fig, title, name):
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    bounds(ax)
    if ax.get_legend() is None:
        ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(images, name))
    plt.close(fig)
    print("wrote", os.path.join(images, name))


def colour(tol):
    cmap = plt.get_cmap("viridis")
    order = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]
    t = float(tol)
    i = min(range(len(order)), key=lambda k: abs(order[k] - t) / order[k])
    return cmap(i / (len(order) - 1) * 0.9)


# Field: sphere in a uniform field, error of the interior H.
rows = read("accuracy_field.csv")
if rows:
    fig, ax = plt.subplots(figsize=(10, 5), dpi=110)
    points = []
    keys = sorted({(r["law"], r["preconditioner"], float(r["tolerance"])) for r in rows},
                  key=lambda k: (k[0], k[1], -k[2]))
    for law, pc, tol in keys:
        rs = sorted((r for r in rows if (r["law"], r["preconditioner"], float(r["tolerance"])) == (law, pc, tol)),
                    key=lambda r: int(r["nodes_per_axis"]))
        t = [float(r["seconds_stage"]) for r in rs]
        e = [float(r["error_vs_langevin"]) for r in rs]
        points += list(zip(t, e))
        style = "-" if pc == "multigrid" else "--"
        if law == "langevin":
            ax.loglog(t, e, style, marker="o", color=colour(tol), ms=4, lw=1, label=f"Langevin, {pc}, tol {tol:.0e}")
        else:
            first = not any(l.get_label().startswith("linear law") for l in ax.get_lines())
            ax.loglog(t, e, style, marker="x", color="0.55", ms=4, lw=0.7,
                      label="linear law (every preconditioner, tolerance)" if first else "_nolegend_")
        if law == "langevin" and pc == "multigrid" and tol == 1e-8:
            for r, ti, ei in zip(rs, t, e):
                ax.annotate(f"{int(r['nodes_per_axis']) - 1}$^3$", (ti, ei), textcoords="offset points",
                            xytext=(4, 4), fontsize=7)
    mark_front(ax, points)
    ax.set_xlabel("wall time of the magnetic stage, s (2 cores)")
    ax.set_ylabel("RMS error of interior H vs the Langevin closed form")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    finish(ax, fig, "Sphere in H0 = 1e5 A/m: resolution, tolerance, preconditioner, law", "accuracy_field.png")

# Laws: the error of assuming the linear law for the Langevin material.
rows = read("accuracy_laws.csv")
if rows:
    cf = [r for r in rows if r["kind"] == "closed_form"]
    H0 = [float(r["H0_A_per_m"]) for r in cf]
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    ax.loglog(H0, [float(r["error_H_linear"]) for r in cf], "-", label="interior H")
    ax.loglog(H0, [float(r["error_M_linear"]) for r in cf], "-", label="magnetization M")
    ax.loglog(H0, [float(r["error_force_linear"]) for r in cf], "-", label="force ~ M$^2$ (sphere pair)")
    sv = [r for r in rows if r["kind"] == "solved"]
    if sv:
        ax.loglog([float(r["H0_A_per_m"]) for r in sv], [float(r["error_rms_linear_solve_vs_langevin"]) for r in sv],
                  "kx", label=f"solved linear sphere ({int(sv[0]['nodes_per_axis']) - 1}$^3$) vs Langevin closed form")
        ax.loglog([float(r["H0_A_per_m"]) for r in sv], [float(r["error_rms_langevin_solve"]) for r in sv],
                  "k+", label="solved Langevin sphere vs its closed form")
    ax.set_xlabel("applied field H0, A/m")
    ax.set_ylabel("relative error of the linear law")
    ax.set_title("Linear law (chi = chi0) for the paper's Langevin material, sphere", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    for b, s in ((0.01, ":"), (0.05, "--"), (0.10, "-.")):
        ax.axhline(b, color="grey", ls=s, lw=0.8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(images, "accuracy_laws.png"))
    plt.close(fig)
    print("wrote", os.path.join(images, "accuracy_laws.png"))

# Force: two spheres against the dipole force.
rows = read("accuracy_force.csv")
if rows:
    fig, ax = plt.subplots(figsize=(7.5, 5), dpi=110)
    points = []
    keys = sorted({(r["preconditioner"], float(r["tolerance"])) for r in rows}, key=lambda k: (k[0], -k[1]))
    for pc, tol in keys:
        rs = sorted((r for r in rows if (r["preconditioner"], float(r["tolerance"])) == (pc, tol)),
                    key=lambda r: float(r["cells_per_radius"]))
        t = [float(r["seconds_stage"]) for r in rs]
        e = [float(r["error"]) for r in rs]
        points += list(zip(t, e))
        ax.loglog(t, e, "-" if pc == "multigrid" else "--", marker="o", color=colour(tol), ms=4, lw=1,
                  label=f"{pc}, tol {tol:.0e}")
        if pc == "multigrid" and tol == 1e-8:
            for r, ti, ei in zip(rs, t, e):
                ax.annotate(f"a = {float(r['cells_per_radius']):g} dx", (ti, ei), textcoords="offset points",
                            xytext=(4, 4), fontsize=7)
    mark_front(ax, points)
    ax.set_xlabel("wall time of the magnetic stage, s (2 cores)")
    ax.set_ylabel("relative error of the force vs the dipole force")
    finish(ax, fig, "Two spheres (d = 3a) in 1e6 A/m: resolution, tolerance, preconditioner", "accuracy_force.png")

# Dynamics: the induced-attraction scene against its reference run.
rows = read("accuracy_dynamics.csv")
if rows:
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8), dpi=110)
    points = []
    names = {"1": "every substep", "5": "every 5 substeps", "0": "once per frame (40 substeps)"}
    for every in ("1", "5", "0"):
        rs = sorted((r for r in rows if r["solve_every_substeps"] == every and float(r["gap_error"]) > 0),
                    key=lambda r: -float(r["tolerance"]))
        if not rs:
            continue
        t = [float(r["seconds_total"]) for r in rs]
        e = [float(r["gap_error"]) for r in rs]
        points += list(zip(t, e))
        line, = ax.loglog(t, e, "o-", ms=4, lw=1, label=names[every])
        for r, ti, ei in zip(rs, t, e):
            ax.annotate(f"{float(r['tolerance']):.0e}", (ti, ei), textcoords="offset points", xytext=(4, -9),
                        fontsize=6, color=line.get_color())
    ref = [r for r in rows if r["solve_every_substeps"] == "1" and float(r["gap_error"]) == 0]
    if ref:
        ax.axvline(float(ref[0]["seconds_total"]), color="r", lw=0.8, ls="--", label="reference run (every substep, 1e-10)")
    mark_front(ax, points)
    ax.set_xlabel("wall time of the run, s (2 cores)")
    ax.set_ylabel("largest gap deviation / largest gap change of the reference")
    ax.set_title(f"Induced attraction, {rows[0]['frames']} frames at dx = {float(rows[0]['dx_m']):g} m", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    bounds(ax)
    ax.legend(fontsize=7)
    traj = read("accuracy_dynamics_trajectories.csv")
    if traj:
        for every, tol in (("1", 1e-10), ("1", 1e-2), ("5", 1e-6), ("0", 1e-6)):
            rs = [r for r in traj if r["solve_every_substeps"] == every and abs(float(r["tolerance"]) - tol) < 1e-3 * tol]
            if rs:
                ax2.plot([float(r["time_s"]) for r in rs],
                         [1e3 * (float(r["right_x_m"]) - float(r["left_x_m"])) for r in rs],
                         "-" if every == "1" and tol == 1e-10 else "--", label=f"{names[every]}, tol {tol:.0e}")
        ax2.set_xlabel("time, s")
        ax2.set_ylabel("gap between the cubes' centres of mass, mm")
        ax2.set_title("Trajectories", fontsize=10)
        ax2.grid(True, alpha=0.25)
        ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(images, "accuracy_dynamics.png"))
    plt.close(fig)
    print("wrote", os.path.join(images, "accuracy_dynamics.png"))

# Markdown tables for docs/accuracy_vs_time.md (printed, not written).
def table(rows, cols, heads):
    print("| " + " | ".join(heads) + " |")
    print("|" + "---|" * len(heads))
    for r in rows:
        print("| " + " | ".join(c(r) for c in cols) + " |")
    print()


def g(key, fmt="{:.3g}"):
    return lambda r: fmt.format(float(r[key])) if r[key] != "" else ""


rows = read("accuracy_field.csv")
if rows:
    print("### field (multigrid 1e-8 and the cheapest per size)")
    table([r for r in rows if float(r["tolerance"]) in (1e-2, 1e-8)],
          [lambda r: r["law"], lambda r: r["preconditioner"], g("tolerance", "{:.0e}"),
           lambda r: str(int(r["nodes_per_axis"]) - 1) + "^3", g("cells_per_radius", "{:g}"),
           g("error_rms", "{:.2e}"), g("error_demag", "{:.2e}"), g("error_vs_langevin", "{:.2e}"),
           lambda r: r["newton_iterations"] + " / " + r["cg_iterations"], g("seconds_solve", "{:.2f}"),
           g("seconds_stage", "{:.2f}")],
          ["law", "precond.", "tol", "cells", "a/dx", "error H (own law)", "error of H - H0", "error vs Langevin",
           "Newton / CG", "solve s", "stage s"])
rows = read("accuracy_force.csv")
if rows:
    print("### force")
    table(rows, [lambda r: r["preconditioner"], g("tolerance", "{:.0e}"), g("cells_per_radius", "{:g}"),
                 g("nodes", "{:.2g}"), g("force_N", "{:.4f}"), g("dipole_force_N", "{:.4f}"), g("error", "{:.2e}"),
                 lambda r: r["newton_iterations"] + " / " + r["cg_iterations"], g("seconds_stage", "{:.2f}")],
          ["precond.", "tol", "a/dx", "nodes", "F (N)", "dipole (N)", "error", "Newton / CG", "stage s"])
rows = read("accuracy_dynamics.csv")
if rows:
    print("### dynamics")
    table(rows, [lambda r: {"1": "every substep", "5": "every 5", "0": "once per frame"}[r["solve_every_substeps"]],
                 g("tolerance", "{:.0e}"), g("field_solves", "{:g}"),
                 lambda r: r["newton_iterations"] + " / " + r["cg_iterations"], g("gap_error", "{:.2e}"),
                 lambda r: "{:.3g}".format(1e6 * float(r["gap_error_m"])), g("seconds_total", "{:.1f}"),
                 g("seconds_magnetic", "{:.1f}")],
          ["field solve", "tol", "solves", "Newton / CG", "gap error (rel.)", "gap error (um)", "run s",
           "magnetic s"])
for name in ("accuracy_table2.csv", "accuracy_presets.csv", "solve_vs_openvdb.csv"):
    rows = read(name)
    if rows:
        print("### " + name)
        table(rows, [(lambda k: lambda r: r[k])(k) for k in rows[0].keys()], list(rows[0].keys()))
