#!/usr/bin/env python3
"""Horizontally averaged granular pressure in a silo (Izard et al. 2014,
fig. 4b) from a run's silo_profile.csv and summary.json: the measured
profile and Janssen's law p = p_inf (1 - exp(-(h - z)/lambda)) fitted over
the slabs above FIT_ABOVE (default: the run's own fit), f_w K = S/(P lambda)
for a square shaft of width WIDTH.

usage: postprocess/plot_silo.py OUT_DIR FIGURE.png [FIT_ABOVE] [WIDTH]
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
width = float(sys.argv[4]) if len(sys.argv) > 4 else 0.1
if len(sys.argv) > 3:
    above = float(sys.argv[3])
    slab = z[1] - z[0]
    fit = [k for k in range(len(z)) if z[k] >= above and z[k] + slab <= h - slab]
    best = None
    for k in range(1, 20000):
        lam = k * 1e-4
        s = [1 - math.exp(-(h - z[i]) / lam) for i in fit]
        pinf = sum(a * p[i] for a, i in zip(s, fit)) / sum(a * a for a in s)
        r = sum((pinf * a - p[i]) ** 2 for a, i in zip(s, fit))
        if best is None or r < best[0]:
            best = (r, lam, pinf)
    _, lam, pinf = best
    label = f"Janssen fit above z = {above} m: $f_wK$ = {width / 4 / lam:.2f}"
else:
    lam, pinf = m["janssen_length"], m["saturation_pressure"]
    label = f"Janssen fit, $f_wK$ = {m['janssen_fwK']:.3f}"
fig, ax = plt.subplots(figsize=(4, 6))
ax.plot(p, z, "o", ms=3, mfc="none", label="grainflow, coarse-grained")
zz = [h * k / 400 for k in range(401)]
ax.plot([pinf * (1 - math.exp(-(h - x) / lam)) for x in zz], zz, "-", label=label)
if len(sys.argv) <= 3 and "janssen_fwK_eq22" in m:
    weight = m["solid_fraction"] * 1317.0 * 9.81  # rho_gm g, the silo's grains
    for fwk, style, name in [(m["janssen_fwK_eq22"], "--", "eq. 22 fit"),
                             (0.30, ":", "eq. 22, paper")]:
        l22 = width / 4 / fwk
        ax.plot([weight * l22 * (1 - math.exp(-(h - x) / l22)) for x in zz], zz, style,
                label=f"{name}: $f_wK$ = {fwk:.3f}")
ax.set_xlabel("granular pressure [Pa]")
ax.set_ylabel("z [m]")
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(figure, dpi=120)
print(f"lambda = {lam:.4f} m, p_inf = {pinf:.0f} Pa, f_w K = {width / 4 / lam:.3f}")
