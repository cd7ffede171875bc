//! Checkpoints: the whole state of a run, from which it resumes bit for bit.
//!
//! A checkpoint is a folder `OUT/checkpoints/checkpoint_SSSSSSSSSSSS/` (the
//! step number) holding one `rank_RRRR.state` per rank (each rank's share
//! of the scene, the writers' records and the schedule, encoded by
//! [`grainflow_core::State`] with a checksum) and `manifest.json` (the
//! program and format version, the scene's kind, the ranks, the time and
//! step, and the resolved case). It is written as `checkpoint_….tmp/`, every
//! file synced to disk, and renamed to its final name only once complete:
//! a run killed at any moment of a write leaves the previous checkpoints
//! whole, and an unfinished `.tmp` folder that no reader takes (the next
//! write or run removes it). The oldest checkpoints beyond `checkpoint.keep`
//! are removed only after the new one is in place.
//!
//! Every file is a plain binary of named flat arrays, readable without
//! grainflow from its documented layout; HDF5 is kept for the outputs a user
//! opens (ParaView, h5py), since the default build needs no system library.

pub mod case_changes;
pub mod extent;

use grainflow_core::{Communicator, State};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The folder of a run's checkpoints, under its output folder.
pub const FOLDER: &str = "checkpoints";
const PREFIX: &str = "checkpoint_";
const UNFINISHED: &str = ".tmp";
const MANIFEST: &str = "manifest.json";

/// What a checkpoint says of itself.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    pub grainflow_version: String,
    pub state_format: u32,
    /// `dry`, `fluid` or `coupled`.
    pub kind: String,
    pub ranks: usize,
    pub time: f64,
    pub steps: u64,
    /// Why it was written: `schedule`, `signal`, `wall_limit`.
    pub reason: String,
    /// The resolved case of the run that wrote it.
    pub case: String,
    /// What each rank's state holds ([`extent`]): a resume on another
    /// number of ranks reads only the states a rank needs (empty in
    /// checkpoints that predate it: then every state).
    #[serde(default)]
    pub extents: Vec<extent::Extent>,
}

/// Why a checkpoint cannot be read.
#[derive(Debug)]
pub struct CheckpointError(pub String);

impl std::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

fn rank_file(rank: usize) -> String {
    format!("rank_{rank:04}.state")
}

/// Writes a file and puts it on disk before returning.
fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut file = File::create(path)?;
    file.write_all(bytes)?;
    file.sync_all()
}

/// Puts a folder's entries (new names, renames) on disk.
fn sync_folder(path: &Path) -> std::io::Result<()> {
    File::open(path)?.sync_all()
}

fn with_path(path: &Path, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// Writes a checkpoint of `state` (this rank's) into `out/checkpoints`
/// and keeps the last `keep` (collective). Returns its folder.
pub fn write(
    out: &Path,
    communicator: &Communicator,
    manifest: &Manifest,
    state: &State,
    keep: usize,
) -> std::io::Result<PathBuf> {
    let folder = out.join(FOLDER);
    let name = format!("{PREFIX}{:012}", manifest.steps);
    let finished = folder.join(&name);
    let unfinished = folder.join(format!("{name}{UNFINISHED}"));
    let root = communicator.is_root();
    if root {
        std::fs::create_dir_all(&folder).map_err(|e| with_path(&folder, e))?;
        // What killed writes left (this step's included).
        for entry in std::fs::read_dir(&folder).map_err(|e| with_path(&folder, e))? {
            let path = entry?.path();
            let stale = path
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(PREFIX) && n.ends_with(UNFINISHED));
            if stale {
                std::fs::remove_dir_all(&path).map_err(|e| with_path(&path, e))?;
            }
        }
        std::fs::create_dir(&unfinished).map_err(|e| with_path(&unfinished, e))?;
    }
    communicator.barrier();
    let path = unfinished.join(rank_file(communicator.rank()));
    write_synced(&path, &state.encode()).map_err(|e| with_path(&path, e))?;
    // Every rank's file is on disk before the checkpoint is declared whole.
    communicator.barrier();
    if root {
        let text = serde_json::to_string_pretty(manifest).expect("json") + "\n";
        let path = unfinished.join(MANIFEST);
        write_synced(&path, text.as_bytes()).map_err(|e| with_path(&path, e))?;
        sync_folder(&unfinished)?;
        // A checkpoint of the same step (a resumed run stopped again at
        // once) is replaced.
        if finished.exists() {
            std::fs::remove_dir_all(&finished).map_err(|e| with_path(&finished, e))?;
        }
        std::fs::rename(&unfinished, &finished).map_err(|e| with_path(&finished, e))?;
        sync_folder(&folder)?;
        let mut all = list(&folder)?;
        all.sort();
        let surplus = all.len().saturating_sub(keep.max(1));
        for (_, old) in all.into_iter().take(surplus) {
            std::fs::remove_dir_all(&old).map_err(|e| with_path(&old, e))?;
        }
    }
    communicator.barrier();
    Ok(finished)
}

