#!/usr/bin/env python3
"""Grains at rest in a box against time, one curve per solver tolerance
(Martin et al. 2022, Fig. 3): E_k/E_p against t (g/H)^1/2 from the runs of
scripts/static_box_sweep.py (each run's kinetic_to_potential.csv).

usage: postprocess/plot_static_box_series.py FIGURE.png SERIES.csv HEIGHT TITLE RUN_DIR...

Writes the runs' series into SERIES.csv (tolerance, time, ratio) and draws
the figure from it; HEIGHT is the packing's height H in metres. With no
RUN_DIR it draws the figure from an existing SERIES.csv.
"""
import csv, math, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

if len(sys.argv) < 5:
    sys.exit(__doc__)
figure, series, height, title = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
runs = sys.argv[5:]
if runs:
    with open(series, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["tolerance", "time", "kinetic_to_potential"])
        for run in runs:
            with open(os.path.join(run, "case.toml")) as c:
                tolerance = next(float(l.split("=")[1]) for l in c if l.strip().startswith("tolerance"))
            with open(os.path.join(run, "kinetic_to_potential.csv")) as k:
                for row in csv.DictReader(k):
                    out.writerow([tolerance, row["time"], row["kinetic_to_potential"]])
curves = {}
with open(series) as f:
    for row in csv.DictReader(f):
        curves.setdefault(float(row["tolerance"]), []).append(
            (float(row["time"]), max(float(row["kinetic_to_potential"]), 1e-30)))
scale = math.sqrt(height / 9.81)
fig, ax = plt.subplots(figsize=(6.0, 4.2))
for tolerance in sorted(curves, reverse=True):
    points = sorted(curves[tolerance])
    ax.plot([t / scale for t, _ in points], [r for _, r in points], lw=1.2,
            label=f"ε = {tolerance:.0e}")
ax.axhline(1e-8, color="gray", lw=1, ls=":")
ax.set_yscale("log")
ax.set_xlabel(r"$t\,(g/H)^{1/2}$")
ax.set_ylabel(r"$E_k/E_p$")
ax.set_title(title, fontsize=9)
ax.legend(fontsize=7, ncol=2)
fig.tight_layout()
fig.savefig(figure, dpi=120)
