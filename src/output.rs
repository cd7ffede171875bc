//! The output directory of a run (DESIGN.md, "Contracts every case follows"):
//! `case.toml`, `log.txt`, `series.csv`, `tracked.csv`, `particles/*.vtp`
//! with the ParaView index `particles.pvd`, and `summary.json`.
//! [`RunDirectory`] holds what every scene writes; [`Outputs`] adds the
//! particle outputs (a fluid scene adds its fields in `fluid_simulation`).
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

use crate::case::Case;
use crate::RunError;
use grainflow_core::Communicator;
use grainflow_dem::DemSystem;
use grainflow_io::{
    temporary_path, write_particle_pieces_index, write_whole, write_whole_bytes, CsvSeries,
    ParticleFrame, PvdIndex, TEMPORARY_SUFFIX,
};
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
    "summary.json",
    "final_particles.csv",
    "fields.pvd",
    "particles.pvd",
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
    ("fields", "fields_", &["vti", "vtr", "pvti", "pvtr"]),
    ("particles", "particles_", &["vtp", "pvtp"]),
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
    Ok(removed)
}

/// The files of the output contract every scene writes: the resolved case,
/// the log, the (possibly empty) `tracked.csv` and the summary.
pub struct RunDirectory {
    pub dir: PathBuf,
    pub started: std::time::Instant,
    /// The log (on the root rank only).
    log: Option<File>,
    /// `t,id,x,y,z,vx,vy,vz,wx,wy,wz` of the tracked particles (on the
    /// root rank only).
    pub tracked: Option<CsvSeries>,
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
        let (log, tracked) = if root {
            write_whole_bytes(&dir.join("case.toml"), case.to_toml())?;
            let log = File::create(dir.join("log.txt"))?;
            let tracked = CsvSeries::create(
                &dir.join("tracked.csv"),
                &["t", "id", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz"],
            )?;
            (Some(log), Some(tracked))
        } else {
            (None, None)
        };
        let mut run = RunDirectory {
            dir: dir.to_path_buf(),
            started: std::time::Instant::now(),
            log,
            tracked,
        };
        if cleared > 0 {
            run.log(&format!(
                "removed {cleared} files an earlier run left in {}",
                dir.display()
            ));
        }
        Ok(run)
    }

    /// Whether this rank writes the shared files.
    pub fn is_root(&self) -> bool {
        self.log.is_some()
    }

