#!/usr/bin/env python3
"""The direct forcing's step dependence in (r, z) (the paper's falling
sphere, scripts/falling_sphere_axisymmetric_sweep.py): terminal Reynolds
number against the grain's CFL number at its terminal velocity, under eq. 7
at every stage, with the forcing step held at nu dt_f / dx^2 = 0.8 and with
the layer relaxed at the flow's renewal rate (coupling.layer_forcing =
"renewal"), at D/dx = 10 and 20, beside Schiller-Naumann and
Clift-Grace-Weber.

usage: postprocess/plot_forcing_step.py [CSV] [PNG]
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
    root, "docs/validation/forcing_step_axisymmetric.csv")
target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(
    root, "docs/validation/forcing_step_axisymmetric.png")
rows = list(csv.DictReader(open(source)))

SCHILLER_NAUMANN, CLIFT_GRACE_WEBER = 20.318, 19.744
fig, ax = plt.subplots(figsize=(7, 4.5))
for per, colour in (("10", "tab:blue"), ("20", "tab:red")):
    for held, style, label in (("", "o--", "eq. 7 at every stage"),
                               ("0.8", "s-", "forcing step held, ν Δt_f/Δx² = 0.8"),
                               ("renewal", "^-", "renewal rate (layer_forcing)")):
        points = sorted((float(r["grain_cfl"]), float(r["terminal_reynolds"]))
                        for r in rows
                        if r["cells_per_diameter"] == per and r["forcing_number"] == held)
        if points:
            ax.plot(*zip(*points), style, color=colour, label=f"D/Δx = {per}, {label}")
ax.axhline(SCHILLER_NAUMANN, color="k", lw=0.8, label="Schiller–Naumann")
ax.axhline(CLIFT_GRACE_WEBER, color="k", lw=0.8, ls=":", label="Clift–Grace–Weber")
ax.set_xscale("log")
ax.set_xlabel("grain CFL number U_t Δt / Δx")
ax.set_ylabel("terminal Reynolds number")
ax.set_title("Falling sphere in (r, z), ρp/ρ = 4, Ar = 800")
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(target, dpi=120)
print(target)
