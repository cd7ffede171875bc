//! The writers of a run, called by the time loop at the output times: the
//! series (`series.csv`, `flow_series.csv`, `timing.csv`), the particle and
//! field files, `tracked.csv`, and the inclined bed's profiles. Which ones
//! a run has follows from its scene (grains, a fluid, both) and the case's
//! `output` section.
//!
//! Every series except `timing.csv` holds numbers of the simulation alone,
//! so that two runs of a case, or a run stopped and resumed, write the same
//! bytes; the wall clock goes to `timing.csv`.

use super::fields::FieldFiles;
use super::grains::{grain_series_row, write_tracked, ParticleFiles, GRAIN_SERIES, TRACKED};
use super::RunDirectory;
use crate::analysis::bed::{self, BedRecord, InclinedBed};
use crate::case::{Case, OutputFormat};
use crate::simulation::model::Model;
use grainflow_core::Communicator;
use grainflow_io::CsvSeries;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Columns of the flow's series: `series.csv` of a fluid alone,
/// `flow_series.csv` of grains in a fluid.
pub const FLOW_SERIES: [&str; 6] = [
    "t",
    "dt",
    "step",
    "kinetic_energy",
    "max_cfl",
    "max_divergence",
];
const COUPLED_FLOW_SERIES: [&str; 6] = [
    "t",
    "dt",
    "step",
    "fluid_kinetic_energy",
    "max_cfl",
    "max_divergence",
];
/// Columns of `timing.csv`: the wall clock at each output, and the seconds
/// spent so far writing outputs and checkpoints.
pub const TIMING: [&str; 5] = [
    "t",
    "step",
    "wall_seconds",
    "output_seconds",
    "checkpoint_seconds",
];

/// The series every run appends to (the flow's only with grains in a
/// fluid, the tracked grains' only with grains).
const SERIES_FILE: &str = "series.csv";
const FLOW_SERIES_FILE: &str = "flow_series.csv";
const TIMING_FILE: &str = "timing.csv";
const TRACKED_FILE: &str = "tracked.csv";

/// What a checkpoint records of the writers: the length of each appended
/// file (the root's), the entries of the ParaView indices, and the clock.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct WritersRecord {
    pub log: u64,
    pub series: Option<u64>,
    pub flow_series: Option<u64>,
    pub timing: Option<u64>,
    pub tracked: Option<u64>,
    pub bed: Option<BedRecord>,
    pub particle_frames: usize,
    pub particle_entries: Vec<(f64, String)>,
    pub field_frames: usize,
    pub field_entries: Vec<(f64, String)>,
    /// HDF5 frames written and the grids of their XDMF indices.
    pub hdf5_fields: (usize, Vec<String>),
    pub hdf5_particles: (usize, Vec<String>),
    pub wall_seconds: f64,
    pub output_seconds: f64,
    pub checkpoint_seconds: f64,
}