    /// A line in `log.txt`, written with its newline in one write, so that
    /// a kill leaves whole lines.
    pub fn log(&mut self, line: &str) {
        if let Some(log) = &mut self.log {
            let _ = log.write_all(format!("{line}\n").as_bytes());
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
}

pub struct Outputs {
    pub run: RunDirectory,
    communicator: Communicator,
    /// `series.csv` (root only).
    series: Option<CsvSeries>,
    /// Whether particle files are written.
    particle_files: bool,
    /// `particles.pvd` (root only).
    particles: Option<PvdIndex>,
    frames: usize,
}

impl Outputs {
    pub fn create(dir: &Path, case: &Case) -> std::io::Result<Self> {
        Self::create_on(dir, case, Communicator::serial())
    }

    /// The outputs of a run seen from one rank of `communicator`.
    pub fn create_on(dir: &Path, case: &Case, communicator: Communicator) -> std::io::Result<Self> {
        let root = communicator.is_root();
        let run = RunDirectory::create_on(dir, case, &communicator)?;
        if case.output.particles {
            std::fs::create_dir_all(dir.join("particles"))?;
        }
        let series = CsvSeries::create_on(
            root,
            &dir.join("series.csv"),
            &[
                "t",
                "dt",
                "step",
                "kinetic_translational",
                "kinetic_rotational",
                "particle_contacts",
                "wall_contacts",
                "max_overlap_ratio",
                "max_speed",
                "neighbour_builds",
                "wall_seconds",
            ],
        )?;
        let particles =
            (root && case.output.particles).then(|| PvdIndex::new(dir.join("particles.pvd")));
        Ok(Outputs {
            run,
            communicator,
            series,
            particle_files: case.output.particles,
            particles,
            frames: 0,
        })
    }

    /// A row of `series.csv` and, if enabled, a particle file (collective).
    pub fn write_frame(&mut self, system: &DemSystem, dt: f64) -> std::io::Result<()> {
        let (translational, rotational) = system.particles.kinetic_energy();
        let c = &self.communicator;
        let (translational, rotational) = (c.sum(translational), c.sum(rotational));
        let max_speed = system.max_speed();
        let last = system.last;
        if let Some(series) = &mut self.series {
            series.row(&[
                system.time,
                dt,
                system.steps as f64,
                translational,
                rotational,
                last.particle_contacts as f64,
                last.wall_contacts as f64,
                last.max_overlap_ratio,
                max_speed,
                system.neighbours.builds as f64,
                self.run.started.elapsed().as_secs_f64(),
            ])?;
        }
        if self.particle_files {
            let p = &system.particles;
            let n = p.n_owned;
            let as_arrays = |v: &[grainflow_core::Vec3]| {
                v[..n].iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>()
            };
            let fixed: Vec<u8> = (0..n).map(|k| p.is_fixed(k) as u8).collect();
            let ranks = self.communicator.size();
            let name = if ranks == 1 {
                format!("particles/particles_{:06}.vtp", self.frames)
            } else {
                format!(
                    "particles/particles_{:06}_{:04}.vtp",
                    self.frames,
                    self.communicator.rank()
                )
            };
            ParticleFrame {
                id: &p.id[..n],
                position: &as_arrays(&p.position),
                velocity: &as_arrays(&p.velocity),
                angular_velocity: &as_arrays(&p.angular_velocity),
                force: &as_arrays(&p.force),
                radius: &p.radius[..n],
                fixed: &fixed,
            }
            .write(&self.run.dir.join(&name))
            .map_err(|e| std::io::Error::new(e.kind(), format!("{name}: {e}")))?;
            // Every rank's piece is whole before the root's index lists it.
            if ranks > 1 {
                self.communicator.barrier();
            }
            if let Some(index) = &mut self.particles {
                if ranks == 1 {
                    index.add(system.time, &name)?;
                } else {
                    let pieces: Vec<String> = (0..ranks)
                        .map(|r| format!("particles_{:06}_{r:04}.vtp", self.frames))
                        .collect();
                    let name = format!("particles/particles_{:06}.pvtp", self.frames);
                    write_particle_pieces_index(&self.run.dir.join(&name), &pieces)?;
                    index.add(system.time, &name)?;
                }
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// `final_particles.csv`: the mobile grains at the end, in the format a
    /// `file` block reads (`x,y[,z],radius,vx,vy[,vz]`), so that a deposit
    /// made by one run is the initial state of others.
    pub fn write_final_particles(&self, system: &DemSystem) -> std::io::Result<()> {
        let p = &system.particles;
        let dim = system.domain.dimension.count();
        // [id, x, y, z, radius, vx, vy, vz] of each mobile grain, on the root.
        let mut local = Vec::new();
        for k in (0..p.n_owned).filter(|&k| !p.is_fixed(k)) {
            local.push(f64::from_bits(p.id[k]));
            local.extend(p.position[k].iter());
            local.push(p.radius[k]);
            local.extend(p.velocity[k].iter());
        }
        let Some(pieces) = self.communicator.gather(&local) else {
            return Ok(());
        };
        let mut grains: Vec<&[f64]> = pieces.iter().flat_map(|m| m.chunks_exact(8)).collect();
        grains.sort_by_key(|g| g[0].to_bits());
        let header = if dim == 2 {
            "x,y,radius,vx,vy"
        } else {
            "x,y,z,radius,vx,vy,vz"
        };
        write_whole(&self.run.dir.join("final_particles.csv"), |file| {
            writeln!(file, "{header}")?;
            for grain in grains {
                let mut row: Vec<String> =
                    (0..dim).map(|a| format!("{:.17e}", grain[1 + a])).collect();
                row.push(format!("{:.17e}", grain[4]));
                row.extend((0..dim).map(|a| format!("{:.17e}", grain[5 + a])));
                writeln!(file, "{}", row.join(","))?;
            }
            Ok(())
        })
    }

    /// Rows of `tracked.csv` for the tracked ids, in the order of `ids`
    /// (collective: each rank hands the root the tracked grains it owns).
    pub fn write_tracked(&mut self, system: &DemSystem, ids: &[u64]) -> std::io::Result<()> {
        if ids.is_empty() {
            return Ok(());
        }
        let p = &system.particles;
        // [id, x, v, ω] of each tracked grain owned here.
        let mut local = Vec::new();
        for &id in ids {
            if let Some(k) = system.index_of(id) {
                local.push(id as f64);
                for v in [p.position[k], p.velocity[k], p.angular_velocity[k]] {
                    local.extend(v.iter());
                }
            }
        }
        let Some(pieces) = self.communicator.gather(&local) else {
            return Ok(());
        };
        let rows: std::collections::HashMap<u64, &[f64]> = pieces
            .iter()
            .flat_map(|m| m.chunks_exact(10))
            .map(|r| (r[0] as u64, r))
            .collect();
        let tracked = self
            .run
            .tracked
            .as_mut()
            .expect("the root writes tracked.csv");
        for id in ids {
            if let Some(state) = rows.get(id) {
                let mut row = vec![system.time];
                row.extend_from_slice(state);
                tracked.row(&row)?;
            }
        }
        Ok(())
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
