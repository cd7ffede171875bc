//! Hard contact from case files (Martin et al. 2022): the keys a hard
//! scene refuses, grains at rest that must stay at rest (Fig. 3) and where
//! the solver tolerance breaks that, and the certificates of each step.

mod common;

use common::{metric, run, run_cli};

/// A soft-contact key with hard contact, restitution with the inelastic
/// COCD, a hard-contact key with soft contact, hard contact in a fluid and
/// an unknown model are refused, named, and nothing is written.
#[test]
fn hard_contact_keys_are_checked_and_nothing_is_written() {
    for (case, overrides, key) in [
        (
            "static_box.toml",
            vec!["contact.restitution=0.5"],
            "contact.restitution",
        ),
        (
            "static_box.toml",
            vec!["contact.contact_time=1e-4"],
            "contact.contact_time",
        ),
        (
            "static_box.toml",
            vec!["contact.rolling_friction=0.05"],
            "contact.rolling_friction",
        ),
        (
            "static_box.toml",
            vec!["contact.tolerance=2.0"],
            "contact.tolerance",
        ),
        (
            "static_box.toml",
            vec!["contact.max_iterations=0"],
            "contact.max_iterations",
        ),
        (
            "static_box.toml",
            vec!["contact.threshold=-1e-3"],
            "contact.threshold",
        ),
        (
            "static_box.toml",
            vec!["contact.model=\"lcp\""],
            "contact.model",
        ),
        (
            "static_box.toml",
            vec!["contact.candidates=\"all\""],
            "contact.candidates",
        ),
        (
            "column_collapse_2d.toml",
            vec!["contact.candidates=\"listed\""],
            "contact.candidates",
        ),
        (
            "column_collapse_2d.toml",
            vec!["contact.tolerance=1e-6"],
            "contact.tolerance",
        ),
        (
            "falling_sphere.toml",
            vec!["contact.model=\"cocd\""],
            "contact.model",
        ),
    ] {
        let (code, stderr, written) = run_cli(case, &overrides);
        assert_ne!(code, Some(0), "{case} {overrides:?} must be refused");
        assert!(stderr.contains(key), "{case} {overrides:?}: {stderr}");
        assert!(!written, "{case} {overrides:?}: nothing may be written");
    }
}

/// 400 discs at rest in a box (`cases/static_box.toml`, 0.2 s of it).
/// COCD with ε = 1e-3 keeps E_k/E_p below 1e-8 (over the full second the
/// sweep measured 1.5e-9 at ε = 1e-3, 6.6e-9 at 3e-3 and 2.9e-6 at 1e-2:
/// docs/validation.md §8); with ε = 1e-1 the interior point stops so early
/// that the packing creeps. NSCD starts without the packing's force
/// network: while Gauss–Seidel builds it the grains stir (1.9e-8 measured
/// over the first 10 ms), then they are at rest again (1.1e-10 at 0.2 s).
/// Every step's certificates hold to ε: Coulomb's cone and non-penetration.
#[test]
fn grains_at_rest_stay_at_rest_below_the_tolerance_where_it_breaks() {
    let (summary, _dir) = run(
        "static_box.toml",
        &["contact.tolerance=1e-3", "time.end=0.2"],
    );
    let ratio = metric(&summary, "max_kinetic_to_potential");
    assert!(ratio < 1e-8, "COCD at ε = 1e-3: E_k/E_p = {ratio:e}");
    assert!(metric(&summary, "max_coulomb_violation") < 1e-3);
    assert!(metric(&summary, "max_penetration") < 1e-3);

    let (summary, _dir) = run(
        "static_box.toml",
        &["contact.tolerance=1e-1", "time.end=0.2"],
    );
    let ratio = metric(&summary, "max_kinetic_to_potential");
    assert!(ratio > 1e-8, "COCD at ε = 0.1: E_k/E_p = {ratio:e}");

    let (summary, _dir) = run(
        "static_box.toml",
        &[
            "contact.model=\"nscd\"",
            "contact.tolerance=1e-6",
            "contact.max_iterations=50000",
            "time.end=0.2",
        ],
    );
    assert_eq!(metric(&summary, "unconverged_steps"), 0.0);
    let largest = metric(&summary, "max_kinetic_to_potential");
    let last = metric(&summary, "final_kinetic_to_potential");
    assert!(largest < 1e-7 && last < 1e-9, "NSCD: {largest:e}, {last:e}");
    assert!(metric(&summary, "max_coulomb_violation") < 1e-6);
    assert!(metric(&summary, "max_penetration") < 1e-6);
}

