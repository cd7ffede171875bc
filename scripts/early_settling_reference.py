#!/usr/bin/env python3
"""The early velocity of a sphere released from rest in a fluid at rest,
from the Basset-Boussinesq-Oseen equation, to read a run's early samples
against (Izard et al. 2014, section 3.1; eq. 20 is its first term):

    (m_p + C_v rho V) dv/dt = (m_p - rho V) g - 6 pi mu R v (1 + 3 Re/16)
                              - 6 R^2 sqrt(pi rho mu) int_0^t v'(s) / sqrt(t - s) ds

with C_v = 1/2, the Oseen factor on the quasi-steady drag, and the
history (Basset) integral over piecewise-constant accelerations, its
newest interval implicit. At the paper's falling sphere (rho_p/rho = 4,
Ar = 800, D = 1 cm) the Basset term takes 7 % off the velocity after the
first step at the paper's step, Delta t (g/D)^1/2 = 0.04.

    scripts/early_settling_reference.py --density-ratio 4 --archimedes 800 \\
        --diameter 0.01 --dt 1.2771e-3 --samples 5 [--tracked run/tracked.csv]

Prints the velocity at each sample time, the fit a0 t - b t^1.5 of those
samples (the analysis `falling_sphere` makes of a run's) against eq. 20,
and, given a run's tracked.csv, the run's speed at the same times.
"""
import argparse
import csv
import math


def bbo_velocity(density_ratio, archimedes, diameter, end, intervals, g=9.81, rho=1000.0):
    """Velocity after each of `intervals` equal intervals up to `end` (s)."""
    rho_p = density_ratio * rho
    nu = math.sqrt((density_ratio - 1.0) * g * diameter**3 / archimedes)
    mu, radius = rho * nu, 0.5 * diameter
    volume = math.pi * diameter**3 / 6.0
    inertia = (rho_p + 0.5 * rho) * volume
    weight = (rho_p - rho) * volume * g
    basset = 6.0 * radius**2 * math.sqrt(math.pi * rho * mu)
    h = end / intervals
    velocity, accelerations = [0.0], []
    for n in range(intervals):
        t = (n + 0.5) * h
        history = sum(a * 2.0 * (math.sqrt(t - k * h) - math.sqrt(t - (k + 1) * h))
                      for k, a in enumerate(accelerations))
        v = velocity[-1]
        drag = 6.0 * math.pi * mu * radius * v * (1.0 + 3.0 / 16.0 * v * diameter / nu)
        # The newest half interval of the history integral, implicit.
        a = (weight - drag - basset * history) / (inertia + basset * 2.0 * math.sqrt(0.5 * h))
        accelerations.append(a)
        velocity.append(v + a * h)
    return h, velocity, weight / inertia


def early_acceleration(samples):
    """Least squares a0 of v = a0 t - b t^1.5 (grainflow_ibm::settling)."""
    s11 = s12 = s22 = r1 = r2 = 0.0
    for t, v in samples:
        f1, f2 = t, t**1.5
        s11, s12, s22 = s11 + f1 * f1, s12 + f1 * f2, s22 + f2 * f2
        r1, r2 = r1 + f1 * v, r2 + f2 * v
    return (r1 * s22 - r2 * s12) / (s11 * s22 - s12 * s12)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--density-ratio", type=float, default=4.0)
    parser.add_argument("--archimedes", type=float, default=800.0)
    parser.add_argument("--diameter", type=float, default=0.01)
    parser.add_argument("--dt", type=float, required=True, help="the run's step (s)")
    parser.add_argument("--samples", type=int, default=5)
    parser.add_argument("--tracked", help="a run's tracked.csv (particle 0, vz)")
    args = parser.parse_args()
    per_step = 400
    end = args.samples * args.dt
    h, velocity, eq20 = bbo_velocity(args.density_ratio, args.archimedes, args.diameter,
                                     end, per_step * args.samples)
    reference = [(k * args.dt, velocity[k * per_step]) for k in range(1, args.samples + 1)]
    run = {}
    if args.tracked:
        with open(args.tracked) as f:
            for row in csv.DictReader(f):
                run[round(float(row["t"]) / args.dt)] = -float(row["vz"])
    print("t [s]       BBO v [m/s]   run v [m/s]   run / BBO - 1")
    for k, (t, v) in enumerate(reference, start=1):
        measured = run.get(k)
        tail = f"{measured:.6e}   {measured / v - 1:+.4f}" if measured is not None else "-"
        print(f"{t:.6e}  {v:.6e}   {tail}")
    fitted = early_acceleration(reference)
    print(f"eq. 20: a0 = {eq20:.4f} m/s^2; the fit of the BBO samples: {fitted:.4f} "
          f"({fitted / eq20 - 1:+.4f})")
    if len(run) >= args.samples:
        measured = early_acceleration([(k * args.dt, run[k]) for k in range(1, args.samples + 1)])
        print(f"the fit of the run's samples: {measured:.4f} ({measured / eq20 - 1:+.4f})")


if __name__ == "__main__":
    main()
