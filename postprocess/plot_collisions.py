#!/usr/bin/env python3
"""Psi2 against Psi1 of the binary collisions (Izard et al. 2014, fig. 3) from
a run's collisions.csv, with the sliding line Psi2 = Psi1 - (7/2) mu (1 + e_n).

usage: postprocess/plot_collisions.py OUT_DIR/collisions.csv FIGURE.png [--friction 0.25] [--restitution 0.87]
"""
import argparse, csv
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

ap = argparse.ArgumentParser()
ap.add_argument("table")
ap.add_argument("figure")
ap.add_argument("--friction", type=float, default=0.25)
ap.add_argument("--restitution", type=float, default=0.87)
args = ap.parse_args()
rows = list(csv.DictReader(open(args.table)))
psi1 = [float(r["psi1"]) for r in rows]
psi2 = [float(r["psi2"]) for r in rows]
offset = 3.5 * args.friction * (1 + args.restitution)
fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(psi1, psi2, "+", label="grainflow (soft-sphere DEM)")
xs = [offset, max(psi1)]
ax.plot(xs, [x - offset for x in xs], "-", label=r"sliding: $\Psi_2 = \Psi_1 - \frac{7}{2}\mu(1+e_n)$")
ax.axhline(0, color="0.7", lw=0.5)
ax.set_xlabel(r"$\Psi_1$")
ax.set_ylabel(r"$\Psi_2$")
ax.set_title(f"acetate spheres, e_n = {args.restitution}, mu = {args.friction}")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(args.figure, dpi=120)
