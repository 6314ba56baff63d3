"""The ferrofluid page's plot (docs/ferrofluid.md) from the Rosensweig
benchmark's CSV (docs/data/rosensweig.csv, written by
lodestone-bench-rosensweig --csv). Run with Debian's python3-matplotlib:
python3 docs/ferrofluid_plots.py. Not part of the build."""
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

here = os.path.dirname(os.path.abspath(__file__))
runs = defaultdict(lambda: {"t": [], "rms": [], "peaks": []})
with open(os.path.join(here, "data", "rosensweig.csv")) as f:
    for row in csv.DictReader(f):
        r = runs[float(row["ratio"])]
        r["t"].append(float(row["time_s"]))
        r["rms"].append(float(row["rms_cells"]))
        r["peaks"].append(int(row["peaks"]))

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4), dpi=110)
for ratio in sorted(runs):
    r = runs[ratio]
    a.plot(r["t"], r["rms"], "-", label=f"H0 = {ratio:g} H0_c")
    b.plot(r["t"], r["peaks"], "-", label=f"{ratio:g} H0_c")
a.axhline(0.5, color="k", lw=0.8, ls="--")
a.set_xlabel("time (s)")
a.set_ylabel("surface rms height (cells)")
a.set_title("Ferrofluid layer: surface height")
a.legend(fontsize=8)
a.grid(True, alpha=0.3)
b.set_xlabel("time (s)")
b.set_ylabel("spikes (prominence >= max(0.5 cells, 1.5 rms))")
b.set_title("Spikes found")
b.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "rosensweig_growth.png"))
print("wrote docs/images/rosensweig_growth.png")

# The dilute liquid (docs/data/rosensweig_dilute.csv, tests/bench/rosensweig_dilute.json):
# peak-to-trough height against time for the Langevin law and its
# linearisation at the same applied fields.
dilute = defaultdict(lambda: {"t": [], "range": []})
with open(os.path.join(here, "data", "rosensweig_dilute.csv")) as f:
    for row in csv.DictReader(f):
        r = dilute[(row["law"], float(row["applied_H_A_per_m"]))]
        r["t"].append(float(row["time_s"]))
        r["range"].append(float(row["range_cells"]))
fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
colours = {}
for (law, H) in sorted(dilute, key=lambda k: (k[1], k[0])):
    r = dilute[(law, H)]
    colour = colours.setdefault(H, f"C{len(colours)}")
    style = "-" if law == "scene" else "--"
    name = "Langevin" if law == "scene" else "linearised"
    ax.plot(r["t"], r["range"], style, color=colour, label=f"{name}, {H / 1e3:.0f} kA/m")
ax.axhline(40, color="k", lw=0.8, ls=":")
ax.text(0.2, 31, "the box's ceiling", fontsize=8, ha="center")
ax.set_yscale("log")
ax.set_xlabel("time (s)")
ax.set_ylabel("peak-to-trough height (cells of 1.15 mm)")
ax.set_title("Dilute ferrofluid (Ms = 8 kA/m): spike height, Langevin against linear")
ax.legend(fontsize=7, ncol=2)
ax.grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(here, "images", "rosensweig_saturation.png"))
print("wrote docs/images/rosensweig_saturation.png")
