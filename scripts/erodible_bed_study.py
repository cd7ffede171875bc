#!/usr/bin/env python3
"""The 2D study of granular collapses on erodible beds (Martin et al. 2022,
section 5.1): for each erodible-layer thickness h_i, rains a deposit with
`cases/erodible_bed_fill_2d.toml` (the column R0 x H0 = 20 x 14 cm behind
the gate, the layer beyond it, the preparation friction), then releases it
on each slope with `cases/erodible_bed_2d.toml` (the run friction, gravity
tilted). Writes one CSV row per run (runout, front phases, bed energy,
cost) and every run's front series.

    scripts/erodible_bed_study.py --work /tmp/study --out docs/validation/erodible_bed_2d.csv \
        --diameter 0.008 --thickness 0 3 5 7 10 --slope 0 16 19 22

--fill-model soft rains the deposits with the soft DEM (compact at
--prep-friction 0 as the paper's), the affordable preparation at the
paper's 1 mm grains.

Thicknesses are in mean diameters (the paper's h_i = 0, 3, 5, 7, 10 mm at
d = 1 mm). The grain counts follow the packing fraction 0.80 that the fill
reaches at μ = 0 (measured at d = 8 mm: 410 discs make a column 12.8 cm
high, 500 a layer 24.7 mm thick over 1.3 m). A deposit is rained once per
thickness and reused by every slope, model and time step.

--bed glued releases the same deposits with the layer's grains glued
where they lie (the column's grains alone move): the layer's roughness
without its erodibility, beside the erodible runs and the lattice's
rigid bed (h_i = 0).

--members N releases each deposit N times on each slope, |g| raised by
k x 1e-8 relative for member k (k = 0 the case's): the same release on
another of its chaotic paths, for the spread of single runs.
--first-member K runs members K to N - 1 only, to add to an ensemble
run before (the deposit is rained again to the same bits).

The same command run again resumes: deposits already in --work are kept,
and so are runs that finished; a run stopped by a signal goes on from
the checkpoint it wrote. --jobs 2 runs two releases side by side, each
on one thread: on two cores a sweep's throughput, since a small scene
gains little from a second thread.
"""
import argparse
import concurrent.futures
import csv
import math
import os
import shutil
import sys

from grainflow_run import finished_summary, run_case
from shrink_deposit import shrunk

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.join(HERE, "..", "cases")
PACKING = 0.80
SPREAD = 0.1
COLUMN_LENGTH = 0.2
COLUMN_HEIGHT = 0.14

FIELDS = [
    "thickness_diameters", "bed", "slope", "model", "dt", "member", "status", "erodible_thickness",
    "aspect_ratio", "column_grains", "bed_grains", "runout", "final_front",
    "front_max_speed", "front_max_speed_time", "deceleration_end_time", "slow_phase",
    "slow_phase_speed", "front_stop_time", "bed_max_kinetic_to_potential", "steps",
    "wall_seconds", "stop_reason",
]


def disc_area(radius):
    """Mean area of a disc of mean radius `radius`, radii uniform within ±SPREAD."""
    return math.pi * radius**2 * (1.0 + SPREAD**2 / 3.0)


# The soft rain (--fill-model soft): the column's grains start below this
# solid fraction's height, so that they land at under 2 m/s, and the
# contact time keeps the landing's overlap near a tenth of a radius for
# 1 mm grains; the deposit's radii are then shrunk by SOFT_SHRINK, so that
# the grains it left pressed together stand apart for hard contact.
SOFT_COLUMN_FRACTION = 0.4
SOFT_CONTACT_TIME = 5e-5
SOFT_SHRINK = 0.999


