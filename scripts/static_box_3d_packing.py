#!/usr/bin/env python3
"""The packing of cases/static_box_3d.toml: 1,600 spheres at rest under
COCD, written as cases/data/static_box_3d.csv (about 90 minutes on one
core).

1. The soft fill of `scripts/bench/cocd_step_3d.py --spheres 2000`: a
   jittered lattice packed by the soft DEM (t_c = 2e-4 s, e = 0.2,
   mu = 0.3) until its grains move slower than 1 mm/s; its contacts
   overlap by up to 1.3 % of a radius.
2. The same packing relaxed with contacts a hundred times stiffer
   (t_c = 2e-5 s) until its rms speed is below 1e-6 m/s: the overlaps
   fall to about 1e-4 of the pairs' diameters.
3. Radii times 1 - 2e-4 (t_c / 2e-5)^2, 0.9998 here, velocities zero: no
   pair overlaps (hard contact refuses overlaps), and the grains have
   0.2 um to settle into.
4. COCD at eps = 1e-8 for 0.1 s (the packing settles, and single grains
   that lost their seat roll and fall), velocities zero, then COCD at
   eps = 1e-5 for 0.8 s more: kinetic over potential energy at most
   6.6e-11 over its last 0.5 s (one grain still rolling slowly).
   Velocities zero again.
5. COCD at eps = 1e-8 for 0.3 s, velocities zero at the end. A packing
   at rest under eps = 1e-5 still holds grains in balances that only the
   looser solution's slack keeps: under the tighter tolerance they
   topple one after the other (five bursts of E_k/E_p up to 2.3e-8, a
   few grains each, inside the packing), then the packing rests at every
   tolerance up to 1e-3 (docs/validation.md, section 8).

A packing shrunk by 1.5 % after the soft fill, as the bench's, crept at
E_k/E_p of 1e-8 to 1e-5 for 0.4 s under COCD at every eps.

The paper's box (110,233 spheres; 111,132 here): --spheres 117500 --conic-solver
projected_gradient --tight 1e-6 --hard-times 0.05,0.2,0.1
--stiff-contact-time 5e-5 --fill-shrink 0.985 (the interior point takes
about an hour a step at that size; the projected gradient does not reach
1e-8 on a jammed packing and took 12,780 iterations for the first step at
1e-7 on the 1,600 spheres, 1,460 at 1e-6, docs/validation.md section 8). Every stage writes
checkpoints every --checkpoint-wall seconds and the script is resumable:
run it again with the same arguments and it skips the stages done and
resumes the one under way from its last checkpoint.

usage: scripts/static_box_3d_packing.py [--binary target/release/grainflow]
           [--work /tmp/static_box_3d] [--out cases/data/static_box_3d.csv]
           [--spheres 2000] [--conic-solver interior_point] [--tight 1e-8]
           [--hard-times 0.1,0.8,0.3] [--stiff-contact-time 2e-5]
           [--fill-shrink 1] [--threads 1] [--checkpoint-wall 900]
"""
import argparse, os, re, sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "bench"))
from shrink_deposit import shrunk  # noqa: E402
import cocd_step_3d  # noqa: E402


