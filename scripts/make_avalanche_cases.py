#!/usr/bin/env python3
"""Writes the immersed granular flow on an inclined plane of Izard et al.
2014, section 4.2 (the immersed avalanche):

- cases/avalanche_bed.toml: the dry fill. Thirty glued half-spheres on the
  floor of a 10 D x 3 D box periodic along x and y (a 10 x 3 array, one
  diameter apart), 200 grains dropped at random above them settle under
  vertical gravity; its final_particles.csv is the bed.
- cases/immersed_avalanche.toml: the bed in a viscous liquid, the box
  10 D x 3 D x 10 D on 100 x 30 x 100 cells, no-slip floor, free-slip top,
  gravity tilted by 22 degrees towards x (the paper's set-up).

With --bed FILE (the fill's final_particles.csv) it copies the bed to
cases/data/avalanche_bed.csv. Run from the repository root:

  scripts/make_avalanche_cases.py
  grainflow run cases/avalanche_bed.toml --out out/avalanche_bed
  scripts/make_avalanche_cases.py --bed out/avalanche_bed/final_particles.csv

The paper's numbers: rho_p/rho = 8, Ar = rho (rho_p - rho) g D^3 / mu^2 = 9,
e_n = 0.87, t_c (g/D)^1/2 = 4.5e-3, mu_c = 0.25, eta/R = 4e-4. With
D = 5 mm and rho = 1000 kg/m3: mu = 0.977 Pa s, t_c = 1.016e-4 s.
"""
import argparse, math, os, shutil

D = 5.0e-3
R = 0.5 * D
RHO, RHO_P, G = 1000.0, 8000.0, 9.81
AR = 9.0
MU = math.sqrt(RHO * (RHO_P - RHO) * G * D ** 3 / AR)
T_C = 4.5e-3 * math.sqrt(D / G)
TILT = math.radians(22.0)
LX, LY, LZ = 10 * D, 3 * D, 10 * D


def fixed_block():
    positions = [[(i + 0.5) * D, (j + 0.5) * D, 0.0] for j in range(3) for i in range(10)]
    points = ", ".join(f"[{x:.6g}, {y:.6g}, {z:.6g}]" for x, y, z in positions)
    radii = ", ".join(f"{R:.6g}" for _ in positions)
    return f"""# Thirty glued half-spheres on the floor (centres on it): a rough bed.
[[particles.block]]
kind = "explicit"
positions = [{points}]
radii = [{radii}]
fixed = true
"""


CONTACT = f"""[contact]
model = "soft"
restitution = 0.87
contact_time = {T_C:.6g}
friction = 0.25

[[walls]]
name = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
"""


def bed_fill():
    return f"""# The dry fill of the immersed avalanche (Izard et al. 2014, section 4.2):
# 200 grains (D = 5 mm, quasi-monodisperse) dropped at random over thirty
# glued half-spheres in a 10 D x 3 D box periodic along x and y settle
# under gravity. Its final_particles.csv is the bed of
# cases/immersed_avalanche.toml (cases/data/avalanche_bed.csv). Written by
# scripts/make_avalanche_cases.py.

[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{LX:.6g}, {LY:.6g}, {30 * D:.6g}]
periodic = [true, true, false]
gravity = [0.0, 0.0, -9.81]

[particles]
density = {RHO_P}
radius = {R:.6g}
radius_spread = 0.05
seed = 7

{fixed_block()}
[[particles.block]]
kind = "random"
lower = [0.0, 0.0, {1.2 * D:.6g}]
upper = [{LX:.6g}, {LY:.6g}, {30 * D:.6g}]
count = 200

{CONTACT}
[time]
end = 2.0
dt_over_contact_time = 0.05
rest_speed = 1.0e-3

[output]
interval = 0.05
"""


def avalanche():
    gx, gz = G * math.sin(TILT), -G * math.cos(TILT)
    return f"""# An immersed granular bed on an inclined plane (Izard et al. 2014,
# section 4.2, the immersed avalanche): 200 grains (D = 5 mm) resting on
# thirty glued half-spheres in a viscous liquid, rho_p/rho = 8,
# Ar = rho (rho_p - rho) g D^3 / mu^2 = 9, in a 10 D x 3 D x 10 D box
# periodic along x and y (D/dx = 10), no-slip floor, free-slip top, gravity
# tilted by 22 degrees towards x. Along the periodic x the fluid carries
# gravity as a body force: it starts to flow over the bed, shears its
# surface and sets the grains in motion (erosion, then an avalanche of the
# whole bed near t (g/D)^1/2 = 50 in the paper). Contacts: e_n = 0.87,
# t_c (g/D)^1/2 = 4.5e-3, mu_c = 0.25; lubrication eta/R = 4e-4. The
# analysis writes the fluid's and the grains' streamwise velocity profiles,
# the bed's motion and the Shields number at its surface (bed_series.csv).
# The bed comes from cases/avalanche_bed.toml. Written by
# scripts/make_avalanche_cases.py.

[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [{LX:.6g}, {LY:.6g}, {LZ:.6g}]
periodic = [true, true, false]
gravity = [{gx:.6g}, 0.0, {gz:.6g}]

[fluid]
cells = [100, 30, 100]
density = {RHO}
viscosity = {MU:.6g}   # Pa s: Ar = 9

[fluid.boundary]
z = ["no_slip", "free_slip"]

[particles]
density = {RHO_P}
radius = {R:.6g}

{fixed_block()}
[[particles.block]]
kind = "file"
path = "data/avalanche_bed.csv"

{CONTACT}
[lubrication]
roughness = 4.0e-4

[time]
end = 2.3        # t (g/D)^1/2 = 102, where the paper plots the profiles
dt = 5.0e-4
cfl = 0.5

[output]
interval = 0.05

[analysis]
kind = "inclined_bed"
"""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--bed", help="the fill's final_particles.csv")
    args = parser.parse_args()
    open("cases/avalanche_bed.toml", "w").write(bed_fill())
    open("cases/immersed_avalanche.toml", "w").write(avalanche())
    if args.bed:
        os.makedirs("cases/data", exist_ok=True)
        shutil.copy(args.bed, "cases/data/avalanche_bed.csv")
    print(f"mu = {MU:.4g} Pa s, t_c = {T_C:.4g} s, (D/g)^1/2 = {math.sqrt(D / G):.4g} s")


if __name__ == "__main__":
    main()