def fill(binary, work, radius, length, thickness, prep_friction, fill_model="cocd"):
    """Rains the deposit of one layer thickness (m) with `fill_model`
    ("cocd", the paper's, or "soft", the soft DEM: at the paper's 1 mm
    grains a hard rain of 45,000 discs takes 5 to 20 s a step, and the soft
    one about an hour in all); returns its path."""
    d = 2.0 * radius
    spacing = 1.1 * d
    column = round(PACKING * COLUMN_LENGTH * COLUMN_HEIGHT / disc_area(radius))
    layer = round(PACKING * (length - COLUMN_LENGTH) * thickness / disc_area(radius))
    suffix = "" if fill_model == "cocd" else f"_{fill_model}"
    out = os.path.join(work, f"fill_{thickness / d:g}d{suffix}")
    deposit = os.path.join(work, f"deposit_{thickness / d:g}d{suffix}.csv")
    if os.path.exists(deposit):
        return deposit
    sets = [
        f"domain.upper=[{length},0.6]",
        f"particles.radius={radius}",
        f"particles.block[0].upper=[{length},{spacing}]",
        f"particles.block[0].spacing={spacing}",
        f"particles.block[1].lower=[0.0,{spacing + 0.2 * radius}]",
        f"particles.block[1].count={column}",
        f"particles.block[2].lower=[{COLUMN_LENGTH},{spacing + 0.2 * radius}]",
        f"particles.block[2].upper=[{length},{spacing + 4.0 * thickness + 4.0 * d}]",
        f"particles.block[2].count={layer}",
        f"walls[2].point=[{length},0.0]",
        f"contact.friction={prep_friction}",
    ]
    if fill_model == "soft":
        top = spacing + column * disc_area(radius) / (SOFT_COLUMN_FRACTION * COLUMN_LENGTH)
        sets += [
            f"particles.block[1].upper=[{COLUMN_LENGTH},{top}]",
            'contact.model="soft"',
            f"contact.contact_time={SOFT_CONTACT_TIME}",
            "contact.restitution=0.2",
            f"time.dt={0.02 * SOFT_CONTACT_TIME}",
        ]
    case = os.path.join(CASES, "erodible_bed_fill_2d.toml")
    if layer == 0:
        # No layer: the fill without its third block.
        with open(case) as f:
            text = f.read()
        start = text.index("# The erodible layer")
        text = text[:start] + text[text.index("[contact]", start):]
        case = os.path.join(work, "fill_without_layer.toml")
        with open(case, "w") as f:
            f.write(text)
        sets = [s for s in sets if not s.startswith("particles.block[2]")]
    # A rain of the paper's 45,000 discs outlasts a session: checkpoints.
    sets.append("checkpoint.wall_interval=600")
    summary, refusal = run_case(binary, case, out, sets, resume=True)
    if summary is None:
        sys.exit(f"fill of {thickness} m refused: {refusal}")
    if fill_model == "soft":
        with open(deposit, "w", newline="") as f:
            csv.writer(f).writerows(shrunk(os.path.join(out, "final_particles.csv"), SOFT_SHRINK))
    else:
        shutil.copy(os.path.join(out, "final_particles.csv"), deposit)
    return deposit


def release(binary, work, deposit, radius, length, thickness, slope, model, dt, end, extra,
            member=0, bed="erodible"):
    d = 2.0 * radius
    spacing = 1.1 * d
    theta = math.radians(slope)
    # Member k of an ensemble: |g| perturbed in its eighth digit, so that
    # the same release follows another of its chaotic paths.
    g = 9.81 * (1.0 + 1e-8 * member)
    out = os.path.join(work, f"run_{thickness / d:g}d_{slope:g}deg_{model}_{dt:g}"
                       + ("_glued" if bed == "glued" else "") + (f"_m{member}" if member else ""))
    sets = [
        f"domain.upper=[{length},0.6]",
        f"domain.gravity=[{g * math.sin(theta)},{-g * math.cos(theta)}]",
        f"particles.radius={radius}",
        f"particles.block[0].upper=[{length},{spacing}]",
        f"particles.block[0].spacing={spacing}",
        f'particles.block[1].path="{os.path.abspath(deposit)}"',
        f"walls[2].point=[{length},0.0]",
        # The case's velocity probes (0.5, 1 and 1.5 m on its 2.5 m
        # channel), at the same fractions of a channel of another length.
        f"analysis.probes=[{0.2 * length:g},{0.4 * length:g},{0.6 * length:g}]",
        f'contact.model="{model}"',
        f"time.dt={dt}",
        f"time.end={end}",
        # Releases at the paper's 1 mm grains outlast a session.
        "checkpoint.wall_interval=600",
    ] + extra
    if bed == "glued" and thickness > 0:
        # The layer's grains (group 2) glued where they lie.
        sets.append("particles.block[1].fixed_groups=[2]")
    summary, refusal = finished_summary(out), None
    if summary is None:
        summary, refusal = run_case(binary, os.path.join(CASES, "erodible_bed_2d.toml"), out, sets,
                                    resume=True)
    row = {"thickness_diameters": thickness / d, "bed": bed, "slope": slope, "model": model, "dt": dt,
           "member": member}
    if summary is None:
        row["status"] = "refused"
        row["stop_reason"] = refusal
        return row, []
    for key in ("status", "stop_reason", "steps", "wall_seconds"):
        row[key] = summary[key]
    for key in FIELDS:
        if key in summary["metrics"]:
            row[key] = summary["metrics"][key]
    fronts = []
    with open(os.path.join(out, "front.csv")) as f:
        for r in csv.DictReader(f):
            r.update({"thickness_diameters": thickness / d, "bed": bed, "slope": slope, "model": model,
                      "dt": dt, "member": member})
            fronts.append(r)
    return row, fronts


