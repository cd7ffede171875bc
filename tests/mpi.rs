//! The DEM on several MPI ranks gives the serial run's results (built with
//! the feature `mpi`; needs `mpirun` of Open MPI on the PATH, which
//! `.ci/run` installs). Four ranks are oversubscribed on a small machine.
//!
//! Round-off differences (another order of summing a grain's contact forces)
//! grow in a dense granular flow like any perturbation of its state, by
//! about ten orders of magnitude over 2,000 steps of this collapse: the
//! comparisons are made after 100 steps, where the bound 1e-10 of the
//! decomposition's contract applies.

#![cfg(feature = "mpi")]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A 3D column of 400 spheres between two gates on a floor, periodic along
/// y; `{BLOCK}`, `{GATES}` and `{TIME}` are filled in by the tests.
const COLUMN: &str = r#"
[domain]
dimension = 3
lower = [-0.3, 0.0, 0.0]
upper = [0.3, 0.06, 0.3]
periodic = [false, true, false]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 5.0e-3
radius_spread = 0.1
seed = 7
{TRACKED}

{BLOCK}

[contact]
model = "soft"
restitution = 0.5
contact_time = 1.0e-4
friction = 0.5
rolling_friction = 0.05

[[walls]]
name = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[[walls]]
name = "gate_left"
point = [-0.05, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
{GATES}

[[walls]]
name = "gate_right"
point = [0.05, 0.0, 0.0]
normal = [-1.0, 0.0, 0.0]
{GATES}

[time]
{TIME}
dt_over_contact_time = 0.05

[output]
interval = 0.1
"#;

const GRAINS: usize = 400;

/// The column's grains placed at random between the gates.
const RANDOM_BLOCK: &str = "[[particles.block]]\nkind = \"random\"\nlower = [-0.05, 0.0, 0.0]\n\
                            upper = [0.05, 0.06, 0.15]\ncount = 400";

/// The `grainflow` command on `ranks` MPI ranks (without mpirun for one),
/// one thread each, allowed to run as root.
fn grainflow_on(ranks: usize) -> Command {
    let binary = env!("CARGO_BIN_EXE_grainflow");
    let mut command = if ranks == 1 {
        Command::new(binary)
    } else {
        let mut c = Command::new("mpirun");
        c.args(["--oversubscribe", "-n", &ranks.to_string(), binary]);
        c
    };
    command
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("RAYON_NUM_THREADS", "1");
    command
}

/// `grainflow run CASE --out OUT [--set ...]` on `ranks` MPI ranks (without
/// mpirun for one), stopped if it has not ended within `limit`: (exit code,
/// stderr); a run that outlives the limit fails the test.
fn run(
    case: &Path,
    out: &Path,
    ranks: usize,
    overrides: &[&str],
    limit: Duration,
) -> (i32, String) {
    let mut command = grainflow_on(ranks);
    command
        .args([
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for assignment in overrides {
        command.args(["--set", assignment]);
    }
    let mut child = command
        .spawn()
        .expect("mpirun starts (is Open MPI installed?)");
    let started = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut stderr = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut stderr)
                .unwrap();
            return (status.code().unwrap_or(-1), stderr);
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            panic!("{ranks} ranks still running after {limit:?}: a hang");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The last rows of `tracked.csv`: id → (x, v, ω) at the final time.
fn final_states(out: &Path) -> (f64, BTreeMap<u64, Vec<f64>>) {
    let text = std::fs::read_to_string(out.join("tracked.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let end = rows.iter().map(|r| r[0]).fold(f64::MIN, f64::max);
    let states = rows
        .iter()
        .filter(|r| r[0] == end)
        .map(|r| (r[1] as u64, r[2..11].to_vec()))
        .collect();
    (end, states)
}

/// Largest deviation of `other` from `reference` over every grain and
/// component, relative to the component's largest magnitude.
fn deviation(reference: &BTreeMap<u64, Vec<f64>>, other: &BTreeMap<u64, Vec<f64>>) -> f64 {
    assert_eq!(
        reference.keys().collect::<Vec<_>>(),
        other.keys().collect::<Vec<_>>(),
        "the same grains are tracked"
    );
    let mut largest: f64 = 0.0;
    for component in 0..9 {
        let scale = reference
            .values()
            .map(|s| s[component].abs())
            .fold(f64::MIN_POSITIVE, f64::max);
        for (id, state) in reference {
            let error = (state[component] - other[id][component]).abs() / scale;
            largest = largest.max(error);
        }
    }
    largest
}

/// Runs `case` on `ranks` ranks into `out` and asserts that its final
/// time and tracked states are the serial run's `(end, states)` within the
/// decomposition's bound 1e-10 (relative).
fn assert_states_match(
    case: &Path,
    out: &Path,
    ranks: usize,
    overrides: &[&str],
    (end, reference): (f64, &BTreeMap<u64, Vec<f64>>),
) {
    let (code, stderr) = run(case, out, ranks, overrides, Duration::from_secs(120));
    assert_eq!(code, 0, "{ranks} ranks {overrides:?}: {stderr}");
    let (other_end, states) = final_states(out);
    assert_eq!(other_end, end);
    let largest = deviation(reference, &states);
    println!("{ranks} ranks {overrides:?}: largest relative deviation {largest:.3e}");
    assert!(
        largest <= 1e-10,
        "{ranks} ranks {overrides:?}: deviation {largest:e}"
    );
}

fn metrics(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    summary["metrics"].clone()
}

fn tracked_all(count: usize) -> String {
    let ids: Vec<String> = (0..count).map(|k| k.to_string()).collect();
    format!("tracked = [{}]", ids.join(", "))
}

/// A column settled for 0.3 s on one rank, then released: 100 steps of the
/// collapse on 1, 2 and 4 ranks (among them process grids split along the
/// periodic axis and across the height), with its analysis.
#[test]
fn a_column_collapse_on_2_and_4_ranks_matches_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let fill = dir.path().join("fill.toml");
    std::fs::write(
        &fill,
        COLUMN
            .replace("{TRACKED}", "")
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TIME}", "end = 0.3"),
    )
    .unwrap();
    let settled = dir.path().join("settled");
    let (code, stderr) = run(&fill, &settled, 1, &[], Duration::from_secs(300));
    assert_eq!(code, 0, "{stderr}");

    let collapse = dir.path().join("collapse.toml");
    let file_block = format!(
        "[[particles.block]]\nkind = \"file\"\npath = \"{}\"",
        settled.join("final_particles.csv").display()
    );
    std::fs::write(
        &collapse,
        COLUMN
            .replace("{TRACKED}", &tracked_all(GRAINS))
            .replace("{BLOCK}", &file_block)
            .replace("{GATES}", "remove_at = 0.0")
            .replace("{TIME}", "end = 5.0e-4")
            .replace("interval = 0.1", "interval = 5.0e-4")
            + "\n[analysis]\nkind = \"column_collapse\"\nprofile_times = [2.5e-4]\n",
    )
    .unwrap();
    // 100 steps of 0.05 t_c = 5e-6 s.
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&collapse, &serial, 1, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (end, reference) = final_states(&serial);
    let reference_metrics = metrics(&serial);
    assert!((end - 5.0e-4).abs() < 1e-12, "{end}");
    assert_eq!(reference.len(), GRAINS);

    for (ranks, grid) in [(2, None), (4, Some("[2,2,1]")), (4, Some("[2,1,2]"))] {
        let out = dir
            .path()
            .join(format!("ranks_{ranks}_{}", grid.unwrap_or("auto")));
        let setting = grid.map(|g| format!("parallel.process_grid={g}"));
        let overrides: Vec<&str> = setting.iter().map(|s| s.as_str()).collect();
        assert_states_match(&collapse, &out, ranks, &overrides, (end, &reference));
        // The analysis runs on the root over the gathered grains.
        let measured = metrics(&out);
        for key in ["initial_height", "final_front", "final_height", "runout"] {
            let (a, b) = (
                reference_metrics[key].as_f64().unwrap(),
                measured[key].as_f64().unwrap(),
            );
            assert!(
                (a - b).abs() <= 1e-10 * a.abs(),
                "{key}: {a} serial, {b} on {ranks} ranks"
            );
        }
        assert_eq!(
            std::fs::read_to_string(serial.join("profiles.csv")).unwrap(),
            std::fs::read_to_string(out.join("profiles.csv")).unwrap()
        );
        // Each rank wrote its piece of the particle output; the root an index.
        for rank in 0..ranks {
            let piece = out.join(format!("particles/particles_000000_{rank:04}.vtp"));
            assert!(piece.exists(), "{}", piece.display());
        }
        let index = std::fs::read_to_string(out.join("particles/particles_000001.pvtp")).unwrap();
        assert_eq!(index.matches("<Piece Source=").count(), ranks);
    }
}

/// Two spheres, one crossing the boundary between two ranks at x = 0 and
/// striking the other obliquely there (friction, sliding then rolling): on
/// two ranks the grain changes owner while the contact spans the ranks,
/// and both move exactly as in the serial run.
#[test]
fn a_grain_crossing_ranks_and_a_contact_across_them_match_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let grains = dir.path().join("pair.csv");
    std::fs::write(
        &grains,
        "x,y,z,radius,vx,vy,vz\n\
         -0.012,0.0,0.0,0.006,0.5,0.1,0.05\n\
         0.004,0.004,0.001,0.003,0.0,0.0,0.0\n",
    )
    .unwrap();
    let case = dir.path().join("pair.toml");
    std::fs::write(
        &case,
        format!(
            r#"
[domain]
dimension = 3
lower = [-0.05, -0.05, -0.05]
upper = [0.05, 0.05, 0.05]
[particles]
density = 2500.0
radius = 5.0e-3
tracked = [0, 1]
[[particles.block]]
kind = "file"
path = "{}"
[contact]
model = "soft"
restitution = 0.7
contact_time = 1.0e-4
friction = 0.4
rolling_friction = 0.05
[time]
end = 0.04
dt_over_contact_time = 0.02
[output]
interval = 0.01
tracked_interval = 1.0e-4
"#,
            grains.display()
        ),
    )
    .unwrap();
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&case, &serial, 1, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let parallel = dir.path().join("parallel");
    let grid = ["parallel.process_grid=[2,1,1]"];
    let (code, stderr) = run(&case, &parallel, 2, &grid, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");

    let rows = |out: &Path| std::fs::read_to_string(out.join("tracked.csv")).unwrap();
    let (serial_rows, parallel_rows) = (rows(&serial), rows(&parallel));
    // The scene does what the test is about: grain 0 starts on rank 0 and
    // ends on rank 1, and the pair touches while their centres lie on
    // either side of x = 0.
    let states: Vec<Vec<f64>> = serial_rows
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let first_x = states.iter().find(|r| r[1] == 0.0).unwrap()[2];
    let last_x = states.iter().rev().find(|r| r[1] == 0.0).unwrap()[2];
    assert!(first_x < 0.0 && last_x > 0.0, "{first_x} {last_x}");
    let spanning = states.chunks(2).any(|pair| {
        let (a, b) = (&pair[0], &pair[1]);
        let distance =
            ((a[2] - b[2]).powi(2) + (a[3] - b[3]).powi(2) + (a[4] - b[4]).powi(2)).sqrt();
        distance < 0.009 && a[2].signum() != b[2].signum()
    });
    assert!(spanning, "the contact must span the two ranks");
    let spin = states.last().unwrap()[8..11]
        .iter()
        .map(|w| w.abs())
        .fold(0.0, f64::max);
    assert!(spin > 1.0, "friction must spin the grains: {spin}");
    // Bit for bit: same rows, every number printed round-trip exact.
    assert_eq!(serial_rows, parallel_rows);
}

/// NSCD on several ranks: a disc thrown onto a pile of six that straddles
/// the boundary between two ranks (restitution 0.3, μ = 0.3), 60 steps of
/// 1 ms. Each rank sweeps its own pairs, the mass of a grain both ranks act
/// on split between them, and the copies are brought in step after each
/// sweep: Jacobi across ranks instead of Gauss–Seidel, so the sweeps differ
/// from one rank's but converge to the same solution, and the states agree
/// to what the tolerance leaves. Measured, relative: 7.5e-12 at ε = 1e-13
/// (1,202 sweeps a step against 715 on one rank), 8.8e-11 at 1e-12.
#[test]
fn nscd_on_2_ranks_matches_the_serial_run_to_its_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let r = 0.005;
    let mut grains = String::from("x,y,radius,vx,vy\n");
    for (layer, count) in [3, 2, 1].into_iter().enumerate() {
        let y = -0.04 + r + layer as f64 * r * 3f64.sqrt() + 1e-6 * layer as f64;
        for i in 0..count {
            let x = (2 * i + 1) as f64 * r - count as f64 * r;
            grains += &format!("{},{y},{r},0.0,0.0\n", 1.0005 * x);
        }
    }
    grains += &format!(
        "-0.002,{},{r},0.3,-0.5\n",
        -0.04 + r + 4.0 * r * 3f64.sqrt()
    );
    std::fs::write(dir.path().join("pile.csv"), grains).unwrap();
    let case = dir.path().join("pile.toml");
    std::fs::write(
        &case,
        r#"
[domain]
dimension = 2
lower = [-0.05, -0.04]
upper = [0.05, 0.0]
gravity = [0.0, -9.81]
[particles]
density = 2500.0
radius = 5.0e-3
tracked = [0, 1, 2, 3, 4, 5, 6]
[[particles.block]]
kind = "file"
path = "pile.csv"
[contact]
model = "nscd"
restitution = 0.3
friction = 0.3
tolerance = 1.0e-13
max_iterations = 100000
[[walls]]
name = "floor"
point = [0.0, -0.04]
normal = [0.0, 1.0]
[time]
end = 0.06
dt = 1.0e-3
[output]
interval = 0.02
tracked_interval = 1.0e-3
"#,
    )
    .unwrap();
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&case, &serial, 1, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    // The thrown disc lands: contacts form across x = 0 and carry it.
    assert!(metrics(&serial)["mean_closed_contacts"].as_f64().unwrap() > 6.0);
    assert_eq!(metrics(&serial)["unconverged_steps"], 0);
    let reference = final_states(&serial);
    let out = dir.path().join("ranks_2");
    let grid = ["parallel.process_grid=[2,1]"];
    assert_states_match(&case, &out, 2, &grid, (reference.0, &reference.1));
    assert_eq!(metrics(&out)["unconverged_steps"], 0);
}

/// COCD on several ranks, the program shared among them (each holds its
/// rows; the grains that pairs on two ranks reach form a separator whose
/// Schur complement the ranks factorise together): the 2D column collapse
/// of `cases/` (410 discs on a bed of 28 glued ones) in a domain cut to
/// 0.25 × 0.2 m so that the ranks' boxes cut the column (separator of 18
/// discs on 2 ranks), and the 3D static box (1,600 spheres) with gravity
/// tilted by 45° so that the packing slumps against its wall (separator of
/// 116 spheres on 2 ranks, 226 on 4). It is one rank's program with its
/// sums in another order: the states agree within 1e-10, positions
/// relative to the largest coordinate, velocities to the largest speed V,
/// spins as ωR/V. Measured (2026-12-05, the cuts leaving equal interiors):
/// 2D 1.8e-11 (2 ranks), 2.3e-11 and 1.3e-11 (4) after 5 steps; 3D 2.3e-11
/// (2) and 3.6e-11 (4) after 3 steps. Clarabel on the program gathered on
/// every rank (the reference, and the interior point's fallback), 2D on 2
/// ranks: 2.0e-12.
#[test]
fn cocd_on_2_and_4_ranks_matches_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases");
    let interior_point = "contact.conic_solver=\"interior_point\"";
    let clarabel = "contact.conic_solver=\"clarabel\"";
    let column = [
        "time.end=0.005",
        "domain.upper=[0.25,0.2]",
        "particles.block[0].upper=[0.25,0.0088]",
    ];
    let slumping = ["time.end=0.003", "domain.gravity=[6.937,0.0,-6.937]"];
    for (name, grains, radius, scene, solver, grids) in [
        (
            "column_collapse_cocd_2d.toml",
            438,
            4.0e-3,
            &column[..],
            interior_point,
            vec![(2, "[2,1]"), (4, "[4,1]"), (4, "[2,2]")],
        ),
        (
            "column_collapse_cocd_2d.toml",
            438,
            4.0e-3,
            &column[..],
            clarabel,
            vec![(2, "[2,1]")],
        ),
        (
            "static_box_3d.toml",
            1600,
            5.0e-4,
            &slumping[..],
            interior_point,
            vec![(2, "[2,1,1]"), (4, "[2,2,1]")],
        ),
    ] {
        let text = std::fs::read_to_string(cases.join(name)).unwrap();
        let case = dir.path().join(name);
        std::fs::write(
            &case,
            text.replace(
                "path = \"data/",
                &format!("path = \"{}/data/", cases.display()),
            )
            .replace(
                "[particles]\n",
                &format!("[particles]\n{}\n", tracked_all(grains)),
            )
            .replace("[output]\n", "[output]\ntracked_interval = 1.0e-3\n"),
        )
        .unwrap();
        let mut settings: Vec<&str> = scene.to_vec();
        settings.push(solver);
        let serial = dir.path().join(format!("{name}_{solver}_serial"));
        let (code, stderr) = run(&case, &serial, 1, &settings, Duration::from_secs(300));
        assert_eq!(code, 0, "{stderr}");
        let (end, reference) = final_states(&serial);
        assert_eq!(reference.len(), grains, "{name}");
        let speed = |s: &Vec<f64>| (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]).sqrt();
        let fastest = reference.values().map(speed).fold(0.0, f64::max);
        // The release, or the tilted gravity, has set the grains moving.
        assert!(fastest > 0.01, "{name}: {fastest}");
        let extent = reference
            .values()
            .flat_map(|s| s[..3].iter().map(|x| x.abs()))
            .fold(0.0, f64::max);
        for (ranks, grid) in grids {
            let out = dir.path().join(format!("{name}_{solver}_{ranks}_{grid}"));
            let grid = format!("parallel.process_grid={grid}");
            let mut on_ranks = settings.clone();
            on_ranks.push(&grid);
            let (code, stderr) = run(&case, &out, ranks, &on_ranks, Duration::from_secs(300));
            assert_eq!(code, 0, "{ranks} ranks {grid}: {stderr}");
            let (other_end, states) = final_states(&out);
            assert_eq!(other_end, end);
            assert_eq!(states.len(), grains);
            let mut largest: f64 = 0.0;
            for (id, state) in &reference {
                for (c, scale) in [(0..3, extent), (3..6, fastest), (6..9, fastest / radius)] {
                    for k in c {
                        largest = largest.max((state[k] - states[id][k]).abs() / scale);
                    }
                }
            }
            println!("{name}, {solver}, {ranks} ranks, {grid}: largest deviation {largest:.3e}");
            assert!(largest <= 1e-10, "{name} {ranks} ranks {grid}: {largest:e}");
            // The certificates hold on the ranks as on one.
            let (a, b) = (metrics(&serial), metrics(&out));
            for key in ["max_penetration", "max_coulomb_violation"] {
                let (a, b) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
                assert!(b <= a + 1e-12, "{key}: {b} on {ranks} ranks, {a} on one");
            }
            assert_eq!(b["fallback_steps"].as_f64(), Some(0.0));
        }
    }
}

