#!/usr/bin/env python3
"""One COCD step on a 3D packing of spheres at rest: grainflow's interior
point (and, with --solvers, its projected gradient) on 1 and 2 threads, at
each tolerance, and optionally Clarabel (the in-process reference,
contact.conic_solver = "clarabel") on the same program.

The packing: spheres of d = 1 mm +- 10 % (rho = 2500 kg/m3) on a jittered
lattice in a square box (side chosen for --spheres), packed by the soft DEM
to rest (e = 0.2, t_c = 2e-4 s, mu = 0.3); their radii are then shrunk by
1.5 % (the soft contacts overlap by up to 5 % of a radius, which hard
contact refuses) and ten COCD steps of 1 ms settle them (--settle-steps;
0 times the first hard step from the shrunk deposit, as for 1.2e5 spheres,
where each settling step takes most of an hour on one thread). From that state
one step of 1 ms is timed per configuration (`seconds_per_solve`, the
conic solve with its assembly), --repeats times, alternating the
configurations. With --ranks 1,2 each configuration also runs on that
many MPI ranks (mpirun, one thread each beyond one rank; the binary built
with --features mpi): the program shared among them, the interior point's
separator's Schur complement factorised together, the projected
gradient's Aᵀz on the separator summed over the ranks each iteration. Prints the table and writes it as
JSON.

usage: scripts/bench/cocd_step_3d.py [--spheres 10000] [--tolerances 1e-8,1e-5]
         [--threads 1,2] [--ranks 1] [--repeats 2] [--settle-steps 10]
         [--solvers interior_point,projected_gradient] [--clarabel]
         [--work DIR] [--json FILE]
"""
import argparse, csv, json, math, os, subprocess, sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from shrink_deposit import shrunk  # noqa: E402

BOX = """[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {height}]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 5.0e-4
radius_spread = 0.1
seed = 3

{block}

[contact]
{contact}

[[walls]]
name = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[walls]]
point = [{side}, 0.0, 0.0]
normal = [-1.0, 0.0, 0.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[walls]]
point = [0.0, {side}, 0.0]
normal = [0.0, -1.0, 0.0]

[time]
{time}

[output]
interval = 1.0
"""

SPACING = 0.0011


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def run(binary, case, out, *sets, threads=2, ranks=1, restart=False):
    args = [binary, "run", case, "--out", out, "--threads", str(threads), "--json"]
    if restart:
        args += ["--restart", "auto"]
    if ranks > 1:
        args = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + args
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def fill(binary, work, spheres, threads=2, checkpoint_wall=None):
    """The soft DEM's packing of the lattice (WORK/fill/final_particles.csv,
    its grains slower than 1 mm/s): the box's side and the lattice's top.
    With `checkpoint_wall` (seconds) the run writes checkpoints that often
    and resumes from the last one if it was cut short."""
    # Lattice sites: a square base of k x k, layers to reach the count.
    per_side = max(4, round((spheres / 1.5) ** (1 / 3)))
    layers = math.ceil(spheres / per_side**2)
    side = (per_side + 0.1) * SPACING
    top = 0.0006 + (layers - 1) * SPACING + 1e-6
    lattice = (f'[[particles.block]]\nkind = "lattice"\nlower = [0.0006, 0.0006, 0.0006]\n'
               f'upper = [{side - 0.0006 + 1e-6}, {side - 0.0006 + 1e-6}, {top}]\n'
               f'spacing = {SPACING}\njitter = 0.3')
    case = os.path.join(work, "fill.toml")
    write(case, BOX.format(side=side, height=2 * top + 0.01, block=lattice,
                           contact='model = "soft"\nrestitution = 0.2\ncontact_time = 2.0e-4\nfriction = 0.3',
                           time="end = 2.0\ndt_over_contact_time = 0.1\nrest_speed = 1.0e-3\nrest_after = 0.4")
          + (f"\n[checkpoint]\nwall_interval = {checkpoint_wall}\n" if checkpoint_wall else ""))
    run(binary, case, os.path.join(work, "fill"), threads=threads,
        restart=checkpoint_wall is not None)
    return side, top