def write_tables(out, fields, rows, fronts):
    """One row per run to `out`, and every run's front series beside it
    (`_fronts.csv`)."""
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    if fronts:
        with open(out.replace(".csv", "_fronts.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(fronts[0].keys()))
            w.writeheader()
            w.writerows(fronts)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--work", required=True, help="folder for the deposits and the runs")
    parser.add_argument("--out", required=True, help="CSV of one row per run")
    parser.add_argument("--diameter", type=float, default=0.008, help="mean diameter d (m)")
    parser.add_argument("--length", type=float, default=2.5, help="channel length (m)")
    parser.add_argument("--thickness", type=float, nargs="+", default=[0, 3, 5, 7, 10],
                        help="erodible-layer thicknesses h_i in mean diameters")
    parser.add_argument("--slope", type=float, nargs="+", default=[0, 16, 19, 22], help="degrees")
    parser.add_argument("--model", nargs="+", default=["cocd"], help="cocd, nscd or soft")
    parser.add_argument("--dt", type=float, default=1e-3)
    parser.add_argument("--end", type=float, default=3.0, help="simulated time after the release (s)")
    parser.add_argument("--prep-friction", type=float, default=0.0)
    parser.add_argument("--fill-model", choices=["cocd", "soft"], default="cocd",
                        help="the rain's contact model (soft: affordable at 1 mm grains)")
    parser.add_argument("--bed", choices=["erodible", "glued"], default="erodible",
                        help="the layer's grains free (the paper's) or glued where they lie")
    parser.add_argument("--set", action="append", default=[], help="extra --set for the runs")
    parser.add_argument("--jobs", type=int, default=1, help="releases side by side, one thread each")
    parser.add_argument("--members", type=int, default=1,
                        help="releases of each deposit and slope, |g| perturbed in its eighth digit")
    parser.add_argument("--first-member", type=int, default=0,
                        help="the first member to run (members below it were run before)")
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    radius = 0.5 * args.diameter
    sets = args.set + (["parallel.threads=1"] if args.jobs > 1 else [])
    deposits = {h: fill(args.binary, args.work, radius, args.length, h * args.diameter, args.prep_friction,
                        args.fill_model)
                for h in args.thickness}

    def run(job):
        h, slope, model, member = job
        row, front = release(args.binary, args.work, deposits[h], radius, args.length,
                             h * args.diameter, slope, model, args.dt, args.end, sets, member, args.bed)
        print(", ".join(f"{k}={row.get(k)}" for k in ("thickness_diameters", "slope", "model", "member",
                                                     "runout", "slow_phase", "wall_seconds")),
              flush=True)
        return row, front

    jobs = [(h, slope, model, member) for h in args.thickness for slope in args.slope
            for model in args.model for member in range(args.first_member, args.members)]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run, jobs))
    rows = [row for row, _ in results]
    fronts = [r for _, front in results for r in front]
    write_tables(args.out, FIELDS, rows, fronts)


if __name__ == "__main__":
    main()
