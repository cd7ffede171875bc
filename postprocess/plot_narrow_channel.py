#!/usr/bin/env python3
"""Chart of scripts/narrow_channel_3d.py (Martin et al. 2022, section 5.2):
for each preparation (column/layer: compact/compact, compact/loose,
loose/loose), the front x_f against time (left), the front speed against
the front's position with the paper's figures marked (middle, cut at
1.6 m/s: where a loose layer flows on its own the front jumps; the largest
speed, about 75 cm/s near x = 16 cm; the end of the deceleration at
x = 26.5 cm; the slow propagation near 15 cm/s), and the final deposit's
thickness h(x) (right). x from the back wall, as the paper's. Tables
given after the chart's path add their runs with a rolling resistance
(`scripts/narrow_channel_3d.py --rolling-friction`), drawn in greens.

    postprocess/plot_narrow_channel.py docs/validation/narrow_channel_3d.csv \
        docs/validation/narrow_channel_3d.png [docs/validation/narrow_channel_3d_rolling.csv]
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {"cc": ("black", "compact / compact"), "cl": ("tab:blue", "compact / loose"),
         "ll": ("tab:red", "loose / loose")}
# Runs with a rolling resistance: a green per mu_r, a line per preparation.
ROLLING_COLOURS = ["yellowgreen", "tab:green", "darkgreen", "darkolivegreen"]
LINES = {"cc": "-", "cl": "--", "ll": ":"}


def run_key(r):
    """A run's preparation, with its rolling resistance where it has one."""
    rolling = float(r.get("rolling_friction") or 0.0)
    return r["preparation"] if rolling == 0.0 else (r["preparation"], rolling)


def columns(path, x, y):
    """{preparation: ([x], [y])} from a table of the script."""
    table = defaultdict(lambda: ([], []))
    with open(path) as f:
        for r in csv.DictReader(f):
            xs, ys = table[run_key(r)]
            xs.append(x(r))
            ys.append(y(r))
    return table


def main():
    table, out, extra = sys.argv[1], sys.argv[2], sys.argv[3:]
    with open(table) as f:
        rows = list(csv.DictReader(f))
    diameter = float(rows[0]["diameter"]) * 1e3
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(14, 4.2))
    position, speed, deposit = {}, {}, {}
    for path in [table] + extra:
        fronts = path.replace(".csv", "_fronts.csv")
        profiles = path.replace(".csv", "_profiles.csv")
        position.update(columns(fronts, lambda r: float(r["time"]), lambda r: 100 * float(r["front"])))
        speed.update(columns(fronts, lambda r: 100 * float(r["front"]), lambda r: 100 * float(r["front_speed"])))
        deposit.update(columns(profiles, lambda r: 100 * float(r["x"]), lambda r: 1000 * float(r["h"])))
    style = {k: (colour, "-", label) for k, (colour, label) in STYLE.items()}
    resistances = sorted({k[1] for k in position if isinstance(k, tuple)})
    for k in sorted(k for k in position if isinstance(k, tuple)):
        colour = ROLLING_COLOURS[resistances.index(k[1]) % len(ROLLING_COLOURS)]
        style[k] = (colour, LINES[k[0]], f"{STYLE[k[0]][1]}, μ_r = {k[1]:g}")
    for name, (colour, line, label) in style.items():
        if name in position:
            a.plot(*position[name], color=colour, ls=line, label=label)
            b.plot(*speed[name], color=colour, ls=line, label=label)
            c.plot(*deposit[name], color=colour, ls=line, label=label)
    b.plot([16], [75], "o", color="grey", label="paper: largest speed")
    b.axvline(26.5, color="grey", ls=":", label="paper: end of deceleration")
    b.axhline(15, color="grey", ls="--", label="paper: slow phase")
    a.set(xlabel="t after the release (s)", ylabel="front x_f (cm)")
    # A loose layer that flows on its own makes the front jump (speeds of
    # metres per second between two samples): the axis shows the flow's.
    b.set(xlabel="front x_f (cm)", ylabel="front speed (cm/s)", ylim=(0, 160))
    b.text(0.98, 0.97, "loose layers: the front jumps\n(the bed flows on its own)", ha="right", va="top",
           transform=b.transAxes, fontsize=7)
    c.set(xlabel="x (cm)", ylabel="final thickness h (mm)", xlim=(0, None))
    for axis in (a, b, c):
        axis.grid(alpha=0.3)
    a.legend(fontsize=7)
    b.legend(fontsize=6)
    fig.suptitle(f"Narrow channel, W = 0.8 cm, 22°, h_i = 5 mm, d = {diameter:g} mm, soft DEM "
                 f"(paper: d = 1 mm, COCD)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
