#!/usr/bin/env python3
"""A deposit (a run's `final_particles.csv`) for hard contact: every radius
times FACTOR and every velocity set to zero, so that grains the soft DEM
left overlapping stand apart. Writes the CSV to standard output.

    scripts/shrink_deposit.py fill/final_particles.csv 0.995 > cases/data/x.csv
"""
import csv
import sys


def shrunk(path, factor):
    """The rows of the deposit at `path` (header first), radii times
    `factor` in (0, 1], velocities zero."""
    if not 0.0 < factor <= 1.0:
        raise ValueError(f"the factor must lie in (0, 1], not {factor}")
    with open(path) as f:
        rows = list(csv.reader(f))
    header = rows[0]
    radius = header.index("radius")
    velocities = [header.index(k) for k in ("vx", "vy", "vz") if k in header]
    for row in rows[1:]:
        row[radius] = repr(float(row[radius]) * factor)
        for k in velocities:
            row[k] = "0.0"
    return rows


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    try:
        rows = shrunk(sys.argv[1], float(sys.argv[2]))
    except ValueError as e:
        sys.exit(str(e))
    csv.writer(sys.stdout, lineterminator="\n").writerows(rows)


if __name__ == "__main__":
    main()
