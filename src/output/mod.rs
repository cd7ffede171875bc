//! The output directory of a run (DESIGN.md, "Contracts every case follows"):
//! `case.toml`, `log.txt`, `series.csv`, `tracked.csv`, `timing.csv`,
//! `particles/*.vtp` with the ParaView index `particles.pvd`, `fields/*.vti`
//! with `fields.pvd`, `summary.json`, and `checkpoints/`.
//! [`RunDirectory`] holds what every scene writes; [`writers::Writers`]
//! gathers the writers of a scene's outputs ([`grains`], [`fields`]) and
//! what a checkpoint records of them.
//!
//! On several MPI ranks the root writes the shared files (log, series,
//! tracked particles, summary, indices) from global reductions and gathers;
//! each rank writes its own piece of every particle output
//! (`particles/particles_NNNNNN_RRRR.vtp`), which the root's
//! `particles_NNNNNN.pvtp` assembles for ParaView, once every rank has
//! written its piece.
//!
//! Files written in one go go through `grainflow_io::write_whole` (a
//! temporary sibling renamed over the file), series and the log are
//! appended a whole line per write: a killed run leaves outputs that open.

pub mod fields;
pub mod grains;
pub mod writers;

use crate::case::Case;
use crate::RunError;
use grainflow_core::Communicator;
use grainflow_io::{temporary_path, write_whole_bytes, TEMPORARY_SUFFIX};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files a run owns at the top of its output folder: every name any
/// scene writes there. A run removes those an earlier run left (with their
/// temporary `NAME.tmp`) before it writes anything, and no other file.
pub const OWNED_FILES: &[&str] = &[
    "case.toml",
    "log.txt",
    "series.csv",
    "flow_series.csv",
    "tracked.csv",
    "timing.csv",
    "summary.json",
    "final_particles.csv",
    "fields.pvd",
    "particles.pvd",
    "fields.xdmf",
    "particles.xdmf",
    "collisions.csv",
    "silo_profile.csv",
    "kinetic_to_potential.csv",
    "profiles.csv",
    "bed_profiles.csv",
    "grain_profiles.csv",
    "bed_series.csv",
];

/// The folders of a run's frames, and the files a run owns in each: the
/// prefix and the extensions of the frames, their per-rank pieces and
/// piece indexes (e.g. `fields/fields_000012.vti`,
/// `particles/particles_000003_0001.vtp`, `fields/fields_000004.pvti`).
const OWNED_FRAMES: &[(&str, &str, &[&str])] = &[
    ("fields", "fields_", &["vti", "vtr", "pvti", "pvtr", "h5"]),
    ("particles", "particles_", &["vtp", "pvtp", "h5"]),
];

/// Whether `name` (in the frame folder of `prefix`) is a frame a run
/// writes: `PREFIX` + digits and underscores + `.EXT`, or its temporary.
fn is_owned_frame(name: &str, prefix: &str, extensions: &[&str]) -> bool {
    let name = name.strip_suffix(TEMPORARY_SUFFIX).unwrap_or(name);
    let Some((stem, extension)) = name.rsplit_once('.') else {
        return false;
    };
    let Some(number) = stem.strip_prefix(prefix) else {
        return false;
    };
    !number.is_empty()
        && number.chars().all(|c| c.is_ascii_digit() || c == '_')
        && extensions.contains(&extension)
}

/// Removes from `dir` the outputs an earlier run left there: the
/// [`OWNED_FILES`], the frames of the `fields/` and `particles/` folders
/// (the folders too, once empty), and the temporary files of a killed run.
/// Every other file stays. Returns how many files were removed.
pub fn clear_earlier_run(dir: &Path) -> std::io::Result<usize> {
    let mut removed = 0;
    let mut remove = |path: &Path| match std::fs::remove_file(path) {
        Ok(()) => {
            removed += 1;
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(std::io::Error::new(
            e.kind(),
            format!("removing {} of an earlier run: {e}", path.display()),
        )),
    };
    for name in OWNED_FILES {
        let path = dir.join(name);
        remove(&path)?;
        remove(&temporary_path(&path))?;
    }
    for (folder, prefix, extensions) in OWNED_FRAMES {
        let folder = dir.join(folder);
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for entry in entries {
            let entry = entry?;
            let owned = entry.file_type()?.is_file()
                && entry
                    .file_name()
                    .to_str()
                    .is_some_and(|name| is_owned_frame(name, prefix, extensions));
            if owned {
                remove(&entry.path())?;
            }
        }
        // Kept if the user put something there.
        let _ = std::fs::remove_dir(&folder);
    }
    removed += crate::checkpoint::clear(&dir.join(crate::checkpoint::FOLDER))?;
    Ok(removed)
}

/// Refuses an output folder the run cannot write (before anything is
/// built or written): the nearest folder of `dir` that exists takes a file
/// (made and removed at once), and nothing on the way is a file.
pub fn check_writable(dir: &Path) -> Result<(), RunError> {
    let refuse = |why: String| {
        Err(RunError::Case(format!(
            "--out {}: {why}; allowed: a folder this user can create and write",
            dir.display()
        )))
    };
    let mut existing = dir;
    while !existing.exists() {
        match existing.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => existing = parent,
            _ => {
                existing = Path::new(".");
                break;
            }
        }
    }
    if !existing.is_dir() {
        return refuse(format!("{} is not a folder", existing.display()));
    }
    let probe = existing.join(format!(".grainflow-probe-{}", std::process::id()));
    match File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => refuse(format!("cannot write in {}: {e}", existing.display())),
    }
}

