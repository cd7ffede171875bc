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

/// Whether `text` is a whole VTK XML index: the declaration and the
/// closing tag.
fn whole_index(text: &str) -> bool {
    text.starts_with("<?xml") && text.trim_end().ends_with("</VTKFile>")
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
        if !whole_index(&text) {
            found.push(format!("{index} is not whole: {text:?}"));
            continue;
        }
        for entry in index_entries(&text) {
            match std::fs::read(out.join(&entry)) {
                // Every array of the file is there in full.
                Ok(data) => {
                    if let Err(e) = grainflow_io::read_vtk(&data) {
                        found.push(format!(
                            "{entry} (listed in {index}) is not whole at {} bytes: {e}",
                            data.len()
                        ));
                    }
                }
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
/// The file names under `dir` (relative), sorted.
fn files_under(dir: &Path) -> Vec<String> {
    let mut names = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let relative = path.strip_prefix(dir).unwrap();
                names.push(relative.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    names.sort();
    names
}

/// A second run into the folder of a first, longer one: the folder holds
/// the second run's outputs, none of the first run's later field and
/// particle files or the analysis tables only the first wrote (nor a
/// temporary file a killed run left), and every file the user put there.
#[test]
fn a_rerun_into_the_same_folder_leaves_no_file_of_the_earlier_run_but_the_users() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("disc");
    let base = [
        "output.interval=0.002",
        "output.fields=true",
        "output.particles=true",
        "fluid.cells=[32,96]",
    ];
    let with_end = |end: &str| {
        let mut o: Vec<String> = base.iter().map(|s| s.to_string()).collect();
        o.push(format!("time.end={end}"));
        o
    };
    let first = with_end("0.02");
    let first: Vec<&str> = first.iter().map(|s| s.as_str()).collect();
    assert!(grainflow("falling_disc.toml", &out, &first)
        .status()
        .unwrap()
        .success());
    assert!(out.join("fields/fields_000010.vti").is_file());
    assert!(out.join("particles/particles_000010.vtp").is_file());
    // What a user adds, what another kind of case of an earlier run wrote,
    // and what a killed run left.
    std::fs::write(out.join("notes.txt"), "mine\n").unwrap();
    std::fs::write(out.join("fields/view.pvsm"), "mine\n").unwrap();
    std::fs::write(out.join("collisions.csv"), "psi1\n").unwrap();
    std::fs::write(out.join("fields/fields_000011.vti.tmp"), "<?xml").unwrap();
    let before = files_under(&out);

    // A bad case touches nothing.
    let refused = grainflow("falling_disc.toml", &out, &["time.end=-1.0"])
        .status()
        .unwrap();
    assert!(!refused.success());
    assert_eq!(
        files_under(&out),
        before,
        "a refused case changed the folder"
    );

    let second = with_end("0.01");
    let second: Vec<&str> = second.iter().map(|s| s.as_str()).collect();
    assert!(grainflow("falling_disc.toml", &out, &second)
        .status()
        .unwrap()
        .success());
    let after = files_under(&out);
    // Exactly the files the second run indexes, and the user's.
    for (index, folder) in [("fields.pvd", "fields/"), ("particles.pvd", "particles/")] {
        let listed = index_entries(&std::fs::read_to_string(out.join(index)).unwrap());
        assert_eq!(listed.len(), 6, "{index}: frames at t = 0, 0.002, …, 0.01");
        let present: Vec<&String> = after
            .iter()
            .filter(|f| f.starts_with(folder) && !f.ends_with("view.pvsm"))
            .collect();
        assert_eq!(
            present,
            listed.iter().collect::<Vec<_>>(),
            "{folder} holds files the index does not list"
        );
    }
    for gone in ["collisions.csv", "fields/fields_000011.vti.tmp"] {
        assert!(!after.contains(&gone.to_string()), "{gone} survived");
    }
    for mine in ["notes.txt", "fields/view.pvsm"] {
        assert_eq!(
            std::fs::read_to_string(out.join(mine)).unwrap(),
            "mine\n",
            "the user's {mine}"
        );
    }
    assert!(
        after.iter().all(|f| !f.ends_with(".tmp")),
        "temporary files left: {after:?}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!((summary["simulated_time"].as_f64().unwrap() - 0.01).abs() < 1e-3);
}
