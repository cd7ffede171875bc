#!/usr/bin/env python3
"""The coupled step's split (flow, immersed boundaries, DEM) of two builds
of grainflow, alternated run by run in one command so that a host whose
load drifts weighs on both alike: the immersed avalanche (10 steps) and
the many-grains bench (10 steps), on 1 and 2 threads.

The immersed boundaries are `seconds_forcing + seconds_loads` of
summary.json (the solid fractions, the forcing's sums and loads, the
inner momentum), the flow `seconds_flow` (prediction and projection), the
DEM `seconds_dem`. The figure to read is their ratio within one run.

usage: scripts/bench/immersed_split.py BEFORE AFTER [--repeats 3]
         [--json FILE] [--set KEY=VALUE ...]
(--set: a case setting for every run, for example
 --set coupling.layer_forcing='"renewal"' --set time.cfl=1.)
(BEFORE and AFTER: two grainflow binaries, for example the last stop's
build copied aside and target/release/grainflow.)
Chart: postprocess/plot_immersed_split.py FILE OUT.png
"""
import argparse, json, os, subprocess, tempfile

SCENES = [
    ("immersed avalanche", ["cases/immersed_avalanche.toml", "--set", "time.end=0.005"]),
    ("many grains", ["scripts/bench/many_grains.toml"]),
]


def run(binary, arguments, threads, out, settings=()):
    command = [binary, "run", *arguments, "--threads", str(threads), "--out", out]
    for setting in settings:
        command += ["--set", setting]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    steps = summary["steps"]
    flow = summary["seconds_flow"] / steps
    immersed = (summary["seconds_forcing"] + summary["seconds_loads"]) / steps
    dem = summary["seconds_dem"] / steps
    return {
        "seconds_per_step": summary["seconds_per_step"],
        "flow": flow,
        "immersed": immersed,
        "dem": dem,
        "immersed_over_flow": immersed / flow,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json")
    ap.add_argument("--set", action="append", default=[], dest="settings")
    args = ap.parse_args()
    builds = {"before": args.before, "after": args.after}
    results = []
    with tempfile.TemporaryDirectory() as scratch:
        for repeat in range(args.repeats):
            for scene, arguments in SCENES:
                for threads in (1, 2):
                    for build, binary in builds.items():
                        out = os.path.join(scratch, f"{build}-{repeat}")
                        row = run(binary, arguments, threads, out, args.settings)
                        row.update(scene=scene, threads=threads, build=build, repeat=repeat)
                        results.append(row)
                        print(
                            f"{scene:20s} {threads} thread(s) {build:6s} "
                            f"IBM/flow {row['immersed_over_flow']:.3f} "
                            f"s/step {row['seconds_per_step']:.3f}",
                            flush=True,
                        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"builds": builds, "settings": args.settings, "runs": results}, f, indent=1)


if __name__ == "__main__":
    main()