/// COCD's projected gradient (`contact.conic_solver =
/// "projected_gradient"`) stops at ε itself where the interior point
/// overshoots it: on the 400 discs at rest it keeps them there, E_k/E_p ≤
/// 1e-8, at ε = 1e-4 (measured 6.7e-10, the interior point 1.3e-11), a
/// decade tighter than the interior point needs (at 1e-3 it measured
/// 3.3e-7: its first step, started from no impulses, stirs the packing),
/// each step's overlap and Coulomb violation within ε, no step handed to
/// the interior point.
#[test]
fn the_projected_gradient_keeps_grains_at_rest_a_decade_tighter_than_the_interior_point() {
    let (summary, _dir) = run(
        "static_box.toml",
        &[
            "contact.conic_solver=\"projected_gradient\"",
            "contact.tolerance=1e-4",
            "time.end=0.2",
        ],
    );
    let ratio = metric(&summary, "max_kinetic_to_potential");
    assert!(
        ratio < 1e-8,
        "projected gradient at ε = 1e-4: E_k/E_p = {ratio:e}"
    );
    assert!(metric(&summary, "max_coulomb_violation") < 1e-12);
    assert!(metric(&summary, "max_penetration") < 1e-4);
    assert_eq!(metric(&summary, "fallback_steps"), 0.0);
}

/// `check --ranks 2` reports the projected gradient's separator as the
/// interior point's (the same program, shared alike): its unknowns, and
/// that it exchanges them at every iteration instead of factorising Σ,
/// which sets no memory beside each rank's share of the scene.
#[test]
fn check_reports_the_projected_gradients_separator_on_several_ranks() {
    let check = |solver: &str| {
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args([
                "check",
                common::case_path("static_box_3d.toml").to_str().unwrap(),
                "--ranks",
                "2",
                "--set",
                &format!("contact.conic_solver=\"{solver}\""),
            ])
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout).to_string();
        assert!(
            output.status.success(),
            "{solver}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        stdout
    };
    let separator = |report: &str| -> String {
        let from = report
            .find("the contact program's separator:")
            .expect(report);
        let line = &report[from..];
        line[..line.find(" unknowns").expect(report)].to_string()
    };
    let (gradient, interior) = (check("projected_gradient"), check("interior_point"));
    assert_eq!(separator(&gradient), separator(&interior));
    assert!(
        gradient.contains("the projected gradient factorises nothing"),
        "{gradient}"
    );
    assert!(!interior.contains("factorises nothing"), "{interior}");
}

