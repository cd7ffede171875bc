#!/usr/bin/env python3
"""Horizontally averaged granular pressure in a silo (Izard et al. 2014,
fig. 4b) from a run's silo_profile.csv and summary.json: the measured
profile, the fitted Janssen law and the hydrostatic line.

usage: postprocess/plot_silo.py OUT_DIR FIGURE.png
"""
import csv, json, math, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

out, figure = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(os.path.join(out, "silo_profile.csv"))))
m = json.load(open(os.path.join(out, "summary.json")))["metrics"]
z = [float(r["z"]) for r in rows]
p = [float(r["pressure"]) for r in rows]
h = m["column_height"]
lam, pinf = m["janssen_length"], m["saturation_pressure"]
fig, ax = plt.subplots(figsize=(4, 6))
ax.plot(p, z, "o", ms=3, mfc="none", label="grainflow, coarse-grained")
zz = [h * k / 200 for k in range(201)]
ax.plot([pinf * (1 - math.exp(-(h - x) / lam)) for x in zz], zz, "-",
        label=f"Janssen fit, $f_wK$ = {m['janssen_fwK']:.3f}")
slope = pinf / lam
ax.plot([slope * (h - x) for x in zz if slope * (h - x) <= 1.3 * max(p)],
        [x for x in zz if slope * (h - x) <= 1.3 * max(p)], "--", label="hydrostatic (fit slope)")
ax.set_xlabel("granular pressure [Pa]")
ax.set_ylabel("z [m]")
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(figure, dpi=120)
