#!/usr/bin/env python3
"""Restitution over e_n against the Stokes number from
scripts/bouncing_sphere_sweep.py, with and without lubrication, beside the
reference band of ../shared/reference/bouncing_e_over_emax_fit_curves.csv
(fit curves through the experiments of Gondret et al. and Joseph et al.,
not data points: Legendre's exp(-35/St) and the thin-film 1 - 10/St).

Where a viscosity was run from several release heights (the contact at
other phases of its fluid step), each marker is the median of the runs and
a bar spans their through-film readings.

Filled markers joined by lines: the rebound read through the film (its
peak after the stages less the loss the film of eq. 19 would still take on
the way out, src/analysis/sphere_in_fluid.rs); open markers: the peak itself, read
after every stage; crosses: the same runs read at the ends of fluid steps
only. Dash-dotted: the answer of
the lubrication film alone (eq. 19 from gap R/2 in to contact and out
again, the contact returning e_n), 1 - (1 + 1/e_n) ln(1 + R/(2 eta)) / St,
with e_n and eta of cases/bouncing_sphere.toml.

usage: postprocess/plot_bouncing_sphere.py [CSV] [PNG] [REFERENCE_CSV]
"""
import csv
import math
import os
import sys
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "docs/validation/bouncing_sphere.csv")
target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, "docs/validation/bouncing_sphere.png")
reference = sys.argv[3] if len(sys.argv) > 3 else os.path.join(
    root, "../shared/reference/bouncing_e_over_emax_fit_curves.csv")

fig, ax = plt.subplots(figsize=(10, 4.5))
if os.path.exists(reference):
    lines = [l for l in open(reference) if not l.startswith("#")]
    rows = list(csv.DictReader(lines))
    st = [float(r["St"]) for r in rows]
    legendre = [float(r["e_over_emax_legendre2006_exp"]) for r in rows]
    film = [float(r["e_over_emax_linear_Stc10"]) for r in rows]
    ax.fill_between(st, [max(v - 0.1, 0) for v in legendre], [v + 0.1 for v in legendre],
                    color="0.85", label="exp(−35/St) ± 0.1 (experiments' spread)")
    ax.plot(st, legendre, "k-", lw=1)
    ax.plot(st, film, "k:", lw=1, label="1 − 10/St")
case = tomllib.load(open(os.path.join(root, "cases/bouncing_sphere.toml"), "rb"))
e_n = case["contact"]["restitution"]
eta = case["lubrication"]["roughness"]
film_critical = (1.0 + 1.0 / e_n) * math.log(1.0 + 0.5 / eta)
st = [10 ** (k / 20) for k in range(0, 81)]
ax.plot(st, [max(0.0, 1.0 - film_critical / s) for s in st], "-.", color="tab:red", lw=1,
        label=f"film alone (eq. 19, η/R = {eta:g}): 1 − {film_critical:.1f}/St")
def median(values):
    values = sorted(values)
    middle = len(values) // 2
    return values[middle] if len(values) % 2 else 0.5 * (values[middle - 1] + values[middle])


def releases_merged(rows):
    """One row per (resolution, lubrication, viscosity): the median over the
    releases of each reading, with the through-film reading's range."""
    groups = {}
    for r in rows:
        groups.setdefault((r["cells_per_diameter"], r["lubrication"], r["viscosity"]), []).append(r)
    merged = []
    for group in groups.values():
        row = dict(group[0])
        for key in ("stokes", "restitution_ratio", "restitution_ratio_through_film",
                    "rebound_velocity", "rebound_velocity_step_end"):
            if all(r.get(key) for r in group):
                row[key] = str(median(float(r[key]) for r in group))
        film = [float(r["restitution_ratio_through_film"]) for r in group
                if r.get("restitution_ratio_through_film")]
        row["film_range"] = (min(film), max(film)) if len(film) > 1 else None
        merged.append(row)
    return merged


runs = releases_merged(
    [r for r in csv.DictReader(open(source)) if r["status"] == "ok" and r["stokes"]])
