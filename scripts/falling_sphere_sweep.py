#!/usr/bin/env python3
"""Falling sphere (Izard et al. 2014, section 3.1) over resolutions, box
widths and time steps: runs `cases/falling_sphere.toml` through --set and
writes one CSV row per run with the acceptance figures (initial
acceleration against eq. 20, terminal Reynolds number against
Schiller-Naumann) and the cost (wall seconds, seconds per step).

    scripts/falling_sphere_sweep.py --out docs/validation/falling_sphere.csv \
        --run 8:8:24:1 --run 12:8:24:1 ...

Each --run is D/dx : box width / D : box height / D : dt factor, where the
dt factor multiplies the paper's dt (g/D)^1/2 = 0.04 scaled to D/dx = 20,
so that the CFL number stays the same across resolutions. An optional fifth
field sets coupling.forcing_step to that factor times the same scaled step
(the forcing relaxes the transition layer as at that step, whatever dt),
or "renewal" sets coupling.layer_forcing = "renewal" (the layer relaxed at
the rate the flow renews it); a sixth, time.cfl.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

D = 0.01
G = 9.81
PAPER_DT = 0.04 * (D / G) ** 0.5  # at D/dx = 20


def run(binary, cells_per_d, width, height, dt_factor, end, workdir, forcing_factor=None,
        cfl=None):
    n_lateral = round(width * cells_per_d)
    n_vertical = round(height * cells_per_d)
    dt = PAPER_DT * 20.0 / cells_per_d * dt_factor
    name = f"fs_{cells_per_d}_{width}_{height}_{dt_factor}_{forcing_factor}_{cfl}"
    out = os.path.join(workdir, name)
    sets = [
        f"fluid.cells=[{n_lateral},{n_lateral},{n_vertical}]",
        f"domain.upper=[{width * D},{width * D},{height * D}]",
        f"particles.block[0].positions=[[{width * D / 2},{width * D / 2},{(height - 2.5) * D}]]",
        f"time.dt={dt}",
        f"time.end={end}",
        "output.interval=0.05",
        f"output.tracked_interval={dt}",
    ]
    forcing_step = None
    if forcing_factor == "renewal":
        forcing_step = "renewal"
        sets.append('coupling.layer_forcing="renewal"')
    elif forcing_factor is not None:
        forcing_step = PAPER_DT * 20.0 / cells_per_d * forcing_factor
        sets.append(f"coupling.forcing_step={forcing_step}")
    if cfl is not None:
        sets.append(f"time.cfl={cfl}")
    command = [binary, "run", "cases/falling_sphere.toml", "--out", out]
    for s in sets:
        command += ["--set", s]
    finished = subprocess.run(command, stdout=subprocess.DEVNULL)
    row = {
        "cells_per_diameter": cells_per_d,
        "box_width_over_d": width,
        "box_height_over_d": height,
        "dt": dt,
        "dt_sqrt_g_over_d": dt / (D / G) ** 0.5,
        "forcing_step": forcing_step or "",
        "cfl": cfl or "",
    }
    if finished.returncode != 0:
        # A refused or unstable run: its log says why.
        with open(os.path.join(out, "log.txt")) as f:
            row["status"] = f.read().strip().splitlines()[-2]
        return row
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    m = summary["metrics"]
    return {
        "status": "ok",
        "cells_per_diameter": cells_per_d,
        "box_width_over_d": width,
        "box_height_over_d": height,
        "dt": dt,
        "dt_sqrt_g_over_d": dt / (D / G) ** 0.5,
        "forcing_step": forcing_step or "",
        "cfl": cfl or "",
        "cells": summary["cells"],
        "steps": summary["steps"],
        "initial_acceleration": m.get("initial_acceleration", ""),
        "initial_acceleration_error": m.get("initial_acceleration_error", ""),
        "terminal_velocity": m["terminal_velocity"],
        "terminal_reynolds": m["terminal_reynolds"],
        "schiller_naumann_reynolds": m["schiller_naumann_reynolds"],
        "terminal_reynolds_error": m["terminal_reynolds_error"],
        "terminal_drift": m["terminal_drift"],
        "wall_seconds": summary["wall_seconds"],
        "seconds_per_step": summary["seconds_per_step"],
        "seconds_flow": summary["seconds_flow"],
        "seconds_forcing": summary["seconds_forcing"],
        "seconds_loads": summary["seconds_loads"],
        "seconds_dem": summary["seconds_dem"],
        "threads": summary["threads"],
        "tracked": os.path.join(out, "tracked.csv"),
    }


FIELDS = [
    "status", "cells_per_diameter", "box_width_over_d", "box_height_over_d", "dt",
    "dt_sqrt_g_over_d", "forcing_step", "cfl", "cells", "steps", "initial_acceleration", "initial_acceleration_error",
    "terminal_velocity", "terminal_reynolds", "schiller_naumann_reynolds",
    "terminal_reynolds_error", "terminal_drift", "wall_seconds", "seconds_per_step",
    "seconds_flow", "seconds_forcing", "seconds_loads", "seconds_dem", "threads", "run",
]


def label(cells_per_d, width, dt_factor, forcing_factor, cfl):
    """The run's name in the CSV and in the tracks file: steps in (D/g)^1/2."""
    scale = PAPER_DT * 20.0 / cells_per_d / (D / G) ** 0.5
    step = f"dt<={dt_factor * scale:.4g}" if cfl is not None else f"dt={dt_factor * scale:.4g}"
    name = f"D/dx={cells_per_d} box={width} {step}"
    if cfl is not None:
        name += f" cfl={cfl:g}"
    if forcing_factor == "renewal":
        name += " renewal"
    elif forcing_factor is not None:
        name += f" forcing={forcing_factor * scale:.4g}"
    return name


def append_track(tracks, name, tracked):
    """Appends the tracked sphere's (t, z, vz) to the tracks file."""
    exists = os.path.exists(tracks)
    with open(tracks, "a", newline="") as out:
        writer = csv.writer(out)
        if not exists:
            writer.writerow(["run", "t", "z", "vz"])
        for line in csv.DictReader(open(tracked)):
            writer.writerow([name, line["t"], line["z"], line["vz"]])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--run", action="append", required=True)
    parser.add_argument("--end", type=float, default=0.5)
    parser.add_argument("--binary", default="target/release/grainflow")
    parser.add_argument("--workdir", default="/tmp/grainflow_falling_sphere")
    parser.add_argument("--tracks", help="append each run's (t, z, vz) to this CSV")
    args = parser.parse_args()
    rows = []
    exists = os.path.exists(args.out)
    with open(args.out, "a", newline="") as f:
        writer = None
        for spec in args.run:
            fields = spec.split(":")
            cells, width, height, factor = fields[:4]
            forcing = None
            if len(fields) > 4 and fields[4]:
                forcing = fields[4] if fields[4] == "renewal" else float(fields[4])
            cfl = float(fields[5]) if len(fields) > 5 and fields[5] else None
            row = run(args.binary, int(cells), float(width), float(height), float(factor),
                      args.end, args.workdir, forcing, cfl)
            row["run"] = label(int(cells), float(width), float(factor), forcing, cfl)
            tracked = row.pop("tracked", None)
            if args.tracks and tracked:
                append_track(args.tracks, row["run"], tracked)
            rows.append(row)
            if writer is None:
                # Rows appended to an earlier table keep its columns.
                fields = next(csv.reader(open(args.out))) if exists else FIELDS
                writer = csv.DictWriter(f, fieldnames=fields, restval="",
                                        extrasaction="ignore")
                if not exists:
                    writer.writeheader()
            writer.writerow(row)
            f.flush()
            print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