impl WritersRecord {
    /// The series a resumed run appends to, with the bytes the checkpoint
    /// recorded of each (the log, where lost, starts again).
    fn appended_files(&self) -> Vec<(&'static str, u64)> {
        let series = [
            (SERIES_FILE, self.series),
            (FLOW_SERIES_FILE, self.flow_series),
            (TIMING_FILE, self.timing),
            (TRACKED_FILE, self.tracked),
        ];
        let mut files: Vec<(&'static str, u64)> = series
            .into_iter()
            .filter_map(|(name, length)| length.map(|l| (name, l)))
            .collect();
        if let Some(bed) = &self.bed {
            files.extend(bed::FILES.into_iter().zip(bed.lengths));
        }
        files
    }

    /// Refuses, before anything is written, to resume in `dir` where an
    /// appended file is missing or shorter than the checkpoint recorded:
    /// a resumed run appends to the outputs of the run that wrote the
    /// checkpoint (`checkpoint`), and cannot start them again midway.
    pub fn check_resumable_in(&self, dir: &Path, checkpoint: &Path) -> Result<(), String> {
        for (name, recorded) in self.appended_files() {
            let path = dir.join(name);
            let found = std::fs::metadata(&path).map(|m| m.len()).ok();
            let what = match found {
                None => "is missing",
                Some(found) if found < recorded => "is shorter than that",
                Some(_) => continue,
            };
            return Err(format!(
                "resuming from {} in {}: the checkpoint recorded {recorded} bytes of {}, \
                 which {what}: a resumed run appends to the outputs of the run that wrote \
                 the checkpoint; allowed: resume in that run's folder (--out), or in a copy \
                 of the whole folder, its outputs with its checkpoints (cp -r RUN COPY, then \
                 --out COPY --restart latest)",
                checkpoint.display(),
                dir.display(),
                path.display(),
            ));
        }
        Ok(())
    }
}

pub struct Writers {
    pub run: RunDirectory,
    series: Option<CsvSeries>,
    flow_series: Option<CsvSeries>,
    timing: Option<CsvSeries>,
    tracked: Option<CsvSeries>,
    tracked_ids: Vec<u64>,
    particles: Option<ParticleFiles>,
    fields: Option<FieldFiles>,
    #[cfg(feature = "hdf5")]
    hdf5_fields: Option<crate::hdf5_output::Hdf5Fields>,
    #[cfg(feature = "hdf5")]
    hdf5_particles: Option<crate::hdf5_output::Hdf5Particles>,
    pub bed: Option<InclinedBed>,
    /// The clock of this piece of the run, and the seconds of the pieces
    /// before it (a resumed run).
    started: Instant,
    seconds_before: f64,
    pub output_seconds: f64,
    pub checkpoint_seconds: f64,
}

/// Opens a series: created afresh, or resumed after `length` bytes.
fn series(
    root: bool,
    dir: &Path,
    name: &str,
    header: &[&str],
    length: Option<u64>,
) -> std::io::Result<Option<CsvSeries>> {
    if !root {
        return Ok(None);
    }
    let path = dir.join(name);
    Ok(Some(match length {
        Some(length) => CsvSeries::resume(&path, header, length)?,
        None => CsvSeries::create(&path, header)?,
    }))
}

impl Writers {
    /// The writers of `model`'s outputs in `run`'s folder; a resumed run
    /// passes the record of its checkpoint.
    pub fn create(
        run: RunDirectory,
        case: &Case,
        model: &Model,
        communicator: &Communicator,
        resumed: Option<&WritersRecord>,
    ) -> std::io::Result<Self> {
        let root = communicator.is_root();
        let dir = run.dir.clone();
        let record = resumed.cloned().unwrap_or_default();
        let length = |l: Option<u64>| {
            if resumed.is_some() {
                l.or(Some(0))
            } else {
                None
            }
        };
        let grains = model.grains().is_some();
        let flow = model.has_flow();
        let series_header: &[&str] = if grains { &GRAIN_SERIES } else { &FLOW_SERIES };
        let vtk = case.output.format == OutputFormat::Vtk;
        let mut writers = Writers {
            series: series(
                root,
                &dir,
                SERIES_FILE,
                series_header,
                length(record.series),
            )?,
            flow_series: if grains && flow {
                series(
                    root,
                    &dir,
                    FLOW_SERIES_FILE,
                    &COUPLED_FLOW_SERIES,
                    length(record.flow_series),
                )?
            } else {
                None
            },
            timing: series(root, &dir, TIMING_FILE, &TIMING, length(record.timing))?,
            tracked: series(root, &dir, TRACKED_FILE, &TRACKED, length(record.tracked))?,
            tracked_ids: if grains {
                case.particles_section().tracked.clone()
            } else {
                Vec::new()
            },
            particles: (vtk && grains && case.output.particles)
                .then(|| ParticleFiles::create(&dir, communicator.clone(), record.particle_entries))
                .transpose()?,
            fields: (vtk && flow && case.output.fields)
                .then(|| FieldFiles::create(&dir, case, root, record.field_entries))
                .transpose()?,
            #[cfg(feature = "hdf5")]
            hdf5_fields: if flow {
                crate::hdf5_output::Hdf5Fields::create(
                    &dir,
                    case,
                    communicator,
                    record.hdf5_fields,
                )?
            } else {
                None
            },
            #[cfg(feature = "hdf5")]
            hdf5_particles: if grains {
                crate::hdf5_output::Hdf5Particles::create(
                    &dir,
                    case,
                    communicator,
                    record.hdf5_particles,
                )?
            } else {
                None
            },
            bed: None,
            run,
            started: Instant::now(),
            seconds_before: record.wall_seconds,
            output_seconds: record.output_seconds,
            checkpoint_seconds: record.checkpoint_seconds,
        };
        if let Some(files) = &mut writers.particles {
            files.frames = record.particle_frames;
        }
        if let Some(files) = &mut writers.fields {
            files.frames = record.field_frames;
        }
        if let Model::Coupled(coupled) = model {
            if let Some(slab) = coupled.bed_slab(case) {
                writers.bed = Some(InclinedBed::create(
                    &dir,
                    case,
                    &coupled.system,
                    slab,
                    resumed.map(|r| r.bed.clone().unwrap_or_default()),
                )?);
            }
        }
        Ok(writers)
    }