/// The binary collisions of the validation (41 pairs along the height, an
/// analysis that follows every pair at every step) on two ranks: the same
/// collisions and metrics as on one, bit for bit.
#[test]
fn binary_collisions_on_two_ranks_give_the_serial_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/binary_collision.toml");
    let (serial, parallel) = (dir.path().join("serial"), dir.path().join("parallel"));
    let (code, stderr) = run(&case, &serial, 1, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (code, stderr) = run(&case, &parallel, 2, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (a, b) = (metrics(&serial), metrics(&parallel));
    assert_eq!(a["collisions"].as_u64(), Some(41));
    assert!((a["restitution"].as_f64().unwrap() - 0.87).abs() < 0.005 * 0.87);
    assert_eq!(a, b);
    let read = |out: &Path| std::fs::read_to_string(out.join("collisions.csv")).unwrap();
    assert_eq!(read(&serial), read(&parallel));
}

/// A rank that cannot write its piece of the particle output stops the
/// whole job with a message naming it, instead of leaving the other rank
/// waiting in the next exchange.
#[test]
fn a_rank_that_fails_stops_the_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("column.toml");
    std::fs::write(
        &case,
        COLUMN
            .replace("{TRACKED}", "")
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TIME}", "end = 10.0"),
    )
    .unwrap();
    let out = dir.path().join("out");
    // A directory where rank 1 writes its first particle piece.
    std::fs::create_dir_all(out.join("particles/particles_000000_0001.vtp")).unwrap();
    let grid = ["parallel.process_grid=[2,1,1]"];
    let (code, stderr) = run(&case, &out, 2, &grid, Duration::from_secs(60));
    assert_ne!(code, 0, "{stderr}");
    assert!(stderr.contains("error on rank 1 of 2"), "{stderr}");
    assert!(
        stderr.contains("particles_000000_0001.vtp") || stderr.contains("writing"),
        "{stderr}"
    );
}

