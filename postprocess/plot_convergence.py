#!/usr/bin/env python3
"""Log–log charts of the refinement study of scripts/fluid_convergence.py:
L2 error against cells per axis (with the slope of a second-order scheme)
and against wall time (the speed–accuracy chart of the flow solver).

usage: postprocess/plot_convergence.py [CSV] [PNG]
"""
import csv, os, sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "docs/validation/fluid_convergence.csv")
target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, "docs/validation/fluid_convergence.png")
rows = list(csv.DictReader(open(source)))
labels = {"taylor_green_2d": "Taylor–Green 2D (in a stream)", "taylor_green_3d": "Beltrami 3D"}
fig, (by_cells, by_time) = plt.subplots(1, 2, figsize=(10, 4.2))
for case, label in labels.items():
    mine = [r for r in rows if r["case"] == case]
    n = [float(r["cells_per_axis"]) for r in mine]
    error = [float(r["l2_error"]) for r in mine]
    seconds = [max(float(r["wall_seconds"]), 1e-3) for r in mine]
    by_cells.loglog(n, error, "o-", label=label)
    by_cells.loglog(n, [error[0] * (n[0] / x) ** 2 for x in n], "k:", lw=0.8)
    by_time.loglog(seconds, error, "o-", label=label)
by_cells.set_xlabel("cells per axis (dt proportional to the cell size)")
by_cells.set_ylabel("relative L2 error of the velocity")
by_cells.set_title("second order in space and time (dotted: slope −2)")
by_cells.legend()
by_time.set_xlabel("wall time of the run [s] (1 thread)")
by_time.set_ylabel("relative L2 error of the velocity")
by_time.set_title("speed against accuracy")
by_time.legend()
fig.tight_layout()
fig.savefig(target, dpi=120)
print(f"wrote {target}")
