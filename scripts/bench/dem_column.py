#!/usr/bin/env python3
"""DEM throughput of grainflow against LAMMPS on the same granular column.

The peer's inputs and the generator of the exact initial lattice are in
../shared/bench/lammps/ (a polydisperse column, d = 5 mm +- 10 %, released from
a jittered lattice in a box with a frictional floor and four side walls;
k_n, gamma_n, k_t = 0.2 k_n, mu = 0.5, dt = 2e-6 s). Two windows are timed:

- settling: steps 1000-3000 after the release (few contacts);
- dense: steps 50200-52200 (t = 0.1 s), when the lower column is compacted
  and about one contact per particle is open.

grainflow writes the wall-clock time into series.csv at every output; a
window's cost is the difference of two rows. LAMMPS reports its loop time.
LIGGGHTS (Debian's `liggghts` package) runs the same column from
scripts/bench/liggghts_column.in when it is installed (the dense window
once, from a single run, as it has no restart here). Prints ns per
particle-step for each code and thread count, their ratios, and peak memory
per particle, and writes the table as JSON.

Before and after each grainflow run on more than one thread, the script
times a cache line's round trip between two threads (core_latency.c): about
100 ns when the two CPUs share a last-level cache, about 400 ns when they
do not (two dies, or a virtual machine's CPUs placed on two dies by its
host). The two-thread gain depends on it, and the JSON keeps it beside each
window.

With --ranks 1,2 the settling window is timed instead on MPI ranks of
one thread each (grainflow built with the feature `mpi`, LAMMPS under
mpirun), interleaved, each code's strong-scaling efficiency t1 / (r t_r)
reported beside its time.

usage: scripts/bench/dem_column.py [--sizes 20000,100000] [--repeats 3]
         [--threads 1,2] [--dense] [--ranks 1,2] [--shared ../shared]
         [--work DIR] [--json FILE]
"""
import argparse, json, os, re, shutil, statistics, subprocess, sys, time

LATTICE = {20000: (20, 20, 50), 100000: (50, 40, 50)}
DT = 2.0e-6
SEED = 12345
KN, GN, KT, MU = 84676.20922, 1.134159422, 16935.24184, 0.5


