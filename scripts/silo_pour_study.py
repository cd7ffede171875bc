#!/usr/bin/env python3
"""How the filling shapes the reduced silo's pressure profile: the 6,125
grains of cases/silo_small.toml poured in batches (make_silo_cases.py
pour-small) with batches of several heights, gaps and waits, and several
seeds; writes one row per run with the run's Janssen figures.

usage: scripts/silo_pour_study.py OUT.csv [WORK_DIR]   (from the repository root;
about 2-3 minutes a run on 2 threads)
"""
import csv, json, os, subprocess, sys

# name, batch layers, interval [s], gap [m], settled speed [m/s] (0: no wait), seed
RUNS = [
    ("5 layers, 5 mm, landed", 5, 0.03, 0.005, 0.05, 3),
    ("5 layers, 5 mm, landed", 5, 0.03, 0.005, 0.05, 4),
    ("5 layers, 5 mm, landed", 5, 0.03, 0.005, 0.05, 5),
    ("5 layers, 10 cm, landed", 5, 0.03, 0.1, 0.05, 3),
    ("10 layers, 5 mm, landed", 10, 0.03, 0.005, 0.05, 3),
    ("10 layers, 1 cm, every 0.12 s", 10, 0.12, 0.01, 0, 3),
]

out_csv = sys.argv[1]
work = sys.argv[2] if len(sys.argv) > 2 else "/tmp/silo_pour_study"
os.makedirs(work, exist_ok=True)
binary = os.path.join("target", "release", "grainflow")
rows = []
for k, (name, layers, interval, gap, settled, seed) in enumerate(RUNS):
    case = os.path.join(work, f"run{k}.toml")
    subprocess.run([sys.executable, "scripts/make_silo_cases.py", "pour-small", case,
                    str(layers), str(interval), str(gap), str(settled), str(seed)], check=True)
    out = os.path.join(work, f"run{k}")
    subprocess.run(["rm", "-rf", out], check=True)
    subprocess.run([binary, "run", case, "--out", out], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    summary = json.load(open(os.path.join(out, "summary.json")))
    m = summary["metrics"]
    row = {
        "fill": name, "batch_layers": layers, "interval": interval, "gap": gap,
        "settled_speed": settled, "seed": seed,
        "column_height": round(m["column_height"], 4),
        "solid_fraction": round(m["solid_fraction"], 4),
        "fwK_free_saturation": round(m["janssen_fwK"], 4),
        "saturation_pressure": round(m["saturation_pressure"], 1),
        "fwK_eq22": round(m["janssen_fwK_eq22"], 4),
        "fwK_direct": round(m["janssen_fwK_direct"], 4),
        "simulated_time": round(summary["simulated_time"], 3),
        "wall_seconds": round(summary["wall_seconds"], 1),
    }
    print(row, flush=True)
    rows.append(row)
with open(out_csv, "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
