#!/usr/bin/env python3
"""The dry cases on one thread against the default threads (and, with
--forced, against two threads forced), runs alternated in one command so
that a host whose load drifts (another build, a competitor) weighs on both
alike; medians of the repeats of the loop's wall-clock time
(summary.json's wall_seconds, the set-up left out).

--busy starts `yes > /dev/null` pinned to core 0 (taskset -c 0) for the
whole benchmark, a competitor that keeps one of the cores busy; --ranks 2
runs every configuration under `mpirun --oversubscribe -n 2` (cargo
feature `mpi`; hard contact runs on one rank only and is left out).

usage: scripts/bench/dry_threads.py [--repeats 5] [--busy] [--ranks 1]
         [--forced] [--end-scale 1] [--binary target/release/grainflow]
         [--cases a,b] [--json FILE]
"""
import argparse, json, os, statistics, subprocess, sys, tempfile

# Case, time.end (about 0.2-3 s of one thread each), hard contact.
CASES = [
    ("binary_collision", "3e-3", False),
    ("bouncing_dry", "0.5", False),
    ("silo_small", "0.02", False),
    ("column_collapse_2d", "0.2", False),
    ("column_collapse_3d", "0.05", False),
    ("static_box", "0.05", True),
    ("column_collapse_cocd_2d", "0.03", True),
]


def run(binary, case, end, threads, ranks, out):
    command = [binary, "run", f"cases/{case}.toml", "--set", f"time.end={end}", "--out", out]
    if threads is not None:
        command += ["--threads", str(threads)]
    if ranks > 1:
        command = ["mpirun", "--oversubscribe", "-n", str(ranks)] + command
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return summary["wall_seconds"], summary["threads"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--busy", action="store_true")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--forced", action="store_true", help="also --threads 2")
    ap.add_argument("--binary", default="target/release/grainflow")
    ap.add_argument("--cases", default=",".join(c for c, _, _ in CASES))
    ap.add_argument("--end-scale", type=float, default=1.0,
                    help="times each case's time.end (shorter runs on MPI ranks, whose "
                    "exchanges cost far more per step)")
    ap.add_argument("--json")
    args = ap.parse_args()
    wanted = args.cases.split(",")
    configs = [("1", 1), ("default", None)] + ([("2", 2)] if args.forced else [])
    competitor = None
    if args.busy:
        competitor = subprocess.Popen(["taskset", "-c", "0", "yes"], stdout=subprocess.DEVNULL)
    results = []
    try:
        with tempfile.TemporaryDirectory() as work:
            for case, end, hard in CASES:
                if case not in wanted or (hard and args.ranks > 1):
                    continue
                end = f"{float(end) * args.end_scale:.3g}"
                times = {name: [] for name, _ in configs}
                used = {}
                for _ in range(args.repeats):
                    for name, threads in configs:
                        out = os.path.join(work, f"{case}_{name}")
                        seconds, used[name] = run(args.binary, case, end, threads, args.ranks, out)
                        times[name].append(seconds)
                medians = {name: statistics.median(t) for name, t in times.items()}
                row = {
                    "case": case,
                    "end": end,
                    "ranks": args.ranks,
                    "busy": args.busy,
                    "median_s": medians,
                    "samples_s": times,
                    "threads_used": used,
                    "default_over_1": medians["default"] / medians["1"],
                }
                results.append(row)
                print(
                    f"{case:26s} 1: {medians['1']:.3f} s  default ({used['default']}): "
                    f"{medians['default']:.3f} s  ratio {row['default_over_1']:.2f}"
                    + (f"  forced 2: {medians['2']:.3f} s" if args.forced else ""),
                    flush=True,
                )
    finally:
        if competitor is not None:
            competitor.kill()
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    print("load average at the end:", " ".join(load))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"results": results, "loadavg_end": load}, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