/// What does not run on several ranks yet is refused before anything is
/// written, on every rank alike; so is a process grid that does not match
/// the ranks.
#[test]
fn scenes_not_shared_among_ranks_are_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let column = dir.path().join("column.toml");
    std::fs::write(
        &column,
        COLUMN
            .replace("{TRACKED}", "")
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TIME}", "end = 0.01"),
    )
    .unwrap();
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases");
    for (case, overrides, expected) in [
        (
            cases.join("falling_sphere_axisymmetric.toml"),
            vec![],
            "an axisymmetric scene (domain.geometry = \"axisymmetric\")",
        ),
        (
            column,
            vec!["parallel.process_grid=[3,1,1]"],
            "parallel.process_grid = [3, 1, 1] holds 3 ranks, but the run has 2",
        ),
        // COCD: the separator is measured on the root alone, which reports.
        (
            cases.join("column_collapse_cocd_2d.toml"),
            vec!["parallel.process_grid=[3,1]"],
            "parallel.process_grid = [3, 1] holds 3 ranks, but the run has 2",
        ),
    ] {
        let out = dir.path().join("out");
        let (code, stderr) = run(&case, &out, 2, &overrides, Duration::from_secs(60));
        let name = case.display();
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert_eq!(
            stderr.matches("error:").count(),
            1,
            "{name}: one message: {stderr}"
        );
        assert!(!out.exists(), "{name}: nothing is written");
    }
}

