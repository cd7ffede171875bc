#!/usr/bin/env python3
"""Which contact model for the erodible-bed scene: runs one prepared
deposit (the column and its layer) on one slope with several contact
models and time steps, and measures each against the finest run of the
list (the reference, by default the first): the relative L2 error of the
front's travel r_f(t) − R0 over the run, the runout's error at the end,
and the wall time per simulated second.

    scripts/erodible_bed_models.py --deposit cases/data/erodible_bed_2d_5d.csv \\
        --thickness 5 --slope 22 --end 2 --out docs/validation/erodible_bed_models.csv \\
        --variant "cocd 0.25 ms:cocd:2.5e-4" \\
        --variant "cocd 1 ms:cocd:1e-3" \\
        --variant "nscd 1 ms:nscd:1e-3:contact.tolerance=1e-4" \\
        --variant "soft tc 0.1 ms:soft:2e-6:contact.restitution=0.2;contact.contact_time=1e-4"

A variant is `label:model:dt[:key=value;key=value...]` (extra `--set`s for
that run). Writes one row per variant to --out and every run's front
series beside it (`_fronts.csv`); postprocess/plot_erodible_bed_models.py
draws the chart. Each run is single-threaded, so that two variants can
run side by side on two cores (--jobs 2) with comparable wall times.
"""
import argparse
import concurrent.futures
import math
import os

from erodible_bed_study import FIELDS, release, write_tables

HERE = os.path.dirname(os.path.abspath(__file__))


def parse_variant(text):
    parts = text.split(":", 3)
    if len(parts) < 3:
        raise SystemExit(f"--variant {text!r}: expected label:model:dt[:key=value;...]")
    label, model, dt = parts[0], parts[1], float(parts[2])
    sets = [s for s in parts[3].split(";") if s] if len(parts) == 4 else []
    return label, model, dt, sets


def travel(fronts):
    """(times, r_f − R0) of one run's front series."""
    t = [float(r["time_after_release"]) for r in fronts]
    length = [float(r["front_over_length"]) - 1.0 for r in fronts]
    return t, length


def interpolate(t, y, at):
    """y(at) by linear interpolation, held at the ends."""
    if at <= t[0]:
        return y[0]
    if at >= t[-1]:
        return y[-1]
    lo, hi = 0, len(t) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t[mid] <= at:
            lo = mid
        else:
            hi = mid
    w = (at - t[lo]) / (t[hi] - t[lo])
    return (1.0 - w) * y[lo] + w * y[hi]


def errors(fronts, reference):
    """Relative L2 error of the front's travel over the reference's
    samples, and the relative error of the travel at the end."""
    t_ref, y_ref = travel(reference)
    t, y = travel(fronts)
    diff = sum((interpolate(t, y, s) - r) ** 2 for s, r in zip(t_ref, y_ref))
    norm = sum(r * r for r in y_ref)
    if norm == 0.0:
        raise SystemExit("the reference run's front did not move: run longer (--end)")
    end = interpolate(t, y, t_ref[-1])
    return math.sqrt(diff / norm), abs(end - y_ref[-1]) / y_ref[-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--deposit", required=True, help="final_particles.csv of a fill (with groups)")
    parser.add_argument("--work", required=True, help="folder for the runs")
    parser.add_argument("--out", required=True, help="CSV of one row per variant")
    parser.add_argument("--diameter", type=float, default=0.008, help="mean diameter d (m)")
    parser.add_argument("--length", type=float, default=2.5, help="channel length (m)")
    parser.add_argument("--thickness", type=float, required=True, help="the deposit's h_i in mean diameters")
    parser.add_argument("--slope", type=float, default=22.0, help="degrees")
    parser.add_argument("--end", type=float, default=2.0, help="simulated time after the release (s)")
    parser.add_argument("--variant", action="append", required=True, help="label:model:dt[:key=value;...]")
    parser.add_argument("--reference", help="label of the reference run (default: the first variant)")
    parser.add_argument("--jobs", type=int, default=1, help="runs side by side")
    parser.add_argument("--set", action="append", default=[], help="extra --set for every run")
    args = parser.parse_args()
    variants = [parse_variant(v) for v in args.variant]
    reference = args.reference or variants[0][0]
    if reference not in [v[0] for v in variants]:
        raise SystemExit(f"--reference {reference!r} is not one of the variants' labels")
    radius = 0.5 * args.diameter
    thickness = args.thickness * args.diameter

    def run(variant):
        label, model, dt, sets = variant
        work = os.path.join(args.work, label.replace(" ", "_"))
        sets = args.set + sets + ["parallel.threads=1"]
        row, fronts = release(args.binary, work, args.deposit, radius, args.length, thickness,
                              args.slope, model, dt, args.end, sets)
        print(f"{label}: {row.get('status')}, runout {row.get('runout')}, "
              f"{row.get('wall_seconds')} s", flush=True)
        return label, row, fronts

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run, variants))
    by_label = {label: (row, fronts) for label, row, fronts in results}
    reference_fronts = by_label[reference][1]
    rows, series = [], []
    for label, row, fronts in results:
        row["label"] = label
        if fronts and reference_fronts:
            row["front_error"], row["travel_error_at_end"] = errors(fronts, reference_fronts)
        if row.get("wall_seconds"):
            row["wall_seconds_per_simulated_second"] = float(row["wall_seconds"]) / args.end
        rows.append(row)
        for r in fronts:
            r["label"] = label
        series += fronts
    fields = ["label"] + FIELDS + ["front_error", "travel_error_at_end", "wall_seconds_per_simulated_second"]
    write_tables(args.out, fields, rows, series)

if __name__ == "__main__":
    main()
