#!/usr/bin/env python3
"""Grains at rest in a box (Martin et al. 2022, Fig. 3) over the solver
tolerance: runs `cases/static_box.toml` for each contact model and
tolerance and writes one CSV row per run (largest kinetic-to-potential
ratio after settling, certificates, solver effort, cost).

    scripts/static_box_sweep.py --out docs/validation/static_box.csv \
        --model cocd --tolerance 1e-1 --tolerance 1e-2 ... [--model nscd ...]

Each model is run with every tolerance given. With --resume (the paper's
box of 110,233 spheres, `cases/static_box_3d_paper.toml`, runs for hours)
every run writes checkpoints, a run cut short goes on from its newest one,
and a run that ended is read back, not run again.
"""
import argparse
import csv
import os
import sys

from grainflow_run import finished_summary, run_case

FIELDS = [
    "model", "tolerance", "status", "max_kinetic_to_potential", "final_kinetic_to_potential",
    "max_coulomb_violation", "max_penetration", "max_complementarity", "mean_iterations",
    "max_iterations", "unconverged_steps", "mean_candidates", "seconds_per_solve",
    "wall_seconds", "steps",
]


def run(binary, case, model, tolerance, workdir, extra, resume=False, threads=None):
    out = os.path.join(workdir, f"static_box_{model}_{tolerance:g}")
    sets = [f'contact.model="{model}"', f"contact.tolerance={tolerance}"] + extra
    summary = finished_summary(out) if resume else None
    refusal = None
    if summary is None:
        summary, refusal = run_case(binary, case, out, sets, resume=resume, threads=threads)
    row = {"model": model, "tolerance": tolerance}
    if summary is None:
        row["status"] = refusal
        return row
    row["status"] = summary["status"]
    for key in FIELDS:
        if key in summary["metrics"]:
            row[key] = summary["metrics"][key]
    row["wall_seconds"] = summary["wall_seconds"]
    row["steps"] = summary["steps"]
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--model", action="append", required=True, choices=["cocd", "nscd"])
    parser.add_argument("--tolerance", action="append", type=float, required=True)
    parser.add_argument("--case", default="cases/static_box.toml")
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--workdir", default="/tmp/grainflow_static_box")
    parser.add_argument("--set", action="append", default=[], dest="extra")
    parser.add_argument("--resume", action="store_true",
                        help="keep the runs that ended, resume those cut short (the case needs [checkpoint])")
    parser.add_argument("--threads", type=int)
    args = parser.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        for model in args.model:
            for tolerance in args.tolerance:
                row = run(args.binary, args.case, model, tolerance, args.workdir, args.extra,
                          args.resume, args.threads)
                writer.writerow(row)
                f.flush()
                print(row, file=sys.stderr)


if __name__ == "__main__":
    main()
