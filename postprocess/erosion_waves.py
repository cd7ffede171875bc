#!/usr/bin/env python3
"""The erosion waves behind the front of a release on an erodible layer
(Martin et al. 2022, §5.1.3, Fig. 15–16), measured from a run's particle
frames and its front (`analysis.kind = "erodible_bed"`).

Near the head of the flow the top of the erodible bed undulates. The
paper compares it with a Kelvin–Helmholtz instability between two
"fluids", the flowing layer (solid fraction Φ1, speed u1) over the bed
(Φ2, u2): a wave of length λ grows when

    u1 − u2 > sqrt( g λ / (2π) · (Φ2/Φ1 − Φ1/Φ2) )          (eq. 17)

It reports λ ≈ 8 cm, Φ1/Φ2 ≈ 0.8, a threshold of about 24 cm/s, a flow
above 40 cm/s over a bed below 15 cm/s, and waves for 0.9 s < t < 2.2 s
(d = 1.8 mm at 22°).

For each frame, in a window of --window metres behind the front r_f
(front.csv):

- the bed's top z_b(x): every mean diameter d along x, the 90th
  percentile of the tops of the grains that started in the layer (group
  2) within 3 d, so that a few grains carried up into the flow do not set
  it;
- u1, u2: the mean x velocity of the grains above and below z_b;
- Φ1, Φ2: the grains' area (2D) over the area between the rigid bed and
  z_b, and between z_b and the surface (the top of the highest grain);
- λ: the wavelength of the largest peak of the power spectrum of z_b
  less its linear trend (zero-padded, wavelengths from 10 d to half the
  window), its amplitude the rms of the detrended z_b, and the peak's
  power over the spectrum's mean (a wave train stands out; noise does
  not);
- the threshold of eq. 17 and whether u1 − u2 exceeds it.

usage: erosion_waves.py RUN --out CSV [--chart PNG] [--window 0.4]
       [--start 0.5] [--end 2.4] [--times 1.0,1.34,1.8]
"""
import argparse
import csv
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from read_output import particle_frames  # noqa: E402

BED_GROUP = 2
TOP_PERCENTILE = 90.0
# The bed's top at each diameter along x is taken over a window of this
# many diameters (a single grain's top is its own roughness), and waves
# shorter than SHORTEST_DIAMETERS are not sought: the paper's are about
# 40 diameters long.
SMOOTHING_DIAMETERS = 3.0
SHORTEST_DIAMETERS = 10.0


def read_front(run):
    """(times after the release, front positions x) of front.csv."""
    with open(os.path.join(run, "front.csv")) as f:
        rows = list(csv.DictReader(f))
    return (np.array([float(r["time_after_release"]) for r in rows]),
            np.array([float(r["front"]) for r in rows]))


def bed_top(x, top, centres, half_width):
    """At each of `centres`, the TOP_PERCENTILE of `top` over the grains
    within `half_width` along x (NaN where fewer than three)."""
    order = np.argsort(x)
    x, top = x[order], top[order]
    lo = np.searchsorted(x, centres - half_width)
    hi = np.searchsorted(x, centres + half_width)
    return np.array([np.percentile(top[a:b], TOP_PERCENTILE) if b - a >= 3 else np.nan
                     for a, b in zip(lo, hi)])


def dominant_wave(z, spacing, shortest, longest):
    """(wavelength, rms amplitude, peak power over mean power) of the
    detrended profile z sampled every `spacing`."""
    good = np.isfinite(z)
    if good.sum() < 8:
        return math.nan, math.nan, math.nan
    s = np.arange(len(z))[good] * spacing
    z = z[good]
    z = z - np.polyval(np.polyfit(s, z, 1), s)
    # Resample on the regular grid (bins without grains filled linearly).
    grid = np.arange(s[0], s[-1] + 0.5 * spacing, spacing)
    z = np.interp(grid, s, z)
    n = 8 * len(z)
    power = np.abs(np.fft.rfft(z * np.hanning(len(z)), n)) ** 2
    wavelength = np.full(len(power), np.inf)
    wavelength[1:] = n * spacing / np.arange(1, len(power))
    band = (wavelength >= shortest) & (wavelength <= longest)
    if not band.any():
        return math.nan, math.nan, math.nan
    peak = np.argmax(np.where(band, power, -1.0))
    return wavelength[peak], float(np.sqrt(np.mean(z * z))), power[peak] / power[band].mean()


