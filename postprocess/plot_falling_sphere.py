#!/usr/bin/env python3
"""Charts of the falling-sphere sweep (scripts/falling_sphere_sweep.py):
settling velocity against time for each run beside eq. 20 (initial slope)
and the Schiller-Naumann terminal velocity (eq. 21); the speed-accuracy
chart: terminal-Reynolds error against wall time, one point per resolution;
and the step dependence at D/dx = 8: the error against the step under eq. 7
and with the forcing step held (coupling.forcing_step).
The velocity histories are read from TRACKS (run, t, z, vz).

usage: postprocess/plot_falling_sphere.py [CSV] [TRACKS] [PNG]
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "docs/validation/falling_sphere.csv")
tracks = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, "docs/validation/falling_sphere_tracks.csv")
target = sys.argv[3] if len(sys.argv) > 3 else os.path.join(root, "docs/validation/falling_sphere.png")
rows = [r for r in csv.DictReader(open(source)) if r["status"] == "ok"]

D, G = 0.01, 9.81
time_unit = (D / G) ** 0.5
speed_unit = (G * D) ** 0.5
fig, (history, chart, steps) = plt.subplots(1, 3, figsize=(16, 4.3))
histories = {}
for line in csv.DictReader(open(tracks)):
    t, w = histories.setdefault(line["run"], ([], []))
    t.append(float(line["t"]) / time_unit)
    w.append(-float(line["vz"]) / speed_unit)
for r in rows:
    # The step-dependence runs at D/dx = 8 are in the third panel only.
    held = bool(r.get("forcing_step"))
    if r["run"] not in histories or (held and r["cells_per_diameter"] == "8"):
        continue
    t, w = histories[r["run"]]
    label = (f"D/Δx = {r['cells_per_diameter']}, box {float(r['box_width_over_d']):g} D, "
             f"Δt (g/D)^½ {'≤ ' if r.get('cfl') else '= '}{float(r['dt_sqrt_g_over_d']):.3g}"
             + (", forcing step held" if held else ""))
    history.plot(t, w, lw=1, label=label)
first = rows[0]
terminal = float(first["schiller_naumann_reynolds"]) / float(first["terminal_reynolds"]) \
    * float(first["terminal_velocity"]) / speed_unit
slope = (4.0 - 1.0) / (4.0 + 0.5)  # eq. 20 in units of g
history.axhline(terminal, color="k", ls=":", lw=1, label="Schiller–Naumann (eq. 21)")
history.plot([0, 1.5], [0, slope * 1.5], "k--", lw=1, label="added mass (eq. 20)")
history.set_xlabel("t (g/D)^½")
history.set_ylabel("settling velocity / (g D)^½")
history.set_title("ρp/ρ = 4, Ar = 800")
history.legend(fontsize=7)

reference_runs = [r for r in rows if float(r["box_width_over_d"]) == 8.0]
# The speed-accuracy chart takes the runs with today's load (over the
# volume moving with the grain) when they are there.
current = os.path.join(os.path.dirname(source), "falling_sphere_moving_volume.csv")
chart_runs = reference_runs
if os.path.exists(current):
    chart_runs = [r for r in csv.DictReader(open(current))
                  if r["status"] == "ok" and float(r["box_width_over_d"]) == 8.0]
by_resolution = {}
for r in chart_runs:
    key = int(r["cells_per_diameter"])
    # One point per resolution: the run at the paper's CFL (dt scaled with
    # dx); the last such row wins.
    if abs(float(r["dt_sqrt_g_over_d"]) * key / 20.0 - 0.04) < 1e-6:
        by_resolution[key] = r
points = sorted(by_resolution.items())
seconds = [float(r["wall_seconds"]) for _, r in points]
error = [abs(float(r["terminal_reynolds_error"])) * 100 for _, r in points]
chart.loglog(seconds, error, "o-", label="3D, box 8 D (Cartesian)")
for (n, _), s, e in zip(points, seconds, error):
    chart.annotate(f"D/Δx = {n}", (s, e), textcoords="offset points", xytext=(5, 5))
# The (r, z) runs of the paper's own domain
# (scripts/falling_sphere_axisymmetric_sweep.py), when there are some.
axisymmetric = os.path.join(os.path.dirname(source), "falling_sphere_axisymmetric.csv")
if os.path.exists(axisymmetric):
    rz = list(csv.DictReader(open(axisymmetric)))
    rz_seconds = [float(r["wall_seconds"]) for r in rz]
    rz_error = [abs(float(r["terminal_reynolds_error"])) * 100 for r in rz]
    chart.loglog(rz_seconds, rz_error, "s-", label="(r, z), the paper's 20 D × 40 D")
    for r, s_, e in zip(rz, rz_seconds, rz_error):
        chart.annotate(f"D/Δx = {r['cells_per_diameter']}", (s_, e), textcoords="offset points",
                       xytext=(5, -12))
chart.legend(fontsize=8)
chart.set_xlabel("wall time of the run [s] (2 threads)")
chart.set_ylabel("|terminal Re error| against Schiller–Naumann [%]")
chart.set_title("speed against accuracy (paper's CFL)")

coarse = [r for r in reference_runs if r["cells_per_diameter"] == "8" and not r.get("cfl")]
for held, marker, name in [(False, "o-", "eq. 7 at every stage"),
                           (True, "s-", "forcing step held at 0.1 (D/g)^½")]:
    chosen = sorted((float(r["dt_sqrt_g_over_d"]), float(r["terminal_reynolds_error"]) * 100)
                    for r in coarse if bool(r.get("forcing_step")) == held)
    if chosen:
        steps.semilogx(*zip(*chosen), marker, label=name)
steps.axhline(0.0, color="k", lw=0.5)
steps.set_xlabel("Δt (g/D)^½")
steps.set_ylabel("terminal Re error against Schiller–Naumann [%]")
steps.set_title("step dependence of the forcing (D/Δx = 8, box 8 D)")
steps.legend(fontsize=8)
fig.tight_layout()
fig.savefig(target, dpi=120)
print(f"wrote {target}")
