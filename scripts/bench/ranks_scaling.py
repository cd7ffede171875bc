#!/usr/bin/env python3
"""Strong and weak scaling of the flow solver and of grains in a fluid over
MPI ranks (cargo feature `mpi`), one thread per rank.

- flow: a triply periodic box on an n^3 grid (1 rank) against a
  (2n) x n x n grid twice as long along x (2 ranks, weak) and the long grid
  on 1 and 2 ranks (strong); 20 steps, of which the last 15 are timed from
  the wall-clock column of series.csv;
- avalanche: the immersed avalanche cases/immersed_avalanche.toml (230
  grains at D/dx = 10 on 100 x 30 x 100 cells, 10 steps from rest) against
  its bed twice along x (weak), and the long box on 1 and 2 ranks (strong);
- coupled: the many-grains scene scripts/bench/many_grains.toml (1,573
  spheres at D/dx = 4 settling in a 64 x 64 x 96 box; 10 steps of the
  coupled step) against the same box twice as long along x holding its
  lattice twice, side by side (weak: exactly twice the grains), and the
  long box on 1 and 2 ranks (strong).

A fourth configuration runs two independent one-rank runs of the small
case at once: the efficiency two cores sharing this machine's memory give
without any communication, the ceiling of the weak scaling.

Before and after each 2-rank run the script times a cache line's round
trip between two threads (core_latency.c): about 100 ns when the two CPUs
share a last-level cache, about 400 ns when they do not. Ranks that
exchange through shared memory pay more in the second case; each
repeat's weak-scaling efficiency is listed beside its probe.

Runs are interleaved; each configuration's median over the repeats is
reported with the wall seconds per step, the peak memory per rank, the
weak-scaling efficiency t(1 rank, N) / t(2 ranks, 2N) and the
strong-scaling efficiency t(1 rank) / (2 t(2 ranks)).

usage: scripts/bench/ranks_scaling.py [--cells 64] [--repeats 3]
         [--binary target/release/grainflow] [--only flow|coupled|avalanche]
         [--json FILE]
"""
import argparse, csv, json, os, statistics, subprocess, sys, tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))


ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           RAYON_NUM_THREADS="1")


def command_of(binary, case, out, overrides):
    command = [binary, "run", case, "--out", out, "--threads", "1"]
    for o in overrides:
        command += ["--set", o]
    return command


