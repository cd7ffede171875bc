#!/usr/bin/env python3
"""One COCD step of a 2D packing at rest: grainflow against Clarabel called
from Python on the same conic problem.

The packing and the peer come from ../shared/bench/cocd/: `cocd_gen.py`
builds a disordered column of N discs (d = 1 mm +- 10 %) at rest between two
walls by deposition, with its candidate contacts (gap < 0.1 d), and
`run_solvers.py` solves the velocity-based COCD step (eq. 10) with Clarabel
(one second-order cone of size 2 per contact, QDLDL). grainflow reads the
same discs (a `file` block) and walls and takes three steps of
dt = 1e-3 s with contact.model = "cocd" at the same tolerance; its
seconds_per_solve is the mean time of the conic solve per step (assembly
included). Prints, per size, the median over --repeats runs of each, their
ratio, the iterations and contacts, and writes the table as JSON. grainflow
runs on each thread count of --threads (its results are the same on any),
and with --ranks 2 also on that many MPI ranks of one thread each (mpirun;
the binary built with --features mpi), the program shared among them.

usage: scripts/bench/cocd_step.py [--sizes 8000,50000] [--tolerance 1e-8]
         [--repeats 3] [--threads 1,2] [--ranks 2] [--shared ../shared]
         [--work DIR] [--json FILE]
"""
import argparse, json, os, shutil, statistics, subprocess, sys

CASE = """[domain]
dimension = 2
lower = [0.0, 0.0]
upper = [{width}, {height}]
gravity = [0.0, -9.81]

[particles]
density = 2500.0
radius = {radius}

[[particles.block]]
kind = "file"
path = "{csv}"

[contact]
model = "cocd"
friction = {mu}
tolerance = {tolerance}
threshold = {threshold}

[[walls]]
name = "floor"
point = [0.0, 0.0]
normal = [0.0, 1.0]

[[walls]]
name = "left"
point = [0.0, 0.0]
normal = [1.0, 0.0]

[[walls]]
name = "right"
point = [{width}, 0.0]
normal = [-1.0, 0.0]

[time]
end = {end}
dt = {dt}

[output]
interval = 1.0
"""


def make_instance(shared, work, n):
    npz = os.path.join(work, f"inst{n}.npz")
    if not os.path.exists(npz):
        subprocess.run([sys.executable, os.path.join(shared, "bench/cocd/cocd_gen.py"),
                        "--N", str(n), "--out", npz], check=True, cwd=work)
    return npz


def grainflow_case(npz, work, n, tolerance):
    import numpy as np
    inst = dict(np.load(npz))
    pos, rad, d = inst["pos"], inst["rad"], float(inst["d"])
    csv = os.path.join(work, f"discs{n}.csv")
    with open(csv, "w") as f:
        f.write("x,y,radius\n")
        for (x, y), r in zip(pos, rad):
            f.write(f"{float(x)!r},{float(y)!r},{float(r)!r}\n")
    dt = float(inst["dt"])
    case = os.path.join(work, f"cocd_step{n}.toml")
    with open(case, "w") as f:
        f.write(CASE.format(width=float(inst["L"]), height=2.0 * pos[:, 1].max() + d,
                            radius=0.5 * d, csv=os.path.basename(csv), mu=float(inst["mu"]),
                            tolerance=tolerance, threshold=float(inst["D"]), end=3.5 * dt, dt=dt))
    return case, len(inst["ci"])


def run_grainflow(binary, case, work, tag, threads, ranks=1):
    out = os.path.join(work, f"out_{tag}")
    shutil.rmtree(out, ignore_errors=True)
    args = [binary, "run", case, "--out", out, "--threads", str(threads)]
    if ranks > 1:
        args = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + args
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    m = s["metrics"]
    return dict(seconds=m["seconds_per_solve"], iterations=m["mean_iterations"],
                contacts=m["mean_candidates"], coulomb=m["max_coulomb_violation"],
                penetration=m["max_penetration"], memory=s["peak_memory_bytes"])


def run_peer(shared, npz, tolerance, work):
    result = subprocess.run([sys.executable, os.path.join(shared, "bench/cocd/run_solvers.py"),
                             npz, "clarabel", "--tol", str(tolerance), "--threads", "1"],
                            check=True, capture_output=True, text=True, cwd=work)
    rec = json.loads(result.stdout.strip().splitlines()[-1])
    return dict(seconds=rec["solve_s"], iterations=rec["iters"], contacts=rec["contacts"],
                status=rec["status"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="8000,50000")
    ap.add_argument("--tolerance", type=float, default=1e-8)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--ranks", default="", help="MPI ranks of one thread each, e.g. 2")
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "../../../shared"))
    ap.add_argument("--work", default="/tmp/grainflow_cocd_bench")
    ap.add_argument("--binary", default="target/release/grainflow")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    binary = os.path.abspath(a.binary)
    shared = os.path.abspath(a.shared)
    table = []
    for n in [int(s) for s in a.sizes.split(",")]:
        npz = make_instance(shared, a.work, n)
        case, peer_contacts = grainflow_case(npz, a.work, n, a.tolerance)
        # (ranks, threads) of each configuration, labelled "t2" or "r2".
        configs = {f"t{t}": (1, int(t)) for t in a.threads.split(",")}
        configs.update({f"r{r}": (int(r), 1) for r in a.ranks.split(",") if r})
        ours, peer = {c: [] for c in configs}, []
        for r in range(a.repeats):  # interleaved, so that all see the same machine load
            for c, (ranks, t) in configs.items():
                ours[c].append(run_grainflow(binary, case, a.work, f"{n}_{r}_{c}", t, ranks))
            peer.append(run_peer(shared, npz, a.tolerance, a.work))
        threads = list(configs)
        first = ours[threads[0]][0]
        row = dict(
            N=n, tolerance=a.tolerance,
            grainflow_iterations=first["iterations"], grainflow_contacts=first["contacts"],
            grainflow_coulomb_violation=max(o["coulomb"] for t in threads for o in ours[t]),
            grainflow_penetration=max(o["penetration"] for t in threads for o in ours[t]),
            grainflow_peak_memory=first["memory"],
            peer_seconds=statistics.median(p["seconds"] for p in peer),
            peer_iterations=peer[0]["iterations"], peer_contacts=peer[0]["contacts"],
            peer_status=peer[0]["status"],
            samples_peer=[p["seconds"] for p in peer],
        )
        line = f"N={n}: "
        for c in threads:
            seconds = statistics.median(o["seconds"] for o in ours[c])
            row[f"grainflow_seconds_{c}"] = seconds
            row[f"samples_grainflow_{c}"] = [o["seconds"] for o in ours[c]]
            row[f"ratio_{c}"] = row["peer_seconds"] / seconds
            ranks, t = configs[c]
            where = f"{ranks} ranks" if ranks > 1 else f"{t} thread(s)"
            line += f"grainflow {seconds:.3f} s/step on {where} (ratio {row[f'ratio_{c}']:.2f}), "
        table.append(row)
        print(line + f"{row['grainflow_iterations']:.0f} it, {row['grainflow_contacts']:.0f} contacts; "
              f"Clarabel from Python {row['peer_seconds']:.3f} s ({row['peer_iterations']} it, "
              f"{row['peer_contacts']} contacts)", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(table, f, indent=1)


if __name__ == "__main__":
    main()
