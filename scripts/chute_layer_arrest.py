#!/usr/bin/env python3
"""Does a layer of grains come to rest on the narrow channel's 22 degree
slope? The question behind the narrow channel of Martin et al. (2022,
section 5.2), whose mass the paper sees at rest at t = 6 s and grainflow
sees run to the channel's end.

    scripts/chute_layer_arrest.py --work /tmp/chute --out docs/validation/chute_layer_arrest.csv

Rains `cases/chute_layer_fill_3d.toml` once (the channel's cross-section,
periodic along the slope), cuts layers 3, 5 and 8 grains thick from it,
pushes each down the slope at 0.4 m/s with `cases/chute_layer_3d.toml`
and reads whether it stops within 3 s or settles to a steady flow: the
soft DEM at three grain frictions and with rolling resistance, COCD at
five steps up to the paper's 3D step (10 ms, and 14.3 ms: the same
fraction of sqrt(d/g) for these grains), and, where `lmp` is on the
PATH, LAMMPS on the same layers with the same contact law (a constant k_n and gamma_n, which grainflow
runs too for the side-by-side rows). One row per run: the layer's
speeds (rms and mean down-slope) averaged over t in [1, 3] s, or when it
came to rest, and the wall time.

The same command run again keeps the runs that finished.
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys

from collapse_2d_3d import vtp_arrays
from grainflow_run import finished_summary, run_case

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.join(HERE, "..", "cases")
# The scene (m, kg/m3): the channel's width, the periodic length, the
# top of the glued grains, the mean grain, the push.
LENGTH, WIDTH, BED_TOP, DIAMETER, DENSITY = 0.0396, 0.008, 0.0021, 0.002, 2500.0
PUSH = 0.4
SLOPE = math.radians(22.0)
# The case's law: restitution 0.5, contact time 0.1 ms, tangential spring
# 0.2 k_n, the step a twentieth of the contact.
RESTITUTION, CONTACT_TIME, STEP = 0.5, 1e-4, 5e-6
# Averages over the steady part of the run (s).
LATE = (1.0, 3.0)
# (model, law, friction, rolling resistance, step or None, thicknesses)
RUNS = (
    [("soft", "case", mu, 0.0, None, (3, 5, 8)) for mu in (0.3, 0.5, 0.9)]
    + [("soft", "case", 0.3, mu_r, None, (3, 8)) for mu_r in (0.05, 0.1, 0.2)]
    # COCD up to the paper's 3D step, 10 ms, and that step scaled to these
    # grains: 10 ms is sqrt(d/g) for its 1 mm grains, 14.3 ms for 2 mm.
    + [("cocd", "rigid", 0.3, 0.0, dt, (3, 5, 8)) for dt in (1e-3, 2e-3, 5e-3, 1e-2, 1.43e-2)]
    + [(model, "matched", mu, 0.0, None, (3, 5, 8)) for model in ("soft", "lammps") for mu in (0.3, 0.5)]
)
FIELDS = ["model", "law", "friction", "rolling_friction", "dt", "thickness", "grains", "solid_thickness",
          "status", "rest_time", "rms_speed", "mean_speed", "wall_seconds"]


def matched_law():
    """k_n [N/m] and gamma_n [N s/m] of the case's law for a pair of mean
    grains (m* = m/2), as grainflow's default calibration sets them: the
    damping rate beta = -ln(e)/t_c and the frequency of a force-clamped
    contact, omega t_c = pi - 2 atan(beta/omega)."""
    beta = -math.log(RESTITUTION) / CONTACT_TIME
    omega = math.pi / CONTACT_TIME
    for _ in range(200):
        omega = (math.pi - 2.0 * math.atan(beta / omega)) / CONTACT_TIME
    reduced_mass = 0.5 * DENSITY * math.pi / 6.0 * DIAMETER ** 3
    return reduced_mass * (omega ** 2 + beta ** 2), 2.0 * reduced_mass * beta


def rain(binary, work):
    out = os.path.join(work, "fill")
    if finished_summary(out) is None:
        summary, refusal = run_case(binary, os.path.join(CASES, "chute_layer_fill_3d.toml"), out,
                                    ["parallel.threads=1"])
        if summary is None:
            sys.exit(f"rain refused: {refusal}")
    return out


def layer(work, fill, thickness, shrink):
    """The rain's grains whose centres lie below BED_TOP + (thickness - 1/2) d,
    pushed down the slope; radii times `shrink` (hard contact cannot start
    from the soft rest's overlaps). Its path, grain count and solid
    thickness (grain volume over the bed's area, in diameters)."""
    path = os.path.join(work, f"layer_{thickness}d{'_hard' if shrink < 1 else ''}.csv")
    with open(os.path.join(fill, "final_particles.csv")) as f:
        rows = [r for r in csv.DictReader(f) if float(r["z"]) < BED_TOP + (thickness - 0.5) * DIAMETER]
    volume = sum(4.0 / 3.0 * math.pi * float(r["radius"]) ** 3 for r in rows)
    with open(path, "w") as f:
        f.write("x,y,z,radius,vx,vy,vz\n")
        for r in rows:
            f.write(f"{r['x']},{r['y']},{r['z']},{float(r['radius']) * shrink!r},{PUSH},0,0\n")
    return path, len(rows), volume / (LENGTH * WIDTH) / DIAMETER, volume * DENSITY


def variant(work, name, model, law):
    """The release case with the contact law of a run written in."""
    with open(os.path.join(CASES, "chute_layer_3d.toml")) as f:
        text = f.read()
    soft_law = 'model = "soft"\nrestitution = 0.5\ncontact_time = 1.0e-4\n'
    step = "dt_over_contact_time = 0.05\n"
    assert soft_law in text and step in text, "chute_layer_3d.toml changed: update the script"
    if model == "cocd":
        text = text.replace(soft_law, 'model = "cocd"\ntolerance = 1.0e-5\n').replace(step, "dt = 1.0e-3\n")
    elif law == "matched":
        stiffness, damping = matched_law()
        text = text.replace(soft_law, f'model = "soft"\nstiffness = {stiffness!r}\ndamping = {damping!r}\n')
        text = text.replace(step, f"dt = {STEP!r}\n")
    path = os.path.join(work, f"{name}.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def late_speeds(times, kinetic, mean_velocity, mass):
    """The rms speed sqrt(2 E_k / M) and the mean down-slope speed
    averaged over the samples in LATE."""
    late = [i for i, t in enumerate(times) if LATE[0] - 1e-9 <= t <= LATE[1] + 1e-9]
    if not late:
        return None, None
    rms = sum(math.sqrt(2.0 * kinetic[i] / mass) for i in late) / len(late)
    mean = sum(mean_velocity[i] for i in late) / len(late) if mean_velocity else None
    return rms, mean


def mean_down_slope(folder):
    """The mean down-slope velocity of the moving grains in each particle file."""
    means = {}
    for name in sorted(os.listdir(os.path.join(folder, "particles"))):
        if name.endswith(".vtp"):
            a = vtp_arrays(os.path.join(folder, "particles", name), {"velocity", "fixed"})
            moving = [v[0] for v, (f,) in zip(a["velocity"], a["fixed"]) if not f]
            means[name] = sum(moving) / len(moving)
    return [means[k] for k in sorted(means)]


def run_grainflow(binary, work, run, thickness, deposit):
    model, law, mu, mu_r, dt, _ = run
    name = f"{model}_{law}_mu{mu:g}_mr{mu_r:g}_dt{dt or STEP:g}_{thickness}d"
    case = variant(work, name, model, law)
    sets = [f'particles.block[1].path="{os.path.abspath(deposit[0])}"', f"contact.friction={mu}",
            "parallel.threads=1"]
    if mu_r:
        sets.append(f"contact.rolling_friction={mu_r}")
    if dt:
        sets.append(f"time.dt={dt}")
    out = os.path.join(work, name)
    summary = finished_summary(out)
    if summary is None:
        summary, refusal = run_case(binary, case, out, sets)
        if summary is None:
            return {"status": "refused: " + refusal}
    with open(os.path.join(out, "series.csv")) as f:
        series = list(csv.DictReader(f))
    times = [float(r["t"]) for r in series]
    kinetic = [float(r["kinetic_translational"]) for r in series]
    means = mean_down_slope(out)
    at_rest = summary["stop_reason"].startswith("at rest")
    if at_rest:
        return {"status": "at rest", "rest_time": f"{summary['simulated_time']:.3f}",
                "wall_seconds": summary["wall_seconds"]}
    rms, mean = late_speeds(times, kinetic, means if len(means) == len(times) else None, deposit[3])
    return {"status": "flowing", "rms_speed": rms, "mean_speed": mean, "wall_seconds": summary["wall_seconds"]}


LAMMPS_INPUT = """units si
atom_style sphere
boundary p f f
comm_modify vel yes
read_data {data}
group mobile type 1
pair_style granular
pair_coeff * * hooke {kn!r} {gn!r} tangential linear_history {kt!r} 0.0 {mu} damping velocity limit_damping
fix floor mobile wall/gran granular hooke {kn!r} {gn!r} tangential linear_history {kt!r} 0.0 0.0 damping velocity limit_damping zplane 0.0 NULL
fix sides mobile wall/gran granular hooke {kn!r} {gn!r} tangential linear_history {kt!r} 0.0 0.0 damping velocity limit_damping yplane 0.0 {width!r}
neighbor 0.0002 bin
neigh_modify delay 0 every 1 check yes exclude type 2 2
fix integrate mobile nve/sphere
fix gravity mobile gravity 9.81 vector {gx!r} 0.0 {gz!r}
timestep {dt!r}
compute kinetic mobile ke
variable vx equal vcm(mobile,x)
thermo_style custom step time c_kinetic v_vx
thermo_modify norm no format float %.10g
thermo {every}
run {steps}
"""


def run_lammps(work, run, thickness, deposit, glued):
    """LAMMPS on the same layer and glued bed with the matched law: the
    grains of the layer type 1, the glued ones type 2 and frozen."""
    _, _, mu, _, _, _ = run
    name = f"lammps_matched_mu{mu:g}_{thickness}d"
    folder = os.path.join(work, name)
    os.makedirs(folder, exist_ok=True)
    with open(deposit[0]) as f:
        layer_rows = list(csv.DictReader(f))
    data = os.path.join(folder, "chute.data")
    with open(data, "w") as f:
        f.write(f"chute layer\n\n{len(glued) + len(layer_rows)} atoms\n2 atom types\n\n"
                f"0 {LENGTH!r} xlo xhi\n0 {WIDTH!r} ylo yhi\n0 0.12 zlo zhi\n\nAtoms # sphere\n\n")
        atoms = [(2, p, r, 0.0) for p, r in glued] + \
            [(1, (float(r["x"]), float(r["y"]), float(r["z"])), float(r["radius"]), PUSH) for r in layer_rows]
        for i, (kind, p, r, _) in enumerate(atoms, 1):
            f.write(f"{i} {kind} {2 * r!r} {DENSITY!r} {p[0]!r} {p[1]!r} {p[2]!r}\n")
        f.write("\nVelocities\n\n")
        for i, (_, _, _, v) in enumerate(atoms, 1):
            f.write(f"{i} {v!r} 0 0 0 0 0\n")
    stiffness, damping = matched_law()
    with open(os.path.join(folder, "in.chute"), "w") as f:
        f.write(LAMMPS_INPUT.format(data=data, kn=stiffness, gn=damping, kt=0.2 * stiffness, mu=mu, width=WIDTH,
                                    gx=math.sin(SLOPE), gz=-math.cos(SLOPE), dt=STEP,
                                    every=round(0.1 / STEP), steps=round(LATE[1] / STEP)))
    log = os.path.join(folder, "log.lammps")
    if not os.path.exists(log) or "Loop time" not in open(log).read():
        subprocess.run(["lmp", "-in", "in.chute", "-log", "log.lammps"], cwd=folder, check=True,
                       stdout=subprocess.DEVNULL)
    times, kinetic, means, wall = [], [], [], None
    reading = False
    for line in open(log):
        words = line.split()
        if words[:2] == ["Step", "Time"]:
            reading = True
        elif reading and words and words[0] == "Loop":
            wall, reading = float(words[3]), False
        elif reading and len(words) == 4:
            times.append(float(words[1]))
            kinetic.append(float(words[2]))
            means.append(float(words[3]))
    rms, mean = late_speeds(times, kinetic, means, deposit[3])
    at_rest = math.sqrt(2.0 * kinetic[-1] / deposit[3]) < 1e-3
    return {"status": "at rest" if at_rest else "flowing", "rms_speed": rms, "mean_speed": mean,
            "wall_seconds": wall}


def glued_grains(fill):
    arrays = vtp_arrays(os.path.join(fill, "particles", "particles_000000.vtp"), {"position", "radius", "fixed"})
    return [(p, r) for p, (r,), (f,) in zip(arrays["position"], arrays["radius"], arrays["fixed"]) if f]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", default=os.path.join(HERE, "..", "target", "release", "grainflow"))
    parser.add_argument("--work", required=True)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    fill = rain(args.binary, args.work)
    glued = glued_grains(fill)
    lammps = shutil.which("lmp") is not None
    if not lammps:
        print("lmp not on the PATH: the LAMMPS rows are left out", file=sys.stderr)
    rows = []
    layers = {}
    for run in RUNS:
        model, law, mu, mu_r, dt, thicknesses = run
        for thickness in thicknesses:
            # Each layer is cut from the rain once and shared by its runs.
            shrink = 0.995 if model == "cocd" else 1.0
            if (thickness, shrink) not in layers:
                layers[thickness, shrink] = layer(args.work, fill, thickness, shrink)
            deposit = layers[thickness, shrink]
            row = {"model": model, "law": law, "friction": mu, "rolling_friction": mu_r,
                   "dt": dt or STEP, "thickness": thickness, "grains": deposit[1],
                   "solid_thickness": round(deposit[2], 3)}
            if model == "lammps":
                if not lammps:
                    continue
                row.update(run_lammps(args.work, run, thickness, deposit, glued))
            else:
                row.update(run_grainflow(args.binary, args.work, run, thickness, deposit))
            for key in ("rms_speed", "mean_speed"):
                if isinstance(row.get(key), float):
                    row[key] = f"{row[key]:.4g}"
            row["wall_seconds"] = f"{row['wall_seconds']:.1f}"
            print(", ".join(f"{k} {row.get(k, '')}" for k in FIELDS), flush=True)
            rows.append(row)
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, FIELDS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