def run(binary, case, out, ranks, overrides):
    if ranks == 0:
        # Two independent one-rank runs at once: what two cores sharing
        # this machine's memory give without any communication.
        runs = [subprocess.Popen(command_of(binary, case, f"{out}_{k}", overrides), env=ENV,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                for k in range(2)]
        assert all(r.wait() == 0 for r in runs)
        times = [timed(f"{out}_{k}") for k in range(2)]
        return sum(t[0] for t in times) / 2, max(t[1] for t in times)
    command = command_of(binary, case, out, overrides)
    if ranks > 1:
        command = ["mpirun", "--oversubscribe", "--bind-to", "none", "-n", str(ranks)] + command
    subprocess.run(command, check=True, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return timed(out)


def timed(out):
    """Wall seconds per step of the timed window, and the peak memory."""
    # Grains in a fluid count fluid steps in flow_series.csv (series.csv
    # counts the DEM's sub-steps).
    series = os.path.join(out, "flow_series.csv")
    if not os.path.exists(series):
        series = os.path.join(out, "series.csv")
    rows = list(csv.DictReader(open(series)))
    summary = json.load(open(os.path.join(out, "summary.json")))
    first = rows[1] if len(rows) > 2 else rows[0]
    last = rows[-1]
    seconds = float(last["wall_seconds"]) - float(first["wall_seconds"])
    steps = float(last["step"]) - float(first["step"])
    return seconds / steps, summary["peak_memory_bytes"]


FLOW = """
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{length}, 1.0, 1.0]
periodic = [true, true, true]

[fluid]
cells = [{cells_x}, {n}, {n}]
density = 1000.0
viscosity = 10.0

[fluid.initial]
kind = "uniform"
velocity = [1.0, 0.5, 0.25]

[time]
end = {end}
dt = {dt}

[output]
interval = {interval}
fields = false
"""


def flow_configurations(work, n):
    # A periodic box: every step does the full work of a step (convection,
    # three Helmholtz solves and a pressure solve per stage) whatever the
    # flow; 20 steps at CFL 0.5.
    dt = 0.5 / n
    paths = {}
    for name, scale in [("short", 1), ("long", 2)]:
        paths[name] = os.path.join(work, f"flow_{name}.toml")
        open(paths[name], "w").write(FLOW.format(length=float(scale), cells_x=scale * n, n=n,
                                                 end=20 * dt, dt=dt, interval=5 * dt))
    return [
        ("1 rank, N", paths["short"], 1, [], n ** 3),
        ("2 ranks, 2N", paths["long"], 2, ["parallel.process_grid=[2,1,1]"], 2 * n ** 3),
        ("1 rank, 2N", paths["long"], 1, [], 2 * n ** 3),
        ("2 x 1 rank, N", paths["short"], 0, [], n ** 3),
    ]


def coupled_configurations(work):
    base = open(os.path.join(ROOT, "scripts/bench/many_grains.toml")).read()
    # Twice the box along x, and the lattice of the small box repeated in
    # its second half: each rank of the long box holds the small box's
    # grains exactly (one lattice over the long box would fit 24 columns
    # where two small boxes fit 2 x 11, 9 % more grains).
    block = base[base.index("[[particles.block]]"):base.index("[contact]")]
    second = block.replace("lower = [0.006, 0.006, 0.03]", "lower = [0.086, 0.006, 0.03]") \
                  .replace("upper = [0.074, 0.074, 0.11]", "upper = [0.154, 0.074, 0.11]")
    assert second != block
    long = (base.replace("upper = [0.08, 0.08, 0.12]", "upper = [0.16, 0.08, 0.12]")
                .replace("cells = [64, 64, 96]", "cells = [128, 64, 96]")
                .replace("point = [0.08, 0.0, 0.0]", "point = [0.16, 0.0, 0.0]")
                .replace("[contact]", second + "[contact]"))
    assert long.count("0.16") == 2 and "128" in long
    paths = {}
    for name, text in [("short", base), ("long", long)]:
        paths[name] = os.path.join(work, f"grains_{name}.toml")
        open(paths[name], "w").write(text)
    return [
        ("1 rank, N", paths["short"], 1, [], 1),
        ("2 ranks, 2N", paths["long"], 2, ["parallel.process_grid=[2,1,1]"], 2),
        ("1 rank, 2N", paths["long"], 1, [], 2),
        ("2 x 1 rank, N", paths["short"], 0, [], 1),
    ]


def avalanche_configurations(work):
    """The immersed avalanche (cases/immersed_avalanche.toml: 230 grains at
    D/dx = 10 on 100 x 30 x 100 cells), 10 steps from rest, against the
    same bed twice along x (20 D x 3 D x 10 D, 200 x 30 x 100 cells)."""
    base = open(os.path.join(ROOT, "cases/immersed_avalanche.toml")).read()
    bed = open(os.path.join(ROOT, "cases/data/avalanche_bed.csv")).read().splitlines()
    length = 0.05
    doubled = [bed[0]] + bed[1:]
    for line in bed[1:]:
        values = line.split(",")
        values[0] = repr(float(values[0]) + length)
        doubled.append(",".join(values))
    open(os.path.join(work, "avalanche_bed_long.csv"), "w").write("\n".join(doubled) + "\n")
    window = {"time.end": "0.005", "output.interval": "0.005", "output.fields": "false"}
    short = base.replace('path = "data/avalanche_bed.csv"',
                         f'path = "{os.path.join(ROOT, "cases/data/avalanche_bed.csv")}"')
    start = base.index("positions = [") + len("positions = [")
    end = base.index("]\nradii")
    fixed = base[start:end]
    shifted = ", ".join(
        "[" + ", ".join([repr(float(p.split(",")[0]) + length)] + p.split(",")[1:]) + "]"
        for p in fixed.strip("[]").split("], [")
    )
    long = (base.replace("upper = [0.05, 0.015, 0.05]", "upper = [0.1, 0.015, 0.05]")
                .replace("cells = [100, 30, 100]", "cells = [200, 30, 100]")
                .replace(fixed, fixed + ", " + shifted)
                .replace('path = "data/avalanche_bed.csv"',
                         f'path = "{os.path.join(work, "avalanche_bed_long.csv")}"'))
    radii = long[long.index("radii = [") + 9:long.index("]", long.index("radii = ["))]
    long = long.replace("radii = [" + radii + "]", "radii = [" + radii + ", " + radii + "]")
    assert "0.1, 0.015" in long and "200, 30" in long
    paths = {}
    for name, text in [("short", short), ("long", long)]:
        paths[name] = os.path.join(work, f"avalanche_{name}.toml")
        open(paths[name], "w").write(text)
    settings = [f"{k}={v}" for k, v in window.items()]
    return [
        ("1 rank, N", paths["short"], 1, settings, 1),
        ("2 ranks, 2N", paths["long"], 2, settings + ["parallel.process_grid=[2,1,1]"], 2),
        ("1 rank, 2N", paths["long"], 1, settings, 2),
        ("2 x 1 rank, N", paths["short"], 0, settings, 1),
    ]


def core_latency_probe(work):
    """Builds the round-trip probe and returns a function that runs it (ns)."""
    binary = os.path.join(work, "core_latency")
    subprocess.run(["cc", "-O2", "-pthread", os.path.join(ROOT, "scripts/bench/core_latency.c"),
                    "-o", binary], check=True)
    return lambda: float(subprocess.run([binary], check=True, capture_output=True, text=True).stdout)


def measure(name, configurations, binary, work, repeats):
    samples = {c[0]: [] for c in configurations}
    memory = {}
    probes = []
    round_trip = core_latency_probe(work)
    for repeat in range(repeats):
        for label, case, ranks, overrides, _ in configurations:
            out = os.path.join(work, f"{name}_{label.replace(' ', '_').replace(',', '')}_{repeat}")
            before = round_trip() if ranks == 2 else None
            seconds, peak = run(binary, case, out, ranks, overrides)
            if ranks == 2:
                probes.append([before, round_trip()])
            samples[label].append(seconds)
            memory[label] = peak
            print(f"{name} {label}: {seconds:.4f} s/step", file=sys.stderr)
    median = {k: statistics.median(v) for k, v in samples.items()}
    weak = median["1 rank, N"] / median["2 ranks, 2N"]
    strong = median["1 rank, 2N"] / (2 * median["2 ranks, 2N"])
    # The machine's own limit: two runs sharing its memory, no messages.
    ceiling = median["1 rank, N"] / median["2 x 1 rank, N"]
    print(f"== {name}")
    for label, *_ in configurations:
        runs = ", ".join(f"{s:.4f}" for s in samples[label])
        print(f"  {label:14s} {median[label]:.4f} s/step ({runs}), {memory[label] / 1e6:.1f} MB/rank")
    print(f"  weak-scaling efficiency (2 ranks): {weak:.3f}")
    print(f"  strong-scaling efficiency (2 ranks): {strong:.3f}")
    print(f"  two independent runs at once: efficiency {ceiling:.3f} (the machine's limit)")
    weak_by_repeat = [a / b for a, b in zip(samples["1 rank, N"], samples["2 ranks, 2N"])]
    for repeat, (weak_r, probe) in enumerate(zip(weak_by_repeat, probes)):
        print(f"  repeat {repeat}: weak {weak_r:.3f}, core round trip {probe[0]:.0f} / {probe[1]:.0f} ns")
    return {"samples_seconds_per_step": samples, "median": median, "peak_memory_bytes": memory,
            "weak_efficiency": weak, "strong_efficiency": strong,
            "independent_runs_efficiency": ceiling, "weak_efficiency_by_repeat": weak_by_repeat,
            "core_round_trip_ns_by_repeat": probes}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cells", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--binary", default=os.path.join(ROOT, "target/release/grainflow"))
    parser.add_argument("--only", choices=["flow", "coupled", "avalanche"])
    parser.add_argument("--json")
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="ranks_scaling_")
    report = {}
    if args.only in (None, "flow"):
        report["flow"] = measure("flow", flow_configurations(work, args.cells), args.binary, work,
                                 args.repeats)
        report["flow"]["cells_per_rank"] = args.cells ** 3
    if args.only in (None, "coupled"):
        report["coupled"] = measure("coupled", coupled_configurations(work), args.binary, work,
                                    args.repeats)
    if args.only in (None, "avalanche"):
        report["avalanche"] = measure("avalanche", avalanche_configurations(work), args.binary,
                                      work, args.repeats)
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
