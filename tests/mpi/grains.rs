//! Soft-sphere grains on ranks: a column collapse, a grain and a contact
//! crossing a rank boundary, binary collisions and a pour, each against the
//! serial run.

use super::*;

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
