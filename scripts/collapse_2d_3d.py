#!/usr/bin/env python3
"""The same granular column in 2D and in a 3D channel (Martin et al. 2022,
section 4.2, Fig. 7): R0 x H0 = 20 x 14 cm released on a rigid bed of
glued grains at each slope, with the same grains (d, rho, mu = 0.3 with
the grains and the walls) in 2D and in 3D between two side walls 20 cm
apart. The paper finds the 2D front about 12 % longer than the 3D one at
t = 1 s on a horizontal plane and 32 % longer at 22 degrees.

    scripts/collapse_2d_3d.py --work /tmp/c23 --out docs/validation/collapse_2d_3d.csv

The 3D column, `cases/data/channel_collapse_3d.csv`, was rained by
`cases/channel_collapse_fill_3d.toml` (the soft DEM, mu = 0; --rain does
it again) and is released by `cases/channel_collapse_3d.toml`; the 2D
column is the deposit of the erodible-bed study without a layer
(`cases/data/erodible_bed_2d_no_layer.csv`, rained by COCD at mu = 0),
released by `cases/erodible_bed_2d.toml`. Each 2D release runs with COCD
(the paper's model) and with the soft DEM of the 3D runs (the same
contact law as in 3D); the 3D releases with the soft DEM (a COCD step on
12,000 spheres takes minutes). --scene coarse runs the same with d = 16 mm
(`cases/data/column_2d_coarse.csv`, `channel_collapse_3d_coarse.csv`),
where --models-3d soft cocd also runs COCD in 3D (about 2 s a step on
1,491 spheres). --scene paper is the paper's grain, d = 4 mm: the 2D
column of the erodible-bed study at that size
(`cases/data/column_2d_paper.csv`, 1,777 discs) and a 3D column of about
95,000 spheres, rained into --work by the fill case at that size (hours
on two cores; not kept in the repository). Writes one row per run with
the front at 0.4 and 1 s, and the mass profiles beside it
(`_profiles.csv`).

The same command run again resumes: the deposit and the runs that
finished are kept, and a 3D rain or release that was stopped (a session
or a job limit) goes on from its newest checkpoint. --jobs 2 runs two
releases side by side, one thread each; --threads N gives each run N.
"""
import argparse
import concurrent.futures
import csv
import math
import os
import shutil
import sys

import shrink_deposit
from grainflow_run import finished_summary, run_case

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.join(HERE, "..", "cases")
FRICTION = 0.3
PERTURBATION = 1e-7
# The two grain sizes: the deposits, the 3D channel's length and the soft
# contact time (the 3D runs' law, used by the 2D soft runs too; t_c grows
# with d, which keeps the overlaps the same fraction of a grain).
SCENES = {
    "fine": {"radius": 4e-3, "deposit_2d": "erodible_bed_2d_no_layer.csv",
             "deposit_3d": "channel_collapse_3d.csv", "length_3d": 2.5, "contact_time": 1e-4},
    "coarse": {"radius": 8e-3, "deposit_2d": "column_2d_coarse.csv",
               "deposit_3d": "channel_collapse_3d_coarse.csv", "length_3d": 1.5, "contact_time": 2e-4},
    "paper": {"radius": 2e-3, "deposit_2d": "column_2d_paper.csv",
              "deposit_3d": None, "length_3d": 2.0, "contact_time": 5e-5},
}
# The fine scene's 3D column; a scene of radius r rains (4 mm / r)^3 times
# as many grains, for the same column.
FINE_COLUMN_GRAINS = 11930
# Where the 3D rain's glued bed ends (m): under the column only.
RAIN_BED = 0.21
FIELDS = [
    "dimension", "model", "slope", "member", "dt", "status", "column_grains", "initial_length",
    "initial_height", "aspect_ratio", "front_0.4", "front_1.0", "runout", "front_max_speed",
    "steps", "wall_seconds", "stop_reason",
]


def fill_sets(scene):
    """The --set of the 3D rain at the scene's grain size (none for the
    fine scene): the same column in grains (r/4 mm)^-3 times as many,
    the contact time scaled with d, and the glued bed under the column
    only (the release lays the whole channel's; the lattices coincide)."""
    if scene["radius"] == SCENES["fine"]["radius"]:
        return []
    r = scene["radius"]
    count = round(FINE_COLUMN_GRAINS * (SCENES["fine"]["radius"] / r) ** 3)
    return bed_sets_3d(r, 0.25, RAIN_BED) + [f"particles.block[1].count={count}",
                                         f"contact.contact_time={scene['contact_time']}"]


