//! The outputs survive what happens to a run from outside: a run killed at
//! any moment leaves indexes whose every entry opens, and a run into the
//! folder of an earlier run leaves none of the earlier run's outputs beside
//! its own (README, "Running cases").

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn case(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name)
}

fn grainflow(case_name: &str, out: &Path, overrides: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_grainflow"));
    command
        .args(["run", case(case_name).to_str().unwrap(), "--out"])
        .arg(out)
        .args(["--threads", "1"]);
    for o in overrides {
        command.args(["--set", o]);
    }
    command.stdout(Stdio::null()).stderr(Stdio::null());
    command
}

/// The `file="…"` entries of a `.pvd` index.
fn index_entries(text: &str) -> Vec<String> {
    text.split("file=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap().to_string())
        .collect()
}

/// Whether `text` is a whole VTK XML file: the declaration, the closing
/// tag, and as many data arrays closed as opened.
fn whole_vtk(text: &str) -> bool {
    text.starts_with("<?xml")
        && text.trim_end().ends_with("</VTKFile>")
        && text.matches("<DataArray").count() == text.matches("</DataArray>").count()
}

/// Whether a CSV file ends with a whole row and every row has the header's
/// columns.
fn whole_rows(text: &str) -> bool {
    let Some(header) = text.lines().next() else {
        return true;
    };
    let columns = header.split(',').count();
    text.ends_with('\n') && text.lines().all(|l| l.split(',').count() == columns)
}

/// What is wrong with the outputs in `out`, if anything: every index must
/// be whole and list only whole files, the summary and the final state are
/// absent or whole, the series end with whole rows.
fn damage(out: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for index in ["fields.pvd", "particles.pvd"] {
        let path = out.join(index);
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        if !whole_vtk(&text) {
            found.push(format!("{index} is not whole: {text:?}"));
            continue;
        }
        for entry in index_entries(&text) {
            match std::fs::read_to_string(out.join(&entry)) {
                Ok(data) if whole_vtk(&data) => {}
                Ok(data) => found.push(format!(
                    "{entry} (listed in {index}) is cut short at {} bytes",
                    data.len()
                )),
                Err(e) => found.push(format!("{entry} (listed in {index}): {e}")),
            }
        }
    }
    if let Ok(text) = std::fs::read_to_string(out.join("summary.json")) {
        if serde_json::from_str::<serde_json::Value>(&text).is_err() {
            found.push(format!("summary.json is not JSON: {text:?}"));
        }
    }
    for table in [
        "final_particles.csv",
        "series.csv",
        "flow_series.csv",
        "tracked.csv",
    ] {
        if let Ok(text) = std::fs::read_to_string(out.join(table)) {
            if !whole_rows(&text) {
                found.push(format!("{table} has a partial row"));
            }
        }
    }
    found
}

/// Kills runs that write an output at every step (fields of a flow, and
/// fields and particles of a grain in a fluid) at spread times once their
/// indexes exist; after every kill each index opens and lists only whole
/// files.
#[test]
fn a_killed_run_leaves_indexes_that_list_only_whole_files() {
    let scenes: [(&str, &[&str]); 2] = [
        (
            "taylor_green_2d.toml",
            &["time.end=20.0", "output.interval=0.01"],
        ),
        (
            "falling_disc.toml",
            &[
                "time.end=0.5",
                "output.interval=6.385e-4",
                "output.fields=true",
                "output.particles=true",
                "fluid.cells=[32,96]",
            ],
        ),
    ];
    // Spread delays from a seed that differs between test runs (printed,
    // so that a failure can be replayed by reading it).
    let mut seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos() as u64;
    println!("seed {seed}");
    let mut next_delay = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        Duration::from_micros((seed >> 33) % 400_000)
    };
    let dir = tempfile::tempdir().unwrap();
    let mut damaged = Vec::new();
    let mut kills = 0;
    for (scene, overrides) in scenes {
        for kill in 0..12 {
            let out = dir.path().join(format!("{scene}_{kill}"));
            let index = out.join("fields.pvd");
            let mut child = grainflow(scene, &out, overrides).spawn().unwrap();
            // Wait for the first output, then let the run write a while.
            let started = Instant::now();
            while !index.exists() && started.elapsed() < Duration::from_secs(20) {
                std::thread::sleep(Duration::from_millis(2));
            }
            std::thread::sleep(next_delay());
            child.kill().unwrap();
            child.wait().unwrap();
            kills += 1;
            for problem in damage(&out) {
                damaged.push(format!("{scene}, kill {kill}: {problem}"));
            }
        }
    }
    assert!(
        damaged.is_empty(),
        "{} problems after {kills} kills:\n{}",
        damaged.len(),
        damaged.join("\n")
    );
}
