//! Hard contact on ranks: NSCD within its tolerance and COCD, the conic
//! program shared among the ranks, against the serial run.

use super::*;

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
        let mut settings: Vec<&str> = scene.to_vec();
        settings.push(solver);
        let deviations = deviations_on_ranks(
            dir.path(),
            name,
            (grains, radius),
            &settings,
            &grids,
            None,
            solver,
        );
        for ((ranks, grid), largest) in grids.iter().zip(deviations) {
            assert!(largest <= 1e-10, "{name} {ranks} ranks {grid}: {largest:e}");
        }
    }
}

/// COCD's projected gradient on several ranks, the program shared as the
/// interior point's (each rank its rows; Aᵀz on the separator summed over
/// the ranks each iteration, every decision taken on sums over all ranks),
/// on the scenes of [`cocd_on_2_and_4_ranks_matches_the_serial_run`]:
///
/// - the 2D column at ε = 1e-8 (about 3,500 iterations a step): the
///   iterates are one rank's up to the order of the sums, and the states
///   agree within 1e-10. Measured (2026-12-06): 1.7e-12 (2 ranks), 3.8e-12
///   (4, 2 × 2) after 5 steps.
/// - the jammed 3D box slumping under tilted gravity at ε = 1e-5 (5,000 to
///   6,900 iterations a step from rest): over so many iterations along the
///   packing's flat directions (its self-stresses) the round-off of the
///   sums grows until the runs stop at other iterates, each within the
///   tolerance. The primal is strongly convex in P = M̃, so a stop at
///   relative gap ε leaves the velocities within √(2ε) of the exact step
///   relative to the motion's size, and two runs within 2√(2ε) = 8.9e-3:
///   the bound. Measured: 1.1e-3 (2 ranks), 5.9e-4 (4, 2 × 2) after 3
///   steps; the certificates below ε on every rank.
#[test]
fn the_projected_gradient_on_2_and_4_ranks_matches_the_serial_run() {
    let dir = tempfile::tempdir().unwrap();
    let gradient = "contact.conic_solver=\"projected_gradient\"";
    let column = [
        "time.end=0.005",
        "domain.upper=[0.25,0.2]",
        "particles.block[0].upper=[0.25,0.0088]",
        gradient,
    ];
    let loose: f64 = 1e-5;
    let slumping = [
        "time.end=0.003",
        "domain.gravity=[6.937,0.0,-6.937]",
        "contact.tolerance=1e-5",
        gradient,
    ];
    for (name, grains, radius, settings, grids, tolerance, bound) in [
        (
            "column_collapse_cocd_2d.toml",
            438,
            4.0e-3,
            &column[..],
            vec![(2, "[2,1]"), (4, "[2,2]")],
            None,
            1e-10,
        ),
        (
            "static_box_3d.toml",
            1600,
            5.0e-4,
            &slumping[..],
            vec![(2, "[2,1,1]"), (4, "[2,2,1]")],
            Some(loose),
            2.0 * (2.0 * loose).sqrt(),
        ),
    ] {
        let deviations = deviations_on_ranks(
            dir.path(),
            name,
            (grains, radius),
            settings,
            &grids,
            tolerance,
            "gradient",
        );
        for ((ranks, grid), largest) in grids.iter().zip(deviations) {
            assert!(largest <= bound, "{name} {ranks} ranks {grid}: {largest:e}");
        }
    }
}

/// Runs `name` of `cases/` (`grains` grains of radius `radius`, every one
/// tracked) with `settings` on one rank and on each of `grids` (ranks and
/// process grid); returns the largest deviation of each from the serial
/// run's final state: positions relative to the largest coordinate,
/// velocities to the largest speed V, spins as ωR/V. Asserts that no step
/// fell back to another solver and that the ranks' certificates (overlap
/// over the mean diameter, Coulomb's violation) hold: as the serial run's
/// where `tolerance` is None, below that ε where given (a solver whose
/// iterates leave one rank's by more than round-off). `label` names the
/// runs' folders in `dir`.
fn deviations_on_ranks(
    dir: &Path,
    name: &str,
    (grains, radius): (usize, f64),
    settings: &[&str],
    grids: &[(usize, &str)],
    tolerance: Option<f64>,
    label: &str,
) -> Vec<f64> {
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases");
    let text = std::fs::read_to_string(cases.join(name)).unwrap();
    let case = dir.join(name);
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
    let serial = dir.join(format!("{name}_{label}_serial"));
    let (code, stderr) = run(&case, &serial, 1, settings, Duration::from_secs(300));
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
    let mut deviations = Vec::new();
    for &(ranks, grid) in grids {
        let out = dir.join(format!("{name}_{label}_{ranks}_{grid}"));
        let grid = format!("parallel.process_grid={grid}");
        let mut on_ranks = settings.to_vec();
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
        println!("{name}, {label}, {ranks} ranks, {grid}: largest deviation {largest:.3e}");
        deviations.push(largest);
        // The certificates hold on the ranks as on one.
        let (a, b) = (metrics(&serial), metrics(&out));
        for key in ["max_penetration", "max_coulomb_violation"] {
            let (a, b) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
            let bound = tolerance.unwrap_or(a + 1e-12);
            assert!(b <= bound, "{key}: {b} on {ranks} ranks, {a} on one");
        }
        assert_eq!(b["fallback_steps"].as_f64(), Some(0.0));
    }
    deviations
}