def peak_rss_of(cmd, cwd=None, env=None):
    """Runs a command and returns (stdout, peak RSS bytes of the child)."""
    pid = os.fork()
    if pid == 0:
        if cwd:
            os.chdir(cwd)
        fd = os.open(os.path.join(cwd or ".", "stdout.txt"), os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.execvpe(cmd[0], cmd, env or os.environ)
    _, status, usage = os.wait4(pid, 0)
    out = open(os.path.join(cwd or ".", "stdout.txt")).read()
    if status != 0:
        sys.exit(f"command failed ({status}): {' '.join(cmd)}\n{out[-3000:]}")
    return out, usage.ru_maxrss * 1024


def generate(shared, work, n):
    nx, ny, nz = LATTICE[n]
    data = os.path.join(work, f"col{n}.data")
    if not os.path.exists(data):
        subprocess.run([sys.executable, os.path.join(shared, "bench/lammps/gen_column.py"),
                        str(nx), str(ny), str(nz), str(SEED), data], check=True, stdout=subprocess.DEVNULL)
    lines = open(data).read().splitlines()
    box = {}
    for line in lines:
        m = re.match(r"\s*0 (\S+) (\w)lo \w+hi", line)
        if m:
            box[m.group(2)] = float(m.group(1))
    start = lines.index("Atoms # sphere") + 2
    rows = [l.split() for l in lines[start:] if l.strip()]
    csv = os.path.join(work, f"col{n}.csv")
    with open(csv, "w") as f:
        f.write("x,y,z,radius\n")
        for r in rows:
            f.write(f"{r[4]},{r[5]},{r[6]},{float(r[2]) / 2!r}\n")
    return data, csv, box


def grainflow_case(work, n, csv, box, steps, interval_steps):
    lx, ly, lz = box["x"], box["y"], box["z"]
    case = os.path.join(work, f"col{n}_{steps}.toml")
    open(case, "w").write(f"""
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{lx!r}, {ly!r}, {lz!r}]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 2.5e-3

[[particles.block]]
kind = "file"
path = "{csv}"

[contact]
model = "soft"
stiffness = {KN}
damping = {GN}
tangential_ratio = {KT / KN!r}
friction = {MU}
skin = 0.0005

[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[walls]]
point = [{lx!r}, 0.0, 0.0]
normal = [-1.0, 0.0, 0.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[walls]]
point = [0.0, {ly!r}, 0.0]
normal = [0.0, -1.0, 0.0]

[time]
end = {steps * DT!r}
dt = {DT}
overlap_limit = 0.5

[output]
interval = {interval_steps * DT!r}
particles = false
""")
    return case


MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def on_ranks(command, ranks):
    """The command on `ranks` MPI ranks (itself for one)."""
    if ranks == 1:
        return command
    return ["mpirun", "--oversubscribe", "--bind-to", "none", "-n", str(ranks)] + command


def core_latency_probe(work):
    """Builds the round-trip probe and returns a function that runs it (ns)."""
    source = os.path.join(os.path.dirname(os.path.abspath(__file__)), "core_latency.c")
    binary = os.path.join(work, "core_latency")
    subprocess.run(["cc", "-O2", "-pthread", source, "-o", binary], check=True)
    return lambda: float(subprocess.run([binary], check=True, capture_output=True, text=True).stdout)


def grainflow_windows(binary, work, n, csv, box, threads, windows, ranks=1):
    """Runs grainflow once and returns [(ns per particle-step, contacts)] for
    each (first_step, last_step) window, and the peak memory in bytes."""
    last = max(w[1] for w in windows)
    interval = 200
    case = grainflow_case(work, n, csv, box, last, interval)
    out = os.path.join(work, f"gf{n}_t{threads}_r{ranks}")
    shutil.rmtree(out, ignore_errors=True)
    command = on_ranks([binary, "run", case, "--out", out, "--threads", str(threads)], ranks)
    _, rss = peak_rss_of(command, cwd=work, env=MPI_ENV)
    rows = {}
    lines = open(os.path.join(out, "series.csv")).read().splitlines()
    header = lines[0].split(",")
    for line in lines[1:]:
        v = dict(zip(header, map(float, line.split(","))))
        rows[int(round(v["step"]))] = v
    result = []
    for a, b in windows:
        seconds = rows[b]["wall_seconds"] - rows[a]["wall_seconds"]
        result.append((1e9 * seconds / (n * (b - a)), rows[b]["particle_contacts"]))
    summary = json.load(open(os.path.join(out, "summary.json")))
    return result, summary.get("peak_memory_bytes") or rss


def lammps_loop_ns(log, n, steps):
    times = [float(m.group(1)) for m in re.finditer(r"Loop time of (\S+) on \d+ procs for (\d+) steps", log)
             if int(m.group(2)) == steps]
    return 1e9 * times[-1] / (n * steps)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="20000")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--dense", action="store_true", help="also time the dense window (t = 0.1 s)")
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "../../../shared"))
    ap.add_argument("--work", default="/tmp/grainflow-bench")
    ap.add_argument("--ranks", default=None, help="time the settling window on these MPI rank counts")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    if args.ranks:
        return ranks_scaling(args)
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=root, check=True)
    binary = os.path.join(root, "target/release/grainflow")
    lmp = shutil.which("lmp")
    liggghts = shutil.which("liggghts")
    os.makedirs(args.work, exist_ok=True)
    shared = os.path.abspath(args.shared)
    inputs = os.path.join(shared, "bench/lammps")
    threads = [int(t) for t in args.threads.split(",")]
    round_trip = core_latency_probe(args.work)
    report = []
    for n in [int(s) for s in args.sizes.split(",")]:
        data, csv, box = generate(shared, args.work, n)
        entry = {"particles": n}
        # Settling window: steps 1000-3000, repeated runs.
        for t in threads:
            samples, memory, probes = [], 0, []
            for _ in range(args.repeats):
                before = round_trip() if t > 1 else None
                (w,), memory = grainflow_windows(binary, args.work, n, csv, box, t, [(1000, 3000)])
                samples.append(w[0])
                if t > 1:
                    probes.append([before, round_trip()])
            entry[f"grainflow_settling_ns_t{t}"] = statistics.median(samples)
            entry[f"grainflow_settling_samples_t{t}"] = samples
            if probes:
                entry[f"core_round_trip_ns_settling_t{t}"] = probes
            entry["grainflow_bytes_per_particle"] = memory / n
        if lmp:
            samples = []
            for _ in range(args.repeats):
                log, rss = peak_rss_of([lmp, "-in", os.path.join(inputs, "in.column"), "-var", "datafile", data,
                                        "-var", "nwarm", "1000", "-var", "nrun", "2000", "-log", "none"], cwd=args.work)
                samples.append(lammps_loop_ns(log, n, 2000))
            entry["lammps_settling_ns"] = statistics.median(samples)
            entry["lammps_settling_samples"] = samples
            entry["lammps_bytes_per_particle"] = rss / n
        liggghts_input = os.path.join(root, "scripts/bench/liggghts_column.in")
        if liggghts:
            samples = []
            for _ in range(args.repeats):
                log, rss = peak_rss_of([liggghts, "-in", liggghts_input, "-var", "datafile", data,
                                        "-var", "nwarm", "1000", "-var", "nrun", "2000", "-log", "none"],
                                       cwd=args.work)
                samples.append(lammps_loop_ns(log, n, 2000))
            entry["liggghts_settling_ns"] = statistics.median(samples)
            entry["liggghts_settling_samples"] = samples
            entry["liggghts_bytes_per_particle"] = rss / n
        if args.dense and liggghts:
            # No restart: one run to the dense window, timed once.
            log, _ = peak_rss_of([liggghts, "-in", liggghts_input, "-var", "datafile", data,
                                  "-var", "nwarm", "50200", "-var", "nrun", "2000", "-log", "none"],
                                 cwd=args.work)
            entry["liggghts_dense_ns"] = lammps_loop_ns(log, n, 2000)
            entry["liggghts_dense_samples"] = [entry["liggghts_dense_ns"]]
        if args.dense:
            windows = [(50200, 52200), (52200, 54200), (54200, 56200)]
            for t in threads:
                before = round_trip() if t > 1 else None
                result, _ = grainflow_windows(binary, args.work, n, csv, box, t, windows)
                if t > 1:
                    entry[f"core_round_trip_ns_dense_t{t}"] = [before, round_trip()]
                entry[f"grainflow_dense_ns_t{t}"] = statistics.median(r[0] for r in result)
                entry[f"grainflow_dense_samples_t{t}"] = [r[0] for r in result]
                entry["grainflow_dense_contacts"] = result[0][1]
            if lmp:
                restart = os.path.join(args.work, f"col{n}_t0.1.restart")
                if not os.path.exists(restart):
                    peak_rss_of([lmp, "-in", os.path.join(inputs, "in.column"), "-var", "datafile", data,
                                 "-var", "nwarm", "1000", "-var", "nrun", "49000", "-var", "wflag", "1",
                                 "-var", "wrestart", restart, "-log", "none"], cwd=args.work)
                samples = []
                for _ in range(args.repeats):
                    log, _ = peak_rss_of([lmp, "-in", os.path.join(inputs, "in.column_dense"), "-var", "rfile",
                                          restart, "-var", "nwarm", "200", "-var", "nrun", "2000", "-log", "none"],
                                         cwd=args.work)
                    samples.append(lammps_loop_ns(log, n, 2000))
                    contacts = re.findall(r"^\s*\d+\s+\S+\s+\d+\s+\S+\s+(\S+)\s*$", log, re.M)
                    entry["lammps_dense_contacts"] = float(contacts[-1]) if contacts else None
                entry["lammps_dense_ns"] = statistics.median(samples)
                entry["lammps_dense_samples"] = samples
        report.append(entry)
        print(json.dumps(entry, indent=1), flush=True)
    print("\nns per particle-step (median; lower is faster)")
    for e in report:
        for window in ["settling", "dense"]:
            peer = e.get(f"lammps_{window}_ns")
            for t in threads:
                ours = e.get(f"grainflow_{window}_ns_t{t}")
                if ours is None:
                    continue
                ratio = f", LAMMPS/grainflow = {peer / ours:.2f}" if peer else ""
                probe = e.get(f"core_round_trip_ns_{window}_t{t}")
                probe = f" (core round trip {json.dumps(probe)} ns)" if probe else ""
                print(f"N={e['particles']:>6} {window:>8} grainflow {t} thread(s): {ours:7.1f} ns{ratio}{probe}")
            if peer:
                print(f"N={e['particles']:>6} {window:>8} LAMMPS 1 rank:         {peer:7.1f} ns")
            other = e.get(f"liggghts_{window}_ns")
            if other:
                ours = e.get(f"grainflow_{window}_ns_t1")
                print(f"N={e['particles']:>6} {window:>8} LIGGGHTS 1 rank:       {other:7.1f} ns, "
                      f"LIGGGHTS/grainflow 1 thread = {other / ours:.2f}")
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


