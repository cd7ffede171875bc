#!/usr/bin/env python3
"""Communication of the DEM decomposition per step, modelled up to 1,024 ranks.

Each rank owns a cubic box of n = N/P grains at number density rho (grains
per d^3; 1.15 for a packing fraction of 0.6). Its ghosts fill the shell of
thickness h (the interaction range, 2 r_max + skin) around the box:
g = rho ((a + 2h)^3 - a^3), a = (n / rho)^(1/3). Per step a rank exchanges:

- the ghost refresh: 6 messages (x, y, z, both ways), 15 doubles per ghost
  (position, velocity, angular velocity, force, torque);
- at a neighbour build (one step in `build_interval`): migration through an
  all-to-all (P messages of counts, a few of data) and the ghost build,
  26 doubles per ghost;
- 5 all-reductions of one number (rebuild flag, finite state, largest
  overlap, two contact counts), each log2(P) latencies deep.

Time per step = n t_pair (measured ns per particle-step on one core) for
the compute; the communication costs latency alpha per message and 1/beta
per byte. The parallel efficiency is compute / (compute + communication);
the model has no overlap of the two, as grainflow has none yet.

usage: scripts/bench/dem_comm_model.py [--ns 29] [--alpha 2e-6]
         [--beta 10e9] [--range 1.1] [--rho 1.15] [--build-interval 20]
"""
import argparse, math


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--ns", type=float, default=29.0, help="ns per particle-step, one core")
    parser.add_argument("--alpha", type=float, default=2e-6, help="latency per message [s]")
    parser.add_argument("--beta", type=float, default=10e9, help="bandwidth [bytes/s]")
    parser.add_argument("--range", type=float, default=1.1, help="interaction range / d")
    parser.add_argument("--rho", type=float, default=1.15, help="grains per d^3")
    parser.add_argument("--build-interval", type=float, default=20.0, help="steps per neighbour build")
    args = parser.parse_args()
    h = args.range
    print(f"{'grains':>9s} {'ranks':>6s} {'grains/rank':>11s} {'ghosts/rank':>11s} "
          f"{'KB/step':>8s} {'msgs/step':>9s} {'compute us':>10s} {'comm us':>8s} {'efficiency':>10s}")
    for total in [1e6, 1e7]:
        for ranks in [2, 8, 64, 256, 1024]:
            n = total / ranks
            a = (n / args.rho) ** (1 / 3)
            ghosts = args.rho * ((a + 2 * h) ** 3 - a ** 3)
            refresh_bytes = ghosts * 15 * 8
            build_bytes = ghosts * 26 * 8 + 0.05 * n * 40 * 8
            bytes_per_step = refresh_bytes + build_bytes / args.build_interval
            reductions = 5 * math.ceil(math.log2(ranks))
            messages = 6 + reductions + (ranks + 6) / args.build_interval
            comm = messages * args.alpha + bytes_per_step / args.beta
            compute = n * args.ns * 1e-9
            print(f"{total:9.0e} {ranks:6d} {n:11.0f} {ghosts:11.0f} {bytes_per_step / 1e3:8.1f} "
                  f"{messages:9.1f} {compute * 1e6:10.1f} {comm * 1e6:8.1f} "
                  f"{compute / (compute + comm):10.3f}")


if __name__ == "__main__":
    main()