/// A field output read back: the cell velocity of every cell of the whole
/// grid, from one `.vti` file or from the pieces of a `.pvti` index.
fn read_velocity(out: &Path, frame: usize) -> BTreeMap<[usize; 3], [f64; 3]> {
    let fields = out.join("fields");
    // ImageData on a uniform grid, RectilinearGrid on a stretched one.
    let named = |extension: &str| fields.join(format!("fields_{frame:06}.{extension}"));
    let single = [named("vti"), named("vtr")]
        .into_iter()
        .find(|p| p.exists());
    let files: Vec<PathBuf> = if let Some(single) = single {
        vec![single]
    } else {
        let index = [named("pvti"), named("pvtr")]
            .iter()
            .find_map(|p| std::fs::read_to_string(p).ok())
            .expect("a field index");
        index
            .lines()
            .filter_map(|line| line.split("Source=\"").nth(1))
            .map(|rest| fields.join(rest.split('"').next().unwrap()))
            .collect()
    };
    let mut cells = BTreeMap::new();
    for file in files {
        let frame = grainflow_io::read_vtk(&std::fs::read(&file).unwrap()).unwrap();
        let extent: Vec<usize> = frame
            .xml
            .split("<Piece Extent=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        let values = frame.arrays["velocity"].f64s();
        let n = [
            extent[1] - extent[0],
            extent[3] - extent[2],
            extent[5] - extent[4],
        ];
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let at = 3 * (i + n[0] * (j + n[1] * k));
                    cells.insert(
                        [extent[0] + i, extent[2] + j, extent[4] + k],
                        [values[at], values[at + 1], values[at + 2]],
                    );
                }
            }
        }
    }
    cells
}

