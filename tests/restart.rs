//! Checkpoint and restart: a run stopped and resumed ends in the same state,
//! byte for byte, as the run that never stopped, for each kind of scene;
//! its series continue without a row lost or repeated; a kill during a
//! checkpoint's write leaves one to resume from; SIGTERM stops a run with a
//! checkpoint and exit status 75; a checkpoint of another case is refused.

mod common;

use common::case_path;
use grainflow::case::Case;
use grainflow::checkpoint;
use grainflow::simulation::{self, Restart, RunOptions};
use grainflow_core::{Communicator, State};
use std::path::{Path, PathBuf};
use std::process::Command;

fn load(name: &str, overrides: &[&str]) -> Case {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Case::load(&case_path(name), &overrides).expect("case loads")
}

fn run(case: &Case, out: &Path, restart: Option<Restart>) -> simulation::Summary {
    let options = RunOptions {
        restart,
        ..RunOptions::default()
    };
    simulation::run_with(case, out, Communicator::serial(), &options).expect("run succeeds")
}

/// The checkpoints of a run, oldest first.
fn checkpoints(out: &Path) -> Vec<PathBuf> {
    let mut all: Vec<PathBuf> = std::fs::read_dir(out.join(checkpoint::FOLDER))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    all.sort();
    all
}

/// A checkpoint's state less the wall-clock records (the seconds each part
/// took), which differ between any two runs.
fn state_without_clocks(checkpoint: &Path) -> Vec<u8> {
    let mut state = checkpoint::read_state(checkpoint, 0).unwrap();
    state.take_u8s("writers").unwrap();
    if state.contains("coupled.timings") {
        state.take_f64s("coupled.timings").unwrap();
    }
    if state.contains("hard_contact.record") {
        state.take_u8s("hard_contact.record").unwrap();
    }
    state.encode()
}

/// The files of the simulation's numbers (all but the wall clock).
const COMPARED: [&str; 9] = [
    "grain_profiles.csv",
    "series.csv",
    "flow_series.csv",
    "tracked.csv",
    "final_particles.csv",
    "bed_series.csv",
    "bed_profiles.csv",
    "collisions.csv",
    "silo_profile.csv",
];

/// Runs `name` uninterrupted with a checkpoint every `every` steps, then
/// again from the checkpoint at step `every` in a copy of the folder as the
/// stopped run left it (the later checkpoints and rows still there), and
/// compares the two byte for byte.
fn resumes_bit_for_bit(name: &str, overrides: &[&str], every: u64) {
    let every_steps = format!("checkpoint.steps={every}");
    let mut all = overrides.to_vec();
    all.extend([every_steps.as_str(), "checkpoint.keep=1000"]);
    let case = load(name, &all);
    let whole = tempfile::tempdir().unwrap();
    let summary = run(&case, whole.path(), None);
    let written = checkpoints(whole.path());
    assert!(written.len() >= 3, "{name}: {} checkpoints", written.len());

    let resumed = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(whole.path()).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_file() {
            std::fs::copy(entry.path(), resumed.path().join(entry.file_name())).unwrap();
        }
    }
    let first = &written[0];
    let copy = resumed
        .path()
        .join(checkpoint::FOLDER)
        .join(first.file_name().unwrap());
    std::fs::create_dir_all(&copy).unwrap();
    for entry in std::fs::read_dir(first).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), copy.join(entry.file_name())).unwrap();
    }
    let again = run(&case, resumed.path(), Some(Restart::From(copy)));
    assert_eq!(summary.json["steps"], again.json["steps"], "{name}");
    // The metrics, less the seconds a solve took.
    let physics = |m: &serde_json::Map<String, serde_json::Value>| {
        let mut m = m.clone();
        m.retain(|key, _| !key.starts_with("seconds"));
        m
    };
    assert_eq!(
        physics(&summary.metrics),
        physics(&again.metrics),
        "{name}: metrics"
    );
    let mut compared = 0;
    for file in COMPARED {
        let (a, b) = (whole.path().join(file), resumed.path().join(file));
        if a.exists() {
            let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
            assert!(a == b, "{name}: {file} differs after the restart");
            compared += 1;
        }
    }
    assert!(compared >= 2, "{name}: compared {compared} files");
    let last = written.last().unwrap();
    let resumed_last = resumed
        .path()
        .join(checkpoint::FOLDER)
        .join(last.file_name().unwrap());
    assert!(
        state_without_clocks(last) == state_without_clocks(&resumed_last),
        "{name}: the final states differ"
    );
}

#[test]
fn a_soft_dry_scene_resumes_bit_for_bit() {
    resumes_bit_for_bit("binary_collision.toml", &["time.end=0.004"], 5000);
}