/// The finished checkpoints in `folder` by step, unfinished ones left out.
fn list(folder: &Path) -> std::io::Result<Vec<(u64, PathBuf)>> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Ok(found);
    };
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let Some(step) = name
            .to_str()
            .and_then(|n| n.strip_prefix(PREFIX))
            .and_then(|n| n.parse::<u64>().ok())
        else {
            continue;
        };
        if entry.path().join(MANIFEST).is_file() {
            found.push((step, entry.path()));
        }
    }
    Ok(found)
}

/// The newest finished checkpoint of the run in `out`, if any.
pub fn latest(out: &Path) -> Option<PathBuf> {
    let mut all = list(&out.join(FOLDER)).ok()?;
    all.sort();
    all.pop().map(|(_, path)| path)
}

/// Removes every checkpoint, finished or not, from `folder` (a new run in
/// the same output folder); returns how many files went.
pub fn clear(folder: &Path) -> std::io::Result<usize> {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Ok(0);
    };
    let mut removed = 0;
    for entry in entries {
        let entry = entry?;
        let owned = entry.file_type()?.is_dir()
            && entry
                .file_name()
                .to_str()
                .is_some_and(|n| n.starts_with(PREFIX));
        if owned {
            removed += std::fs::read_dir(entry.path())?.count();
            std::fs::remove_dir_all(entry.path()).map_err(|e| with_path(&entry.path(), e))?;
        }
    }
    // Kept if the user put something there.
    let _ = std::fs::remove_dir(folder);
    Ok(removed)
}

/// Reads a checkpoint's manifest.
pub fn read_manifest(checkpoint: &Path) -> Result<Manifest, CheckpointError> {
    let path = checkpoint.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        CheckpointError(format!(
            "{} is not a finished checkpoint ({}: {e}); give a folder \
             OUT/checkpoints/checkpoint_NNNNNNNNNNNN or --restart latest",
            checkpoint.display(),
            path.display()
        ))
    })?;
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| {
        CheckpointError(format!(
            "{} is not a checkpoint manifest: {e}",
            path.display()
        ))
    })?;
    if manifest.state_format != grainflow_core::state::FORMAT_VERSION {
        return Err(CheckpointError(format!(
            "{} holds states of format {}; this grainflow reads format {}",
            checkpoint.display(),
            manifest.state_format,
            grainflow_core::state::FORMAT_VERSION
        )));
    }
    Ok(manifest)
}

/// Reads this rank's state from a checkpoint; refuses a truncated or
/// corrupted file, naming it.
pub fn read_state(checkpoint: &Path, rank: usize) -> Result<State, CheckpointError> {
    let path = checkpoint.join(rank_file(rank));
    let bytes = std::fs::read(&path)
        .map_err(|e| CheckpointError(format!("reading {}: {e}", path.display())))?;
    State::decode(&bytes).map_err(|e| CheckpointError(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(steps: u64) -> Manifest {
        Manifest {
            grainflow_version: "test".into(),
            state_format: grainflow_core::state::FORMAT_VERSION,
            kind: "dry".into(),
            ranks: 1,
            time: steps as f64 * 1e-3,
            steps,
            reason: "schedule".into(),
            case: String::new(),
            extents: Vec::new(),
        }
    }

    #[test]
    fn the_last_checkpoints_are_kept_and_an_unfinished_one_is_never_taken() {
        let dir = tempfile::tempdir().unwrap();
        let c = Communicator::serial();
        let mut state = State::new();
        for step in [10, 20, 30] {
            state.put_u64("step", step);
            write(dir.path(), &c, &manifest(step), &state, 2).unwrap();
        }
        let folder = dir.path().join(FOLDER);
        let mut kept: Vec<u64> = list(&folder).unwrap().into_iter().map(|(s, _)| s).collect();
        kept.sort();
        assert_eq!(kept, [20, 30]);
        // A write killed before its rename: a folder without the final name.
        std::fs::create_dir(folder.join(format!("{PREFIX}{:012}{UNFINISHED}", 40))).unwrap();
        let newest = latest(dir.path()).unwrap();
        assert!(newest.ends_with(format!("{PREFIX}{:012}", 30)));
        assert_eq!(read_manifest(&newest).unwrap().steps, 30);
        let mut back = read_state(&newest, 0).unwrap();
        assert_eq!(back.take_u64("step").unwrap(), 30);
        // Two files in each of the two kept; the unfinished one is empty.
        assert_eq!(clear(&folder).unwrap(), 4);
        assert!(latest(dir.path()).is_none());
    }

    #[test]
    fn a_corrupted_state_file_is_refused_with_its_name() {
        let dir = tempfile::tempdir().unwrap();
        let c = Communicator::serial();
        let mut state = State::new();
        state.put_f64s("x", &[1.0; 100]);
        let path = write(dir.path(), &c, &manifest(5), &state, 2).unwrap();
        let file = path.join(rank_file(0));
        let mut bytes = std::fs::read(&file).unwrap();
        bytes[200] ^= 1;
        std::fs::write(&file, &bytes).unwrap();
        let error = read_state(&path, 0).unwrap_err().0;
        assert!(
            error.contains("rank_0000.state") && error.contains("corrupted"),
            "{error}"
        );
        std::fs::write(&file, &bytes[..100]).unwrap();
        let error = read_state(&path, 0).unwrap_err().0;
        assert!(error.contains("truncated"), "{error}");
    }
}
