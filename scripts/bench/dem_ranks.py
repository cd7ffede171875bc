#!/usr/bin/env python3
"""Strong and weak scaling of the DEM over MPI ranks (cargo feature `mpi`).

The scene is a layer of grains (d = 10 mm +- 10 %) released from a jittered
lattice onto a frictional floor in a box periodic along x and y; it is
`per_rank` grains per 0.44 m of x. Each configuration runs one thread per
rank, so that ranks alone share the cores:

- weak: 1 rank with N grains against 2 ranks with 2N grains (the box twice
  as long along x); efficiency = t(1 rank, N) / t(2 ranks, 2N);
- strong: 2N grains on 1 rank against 2 ranks; efficiency = t1 / (2 t2);
- threads: 2N grains on 1 rank with 2 threads, the peer the ranks compete
  with on one node.

A window of steps is timed from the wall-clock column of series.csv (the
set-up and the first output are left out). Runs are interleaved and each
configuration's median over the repeats is reported, with ns per
particle-step and the peak memory per rank.

usage: scripts/bench/dem_ranks.py [--per-rank 20000] [--steps 4000]
         [--repeats 3] [--binary target/release/grainflow] [--json FILE]
"""
import argparse, csv, json, os, statistics, subprocess, sys, tempfile

CASE = """
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{length}, 0.22, 0.6]
periodic = [true, true, false]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 5.0e-3
radius_spread = 0.1
seed = 3

[[particles.block]]
kind = "lattice"
lower = [0.0, 0.0, 0.0]
upper = [{length}, 0.22, 0.275]
spacing = 0.011
jitter = 0.8

[contact]
model = "soft"
restitution = 0.5
contact_time = 1.0e-4
friction = 0.5
rolling_friction = 0.05

[[walls]]
name = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[time]
end = {end}
dt_over_contact_time = 0.05

[output]
interval = {interval}
particles = false
"""
DT = 5.0e-6


def run(binary, case, out, ranks, threads):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               RAYON_NUM_THREADS=str(threads))
    command = [binary, "run", case, "--out", out, "--threads", str(threads)]
    if ranks > 1:
        command = ["mpirun", "--oversubscribe", "--bind-to", "none", "-n", str(ranks)] + command
    subprocess.run(command, check=True, env=env, stdout=subprocess.DEVNULL)
    rows = list(csv.DictReader(open(os.path.join(out, "series.csv"))))
    summary = json.load(open(os.path.join(out, "summary.json")))
    # Rows at 1/4 and at the end of the run: the window between them.
    first, last = rows[1], rows[-1]
    seconds = float(last["wall_seconds"]) - float(first["wall_seconds"])
    steps = float(last["step"]) - float(first["step"])
    return seconds, steps, summary


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--per-rank", type=int, default=20000)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--json")
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="dem_ranks_")
    # 40 x 20 x 25 lattice sites per 0.44 m of x.
    length = 0.44 * args.per_rank / 20000
    end = args.steps * DT
    cases = {}
    for name, scale in [("N", 1), ("2N", 2)]:
        path = os.path.join(work, f"{name}.toml")
        with open(path, "w") as f:
            f.write(CASE.format(length=length * scale, end=end, interval=end / 4))
        cases[name] = path
    configurations = [
        ("1 rank, N", "N", 1, 1),
        ("2 ranks, 2N", "2N", 2, 1),
        ("1 rank, 2N", "2N", 1, 1),
        ("1 rank x 2 threads, 2N", "2N", 1, 2),
    ]
    samples = {c[0]: [] for c in configurations}
    memory = {}
    particles = {}
    for repeat in range(args.repeats):
        for label, case, ranks, threads in configurations:
            out = os.path.join(work, f"{label.replace(' ', '_').replace(',', '')}_{repeat}")
            seconds, steps, summary = run(args.binary, cases[case], out, ranks, threads)
            n = summary["particles"]
            particles[label] = n
            samples[label].append(seconds / steps / n * ranks * threads * 1e9)
            memory[label] = summary["peak_memory_bytes"]
            print(f"{label}: {n} grains, {seconds:.3f} s for {steps:.0f} steps", file=sys.stderr)
    median = {k: statistics.median(v) for k, v in samples.items()}
    # Wall time per step of each configuration (median).
    per_step = {k: median[k] * particles[k] / (ranks * threads) * 1e-9
                for (k, _, ranks, threads) in configurations}
    weak = per_step["1 rank, N"] / per_step["2 ranks, 2N"]
    strong = per_step["1 rank, 2N"] / (2 * per_step["2 ranks, 2N"])
    threads = per_step["1 rank, 2N"] / (2 * per_step["1 rank x 2 threads, 2N"])
    print(f"{'configuration':28s} {'grains':>8s} {'ns/(particle-step) x cores':>28s} {'s/step':>10s} {'MB/rank':>8s}")
    for label, *_ in configurations:
        print(f"{label:28s} {particles[label]:8d} {median[label]:28.1f} "
              f"{per_step[label]:10.3e} {memory[label] / 1e6:8.1f}")
    print(f"weak-scaling efficiency (2 ranks): {weak:.3f}")
    print(f"strong-scaling efficiency (2 ranks): {strong:.3f}")
    print(f"thread efficiency (2 threads, 1 rank): {threads:.3f}")
    if args.json:
        json.dump({"per_rank": args.per_rank, "steps": args.steps, "repeats": args.repeats,
                   "samples_ns_per_particle_step_core": samples, "median": median,
                   "seconds_per_step": per_step, "peak_memory_bytes": memory,
                   "particles": particles, "weak_efficiency": weak,
                   "strong_efficiency": strong, "thread_efficiency": threads},
                  open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
