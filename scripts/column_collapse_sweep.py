#!/usr/bin/env python3
"""Runout of collapsing granular columns against the aspect ratio
(Izard et al. 2014, section 3.4): one grainflow run per aspect ratio, from
cases/column_collapse_2d.toml or _3d.toml with the grain count, fill region,
release time and domain set for each. Writes a CSV of (aspect ratio at
release, runout at rest, grains, wall time) and prints it.

usage: scripts/column_collapse_sweep.py --dimension 2 [--aspects 0.5,1,2,3,5,7,10]
         [--half-width 0.1] [--seed 7] [--out docs/validation/runout_2d.csv]
"""
import argparse, json, math, os, subprocess, sys, tempfile

RADIUS = 5.0e-3
SPREAD = 0.1
# Solid fraction of the settled column and of the random fill (measured on
# the reduced columns of tests/column_collapse.rs).
SETTLED = {2: 0.75, 3: 0.53}
FILL = {2: 0.45, 3: 0.22}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dimension", type=int, choices=[2, 3], required=True)
    ap.add_argument("--aspects", default="0.5,1,2,3,5,7,10")
    ap.add_argument("--half-width", type=float, default=None, help="R0 [m] (default 0.1 in 2D, 0.05 in 3D)")
    ap.add_argument("--span", type=float, default=0.12, help="3D periodic spanwise length [m] (12 D)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
    dim = args.dimension
    r0 = args.half_width or (0.1 if dim == 2 else 0.05)
    out = args.out or os.path.join(root, f"docs/validation/runout_{dim}d.csv")
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=root, check=True)
    binary = os.path.join(root, "target/release/grainflow")
    case = os.path.join(root, f"cases/column_collapse_{dim}d.toml")
    # Mean grain size with the uniform spread: <r^2> and <r^3>.
    r2 = RADIUS**2 * (1 + SPREAD**2 / 3)
    r3 = RADIUS**3 * (1 + SPREAD**2)
    rows, failed = [], []
    for a in [float(x) for x in args.aspects.split(",")]:
        h0 = a * r0
        if dim == 2:
            grain = math.pi * r2
            count = round(2 * r0 * h0 * SETTLED[2] / grain)
            fill = count * grain / (2 * r0 * FILL[2])
        else:
            grain = 4.0 / 3.0 * math.pi * r3
            count = round(2 * r0 * args.span * h0 * SETTLED[3] / grain)
            fill = count * grain / (2 * r0 * args.span * FILL[3])
        # Random placement jams near a solid fraction of 0.55 in 2D and
        # 0.38 in 3D, and a seed may jam earlier: a column that does not fit
        # gets a fill region 10 % taller, at most three times.
        for attempt in range(4):
            summary, error = run_column(binary, case, column_settings(args, dim, a, r0, count, fill * 1.1**attempt),
                                        args.threads)
            if summary is not None or "could place only" not in error:
                break
            print(f"a = {a}: fill region too full ({error.strip()}); 10 % taller", file=sys.stderr)
        if summary is None:
            print(f"a = {a}: failed\n{error}", file=sys.stderr)
            failed.append(a)
            continue
        m = summary["metrics"]
        row = dict(target_aspect_ratio=a, aspect_ratio=m["aspect_ratio"], runout=m["runout"], grains=count,
                   half_width=r0, at_rest=summary["stop_reason"].startswith("at rest"),
                   simulated_time=summary["simulated_time"], wall_seconds=summary["wall_seconds"])
        rows.append(row)
        print(json.dumps(row), flush=True)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        f.write(",".join(rows[0].keys()) + "\n")
        for row in rows:
            f.write(",".join(str(v) for v in row.values()) + "\n")
    print(f"wrote {out}")
    if failed:
        sys.exit(f"no runout for the aspect ratios {failed}: see the errors above")


def column_settings(args, dim, a, r0, count, fill):
    """The --set overrides of a column of `count` grains filled up to `fill`."""
    release = math.sqrt(2 * fill / 9.81) + 0.6
    reach = r0 * (2.0 + 3.0 * a ** (2.0 / 3.0))
    top = fill + 0.1
    if dim == 2:
        sets = [f"domain.lower=[{-reach}, 0.0]", f"domain.upper=[{reach}, {top}]",
                f"particles.block[0].lower=[{-r0}, 0.0]", f"particles.block[0].upper=[{r0}, {fill}]",
                f"walls[1].point=[{-r0}, 0.0]", f"walls[2].point=[{r0}, 0.0]"]
    else:
        sets = [f"domain.lower=[{-reach}, 0.0, 0.0]", f"domain.upper=[{reach}, {args.span}, {top}]",
                f"particles.block[0].lower=[{-r0}, 0.0, 0.0]",
                f"particles.block[0].upper=[{r0}, {args.span}, {fill}]",
                f"walls[1].point=[{-r0}, 0.0, 0.0]", f"walls[2].point=[{r0}, 0.0, 0.0]"]
    return sets + [f"particles.block[0].count={count}", f"particles.seed={args.seed}",
                   f"walls[1].remove_at={release}", f"walls[2].remove_at={release}",
                   f"time.end={release + 6.0}", "output.interval=0.05"]


def run_column(binary, case, sets, threads=None):
    """One grainflow run: (summary, None), or (None, its error)."""
    with tempfile.TemporaryDirectory() as tmp:
        command = [binary, "run", case, "--out", tmp]
        for s in sets:
            command += ["--set", s]
        if threads:
            command += ["--threads", str(threads)]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            return None, result.stderr
        return json.load(open(os.path.join(tmp, "summary.json"))), None


if __name__ == "__main__":
    main()
