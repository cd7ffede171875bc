#!/usr/bin/env python3
"""Restitution over e_n against the Stokes number of the bouncing sphere
(Izard et al. 2014, section 4.1), this version first, beside the fit
through the experiments of Gondret et al. and Joseph et al.
(../shared/reference/bouncing_e_over_emax_fit_curves.csv: Legendre's
exp(-35/St) with the experiments' spread of about 0.1, and 1 - 10/St;
fit curves, not data points).

Drawn from the rows of scripts/bouncing_sphere_sweep.py in
docs/validation/:
- the sweep of this version at D/Δx = 8, the paper's forcing of the
  first cells at the wall (the default), read through the film (filled,
  joined: the peak after the stages less the loss the film of eq. 19
  would still take on the way out, src/analysis/sphere_in_fluid.rs), at
  the peak (open) and at step ends only (crosses)
  (bouncing_sphere_wall_layers_2026-12-04.csv);
- seven releases 0.05 mm apart at St ≈ 38 (the contact at other phases of
  its fluid step): their range as a bar, their mean as a diamond
  (bouncing_sphere_phases_3d.csv, eq. 7 rows);
- the first cells at the wall left to the fluid on the same version
  (bouncing_sphere_pointwise_cfl.csv, grey);
- the same sphere on the axis in (r, z), forced layer, D/Δx = 20 and 40
  (bouncing_sphere_axisymmetric_wall_layers.csv,
  bouncing_sphere_axisymmetric_40.csv; stars);
- without the film (an earlier version, 2026-12-01, the peak;
  bouncing_sphere.csv), dashed;
- the film alone (dash-dotted): eq. 19 from gap R/2 in to contact and out
  again, the contact returning e_n, 1 - (1 + 1/e_n) ln(1 + R/(2 eta)) / St,
  with e_n and eta of cases/bouncing_sphere.toml.

usage: postprocess/plot_bouncing_sphere.py [PNG] [REFERENCE_CSV]
"""
import csv
import math
import os
import sys
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
data = os.path.join(root, "docs/validation")
target = sys.argv[1] if len(sys.argv) > 1 else os.path.join(data, "bouncing_sphere.png")
reference = sys.argv[2] if len(sys.argv) > 2 else os.path.join(
    root, "../shared/reference/bouncing_e_over_emax_fit_curves.csv")


def rows_of(name, keep=lambda r: True):
    """The finished runs of a table in docs/validation, by Stokes number."""
    path = os.path.join(data, name)
    if not os.path.exists(path):
        return []
    rows = [r for r in csv.DictReader(open(path))
            if r["status"] == "ok" and r["stokes"] and keep(r)]
    return sorted(rows, key=lambda r: float(r["stokes"]))


def column(rows, key):
    return [float(r[key]) for r in rows]


fig, ax = plt.subplots(figsize=(10, 4.5))
if os.path.exists(reference):
    lines = [l for l in open(reference) if not l.startswith("#")]
    curves = list(csv.DictReader(lines))
    st = column(curves, "St")
    legendre = column(curves, "e_over_emax_legendre2006_exp")
    ax.fill_between(st, [max(v - 0.1, 0) for v in legendre], [v + 0.1 for v in legendre],
                    color="0.85", label="exp(−35/St) ± 0.1 (experiments' spread)")
    ax.plot(st, legendre, "k-", lw=1)
    ax.plot(st, column(curves, "e_over_emax_linear_Stc10"), "k:", lw=1, label="1 − 10/St")

case = tomllib.load(open(os.path.join(root, "cases/bouncing_sphere.toml"), "rb"))
e_n = case["contact"]["restitution"]
eta = case["lubrication"]["roughness"]
film_critical = (1.0 + 1.0 / e_n) * math.log(1.0 + 0.5 / eta)
st = [10 ** (k / 20) for k in range(0, 81)]
ax.plot(st, [max(0.0, 1.0 - film_critical / s) for s in st], "-.", color="tab:red", lw=1,
        label=f"film alone (eq. 19, η/R = {eta:g}): 1 − {film_critical:.1f}/St")

# This version, the default (forced) layer.
now = rows_of("bouncing_sphere_wall_layers_2026-12-04.csv",
              lambda r: r["wall_layer"] == "forced" and r["lubrication"] == "True")
stokes = column(now, "stokes")
line, = ax.plot(stokes, column(now, "restitution_ratio_through_film"), "o-",
                label="grainflow, D/Δx = 8, this version, through the film")
ax.plot(stokes, column(now, "restitution_ratio"), "o", mfc="none", color=line.get_color(),
        label="  same, peak after the stages")
step_ends = [float(r["restitution_ratio"]) * float(r["rebound_velocity_step_end"])
             / float(r["rebound_velocity"]) if float(r["rebound_velocity"]) > 0 else 0.0
             for r in now]
ax.plot(stokes, step_ends, "x", color=line.get_color(), alpha=0.6,
        label="  same, read at step ends only")

# Seven releases at St ≈ 38: the contact's phase in its step.
phases = rows_of("bouncing_sphere_phases_3d.csv", lambda r: not r["settings"])
if phases:
    film = column(phases, "restitution_ratio_through_film")
    mean_stokes = sum(column(phases, "stokes")) / len(phases)
    ax.plot([mean_stokes] * 2, [min(film), max(film)], "-", color=line.get_color(), lw=3,
            alpha=0.5)
    ax.plot([mean_stokes], [sum(film) / len(film)], "D", color=line.get_color(),
            label=f"  {len(phases)} releases 0.05 mm apart: range and mean")

# The first cells left to the fluid, on the same version.
free = rows_of("bouncing_sphere_pointwise_cfl.csv", lambda r: r["lubrication"] == "True")
ax.plot(column(free, "stokes"), column(free, "restitution_ratio_through_film"), "o:",
        color="0.45", mfc="none", lw=0.8,
        label="grainflow, D/Δx = 8, first cells at the wall free")

# The same sphere on the axis, in (r, z).
for name, resolution in [("bouncing_sphere_axisymmetric_wall_layers.csv", 20),
                         ("bouncing_sphere_axisymmetric_40.csv", 40)]:
    rz = rows_of(name, lambda r: r["lubrication"] == "True"
                 and "free" not in r["settings"] and "renewal" not in r["settings"])
    if rz:
        ax.plot(column(rz, "stokes"), column(rz, "restitution_ratio_through_film"), "*",
                ms=8, ls="none",
                label=f"grainflow (r, z), D/Δx = {resolution}, through the film")

# Without the film (an earlier version, read at the peak).
dry = rows_of("bouncing_sphere.csv",
              lambda r: r["lubrication"] == "False" and r["cells_per_diameter"] == "8")
ax.plot(column(dry, "stokes"), column(dry, "restitution_ratio"), "o--", mfc="none",
        color="tab:purple", lw=0.8,
        label="grainflow, D/Δx = 8, without the film (2026-12-01), peak")

ax.set_xscale("log")
ax.set_xlabel("St = (ρp + ρ/2) V_T D / (9 μ)")
ax.set_ylabel("e / e_n")
ax.set_ylim(-0.05, 1.1)
ax.set_title("sphere bouncing on a wall, ρp/ρ = 8")
ax.legend(fontsize=6.5, loc="center left", bbox_to_anchor=(1.01, 0.5))
fig.tight_layout()
fig.savefig(target, dpi=120)
print(f"wrote {target}")
