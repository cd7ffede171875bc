#!/usr/bin/env python3
"""Cost of one full fluid time step (three RK3 stages with their Helmholtz
and Poisson solves) in grainflow: nanoseconds per cell per step and peak
memory per cell, for a triply periodic vortex at 64^3 and 128^3 and a
channel (periodic x and y, no-slip walls in z, pressure-driven) at
128 x 64 x 64, on 1 and 2 threads. Each run starts from the case's flow,
takes `--steps` steps, and reads the wall time of the steps from
timing.csv (the set-up, FFTW's planning included, is left out). Prints the
medians over `--repeats` runs and writes them as JSON.

Variants are compared in the same command, their runs interleaved so that
the machine's load falls on all of them alike: `--transforms rust,fftw`
runs both transform backends (FFTW needs a binary built with
`--features fftw`, given by `--binary`), and `--baseline BINARY` adds
another build of grainflow (an earlier commit, say) with the default
transforms.

usage: scripts/bench/fluid_step.py [--repeats 3] [--steps 10] [--threads 1,2]
           [--grids vortex_64,...] [--binary PATH] [--transforms rust,fftw]
           [--baseline PATH] [--json FILE]
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


def one_run(binary, root, case, cells, dt, steps, threads, extra):
    """ns per cell-step of one run and its peak memory (bytes)."""
    with tempfile.TemporaryDirectory() as out:
        sets = [f"fluid.cells={cells}", f"time.dt={dt!r}", f"time.end={dt * steps!r}",
                f"output.interval={dt!r}", "output.fields=false"] + extra
        command = [binary, "run", os.path.join(root, f"cases/{case}.toml"), "--out", out,
                   "--threads", str(threads)]
        for s in sets:
            command += ["--set", s]
        _, memory = peak_rss_of(command, cwd=out)
        # The wall clock of each output row (timing.csv; series.csv before
        # the timing was written apart).
        timing = os.path.join(out, "timing.csv")
        lines = open(timing if os.path.exists(timing) else os.path.join(out, "series.csv")).read().split()
        header = lines[0].split(",")
        rows = [dict(zip(header, map(float, l.split(",")))) for l in lines[1:]]
        seconds = rows[-1]["wall_seconds"] - rows[0]["wall_seconds"]
        step_count = rows[-1]["step"] - rows[0]["step"]
        n_cells = cells[0] * cells[1] * cells[2]
        return 1e9 * seconds / (n_cells * step_count), memory


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--grids", default=",".join(GRIDS))
    ap.add_argument("--binary", default=None, help="grainflow binary (default: build this checkout)")
    ap.add_argument("--transforms", default=None, help="e.g. rust,fftw (default: the build's)")
    ap.add_argument("--baseline", default=None, help="another grainflow binary to compare with")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))
    binary = args.binary
    if binary is None:
        subprocess.run(["cargo", "build", "--release", "-q"], cwd=root, check=True)
        binary = os.path.join(root, "target/release/grainflow")
    variants = []
    for transform in (args.transforms.split(",") if args.transforms else [None]):
        label = transform or "default"
        extra = [f"fluid.transforms=\"{transform}\""] if transform else []
        variants.append((label, binary, extra))
    if args.baseline:
        variants.append(("baseline", args.baseline, []))
    report = []
    for name in args.grids.split(","):
        case, cells, grid_sets = GRIDS[name]
        n_cells = cells[0] * cells[1] * cells[2]
        dt = 0.01 * 64 / max(cells)
        for threads in [int(t) for t in args.threads.split(",")]:
            samples = {label: [] for label, _, _ in variants}
            memory = {}
            for _ in range(args.repeats):
                for label, variant_binary, extra in variants:
                    ns, memory[label] = one_run(variant_binary, root, case, cells, dt, args.steps,
                                                threads, grid_sets + extra)
                    samples[label].append(ns)
            entry = {"grid": name, "cells": cells, "threads": threads}
            for label, _, _ in variants:
                median = statistics.median(samples[label])
                entry[label] = {"ns_per_cell_step": median, "samples": samples[label],
                                "bytes_per_cell": memory[label] / n_cells}
                print(f"{name:18s} {threads} thread(s) {label:9s}: {median:7.1f} ns per cell-step "
                      f"(samples {', '.join(f'{s:.1f}' for s in samples[label])}), "
                      f"{memory[label] / n_cells:.0f} B per cell", flush=True)
            if len(variants) > 1:
                first = variants[0][0]
                for label, _, _ in variants[1:]:
                    ratios = [b / a for a, b in zip(samples[first], samples[label])]
                    entry[f"{label}_over_{first}"] = statistics.median(ratios)
                    print(f"{'':18s} {label} / {first} per interleaved pair: median "
                          f"{statistics.median(ratios):.3f} ({', '.join(f'{r:.3f}' for r in ratios)})",
                          flush=True)
            report.append(entry)
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
