#!/usr/bin/env python3
"""The coupled step's split before and after a change, from
scripts/bench/immersed_split.py's JSON: per scene and thread count, the
median seconds per step of the flow, the immersed boundaries and the DEM,
stacked, the two builds side by side, with the ratio of the immersed
boundaries to the flow (medians of the per-run ratios) above each bar.

usage: postprocess/plot_immersed_split.py FILE.json OUT.png
"""
import json, statistics, sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    source, target = sys.argv[1], sys.argv[2]
    with open(source) as f:
        runs = json.load(f)["runs"]
    groups = []
    for run in runs:
        key = (run["scene"], run["threads"])
        if key not in groups:
            groups.append(key)
    parts = [("flow", "tab:blue"), ("immersed", "tab:orange"), ("dem", "tab:green")]
    labels = {"flow": "flow", "immersed": "immersed boundaries", "dem": "DEM"}
    fig, ax = plt.subplots(figsize=(8, 4.2))
    width = 0.38
    for g, (scene, threads) in enumerate(groups):
        for b, build in enumerate(("before", "after")):
            mine = [r for r in runs if (r["scene"], r["threads"], r["build"]) == (scene, threads, build)]
            x = g + (b - 0.5) * width
            bottom = 0.0
            for part, colour in parts:
                value = statistics.median(r[part] for r in mine)
                ax.bar(x, value, width * 0.95, bottom=bottom, color=colour,
                       alpha=0.45 if build == "before" else 1.0,
                       label=labels[part] if g == 0 and b == 1 else None)
                bottom += value
            ratio = statistics.median(r["immersed_over_flow"] for r in mine)
            ax.text(x, bottom, f"{ratio:.2f}", ha="center", va="bottom", fontsize=8)
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([f"{scene}\n{threads} thread{'s' if threads > 1 else ''}" for scene, threads in groups])
    ax.set_ylabel("seconds per step (median)")
    ax.set_title("Coupled step before (pale) and after (solid); immersed boundaries / flow above each bar")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=120)


if __name__ == "__main__":
    main()
