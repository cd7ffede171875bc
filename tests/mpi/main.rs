//! Runs on several MPI ranks give the serial run's results (built with
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

mod fluid;
mod grains;
mod hard_contact;
mod runs;

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

/// The last row of a run's `bed_series.csv` (the inclined bed's series).
fn last_bed_row(out: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(out.join("bed_series.csv")).unwrap();
    let row = text.lines().last().unwrap();
    row.split(',').map(|v| v.parse().unwrap()).collect()
}

/// The deviation of each column of a bed series' `row` from `reference`:
/// the velocity columns (2–4) against the largest of them, the others
/// against their own size.
fn bed_row_deviations(reference: &[f64], row: &[f64]) -> Vec<f64> {
    let scale = reference[2..5].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    reference
        .iter()
        .zip(row)
        .enumerate()
        .map(|(column, (a, b))| {
            let size = if (2..5).contains(&column) {
                scale
            } else {
                a.abs()
            };
            (a - b).abs() / size.max(f64::MIN_POSITIVE)
        })
        .collect()
}
