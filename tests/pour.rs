//! Grains poured during a run (`[[particles.pour]]`): each batch is released
//! its gap above the highest moving grain, on schedule, and a pour that
//! cannot run is refused before anything is written.

mod common;

use common::run_cli;
use grainflow::case::Case;
use grainflow::{scene, scene::pouring};
use grainflow_dem::DemSystem;

/// A 4 × 4 cm box, grains of 2 mm ± 10 %, batches of 8 × 8 × 3 sites.
const BOX: &str = r#"
[domain]
dimension = 3
lower = [0.0, 0.0, 0.0]
upper = [0.04, 0.04, 0.3]
gravity = [0.0, 0.0, -9.81]

[particles]
density = 2500.0
radius = 2.0e-3
radius_spread = 0.1
seed = 7

[[particles.pour]]
lower = [0.002, 0.002, 0.0]
upper = [0.038, 0.038, 0.0135]
spacing = 0.0045
jitter = 0.5
count = 500
interval = 0.03
gap = 0.005
{SETTLED}

[contact]
model = "soft"
restitution = 0.3
contact_time = 1.0e-4
friction = 0.4

[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[walls]]
point = [0.04, 0.0, 0.0]
normal = [-1.0, 0.0, 0.0]
[[walls]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[walls]]
point = [0.0, 0.04, 0.0]
normal = [0.0, -1.0, 0.0]

[time]
end = 0.2
dt_over_contact_time = 0.05
"#;

fn case(settled: &str, end: f64) -> Case {
    let text = BOX
        .replace("{SETTLED}", settled)
        .replace("end = 0.2", &format!("end = {end}"));
    Case::from_text(&text, "pour test", &[]).expect("valid case")
}

/// Highest surface of the mobile grains along z.
fn highest(system: &DemSystem) -> f64 {
    let p = &system.particles;
    (0..p.n_owned)
        .filter(|&k| !p.is_fixed(k))
        .map(|k| p.position[k].z + p.radius[k])
        .fold(f64::MIN, f64::max)
}

/// A released batch: when, its first id, how many grains, its lowest
/// surface, and the highest surface of the scene and the rms speed of the
/// previous batch just before it.
#[derive(Clone, Copy, Debug)]
struct Batch {
    time: f64,
    first_id: u64,
    grains: usize,
    lowest: f64,
    top_before: f64,
    previous_speed: f64,
}

/// Root-mean-square speed of the grains with ids in `ids`.
fn rms_speed(system: &DemSystem, ids: std::ops::Range<u64>) -> f64 {
    let p = &system.particles;
    let speeds: Vec<f64> = (0..p.n_owned)
        .filter(|&k| ids.contains(&p.id[k]))
        .map(|k| p.velocity[k].norm_squared())
        .collect();
    (speeds.iter().sum::<f64>() / speeds.len() as f64).sqrt()
}

/// Steps the scene to its end, releasing batches as a run does.
fn pour(case: &Case) -> (DemSystem, Vec<Batch>) {
    let mut system = scene::build(case).unwrap();
    let record = |system: &DemSystem, before: usize, top_before: f64, previous_speed: f64| {
        let p = &system.particles;
        let new: Vec<usize> = (0..p.n_owned)
            .filter(|&k| p.id[k] >= before as u64)
            .collect();
        let lowest = new
            .iter()
            .map(|&k| p.position[k].z - p.radius[k])
            .fold(f64::MAX, f64::min);
        Batch {
            time: system.time,
            first_id: before as u64,
            grains: new.len(),
            lowest,
            top_before,
            previous_speed,
        }
    };
    let (mut pouring, _) = pouring::start(case, &mut system).unwrap();
    let mut batches = vec![record(&system, 0, f64::MIN, 0.0)];
    let dt = 0.05 * 1e-4;
    while system.time < case.time.end - 0.5 * dt {
        system.step(dt);
        let last = batches.last().unwrap();
        let (before, top, speed) = (
            system.particles.len(),
            highest(&system),
            rms_speed(&system, last.first_id..last.first_id + last.grains as u64),
        );
        if !pouring.release_due(&mut system).unwrap().is_empty() {
            batches.push(record(&system, before, top, speed));
        }
    }
    assert!(pouring.is_done(), "released {batches:?}");
    (system, batches)
}

