#!/usr/bin/env python3
"""Cost of one full fluid time step (three RK3 stages with their Helmholtz
and Poisson solves) in grainflow: nanoseconds per cell per step and peak
memory per cell, for a triply periodic vortex at 64^3 and 128^3 and a
channel (periodic x and y, no-slip walls in z, pressure-driven) at
128 x 64 x 64, on 1 and 2 threads. Each run starts from the case's flow,
takes `--steps` steps, and reads the wall time of the steps from
series.csv (the set-up is left out). Prints the medians over `--repeats`
runs and writes them as JSON.

usage: scripts/bench/fluid_step.py [--repeats 3] [--steps 10] [--threads 1,2] [--json FILE]
"""
import argparse, json, os, statistics, subprocess, tempfile

from dem_column import peak_rss_of

GRIDS = {
    "vortex_64": ("taylor_green_3d", [64, 64, 64], []),
    "vortex_128": ("taylor_green_3d", [128, 128, 128], []),
    "channel_128x64x64": ("taylor_green_3d", [128, 64, 64], [
        "domain.periodic=[true, true, false]",
        "domain.upper=[12.566370614359172, 6.283185307179586, 6.283185307179586]",
        "fluid.boundary.z=[\"no_slip\", \"no_slip\"]",
        "fluid.initial={kind=\"uniform\", velocity=[1.0, 0.0, 0.0]}",
        "fluid.pressure_gradient=[-1.0, 0.0, 0.0]",
        "analysis.kind=\"channel\"",
    ]),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=root, check=True)
    binary = os.path.join(root, "target/release/grainflow")
    report = []
    for name, (case, cells, extra) in GRIDS.items():
        n_cells = cells[0] * cells[1] * cells[2]
        dt = 0.01 * 64 / max(cells)
        entry = {"grid": name, "cells": cells}
        for threads in [int(t) for t in args.threads.split(",")]:
            samples, memory = [], 0
            for _ in range(args.repeats):
                with tempfile.TemporaryDirectory() as out:
                    sets = [f"fluid.cells={cells}", f"time.dt={dt!r}", f"time.end={dt * args.steps!r}",
                            f"output.interval={dt!r}", "output.fields=false"] + extra
                    command = [binary, "run", os.path.join(root, f"cases/{case}.toml"), "--out", out,
                               "--threads", str(threads)]
                    for s in sets:
                        command += ["--set", s]
                    _, memory = peak_rss_of(command, cwd=out)
                    lines = open(os.path.join(out, "series.csv")).read().split()
                    header = lines[0].split(",")
                    rows = [dict(zip(header, map(float, l.split(",")))) for l in lines[1:]]
                    seconds = rows[-1]["wall_seconds"] - rows[0]["wall_seconds"]
                    steps = rows[-1]["step"] - rows[0]["step"]
                    samples.append(1e9 * seconds / (n_cells * steps))
            entry[f"ns_per_cell_step_t{threads}"] = statistics.median(samples)
            entry[f"samples_t{threads}"] = samples
            entry["bytes_per_cell"] = memory / n_cells
            print(f"{name:18s} {threads} thread(s): {statistics.median(samples):7.1f} ns per cell-step "
                  f"(samples {', '.join(f'{s:.1f}' for s in samples)}), {memory / n_cells:.0f} B per cell",
                  flush=True)
        report.append(entry)
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