#[test]
fn a_hard_contact_scene_resumes_bit_for_bit() {
    resumes_bit_for_bit("column_collapse_cocd_2d.toml", &["time.end=0.02"], 4);
}

#[test]
fn a_fluid_resumes_bit_for_bit() {
    resumes_bit_for_bit("channel_poiseuille.toml", &["time.end=0.5"], 20);
}

#[test]
fn grains_in_a_fluid_resume_bit_for_bit() {
    resumes_bit_for_bit(
        "falling_sphere.toml",
        &[
            "time.end=0.02",
            "fluid.cells=[32,32,96]",
            "output.fields=true",
        ],
        2,
    );
}

/// The inclined bed resumed after 60 of 200 steps: its series and profiles are
/// scaled by the grains' mean diameter measured at the start, which the
/// checkpoint carries (the resumed grains come in another order).
#[test]
fn the_inclined_bed_resumes_bit_for_bit() {
    resumes_bit_for_bit(
        "immersed_avalanche.toml",
        &[
            "fluid.cells=[40,12,40]",
            "time.end=0.1",
            "output.interval=0.01",
            "output.fields=false",
            "output.particles=false",
        ],
        60,
    );
}

#[test]
fn a_finished_run_is_taken_further_with_a_later_end_time() {
    let case = load(
        "binary_collision.toml",
        &["time.end=0.004", "checkpoint.keep=1"],
    );
    let whole = tempfile::tempdir().unwrap();
    run(&case, whole.path(), None);
    let pieces = tempfile::tempdir().unwrap();
    let short = load(
        "binary_collision.toml",
        &["time.end=0.002", "checkpoint.keep=1"],
    );
    let first = run(&short, pieces.path(), None);
    assert_eq!(first.json["status"], "ok");
    run(&case, pieces.path(), Some(Restart::Latest));
    for file in ["series.csv", "collisions.csv", "final_particles.csv"] {
        let (a, b) = (
            std::fs::read(whole.path().join(file)).unwrap(),
            std::fs::read(pieces.path().join(file)).unwrap(),
        );
        assert!(a == b, "{file} differs");
    }
}

#[test]
fn the_wall_limit_stops_a_run_with_a_checkpoint_it_resumes_from() {
    // One second of wall clock for a run of many: it stops at once, with a
    // checkpoint, and resumes to the end.
    let case = load(
        "binary_collision.toml",
        &["time.end=0.004", "time.wall_limit=1"],
    );
    let dir = tempfile::tempdir().unwrap();
    let stopped = run(&case, dir.path(), None);
    let why = stopped.stopped.expect("stopped by the wall limit");
    assert!(
        why.contains("time.wall_limit") && why.contains("checkpoint_"),
        "{why}"
    );
    assert_eq!(stopped.json["status"], "stopped");
    let steps = stopped.json["steps"].as_u64().unwrap();
    assert!(steps < 20_000, "{steps} steps before the limit");
    let free = load("binary_collision.toml", &["time.end=0.004"]);
    let finished = run(&free, dir.path(), Some(Restart::Latest));
    assert_eq!(finished.json["status"], "ok");
    let whole = tempfile::tempdir().unwrap();
    run(&free, whole.path(), None);
    let (a, b) = (
        std::fs::read(whole.path().join("series.csv")).unwrap(),
        std::fs::read(dir.path().join("series.csv")).unwrap(),
    );
    assert!(a == b, "series.csv differs after the restart");
}

/// `grainflow run` of a case with arguments, without waiting.
fn start(case: &str, out: &Path, extra: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["run", case_path(case).to_str().unwrap(), "--out"])
        .arg(out)
        .args(extra)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Rows of a series so far.
fn rows(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| t.lines().count())
}