/// Largest deviation of two velocity fields over every cell and component,
/// relative to the largest speed.
fn field_deviation(
    reference: &BTreeMap<[usize; 3], [f64; 3]>,
    other: &BTreeMap<[usize; 3], [f64; 3]>,
) -> f64 {
    assert_eq!(reference.len(), other.len(), "the same cells");
    let scale = reference
        .values()
        .flat_map(|v| v.iter())
        .fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
    reference
        .iter()
        .flat_map(|(cell, v)| (0..3).map(move |c| (v[c] - other[cell][c]).abs() / scale))
        .fold(0.0, f64::max)
}

/// The flows of the validation on 2 and 4 ranks after 100 steps (the 2D
/// Taylor–Green vortex, the 3D Beltrami flow, a lid-driven box walled on
/// every side: walls across the split axes) and after the start-up of a
/// Couette flow on a stretched grid: the velocity of every cell deviates from the serial run's by at
/// most 1e-10 of the largest speed, and the analyses agree. The ranks of
/// one node read one another's pencils directly, and a slab along x
/// (`[2,1,1]`, `[4,1,1]`) solves its planes across the ranks' arrays; the
/// grids marked `messages` send pencils instead
/// (`parallel.shared_memory = false`, the path between nodes).
#[test]
fn flows_on_2_and_4_ranks_match_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases");
    let cavity = dir.path().join("cavity.toml");
    std::fs::write(
        &cavity,
        r#"
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
[fluid]
cells = [16, 12, 10]
density = 1.0
viscosity = 0.01
[fluid.boundary]
x = ["no_slip", "no_slip"]
y = ["free_slip", "free_slip"]
z = ["no_slip", "moving"]
z_upper_velocity = [1.0, 0.3, 0.0]
[time]
end = 0.2
dt = 0.01
[output]
interval = 0.2
"#,
    )
    .unwrap();
    // 100 steps of each (dt = 0.01, 0.02, 0.01; the start-up its own run).
    for (case, settings, grids, last_frame, metric) in [
        (
            cases.join("taylor_green_2d.toml"),
            vec![],
            vec!["[2,1]", "[4,1]"],
            10,
            Some("l2_error"),
        ),
        (
            cases.join("taylor_green_3d.toml"),
            vec!["time.end=2.0", "output.interval=2.0"],
            vec![
                "[2,1,1]",
                "[4,1,1]",
                "[2,2,1]",
                "[1,4,1]",
                "[2,1,1] messages",
                "[2,2,1] messages",
            ],
            1,
            Some("l2_error"),
        ),
        (
            cavity,
            vec!["time.end=1.0", "output.interval=1.0"],
            vec!["[2,1,1]", "[4,1,1]", "[2,2,1]"],
            1,
            None,
        ),
        // A grid stretched along its last axis (RectilinearGrid pieces).
        (
            cases.join("couette_startup.toml"),
            vec![],
            vec!["[2,1]"],
            4,
            Some("profile_error"),
        ),
    ] {
        let name = case.file_name().unwrap().to_string_lossy().into_owned();
        let serial = dir.path().join(format!("{name}_serial"));
        let (code, stderr) = run(&case, &serial, 1, &settings, Duration::from_secs(300));
        assert_eq!(code, 0, "{name}: {stderr}");
        let reference = read_velocity(&serial, last_frame);
        for grid in grids {
            let (grid, messages) = match grid.strip_suffix(" messages") {
                Some(grid) => (grid, true),
                None => (grid, false),
            };
            let ranks: usize = grid
                .trim_matches(|c| c == '[' || c == ']')
                .split(',')
                .map(|v| v.parse::<usize>().unwrap())
                .product();
            let out = dir.path().join(format!("{name}_{grid}_{messages}"));
            let setting = format!("parallel.process_grid={grid}");
            let mut all = settings.clone();
            all.push(&setting);
            if messages {
                all.push("parallel.shared_memory=false");
            }
            let (code, stderr) = run(&case, &out, ranks, &all, Duration::from_secs(300));
            assert_eq!(code, 0, "{name} on {grid}: {stderr}");
            let largest = field_deviation(&reference, &read_velocity(&out, last_frame));
            println!(
                "{name} on {grid} (messages: {messages}): largest relative deviation of the \
                 velocity {largest:.3e}"
            );
            assert!(largest <= 1e-10, "{name} on {grid}: {largest:e}");
            if let Some(key) = metric {
                let (a, b) = (
                    metrics(&serial)[key].as_f64().unwrap(),
                    metrics(&out)[key].as_f64().unwrap(),
                );
                assert!(
                    (a - b).abs() <= 1e-10 * a,
                    "{name} on {grid}: {key} {a} against {b}"
                );
            }
        }
    }
}

