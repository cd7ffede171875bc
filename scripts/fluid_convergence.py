#!/usr/bin/env python3
"""Refinement study of the exact decaying flows: cases/taylor_green_2d.toml
(a Taylor–Green vortex in a uniform stream) and cases/taylor_green_3d.toml
(the Beltrami flow), refined in space and time together (dt proportional to
the cell size, constant CFL), so that a scheme second order in both shows an
observed order of 2. Writes a CSV of (case, cells, dt, l2_error, observed
order, max_divergence, wall seconds) and prints it; plot it with
postprocess/plot_convergence.py.

usage: scripts/fluid_convergence.py [--out docs/validation/fluid_convergence.csv]
"""
import argparse, json, math, os, subprocess, tempfile

SEQUENCES = {
    # case: (cells per axis, dt at the coarsest, dimension, extra overrides)
    "taylor_green_2d": ([16, 32, 64, 128, 256], 0.04, 2, []),
    "taylor_green_3d": ([8, 16, 32, 64], 0.08, 3, ["time.end=0.32"]),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
    out = args.out or os.path.join(root, "docs/validation/fluid_convergence.csv")
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=root, check=True)
    binary = os.path.join(root, "target/release/grainflow")
    rows = []
    for case, (cells, dt0, dim, extra) in SEQUENCES.items():
        previous = None
        for n in cells:
            dt = dt0 * cells[0] / n
            with tempfile.TemporaryDirectory() as work:
                sets = [f"fluid.cells=[{', '.join([str(n)] * dim)}]", f"time.dt={dt!r}",
                        "output.fields=false"] + extra
                command = [binary, "run", os.path.join(root, f"cases/{case}.toml"), "--out", work]
                for s in sets:
                    command += ["--set", s]
                subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                summary = json.load(open(os.path.join(work, "summary.json")))
            error = summary["metrics"]["l2_error"]
            order = math.log2(previous / error) if previous else float("nan")
            previous = error
            rows.append((case, n, dt, error, order, summary["metrics"]["max_divergence"],
                         summary["wall_seconds"]))
            print(f"{case:16s} {n:4d} cells/axis dt {dt:.4e}  L2 error {error:.4e}  order {order:5.3f}  "
                  f"max div {rows[-1][5]:.1e}  {rows[-1][6]:.2f} s", flush=True)
    with open(out, "w") as f:
        f.write("case,cells_per_axis,dt,l2_error,observed_order,max_divergence,wall_seconds\n")
        for r in rows:
            f.write(",".join(str(v) for v in r) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