markers = {"8": "o", "12": "s", "16": "D", "24": "^"}
for resolution in sorted({r["cells_per_diameter"] for r in runs}, key=int):
    for lubricated, style in [("True", "-"), ("False", "--")]:
        group = sorted((r for r in runs
                        if r["lubrication"] == lubricated and r["cells_per_diameter"] == resolution),
                       key=lambda r: float(r["stokes"]))
        if not group:
            continue
        stokes = [float(r["stokes"]) for r in group]
        label = "with lubrication" if lubricated == "True" else "without lubrication"
        marker = markers.get(resolution, "x")
        through_film = lubricated == "True" and all(
            r.get("restitution_ratio_through_film") for r in group)
        if through_film:
            line, = ax.plot(stokes, [float(r["restitution_ratio_through_film"]) for r in group],
                            marker, ls=style,
                            label=f"grainflow, D/Δx = {resolution}, {label}, through the film")
            # The spread over releases (the contact's phase in its step).
            for r, stokes_number in zip(group, stokes):
                if r["film_range"]:
                    ax.plot([stokes_number, stokes_number], r["film_range"], "-",
                            color=line.get_color(), lw=2.5,
                            alpha=0.5)
            ax.plot(stokes, [float(r["restitution_ratio"]) for r in group], marker, ls="none",
                    mfc="none", color=line.get_color(), label="  same, peak after the stages")
        else:
            line, = ax.plot(stokes, [float(r["restitution_ratio"]) for r in group],
                            marker, ls=style,
                            mfc="none" if lubricated == "False" else None,
                            label=f"grainflow, D/Δx = {resolution}, {label}, peak")
        # The same runs read at the ends of steps only (phase-dependent).
        if lubricated == "True" and all(r.get("rebound_velocity_step_end") for r in group):
            step_ends = [float(r["restitution_ratio"]) * float(r["rebound_velocity_step_end"])
                         / float(r["rebound_velocity"]) if float(r["rebound_velocity"]) > 0 else 0.0
                         for r in group]
            ax.plot(stokes, step_ends, "x", color=line.get_color(), alpha=0.6,
                    label="  same, read at step ends only")
# The (r, z) runs (scripts/bouncing_sphere_sweep.py --axisymmetric), if any:
# the same sphere on the axis of a cylinder of radius 3 D.
axisymmetric = os.path.join(os.path.dirname(source), "bouncing_sphere_axisymmetric.csv")
if os.path.exists(axisymmetric):
    rz = [r for r in csv.DictReader(open(axisymmetric)) if r["status"] == "ok" and r["stokes"]]
    for resolution in sorted({r["cells_per_diameter"] for r in rz}, key=int):
        for lubricated, style in [("True", "-"), ("False", "--")]:
            group = sorted((r for r in rz if r["lubrication"] == lubricated
                            and r["cells_per_diameter"] == resolution),
                           key=lambda r: float(r["stokes"]))
            if not group:
                continue
            key = "restitution_ratio_through_film" if lubricated == "True" else "restitution_ratio"
            ax.plot([float(r["stokes"]) for r in group], [float(r[key]) for r in group], "*",
                    ls=style, ms=8, mfc="none" if lubricated == "False" else None,
                    label=f"grainflow (r, z), D/Δx = {resolution}, "
                          f"{'with lubrication, through the film' if lubricated == 'True' else 'without lubrication, peak'}")
# The paper's forcing of the first cells at the wall (coupling.wall_layer =
# "forced"), the case's default until 2026-12-01, at D/Δx = 8.
forced = os.path.join(os.path.dirname(source), "bouncing_sphere_forced_wall_layer.csv")
if os.path.exists(forced):
    rows = sorted((r for r in releases_merged(
        [r for r in csv.DictReader(open(forced)) if r["status"] == "ok" and r["stokes"]])
        if r["cells_per_diameter"] == "8" and r["lubrication"] == "True"
        and r.get("restitution_ratio_through_film")), key=lambda r: float(r["stokes"]))
    ax.plot([float(r["stokes"]) for r in rows],
            [float(r["restitution_ratio_through_film"]) for r in rows], "o:", color="0.45",
            mfc="none", lw=0.8, label="grainflow, D/Δx = 8, first cells at the wall forced")
# The roughness study (scripts/bouncing_sphere_sweep.py --roughness), if run.
study = os.path.join(os.path.dirname(source), "bouncing_sphere_roughness.csv")
if os.path.exists(study):
    rows = sorted((r for r in csv.DictReader(open(study)) if r["status"] == "ok"),
                  key=lambda r: float(r["stokes"]))
    for roughness in sorted({r["roughness"] for r in rows}):
        group = [r for r in rows if r["roughness"] == roughness]
        critical = (1.0 + 1.0 / e_n) * math.log(1.0 + 0.5 / float(roughness))
        line, = ax.plot([float(r["stokes"]) for r in group],
                        [float(r["restitution_ratio"]) for r in group], "v-", lw=0.8,
                        label=f"grainflow, D/Δx = {group[0]['cells_per_diameter']}, "
                              f"η/R = {roughness}, first cells forced")
        ax.plot(st, [max(0.0, 1.0 - critical / s) for s in st], "-.", lw=0.8,
                color=line.get_color(), label=f"film alone, η/R = {roughness}: 1 − {critical:.1f}/St")
ax.set_xscale("log")
ax.set_xlabel("St = (ρp + ρ/2) V_T D / (9 μ)")
ax.set_ylabel("e / e_n")
ax.set_ylim(-0.05, 1.1)
ax.set_title("sphere bouncing on a wall, ρp/ρ = 8")
ax.legend(fontsize=6.5, loc="center left", bbox_to_anchor=(1.01, 0.5))
fig.tight_layout()
fig.savefig(target, dpi=120)
print(f"wrote {target}")