fn signal(child: &std::process::Child, name: &str) {
    let status = Command::new("kill")
        .args([format!("-{name}"), child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

const LONG_RUN: [&str; 4] = ["--set", "time.end=0.05", "--set", "output.interval=1e-4"];

#[test]
fn sigterm_stops_a_run_with_a_checkpoint_and_status_75_and_it_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let pieces = dir.path().join("pieces");
    let mut resumes = 0;
    loop {
        let mut args = LONG_RUN.to_vec();
        if resumes > 0 {
            args.extend(["--restart", "latest"]);
        }
        let child = start("binary_collision.toml", &pieces, &args);
        // Stopped twice, once it has written some rows past where it began.
        let begun = rows(&pieces.join("series.csv"));
        if resumes < 2 {
            let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
            while rows(&pieces.join("series.csv")) < begun + 20 {
                assert!(std::time::Instant::now() < deadline, "no progress");
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            signal(&child, "TERM");
        }
        let output = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        if resumes < 2 {
            assert_eq!(output.status.code(), Some(75), "{stderr}");
            assert!(stderr.contains("stopped by a signal"), "{stderr}");
            resumes += 1;
        } else {
            assert_eq!(output.status.code(), Some(0), "{stderr}");
            break;
        }
    }
    let log = std::fs::read_to_string(pieces.join("log.txt")).unwrap();
    assert_eq!(log.matches("resumed from").count(), 2, "{log}");
    let whole = dir.path().join("whole");
    let output = start("binary_collision.toml", &whole, &LONG_RUN)
        .wait_with_output()
        .unwrap();
    assert!(output.status.success());
    for file in ["series.csv", "collisions.csv", "final_particles.csv"] {
        let (a, b) = (
            std::fs::read(whole.join(file)).unwrap(),
            std::fs::read(pieces.join(file)).unwrap(),
        );
        assert!(
            a == b,
            "{file} differs between the run in pieces and the whole"
        );
    }
}

#[test]
fn a_kill_during_checkpoint_writes_leaves_a_checkpoint_to_resume_from() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // A checkpoint at every step of a 410-grain column under hard contact,
    // each synced to disk: a kill a few milliseconds after one is whole
    // lands in or around the next write.
    let settings = [
        "--set",
        "time.end=0.04",
        "--set",
        "checkpoint.steps=1",
        "--set",
        "checkpoint.keep=2",
        "--set",
        "output.interval=0.002",
    ];
    let mut args = settings.to_vec();
    args.extend(["--restart", "auto"]);
    for delay in [3u64, 11, 23, 37] {
        let mut child = start("column_collapse_cocd_2d.toml", &out, &args);
        let before = checkpoint::latest(&out);
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        while checkpoint::latest(&out) == before {
            assert!(
                std::time::Instant::now() < deadline,
                "no checkpoint written"
            );
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        std::thread::sleep(std::time::Duration::from_millis(delay));
        signal(&child, "KILL");
        child.wait().unwrap();
        let latest = checkpoint::latest(&out).expect("a checkpoint survives the kill");
        checkpoint::read_manifest(&latest).unwrap();
        let state: State = checkpoint::read_state(&latest, 0).unwrap();
        assert!(state.contains("dem.particles.position"));
    }
    // Resumed after four kills, it ends as the run that was never killed.
    let output = start("column_collapse_cocd_2d.toml", &out, &args)
        .wait_with_output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let whole = dir.path().join("whole");
    let output = start("column_collapse_cocd_2d.toml", &whole, &settings)
        .wait_with_output()
        .unwrap();
    assert!(output.status.success());
    for file in ["series.csv", "final_particles.csv"] {
        let (a, b) = (
            std::fs::read(whole.join(file)).unwrap(),
            std::fs::read(out.join(file)).unwrap(),
        );
        assert!(a == b, "{file} differs after the kills");
    }
}

/// A binary collision run in `dir/out` with a checkpoint at its end; returns
/// the run's folder.
fn a_collision_with_a_checkpoint(dir: &Path) -> PathBuf {
    let out = dir.join("out");
    let case = load(
        "binary_collision.toml",
        &["time.end=0.001", "checkpoint.keep=1"],
    );
    run(&case, &out, None);
    out
}

#[test]
fn a_checkpoint_of_another_case_is_refused_naming_the_key_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = a_collision_with_a_checkpoint(dir.path());
    let before: Vec<(PathBuf, std::time::SystemTime)> = walk(&out);
    for (overrides, expected) in [
        (vec!["contact.friction=0.9"], "contact.friction"),
        (vec!["time.dt=1e-7"], "time.dt"),
    ] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_grainflow"));
        command
            .args([
                "run",
                case_path("binary_collision.toml").to_str().unwrap(),
                "--out",
            ])
            .arg(&out)
            .args(["--restart", "latest", "--set", "time.end=0.002"]);
        for o in overrides {
            command.args(["--set", o]);
        }
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(expected) && stderr.contains("allowed"),
            "{stderr}"
        );
        assert_eq!(
            walk(&out),
            before,
            "a refused restart wrote into the folder"
        );
    }
    // A corrupted checkpoint is refused with the file named.
    let latest = checkpoint::latest(&out).unwrap();
    let file = latest.join("rank_0000.state");
    let mut bytes = std::fs::read(&file).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0xff;
    std::fs::write(&file, &bytes).unwrap();
    let before = walk(&out);
    let output = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "run",
            case_path("binary_collision.toml").to_str().unwrap(),
            "--out",
        ])
        .arg(&out)
        .args(["--restart", "latest", "--set", "time.end=0.002"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("rank_0000.state") && stderr.contains("corrupted"),
        "{stderr}"
    );
    assert_eq!(walk(&out), before);
}

