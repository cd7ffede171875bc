#!/usr/bin/env python3
"""COCD's tolerance on a flowing scene: one erodible-bed deposit released
at each interior-point tolerance ε, two runs each (the second with |g|
perturbed in its eighth digit: the spread of single runs), measured
against the first run at the tightest ε: the relative L2 error of the
front's travel, the iterations and wall time, and how far the layer's
grains far ahead of the flow moved (a resting layer that creeps is where
the tolerance breaks).

    scripts/erodible_bed_tolerance.py --work /tmp/tolerance \\
        --out docs/validation/erodible_bed_tolerance.csv \\
        --diameter 0.004 --thickness 5 --slope 22 --end 1.0

The first ε rains the deposit (`scripts/erodible_bed_study.py`); the others
release a copy of it. Runs already finished in --work are kept. The
chart: postprocess/plot_erodible_bed_models.py OUT PNG.
"""
import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys

from erodible_bed_models import errors

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--work", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--diameter", type=float, default=0.004)
    parser.add_argument("--thickness", type=float, default=5.0, help="in mean diameters")
    parser.add_argument("--slope", type=float, default=22.0)
    parser.add_argument("--end", type=float, default=1.0)
    parser.add_argument("--tolerances", default="1e-8,1e-6,1e-5,1e-4,1e-3",
                        help="the first is the reference")
    parser.add_argument("--ahead", type=float, default=1.2,
                        help="the layer's grains that start beyond this x (m) are 'ahead'")
    args = parser.parse_args()
    tolerances = args.tolerances.split(",")
    study = [sys.executable, os.path.join(HERE, "erodible_bed_study.py"), "--binary", args.binary,
             "--diameter", str(args.diameter), "--thickness", f"{args.thickness:g}",
             "--slope", f"{args.slope:g}", "--end", str(args.end), "--members", "2",
             "--set", "parallel.threads=1"]
    deposit_name = f"deposit_{args.thickness:g}d.csv"
    first = os.path.join(args.work, f"e{tolerances[0]}")
    for e in tolerances:
        work = os.path.join(args.work, f"e{e}")
        os.makedirs(work, exist_ok=True)
        if e != tolerances[0] and not os.path.exists(os.path.join(work, deposit_name)):
            shutil.copy(os.path.join(first, deposit_name), work)
        subprocess.run(study + ["--work", work, "--out", os.path.join(args.work, f"e{e}.csv"),
                                "--set", f"contact.tolerance={e}"], check=True)

    run = f"run_{args.thickness:g}d_{args.slope:g}deg_cocd_0.001"
    deposit = list(csv.DictReader(open(os.path.join(first, deposit_name))))

    def folder(e, member):
        return os.path.join(args.work, f"e{e}", run + (f"_m{member}" if member else ""))

    def fronts(e, member):
        with open(os.path.join(folder(e, member), "front.csv")) as f:
            return list(csv.DictReader(f))

    reference = fronts(tolerances[0], 0)
    rows, series = [], []
    for e in tolerances:
        for member in (0, 1):
            with open(os.path.join(folder(e, member), "summary.json")) as f:
                summary = json.load(f)
            metrics = summary["metrics"]
            front = fronts(e, member)
            error, at_end = (0.0, 0.0) if (e, member) == (tolerances[0], 0) else errors(front, reference)
            with open(os.path.join(folder(e, member), "final_particles.csv")) as f:
                final = list(csv.DictReader(f))
            # The grains keep their order from the deposit to the end.
            ahead = [float(b["x"]) - float(a["x"]) for a, b in zip(deposit, final)
                     if float(a["x"]) > args.ahead]
            label = f"eps {e}" + (f" m{member}" if member else "")
            rows.append({
                "label": label, "model": "cocd", "tolerance": e, "member": member,
                "runout": round(metrics["runout"], 4), "front_error": round(error, 4),
                "travel_error_at_end": round(at_end, 4),
                "wall_seconds_per_simulated_second": round(summary["wall_seconds"] / args.end, 1),
                "mean_iterations": round(metrics["mean_iterations"], 2),
                "seconds_per_solve": round(metrics["seconds_per_solve"], 4),
                "layer_ahead_mean_shift_mm": round(1e3 * statistics.mean(ahead), 3),
                "layer_ahead_largest_shift_mm": round(1e3 * max(ahead), 2),
            })
            series += [dict(r, label=label) for r in front]
    for path, table in ((args.out, rows), (args.out.replace(".csv", "_fronts.csv"), series)):
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(table[0].keys()), lineterminator="\n")
            w.writeheader()
            w.writerows(table)


if __name__ == "__main__":
    main()
