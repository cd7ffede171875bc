#!/usr/bin/env python3
"""Charts of the 2D erodible-bed study (scripts/erodible_bed_study.py):
for each slope, the front r_f/R0 (Martin et al. 2022, Fig. 9), its speed
v_f (Fig. 11) and the erodible bed's E_k/E_p (Fig. 13) against time, one
curve per layer thickness h_i.

    postprocess/plot_erodible_bed.py docs/validation/erodible_bed_2d_fronts.csv \
        docs/validation/erodible_bed_2d.png
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    fronts, out = sys.argv[1], sys.argv[2]
    runs = defaultdict(lambda: defaultdict(list))
    with open(fronts) as f:
        for row in csv.DictReader(f):
            key = (float(row["slope"]), float(row["thickness_diameters"]), row["model"], float(row["dt"]))
            for name in ("time_after_release", "front_over_length", "front_speed", "bed_kinetic_to_potential"):
                runs[key][name].append(float(row[name]))
    slopes = sorted({k[0] for k in runs})
    fig, axes = plt.subplots(3, len(slopes), figsize=(4 * len(slopes), 9), squeeze=False, sharex=True)
    for column, slope in enumerate(slopes):
        for key in sorted(k for k in runs if k[0] == slope):
            run = runs[key]
            label = f"h_i = {key[1]:g} d" + ("" if key[2] == "cocd" else f" ({key[2]})")
            t = run["time_after_release"]
            axes[0][column].plot(t, run["front_over_length"], label=label)
            axes[1][column].plot(t, run["front_speed"], label=label)
            axes[2][column].plot(t, run["bed_kinetic_to_potential"], label=label)
        axes[0][column].set_title(f"θ = {slope:g}°")
        axes[2][column].set_xlabel("t after the release (s)")
    axes[0][0].set_ylabel("front r_f / R0")
    axes[1][0].set_ylabel("front speed v_f (m/s)")
    axes[2][0].set_ylabel("bed E_k / E_p")
    axes[0][-1].legend(fontsize="small")
    for row in axes:
        for ax in row:
            ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