/// A checkpoint resumed where the series it continues are missing (the
/// checkpoint copied alone into another folder) or cut short is refused
/// naming the file and what is allowed, writing nothing; in a copy of the
/// whole folder it resumes.
#[test]
fn a_resume_without_the_runs_series_is_refused_naming_the_file_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = a_collision_with_a_checkpoint(dir.path());
    let latest = checkpoint::latest(&out).unwrap();
    let resume_in = |folder: &Path| {
        Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args([
                "run",
                case_path("binary_collision.toml").to_str().unwrap(),
                "--out",
            ])
            .arg(folder)
            .args(["--restart", "latest", "--set", "time.end=0.002"])
            .output()
            .unwrap()
    };
    // The checkpoint alone in a new folder.
    let alone = dir.path().join("alone");
    let copied = alone
        .join(checkpoint::FOLDER)
        .join(latest.file_name().unwrap());
    std::fs::create_dir_all(&copied).unwrap();
    for entry in std::fs::read_dir(&latest).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), copied.join(entry.file_name())).unwrap();
    }
    let before = walk(&alone);
    let output = resume_in(&alone);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("series.csv") && stderr.contains("missing") && stderr.contains("allowed"),
        "{stderr}"
    );
    assert_eq!(
        walk(&alone),
        before,
        "a refused restart wrote into the folder"
    );
    // The whole folder copied, its series cut short.
    let copy = dir.path().join("copy");
    let mut stack = vec![(out.clone(), copy.clone())];
    while let Some((from, to)) = stack.pop() {
        std::fs::create_dir_all(&to).unwrap();
        for entry in std::fs::read_dir(&from).unwrap() {
            let entry = entry.unwrap();
            let target = to.join(entry.file_name());
            if entry.file_type().unwrap().is_dir() {
                stack.push((entry.path(), target));
            } else {
                std::fs::copy(entry.path(), target).unwrap();
            }
        }
    }
    let tracked = copy.join("tracked.csv");
    let length = std::fs::metadata(&tracked).unwrap().len();
    let file = std::fs::OpenOptions::new()
        .write(true)
        .open(&tracked)
        .unwrap();
    file.set_len(length - 1).unwrap();
    drop(file);
    let before = walk(&copy);
    let output = resume_in(&copy);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("tracked.csv") && stderr.contains("shorter"),
        "{stderr}"
    );
    assert_eq!(
        walk(&copy),
        before,
        "a refused restart wrote into the folder"
    );
    // Whole again, the copy resumes.
    std::fs::copy(out.join("tracked.csv"), &tracked).unwrap();
    let output = resume_in(&copy);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Every file under `dir` with its modification time.
fn walk(dir: &Path) -> Vec<(PathBuf, std::time::SystemTime)> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let entry = entry.unwrap();
            if entry.file_type().unwrap().is_dir() {
                stack.push(entry.path());
            } else {
                found.push((entry.path(), entry.metadata().unwrap().modified().unwrap()));
            }
        }
    }
    found.sort();
    found
}

/// The size `check` announces for a checkpoint is within 15 % of what a
/// run writes, for grains alone and for a fluid with a grain.
#[test]
fn the_checkpoint_size_check_announces_is_what_a_run_writes() {
    for (name, overrides) in [
        (
            "column_collapse_3d.toml",
            vec!["time.end=1e-4", "checkpoint.keep=1"],
        ),
        (
            "falling_sphere.toml",
            vec![
                "time.end=0.004",
                "fluid.cells=[32,32,96]",
                "checkpoint.keep=1",
            ],
        ),
    ] {
        let case = load(name, &overrides);
        let dir = tempfile::tempdir().unwrap();
        run(&case, dir.path(), None);
        let written = std::fs::metadata(checkpoints(dir.path())[0].join("rank_0000.state"))
            .unwrap()
            .len() as f64;
        let announced =
            grainflow::footprint::Footprint::of(&case).checkpoint_bytes(case.walls.len());
        let error = (announced / written - 1.0).abs();
        assert!(
            error < 0.15,
            "{name}: {announced} announced, {written} written"
        );
    }
}

#[test]
fn an_axisymmetric_scene_resumes_bit_for_bit() {
    resumes_bit_for_bit(
        "bouncing_sphere_axisymmetric.toml",
        &[
            "time.end=0.03",
            "fluid.cells=[60,60,130]",
            "output.fields=true",
        ],
        10,
    );
}
