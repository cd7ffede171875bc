#!/usr/bin/env python3
"""The settling sphere of ten Cate et al. (2002), E1-E4: gap over D and
velocity against time (TRACKS: case, t, z, vz, from the runs of
scripts/ten_cate_runs.py) beside the measured curves (digitized,
../shared/reference/tencate2002; read there, not copied).

usage: postprocess/plot_ten_cate.py [TRACKS] [PNG] [REFERENCE_DIR] [TITLE]
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "docs/validation/ten_cate_tracks.csv")
target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, "docs/validation/ten_cate.png")
reference = sys.argv[3] if len(sys.argv) > 3 else os.path.join(root, "../shared/reference/tencate2002")
title = sys.argv[4] if len(sys.argv) > 4 else "ten Cate et al. (2002), D/Δx = 12"
names = {"E1": "Re1_5", "E2": "Re4_1", "E3": "Re11_6", "E4": "Re32_2"}
D = 0.015


def pairs(path):
    out = []
    for line in open(path):
        parts = [p.strip() for p in line.split(",") if p.strip()]
        if len(parts) == 2:
            out.append((float(parts[0]), float(parts[1])))
    return out


fig, (gap, velocity) = plt.subplots(1, 2, figsize=(11, 4.3))
colours = dict(zip(names, ["C0", "C1", "C2", "C3"]))
runs = {}
for line in csv.DictReader(open(source)):
    t, g, w = runs.setdefault(line["case"], ([], [], []))
    t.append(float(line["t"]))
    g.append((float(line["z"]) - D / 2) / D)
    w.append(float(line["vz"]))
for case, (t, g, w) in sorted(runs.items()):
    c = colours[case]
    gap.plot(t, g, color=c, label=f"{case} grainflow")
    velocity.plot(t, w, color=c, label=f"{case} grainflow")
    measured_gap = pairs(os.path.join(reference, f"tencate_{names[case]}.csv"))
    measured_w = pairs(os.path.join(reference, f"tencate_u_{names[case]}.csv"))
    gap.plot(*zip(*measured_gap), "o", color=c, ms=3, mfc="none", label=f"{case} measured")
    velocity.plot(*zip(*measured_w), "o", color=c, ms=3, mfc="none", label=f"{case} measured")
gap.set_xlabel("t [s]")
gap.set_ylabel("gap above the floor / D")
gap.legend(fontsize=7, ncol=2)
velocity.set_xlabel("t [s]")
velocity.set_ylabel("vertical velocity [m/s]")
velocity.set_title(title)
fig.tight_layout()
fig.savefig(target, dpi=120)
print(f"wrote {target}")
