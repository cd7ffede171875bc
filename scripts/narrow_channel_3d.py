#!/usr/bin/env python3
"""The 3D narrow channel of Martin et al. (2022, section 5.2): a column
R0 x H0 = 10 x 7 cm released on an erodible layer h_i = 5 mm in a channel
W = 0.8 cm wide between frictionless side walls, inclined at 22 degrees,
from the paper's three preparations: compact/compact, compact/loose and
loose/loose (the column's, then the layer's; compact is rained at
mu = 0, loose at mu = 0.3). The paper finds the front fastest, about
75 cm/s, near x = 16 cm, decelerating until x = 26.5 cm, then a slow
propagation near 15 cm/s; the runout independent of the compaction and a
thicker compact column upslope.

    scripts/narrow_channel_3d.py --work /tmp/narrow --out docs/validation/narrow_channel_3d.csv

Rains `cases/narrow_channel_fill_3d.toml` once at each preparation
friction, builds each preparation's deposit from the two rains (the
column's grains from one, the layer's from the other: both rest on the
same glued bed, drawn from the same seed), then releases it with
`cases/narrow_channel_3d.toml` (the soft DEM). --diameter sets the mean
grain (default 2 mm; the paper's is 1 mm): the counts grow as d^-3 and
the contact time with d (the overlaps stay the same fraction of a grain).
--rolling-friction gives the releases a rolling resistance (the paper's
spheres have none; a layer on this slope stops only with one, see
scripts/chute_layer_arrest.py). Writes one row per run (the front's
phases, where they happen, the runout, the deposit's thickness upslope,
the cost) and the fronts and
final profiles beside it (`_fronts.csv`, `_profiles.csv`).

The same command run again resumes: rains and releases that finished are
kept, and one that was stopped goes on from its newest checkpoint.
--jobs 2 runs two at once, one thread each.
"""
import argparse
import concurrent.futures
import csv
import math
import os
import sys

from collapse_2d_3d import vtp_arrays
from grainflow_run import finished_summary, run_case

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.join(HERE, "..", "cases")
# The channel (m) and the files' grain (radius 1 mm) and counts.
WIDTH, GATE, LENGTH = 0.008, 0.1, 1.2
CASE_RADIUS, COLUMN_GRAINS, LAYER_GRAINS = 1e-3, 7700, 5600
CASE_CONTACT_TIME = 1e-4
PREPARATIONS = {"compact": 0.0, "loose": 0.3}
# Column's preparation, then the layer's.
RUNS = {"cc": ("compact", "compact"), "cl": ("compact", "loose"), "ll": ("loose", "loose")}
# Upslope: the deposit's thickness is averaged over x in [0, UPSLOPE].
UPSLOPE = 0.02
FIELDS = [
    "preparation", "slope", "diameter", "rolling_friction", "status", "column_grains", "bed_grains", "initial_height",
    "aspect_ratio", "front_max_speed", "front_max_speed_time", "front_max_speed_x",
    "deceleration_end_time", "deceleration_end_x", "slow_phase", "slow_phase_speed",
    "final_front", "runout_x", "upslope_thickness", "steps", "simulated_time", "wall_seconds",
    "stop_reason",
]


def grain_sets(radius):
    """The --set of both cases for grains of mean radius `radius`: the
    glued lattice 2.2 r apart centred across the channel, the contact time
    scaled with d (none at the files' own grain)."""
    if radius == CASE_RADIUS:
        return []
    spacing = 2.2 * radius
    across = math.floor(WIDTH / spacing)
    offset = 0.5 * (WIDTH - across * spacing)
    return [f"particles.radius={radius}", f"particles.block[0].spacing={spacing}",
            f"particles.block[0].lower=[0.0,{offset},0.0]",
            f"particles.block[0].upper=[{LENGTH},{WIDTH},{spacing}]",
            f"contact.contact_time={CASE_CONTACT_TIME * radius / CASE_RADIUS}"]


def rain(binary, work, radius, preparation, threads):
    """Rains the deposit at the preparation's friction; its folder."""
    out = os.path.join(work, f"fill_{preparation}")
    scale = (CASE_RADIUS / radius) ** 3
    sets = grain_sets(radius) + [f"contact.friction={PREPARATIONS[preparation]}"]
    if radius != CASE_RADIUS:
        sets += [f"particles.block[1].count={round(COLUMN_GRAINS * scale)}",
                 f"particles.block[1].lower=[0.0,0.0,{3.5 * radius}]",
                 f"particles.block[2].count={round(LAYER_GRAINS * scale)}",
                 f"particles.block[2].lower=[{GATE},0.0,{3.5 * radius}]"]
    if threads:
        sets.append(f"parallel.threads={threads}")
    if finished_summary(out) is None:
        summary, refusal = run_case(binary, os.path.join(CASES, "narrow_channel_fill_3d.toml"), out, sets,
                                    resume=True)
        if summary is None:
            sys.exit(f"rain ({preparation}) refused: {refusal}")
    return out


def deposit(work, column_fill, layer_fill, name):
    """The column's grains (x < gate) of one rain and the layer's of the
    other, centres and radii to seven digits, at rest."""
    path = os.path.join(work, f"deposit_{name}.csv")
    if os.path.exists(path):
        return path
    rows = []
    for fill, keep in ((column_fill, lambda x: x < GATE), (layer_fill, lambda x: x > GATE)):
        with open(os.path.join(fill, "final_particles.csv")) as f:
            rows += [r for r in csv.DictReader(f) if keep(float(r["x"]))]
    with open(path, "w") as d:
        d.write("x,y,z,radius,group\n")
        for r in rows:
            d.write(",".join(f"{float(r[k]):.7g}" for k in ("x", "y", "z", "radius")) + f",{r['group']}\n")
    return path