def packing(binary, work, spheres, settle_steps):
    """The packing after `settle_steps` hard steps of 1 ms: the name of its
    CSV of spheres in WORK (the soft fill and the shrinking are kept and
    reused by later calls)."""
    name = "shrunk.csv" if settle_steps == 0 else f"rest_{settle_steps}.csv"
    if os.path.exists(os.path.join(work, name)):
        return name
    if not os.path.exists(os.path.join(work, "shrunk.csv")):
        side, top = fill(binary, work, spheres)
        write(os.path.join(work, "box.json"), json.dumps({"side": side, "height": 2 * top + 0.01}))
        # Shrink the radii by 1.5 %, at rest.
        rows = shrunk(os.path.join(work, "fill", "final_particles.csv"), 0.985)
        with open(os.path.join(work, "shrunk.csv"), "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
    if settle_steps > 0:
        with open(os.path.join(work, "box.json")) as f:
            box = json.load(f)
        settle = os.path.join(work, "settle.toml")
        write(settle, step_case(box["side"], box["height"], "shrunk.csv",
                                f"end = {settle_steps}.0e-3\ndt = 1.0e-3"))
        run(binary, settle, os.path.join(work, "settle"))
        os.replace(os.path.join(work, "settle", "final_particles.csv"), os.path.join(work, name))
    return name


def step_case(side, height, csv, time):
    block = f'[[particles.block]]\nkind = "file"\npath = "{csv}"'
    return BOX.format(side=side, height=height, block=block,
                      contact='model = "cocd"\nfriction = 0.3', time=time)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spheres", type=int, default=10000)
    ap.add_argument("--tolerances", default="1e-8,1e-5")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--ranks", default="1", help="MPI ranks, e.g. 1,2")
    ap.add_argument("--settle-steps", type=int, default=10,
                    help="hard steps of 1 ms before the timed one (0: from the shrunk deposit)")
    ap.add_argument("--solvers", default="interior_point",
                    help="interior_point and/or projected_gradient, e.g. interior_point,projected_gradient")
    ap.add_argument("--clarabel", action="store_true")
    ap.add_argument("--work", default="/tmp/grainflow_cocd3d_bench")
    ap.add_argument("--binary", default="target/release/grainflow")
    ap.add_argument("--json")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    work = os.path.join(a.work, str(a.spheres))
    os.makedirs(work, exist_ok=True)
    rest = packing(binary, work, a.spheres, a.settle_steps)
    with open(os.path.join(work, "box.json")) as f:
        box = json.load(f)
    case = os.path.join(work, "step.toml")
    write(case, step_case(box["side"], box["height"], rest, "end = 1.0e-3\ndt = 1.0e-3"))
    configs = [(solver, t, float(e), r) for solver in a.solvers.split(",")
               for e in a.tolerances.split(",")
               for r in map(int, a.ranks.split(","))
               for t in (map(int, a.threads.split(",")) if r == 1 else [1])]
    if a.clarabel:
        configs += [("clarabel", 2, float(e), 1) for e in a.tolerances.split(",")]
    results = {c: [] for c in configs}
    for _ in range(a.repeats):
        for c in configs:
            solver, threads, tol, ranks = c
            s = run(binary, case, os.path.join(work, "step"), f"contact.tolerance={tol}",
                    f'contact.conic_solver="{solver}"', threads=threads, ranks=ranks)
            results[c].append(s["metrics"])
    table = []
    print(f"{'solver':18} {'ranks':>5} {'threads':>7} {'eps':>7} {'s per step':>22} {'iterations':>10} {'candidates':>10}")
    for (solver, threads, tol, ranks), ms in results.items():
        times = [m["seconds_per_solve"] for m in ms]
        print(f"{solver:18} {ranks:5d} {threads:7d} {tol:7.0e} {', '.join(f'{t:.1f}' for t in times):>22} "
              f"{ms[0]['mean_iterations']:10.0f} {ms[0]['mean_candidates']:10.0f}")
        table.append({"solver": solver, "ranks": ranks, "threads": threads, "tolerance": tol,
                      "seconds_per_solve": times, "iterations": ms[0]["mean_iterations"],
                      "fallback_steps": max(m.get("fallback_steps", 0) for m in ms),
                      "candidates": ms[0]["mean_candidates"],
                      "max_penetration": max(m["max_penetration"] for m in ms),
                      "max_coulomb_violation": max(m["max_coulomb_violation"] for m in ms)})
    if a.json:
        write(a.json, json.dumps({"spheres": a.spheres, "settle_steps": a.settle_steps,
                                  "results": table}, indent=1))


if __name__ == "__main__":
    main()
