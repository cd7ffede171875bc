#!/usr/bin/env python3
"""Hard against soft contact on a column collapse (2D or 3D), from
scripts/cocd_collapse_runs.py (Martin et al. 2022, Fig. 2 and 4):

(a) COCD mass profiles h(x) at three times for several time steps;
(b) COCD, NSCD and soft-DEM profiles at their smallest step;
(c) the relative profile error ||h - h_ref|| / ||h_ref|| against the COCD
    profile at its smallest step, against dt, per model, at two times;
(d) runout error against wall time per model (labels: dt), relative to the
    COCD runout at its smallest step.

Prints every profile error and writes FIGURE.png and, beside it,
FIGURE_errors.csv. A model named `cocd-clarabel` (the same program solved
by Clarabel) shows how far two solutions to ε drift apart.

usage: postprocess/plot_cocd_collapse.py FIGURE.png RUNS.csv
"""
import csv, math, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

figure, runs_path = sys.argv[1], sys.argv[2]
runs = list(csv.DictReader(open(runs_path)))
profiles = {}
for r in csv.DictReader(open(runs_path[:-4] + "_profiles.csv")):
    key = (r["model"], float(r["dt"]), float(r["time_after_release"]))
    profiles.setdefault(key, []).append((float(r["x"]), float(r["height"])))


def norm(values):
    return math.sqrt(sum(v * v for v in values))


def error(prof, ref):
    return norm([a[1] - b[1] for a, b in zip(prof, ref)]) / norm([b[1] for b in ref])


cocd_dts = sorted({k[1] for k in profiles if k[0] == "cocd"})
reference_dt = cocd_dts[0]
times = sorted({k[2] for k in profiles})
errors = []
for (model, dt, t), prof in sorted(profiles.items()):
    ref = profiles.get(("cocd", reference_dt, t))
    if ref is None or len(ref) != len(prof) or (model == "cocd" and dt == reference_dt):
        continue
    e = error(prof, ref)
    errors.append(dict(model=model, dt=dt, time_after_release=t, profile_error=e))
    print(f"{model} dt={dt:g} t={t:g}: profile error {e:.4f} against COCD dt={reference_dt:g}")
with open(figure[:-4] + "_errors.csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=["model", "dt", "time_after_release", "profile_error"])
    w.writeheader()
    w.writerows(errors)

styles = {"cocd": "o-", "cocd-clarabel": "D", "nscd": "s--", "soft": "^:"}
shown = [times[0], times[len(times) // 2], times[-1]]
fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
ax = axes[0][0]
for dt, ls in zip([d for d in cocd_dts if d in (cocd_dts[-1], 1e-3, cocd_dts[0])], ["--", "-", ":"]):
    for t, color in zip(shown, ["C0", "C1", "C2"]):
        prof = profiles.get(("cocd", dt, t))
        if prof:
            ax.plot([p[0] for p in prof], [p[1] for p in prof], ls, color=color, lw=1,
                    label=f"dt={dt:g} s, t={t:g} s")
ax.set_xlim(0, 0.5)
ax.set_xlabel("x [m]")
ax.set_ylabel("mass profile h [m]")
ax.set_title("(a) COCD against the time step (cf. Fig. 2)", fontsize=9)
ax.legend(fontsize=6)

ax = axes[0][1]
for model, ls in [("cocd", "-"), ("nscd", "--"), ("soft", ":")]:
    dts = sorted({k[1] for k in profiles if k[0] == model})
    if not dts:
        continue
    for t, color in zip(shown, ["C0", "C1", "C2"]):
        prof = profiles.get((model, dts[0], t))
        if prof:
            ax.plot([p[0] for p in prof], [p[1] for p in prof], ls, color=color, lw=1,
                    label=f"{model.upper()} dt={dts[0]:g}, t={t:g} s")
ax.set_xlim(0, 0.5)
ax.set_xlabel("x [m]")
ax.set_title("(b) COCD against NSCD and the soft DEM (cf. Fig. 4)", fontsize=9)
ax.legend(fontsize=6)

ax = axes[1][0]
for model in styles:
    for t, fill in zip([times[len(times) // 2], times[-1]], [None, "none"]):
        pts = sorted((e["dt"], e["profile_error"]) for e in errors
                     if e["model"] == model and e["time_after_release"] == t)
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], styles[model], mfc=fill,
                    label=f"{model.upper()}, t={t:g} s")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("dt [s]")
ax.set_ylabel(f"profile error against COCD dt={reference_dt:g} s")
ax.set_title("(c) profile error against the time step", fontsize=9)
ax.legend(fontsize=6)

ax = axes[1][1]
reference = [float(r["runout"]) for r in runs
             if r["model"] == "cocd" and float(r["dt"]) == reference_dt and r["status"] == "ok"]
for model in styles:
    ok = [r for r in runs if r["model"] == model and r["status"] == "ok" and r.get("runout")
          and not (model == "cocd" and float(r["dt"]) == reference_dt)]
    if reference and ok:
        pts = sorted((float(r["wall_seconds"]), abs(float(r["runout"]) / reference[0] - 1.0),
                      float(r["dt"])) for r in ok)
        ax.plot([p[0] for p in pts], [max(p[1], 1e-4) for p in pts], styles[model], label=model.upper())
        for p in pts:
            ax.annotate(f"{p[2]:g}", (p[0], max(p[1], 1e-4)), fontsize=6)
    for r in runs:
        if r["model"] == model and r["status"] != "ok":
            ax.annotate(f"{model} dt={float(r['dt']):g}: refused (past the stability limit)",
                        (0.02, 0.03), xycoords="axes fraction", fontsize=6, color="red")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("wall time [s]")
ax.set_ylabel(f"|runout / runout(COCD, dt={reference_dt:g}) - 1|")
ax.set_title("(d) runout error against cost (labels: dt [s])", fontsize=9)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(figure, dpi=110)
