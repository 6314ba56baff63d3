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

# Field-solve time (docs/data): cold solves, multigrid vs Jacobi.
def rows(name):
    with open(os.path.join(here, "data", name)) as f:
        return [r for r in csv.DictReader(f) if r["start"] == "cold"]

mg, jac = rows("bench_field_solve_multigrid.csv"), rows("bench_field_solve_jacobi.csv")
labels = [f"{r['body']} {r['nodes_per_axis']}^3\nH0={float(r['H0_A_per_m']):.0e}" for r in mg]
x = range(len(mg))
fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
ax.bar([i - 0.2 for i in x], [float(r["seconds_solve"]) for r in jac], 0.4, label="Jacobi-PCG")
ax.bar([i + 0.2 for i in x], [float(r["seconds_solve"]) for r in mg], 0.4, label="multigrid-PCG")
ax.axhline(2.0, color="k", ls="--", lw=0.8, label="2 s target (128^3)")
ax.set_xticks(list(x))
ax.set_xticklabels(labels, fontsize=7)
ax.set_ylabel("cold nonlinear solve, s (2 cores)")
ax.set_title("Newton-PCG field solve, relative residual 1e-8")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "field_solve_time.png"))