/// The falling sphere of the validation (D/Δx = 4 here, the sphere on the
/// line where the boxes of 2 × 2 ranks meet, so that its forcing region
/// straddles all four), 100 steps on 2 and 4 ranks: the sphere's state and
/// the fluid's velocity deviate from the serial run's by at most 1e-10,
/// under eq. 7 and with the layer relaxed at its renewal rate (each grain's
/// slip summed over the ranks its layer straddles).
#[test]
fn the_falling_sphere_on_2_and_4_ranks_matches_the_serial_run() {
    for layer in ["every_stage", "renewal"] {
        falling_sphere_on_ranks_matches_the_serial_run(layer);
    }
}

/// [`the_falling_sphere_on_2_and_4_ranks_matches_the_serial_run`] with
/// `coupling.layer_forcing = layer`.
fn falling_sphere_on_ranks_matches_the_serial_run(layer: &str) {
    let dir = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/falling_sphere.toml");
    let end = 100.0 * 1.5964e-3;
    let settings = [
        "fluid.cells=[32,32,96]".to_string(),
        format!("time.end={end}"),
        format!("output.interval={end}"),
        format!("output.tracked_interval={end}"),
        "output.fields=true".to_string(),
        format!("coupling.layer_forcing=\"{layer}\""),
    ];
    let with = |extra: Option<&str>| {
        let mut all: Vec<String> = settings.to_vec();
        all.extend(extra.map(|g| format!("parallel.process_grid={g}")));
        all
    };
    let serial = dir.path().join("serial");
    let overrides = with(None);
    let list: Vec<&str> = overrides.iter().map(|s| s.as_str()).collect();
    let (code, stderr) = run(&case, &serial, 1, &list, Duration::from_secs(300));
    assert_eq!(code, 0, "{stderr}");
    let (_, sphere) = final_states(&serial);
    let fluid = read_velocity(&serial, 1);
    let fall = sphere[&0][5].abs();
    assert!(fall > 0.05, "the sphere falls: {fall}");
    for (ranks, grid) in [(2, "[1,2,1]"), (4, "[2,2,1]")] {
        let out = dir.path().join(format!("ranks_{ranks}"));
        let overrides = with(Some(grid));
        let list: Vec<&str> = overrides.iter().map(|s| s.as_str()).collect();
        let (code, stderr) = run(&case, &out, ranks, &list, Duration::from_secs(300));
        assert_eq!(code, 0, "{grid}: {stderr}");
        let (_, other) = final_states(&out);
        // Position and velocity relative to the fall, spin to its rate.
        let state_deviation = (0..9)
            .map(|c| (sphere[&0][c] - other[&0][c]).abs())
            .fold(0.0, f64::max)
            / fall.min(sphere[&0][2]);
        let fluid_deviation = field_deviation(&fluid, &read_velocity(&out, 1));
        println!(
            "falling sphere ({layer}) on {grid}: sphere {state_deviation:.3e}, fluid \
             {fluid_deviation:.3e}"
        );
        assert!(
            state_deviation <= 1e-10,
            "{layer}, {grid}: {state_deviation:e}"
        );
        assert!(
            fluid_deviation <= 1e-10,
            "{layer}, {grid}: {fluid_deviation:e}"
        );
    }
}

/// The immersed avalanche (`cases/immersed_avalanche.toml`, D/Δx = 5, 10
/// steps) on 2 and 4 ranks along x (the box is 3 D wide in y, narrower
/// than two grains' reach): gravity along the
/// periodic x drives the fluid, each grain's grid volume is summed from the
/// ranks its forcing region straddles, and the inclined-bed analysis sums
/// its profiles over the ranks. Every column of the last row of
/// `bed_series.csv` deviates from the serial run's by at most 1e-10
/// relative (to the largest of the row's velocities for the velocities).
///
/// Also with the layer relaxed at its renewal rate at a step of 1.5 ms,
/// where the viscous rate alone gives r Δt = 1.17: the grains of the bed
/// force in two passes a stage, each followed by the projection, their
/// number the largest over the ranks.
#[test]
fn the_inclined_bed_on_2_and_4_ranks_matches_the_serial_run() {
    inclined_bed_on_ranks_matches_the_serial_run(&[]);
    inclined_bed_on_ranks_matches_the_serial_run(&[
        "coupling.layer_forcing=\"renewal\"",
        "time.dt=1.5e-3",
        "time.end=0.006",
        "output.interval=0.006",
    ]);
}

