#!/usr/bin/env python3
"""The four settling experiments of ten Cate et al. (2002), E1-E4: runs
`cases/ten_cate.toml` with each case's fluid and writes one CSV row per run
(the largest settling speed against the measured U_inf, cost); the tracked
trajectories stay in the work directory for postprocess/plot_ten_cate.py.

    scripts/ten_cate_runs.py --out docs/validation/ten_cate.csv [--cells-per-diameter 12]
        [--set coupling.layer_forcing=renewal]
"""
import argparse
import csv
import json
import os
import subprocess
import sys

# case: fluid density [kg/m3], viscosity [Pa s], measured U_inf [m/s], end [s]
CASES = {
    "E1": (970.0, 0.373, 0.038, 4.5),
    "E2": (965.0, 0.212, 0.060, 2.8),
    "E3": (962.0, 0.113, 0.091, 2.0),
    "E4": (960.0, 0.058, 0.128, 1.6),
}
D = 0.015


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--cells-per-diameter", type=int, default=12)
    parser.add_argument("--case", action="append", choices=sorted(CASES))
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--workdir", default="/tmp/grainflow_ten_cate")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a further setting for every run (grainflow run --set)")
    args = parser.parse_args()
    n = args.cells_per_diameter
    cells = [round(0.1 / D * n), round(0.1 / D * n), round(0.16 / D * n)]
    fields = ["case", "cells_per_diameter", "terminal_velocity", "measured_velocity",
              "velocity_error", "terminal_reynolds", "wall_seconds", "steps", "tracked"]
    exists = os.path.exists(args.out)
    with open(args.out, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        if not exists:
            writer.writeheader()
        for name in args.case or sorted(CASES):
            density, viscosity, measured, end = CASES[name]
            out = os.path.join(args.workdir, f"{name}_{n}")
            command = [args.binary, "run", "cases/ten_cate.toml", "--out", out,
                       "--set", f"fluid.density={density}",
                       "--set", f"fluid.viscosity={viscosity}",
                       "--set", f"fluid.cells=[{cells[0]},{cells[1]},{cells[2]}]",
                       "--set", f"time.end={end}"]
            for setting in args.set:
                command += ["--set", setting]
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            summary = json.load(open(os.path.join(out, "summary.json")))
            m = summary["metrics"]
            row = {
                "case": name,
                "cells_per_diameter": n,
                "terminal_velocity": m["terminal_velocity"],
                "measured_velocity": measured,
                "velocity_error": m["terminal_velocity"] / measured - 1.0,
                "terminal_reynolds": m["terminal_reynolds"],
                "wall_seconds": summary["wall_seconds"],
                "steps": summary["steps"],
                "tracked": os.path.join(out, "tracked.csv"),
            }
            writer.writerow(row)
            f.flush()
            print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
