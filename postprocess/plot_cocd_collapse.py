#!/usr/bin/env python3
"""Hard against soft contact on the 2D column collapse, from
scripts/cocd_collapse_runs.py (Martin et al. 2022, Fig. 2 and 4):

1. height profiles h(x) of COCD at each time step and the relative error
   ||h_dt - h_ref|| / ||h_ref|| against the smallest COCD step, per time;
2. COCD against NSCD (and soft) profiles at three times;
3. runout error against wall time and against dt for each model, relative
   to the COCD runout at its smallest step (failed runs marked).

Prints the profile errors and writes FIGURE.png (three panels) and, beside
it, FIGURE_errors.csv.

usage: postprocess/plot_cocd_collapse.py FIGURE.png RUNS.csv
"""
import csv, math, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

figure, runs_path = sys.argv[1], sys.argv[2]
profiles_path = runs_path[:-4] + "_profiles.csv"
runs = list(csv.DictReader(open(runs_path)))
profiles = {}
for r in csv.DictReader(open(profiles_path)):
    key = (r["model"], float(r["dt"]), float(r["time_after_release"]))
    profiles.setdefault(key, []).append((float(r["x"]), float(r["height"])))


def norm(values):
    return math.sqrt(sum(v * v for v in values))


cocd_dts = sorted({k[1] for k in profiles if k[0] == "cocd"})
reference_dt = cocd_dts[0]
times = sorted({k[2] for k in profiles})
errors = []
for (model, dt, t), prof in sorted(profiles.items()):
    ref = profiles.get(("cocd", reference_dt, t))
    if ref is None or len(ref) != len(prof):
        continue
    e = norm([a[1] - b[1] for a, b in zip(prof, ref)]) / norm([b[1] for b in ref])
    errors.append(dict(model=model, dt=dt, time_after_release=t, profile_error=e))
    print(f"{model} dt={dt:g} t={t:g}: profile error {e:.4f} against COCD dt={reference_dt:g}")
with open(figure[:-4] + "_errors.csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=["model", "dt", "time_after_release", "profile_error"])
    w.writeheader()
    w.writerows(errors)

fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
ax = axes[0]
shown = [t for t in times if t in (times[0], times[len(times) // 2], times[-1])]
for dt, ls in zip(cocd_dts, ["-", "--", ":", "-."]):
    for t in shown:
        prof = profiles.get(("cocd", dt, t))
        if prof:
            ax.plot([p[0] for p in prof], [p[1] for p in prof], ls, lw=1,
                    label=f"dt={dt:g} s, t={t:g} s")
ax.set_xlabel("x [m]")
ax.set_ylabel("h [m]")
ax.set_title("COCD profiles against the time step (cf. Fig. 2)", fontsize=9)
ax.legend(fontsize=6)

ax = axes[1]
for model, ls in [("cocd", "-"), ("nscd", "--"), ("soft", ":")]:
    dts = sorted({k[1] for k in profiles if k[0] == model})
    if not dts:
        continue
    for t in shown:
        prof = profiles.get((model, dts[0], t))
        if prof:
            ax.plot([p[0] for p in prof], [p[1] for p in prof], ls, lw=1,
                    label=f"{model.upper()} dt={dts[0]:g}, t={t:g} s")
ax.set_xlabel("x [m]")
ax.set_title("COCD against NSCD and soft DEM (cf. Fig. 4)", fontsize=9)
ax.legend(fontsize=6)

ax = axes[2]
reference = [float(r["runout"]) for r in runs
             if r["model"] == "cocd" and float(r["dt"]) == reference_dt and r["status"] == "ok"]
for model, marker in [("cocd", "o"), ("nscd", "s"), ("soft", "^")]:
    ok = [r for r in runs if r["model"] == model and r["status"] == "ok" and r.get("runout")]
    if reference and ok:
        pts = sorted((float(r["wall_seconds"]), abs(float(r["runout"]) / reference[0] - 1.0) + 1e-4,
                      float(r["dt"])) for r in ok)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker + "-", label=model.upper())
        for p in pts:
            ax.annotate(f"{p[2]:g}", (p[0], p[1]), fontsize=6)
    bad = [r for r in runs if r["model"] == model and r["status"] != "ok"]
    for r in bad:
        ax.annotate(f"{model} dt={float(r['dt']):g}: {r['status']}", (0.02, 0.02 + 0.05 * bad.index(r)),
                    xycoords="axes fraction", fontsize=6, color="red")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("wall time [s]")
ax.set_ylabel("|runout / runout(COCD, smallest dt) - 1| + 1e-4")
ax.set_title("speed against accuracy (labels: dt [s])", fontsize=9)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(figure, dpi=120)
