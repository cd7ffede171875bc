#!/usr/bin/env python3
"""Bouncing sphere (Izard et al. 2014, section 4.1) over the Stokes number:
runs `cases/bouncing_sphere.toml` with each viscosity, with and without
lubrication, and writes one CSV row per run (Stokes and Reynolds numbers,
approach and rebound velocities, restitution over e_n, cost).

    scripts/bouncing_sphere_sweep.py --out docs/validation/bouncing_sphere.csv \
        --viscosity 0.6 --viscosity 0.066 ... [--cells-per-diameter 12]

With --axisymmetric the runs are those of
`cases/bouncing_sphere_axisymmetric.toml`: the same sphere on the axis of a
cylinder of radius 3 D in (r, z).

With --release-offsets each viscosity is run from several heights a
fraction of a millimetre apart: the contact then falls at other points of
its fluid step, and the rebound read after the stages spreads with that
phase (by up to 0.1 of e_n at St ~ 5000, docs/validation.md, section 7);
the chart takes the median of the releases.

Without lubrication the film force is switched off by a vanishing range.
The fluid step is at most 0.8 Δx over the largest approach speed the
sphere can reach from its release height, and time.cfl (--cfl, default 1)
shortens it where the flow is faster.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

FIELDS = [
    "status", "viscosity", "lubrication", "cells_per_diameter", "dt", "cfl", "stokes", "reynolds",
    "approach_velocity", "rebound_velocity", "rebound_velocity_step_end", "restitution",
    "restitution_ratio", "wall_seconds", "steps", "roughness", "settings",
    "rebound_velocity_through_film", "restitution_ratio_through_film", "release_offset_mm",
]
D = 6e-3
G = 9.81
RELEASE = 10.0  # diameters above the floor (sphere bottom)


def run(binary, viscosity, lubrication, cells_per_d, cfl, workdir, roughness=None, extra=(),
        offset_mm=0.0, axisymmetric=False):
    width, height = 6.0, 13.0
    case = "cases/bouncing_sphere_axisymmetric.toml" if axisymmetric else "cases/bouncing_sphere.toml"
    # The axis of the (r, z) case is x = y = 0; the 3D box's centre is at 3 D.
    centre = 0.0 if axisymmetric else 0.018
    dx = D / cells_per_d
    # Free fall of the buoyant weight over the release height bounds the speed.
    reduced_g = G * 7.0 / 8.5
    fastest = (2.0 * reduced_g * RELEASE * D) ** 0.5
    dt = min(0.8 * dx / fastest, 6e-4)
    end = 2.0 * (2.0 * RELEASE * D / reduced_g) ** 0.5 + 0.15
    tag = "_".join(a.replace("/", "") for a in extra)
    name = (f"bounce_{'rz_' if axisymmetric else ''}{cells_per_d}_{viscosity}_"
            f"{'lub' if lubrication else 'dry'}_{roughness}{tag}_{offset_mm}mm")
    out = os.path.join(workdir, name)
    sets = [
        f"fluid.viscosity={viscosity}",
        f"fluid.cells=[{round(width * cells_per_d)},{round(width * cells_per_d)},{round(height * cells_per_d)}]",
        f"time.dt={dt}",
        f"time.cfl={cfl}",
        f"time.end={end}",
        f"output.tracked_interval={dt}",
    ]
    if offset_mm:
        # The case's sphere: centre 10 D above the floor plus its radius.
        height = RELEASE * D + 0.5 * D + offset_mm * 1e-3
        sets.append(f"particles.block[0].positions=[[{centre},{centre},{height}]]")
    if not lubrication:
        sets.append("lubrication.range=1e-9")
    if roughness is not None:
        sets.append(f"lubrication.roughness={roughness}")
    sets += list(extra)
    command = [binary, "run", case, "--out", out]
    for s in sets:
        command += ["--set", s]
    finished = subprocess.run(command, stdout=subprocess.DEVNULL)
    row = {"viscosity": viscosity, "lubrication": lubrication,
           "cells_per_diameter": cells_per_d, "dt": dt, "cfl": cfl, "roughness": roughness or "",
           "settings": " ".join(extra), "release_offset_mm": offset_mm}
    if finished.returncode != 0:
        with open(os.path.join(out, "log.txt")) as f:
            row["status"] = f.read().strip().splitlines()[-2]
        return row
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    m = summary["metrics"]
    row.update({"status": "ok", "wall_seconds": summary["wall_seconds"],
                "steps": summary["steps"]})
    for key in ("stokes", "reynolds", "approach_velocity", "rebound_velocity",
                "rebound_velocity_step_end", "restitution", "restitution_ratio",
                "rebound_velocity_through_film", "restitution_ratio_through_film"):
        row[key] = m.get(key, "")
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--viscosity", type=float, action="append", required=True)
    parser.add_argument("--cells-per-diameter", type=int, default=12)
    parser.add_argument("--cfl", type=float, default=1.0,
                        help="time.cfl: the forcing is calibrated near 1 (docs/validation.md, §7)")
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--workdir", default="/tmp/grainflow_bouncing_sphere")
    parser.add_argument("--roughness", type=float,
                        help="lubrication.roughness, eta/R (default: the case's)")
    parser.add_argument("--set", action="append", default=[], dest="extra",
                        help="another assignment for every run, as grainflow run --set")
    parser.add_argument("--lubrication", choices=["on", "off", "both"], default="on",
                        help="run each viscosity with the film force, without it, or both")
    parser.add_argument("--axisymmetric", action="store_true",
                        help="the (r, z) case on the axis of a cylinder of radius 3 D")
    parser.add_argument("--release-offsets", default="0",
                        help="comma-separated heights [mm] added to the release, one run each")
    args = parser.parse_args()
    exists = os.path.exists(args.out)
    fields = FIELDS
    if exists:
        # Rows appended to an earlier table keep its columns.
        fields = next(csv.reader(open(args.out)))
        if args.roughness is not None and "roughness" not in fields:
            sys.exit(f"{args.out} has no roughness column: write --roughness runs to a new file")
    with open(args.out, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, restval="", extrasaction="ignore")
        if not exists:
            writer.writeheader()
        offsets = [float(o) for o in args.release_offsets.split(",")]
        for viscosity in args.viscosity:
            for lubrication in {"on": [True], "off": [False], "both": [True, False]}[args.lubrication]:
                for offset in offsets:
                    row = run(args.binary, viscosity, lubrication, args.cells_per_diameter,
                              args.cfl, args.workdir, args.roughness, args.extra, offset,
                              args.axisymmetric)
                    writer.writerow(row)
                    f.flush()
                    print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