/// The files of the output contract every scene writes: the resolved case,
/// the log and the summary.
pub struct RunDirectory {
    pub dir: PathBuf,
    /// The log (on the root rank only) and its length in bytes.
    log: Option<(File, u64)>,
}

impl RunDirectory {
    pub fn create(dir: &Path, case: &Case) -> std::io::Result<Self> {
        Self::create_on(dir, case, &Communicator::serial())
    }

    /// The run directory seen from one rank of `communicator` (every rank
    /// calls it): the root removes what an earlier run left in `dir`
    /// ([`clear_earlier_run`]: only the names a run owns) and creates the
    /// shared files; the others wait for that, then only make sure the
    /// directory exists. Called once the case is validated and the scene
    /// built, so that a refused case leaves the folder as it was.
    pub fn create_on(
        dir: &Path,
        case: &Case,
        communicator: &Communicator,
    ) -> std::io::Result<Self> {
        let root = communicator.is_root();
        std::fs::create_dir_all(dir)?;
        let cleared = if root { clear_earlier_run(dir)? } else { 0 };
        // No rank writes into the folder before it is cleared.
        communicator.barrier();
        let log = if root {
            write_whole_bytes(&dir.join("case.toml"), case.to_toml())?;
            Some((File::create(dir.join("log.txt"))?, 0))
        } else {
            None
        };
        let mut run = RunDirectory {
            dir: dir.to_path_buf(),
            log,
        };
        if cleared > 0 {
            run.log(&format!(
                "removed {cleared} files an earlier run left in {}",
                dir.display()
            ));
        }
        Ok(run)
    }

    /// The run directory of a run resumed from a checkpoint: nothing is
    /// removed, and the log continues after the `log_length` bytes it had
    /// when the checkpoint was written.
    pub fn resume(
        dir: &Path,
        communicator: &Communicator,
        log_length: u64,
    ) -> std::io::Result<Self> {
        let log = if communicator.is_root() {
            let path = dir.join("log.txt");
            let mut file = std::fs::OpenOptions::new()
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)?;
            let found = file.metadata()?.len();
            let length = log_length.min(found);
            file.set_len(length)?;
            std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(length))?;
            Some((file, length))
        } else {
            None
        };
        Ok(RunDirectory {
            dir: dir.to_path_buf(),
            log,
        })
    }

    /// Bytes in the log so far (on the root; 0 elsewhere).
    pub fn log_length(&self) -> u64 {
        self.log.as_ref().map_or(0, |(_, length)| *length)
    }

    /// Whether this rank writes the shared files.
    pub fn is_root(&self) -> bool {
        self.log.is_some()
    }

    /// A line in `log.txt`, written with its newline in one write, so that
    /// a kill leaves whole lines.
    pub fn log(&mut self, line: &str) {
        if let Some((log, length)) = &mut self.log {
            let line = format!("{line}\n");
            if log.write_all(line.as_bytes()).is_ok() {
                *length += line.len() as u64;
            }
        }
    }

    pub fn write_summary(&self, summary: &serde_json::Value) -> std::io::Result<()> {
        if !self.is_root() {
            return Ok(());
        }
        let text = serde_json::to_string_pretty(summary).expect("json");
        write_whole_bytes(&self.dir.join("summary.json"), text + "\n")
    }

    /// The end of every run: the summary, then either the diagnosis of a
    /// failure (the run's error; the outputs keep the last good state) or
    /// the `done` line.
    pub fn finish(
        &mut self,
        summary: &serde_json::Value,
        failure: Option<String>,
        done: &str,
    ) -> Result<(), RunError> {
        self.write_summary(summary).map_err(RunError::Io)?;
        if let Some(message) = failure {
            self.log(&message);
            self.log("the outputs hold the last good state before the failure");
            return Err(RunError::Unstable(message));
        }
        self.log(done);
        Ok(())
    }

    /// A line for the log and, on the root, for the terminal (warnings).
    pub fn warn(&mut self, line: &str) {
        self.log(line);
        if self.is_root() {
            eprintln!("{line}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::is_owned_frame;

    #[test]
    fn only_the_frames_a_run_writes_are_its_own() {
        let fields = ["vti", "vtr", "pvti", "pvtr"];
        for name in [
            "fields_000012.vti",
            "fields_000012_0003.vtr",
            "fields_000004.pvti",
            "fields_000012.vti.tmp",
        ] {
            assert!(is_owned_frame(name, "fields_", &fields), "{name}");
        }
        for name in [
            "fields_final.vti",
            "my_fields_000001.vti",
            "fields_000001.png",
            "fields_.vti",
            "view.pvsm",
            "fields_000001.vti.bak",
        ] {
            assert!(!is_owned_frame(name, "fields_", &fields), "{name}");
        }
    }
}
