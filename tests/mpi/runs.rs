//! How a run on ranks stops, refuses and resumes: a failing rank stops
//! them all, a scene that cannot be shared is refused before anything is
//! written, and a checkpoint resumes bit for bit on the same ranks and
//! within round-off on another number of them.

use super::*;

/// A rank that cannot write its piece of the particle output stops the
/// whole job with a message naming it, instead of leaving the other rank
/// waiting in the next exchange.
#[test]
fn a_rank_that_fails_stops_the_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("column.toml");
    std::fs::write(
        &case,
        COLUMN
            .replace("{TRACKED}", "")
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TIME}", "end = 10.0"),
    )
    .unwrap();
    let out = dir.path().join("out");
    // A directory where rank 1 writes its first particle piece.
    std::fs::create_dir_all(out.join("particles/particles_000000_0001.vtp")).unwrap();
    let grid = ["parallel.process_grid=[2,1,1]"];
    let (code, stderr) = run(&case, &out, 2, &grid, Duration::from_secs(60));
    assert_ne!(code, 0, "{stderr}");
    assert!(stderr.contains("error on rank 1 of 2"), "{stderr}");
    assert!(
        stderr.contains("particles_000000_0001.vtp") || stderr.contains("writing"),
        "{stderr}"
    );
}

/// What does not run on several ranks yet is refused before anything is
/// written, on every rank alike; so is a process grid that does not match
/// the ranks.
#[test]
fn scenes_not_shared_among_ranks_are_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let column = dir.path().join("column.toml");
    std::fs::write(
        &column,
        COLUMN
            .replace("{TRACKED}", "")
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TIME}", "end = 0.01"),
    )
    .unwrap();
    let cases = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases");
    for (case, overrides, expected) in [
        (
            cases.join("falling_sphere_axisymmetric.toml"),
            vec![],
            "an axisymmetric scene (domain.geometry = \"axisymmetric\")",
        ),
        (
            column,
            vec!["parallel.process_grid=[3,1,1]"],
            "parallel.process_grid = [3, 1, 1] holds 3 ranks, but the run has 2",
        ),
        // COCD: the separator is measured on the root alone, which reports.
        (
            cases.join("column_collapse_cocd_2d.toml"),
            vec!["parallel.process_grid=[3,1]"],
            "parallel.process_grid = [3, 1] holds 3 ranks, but the run has 2",
        ),
    ] {
        let out = dir.path().join("out");
        let (code, stderr) = run(&case, &out, 2, &overrides, Duration::from_secs(60));
        let name = case.display();
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert_eq!(
            stderr.matches("error:").count(),
            1,
            "{name}: one message: {stderr}"
        );
        assert!(!out.exists(), "{name}: nothing is written");
    }
}

/// The column of the tests without gates (collapsing from the start),
/// every grain tracked, written into `dir` with the `[time]` line `time`.
fn open_column(dir: &Path, time: &str) -> PathBuf {
    let column = dir.join("column.toml");
    std::fs::write(
        &column,
        COLUMN
            .replace("{BLOCK}", RANDOM_BLOCK)
            .replace("{GATES}", "")
            .replace("{TRACKED}", &tracked_all(GRAINS))
            .replace("{TIME}", time),
    )
    .unwrap();
    column
}