    /// Seconds of the run so far, the pieces before a resume included.
    pub fn wall_seconds(&self) -> f64 {
        self.seconds_before + self.started.elapsed().as_secs_f64()
    }

    /// The rows of the series and, if enabled, the particle and field files
    /// of the model now, after a step of `dt` (collective).
    pub fn write_frame(&mut self, model: &mut Model, dt: f64) -> std::io::Result<()> {
        let clock = Instant::now();
        if let Some(system) = model.grains() {
            let row = grain_series_row(system, dt);
            if let Some(series) = &mut self.series {
                series.row(&row)?;
            }
            if let Some(files) = &mut self.particles {
                files.write(system)?;
            }
            #[cfg(feature = "hdf5")]
            if let Some(files) = &mut self.hdf5_particles {
                files.write(system)?;
            }
        }
        if let Some(row) = model.flow_row(dt) {
            let series = if model.grains().is_some() {
                &mut self.flow_series
            } else {
                &mut self.series
            };
            if let Some(series) = series {
                series.row(&row)?;
            }
        }
        #[cfg(feature = "hdf5")]
        let any_fields = self.fields.is_some() || self.hdf5_fields.is_some();
        #[cfg(not(feature = "hdf5"))]
        let any_fields = self.fields.is_some();
        // The solid fraction of a field file only when one is written.
        if let Some(output) = any_fields.then(|| model.field_output()).flatten() {
            let extra: Vec<(&str, &[f64])> = output
                .solid_fraction
                .iter()
                .map(|s| ("solid_fraction", s.as_slice()))
                .collect();
            if let Some(files) = &mut self.fields {
                files.write(output.solver, output.density, &extra)?;
            }
            #[cfg(feature = "hdf5")]
            if let Some(files) = &mut self.hdf5_fields {
                files.write(output.solver, output.density, &extra)?;
            }
        }
        if let (Some(files), Some(rz)) = (&mut self.fields, model.axisymmetric()) {
            files.write_rz(&mut rz.system)?;
        }
        if let (Some(bed), Model::Coupled(coupled)) = (&mut self.bed, &*model) {
            bed.sample(&coupled.system)?;
        }
        self.output_seconds += clock.elapsed().as_secs_f64();
        let row = [
            model.time(),
            model.steps() as f64,
            self.wall_seconds(),
            self.output_seconds,
            self.checkpoint_seconds,
        ];
        if let Some(timing) = &mut self.timing {
            timing.row(&row)?;
        }
        Ok(())
    }

    /// Rows of `tracked.csv` for the case's tracked grains (collective).
    pub fn write_tracked(&mut self, model: &Model) -> std::io::Result<()> {
        let clock = Instant::now();
        if let Some(system) = model.grains() {
            write_tracked(self.tracked.as_mut(), system, &self.tracked_ids)?;
        }
        self.output_seconds += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// What a checkpoint records of the writers now.
    pub fn record(&self) -> WritersRecord {
        WritersRecord {
            log: self.run.log_length(),
            series: self.series.as_ref().map(CsvSeries::length),
            flow_series: self.flow_series.as_ref().map(CsvSeries::length),
            timing: self.timing.as_ref().map(CsvSeries::length),
            tracked: self.tracked.as_ref().map(CsvSeries::length),
            bed: self.bed.as_ref().and_then(InclinedBed::record),
            particle_frames: self.particles.as_ref().map_or(0, |f| f.frames),
            particle_entries: self
                .particles
                .as_ref()
                .map_or_else(Vec::new, |f| f.entries()),
            field_frames: self.fields.as_ref().map_or(0, |f| f.frames),
            field_entries: self.fields.as_ref().map_or_else(Vec::new, |f| f.entries()),
            #[cfg(feature = "hdf5")]
            hdf5_fields: self
                .hdf5_fields
                .as_ref()
                .map(|f| f.record())
                .unwrap_or_default(),
            #[cfg(feature = "hdf5")]
            hdf5_particles: self
                .hdf5_particles
                .as_ref()
                .map(|f| f.record())
                .unwrap_or_default(),
            #[cfg(not(feature = "hdf5"))]
            hdf5_fields: Default::default(),
            #[cfg(not(feature = "hdf5"))]
            hdf5_particles: Default::default(),
            wall_seconds: self.wall_seconds(),
            output_seconds: self.output_seconds,
            checkpoint_seconds: self.checkpoint_seconds,
        }
    }
}
