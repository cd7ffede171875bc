#!/usr/bin/env python3
"""Hard-contact runs of moderate size, where the normal matrix's factor
is whole or split in two by its size (2D packings of a few hundred to a
few thousand discs, 3D up to about 3,300 spheres), with two builds of
grainflow alternated run by run in one command, so that a host whose load
drifts weighs on both alike.

Each scene is a whole run (`grainflow run`, its wall time from
summary.json) and its result (a metric the scene's analysis writes), so
that a change of the factor shows both what it saves and that the run
ends where it did, to the interior point's tolerance.

usage: scripts/bench/cocd_moderate_factor.py BEFORE AFTER [--repeats 3]
         [--threads 1] [--scene NAME=CASE:END[:METRIC] ...] [--json FILE]
(BEFORE and AFTER: two grainflow binaries, for example the last stop's
build copied aside and target/release/grainflow. --scene adds a case,
run to t = END, for example a deposit of the erodible-bed study.)
"""
import argparse, json, os, statistics, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from grainflow_run import run_case  # noqa: E402

CASES = os.path.join(HERE, "..", "..", "cases")
# name: (case, end time, the metric that says where the run ended)
SCENES = {
    "2D box at rest, 400 discs": ("static_box.toml", 0.2, "max_kinetic_to_potential"),
    "2D column collapse, 410 discs": ("column_collapse_cocd_2d.toml", 0.4, "runout"),
    "2D erodible bed, 8 mm": ("erodible_bed_2d.toml", 0.2, "runout"),
    "3D column collapse, 2,100 spheres": ("column_collapse_cocd_3d.toml", 0.01, "runout"),
}


def run(binary, case, end, threads, out):
    summary, refused = run_case(binary, case, out, [f"time.end={end}"], threads=threads)
    if summary is None:
        sys.exit(f"{case}: {refused}")
    return summary


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--scene", action="append", default=[],
                        help="NAME=CASE:END[:METRIC], reporting the metric (runout by default)")
    parser.add_argument("--json")
    args = parser.parse_args()
    scenes = {name: (os.path.join(CASES, case), end, metric)
              for name, (case, end, metric) in SCENES.items()}
    for extra in args.scene:
        name, rest = extra.split("=", 1)
        case, end, *metric = rest.split(":")
        scenes[name] = (case, float(end), metric[0] if metric else "runout")
    table = []
    with tempfile.TemporaryDirectory() as work:
        for name, (case, end, metric) in scenes.items():
            runs = {"before": [], "after": []}
            for repeat in range(args.repeats):
                for label in ("before", "after"):
                    binary = getattr(args, label)
                    summary = run(binary, case, end, args.threads,
                                  os.path.join(work, f"{label}_{repeat}"))
                    runs[label].append({
                        "wall_seconds": summary["wall_seconds"],
                        "metric": summary["metrics"][metric],
                        "mean_iterations": summary["metrics"]["mean_iterations"],
                        "seconds_per_solve": summary["metrics"]["seconds_per_solve"],
                        "peak_memory_bytes": summary["peak_memory_bytes"],
                    })
            median = {label: statistics.median(r["wall_seconds"] for r in rs)
                      for label, rs in runs.items()}
            row = {"scene": name, "case": case, "end": end, "threads": args.threads,
                   "metric": metric, "runs": runs,
                   "speed_up": median["before"] / median["after"]}
            table.append(row)
            walls = {label: ", ".join(f"{r['wall_seconds']:.2f}" for r in rs)
                     for label, rs in runs.items()}
            print(f"{name}: before {walls['before']} s; after {walls['after']} s; "
                  f"speed-up {row['speed_up']:.2f}; {metric} "
                  f"{runs['before'][0]['metric']:.6g} / {runs['after'][0]['metric']:.6g}",
                  flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"before": args.before, "after": args.after, "scenes": table}, f, indent=1)


if __name__ == "__main__":
    main()