/// The first 0.1 s of the 2D column collapse
/// (`cases/column_collapse_cocd_2d.toml`, 410 discs released at t = 0).
/// COCD: every step's certificates hold to ε. NSCD: Coulomb's cone holds
/// exactly; Gauss–Seidel on the non-associated law may stall short of ε in
/// the flowing column (docs/validation.md §8), and the overlap after each
/// move stays within √2 times the residual it stopped at. Both columns
/// have started to spread (the front beyond the gate by a diameter).
#[test]
fn collapsing_column_keeps_its_certificates_with_both_schemes() {
    for (model, tolerance, sweeps) in [("cocd", 1e-8, 200), ("nscd", 1e-4, 1000)] {
        let (summary, _dir) = run(
            "column_collapse_cocd_2d.toml",
            &[
                &format!("contact.model=\"{model}\""),
                &format!("contact.tolerance={tolerance}"),
                &format!("contact.max_iterations={sweeps}"),
                "time.end=0.1",
                "time.rest_speed=1e-9",
            ],
        );
        assert!(
            metric(&summary, "max_coulomb_violation") < tolerance,
            "{model}"
        );
        let penetration = metric(&summary, "max_penetration");
        if model == "cocd" {
            assert_eq!(metric(&summary, "unconverged_steps"), 0.0);
            assert!(penetration < tolerance, "{model}: {penetration:e}");
        } else {
            let residual = metric(&summary, "max_complementarity");
            assert!(
                penetration <= std::f64::consts::SQRT_2 * residual,
                "{model}: overlap {penetration:e}, residual {residual:e}"
            );
        }
        let front = metric(&summary, "final_front");
        assert!(front > 0.2 + 0.008, "{model}: front {front}");
    }
}

/// Where COCD cannot start: a sphere sitting in the hole of a square bed of
/// four glued spheres (spacing 8.8 mm, d = 8 mm: contact normals 51° from
/// the vertical) and overlapping them by 1 µm. COCD's convexified cone asks
/// it to leave each at the overlap's rate plus μ |v_t|; rising, it slides
/// along each normal at tan 51° = 1.24 times its separation, so for
/// μ > 1/1.24 = 0.81 no motion does (the program is infeasible at any step
/// and tolerance). At μ = 0.9 the run stops at its first step naming the
/// overlap and what to do; at μ = 0.5 it starts, and with no overlap at
/// μ = 0.9 too.
#[test]
fn cocd_refuses_a_grain_wedged_with_overlaps_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let case = |friction: f64, overlap: f64| {
        let (radius, spacing) = (4.0e-3, 8.8e-3);
        let across = (0.5_f64).sqrt() * spacing;
        let height = ((2.0 * radius - overlap).powi(2) - across * across).sqrt();
        let h = 0.5 * spacing;
        let text = format!(
            "[domain]\ndimension = 3\nlower = [-0.02, -0.02, -0.01]\nupper = [0.02, 0.02, 0.03]\n\
             gravity = [0.0, 0.0, -9.81]\n\n[particles]\ndensity = 2500.0\nradius = {radius}\n\n\
             [[particles.block]]\nkind = \"explicit\"\nfixed = true\n\
             positions = [[{h}, {h}, 0.0], [-{h}, {h}, 0.0], [{h}, -{h}, 0.0], [-{h}, -{h}, 0.0]]\n\n\
             [[particles.block]]\nkind = \"explicit\"\npositions = [[0.0, 0.0, {height}]]\n\n\
             [contact]\nmodel = \"cocd\"\nfriction = {friction}\n\n\
             [time]\nend = 0.005\ndt = 1.0e-3\n\n[output]\ninterval = 0.005\n"
        );
        let path = dir.path().join(format!("wedged_{friction}_{overlap}.toml"));
        std::fs::write(&path, text).unwrap();
        let out = dir.path().join(format!("out_{friction}_{overlap}"));
        let result = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args([
                "run",
                path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        (
            result.status.success(),
            String::from_utf8_lossy(&result.stderr).into_owned(),
        )
    };
    let (ok, stderr) = case(0.9, 1e-6);
    assert!(!ok, "the wedged grain ran");
    assert!(
        stderr.contains("step 1)")
            && stderr.contains("overlapping by up to 1.000e-6 m")
            && stderr.contains("start from a deposit without overlaps"),
        "{stderr}"
    );
    let (ok, stderr) = case(0.5, 1e-6);
    assert!(ok, "{stderr}");
    let (ok, stderr) = case(0.9, 0.0);
    assert!(ok, "{stderr}");
}
