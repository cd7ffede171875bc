#!/usr/bin/env python3
"""Charts of the falling-sphere sweep (scripts/falling_sphere_sweep.py):
settling velocity against time for each run beside eq. 20 (initial slope)
and the Schiller-Naumann terminal velocity (eq. 21); the speed-accuracy
chart: the terminal Reynolds number against the steady drag computed on a
body-fitted grid (scripts/sphere_drag_reference.py) against wall time, one
point per resolution, 3D and (r, z), eq. 7 and the renewal forcing;
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
history.axhline(terminal * 19.715 / float(first["schiller_naumann_reynolds"]), color="k", lw=1,
                label="steady drag, body-fitted grid")
history.plot([0, 1.5], [0, slope * 1.5], "k--", lw=1, label="added mass (eq. 20)")
history.set_xlabel("t (g/D)^½")
history.set_ylabel("settling velocity / (g D)^½")
history.set_title("ρp/ρ = 4, Ar = 800")
history.legend(fontsize=7)

reference_runs = [r for r in rows if float(r["box_width_over_d"]) == 8.0]
# The speed-accuracy chart: the terminal Reynolds number against the steady
# drag computed on a body-fitted grid (scripts/sphere_drag_reference.py,
# 19.715 at Ar = 800; docs/validation.md, section 7), the 3D runs corrected
# for their 8 D box by the (r, z) sphere in its cross-section (x 1.0141),
# each forcing at the paper's grain CFL number (dt scaled with dx).
BODY_FITTED = 19.715
BOX = 1.0141
folder = os.path.dirname(source)


def paper_cfl(per, dt):
    return abs(dt * per / 20.0 - 0.04) < 1e-6


def series(rows, per_key, dt_key, scale, wanted):
    chosen = {}
    for r in rows:
        per, dt = int(r[per_key]), float(r[dt_key])
        if r.get("status", "ok") == "ok" and paper_cfl(per, dt) and wanted(r):
            chosen[per] = r
    points = sorted(chosen.items())
    return ([float(r["wall_seconds"]) for _, r in points],
            [100.0 * (scale * float(r["terminal_reynolds"]) / BODY_FITTED - 1.0)
             for _, r in points],
            [per for per, _ in points])


def read(name):
    path = os.path.join(folder, name)
    return list(csv.DictReader(open(path))) if os.path.exists(path) else []


box8 = lambda r: float(r["box_width_over_d"]) == 8.0
rz_rows = read("forcing_step_axisymmetric.csv") + [
    dict(r, forcing_number="") for r in read("falling_sphere_axisymmetric.csv")]
curves = [
    (series(read("falling_sphere_moving_volume.csv"), "cells_per_diameter", "dt_sqrt_g_over_d",
            BOX, box8), "o-", "3D, 8 D box, eq. 7 (default)"),
    (series(read("falling_sphere_renewal.csv"), "cells_per_diameter", "dt_sqrt_g_over_d",
            BOX, box8), "o--", "3D, 8 D box, renewal"),
    (series(rz_rows, "cells_per_diameter", "dt_sqrt_g_over_d", 1.0,
            lambda r: r["forcing_number"] == ""), "s-", "(r, z), paper's 20 D × 40 D, eq. 7"),
    (series(rz_rows, "cells_per_diameter", "dt_sqrt_g_over_d", 1.0,
            lambda r: r["forcing_number"] == "renewal"), "s--",
     "(r, z), paper's 20 D × 40 D, renewal"),
]
for (seconds, error, pers), style, label in curves:
    if not seconds:
        continue
    chart.semilogx(seconds, error, style, label=label)
    for n, s_, e in zip(pers, seconds, error):
        chart.annotate(f"{n}", (s_, e), textcoords="offset points", xytext=(4, 4), fontsize=7)
sn = 100.0 * (float(first["schiller_naumann_reynolds"]) / BODY_FITTED - 1.0)
chart.axhspan(-1.0, 1.0, color="0.9", zorder=0, label="±1 % of the body-fitted drag")
chart.axhline(0.0, color="k", lw=0.5)
chart.axhline(sn, color="k", ls=":", lw=1, label=f"Schiller–Naumann ({sn:+.1f} %)")
chart.legend(fontsize=7)
chart.set_xlabel("wall time of the run [s] ((r, z): 1–2 threads; 3D: 2)")
chart.set_ylabel("terminal Re against the body-fitted drag [%]")
chart.set_title("speed against accuracy (paper's grain CFL; labels D/Δx)")

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