def ranks_scaling(args):
    """The settling window on MPI ranks of one thread: grainflow and LAMMPS."""
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))
    subprocess.run(["cargo", "build", "--release", "-q", "--features", "mpi"], cwd=root, check=True)
    binary = os.path.join(root, "target/release/grainflow")
    lmp = shutil.which("lmp")
    os.makedirs(args.work, exist_ok=True)
    shared = os.path.abspath(args.shared)
    inputs = os.path.join(shared, "bench/lammps")
    rank_counts = [int(r) for r in args.ranks.split(",")]
    report = []
    for n in [int(s) for s in args.sizes.split(",")]:
        data, csv, box = generate(shared, args.work, n)
        samples = {}
        for _ in range(args.repeats):
            for r in rank_counts:
                (w,), _ = grainflow_windows(binary, args.work, n, csv, box, 1, [(1000, 3000)], ranks=r)
                samples.setdefault(f"grainflow_r{r}", []).append(w[0])
                if lmp:
                    log, _ = peak_rss_of(on_ranks([lmp, "-in", os.path.join(inputs, "in.column"), "-var",
                                                   "datafile", data, "-var", "nwarm", "1000", "-var", "nrun",
                                                   "2000", "-log", "none"], r), cwd=args.work, env=MPI_ENV)
                    samples.setdefault(f"lammps_r{r}", []).append(lammps_loop_ns(log, n, 2000))
        entry = {"particles": n, "samples_ns_per_particle_step": samples}
        for key, values in samples.items():
            entry[key] = statistics.median(values)
        print(f"{n} particles, settling window, ns per particle-step (wall), median of {args.repeats}:")
        for code in ["grainflow", "lammps"]:
            if f"{code}_r1" not in entry:
                continue
            for r in rank_counts:
                t = entry[f"{code}_r{r}"]
                efficiency = entry[f"{code}_r1"] / (r * t)
                entry[f"{code}_efficiency_r{r}"] = efficiency
                print(f"  {code:9s} {r} ranks: {t:6.1f} ns, strong-scaling efficiency {efficiency:.3f}")
        for r in rank_counts:
            if f"lammps_r{r}" in entry:
                ratio = entry[f"grainflow_r{r}"] / entry[f"lammps_r{r}"]
                entry[f"grainflow_over_lammps_r{r}"] = ratio
                print(f"  grainflow / LAMMPS on {r} ranks: {ratio:.3f}")
        report.append(entry)
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
