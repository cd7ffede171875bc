#!/usr/bin/env python3
"""Checkpoint write and read bandwidth, and the time to resume against the
time to set a case up from scratch, for a dry scene of 10^6 grains and a
256^3 fluid, on 1 and (with --ranks 2, cargo feature `mpi`) 2 ranks.

Each scene runs two steps with a checkpoint after each (`checkpoint.steps
= 1`); the log gives each write's seconds (synced to disk) and the state
files their bytes. Then the run resumes from the first checkpoint and ends
after the second step: the log gives the seconds to read and restore the
state, and the whole command's time (scene built, state read, one step,
one checkpoint) is set against the fresh run's (built, two steps, two
checkpoints).

usage: scripts/bench/checkpoint_io.py [--ranks 1] [--grains 1000000]
         [--cells 256] [--binary target/release/grainflow] [--json FILE]
"""
import argparse, glob, json, os, re, subprocess, tempfile, time

DRY = """
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {height}]
periodic = [true, true, false]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 1.0e-3
radius_spread = 0.1

[[particles.block]]
kind = "lattice"
lower = [0.0011, 0.0011, 0.0011]
upper = [{inner}, {inner}, {inner_height}]
spacing = 2.3e-3

[contact]
model = "soft"
restitution = 0.5
contact_time = 1.0e-4
friction = 0.5

[[walls]]
name = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[time]
end = {end}
dt = 2.0e-6

[output]
interval = 1.0e-6
particles = false
"""

FLUID = """
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [6.283185307179586, 6.283185307179586, 6.283185307179586]
periodic = [true, true, true]

[fluid]
cells = [{cells}, {cells}, {cells}]
density = 1000.0
viscosity = 10.0

[fluid.initial]
kind = "beltrami"
velocity = 1.0

[time]
end = {end}
dt = 1.0e-3

[output]
interval = 1.0e-3
fields = false
"""


def run(binary, case, out, ranks, extra):
    command = [binary, "run", case, "--out", out, "--set", "checkpoint.steps=1",
               "--set", "checkpoint.keep=10"] + extra
    if ranks > 1:
        command = ["mpirun", "--oversubscribe", "-n", str(ranks)] + command
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    started = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    return time.perf_counter() - started


def read_seconds(out):
    text = open(os.path.join(out, "log.txt")).read()
    return [float(s) for s in re.findall(r"read and restored in ([0-9.]+) s", text)][-1]


def checkpoint_seconds(out):
    text = open(os.path.join(out, "log.txt")).read()
    return [float(s) for s in re.findall(r"checkpoint \S+ \(\w+, ([0-9.]+) s\)", text)]


def measure(binary, name, text, ranks, workdir):
    case = os.path.join(workdir, f"{name}.toml")
    open(case, "w").write(text)
    fresh = os.path.join(workdir, f"{name}_fresh")
    total_fresh = run(binary, case, fresh, ranks, [])
    writes = checkpoint_seconds(fresh)
    first = sorted(glob.glob(os.path.join(fresh, "checkpoints", "checkpoint_*")))[0]
    state_bytes = sum(os.path.getsize(f) for f in glob.glob(os.path.join(first, "*.state")))
    summary = json.load(open(os.path.join(fresh, "summary.json")))
    steps_seconds = summary["wall_seconds"] - summary["checkpoint_seconds"] - summary["output_seconds"]
    # The resumed run: one step from the first checkpoint, its own clock.
    resumed = os.path.join(workdir, f"{name}_resumed")
    subprocess.run(["cp", "-r", fresh, resumed], check=True)
    total_resumed = run(binary, case, resumed, ranks, ["--restart", os.path.join(
        resumed, "checkpoints", os.path.basename(first))])
    read = read_seconds(resumed)
    return {
        "scene": name,
        "read_restore_seconds": read,
        "read_gb_per_s": state_bytes / read / 1e9,
        "ranks": ranks,
        "state_bytes": state_bytes,
        "write_seconds": writes,
        "write_gb_per_s": state_bytes / min(writes) / 1e9,
        "fresh_run_seconds": total_fresh,
        "fresh_steps_seconds": steps_seconds,
        "resumed_run_seconds": total_resumed,
        "summary_steps": summary["steps"],
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--grains", type=int, default=1_000_000)
    ap.add_argument("--cells", type=int, default=256)
    ap.add_argument("--binary", default="target/release/grainflow")
    ap.add_argument("--json")
    args = ap.parse_args()
    per_side = round((args.grains / 2) ** (1 / 3))
    side = per_side * 2.3e-3 + 2.2e-3
    height = 4 * per_side * 2.3e-3
    dry = DRY.format(side=side, height=height, inner=side - 0.0011,
                     inner_height=2 * per_side * 2.3e-3, end=4.0e-6)
    fluid = FLUID.format(cells=args.cells, end=2.0e-3)
    results = []
    with tempfile.TemporaryDirectory() as workdir:
        for name, text in [("dry", dry), ("fluid", fluid)]:
            result = measure(os.path.abspath(args.binary), name, text, args.ranks, workdir)
            print(json.dumps(result), flush=True)
            results.append(result)
    if args.json:
        json.dump(results, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
