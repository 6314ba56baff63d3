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

# The desk toy (examples/scenes/desk_toy.json; lodestone-bench-rosensweig
# --sources scene): the last frame's surface seen from above, with the
# spikes found and the circle within which the magnet's field passes the
# onset (docs/data/desk_toy_surface.csv, docs/data/desk_toy.csv), for the
# scene's magnet and a 0.7 T one (docs/data/desk_toy_07T*.csv).
def desk_toy(ax, stem, title):
    cells, spikes = [], []
    with open(os.path.join(here, "data", stem + "_surface.csv")) as f:
        for row in csv.DictReader(f):
            p = (1e3 * float(row["x_m"]), 1e3 * float(row["y_m"]), 1e3 * float(row["z_m"]))
            (cells if row["kind"] == "cell" else spikes).append(p)
    with open(os.path.join(here, "data", stem + ".csv")) as f:
        last = list(csv.DictReader(f))[-1]
    rc = 1e3 * float(last["onset_radius_m"])
    xs, ys = sorted({c[0] for c in cells}), sorted({c[1] for c in cells})
    h = xs[1] - xs[0]
    grid = [[float("nan")] * len(xs) for _ in ys]
    for x, y, z in cells:
        grid[round((y - ys[0]) / h)][round((x - xs[0]) / h)] = z
    sc = ax.imshow(grid, origin="lower", extent=(xs[0] - h / 2, xs[-1] + h / 2, ys[0] - h / 2, ys[-1] + h / 2),
                   cmap="viridis", vmin=4, vmax=11, interpolation="nearest")
    ax.plot([s[0] for s in spikes], [s[1] for s in spikes], "r^", ms=5, label=f"{len(spikes)} peaks found")
    if rc > 0:
        ax.add_patch(matplotlib.patches.Circle((0, 0), rc, fill=False, color="w", ls="--", lw=1.2,
                                               label=f"above onset: r < {rc:.1f} mm"))
    ax.set_aspect("equal")
    ax.set_xlim(-25, 25)
    ax.set_ylim(-25, 25)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{title}: {float(last['centre_applied_H_A_per_m']) / 1e3:.1f} kA/m at the centre, "
                 f"{float(last['ratio']):.2f} H0_c", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    return sc


import matplotlib.patches  # noqa: E402

fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), dpi=110)
for ax, (stem, title) in zip(axes, [("desk_toy", "1.45 T magnet"), ("desk_toy_07T", "0.7 T magnet")]):
    sc = desk_toy(ax, stem, title)
fig.colorbar(sc, ax=axes, label="surface height (mm)")
fig.savefig(os.path.join(here, "images", "desk_toy_surface.png"))
print("wrote docs/images/desk_toy_surface.png")