def bed_sets_3d(r, length, bed_length):
    """The --set of grains of radius r in a 3D channel `length` long on a
    glued lattice 2.2 r apart, its first sphere at 1.1 r from the back
    wall, reaching `bed_length` (the rain's and the release's lattices
    coincide)."""
    spacing = 2.2 * r
    return [f"particles.radius={r}", f"particles.block[0].spacing={spacing}",
            f"domain.upper=[{length},0.2,0.6]", f"particles.block[0].lower=[{1.1 * r},0.0,0.0]",
            f"particles.block[0].upper=[{bed_length},0.2,{spacing}]"]


def fill_3d(binary, work, scene, threads):
    """Rains the 3D column (`channel_collapse_fill_3d.toml`) and writes its
    deposit as `cases/data/channel_collapse_3d.csv` holds it: centres and
    radii to seven digits (10 nm, a thousandth of the soft contacts'
    overlaps), the group, no velocity (the grains start at rest)."""
    deposit = os.path.join(work, "deposit_3d.csv")
    if os.path.exists(deposit):
        return deposit
    out = os.path.join(work, "fill_3d")
    sets = fill_sets(scene) + ([f"parallel.threads={threads}"] if threads else [])
    summary, refusal = run_case(binary, os.path.join(CASES, "channel_collapse_fill_3d.toml"), out, sets,
                                resume=True)
    if summary is None:
        sys.exit(f"3D fill refused: {refusal}")
    with open(os.path.join(out, "final_particles.csv")) as f, open(deposit, "w") as d:
        d.write("x,y,z,radius,group\n")
        for r in csv.DictReader(f):
            d.write(",".join(f"{float(r[k]):.7g}" for k in ("x", "y", "z", "radius")) + f",{r['group']}\n")
    return deposit


def vtp_arrays(path, names):
    """The named point arrays (and "position") of a particle file grainflow
    wrote (raw appended data, UInt64 headers), as lists of tuples."""
    import re
    import struct
    with open(path, "rb") as f:
        data = f.read()
    head, raw = data.split(b'<AppendedData encoding="raw">', 1)
    raw = raw[raw.index(b"_") + 1:]
    kinds = {"Float64": "d", "UInt64": "Q", "UInt8": "B", "Int64": "q"}
    out = {}
    for m in re.finditer(rb'<DataArray type="(\w+)" Name="(\w+)" NumberOfComponents="(\d+)" '
                         rb'format="appended" offset="(\d+)"', head):
        kind, name, components, offset = (m.group(1).decode(), m.group(2).decode(),
                                          int(m.group(3)), int(m.group(4)))
        if name not in names:
            continue
        size = struct.unpack_from("<Q", raw, offset)[0]
        code = kinds[kind]
        count = size // struct.calcsize(code)
        values = struct.unpack_from(f"<{count}{code}", raw, offset + 8)
        out[name] = [tuple(values[i:i + components]) for i in range(0, count, components)]
    return out


def glued_of_rain(work):
    """The glued grains under the rained 3D column, as the rain drew their
    radii (its first particle file), as `x,y,z,radius,group` in WORK. The
    release's lattice over the rest of the channel draws other radii for
    the same sites: a rained grain sitting on a small glued one would
    overlap the larger one drawn there."""
    glued = os.path.join(work, "glued_3d.csv")
    if not os.path.exists(glued):
        first = os.path.join(work, "fill_3d", "particles", "particles_000000.vtp")
        arrays = vtp_arrays(first, {"position", "radius", "fixed"})
        with open(glued, "w") as f:
            f.write("x,y,z,radius,group\n")
            for (x, y, z), (r,), (fixed,) in zip(arrays["position"], arrays["radius"], arrays["fixed"]):
                if fixed:
                    f.write(f"{x:.9g},{y:.9g},{z:.9g},{r:.9g},0\n")
    return glued


def rained_release_case(work, scene, glued):
    """The 3D release case of a scene rained into WORK: the rain's glued
    grains kept as they were drawn (a fixed `file` block), the glued lattice
    continued beyond them to the channel's end."""
    case = os.path.join(work, "channel_collapse_3d_rained.toml")
    with open(os.path.join(CASES, "channel_collapse_3d.toml")) as f:
        text = f.read()
    marker = "[contact]"
    block = f'[[particles.block]]\nkind = "file"\npath = "{os.path.abspath(glued)}"\nfixed = true\n\n'
    with open(case, "w") as f:
        f.write(text.replace(marker, block + marker, 1))
    return case


