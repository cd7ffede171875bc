#!/usr/bin/env python3
"""The runout at the end of the releases against the layer's thickness, on
each slope: the erodible layer (the paper's), the same layer glued where
it lies (`--bed glued` of scripts/erodible_bed_study.py: its roughness
without its erodibility) and the lattice's rigid bed (h_i = 0). Means of
the ensemble's members, bars their range.

    postprocess/plot_erodible_glued.py chart.png study.csv [study.csv ...]

Rows of the study's CSVs without a `bed` column are the erodible runs.
Prints the table of means beside the chart.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "erodible": dict(marker="o", label="erodible layer"),
    "glued": dict(marker="s", label="the same layer glued"),
    "lattice": dict(marker="^", label="rigid bed (one glued row)"),
}


def read(paths):
    """{(slope, bed, thickness): [runouts]} of the runs that ended."""
    runs = defaultdict(list)
    for path in paths:
        with open(path) as f:
            for r in csv.DictReader(f):
                if r.get("status") not in ("ok", "at_rest", "at rest") or not r.get("runout"):
                    continue
                h = float(r["thickness_diameters"])
                bed = "lattice" if h == 0 else r.get("bed") or "erodible"
                runs[(float(r["slope"]), bed, h)].append(float(r["runout"]))
    return runs


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    runs = read(sys.argv[2:])
    slopes = sorted({k[0] for k in runs})
    fig, axes = plt.subplots(1, len(slopes), figsize=(4 * len(slopes), 3.6), sharey=True, squeeze=False)
    print("| slope | bed | h_i (d) | runs | runout (R0): mean (range) |")
    print("| --- | --- | --- | --- | --- |")
    for ax, slope in zip(axes[0], slopes):
        for bed, style in STYLE.items():
            points = sorted((h, v) for (s, b, h), v in runs.items() if s == slope and b == bed)
            if not points:
                continue
            hs = [h for h, _ in points]
            means = [sum(v) / len(v) for _, v in points]
            low = [m - min(v) for m, (_, v) in zip(means, points)]
            high = [max(v) - m for m, (_, v) in zip(means, points)]
            ax.errorbar(hs, means, yerr=[low, high], capsize=3, linestyle="-" if len(hs) > 1 else "none",
                        **style)
            for h, (_, v), m in zip(hs, points, means):
                print(f"| {slope:g}° | {bed} | {h:g} | {len(v)} | {m:.3f} ({min(v):.3f}–{max(v):.3f}) |")
        ax.set_title(f"{slope:g}°")
        ax.set_xlabel("layer thickness h_i / d")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("runout (r_f − R0)/R0 at the end")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[1], dpi=120)


if __name__ == "__main__":
    main()