#[test]
fn each_batch_is_released_its_gap_above_the_highest_moving_grain() {
    let (system, batches) = pour(&case("", 0.2));
    // 8 × 8 × 3 sites a batch: 192, 192, then the 116 lowest sites.
    let sizes: Vec<usize> = batches.iter().map(|b| b.grains).collect();
    assert_eq!(sizes, vec![192, 192, 116]);
    assert_eq!(system.particles.n_owned, 500);
    let mut ids = system.particles.id.clone();
    ids.sort_unstable();
    assert_eq!(ids, (0..500).collect::<Vec<u64>>());
    // The first batch sits in its box (lowest surface within a jittered
    // site of the floor); each later one on schedule, 0.03 s apart to
    // within a step, with its lowest surface 5 mm above the highest grain.
    assert!(batches[0].lowest >= 0.0 && batches[0].lowest < 0.0045 / 2.0);
    for (k, b) in batches.iter().enumerate().skip(1) {
        let (time, lowest, top) = (b.time, b.lowest, b.top_before);
        let scheduled = 0.03 * k as f64;
        assert!(
            time >= scheduled - 1e-9 && time < scheduled + 5e-6,
            "batch {k} at t = {time}, scheduled {scheduled}"
        );
        let gap = lowest - top;
        println!("batch {k}: t = {time:.5} s, lowest surface {lowest:.5} m, gap {gap:.3e} m");
        assert!((gap - 0.005).abs() < 1e-12, "batch {k}: gap {gap}");
    }
    // Every grain ended inside the box (none escaped through a wall).
    let p = &system.particles;
    for k in 0..p.n_owned {
        let x = p.position[k];
        assert!((0.0..=0.04).contains(&x.x) && (0.0..=0.04).contains(&x.y) && x.z > 0.0);
    }
}

#[test]
fn a_batch_waits_until_the_previous_one_has_landed() {
    let (_, batches) = pour(&case("settled_speed = 0.05", 0.4));
    assert_eq!(batches.len(), 3);
    for (k, pair) in batches.windows(2).enumerate() {
        let (previous, next) = (pair[0], pair[1]);
        println!(
            "batch {}: t = {:.5} s, rms speed of the batch before it {:.4} m/s",
            k + 2,
            next.time,
            next.previous_speed
        );
        assert!(
            next.previous_speed <= 0.05,
            "released while the previous batch moved at {} m/s",
            next.previous_speed
        );
        assert!(next.time - previous.time >= 0.03 - 1e-9);
    }
    // The wait is real: the second batch, landing from 5 mm onto the
    // first, takes longer than the interval to come to rest.
    let wait = batches[2].time - batches[1].time;
    assert!(wait > 0.03 + 0.01, "third batch {wait} s after the second");
}

/// `check`'s estimate of a pour runs the scene through its first batches as
/// `grainflow run` does: the probe sees the releases the run makes, at the
/// same times, and hands on what is left of the pour.
#[test]
fn checks_probe_of_a_pour_sees_the_releases_of_the_run() {
    let case = case("settled_speed = 0.05", 0.4);
    let (_, batches) = pour(&case);
    let (probe, plan) = grainflow::check::pour_cost::run_first_batches(&case)
        .unwrap()
        .expect("a pour to probe");
    // The probe stops at its third release here: the pour is done.
    assert_eq!(probe.releases.len(), batches.len());
    for (seen, made) in probe.releases.iter().zip(&batches) {
        assert!((seen - made.time).abs() < 1e-12, "{seen} {}", made.time);
    }
    assert_eq!(probe.moving, 500);
    assert_eq!(
        (plan.remaining, plan.batch, plan.waits_for_landing),
        (0, 192, true)
    );
    assert!((plan.interval - 0.03).abs() < 1e-15 && (plan.dt - 5e-6).abs() < 1e-18);
    // Each timed step knows the grains it moved: 192, then 384, then 500.
    let counts: Vec<f64> = probe.steps.iter().map(|s| s.0).collect();
    assert_eq!(counts[0], 192.0);
    assert_eq!(*counts.last().unwrap(), 384.0);
}

#[test]
fn a_pour_that_cannot_run_is_refused_before_anything_is_written() {
    let pour = |extra: &str| {
        format!(
            "particles.pour=[{{lower = [0.0055, 0.0055, 0.0], upper = [0.0945, 0.0945, 0.1], \
             spacing = 0.0112, count = 100, interval = 0.1{extra}}}]"
        )
    };
    let cases = [
        (vec![pour("")], "domain.gravity"),
        (vec![pour(", spacing = 0.01")], "spacing"),
        (vec![pour(", interval = 0.0")], "interval"),
        (vec![pour(", gap = -0.01")], "gap"),
        (vec![pour(", settled_speed = 0.0")], "settled_speed"),
        (
            vec![pour(", settled_speed = 0.5, interval = 0.05")],
            "interval",
        ),
        (
            vec![pour("").replace("[0.0945, 0.0945, 0.1]", "[0.0945, 0.12, 0.1]")],
            "particles.pour[0].lower",
        ),
        (
            vec![pour("").replace("[0.0945, 0.0945, 0.1]", "[0.01, 0.0945, 0.1]")],
            "particles.pour[0].upper",
        ),
        (vec![pour(""), "contact.model=\"nscd\"".into()], "dry scene"),
    ];
    for (overrides, named) in cases {
        let mut all: Vec<&str> = overrides.iter().map(String::as_str).collect();
        // All but the first case have gravity.
        if named != "domain.gravity" {
            all.push("domain.gravity=[0.0, 0.0, -9.81]");
        } else {
            all.push("domain.gravity=[0.0, 0.0, 0.0]");
        }
        let (code, stderr, written) = run_cli("silo_small.toml", &all);
        assert_ne!(code, Some(0), "{all:?} ran");
        assert!(stderr.contains(named), "{all:?}: {stderr}");
        assert!(!written, "{all:?} wrote its output directory");
    }
}
