#!/usr/bin/env python3
"""Chart of scripts/chute_layer_arrest.py: a layer pushed down the narrow
channel's 22 degree slope, its steady speed against its thickness in
grains. Left: grainflow's soft DEM and COCD at the frictions, rolling
resistances and steps of the study (a layer that came to rest is drawn
on the bottom axis, its rest time beside it). Right: grainflow against
LAMMPS on the same layers with the same law (a constant k_n and gamma_n).
Third: COCD's speed against its step in units of the grains' fall time
over a diameter, sqrt(d/g), each thickness over its speed at the shortest
step (the paper's 3D step is 1 in these units).

    postprocess/plot_chute_layer.py docs/validation/chute_layer_arrest.csv \
        docs/validation/chute_layer_arrest.png
"""
import csv
import os
import sys
import tomllib
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The speed a layer at rest is drawn at (m/s), on the log axis's floor.
REST = 0.005
# The grains' mean diameter (m) and gravity (m/s2) of the case the study
# runs: sqrt(d/g) is the time unit of the third panel.
CASE = tomllib.load(open(os.path.join(os.path.dirname(__file__), "..", "cases",
                                      "chute_layer_3d.toml"), "rb"))
DIAMETER = 2.0 * CASE["particles"]["radius"]
GRAVITY = sum(g * g for g in CASE["domain"]["gravity"]) ** 0.5


def label(r):
    if r["model"] == "cocd":
        return f"COCD, μ {r['friction']}, Δt {float(r['dt']) * 1e3:g} ms"
    if float(r["rolling_friction"]):
        return f"soft, μ {r['friction']}, μ_r {r['rolling_friction']}"
    return f"soft, μ {r['friction']}"


def main():
    table, out = sys.argv[1], sys.argv[2]
    with open(table) as f:
        rows = list(csv.DictReader(f))
    fig, (left, right, steps) = plt.subplots(1, 3, figsize=(17, 4.8))

    series = defaultdict(list)
    rests_at = defaultdict(int)
    for r in rows:
        if r["law"] in ("case", "rigid"):
            series[label(r)].append(r)
    for name, runs in series.items():
        cocd = name.startswith("COCD")
        xs = [int(r["thickness"]) for r in runs]
        ys = [float(r["mean_speed"]) if r["status"] == "flowing" else REST for r in runs]
        line, = left.plot(xs, ys, "s--" if cocd else "o-", label=name)
        for r, x, y in zip(runs, xs, ys):
            if r["status"] == "at rest":
                left.plot([x], [y], "v", color=line.get_color(), markersize=10)
                # Stacked above the marker, one line per layer at rest there.
                left.annotate(f"at rest at {float(r['rest_time']):.2f} s", (x, y), textcoords="offset points",
                              xytext=(8, 4 + 10 * rests_at[x]), fontsize=7, color=line.get_color())
                rests_at[x] += 1
    left.axhline(REST, color="grey", lw=0.5)
    left.set_yscale("log")
    left.set_xlabel("layer thickness (grains)")
    left.set_ylabel("mean down-slope speed over t = 1–3 s (m/s)")
    left.set_title("22°, d = 2 mm, frictionless side walls 4 grains apart")
    left.legend(fontsize=7, ncol=2)

    matched = defaultdict(dict)
    for r in rows:
        if r["law"] == "matched":
            matched[(r["friction"], r["thickness"])][r["model"]] = float(r["mean_speed"])
    for (mu, thickness), speeds in sorted(matched.items()):
        if {"soft", "lammps"} <= speeds.keys():
            right.plot([speeds["lammps"]], [speeds["soft"]], "o", color="tab:blue" if mu == "0.3" else "tab:red")
            right.annotate(f"μ {mu}, {thickness} grains", (speeds["lammps"], speeds["soft"]),
                           textcoords="offset points", xytext=(5, -10), fontsize=7)
    top = 1.1 * max(max(s.values()) for s in matched.values())
    right.plot([0, top], [0, top], "k-", lw=0.6, label="equal")
    right.set_xlim(0, top)
    right.set_ylim(0, top)
    right.set_xlabel("LAMMPS: mean down-slope speed (m/s)")
    right.set_ylabel("grainflow soft DEM (m/s)")
    right.set_title("the same layers and law in both codes")
    right.legend(fontsize=8)
    by_thickness = defaultdict(list)
    for r in rows:
        if r["model"] == "cocd" and r["status"] == "flowing":
            by_thickness[int(r["thickness"])].append((float(r["dt"]), float(r["mean_speed"])))
    fall_time = (DIAMETER / GRAVITY) ** 0.5
    for thickness, points in sorted(by_thickness.items()):
        points.sort()
        shortest = points[0][1]
        steps.plot([dt / fall_time for dt, _ in points], [v / shortest for _, v in points], "s-",
                   label=f"{thickness} grains (at {points[0][0] * 1e3:g} ms: {shortest:.3f} m/s)")
    steps.axvline(1.0, color="grey", lw=0.5)
    steps.annotate("the paper's 3D step", (1.0, 0.9), textcoords="offset points", xytext=(-100, 0), fontsize=7)
    steps.set_ylim(0, 1.1)
    steps.set_xlabel("COCD step Δt / sqrt(d/g)")
    steps.set_ylabel("mean speed / its speed at the shortest step")
    steps.set_title("COCD: the layers slow down with the step")
    steps.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
