#!/usr/bin/env python3
"""Writes cases/silo.toml (the paper's silo, poured batch after batch just
above the deposit) and cases/silo_small.toml (a reduced silo for the tests,
filled from a loose jittered lattice that settles under gravity), both a
square shaft lined with glued grains centred on the side walls; with
arguments, the variants of the studies of docs/validation.md, section 4.
Run from the repository root."""

HEADER_FULL = """# The silo of Izard et al. 2014, section 3.3: about 56,000 grains
# (rho = 1317 kg/m3, R = 5 mm +- 10 %, mu = 0.25, e_n = 0.3, t_c = 1e-4 s) in a
# 0.1 x 0.1 m shaft lined with glued grains, a column about 5 m high. The
# grains start on a loose jittered lattice and settle; at rest the
# coarse-grained pressure is fitted with Janssen's law (eq. 22), to compare
# with the paper's f_w K = 0.30 +- 0.06. A validation run (docs/validation.md),
# not part of the tests. Written by scripts/make_silo_cases.py.
"""

HEADER_POURED = """# The silo of Izard et al. 2014, section 3.3 (rho = 1317 kg/m3, R = 5 mm +- 10 %,
# mu = 0.25, e_n = 0.3, t_c = 1e-4 s) in a 0.1 x 0.1 m shaft lined with glued
# grains: 35,868 grains poured in batches of five lattice layers, each released
# 5 mm above the deposit once the previous one has landed, a column of 3.9 m.
# At rest the coarse-grained pressure is fitted with Janssen's law (eq. 22), to
# compare with the paper's f_w K = 0.30 +- 0.06. A validation run of about an
# hour on 2 threads (docs/validation.md, section 4), not part of the tests.
# Written by scripts/make_silo_cases.py.
"""

HEADER_SMALL = """# A reduced silo for the tests (the full one is cases/silo.toml): the grains
# of Izard et al. 2014, section 3.3 (rho = 1317 kg/m3, R = 5 mm +- 10 %,
# mu = 0.25, e_n = 0.3, t_c = 1e-4 s) in the same 0.1 x 0.1 m shaft lined
# with glued grains (a narrower shaft jams), a column of about 0.8 m instead
# of 5 m. The grains start on a loose lattice
# and settle; at rest the coarse-grained pressure along the shaft is fitted
# with Janssen's law (eq. 22). Metrics: janssen_fwK, saturation_pressure,
# solid_fraction. Written by scripts/make_silo_cases.py.
"""


