#!/usr/bin/env python3
"""Grains at rest in a box (Martin et al. 2022, Fig. 3): the largest ratio
of kinetic to potential energy over the run against the solver tolerance,
for each contact model, from scripts/static_box_sweep.py.

usage: postprocess/plot_static_box.py FIGURE.png SWEEP.csv [TITLE [SPAN]]
(TITLE: the scene, SPAN: the time at rest the largest ratio is taken over;
by default those of cases/static_box.toml)
"""
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

figure, sweep = sys.argv[1], sys.argv[2]
title = sys.argv[3] if len(sys.argv) > 3 else "400 discs at rest in a box, dt = 1e-3 s"
span = sys.argv[4] if len(sys.argv) > 4 else "1 s"
rows = [r for r in csv.DictReader(open(sweep)) if r["status"] == "ok"]
fig, ax = plt.subplots(figsize=(5.5, 4.2))
for model, marker in [("cocd", "o-"), ("nscd", "s--")]:
    pts = sorted((float(r["tolerance"]), float(r["max_kinetic_to_potential"]))
                 for r in rows if r["model"] == model)
    if pts:
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker, label=model.upper())
ax.axhline(1e-8, color="gray", lw=1, ls=":", label="bound 1e-8")
ax.set_xscale("log")
ax.set_yscale("log")
ax.invert_xaxis()
ax.set_xlabel(r"solver tolerance $\varepsilon$")
ax.set_ylabel(r"max $E_k/E_p$ over " + span + " at rest")
ax.set_title(title, fontsize=9)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(figure, dpi=120)