def gravity(dimension, slope, member):
    """Gravity tilted by `slope` degrees; member k of an ensemble adds
    k x 1e-7 m/s^2 along the slope (a single run of a collapse is one
    draw of its chaos)."""
    theta = math.radians(slope)
    along, normal = 9.81 * math.sin(theta) + PERTURBATION * member, -9.81 * math.cos(theta)
    return f"[{along},{normal}]" if dimension == 2 else f"[{along},0.0,{normal}]"


def front_at(rows, time):
    """r_f/R0 at the sample nearest `time` (None before it)."""
    best = None
    for r in rows:
        t = float(r["time_after_release"])
        if t <= time + 1e-9:
            best = r
    return None if best is None else float(best["front_over_length"])


def scene_sets(scene, dimension):
    """The --set of the coarse and paper scenes' grain size, lattice and
    channel (none for the fine scene, the cases' own). A scene rained into
    the work folder (the paper's) continues the glued lattice beyond the
    rain's, whose grains its case keeps (`rained_release_case`)."""
    if scene["radius"] == SCENES["fine"]["radius"]:
        return []
    r, length = scene["radius"], scene["length_3d"]
    if dimension == 2:
        spacing = 2.2 * r
        return [f"particles.radius={r}", f"particles.block[0].spacing={spacing}",
                f"particles.block[0].upper=[2.5,{spacing}]"]
    sets = bed_sets_3d(r, length, length) + [f"walls[2].point=[{length},0.0,0.0]"]
    if scene["deposit_3d"] is None:
        # The rain's lattice: sites at 1.1 r + (i + 1/2) 2.2 r below RAIN_BED.
        spacing = 2.2 * r
        sites = math.floor((RAIN_BED - 1.1 * r) / spacing + 1e-9)
        lower = f"particles.block[0].lower=[{1.1 * r + sites * spacing},0.0,0.0]"
        sets = [lower if s.startswith("particles.block[0].lower=") else s for s in sets]
    return sets