/// [`the_inclined_bed_on_2_and_4_ranks_matches_the_serial_run`] with the
/// further settings `extra`.
fn inclined_bed_on_ranks_matches_the_serial_run(extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/immersed_avalanche.toml");
    let mut settings = vec![
        "fluid.cells=[40,12,40]",
        "time.end=0.005",
        "output.interval=0.005",
        "output.fields=false",
    ];
    settings.extend_from_slice(extra);
    let last_row = |out: &Path| -> Vec<f64> {
        let text = std::fs::read_to_string(out.join("bed_series.csv")).unwrap();
        text.lines()
            .last()
            .unwrap()
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&case, &serial, 1, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let reference = last_row(&serial);
    for (grid, ranks) in [("[2,1,1]", 2), ("[4,1,1]", 4)] {
        let out = dir.path().join(format!("ranks_{ranks}"));
        let setting = format!("parallel.process_grid={grid}");
        let mut all = settings.to_vec();
        all.push(&setting);
        let (code, stderr) = run(&case, &out, ranks, &all, Duration::from_secs(120));
        assert_eq!(code, 0, "{grid}: {stderr}");
        let row = last_row(&out);
        let scale = reference[2..5].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (column, (a, b)) in reference.iter().zip(&row).enumerate() {
            let size = if (2..5).contains(&column) {
                scale
            } else {
                a.abs()
            };
            let deviation = (a - b).abs() / size.max(f64::MIN_POSITIVE);
            println!("{extra:?} {grid} column {column}: {a} serial, {b}: {deviation:.2e}");
            assert!(
                deviation <= 1e-10,
                "{extra:?} {grid} column {column}: {a} against {b}"
            );
        }
    }
}

/// Three batches of a pour released 40 steps apart, each 5 mm above the
/// highest moving grain (a maximum over the ranks), in a box cut across the
/// batches: on 2 and 4 ranks the same grains, ids and states as on one
/// after 100 steps.
#[test]
fn a_pour_on_2_and_4_ranks_matches_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("pour.toml");
    std::fs::write(
        &case,
        format!(
            r#"
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [0.04, 0.04, 0.06]
gravity = [0.0, 0.0, -9.81]
[particles]
density = 2500.0
radius = 2.0e-3
radius_spread = 0.1
seed = 7
{}
[[particles.pour]]
lower = [0.002, 0.002, 0.0]
upper = [0.038, 0.038, 0.0135]
spacing = 0.0045
jitter = 0.5
count = 500
interval = 2.0e-4
gap = 0.005
velocity = [0.0, 0.0, -0.5]
[contact]
model = "soft"
restitution = 0.3
contact_time = 1.0e-4
friction = 0.4
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[time]
end = 5.0e-4
dt_over_contact_time = 0.05
[output]
interval = 5.0e-4
"#,
            tracked_all(500)
        ),
    )
    .unwrap();
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&case, &serial, 1, &[], Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (end, reference) = final_states(&serial);
    assert!((end - 5.0e-4).abs() < 1e-12, "{end}");
    assert_eq!(reference.len(), 500, "all three batches poured");
    for (ranks, grid) in [(2, "[1,1,2]"), (4, "[2,1,2]")] {
        let out = dir.path().join(format!("ranks_{ranks}"));
        let setting = format!("parallel.process_grid={grid}");
        assert_states_match(&case, &out, ranks, &[&setting], (end, &reference));
    }
}

/// The column of the tests without gates (collapsing from the start),
/// every grain tracked, written into `dir` with the `[time]` line `time`.
fn open_column(dir: &Path, time: &str) -> PathBuf {
    let column = dir.join("column.toml");
    std::fs::write(
        &column,
        COLUMN
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TRACKED}", &tracked_all(GRAINS))
            .replace("{TIME}", time),
    )
    .unwrap();
    column
}