def silo(width, fill_top, end, seed, exclude_bottom, slab, liner=0.011, layer=None, liner_top=None,
         pour=None, dt_ratio=0.05):
    """pour = (count, batch_layers, interval, gap, settled_speed): the grains are
    poured batch after batch just above the deposit instead of starting on a
    lattice; fill_top is then the domain's height less 5 cm."""
    top = fill_top + 0.05
    liner_top = liner_top or top
    r = 0.5 * liner  # half the liner spacing: liner grains are centred on the walls
    liners = [
        ([-r, 0.0, 0.0], [r, width, liner_top]),
        ([width - r, 0.0, 0.0], [width + r, width, liner_top]),
        ([r, -r, 0.0], [width - r, r, liner_top]),
        ([r, width - r, 0.0], [width - r, width + r, liner_top]),
    ]
    text = f"""
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{width}, {width}, {top}]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 1317.0
radius = 5.0e-3
radius_spread = 0.1
seed = {seed}
"""
    text += "\n# Glued grains centred on the four side walls (the rough walls of the paper).\n"
    for lo, hi in liners:
        text += f"""[[particles.block]]
kind = "lattice"
lower = {lo}
upper = {hi}
spacing = {liner}
fixed = true

"""
    if pour is not None:
        count, batch_layers, interval, gap, settled = pour
        text += f"""# The grains: poured in batches of {batch_layers} lattice layers, each released
# {gap} m above the highest moving grain once the previous one has landed, so
# that grains land from a small height however high the deposit has grown.
[[particles.pour]]
lower = [{r}, {r}, 0.0]
upper = [{width - r}, {width - r}, {round(batch_layers * 0.0112 + 1e-6, 7)}]
spacing = 0.0112
jitter = 0.5
count = {count}
interval = {interval}
gap = {gap}
"""
        if settled > 0:  # 0: no wait, a batch every interval
            text += f"settled_speed = {settled}\n"
    elif layer is None:
        text += "# The grains: a loose jittered lattice that settles under gravity.\n"
    else:
        text += ("# The grains: sparse layers that rain down one after the other onto the\n"
                 "# growing deposit, like a poured fill.\n")
    if pour is None:
        text += f"""[[particles.block]]
kind = "lattice"
lower = [{r}, {r}, 0.0]
upper = [{width - r}, {width - r}, {fill_top}]
spacing = 0.0112
"""
        if layer is not None:
            text += f"layer_spacing = {layer}\n"
        text += "jitter = 0.5\n"
    text += """
[contact]
model = "soft"
restitution = 0.3
contact_time = 1.0e-4
friction = 0.25
"""
    for name, point, normal in [
        ("floor", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ("x_low", [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        ("x_high", [width, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ("y_low", [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ("y_high", [0.0, width, 0.0], [0.0, -1.0, 0.0]),
    ]:
        text += f"""
[[walls]]
name = "{name}"
point = {point}
normal = {normal}
"""
    text += f"""
[time]
end = {end}
dt_over_contact_time = {dt_ratio}
rest_speed = 1.0e-3

[output]
interval = 0.05

[analysis]
kind = "silo"
slab = {slab}
exclude_bottom = {exclude_bottom}
"""
    return text


import sys

def poured_full():
    # The full silo's 35,868 grains poured in batches of 5 layers.
    return HEADER_POURED + silo(0.1, 4.25, 40.0, 5, 0.7, 0.05,
                                pour=(35868, 5, 0.03, 0.005, 0.1), dt_ratio=0.1)


if len(sys.argv) == 3 and sys.argv[1] == "lattice-full":  # make_silo_cases.py lattice-full OUT
    # The full silo filled from a loose lattice (the first validation run).
    open(sys.argv[2], "w").write(HEADER_FULL + silo(0.1, 8.2, 6.0, 5, 0.7, 0.05))
    sys.exit(0)
if len(sys.argv) >= 3 and sys.argv[1] == "pour-small":
    # make_silo_cases.py pour-small OUT [LAYERS INTERVAL GAP SETTLED SEED]: the reduced
    # silo's 6,125 grains poured in batches (docs/validation.md, section 4).
    layers, interval, gap, settled, seed = (sys.argv[3:] + [None] * 5)[:5]
    pour = (6125, int(layers or 5), float(interval or 0.03), float(gap or 0.005),
            float(settled or 0.05))
    open(sys.argv[2], "w").write(HEADER_SMALL + silo(0.1, 0.95, 8.0, int(seed or 3), 0.2, 0.02,
                                                     pour=pour, dt_ratio=0.1))
    sys.exit(0)
if len(sys.argv) == 3 and sys.argv[1] == "poured":  # make_silo_cases.py poured OUT
    # The full silo's grains in 732 layers 16.8 mm apart (docs/validation.md, section 4).
    open(sys.argv[2], "w").write(HEADER_FULL + silo(0.1, 12.3, 4.0, 5, 0.7, 0.05, layer=0.0168, liner_top=6.0))
    sys.exit(0)
if len(sys.argv) > 2:  # variants for studies: make_silo_cases.py OUT LINER_SPACING
    open(sys.argv[1], "w").write(HEADER_SMALL + silo(0.1, 1.4, 2.0, 3, 0.2, 0.02, float(sys.argv[2])))
    sys.exit(0)
open("cases/silo.toml", "w").write(poured_full())
open("cases/silo_small.toml", "w").write(HEADER_SMALL + silo(0.1, 1.4, 2.0, 3, 0.2, 0.02))
