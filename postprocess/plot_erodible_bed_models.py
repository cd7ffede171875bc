#!/usr/bin/env python3
"""Chart of scripts/erodible_bed_models.py: the front r_f/R0 against time
for each contact model and time step (left), and each run's front error
against the reference run over its wall time per simulated second
(right): the user's choice of model for the scene.

    postprocess/plot_erodible_bed_models.py docs/validation/erodible_bed_models.csv \
        docs/validation/erodible_bed_models.png
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {"cocd": "tab:blue", "nscd": "tab:green", "soft": "tab:red"}


def main():
    table, out = sys.argv[1], sys.argv[2]
    with open(table) as f:
        rows = list(csv.DictReader(f))
    series = defaultdict(lambda: ([], []))
    with open(table.replace(".csv", "_fronts.csv")) as f:
        for r in csv.DictReader(f):
            t, y = series[r["label"]]
            t.append(float(r["time_after_release"]))
            y.append(float(r["front_over_length"]))
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    markers = "os^vD<>p*h"
    for k, row in enumerate(rows):
        label, model = row["label"], row["model"]
        colour = COLOURS.get(model, "black")
        t, y = series[label]
        left.plot(t, y, color=colour, marker=markers[k % len(markers)], markevery=max(1, len(t) // 8),
                  markersize=4, label=label)
        error, cost = row.get("front_error"), row.get("wall_seconds_per_simulated_second")
        if error and cost and float(error) > 0.0:
            right.loglog(float(cost), float(error), marker=markers[k % len(markers)], color=colour,
                         linestyle="none", label=label)
            right.annotate(label, (float(cost), float(error)), textcoords="offset points",
                           xytext=(4, 4), fontsize=7)
    left.set_xlabel("t after the release (s)")
    left.set_ylabel("front r_f / R0")
    left.legend(fontsize=7)
    right.set_xlabel("wall seconds per simulated second (one core)")
    right.set_ylabel("front error against the reference")
    right.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