/// The inclined bed, the column collapse and the COCD column collapse on 2
/// ranks, resumed on 2 ranks from their first checkpoint (step 4 of 16,
/// step 100 of 1000, step 6 of 12): the same bytes in every series as the
/// run that never stopped.
#[test]
fn runs_on_2_ranks_resume_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let column = open_column(dir.path(), "end = 0.005");
    let scenes: [(PathBuf, Vec<&str>, &[&str], u64); 3] = [
        (
            root.join("cases/immersed_avalanche.toml"),
            vec![
                "fluid.cells=[40,12,40]",
                "time.end=0.008",
                "output.interval=0.001",
                "output.fields=false",
                "parallel.process_grid=[2,1,1]",
            ],
            &[
                "series.csv",
                "flow_series.csv",
                "bed_series.csv",
                "bed_profiles.csv",
            ],
            4,
        ),
        (
            column,
            vec!["parallel.process_grid=[2,1,1]", "output.interval=0.0005"],
            &["series.csv", "tracked.csv", "final_particles.csv"],
            100,
        ),
        // COCD's program shared by the two ranks.
        (
            root.join("cases/column_collapse_cocd_2d.toml"),
            vec![
                "parallel.process_grid=[2,1]",
                "time.end=0.012",
                "output.interval=0.004",
                // The ranks' boxes cut the column.
                "domain.upper=[0.25,0.2]",
                "particles.block[0].upper=[0.25,0.0088]",
            ],
            &["series.csv", "final_particles.csv"],
            6,
        ),
    ];
    for (case, settings, files, every) in scenes {
        let mut settings = settings;
        let every_steps = format!("checkpoint.steps={every}");
        settings.extend([every_steps.as_str(), "checkpoint.keep=100"]);
        let whole = dir.path().join("whole");
        let (code, stderr) = run(&case, &whole, 2, &settings, Duration::from_secs(300));
        assert_eq!(code, 0, "{stderr}");
        let first = std::fs::read_dir(whole.join("checkpoints"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .min()
            .unwrap();
        assert!(
            first.ends_with(format!("checkpoint_{every:012}")),
            "{first:?}"
        );
        let resumed = dir.path().join("resumed");
        // The resumed folder as the stopped run left it: later rows too.
        let checkpoint = copy_run(&whole, &resumed, every);
        resume(&case, &resumed, 2, &settings, &checkpoint);
        for file in files {
            let (a, b) = (
                std::fs::read(whole.join(file)).unwrap(),
                std::fs::read(resumed.join(file)).unwrap(),
            );
            assert!(
                a == b,
                "{case:?}: {file} differs after the restart on 2 ranks"
            );
        }
        std::fs::remove_dir_all(&whole).unwrap();
        std::fs::remove_dir_all(&resumed).unwrap();
    }
}

/// `grainflow run CASE --out OUT --restart=CHECKPOINT` on `ranks` ranks.
fn resume(case: &Path, out: &Path, ranks: usize, overrides: &[&str], checkpoint: &Path) {
    let restart = format!("--restart={}", checkpoint.display());
    let mut command = grainflow_on(ranks);
    command
        .arg("run")
        .arg(case)
        .arg("--out")
        .arg(out)
        .arg(&restart);
    for s in overrides {
        command.args(["--set", s]);
    }
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{ranks} ranks from {checkpoint:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// A copy of a run's folder, resumed there from its checkpoint at `step`.
fn copy_run(from: &Path, to: &Path, step: u64) -> PathBuf {
    let status = Command::new("cp")
        .arg("-r")
        .arg(from)
        .arg(to)
        .status()
        .unwrap();
    assert!(status.success());
    to.join(format!("checkpoints/checkpoint_{step:012}"))
}

/// Checkpoints resume on another number of ranks within the bound 1e-10
/// of the decomposition's contract: the column collapse written on 2 ranks
/// resumed on 1 and 4 (after 100 of 200 steps), the Beltrami flow written
/// on 2 ranks resumed on 1 and 4, the inclined bed written on 2 ranks
/// resumed on 1. On 4 ranks each reads only the states that hold its
/// share (and the old root's).
#[test]
fn a_checkpoint_resumes_on_another_number_of_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let column = open_column(dir.path(), "end = 0.001");
    let settings = ["checkpoint.steps=100", "checkpoint.keep=10"];
    let whole = dir.path().join("column_2");
    let (code, stderr) = run(&column, &whole, 2, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (end, reference) = final_states(&whole);
    for ranks in [1, 4] {
        let out = dir.path().join(format!("column_2_to_{ranks}"));
        let checkpoint = copy_run(&whole, &out, 100);
        resume(&column, &out, ranks, &settings, &checkpoint);
        let (other_end, states) = final_states(&out);
        assert_eq!(other_end, end);
        let largest = deviation(&reference, &states);
        println!("column, 2 ranks resumed on {ranks}: {largest:.3e}");
        assert!(largest <= 1e-10, "column on {ranks} ranks: {largest:e}");
    }

    let flow = root.join("cases/taylor_green_3d.toml");
    let settings = [
        "fluid.cells=[16,16,16]",
        "time.end=0.2",
        "output.interval=0.2",
        "checkpoint.steps=5",
        "checkpoint.keep=10",
    ];
    let whole = dir.path().join("flow_2");
    let (code, stderr) = run(&flow, &whole, 2, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let reference = read_velocity(&whole, 1);
    for ranks in [1, 4] {
        let out = dir.path().join(format!("flow_2_to_{ranks}"));
        let checkpoint = copy_run(&whole, &out, 5);
        resume(&flow, &out, ranks, &settings, &checkpoint);
        let largest = field_deviation(&reference, &read_velocity(&out, 1));
        println!("Beltrami flow, 2 ranks resumed on {ranks}: {largest:.3e}");
        assert!(largest <= 1e-10, "flow on {ranks} ranks: {largest:e}");
    }

    let bed = root.join("cases/immersed_avalanche.toml");
    let settings = [
        "fluid.cells=[40,12,40]",
        "time.end=0.005",
        "output.interval=0.005",
        "output.fields=false",
        "checkpoint.steps=4",
        "checkpoint.keep=10",
    ];
    let last_row = |out: &Path| -> Vec<f64> {
        let text = std::fs::read_to_string(out.join("bed_series.csv")).unwrap();
        let row = text.lines().last().unwrap();
        row.split(',').map(|v| v.parse().unwrap()).collect()
    };
    let whole = dir.path().join("bed_2");
    let mut on_two = settings.to_vec();
    on_two.push("parallel.process_grid=[2,1,1]");
    let (code, stderr) = run(&bed, &whole, 2, &on_two, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let out = dir.path().join("bed_2_to_1");
    let checkpoint = copy_run(&whole, &out, 4);
    resume(&bed, &out, 1, &settings, &checkpoint);
    let (reference, row) = (last_row(&whole), last_row(&out));
    let scale = reference[2..5].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (column, (a, b)) in reference.iter().zip(&row).enumerate() {
        let size = if (2..5).contains(&column) {
            scale
        } else {
            a.abs()
        };
        let deviation = (a - b).abs() / size.max(f64::MIN_POSITIVE);
        assert!(deviation <= 1e-10, "bed column {column}: {a} against {b}");
    }
}
