//! The flow and grains in a fluid on ranks: flows of every boundary kind,
//! the falling sphere and the inclined bed, against the serial run.

use super::*;

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
    let serial = dir.path().join("serial");
    let (code, stderr) = run(&case, &serial, 1, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let reference = last_bed_row(&serial);
    for (grid, ranks) in [("[2,1,1]", 2), ("[4,1,1]", 4)] {
        let out = dir.path().join(format!("ranks_{ranks}"));
        let setting = format!("parallel.process_grid={grid}");
        let mut all = settings.to_vec();
        all.push(&setting);
        let (code, stderr) = run(&case, &out, ranks, &all, Duration::from_secs(120));
        assert_eq!(code, 0, "{grid}: {stderr}");
        let row = last_bed_row(&out);
        let deviations = bed_row_deviations(&reference, &row);
        for (column, ((a, b), deviation)) in reference.iter().zip(&row).zip(deviations).enumerate()
        {
            println!("{extra:?} {grid} column {column}: {a} serial, {b}: {deviation:.2e}");
            assert!(
                deviation <= 1e-10,
                "{extra:?} {grid} column {column}: {a} against {b}"
            );
        }
    }
}