def glued(folder):
    """The glued grains of a run's first particle file."""
    arrays = vtp_arrays(os.path.join(folder, "particles", "particles_000000.vtp"),
                        {"position", "radius", "fixed"})
    return sorted((p, r) for p, (r,), (f,) in zip(arrays["position"], arrays["radius"], arrays["fixed"]) if f)


def front_x_at(fronts, time):
    """The front (m) at the sample nearest `time`."""
    if time is None:
        return None
    return min(fronts, key=lambda r: abs(float(r["time_after_release"]) - time))["front"]


def final_profile(folder, radius):
    """h(x) of the deposit at the end: the grains' volume in bins two mean
    diameters wide over the bin's width and the channel's (m)."""
    width = 4.0 * radius
    volume = {}
    with open(os.path.join(folder, "final_particles.csv")) as f:
        for r in csv.DictReader(f):
            k = int(float(r["x"]) / width)
            volume[k] = volume.get(k, 0.0) + 4.0 / 3.0 * math.pi * float(r["radius"]) ** 3
    return [((k + 0.5) * width, v / (width * WIDTH)) for k, v in sorted(volume.items())]


def release_folder(work, name, slope, rolling):
    """The folder of a release: its preparation, slope and rolling resistance."""
    return os.path.join(work, f"run_{name}_{slope:g}deg" + (f"_mr{rolling:g}" if rolling else ""))


def release(binary, work, radius, name, path, slope, end, threads, rolling=0.0):
    out = release_folder(work, name, slope, rolling)
    theta = math.radians(slope)
    sets = grain_sets(radius) + [
        f'particles.block[1].path="{os.path.abspath(path)}"', f"time.end={end}",
        f"domain.gravity=[{9.81 * math.sin(theta)},0.0,{-9.81 * math.cos(theta)}]"]
    if threads:
        sets.append(f"parallel.threads={threads}")
    if rolling:
        sets.append(f"contact.rolling_friction={rolling}")
    summary, refusal = finished_summary(out), None
    if summary is None:
        summary, refusal = run_case(binary, os.path.join(CASES, "narrow_channel_3d.toml"), out, sets,
                                    resume=True)
    row = {"preparation": name, "slope": slope, "diameter": 2 * radius, "rolling_friction": rolling}
    if summary is None:
        row.update(status="refused", stop_reason=refusal)
        return row, [], []
    for key in ("status", "stop_reason", "steps", "wall_seconds", "simulated_time"):
        row[key] = summary.get(key)
    row.update({k: v for k, v in summary["metrics"].items() if k in FIELDS})
    with open(os.path.join(out, "front.csv")) as f:
        fronts = list(csv.DictReader(f))
    row["front_max_speed_x"] = front_x_at(fronts, summary["metrics"].get("front_max_speed_time"))
    row["deceleration_end_x"] = front_x_at(fronts, summary["metrics"].get("deceleration_end_time"))
    row["runout_x"] = fronts[-1]["front"]
    profile = final_profile(out, radius)
    upslope = [h for x, h in profile if x < UPSLOPE]
    row["upslope_thickness"] = sum(upslope) / len(upslope) if upslope else None
    series = [{"preparation": name, "slope": slope, "rolling_friction": rolling, "time": r["time_after_release"],
               "front": r["front"],
               "front_speed": r["front_speed"], "bed_kinetic_to_potential": r["bed_kinetic_to_potential"]}
              for r in fronts]
    profiles = [{"preparation": name, "slope": slope, "rolling_friction": rolling, "x": x, "h": h}
                for x, h in profile]
    return row, series, profiles


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--work", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--diameter", type=float, default=2e-3, help="mean grain diameter (m)")
    parser.add_argument("--preparations", nargs="+", choices=sorted(RUNS), default=["cc", "cl", "ll"])
    parser.add_argument("--slope", type=float, default=22.0)
    parser.add_argument("--end", type=float, default=6.0, help="simulated time after the release (s)")
    parser.add_argument("--rolling-friction", type=float, default=0.0,
                        help="rolling resistance mu_r of the releases (the paper's spheres have none)")
    parser.add_argument("--threads", type=int, help="threads of each run (one with --jobs 2)")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    radius = 0.5 * args.diameter
    threads = 1 if args.jobs > 1 else args.threads
    needed = sorted({p for name in args.preparations for p in RUNS[name]})
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        fills = dict(zip(needed, pool.map(lambda p: rain(args.binary, args.work, radius, p, threads), needed)))
    # Both rains must stand on the same glued bed for their halves to be
    # put together.
    beds = [glued(fills[p]) for p in needed]
    if any(bed != beds[0] for bed in beds):
        sys.exit("the rains' glued beds differ: their deposits cannot be put together")
    deposits = {name: deposit(args.work, fills[RUNS[name][0]], fills[RUNS[name][1]], name)
                for name in args.preparations}

    def run(name):
        return release(args.binary, args.work, radius, name, deposits[name], args.slope, args.end, threads,
                       args.rolling_friction)

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run, args.preparations))
    first = release_folder(args.work, args.preparations[0], args.slope, args.rolling_friction)
    if glued(first) != beds[0]:
        sys.exit("the release's glued bed differs from the rain's")
    rows = [r for r, _, _ in results]
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    for suffix, k in (("_fronts.csv", 1), ("_profiles.csv", 2)):
        table = [r for result in results for r in result[k]]
        if table:
            with open(args.out.replace(".csv", suffix), "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(table[0].keys()), lineterminator="\n")
                w.writeheader()
                w.writerows(table)
    for r in rows:
        print(", ".join(f"{k}={r.get(k)}" for k in FIELDS if r.get(k) is not None), flush=True)


if __name__ == "__main__":
    main()
