//! The output directory of a run (DESIGN.md, "Contracts every case follows"):
//! `case.toml`, `log.txt`, `series.csv`, `tracked.csv`, `particles/*.vtp`
//! with the ParaView index `particles.pvd`, and `summary.json`.
//! [`RunDirectory`] holds what every scene writes; [`Outputs`] adds the
//! particle outputs (a fluid scene adds its fields in `fluid_simulation`).

use crate::case::Case;
use crate::RunError;
use grainflow_dem::DemSystem;
use grainflow_io::{CsvSeries, ParticleFrame, PvdIndex};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files of the output contract every scene writes: the resolved case,
/// the log, the (possibly empty) `tracked.csv` and the summary.
pub struct RunDirectory {
    pub dir: PathBuf,
    pub started: std::time::Instant,
    log: File,
    /// `t,id,x,y,z,vx,vy,vz,wx,wy,wz` of the tracked particles.
    pub tracked: CsvSeries,
}

impl RunDirectory {
    pub fn create(dir: &Path, case: &Case) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join("case.toml"), case.to_toml())?;
        let log = File::create(dir.join("log.txt"))?;
        let tracked = CsvSeries::create(
            &dir.join("tracked.csv"),
            &["t", "id", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz"],
        )?;
        Ok(RunDirectory {
            dir: dir.to_path_buf(),
            started: std::time::Instant::now(),
            log,
            tracked,
        })
    }

    /// A line in `log.txt`.
    pub fn log(&mut self, line: &str) {
        let _ = writeln!(self.log, "{line}");
        let _ = self.log.flush();
    }

    pub fn write_summary(&self, summary: &serde_json::Value) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(summary).expect("json");
        std::fs::write(self.dir.join("summary.json"), text + "\n")
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
    series: CsvSeries,
    particles: Option<PvdIndex>,
    frames: usize,
}

impl Outputs {
    pub fn create(dir: &Path, case: &Case) -> std::io::Result<Self> {
        let run = RunDirectory::create(dir, case)?;
        let series = CsvSeries::create(
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
        let particles = if case.output.particles {
            std::fs::create_dir_all(dir.join("particles"))?;
            Some(PvdIndex::new(dir.join("particles.pvd")))
        } else {
            None
        };
        Ok(Outputs {
            run,
            series,
            particles,
            frames: 0,
        })
    }

    /// A row of `series.csv` and, if enabled, a particle file.
    pub fn write_frame(&mut self, system: &DemSystem, dt: f64) -> std::io::Result<()> {
        let (translational, rotational) = system.particles.kinetic_energy();
        let last = system.last;
        self.series.row(&[
            system.time,
            dt,
            system.steps as f64,
            translational,
            rotational,
            last.particle_contacts as f64,
            last.wall_contacts as f64,
            last.max_overlap_ratio,
            system.max_speed(),
            system.neighbours.builds as f64,
            self.run.started.elapsed().as_secs_f64(),
        ])?;
        if let Some(index) = &mut self.particles {
            let p = &system.particles;
            let n = p.n_owned;
            let as_arrays = |v: &[grainflow_core::Vec3]| {
                v[..n].iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>()
            };
            let fixed: Vec<u8> = (0..n).map(|k| p.is_fixed(k) as u8).collect();
            let name = format!("particles/particles_{:06}.vtp", self.frames);
            ParticleFrame {
                id: &p.id[..n],
                position: &as_arrays(&p.position),
                velocity: &as_arrays(&p.velocity),
                angular_velocity: &as_arrays(&p.angular_velocity),
                force: &as_arrays(&p.force),
                radius: &p.radius[..n],
                fixed: &fixed,
            }
            .write(&self.run.dir.join(&name))?;
            index.add(system.time, &name)?;
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
        let mut file = std::io::BufWriter::new(std::fs::File::create(
            self.run.dir.join("final_particles.csv"),
        )?);
        let header = if dim == 2 {
            "x,y,radius,vx,vy"
        } else {
            "x,y,z,radius,vx,vy,vz"
        };
        writeln!(file, "{header}")?;
        let mut order: Vec<usize> = (0..p.n_owned).filter(|&k| !p.is_fixed(k)).collect();
        order.sort_by_key(|&k| p.id[k]);
        for k in order {
            let mut row: Vec<String> = (0..dim)
                .map(|a| format!("{:.17e}", p.position[k][a]))
                .collect();
            row.push(format!("{:.17e}", p.radius[k]));
            row.extend((0..dim).map(|a| format!("{:.17e}", p.velocity[k][a])));
            writeln!(file, "{}", row.join(","))?;
        }
        Ok(())
    }

    /// Rows of `tracked.csv` for the tracked ids.
    pub fn write_tracked(&mut self, system: &DemSystem, ids: &[u64]) -> std::io::Result<()> {
        let p = &system.particles;
        for &id in ids {
            if let Some(k) = system.index_of(id) {
                let (x, v, w) = (p.position[k], p.velocity[k], p.angular_velocity[k]);
                self.run.tracked.row(&[
                    system.time,
                    id as f64,
                    x.x,
                    x.y,
                    x.z,
                    v.x,
                    v.y,
                    v.z,
                    w.x,
                    w.y,
                    w.z,
                ])?;
            }
        }
        Ok(())
    }
}
