#!/usr/bin/env python3
"""The line transforms of the direct solvers against FFTW on the same lines:
runs `cargo bench -p grainflow-fluid --bench transforms` (rustfft/rustdct
through grainflow's AxisTransform) and scripts/bench/fftw_lines.c (FFTW
guru plans, FFTW_MEASURE; needs Debian's libfftw3-dev), both on one thread,
and prints ns per value per transform for each and their ratio.

usage: scripts/bench/transforms.py [--json FILE]
"""
import argparse, json, os, re, subprocess, tempfile


def parse(text):
    rows = {}
    for m in re.finditer(r"(\w+) n=(\d+) kind=(\w+) axis=(\d) ns_per_value=([\d.]+)", text):
        rows[(int(m.group(2)), m.group(3), int(m.group(4)))] = float(m.group(5))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "../.."))
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    ours = parse(subprocess.run(["cargo", "bench", "-q", "-p", "grainflow-fluid", "--bench", "transforms"],
                                cwd=root, env=env, check=True, capture_output=True, text=True).stdout)
    with tempfile.TemporaryDirectory() as work:
        binary = os.path.join(work, "fftw_lines")
        subprocess.run(["cc", "-O2", os.path.join(root, "scripts/bench/fftw_lines.c"), "-o", binary,
                        "-lfftw3", "-lm"], check=True)
        fftw = parse(subprocess.run([binary], check=True, capture_output=True, text=True).stdout)
    report = []
    print(f"{'n':>4} {'kind':>9} {'axis':>4} {'grainflow':>10} {'FFTW':>8} {'grainflow/FFTW':>15}")
    for key in sorted(ours):
        n, kind, axis = key
        report.append({"n": n, "kind": kind, "axis": axis, "grainflow_ns": ours[key], "fftw_ns": fftw[key]})
        print(f"{n:4d} {kind:>9} {'xy'[axis]:>4} {ours[key]:10.3f} {fftw[key]:8.3f} {ours[key] / fftw[key]:15.2f}")
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
