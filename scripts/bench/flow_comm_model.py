#!/usr/bin/env python3
"""Communication of the flow's decomposition per step, modelled up to 1,024
ranks and 2048^3 cells.

An N^3 grid on P ranks in a px x py process grid (x and y split, px = py =
sqrt(P) where it is a square, else px = 2 py): each rank holds n = N^3/P
cells. Per step of three Runge-Kutta stages:

- direct solves: 3 Helmholtz (one per velocity component) and 1 Poisson
  per stage, 12 per step; each changes the arrangement of its unknowns six
  times (physical -> x-pencils -> y-pencils -> physical and back), each an
  all-to-all within a row or a column of the process grid that moves the
  rank's n values but its own share (8 bytes each), in px - 1 or py - 1
  messages;
- halo exchanges: about 12 ghost fills of a field per stage (velocity
  components, pressure, the projection's potential), each sending the
  planes next to the four shared faces (x and y), n^(2/3) cells each for a
  cube-shaped share;
- about 6 all-reductions per step (CFL, energy, divergence, sums).

Compute time per step = n t_cell (measured seconds per cell-step on one
core); communication = messages x alpha + bytes / beta. The efficiency
assumes no overlap of the two (grainflow has none).

usage: scripts/bench/flow_comm_model.py [--cell-ns 239] [--alpha 2e-6]
         [--beta 10e9]
"""
import argparse, math


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cell-ns", type=float, default=239.0, help="ns per cell-step, one core")
    parser.add_argument("--alpha", type=float, default=2e-6, help="latency per message [s]")
    parser.add_argument("--beta", type=float, default=10e9, help="bandwidth [bytes/s]")
    args = parser.parse_args()
    print(f"{'grid':>6s} {'ranks':>6s} {'px x py':>8s} {'cells/rank':>11s} {'MB/step':>9s} "
          f"{'msgs/step':>9s} {'compute s':>10s} {'comm s':>8s} {'efficiency':>10s}")
    for size in [512, 1024, 2048]:
        for ranks in [64, 256, 1024]:
            py = int(math.sqrt(ranks))
            while ranks % py:
                py -= 1
            px = ranks // py
            if size < 2 * px or size < 2 * py:
                continue
            n = size ** 3 / ranks
            transposes = 12 * 6
            own = 0.5 * (1 / px + 1 / py)
            transpose_bytes = transposes * 8 * n * (1 - own)
            transpose_messages = 12 * 3 * ((px - 1) + (py - 1))
            plane = n ** (2 / 3)
            halo_bytes = 3 * 12 * 4 * 8 * plane
            halo_messages = 3 * 12 * 4
            reductions = 6 * math.ceil(math.log2(ranks))
            total_bytes = transpose_bytes + halo_bytes
            messages = transpose_messages + halo_messages + reductions
            comm = messages * args.alpha + total_bytes / args.beta
            compute = n * args.cell_ns * 1e-9
            print(f"{size:5d}^3 {ranks:6d} {px:3d} x {py:<3d} {n:11.3e} {total_bytes / 1e6:9.1f} "
                  f"{messages:9d} {compute:10.3f} {comm:8.3f} {compute / (compute + comm):10.3f}")


if __name__ == "__main__":
    main()