def write_rows(path, rows):
    import csv
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def stage(binary, case_text, work, name, *sets, threads=1, checkpoint_wall=900):
    """Runs `case_text` as WORK/NAME.toml into WORK/NAME, resuming from its
    last checkpoint if a run was cut short, and skipping it if it ended;
    returns its final particles' path."""
    final = os.path.join(work, name, "final_particles.csv")
    if os.path.exists(final):
        print(f"{name}: done before, kept", flush=True)
        return final
    case = os.path.join(work, name + ".toml")
    case_text = re.sub(r"\n\[checkpoint\]\n[^\[]*", "\n", case_text)
    cocd_step_3d.write(case, case_text + f"\n[checkpoint]\nwall_interval = {checkpoint_wall}\n")
    print(f"{name}: running", flush=True)
    cocd_step_3d.run(binary, case, os.path.join(work, name), *sets, threads=threads, restart=True)
    return final


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--work", default="/tmp/static_box_3d")
    parser.add_argument("--out", default="cases/data/static_box_3d.csv")
    parser.add_argument("--spheres", type=int, default=2000,
                        help="lattice sites of the soft fill (2000 gives the 1,600 of the case)")
    parser.add_argument("--conic-solver", default="interior_point",
                        help="interior_point or projected_gradient")
    parser.add_argument("--tight", type=float, default=1e-8,
                        help="the tolerance of the first and last COCD stages")
    parser.add_argument("--hard-times", default="0.1,0.8,0.3",
                        help="seconds of the three COCD stages (tight, 1e-5, tight)")
    parser.add_argument("--stiff-contact-time", type=float, default=2e-5,
                        help="t_c of the relaxation with stiffer contacts (s); the radii are then "
                             "shrunk by 2e-4 (t_c / 2e-5)^2, the overlaps it leaves")
    parser.add_argument("--fill-shrink", type=float, default=1.0,
                        help="radii of the soft fill times this before the stiff relaxation: a deep "
                             "fill's soft contacts overlap by more than a run accepts (0.985 for "
                             "the paper's box, whose fill overlaps by up to 7.3 %% of a radius)")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--checkpoint-wall", type=int, default=900,
                        help="wall-clock seconds between each stage's checkpoints")
    args = parser.parse_args()
    binary = os.path.abspath(args.binary)
    os.makedirs(args.work, exist_ok=True)
    times = [float(t) for t in args.hard_times.split(",")]
    if len(times) != 3 or min(times) <= 0.0:
        sys.exit(f"--hard-times takes three positive durations, not {args.hard_times!r}")
    solver = f'contact.conic_solver="{args.conic_solver}"'
    run = dict(threads=args.threads, checkpoint_wall=args.checkpoint_wall)
    # 1. The soft fill (the bench's).
    fill_case_path = os.path.join(args.work, "fill.toml")
    if not os.path.exists(os.path.join(args.work, "fill", "final_particles.csv")):
        cocd_step_3d.fill(binary, args.work, args.spheres, threads=args.threads,
                          checkpoint_wall=args.checkpoint_wall)
    fill_case = open(fill_case_path).read()
    # 2. Stiffer contacts, to rest.
    write_rows(os.path.join(args.work, "fill_at_rest.csv"),
               shrunk(os.path.join(args.work, "fill", "final_particles.csv"), args.fill_shrink))
    stiff = re.sub(r"\[\[particles\.block\]\].*?jitter = 0\.3",
                   '[[particles.block]]\nkind = "file"\npath = "fill_at_rest.csv"',
                   fill_case, flags=re.S)
    stiff = stiff.replace("contact_time = 2.0e-4", f"contact_time = {args.stiff_contact_time!r}")
    stiff = stiff.replace("seed = 3\n", "")
    stiff = re.sub(r"\[time\].*?\n\n", "[time]\nend = 0.6\ndt_over_contact_time = 0.1\n"
                   "rest_speed = 1.0e-6\nrest_after = 0.05\n\n", stiff, flags=re.S)
    relaxed = stage(binary, stiff, args.work, "stiff", **run)
    # 3. Apart.
    shrink = 1.0 - 2e-4 * (args.stiff_contact_time / 2e-5) ** 2
    write_rows(os.path.join(args.work, "apart.csv"), shrunk(relaxed, shrink))
    # 4. COCD, twice, from rest.
    hard = re.sub(r'path = "fill_at_rest.csv"', 'path = "apart.csv"', stiff)
    hard = re.sub(r"\[contact\].*?\n\n", '[contact]\nmodel = "cocd"\nfriction = 0.3\n\n',
                  hard, flags=re.S)
    hard = re.sub(r"\[time\].*?\n\n", "[time]\nend = TIME\ndt = 1.0e-3\n\n", hard, flags=re.S)
    tight = f"contact.tolerance={args.tight}"
    settled = stage(binary, hard.replace("TIME", str(times[0])), args.work, "cocd_tight",
                    tight, solver, **run)
    write_rows(os.path.join(args.work, "settled.csv"), shrunk(settled, 1.0))
    longer = hard.replace('path = "apart.csv"', 'path = "settled.csv"')
    rest = stage(binary, longer.replace("TIME", str(times[1])), args.work, "cocd_long",
                 "contact.tolerance=1e-5", solver, **run)
    write_rows(os.path.join(args.work, "rest_loose.csv"), shrunk(rest, 1.0))
    tighter = longer.replace('path = "settled.csv"', 'path = "rest_loose.csv"')
    rest = stage(binary, tighter.replace("TIME", str(times[2])), args.work, "cocd_tight_rest",
                 tight, solver, **run)
    write_rows(args.out, shrunk(rest, 1.0))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
