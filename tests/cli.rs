//! The command-line contract (DESIGN.md): `run` writes the output files, a
//! bad case file gets an error naming the key and what is allowed, exit code
//! non-zero, and no output directory.

use std::path::Path;
use std::process::Command;

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

fn case(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name)
        .display()
        .to_string()
}

/// What a successful `grainflow ARGS` writes to stdout (panics naming the
/// arguments if it fails).
fn stdout_of(args: &[&str]) -> String {
    let output = grainflow().args(args).output().unwrap();
    assert!(output.status.success(), "{args:?}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// The number written right after `words` in `line` (panics naming the
/// line if there is none).
fn number_after<T: std::str::FromStr>(line: &str, words: &str) -> T {
    line.split(words)
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{line}"))
}

/// Runs `grainflow run` on a case with overrides into a fresh directory;
/// returns (exit code, stderr, whether the output directory exists).
fn run_with(overrides: &[&str]) -> (i32, String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut command = grainflow();
    command.args([
        "run",
        &case("bouncing_dry.toml"),
        "--out",
        out.to_str().unwrap(),
    ]);
    for o in overrides {
        command.args(["--set", o]);
    }
    let result = command.output().unwrap();
    (
        result.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&result.stderr).into_owned(),
        out.exists(),
    )
}

#[test]
fn a_run_writes_every_output_of_the_contract() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bounce");
    let status = grainflow()
        .args([
            "run",
            &case("bouncing_dry.toml"),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--set", "time.end=0.2", "--set", "output.particles=true"])
        .status()
        .unwrap();
    assert!(status.success());
    for file in [
        "case.toml",
        "log.txt",
        "series.csv",
        "tracked.csv",
        "summary.json",
        "particles.pvd",
    ] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    // The resolved case carries the override.
    let resolved = std::fs::read_to_string(out.join("case.toml")).unwrap();
    assert!(resolved.contains("end = 0.2"), "{resolved}");
    // Every particle file named by the ParaView index exists.
    let index = std::fs::read_to_string(out.join("particles.pvd")).unwrap();
    let files: Vec<&str> = index
        .split("file=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert_eq!(
        files.len(),
        21,
        "one frame per output interval (0.01 s over 0.2 s) plus t = 0"
    );
    for f in files {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // tracked.csv has the contract's header and rows for particle 0.
    let tracked = std::fs::read_to_string(out.join("tracked.csv")).unwrap();
    assert!(tracked.starts_with("t,id,x,y,z,vx,vy,vz,wx,wy,wz\n"));
    assert!(tracked.lines().count() > 100);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "wall_seconds",
        "steps",
        "particle_steps_per_second",
        "metrics",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
}

#[test]
fn an_unknown_key_is_named_and_nothing_is_written() {
    let (code, stderr, written) = run_with(&["contact.stifness=3"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("stifness"), "{stderr}");
    assert!(!written);
}

#[test]
fn a_wrong_type_is_named_and_nothing_is_written() {
    let (code, stderr, written) = run_with(&["particles.density=\"heavy\""]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("density") || stderr.contains("invalid type"),
        "{stderr}"
    );
    assert!(!written);
}

#[test]
fn out_of_range_values_name_the_key_and_the_allowed_range() {
    for (assignment, key, allowed) in [
        (
            "contact.restitution=1.5",
            "contact.restitution",
            "0 < restitution ≤ 1",
        ),
        ("domain.dimension=4", "domain.dimension", "2 or 3"),
        (
            "contact.model=\"rigid\"",
            "contact.model",
            "`soft`, `cocd`, `nscd`",
        ),
        ("particles.radius=-1.0", "particles.radius", "positive"),
        (
            "time.dt_over_contact_time=1.0",
            "time step",
            "stability limit",
        ),
    ] {
        let (code, stderr, written) = run_with(&[assignment]);
        assert_eq!(code, 2, "{assignment}: {stderr}");
        assert!(
            stderr.contains(key) && stderr.contains(allowed),
            "{assignment}: {stderr}"
        );
        assert!(!written, "{assignment} wrote an output directory");
    }
}

#[test]
fn inconsistent_contact_parameters_are_refused() {
    let (code, stderr, _) = run_with(&["contact.stiffness=1.0e5"]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("either restitution and contact_time, or stiffness and damping"),
        "{stderr}"
    );
}

#[test]
fn check_reports_the_models_and_the_time_step_limits() {
    let output = grainflow()
        .args(["check", &case("silo_small.toml")])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    for expected in [
        "soft-sphere DEM",
        "no fluid grid",
        "glued",
        "t_c = 1.0000e-4",
        "stable dt <=",
    ] {
        assert!(
            text.contains(expected),
            "check output lacks {expected:?}:\n{text}"
        );
    }
}

#[test]
fn check_warns_between_the_accuracy_and_the_stability_limit() {
    let output = grainflow()
        .args([
            "check",
            &case("bouncing_dry.toml"),
            "--set",
            "time.dt_over_contact_time=0.2",
        ])
        .output()
        .unwrap();
    assert!(output.status.success());
    assert!(String::from_utf8_lossy(&output.stdout).contains("warning"));
    let refused = grainflow()
        .args([
            "check",
            &case("bouncing_dry.toml"),
            "--set",
            "time.dt_over_contact_time=0.5",
        ])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
}

/// COCD looser than 1e-4 lets grains at rest on a slope creep (an
/// erodible layer at 22° flowed ahead of the front at ε = 1e-3 and held at
/// 1e-4): `check` warns above it and not at it.
#[test]
fn check_warns_of_a_cocd_tolerance_too_loose_to_hold_grains_at_rest() {
    let loose = stdout_of(&[
        "check",
        &case("static_box.toml"),
        "--set",
        "contact.tolerance=1e-3",
    ]);
    assert!(
        loose.contains("warning: contact.tolerance = 1.0e-3 is looser than 1e-4"),
        "{loose}"
    );
    let held = stdout_of(&[
        "check",
        &case("static_box.toml"),
        "--set",
        "contact.tolerance=1e-4",
    ]);
    assert!(!held.contains("contact.tolerance ="), "{held}");
}

/// Hard contact's slow flows slow down with the step: a layer on a 22°
/// slope flowed 4 to 5 times slower under COCD at Δt = √(d/g) than at 0.07
/// √(d/g). `check` warns above 0.1 √(d/g) and names the step that holds:
/// the 2D box's discs (mean d = 3.984 mm, √(d/g) = 20.15 ms) warn at
/// 2.5 ms and not at 2 ms; `run` logs the same warning.
#[test]
fn check_and_run_warn_of_a_hard_contact_step_long_against_the_grains_fall_time() {
    let long = stdout_of(&["check", &case("static_box.toml"), "--set", "time.dt=2.5e-3"]);
    assert!(
        long.contains("warning: time.dt = 2.500e-3 s is 0.12 times the grains' fall time"),
        "{long}"
    );
    assert!(long.contains("use time.dt ≤ 2.015e-3 s"), "{long}");
    let held = stdout_of(&["check", &case("static_box.toml"), "--set", "time.dt=2e-3"]);
    assert!(!held.contains("warning: time.dt"), "{held}");
    let out = tempfile::tempdir().unwrap();
    let run = out.path().join("run");
    stdout_of(&[
        "run",
        &case("static_box.toml"),
        "--out",
        run.to_str().unwrap(),
        "--set",
        "time.dt=2.5e-3",
        "--set",
        "time.end=5e-3",
    ]);
    let log = std::fs::read_to_string(run.join("log.txt")).unwrap();
    assert!(
        log.contains("warning: time.dt = 2.500e-3 s is 0.12"),
        "{log}"
    );
}

/// A hard-contact step stopped at its iteration cap has forces where the
/// solver stood: NSCD held to 5 sweeps on the 2D box stops every one of
/// its 10 steps there, and the run's report says so, with the largest
/// complementarity and what to change; COCD's interior point, which
/// reaches its tolerance, says nothing. (NSCD's 5,000 default sweeps do
/// not reach 1e-6 on this box either: 3.1e-6.)
#[test]
fn a_run_whose_hard_steps_stop_at_the_iteration_cap_says_so() {
    let out = tempfile::tempdir().unwrap();
    let case = case("static_box.toml");
    let run = |name: &str, settings: &[&str]| {
        let dir = out.path().join(name);
        let mut args = vec![
            "run",
            &case,
            "--out",
            dir.to_str().unwrap(),
            "--set",
            "time.end=0.01",
        ];
        args.extend(settings);
        stdout_of(&args)
    };
    let capped = run(
        "capped",
        &[
            "--set",
            "contact.model=\"nscd\"",
            "--set",
            "contact.max_iterations=5",
        ],
    );
    assert!(
        capped.contains("warning: 10 of 10 step(s) stopped at contact.max_iterations"),
        "{capped}"
    );
    assert!(
        capped.contains("shorten time.dt or raise contact.max_iterations"),
        "{capped}"
    );
    let converged = run("converged", &[]);
    assert!(
        !converged.contains("stopped at contact.max_iterations"),
        "{converged}"
    );
}

/// `check --ranks N` shows, before a cluster job, how a scene would be
/// shared: the process grid, each rank's load (the 2,700 grains of the 3D
/// column, the 32³ cells of the Beltrami flow), the warning when ranks hold
/// too little, the separator of a COCD program, and the refusal of what does
/// not run on several ranks.
#[test]
fn check_shows_how_a_scene_is_shared_among_ranks() {
    let column = stdout_of(&["check", &case("column_collapse_3d.toml"), "--ranks", "4"]);
    assert!(column.contains("on 4 MPI ranks:"), "{column}");
    assert!(column.contains("process grid 2 x 2 x 1"), "{column}");
    // 2,700 grains over 4 ranks.
    assert!(column.contains("(mean 675)"), "{column}");
    assert!(
        column.contains("675 grains per rank (below 10000)"),
        "{column}"
    );
    // Under COCD the factor's work dwarfs the exchanges: 800 spheres a
    // rank ran at an efficiency of 0.95, and no such warning is given.
    let hard = stdout_of(&["check", &case("static_box_3d.toml"), "--ranks", "2"]);
    assert!(hard.contains("(mean 800)"), "{hard}");
    assert!(!hard.contains("grains per rank (below"), "{hard}");
    let flow = stdout_of(&["check", &case("taylor_green_3d.toml"), "--ranks", "4"]);
    assert!(flow.contains("process grid 2 x 2 x 1"), "{flow}");
    // 32³ cells over 2 x 2 ranks, the last axis whole.
    assert!(
        flow.contains("fluid cells per rank: 8192 to 8192"),
        "{flow}"
    );
    assert!(
        flow.contains("8192 cells per rank (below 100000)"),
        "{flow}"
    );
    let chosen = stdout_of(&[
        "check",
        &case("taylor_green_3d.toml"),
        "--ranks",
        "2",
        "--set",
        "fluid.cells=[128,128,128]",
    ]);
    assert!(!chosen.contains("warning: "), "{chosen}");
    // COCD on two ranks, with the separator the ranks factorise together:
    // 400 discs, three unknowns each, cut across the box's height (the
    // shorter cut) among the discs so that the ranks' interiors match: the
    // upper box holds 210 discs, 19 of them in the separator (the discs
    // above the cut that pair with one below), the lower 190 (570 and 573
    // unknowns of their own; at the discs' median height, 200 each, the
    // separator held 54 unknowns and the interiors 600 and 546; with a
    // layer one interaction range wide taken for the separator, 564 and
    // 579).
    let boxed = stdout_of(&["check", &case("static_box.toml"), "--ranks", "2"]);
    assert!(
        boxed.contains(
            "COCD on 2 ranks (process grid 1 x 2 x 1): the contact program's separator: 57 \
             of 1200 unknowns"
        ) && boxed
            .contains("boxes cut among the grains for equal interiors along the split axes: y = ")
            && boxed.contains("grains per rank at the start: 190 to 210")
            && boxed.contains("ranks' interiors 570 to 573 unknowns"),
        "{boxed}"
    );
    // An axisymmetric scene runs on one rank.
    let refused = grainflow()
        .args([
            "check",
            &case("falling_sphere_axisymmetric.toml"),
            "--ranks",
            "2",
        ])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    let refusal = String::from_utf8_lossy(&refused.stderr);
    assert!(refusal.contains("an axisymmetric scene"), "{refusal}");
}

/// With `time.cfl`, `check` counts the steps at the speeds the scene is
/// set to reach instead of those of `time.dt`: on the immersed avalanche,
/// the flow gravity drives along the periodic x in the film above the
/// stored bed. The bed's plane-averaged solid fraction falls through 0.3
/// between 0.029 m (0.48) and 0.031 m (0.19) over the floor of the 0.05 m
/// box, so the film is 0.020 m deep, within a millimetre; its laminar
/// start-up reaches g_x H²/(2ν) = 0.75 m/s, and the count passes the 4,600
/// steps of time.dt (11,041 made in the full run).
#[test]
fn check_counts_the_steps_of_a_cfl_run_at_the_speeds_the_scene_reaches() {
    let output = grainflow()
        .args(["check", &case("immersed_avalanche.toml")])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("time.cfl = 0.5: about"))
        .unwrap_or_else(|| panic!("{text}"));
    let number_after = |marker: &str| -> f64 {
        let rest = &line[line.find(marker).unwrap_or_else(|| panic!("{line}")) + marker.len()..];
        rest.split_whitespace().next().unwrap().parse().unwrap()
    };
    let depth = number_after("in a film ");
    assert!((depth - 0.020).abs() < 1e-3, "{line}");
    let steps = number_after("about ");
    assert!(steps > 4600.0, "{line}");
    assert!(
        text.contains(&format!("for {steps:.0} steps adapted to CFL 0.5")),
        "{text}"
    );
}

/// `check` runs a pour through its first batches before estimating it: the
/// full silo (`cases/silo.toml`) releases 35,868 grains in batches of 245;
/// after the probe's (four, or fewer where its time budget runs out), the
/// rest of the 147 batches are summed, each landing in the time measured
/// between the probe's releases.
#[test]
fn check_runs_a_pour_through_its_first_batches_and_sums_the_rest() {
    let output = grainflow()
        .args(["check", &case("silo.toml")])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("estimated wall time on this machine"))
        .unwrap_or_else(|| panic!("{text}"));
    // The probe runs up to four batches within its wall-time budget (three
    // on a loaded host); the rest of the 147 are summed.
    let (probed, summed): (usize, usize) = (
        number_after(line, "the first "),
        number_after(line, "then "),
    );
    assert!(
        (2..=4).contains(&probed) && probed + summed == 147,
        "{line}"
    );
    assert!(
        line.contains(&format!("measured on the first {probed} batches"))
            && line.contains("per grain in motion"),
        "{line}"
    );
    // The batch time read from the line: the silo's batches land in about
    // 0.17–0.19 s (the run's log), never the pour's 0.03 s interval.
    let landing: f64 = number_after(line, "one batch landing every ");
    assert!((0.15..0.21).contains(&landing), "{landing}");
}

/// Grains that start apart and will pack cost several times more a step
/// once packed than `check`'s probe times at the start (a column of 2,700
/// spheres rained on a floor: 5.2 times, `docs/performance.md`): `check`
/// says so, counts the steps after the highest grain's fall at the packed
/// cost, and leaves a lone grain, which never packs, as timed.
#[test]
fn check_counts_the_steps_of_grains_that_will_pack_at_the_packed_cost() {
    let text = |name: &str| {
        let output = grainflow().args(["check", &case(name)]).output().unwrap();
        assert!(output.status.success());
        String::from_utf8_lossy(&output.stdout).into_owned()
    };
    let rain = text("column_collapse_2d.toml");
    let line = rain
        .lines()
        .find(|l| l.contains("the grains start apart"))
        .unwrap_or_else(|| panic!("{rain}"));
    assert!(line.contains("counted at 2.2 times"), "{line}");
    // 400 discs rained from up to about 0.5 m: the highest lands after
    // √(2H/g), about a third of a second.
    let landed: f64 = number_after(line, "the steps after t = ");
    assert!((0.2..0.45).contains(&landed), "{landed}");
    let lone = text("bouncing_dry.toml");
    assert!(lone.contains("estimated wall time"), "{lone}");
    assert!(!lone.contains("the grains start apart"), "{lone}");
}

/// A fluid step short against the time a grain takes to cross a cell makes
/// the grains look larger under the forcing of eq. 7: `check` warns, and
/// names `coupling.forcing_step`, which, set to the calibration step,
/// removes the cause and the warning (the falling sphere at D/Δx = 4:
/// CFL 0.08 at its settling speed, against 1.00 at the forcing step), as
/// does `coupling.layer_forcing = "renewal"`, which refuses a held step
/// beside it.
#[test]
fn check_warns_of_a_short_forcing_step_unless_it_is_held() {
    let check = |extra: &[&str]| {
        let mut args = vec![
            "check".to_string(),
            case("falling_sphere.toml"),
            "--set".into(),
            "fluid.cells=[32,32,96]".into(),
            "--set".into(),
            "time.dt=5.0e-4".into(),
        ];
        for assignment in extra {
            args.push("--set".into());
            args.push(assignment.to_string());
        }
        let output = grainflow().args(&args).output().unwrap();
        assert!(output.status.success());
        String::from_utf8_lossy(&output.stdout).into_owned()
    };
    let short = check(&[]);
    assert!(
        short.contains("warning: the grains' CFL number (speed Δt/Δx) is 0.08"),
        "{short}"
    );
    assert!(short.contains("coupling.forcing_step"), "{short}");
    let held = check(&["coupling.forcing_step=6.4e-3"]);
    assert!(!held.contains("warning: the grains' CFL"), "{held}");
    assert!(
        held.contains("relaxed as eq. 7 does at a step of 6.4000e-3 s"),
        "{held}"
    );
    // Relaxed at the flow's renewal rate, the grain does not depend on the
    // step: no warning.
    let renewal = check(&["coupling.layer_forcing=\"renewal\""]);
    assert!(!renewal.contains("warning: the grains' CFL"), "{renewal}");
    assert!(
        renewal.contains("relaxed at the rate the flow renews it"),
        "{renewal}"
    );
    // At this step the viscous renewal (ν Δt/(0.8 Δx²) = 0.019) needs one
    // pass of forcing a stage; at 5e-2 s (1.92) two,
    // and `check` says so.
    assert!(!renewal.contains("passes"), "{renewal}");
    let long = check(&["coupling.layer_forcing=\"renewal\"", "time.dt=5.0e-2"]);
    assert!(
        long.contains("r dt = 1.92: a stage forces in at least 2 passes"),
        "{long}"
    );
    // A held step and the renewal rate are two answers to one question.
    let both = grainflow()
        .args(["check", &case("falling_sphere.toml"), "--set"])
        .args([
            "coupling.layer_forcing=\"renewal\"",
            "--set",
            "coupling.forcing_step=6.4e-3",
        ])
        .output()
        .unwrap();
    assert!(!both.status.success());
    let error = String::from_utf8_lossy(&both.stderr);
    assert!(error.contains("coupling.forcing_step"), "{error}");
    assert!(error.contains("renewal"), "{error}");
}

/// `check` and `run` of `case` with `overrides`: (exit code, stderr) of
/// each, and whether `run` wrote its output directory.
fn check_and_run(case_name: &str, overrides: &[&str]) -> [(i32, String); 2] {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let results = ["check", "run"].map(|verb| {
        let mut command = grainflow();
        command.args([verb, &case(case_name)]);
        if verb == "run" {
            command.args(["--out", out.to_str().unwrap()]);
        }
        for o in overrides {
            command.args(["--set", o]);
        }
        let result = command.output().unwrap();
        (
            result.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&result.stderr).into_owned(),
        )
    });
    assert!(!out.exists(), "{overrides:?}: run wrote {out:?}");
    results
}

#[test]
fn scenes_that_cannot_start_are_refused_by_check_and_run_naming_their_keys() {
    for (case_name, assignment, key) in [
        // 10¹² cells: more than any machine holds.
        (
            "taylor_green_2d.toml",
            "fluid.cells=[1000000, 1000000]",
            "fluid.cells",
        ),
        // Two moving grains placed a tenth of a millimetre apart.
        (
            "bouncing_dry.toml",
            "particles.block[0].positions=[[0.0, 0.0, 0.05], [0.0001, 0.0, 0.05]]",
            "particles.block[0] grain 1",
        ),
        // 10¹² random grains in a box that jams after about two thousand.
        (
            "column_collapse_2d.toml",
            "particles.block[0].count=1000000000000",
            "particles.block[0].count",
        ),
    ] {
        for (code, stderr) in check_and_run(case_name, &[assignment]) {
            assert_eq!(code, 2, "{assignment}: {stderr}");
            assert!(stderr.contains(key), "{assignment}: {stderr}");
        }
    }
}

/// Light grains with the load from the inner fluid momentum: `check` warns
/// below the density ratios where it was seen to hold (1.05 for a 2D disc,
/// which blew up at 0.95; 0.5 for a 3D sphere), and not above.
#[test]
fn check_warns_of_light_grains_below_the_tested_density_ratios() {
    let check = |case_name: &str, extra: &[&str]| {
        let mut command = grainflow();
        command.args(["check", &case(case_name)]);
        for assignment in extra {
            command.args(["--set", assignment]);
        }
        let output = command.output().unwrap();
        assert!(output.status.success(), "{extra:?}");
        String::from_utf8_lossy(&output.stdout).into_owned()
    };
    let light = check("falling_disc.toml", &["particles.density=100.0"]);
    assert!(
        light.contains("rho_p/rho = 0.1000 is below 1.05"),
        "{light}"
    );
    let heavy = check("falling_disc.toml", &["particles.density=1100.0"]);
    assert!(!heavy.contains("warning: density ratio"), "{heavy}");
    let sphere = ["fluid.cells=[32,32,96]", "time.dt=5.0e-4"];
    let light = check(
        "falling_sphere.toml",
        &[&sphere[..], &["particles.density=300.0"]].concat(),
    );
    assert!(light.contains("is below 0.5"), "{light}");
    let tested = check(
        "falling_sphere.toml",
        &[&sphere[..], &["particles.density=600.0"]].concat(),
    );
    assert!(!tested.contains("warning: density ratio"), "{tested}");
}

/// Bad input of every kind: exit status 2, a message naming what is wrong
/// and what is allowed, no panic, and nothing written.
#[test]
fn a_sweep_of_bad_inputs_gets_status_2_a_named_reason_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let malformed = dir.path().join("malformed.toml");
    std::fs::write(&malformed, "[time\nend = 1.0\n").unwrap();
    let a_file = dir.path().join("a_file");
    std::fs::write(&a_file, "not a folder").unwrap();
    let out = dir.path().join("out");
    let bouncing = case("bouncing_dry.toml");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec![malformed.display().to_string()], "malformed.toml"),
        (
            vec![bouncing.clone(), "--set".into(), "time.end=\"soon\"".into()],
            "time.end",
        ),
        (
            vec![bouncing.clone(), "--set".into(), "time.end=-1".into()],
            "time.end",
        ),
        (
            vec![bouncing.clone(), "--set".into(), "checkpoint.keep=0".into()],
            "checkpoint.keep",
        ),
        (
            vec![bouncing.clone(), "--set".into(), "time.wall_limit=0".into()],
            "time.wall_limit",
        ),
        (
            vec![
                bouncing.clone(),
                "--set".into(),
                "checkpoint.every=3".into(),
            ],
            "every",
        ),
        (
            vec![bouncing.clone(), "--restart".into(), "latest".into()],
            "--restart",
        ),
        (
            vec![
                bouncing.clone(),
                "--restart".into(),
                dir.path().join("nowhere").display().to_string(),
            ],
            "nowhere",
        ),
    ];
    for (args, named) in cases {
        let result = grainflow()
            .arg("run")
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(named), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    // An output folder that cannot be made: its parent is a file.
    let result = grainflow()
        .args(["run", &bouncing, "--out"])
        .arg(a_file.join("out"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--out") && stderr.contains("not a folder"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&a_file).unwrap(), "not a folder");
}

/// A coupled run whose fixed step the flow cannot take stops with status
/// 3 and a diagnosis naming the CFL number and what to change, and keeps
/// the outputs of its last good state: in 3D and in (r, z), which share
/// the diagnosis.
#[test]
fn a_coupled_run_past_the_cfl_limit_stops_with_a_diagnosis_keeping_its_outputs() {
    let scenes: [(&str, &[&str]); 2] = [
        (
            "falling_sphere.toml",
            &[
                "domain.upper=[0.04,0.04,0.12]",
                "fluid.cells=[16,16,48]",
                "particles.block[0].positions=[[0.02,0.02,0.095]]",
            ],
        ),
        ("falling_sphere_axisymmetric.toml", &[]),
    ];
    for (name, overrides) in scenes {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let mut command = grainflow();
        command.args(["run", &case(name), "--out", out.to_str().unwrap()]);
        for o in overrides.iter().chain(&["time.dt=0.05", "time.end=1.0"]) {
            command.args(["--set", o]);
        }
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(3), "{name}: {stderr}");
        assert!(
            stderr.contains("unstable at t = ")
                && stderr.contains("beyond the RK3 limit")
                && stderr.contains("reduce time.dt or set time.cfl")
                && stderr.contains("hold the last good state"),
            "{name}: {stderr}"
        );
        for file in ["summary.json", "series.csv", "tracked.csv"] {
            assert!(out.join(file).exists(), "{name}: {file}");
        }
    }
}