def measure(frame, front, window, gravity):
    """One frame's row and its bed-top profile (x − r_f, z_b)."""
    a = frame.arrays
    position, radius = a["position"], a["radius"]
    velocity, fixed, group = a["velocity"], a["fixed"].astype(bool), a["group"]
    x, y = position[:, 0], position[:, 1]
    rigid_top = float(np.max(y[fixed] + radius[fixed])) if fixed.any() else 0.0
    d = 2.0 * float(np.mean(radius[~fixed]))
    edges = np.arange(front - window, front + 0.5 * d, d)
    centres = 0.5 * (edges[1:] + edges[:-1])
    mobile = ~fixed
    bed = mobile & (group == BED_GROUP)
    z_b = bed_top(x[bed], y[bed] + radius[bed], centres, SMOOTHING_DIAMETERS / 2 * d)
    lam, amplitude, contrast = dominant_wave(z_b, d, SHORTEST_DIAMETERS * d, 0.5 * window)
    # Grains in the window above and below the bed's top of their bin.
    inside = mobile & (x >= edges[0]) & (x < edges[-1])
    index = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
    top_here = z_b[index]
    known = np.isfinite(top_here)
    above = inside & known & (y > top_here)
    below = inside & known & (y <= top_here)
    area = math.pi * radius ** 2
    surface = np.full(len(edges) - 1, np.nan)
    for b in range(len(edges) - 1):
        here = inside & (index == b)
        if here.any():
            surface[b] = np.max(y[here] + radius[here])
    bins = np.isfinite(z_b) & np.isfinite(surface)
    bed_area = np.sum((z_b[bins] - rigid_top) * d)
    flow_area = np.sum((surface[bins] - z_b[bins]) * d)
    in_bins = bins[index]
    phi2 = area[below & in_bins].sum() / bed_area if bed_area > 0 else math.nan
    phi1 = area[above & in_bins].sum() / flow_area if flow_area > 0 else math.nan
    mass = area  # one density: the area weights the mean
    u1 = np.sum(mass[above] * velocity[above, 0]) / mass[above].sum() if above.any() else math.nan
    u2 = np.sum(mass[below] * velocity[below, 0]) / mass[below].sum() if below.any() else math.nan
    ratio = phi2 / phi1 - phi1 / phi2 if phi1 > 0 and phi2 > 0 else math.nan
    threshold = math.sqrt(gravity * lam / (2.0 * math.pi) * ratio) if ratio > 0 else math.nan
    row = {
        "time_after_release": frame.time,
        "front": front,
        "wavelength": lam,
        "amplitude": amplitude,
        "peak_contrast": contrast,
        "phi_flow": phi1,
        "phi_bed": phi2,
        "u_flow": u1,
        "u_bed": u2,
        "kh_threshold": threshold,
        "unstable": int(u1 - u2 > threshold) if math.isfinite(threshold) else "",
    }
    return row, (centres - front, z_b - rigid_top)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run")
    parser.add_argument("--out", required=True)
    parser.add_argument("--chart")
    parser.add_argument("--window", type=float, default=0.4, help="metres behind the front")
    parser.add_argument("--start", type=float, default=0.5, help="first time after the release (s)")
    parser.add_argument("--end", type=float, default=math.inf)
    parser.add_argument("--gravity", type=float, default=9.81)
    parser.add_argument("--release", type=float, default=0.0, help="simulated time of the release (s)")
    parser.add_argument("--times", default="1.0,1.34,1.8", help="profiles to chart (s after the release)")
    args = parser.parse_args()
    front_t, front_x = read_front(args.run)
    rows, profiles = [], {}
    chart_times = [float(t) for t in args.times.split(",") if t]
    seen = set()
    for frame in particle_frames(args.run):
        after = frame.time - args.release
        if round(after, 9) in seen:
            continue  # the final frame repeats the last scheduled one
        seen.add(round(after, 9))
        if after < args.start - 1e-9 or after > args.end + 1e-9:
            continue
        front = float(np.interp(after, front_t, front_x))
        row, profile = measure(frame, front, args.window, args.gravity)
        row["time_after_release"] = after
        rows.append(row)
        for t in chart_times:
            if abs(after - t) < 0.011:
                profiles[t] = profile
        print(f"t = {after:.2f} s: front {front:.3f} m, λ {row['wavelength']:.3f} m, "
              f"amplitude {row['amplitude']:.2e} m, Φ1/Φ2 {row['phi_flow'] / row['phi_bed']:.3f}, "
              f"u1 − u2 {row['u_flow'] - row['u_bed']:.3f} m/s, threshold {row['kh_threshold']:.3f} m/s",
              flush=True)
    if not rows:
        raise SystemExit(f"{args.run}: no particle frame between {args.start} and {args.end} s")
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    if args.chart:
        chart(rows, profiles, args.chart)


def chart(rows, profiles, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.2))
    for k, (t, (x, z)) in enumerate(sorted(profiles.items())):
        left.plot(100 * x, 1000 * z + 10 * k, label=f"t = {t:.2f} s (+{10 * k} mm)")
    left.set_xlabel("x − r_f (cm)")
    left.set_ylabel("top of the erodible bed above the rigid bed (mm)")
    left.legend(fontsize=8)
    t = [r["time_after_release"] for r in rows]
    right.plot(t, [r["u_flow"] - r["u_bed"] for r in rows], label="u1 − u2")
    right.plot(t, [r["kh_threshold"] for r in rows], label="eq. 17 threshold")
    right.plot(t, [10 * r["wavelength"] for r in rows], ":", label="λ × 10 (m)")
    right.set_xlabel("t after the release (s)")
    right.set_ylabel("m/s")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
