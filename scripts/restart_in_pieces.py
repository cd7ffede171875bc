#!/usr/bin/env python3
"""A case run in pieces, each stopped by SIGTERM and resumed with
`--restart latest`, against the same case run in one go: the final states
(the end checkpoints, less the wall-clock records) and the series must be
the same bytes.

usage: scripts/restart_in_pieces.py CASE [--pieces 3] [--set key=value ...]
         [--binary target/release/grainflow] [--threads N] [--out DIR]
The stops fall at even shares of the uninterrupted run's wall time.
"""
import argparse, glob, os, signal, subprocess, sys, time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "postprocess"))
from read_checkpoint import read_state  # noqa: E402

CLOCKS = {"writers", "coupled.timings", "hard_contact.record"}
SERIES = ["series.csv", "flow_series.csv", "tracked.csv", "bed_series.csv",
          "bed_profiles.csv", "grain_profiles.csv", "final_particles.csv"]


def command(args, out, restart):
    c = [args.binary, "run", args.case, "--out", out, "--set", "checkpoint.keep=2"]
    for s in args.set:
        c += ["--set", s]
    if args.threads:
        c += ["--threads", str(args.threads)]
    if restart:
        c += ["--restart", "latest"]
    return c


def final_state(out):
    last = sorted(glob.glob(os.path.join(out, "checkpoints", "checkpoint_*")))[-1]
    state = read_state(os.path.join(last, "rank_0000.state"))
    return os.path.basename(last), {k: v for k, v in state.items() if k not in CLOCKS}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("case")
    ap.add_argument("--pieces", type=int, default=3)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--binary", default="target/release/grainflow")
    ap.add_argument("--threads", type=int)
    ap.add_argument("--out", default="out/restart_in_pieces")
    ap.add_argument("--whole-seconds", type=float,
                    help="reuse OUT/whole from an earlier call, which took this long")
    args = ap.parse_args()
    whole, pieces = os.path.join(args.out, "whole"), os.path.join(args.out, "pieces")
    if args.whole_seconds:
        seconds = args.whole_seconds
    else:
        started = time.perf_counter()
        subprocess.run(command(args, whole, False), check=True, stdout=subprocess.DEVNULL)
        seconds = time.perf_counter() - started
    print(f"whole run: {seconds:.1f} s", flush=True)
    stops = 0
    while True:
        child = subprocess.Popen(command(args, pieces, stops > 0), stdout=subprocess.DEVNULL)
        if stops < args.pieces - 1:
            try:
                child.wait(timeout=seconds / args.pieces)
            except subprocess.TimeoutExpired:
                child.send_signal(signal.SIGTERM)
        status = child.wait()
        print(f"piece {stops + 1}: exit {status}", flush=True)
        if status == 75:
            stops += 1
            continue
        if status != 0:
            sys.exit(f"piece {stops + 1} failed with {status}")
        break
    same = True
    for name in SERIES:
        a, b = os.path.join(whole, name), os.path.join(pieces, name)
        if os.path.exists(a):
            equal = open(a, "rb").read() == open(b, "rb").read()
            same &= equal
            print(f"{name}: {'same bytes' if equal else 'DIFFERS'}")
    (na, a), (nb, b) = final_state(whole), final_state(pieces)
    equal = na == nb and a.keys() == b.keys() and all(a[k].tobytes() == b[k].tobytes() for k in a)
    same &= equal
    print(f"final state ({na}, {len(a)} sections): {'same bytes' if equal else 'DIFFERS'}")
    print(f"stopped {stops} times by SIGTERM")
    sys.exit(0 if same and stops == args.pieces - 1 else 1)


if __name__ == "__main__":
    main()
