#!/usr/bin/env python3
"""Runout (R_inf - R0)/R0 against the aspect ratio a = H0/R0 from the sweeps
of scripts/column_collapse_sweep.py, beside the published laws in
docs/reference/column_collapse_runout.csv.

usage: postprocess/plot_runout.py FIGURE.png SWEEP.csv [SWEEP.csv ...]
"""
import csv, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

figure, sweeps = sys.argv[1], sys.argv[2:]
root = os.path.join(os.path.dirname(__file__), "..")
fig, ax = plt.subplots(figsize=(5.5, 4.2))
reference = list(csv.DictReader(open(os.path.join(root, "docs/reference/column_collapse_runout.csv"))))
sources = sorted({r["source"] for r in reference if "axisym" not in r["source"].lower()})
for source in sources:
    pts = [(float(r["a"]), float(r["runout"])) for r in reference if r["source"] == source]
    pts.sort()
    ax.plot([p[0] for p in pts], [p[1] for p in pts], "--", lw=1, label=source)
markers = {"2d": "o", "3d": "s"}
for sweep in sweeps:
    rows = list(csv.DictReader(open(sweep)))
    tag = "3d" if "3d" in os.path.basename(sweep) else "2d"
    ax.plot([float(r["aspect_ratio"]) for r in rows], [float(r["runout"]) for r in rows], markers[tag],
            ms=7, mfc="none" if tag == "3d" else None, color="k", label=f"grainflow {tag.upper()} DEM")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel(r"aspect ratio $a = H_0/R_0$")
ax.set_ylabel(r"runout $(R_\infty - R_0)/R_0$")
ax.legend(fontsize=6)
fig.tight_layout()
fig.savefig(figure, dpi=120)
