#!/usr/bin/env python3
"""Hard against soft contact on one 2D column collapse
(`cases/column_collapse_cocd_2d.toml`, Martin et al. 2022 sections 3.4–3.5):
runs each (model, time step) given and writes one CSV row per run (runout,
certificates, solver effort, cost) and every run's height profiles.

    scripts/cocd_collapse_runs.py --out docs/validation/cocd_collapse.csv \
        --run cocd:1e-3 --run cocd:1e-4 --run nscd:1e-3 --run soft:5e-6 ...

A soft run uses restitution 0.5 and contact time 1e-4 s unless --soft-set
says otherwise. The profiles go to `<out without .csv>_profiles.csv` with
the model and time step of each row.
"""
import argparse
import csv
import os
import sys

from grainflow_run import run_case

FIELDS = [
    "model", "dt", "status", "runout", "final_front", "aspect_ratio", "steps", "wall_seconds",
    "seconds_per_solve", "mean_iterations", "max_iterations", "unconverged_steps",
    "mean_candidates", "max_coulomb_violation", "max_penetration", "max_complementarity",
    "stop_reason",
]


def run(binary, case, model, dt, workdir, soft_sets, extra):
    out = os.path.join(workdir, f"collapse_{model}_{dt:g}")
    sets = [f'contact.model="{model}"', f"time.dt={dt}"]
    sets += (soft_sets if model == "soft" else []) + extra
    summary, refusal = run_case(binary, case, out, sets)
    row = {"model": model, "dt": dt}
    if summary is None:
        row["status"] = "refused"
        row["stop_reason"] = refusal
        return row, []
    row["status"] = summary["status"]
    row["stop_reason"] = summary["stop_reason"]
    row["steps"] = summary["steps"]
    row["wall_seconds"] = summary["wall_seconds"]
    for key in FIELDS:
        if key in summary["metrics"]:
            row[key] = summary["metrics"][key]
    profiles = []
    path = os.path.join(out, "profiles.csv")
    if os.path.exists(path):
        with open(path) as f:
            for p in csv.DictReader(f):
                profiles.append({"model": model, "dt": dt, **p})
    return row, profiles


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--run", action="append", required=True, help="model:dt")
    parser.add_argument("--case", default="cases/column_collapse_cocd_2d.toml")
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--workdir", default="/tmp/grainflow_cocd_collapse")
    parser.add_argument("--soft-set", action="append",
                        default=["contact.restitution=0.5", "contact.contact_time=1e-4"])
    parser.add_argument("--set", action="append", default=[], dest="extra")
    args = parser.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    profile_path = args.out[:-4] + "_profiles.csv" if args.out.endswith(".csv") else args.out + "_profiles.csv"
    with open(args.out, "w", newline="") as f, open(profile_path, "w", newline="") as g:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        profiles = csv.DictWriter(g, fieldnames=["model", "dt", "time_after_release", "x", "height", "top"])
        profiles.writeheader()
        for spec in args.run:
            model, dt = spec.split(":")
            row, rows = run(args.binary, args.case, model, float(dt), args.workdir,
                            args.soft_set, args.extra)
            writer.writerow(row)
            profiles.writerows(rows)
            f.flush()
            g.flush()
            print(row, file=sys.stderr)


if __name__ == "__main__":
    main()