/// The inclined bed, the column collapse and the COCD column collapse on 2
/// ranks, resumed on 2 ranks from their first checkpoint (step 4 of 16,
/// step 100 of 1000, step 6 of 12): the same bytes in every series as the
/// run that never stopped.
#[test]
fn runs_on_2_ranks_resume_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let column = open_column(dir.path(), "end = 0.005");
    let scenes: [(PathBuf, Vec<&str>, &[&str], u64); 3] = [
        (
            root.join("cases/immersed_avalanche.toml"),
            vec![
                "fluid.cells=[40,12,40]",
                "time.end=0.008",
                "output.interval=0.001",
                "output.fields=false",
                "parallel.process_grid=[2,1,1]",
            ],
            &[
                "series.csv",
                "flow_series.csv",
                "bed_series.csv",
                "bed_profiles.csv",
            ],
            4,
        ),
        (
            column,
            vec!["parallel.process_grid=[2,1,1]", "output.interval=0.0005"],
            &["series.csv", "tracked.csv", "final_particles.csv"],
            100,
        ),
        // COCD's program shared by the two ranks.
        (
            root.join("cases/column_collapse_cocd_2d.toml"),
            vec![
                "parallel.process_grid=[2,1]",
                "time.end=0.012",
                "output.interval=0.004",
                // The ranks' boxes cut the column.
                "domain.upper=[0.25,0.2]",
                "particles.block[0].upper=[0.25,0.0088]",
            ],
            &["series.csv", "final_particles.csv"],
            6,
        ),
    ];
    for (case, settings, files, every) in scenes {
        let mut settings = settings;
        let every_steps = format!("checkpoint.steps={every}");
        settings.extend([every_steps.as_str(), "checkpoint.keep=100"]);
        let whole = dir.path().join("whole");
        let (code, stderr) = run(&case, &whole, 2, &settings, Duration::from_secs(300));
        assert_eq!(code, 0, "{stderr}");
        let first = std::fs::read_dir(whole.join("checkpoints"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .min()
            .unwrap();
        assert!(
            first.ends_with(format!("checkpoint_{every:012}")),
            "{first:?}"
        );
        let resumed = dir.path().join("resumed");
        // The resumed folder as the stopped run left it: later rows too.
        let checkpoint = copy_run(&whole, &resumed, every);
        resume(&case, &resumed, 2, &settings, &checkpoint);
        for file in files {
            let (a, b) = (
                std::fs::read(whole.join(file)).unwrap(),
                std::fs::read(resumed.join(file)).unwrap(),
            );
            assert!(
                a == b,
                "{case:?}: {file} differs after the restart on 2 ranks"
            );
        }
        std::fs::remove_dir_all(&whole).unwrap();
        std::fs::remove_dir_all(&resumed).unwrap();
    }
}

/// `grainflow run CASE --out OUT --restart=CHECKPOINT` on `ranks` ranks.
fn resume(case: &Path, out: &Path, ranks: usize, overrides: &[&str], checkpoint: &Path) {
    let restart = format!("--restart={}", checkpoint.display());
    let mut command = grainflow_on(ranks);
    command
        .arg("run")
        .arg(case)
        .arg("--out")
        .arg(out)
        .arg(&restart);
    for s in overrides {
        command.args(["--set", s]);
    }
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{ranks} ranks from {checkpoint:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// A copy of a run's folder, resumed there from its checkpoint at `step`.
fn copy_run(from: &Path, to: &Path, step: u64) -> PathBuf {
    let status = Command::new("cp")
        .arg("-r")
        .arg(from)
        .arg(to)
        .status()
        .unwrap();
    assert!(status.success());
    to.join(format!("checkpoints/checkpoint_{step:012}"))
}

/// Checkpoints resume on another number of ranks within the bound 1e-10
/// of the decomposition's contract: the column collapse written on 2 ranks
/// resumed on 1 and 4 (after 100 of 200 steps), the Beltrami flow written
/// on 2 ranks resumed on 1 and 4, the inclined bed written on 2 ranks
/// resumed on 1. On 4 ranks each reads only the states that hold its
/// share (and the old root's).
#[test]
fn a_checkpoint_resumes_on_another_number_of_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let column = open_column(dir.path(), "end = 0.001");
    let settings = ["checkpoint.steps=100", "checkpoint.keep=10"];
    let whole = dir.path().join("column_2");
    let (code, stderr) = run(&column, &whole, 2, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let (end, reference) = final_states(&whole);
    for ranks in [1, 4] {
        let out = dir.path().join(format!("column_2_to_{ranks}"));
        let checkpoint = copy_run(&whole, &out, 100);
        resume(&column, &out, ranks, &settings, &checkpoint);
        let (other_end, states) = final_states(&out);
        assert_eq!(other_end, end);
        let largest = deviation(&reference, &states);
        println!("column, 2 ranks resumed on {ranks}: {largest:.3e}");
        assert!(largest <= 1e-10, "column on {ranks} ranks: {largest:e}");
    }

    let flow = root.join("cases/taylor_green_3d.toml");
    let settings = [
        "fluid.cells=[16,16,16]",
        "time.end=0.2",
        "output.interval=0.2",
        "checkpoint.steps=5",
        "checkpoint.keep=10",
    ];
    let whole = dir.path().join("flow_2");
    let (code, stderr) = run(&flow, &whole, 2, &settings, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let reference = read_velocity(&whole, 1);
    for ranks in [1, 4] {
        let out = dir.path().join(format!("flow_2_to_{ranks}"));
        let checkpoint = copy_run(&whole, &out, 5);
        resume(&flow, &out, ranks, &settings, &checkpoint);
        let largest = field_deviation(&reference, &read_velocity(&out, 1));
        println!("Beltrami flow, 2 ranks resumed on {ranks}: {largest:.3e}");
        assert!(largest <= 1e-10, "flow on {ranks} ranks: {largest:e}");
    }

    let bed = root.join("cases/immersed_avalanche.toml");
    let settings = [
        "fluid.cells=[40,12,40]",
        "time.end=0.005",
        "output.interval=0.005",
        "output.fields=false",
        "checkpoint.steps=4",
        "checkpoint.keep=10",
    ];
    let whole = dir.path().join("bed_2");
    let mut on_two = settings.to_vec();
    on_two.push("parallel.process_grid=[2,1,1]");
    let (code, stderr) = run(&bed, &whole, 2, &on_two, Duration::from_secs(120));
    assert_eq!(code, 0, "{stderr}");
    let out = dir.path().join("bed_2_to_1");
    let checkpoint = copy_run(&whole, &out, 4);
    resume(&bed, &out, 1, &settings, &checkpoint);
    let (reference, row) = (last_bed_row(&whole), last_bed_row(&out));
    let deviations = bed_row_deviations(&reference, &row);
    for (column, ((a, b), deviation)) in reference.iter().zip(&row).zip(deviations).enumerate() {
        assert!(deviation <= 1e-10, "bed column {column}: {a} against {b}");
    }
}