def hard_contact_3d(work, deposit):
    """The 3D case and deposit for hard contact: the case without its soft
    keys, the deposit's radii shrunk by 0.5 % (soft contacts at rest
    overlap, and COCD cannot part a grain wedged into a pocket: docs/
    validation.md, section 8)."""
    case = os.path.join(work, "channel_collapse_3d_hard.toml")
    with open(os.path.join(CASES, "channel_collapse_3d.toml")) as f:
        lines = [line for line in f if not line.startswith(("restitution", "contact_time"))]
    with open(case, "w") as f:
        f.writelines("dt = 1.0e-3\n" if line.startswith("dt_over_contact_time") else line for line in lines)
    shrunk = os.path.join(work, "deposit_3d_shrunk.csv")
    with open(shrunk, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(shrink_deposit.shrunk(deposit, 0.995))
    return case, shrunk


def release(binary, work, scene, dimension, model, slope, member, deposit, end, cocd_dt, threads):
    soft_dt = scene["contact_time"] / 20.0
    dt = soft_dt if model == "soft" else cocd_dt[dimension]
    out = os.path.join(work, f"run_{dimension}d_{model}_{slope:g}deg_{member}")
    if dimension == 2:
        case = os.path.join(CASES, "erodible_bed_2d.toml")
    elif model == "soft" and scene["deposit_3d"] is None:
        case = rained_release_case(work, scene, glued_of_rain(work))
    elif model == "soft":
        case = os.path.join(CASES, "channel_collapse_3d.toml")
    else:
        case, deposit = hard_contact_3d(work, deposit)
    sets = [f"domain.gravity={gravity(dimension, slope, member)}", f"time.end={end}",
            f'particles.block[1].path="{os.path.abspath(deposit)}"',
            f"contact.friction={FRICTION}", f'contact.model="{model}"'] + scene_sets(scene, dimension)
    if dimension == 2:
        sets += [f"time.dt={dt}", "analysis.profile_times=[0.4,1.0]", "analysis.smoothing=0.05"]
    elif model != "soft":
        sets.append(f"time.dt={dt}")
    if model == "soft":
        sets += ["contact.restitution=0.5", f"contact.contact_time={scene['contact_time']}"]
        if dimension == 3:
            sets.append("time.dt_over_contact_time=0.05")
    if threads:
        sets.append(f"parallel.threads={threads}")
    summary, refusal = finished_summary(out), None
    if summary is None:
        summary, refusal = run_case(binary, case, out, sets, resume=dimension == 3)
    row = {"dimension": dimension, "model": model, "slope": slope, "member": member, "dt": dt}
    if summary is None:
        row.update(status="refused", stop_reason=refusal)
        return row, [], []
    for key in ("status", "stop_reason", "steps", "wall_seconds"):
        row[key] = summary.get(key)
    for key in FIELDS:
        if key in summary["metrics"]:
            row[key] = summary["metrics"][key]
    with open(os.path.join(out, "front.csv")) as f:
        fronts = list(csv.DictReader(f))
    row["front_0.4"] = front_at(fronts, 0.4)
    row["front_1.0"] = front_at(fronts, 1.0)
    tags = {"dimension": dimension, "model": model, "slope": slope, "member": member}
    with open(os.path.join(out, "profiles.csv")) as f:
        profiles = [dict(r, **tags) for r in csv.DictReader(f)]
    series = [dict(tags, time=r["time_after_release"], front_over_length=r["front_over_length"])
              for r in fronts]
    return row, profiles, series


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--work", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--slope", type=float, nargs="+", default=[0, 22])
    parser.add_argument("--end", type=float, default=1.0, help="simulated time after the release (s)")
    parser.add_argument("--dimension", type=int, nargs="+", default=[2, 3])
    parser.add_argument("--members", type=int, nargs=2, default=[8, 1], metavar=("2D", "3D"),
                        help="runs per slope and model, gravity perturbed (2D and 3D)")
    parser.add_argument("--scene", choices=sorted(SCENES), default="fine",
                        help="fine: d = 8 mm (11,930 spheres); coarse: d = 16 mm (1,491); "
                             "paper: d = 4 mm (about 95,000, rained into --work)")
    parser.add_argument("--threads", type=int, help="threads of each run (one with --jobs 2)")
    parser.add_argument("--models-3d", nargs="+", default=["soft"], help="soft and/or cocd")
    parser.add_argument("--cocd-dt", type=float, nargs=2, default=[5e-4, 1e-3], metavar=("2D", "3D"))
    parser.add_argument("--rain", action="store_true",
                        help="rain the 3D column anew instead of cases/data/channel_collapse_3d.csv")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    scene = SCENES[args.scene]
    if args.rain and args.scene == "coarse":
        sys.exit("--rain makes the fine and paper scenes' deposits only")
    threads = 1 if args.jobs > 1 else args.threads
    rain = args.rain or scene["deposit_3d"] is None
    deposits = {2: os.path.join(CASES, "data", scene["deposit_2d"])}
    if 3 in args.dimension:
        deposits[3] = (fill_3d(args.binary, args.work, scene, threads) if rain else
                       os.path.join(CASES, "data", scene["deposit_3d"]))
    cocd_dt = {2: args.cocd_dt[0], 3: args.cocd_dt[1]}
    members_2d, members_3d = args.members
    jobs = [(3, m, s, k) for k in range(members_3d) for s in args.slope for m in args.models_3d
            if 3 in args.dimension]
    jobs += [(2, m, s, k) for s in args.slope for m in ("cocd", "soft") for k in range(members_2d)
             if 2 in args.dimension]

    def run(job):
        dimension, model, slope, member = job
        row, profiles, series = release(args.binary, args.work, scene, dimension, model, slope, member,
                                        deposits[dimension], args.end, cocd_dt, threads)
        print(", ".join(f"{k}={row.get(k)}" for k in ("dimension", "model", "slope", "member", "front_0.4",
                                                     "front_1.0", "wall_seconds")), flush=True)
        return row, profiles, series

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run, jobs))
    rows = [row for row, _, _ in results]
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    for suffix, k in (("_profiles.csv", 1), ("_fronts.csv", 2)):
        table = [r for result in results for r in result[k]]
        if table:
            with open(args.out.replace(".csv", suffix), "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
                w.writeheader()
                w.writerows(table)
    def mean_front(dimension, model, slope):
        fronts = [r["front_1.0"] for r in rows
                  if (r["dimension"], r["model"], r["slope"]) == (dimension, model, slope) and r.get("front_1.0")]
        return sum(fronts) / len(fronts) if fronts else None

    for slope in args.slope:
        for model_3d in args.models_3d:
            three = mean_front(3, model_3d, slope)
            for model in ("soft", "cocd"):
                two = mean_front(2, model, slope)
                if two and three:
                    print(f"{slope:g} deg: 2D {model} front at 1 s / 3D {model_3d} = {two / three:.3f}")


if __name__ == "__main__":
    main()
