#!/usr/bin/env python3
"""The immersed avalanche (cases/immersed_avalanche.toml, Izard et al. 2014,
section 4.2) from the outputs of its inclined-bed analysis: (a) the moving
grains' mean streamwise velocity, and that of the bed's lower and upper
halves, against t (g/D)^1/2; (b) the fluid's and the grains' streamwise
velocity profiles at the output nearest t (g/D)^1/2 = 102, where the paper
plots them, with the clear fluid's steady film profile divided by 10 (the
paper's dashed line); (c) the Shields number at the bed surface.

Copies the series and the chosen profiles to docs/validation/ and prints
the figures the validation page quotes.

usage: postprocess/plot_avalanche.py RUN_DIR [PNG]
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
run = sys.argv[1]
target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, "docs/validation/avalanche.png")
G = 9.81
TILT = math.radians(22.0)
H = 0.05  # box height [m]: 10 D


def rows(name):
    return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(open(os.path.join(run, name)))]


series = rows("bed_series.csv")
case = tomllib.load(open(os.path.join(run, "case.toml"), "rb"))
D = 2.0 * case["particles"]["radius"]
nu = case["fluid"]["viscosity"] / case["fluid"]["density"]
scale_v, scale_t = math.sqrt(G * D), math.sqrt(D / G)

target_t = 102.0
times = sorted({r["t"] for r in rows("bed_profiles.csv")})
chosen = min(times, key=lambda t: abs(t / scale_t - target_t))
fluid = [r for r in rows("bed_profiles.csv") if r["t"] == chosen]
grains = [r for r in rows("grain_profiles.csv") if r["t"] == chosen]

fig, axes = plt.subplots(1, 3, figsize=(14, 4.5))
ax = axes[0]
ts = [r["t_scaled"] for r in series]
ax.plot(ts, [r["grain_velocity"] for r in series], "k-", label="all moving grains")
ax.plot(ts, [r["lower_half_velocity"] for r in series], "b-", label="lower half of the bed")
ax.plot(ts, [r["upper_half_velocity"] for r in series], "r-", label="upper half")
ax.axvline(50.0, color="0.6", ls=":", label="paper: whole bed set in motion")
ax.set_xlabel("t (g/D)$^{1/2}$")
ax.set_ylabel("mean streamwise grain velocity / (g D)$^{1/2}$")
ax.legend(fontsize=8)

ax = axes[1]
g_x = G * math.sin(TILT)
z = [r["z"] for r in fluid]
film = [g_x / nu * (H * zz - 0.5 * zz * zz) / 10.0 for zz in z]
ax.plot([r["fluid_velocity"] / scale_v for r in fluid], [zz / D for zz in z], "b-", label="fluid")
ax.plot([r["grain_velocity"] / scale_v for r in grains], [r["z"] / D for r in grains], "ko", ms=4,
        label="grains")
ax.plot([f / scale_v for f in film], [zz / D for zz in z], "b--", label="film without grains / 10")
ax.set_xlabel("streamwise velocity / (g D)$^{1/2}$")
ax.set_ylabel("z / D")
ax.set_title(f"t (g/D)$^{{1/2}}$ = {chosen / scale_t:.1f}")
ax.legend(fontsize=8)

ax = axes[2]
ax.plot(ts, [r["shields_number"] for r in series], "k-")
ax.set_xlabel("t (g/D)$^{1/2}$")
ax.set_ylabel("Shields number at the bed surface")
fig.tight_layout()
fig.savefig(target, dpi=120)

out = os.path.join(root, "docs/validation")
with open(os.path.join(out, "avalanche_series.csv"), "w") as f:
    f.write(open(os.path.join(run, "bed_series.csv")).read())
with open(os.path.join(out, "avalanche_profiles.csv"), "w") as f:
    f.write("z_over_D,fluid_velocity_scaled,solid_fraction\n")
    for r in fluid:
        f.write(f"{r['z'] / D:.4f},{r['fluid_velocity'] / scale_v:.6g},{r['solid_fraction']:.4f}\n")
with open(os.path.join(out, "avalanche_grain_profiles.csv"), "w") as f:
    f.write("z_over_D,grain_velocity_scaled,grains\n")
    for r in grains:
        f.write(f"{r['z'] / D:.4f},{r['grain_velocity'] / scale_v:.6g},{int(r['grains'])}\n")

print(f"profiles at t (g/D)^1/2 = {chosen / scale_t:.2f}")
for r in series:
    if abs(r["t_scaled"] - round(r["t_scaled"] / 10) * 10) < 1.2:
        print(f"  t* {r['t_scaled']:7.2f}: grains {r['grain_velocity']:.4f}, lower "
              f"{r['lower_half_velocity']:.4f}, upper {r['upper_half_velocity']:.4f}, "
              f"surface {r['bed_surface']:.2f} D, Shields {r['shields_number']:.4f}")
