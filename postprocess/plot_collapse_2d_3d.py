#!/usr/bin/env python3
"""Chart of scripts/collapse_2d_3d.py (Martin et al. 2022, Fig. 7): for
each slope, the front r_f/R0 against time (top: each 2D model's ensemble
as its mean and range, the 3D runs as lines) and the mass profiles h(x)
at 0.4 and 1 s over the column's at the release (bottom: the ensembles'
means), 2D dashed and 3D solid as in the paper. A run at rest before 1 s
(some of COCD's at 0 degrees) has no profile at 1 s.

    postprocess/plot_collapse_2d_3d.py docs/validation/collapse_2d_3d.csv \
        docs/validation/collapse_2d_3d.png
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {(2, "cocd"): ("tab:blue", "--", "2D COCD"), (2, "soft"): ("tab:red", "--", "2D soft"),
         (3, "soft"): ("black", "-", "3D soft"), (3, "cocd"): ("tab:blue", "-", "3D COCD")}
COLUMN_LENGTH = 0.2


def grouped(path, value):
    """{(dimension, model, slope): {member: ([x], [y])}} from a table of
    the script, x and y the columns named by `value`."""
    table = defaultdict(lambda: defaultdict(lambda: ([], [])))
    with open(path) as f:
        for r in csv.DictReader(f):
            key = (int(r["dimension"]), r["model"], float(r["slope"]))
            x, y = value(r)
            xs, ys = table[key][(r["member"], x[0])]
            xs.append(x[1])
            ys.append(y)
    return table


def main():
    table, out = sys.argv[1], sys.argv[2]
    fronts = grouped(table.replace(".csv", "_fronts.csv"),
                     lambda r: ((None, float(r["time"])), float(r["front_over_length"])))
    # h over the column's mean h at the release: a 2D column of discs
    # holds more solid per unit height than a 3D one of spheres (packing
    # fractions about 0.82 and 0.6), so the two are compared in shape.
    column = defaultdict(list)
    with open(table.replace(".csv", "_profiles.csv")) as f:
        for r in csv.DictReader(f):
            if float(r["x"]) < COLUMN_LENGTH:
                column[(int(r["dimension"]), r["model"], float(r["slope"]), r["member"],
                        r["time_after_release"])].append(float(r["height_at_release"]))
    initial = {key[:4]: sum(v) / len(v) for key, v in column.items()}
    profiles = grouped(table.replace(".csv", "_profiles.csv"),
                       lambda r: ((float(r["time_after_release"]), float(r["x"])),
                                  float(r["height"]) / initial[(int(r["dimension"]), r["model"],
                                                                float(r["slope"]), r["member"])]))
    slopes = sorted({key[2] for key in fronts})
    fig, axes = plt.subplots(2, len(slopes), figsize=(6 * len(slopes), 8), squeeze=False)
    for column, slope in enumerate(slopes):
        top, bottom = axes[0][column], axes[1][column]
        for (dimension, model), (colour, line, label) in STYLE.items():
            runs = list(fronts.get((dimension, model, slope), {}).values())
            if not runs:
                continue
            length = min(len(t) for t, _ in runs)
            t = runs[0][0][:length]
            ys = [y[:length] for _, y in runs]
            mean = [sum(v) / len(v) for v in zip(*ys)]
            top.plot(t, mean, color=colour, linestyle=line, label=f"{label} ({len(runs)} run{'s' if len(runs) > 1 else ''})")
            if len(runs) > 1:
                top.fill_between(t, [min(v) for v in zip(*ys)], [max(v) for v in zip(*ys)],
                                 color=colour, alpha=0.15)
            by_time = defaultdict(list)
            for (member, time), (x, h) in profiles.get((dimension, model, slope), {}).items():
                by_time[time].append((x, h))
            for time, members in sorted(by_time.items()):
                n = min(len(x) for x, _ in members)
                x = members[0][0][:n]
                h = [sum(v) / len(v) for v in zip(*(m[1][:n] for m in members))]
                bottom.plot([v / COLUMN_LENGTH for v in x], h, color=colour, linestyle=line,
                            alpha=1.0 if time > 0.5 else 0.5, label=f"{label}, t = {time:g} s")
        top.set_title(f"slope {slope:g}°")
        top.set_xlabel("t after the release (s)")
        top.set_ylabel("front r_f / R0")
        top.legend(fontsize=8)
        bottom.set_xlabel("x / R0")
        bottom.set_xlim(0, 8 if slope > 0 else 3)
        bottom.set_ylabel("h / h0 (h0: the column at the release)")
        bottom.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
