#!/usr/bin/env python3
"""The narrow channel's release, frame by frame, as the rows of
docs/validation.md §11 ("The narrow channel with COCD"): the time, the
leading grain of the column (group 1), the farthest grain moving faster
than 1 cm/s, how many layer grains (group 2) move faster than 1 cm/s, and
the grains' translational kinetic energy (mJ, from series.csv at the
frame's time). x from the back wall, as the paper's.

    postprocess/narrow_channel_rows.py RUN_FOLDER [--every 0.1]
"""
import argparse
import csv
import os

import numpy as np

from read_output import particle_frames

MOVING = 0.01  # m/s: the paper's static/flowing criterion


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run")
    parser.add_argument("--every", type=float, default=0.1, help="seconds between rows")
    args = parser.parse_args()
    with open(os.path.join(args.run, "series.csv")) as f:
        series = [(float(r["t"]), float(r["kinetic_translational"])) for r in csv.DictReader(f)]
    print("| t (s) | leading column grain (m) | farthest moving grain (m) "
          "| layer grains moving (> 1 cm/s) | E_k of the grains (mJ) |")
    print("| --- | --- | --- | --- | --- |")
    next_row = 0.0
    for frame in particle_frames(args.run):
        if frame.time < next_row - 1e-9:
            continue
        next_row = frame.time + args.every
        a = frame.arrays
        x = np.asarray(a["position"])[:, 0]
        speed = np.linalg.norm(np.asarray(a["velocity"]), axis=1)
        group = np.asarray(a["group"]).ravel()
        moving = speed > MOVING
        column = group == 1
        layer = group == 2
        leading = x[column].max() if column.any() else float("nan")
        farthest = x[moving].max() if moving.any() else float("nan")
        energy = min(series, key=lambda row: abs(row[0] - frame.time))[1]
        print(f"| {frame.time:.3g} | {leading:.3f} | {farthest:.3f} | "
              f"{int((moving & layer).sum()):,} | {1e3 * energy:.3g} |")


if __name__ == "__main__":
    main()
