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
3. Radii times 0.9998, velocities zero: no pair overlaps (hard contact
   refuses overlaps), and the grains have 0.2 um to settle into.
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

usage: scripts/static_box_3d_packing.py [--binary target/release/grainflow]
           [--work /tmp/static_box_3d] [--out cases/data/static_box_3d.csv]
"""
import argparse, os, re, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "bench"))
from shrink_deposit import shrunk  # noqa: E402
import cocd_step_3d  # noqa: E402


def write_rows(path, rows):
    import csv
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def stage(binary, case_text, work, name, *sets, threads=1):
    """Runs `case_text` as WORK/NAME.toml into WORK/NAME; returns its final
    particles' path."""
    case = os.path.join(work, name + ".toml")
    cocd_step_3d.write(case, case_text)
    out = os.path.join(work, name)
    cocd_step_3d.run(binary, case, out, *sets, threads=threads)
    return os.path.join(out, "final_particles.csv")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--work", default="/tmp/static_box_3d")
    parser.add_argument("--out", default="cases/data/static_box_3d.csv")
    args = parser.parse_args()
    binary = os.path.abspath(args.binary)
    os.makedirs(args.work, exist_ok=True)
    # 1. The soft fill (the bench's).
    cocd_step_3d.fill(binary, args.work, 2000)
    fill_case = open(os.path.join(args.work, "fill.toml")).read()
    # 2. Stiffer contacts, to rest.
    write_rows(os.path.join(args.work, "fill_at_rest.csv"),
               shrunk(os.path.join(args.work, "fill", "final_particles.csv"), 1.0))
    stiff = re.sub(r"\[\[particles\.block\]\].*?jitter = 0\.3",
                   '[[particles.block]]\nkind = "file"\npath = "fill_at_rest.csv"',
                   fill_case, flags=re.S)
    stiff = stiff.replace("contact_time = 2.0e-4", "contact_time = 2.0e-5")
    stiff = stiff.replace("seed = 3\n", "")
    stiff = re.sub(r"\[time\].*?\n\n", "[time]\nend = 0.6\ndt_over_contact_time = 0.1\n"
                   "rest_speed = 1.0e-6\nrest_after = 0.05\n\n", stiff, flags=re.S)
    relaxed = stage(binary, stiff, args.work, "stiff")
    # 3. Apart.
    write_rows(os.path.join(args.work, "apart.csv"), shrunk(relaxed, 0.9998))
    # 4. COCD, twice, from rest.
    hard = re.sub(r'path = "fill_at_rest.csv"', 'path = "apart.csv"', stiff)
    hard = re.sub(r"\[contact\].*?\n\n", '[contact]\nmodel = "cocd"\nfriction = 0.3\n\n',
                  hard, flags=re.S)
    hard = re.sub(r"\[time\].*?\n\n", "[time]\nend = 0.1\ndt = 1.0e-3\n\n", hard, flags=re.S)
    settled = stage(binary, hard, args.work, "cocd_tight", "contact.tolerance=1e-8")
    write_rows(os.path.join(args.work, "settled.csv"), shrunk(settled, 1.0))
    longer = hard.replace('path = "apart.csv"', 'path = "settled.csv"')
    longer = longer.replace("end = 0.1\n", "end = 0.8\n")
    rest = stage(binary, longer, args.work, "cocd_long", "contact.tolerance=1e-5")
    write_rows(os.path.join(args.work, "rest_loose.csv"), shrunk(rest, 1.0))
    tighter = longer.replace('path = "settled.csv"', 'path = "rest_loose.csv"')
    tighter = tighter.replace("end = 0.8\n", "end = 0.3\n")
    rest = stage(binary, tighter, args.work, "cocd_tight_rest", "contact.tolerance=1e-8")
    write_rows(args.out, shrunk(rest, 1.0))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
