//! Case files: TOML in SI units, read once into typed structs.
//!
//! Every table denies unknown keys; [`Case::validate`] checks ranges and
//! consistency and names the key and what is allowed. Nothing below this
//! module reads TOML.

use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("case file {path}: {message}")]
    Parse { path: String, message: String },
    #[error("--set {assignment}: {message}")]
    Override { assignment: String, message: String },
    #[error("{key} = {value}: {allowed}")]
    Invalid {
        key: String,
        value: String,
        allowed: String,
    },
}

fn invalid(key: &str, value: impl std::fmt::Display, allowed: &str) -> CaseError {
    CaseError::Invalid {
        key: key.to_string(),
        value: value.to_string(),
        allowed: allowed.to_string(),
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub domain: DomainSection,
    /// The fluid (absent in a dry scene: no grid is allocated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fluid: Option<FluidSection>,
    /// The grains and their contacts (absent in a fluid-only scene).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<ParticlesSection>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSection>,
    #[serde(default)]
    pub walls: Vec<WallSection>,
    /// How grains and fluid exchange momentum (a scene with both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling: Option<CouplingSection>,
    /// The film force between close grains (a scene with both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lubrication: Option<LubricationSection>,
    pub time: TimeSection,
    #[serde(default)]
    pub output: OutputSection,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub analysis: Option<AnalysisSection>,
    /// How the scene is shared among MPI ranks (default: the process grid
    /// with the least area of cuts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parallel: Option<ParallelSection>,
    /// When checkpoints are written (default: only when the run is told
    /// to stop, by a signal or `time.wall_limit`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint: Option<CheckpointSection>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParallelSection {
    /// Ranks along each axis; their product must be the number of ranks
    /// the run is started on (default: chosen by the run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub process_grid: Option<Vec<usize>>,
    /// Whether ranks on one node read one another's arrays directly in the
    /// flow's transposes (default true); false sends messages, as between
    /// nodes.
    #[serde(default = "default_true")]
    pub shared_memory: bool,
    /// Threads of each rank (`grainflow run --threads N` sets it; default:
    /// chosen from the scene's size, see `grainflow_dem::threads`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threads: Option<usize>,
}

impl ParallelSection {
    /// The process grid along x, y, z (1 along an axis the case omits), if
    /// the case sets one.
    pub fn ranks(&self) -> Option<[usize; 3]> {
        let grid = self.process_grid.as_ref()?;
        let mut ranks = [1; 3];
        ranks[..grid.len()].copy_from_slice(grid);
        Some(ranks)
    }
}

mod fluid_sections;
mod grain_sections;
mod run_sections;
mod validate_analysis;
mod validate_axisymmetric;
mod validate_fluid;
mod validate_grains;

pub use fluid_sections::*;
pub use grain_sections::*;
use run_sections::default_true;
pub use run_sections::*;

impl Case {
    /// Reads a case file and applies `--set key=value` overrides.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Read {
            path: path.display().to_string(),
            source,
        })?;
        let mut case = Self::from_text(&text, &path.display().to_string(), overrides)?;
        // Files named by the case are relative to it.
        let base = path.parent().unwrap_or(Path::new("."));
        for block in case.particles.iter_mut().flat_map(|p| &mut p.block) {
            if let BlockSection::File { path: file, .. } = block {
                if Path::new(file.as_str()).is_relative() {
                    *file = base.join(file.as_str()).display().to_string();
                }
            }
        }
        Ok(case)
    }

    pub fn from_text(text: &str, origin: &str, overrides: &[String]) -> Result<Case, CaseError> {
        let mut document: toml::Table = toml::from_str(text).map_err(|e| CaseError::Parse {
            path: origin.to_string(),
            message: e.to_string(),
        })?;
        for assignment in overrides {
            apply_override(&mut document, assignment)?;
        }
        let case: Case =
            Case::deserialize(toml::Value::Table(document)).map_err(|e| CaseError::Parse {
                path: origin.to_string(),
                message: e.to_string().trim().to_string(),
            })?;
        case.validate()?;
        Ok(case)
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a case always serialises")
    }

    pub fn dimension(&self) -> usize {
        self.domain.dimension as usize
    }

    /// The particle section of a scene with grains (validation guarantees
    /// it with the contact section whenever either is present).
    pub fn particles_section(&self) -> &ParticlesSection {
        self.particles.as_ref().expect("a scene with grains")
    }

    pub fn contact_section(&self) -> &ContactSection {
        self.contact.as_ref().expect("a scene with grains")
    }

    /// The fluid section of a fluid scene.
    pub fn fluid_section(&self) -> &FluidSection {
        self.fluid.as_ref().expect("a fluid scene")
    }

    /// Whether the scene has grains (else it is fluid only).
    pub fn has_grains(&self) -> bool {
        self.particles.is_some()
    }

    /// Checks ranges and consistency; the error names the key and what is
    /// allowed.
    pub fn validate(&self) -> Result<(), CaseError> {
        self.validate_checkpoints()?;
        let d = &self.domain;
        if d.dimension != 2 && d.dimension != 3 {
            return Err(invalid("domain.dimension", d.dimension, "allowed: 2 or 3"));
        }
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        check_len("domain.lower", &d.lower, dim, &need)?;
        check_len("domain.upper", &d.upper, dim, &need)?;
        for axis in 0..dim {
            if d.upper[axis] <= d.lower[axis] {
                return Err(invalid(
                    "domain.upper",
                    format!("{:?}", d.upper),
                    "allowed: each bound above domain.lower",
                ));
            }
        }
        if !d.periodic.is_empty() && d.periodic.len() != dim {
            return Err(invalid(
                "domain.periodic",
                format!("{:?}", d.periodic),
                &format!("allowed: a list of {dim} booleans"),
            ));
        }
        if !d.gravity.is_empty() {
            check_len("domain.gravity", &d.gravity, dim, &need)?;
        }
        if let Some(grid) = self.parallel.as_ref().and_then(|p| p.process_grid.as_ref()) {
            if grid.len() != dim || grid.contains(&0) {
                return Err(invalid(
                    "parallel.process_grid",
                    format!("{grid:?}"),
                    &format!("allowed: {dim} positive rank counts, one per axis"),
                ));
            }
        }
        if self.parallel.as_ref().and_then(|p| p.threads) == Some(0) {
            return Err(invalid(
                "parallel.threads",
                0,
                "allowed: at least 1 (or leave it out to choose from the scene's size)",
            ));
        }

        match (&self.particles, &self.contact, &self.fluid) {
            (Some(p), Some(c), _) => self.validate_grains(p, c)?,
            (Some(_), None, _) => {
                return Err(invalid(
                    "contact",
                    "(missing)",
                    "a scene with [particles] needs a [contact] table",
                ))
            }
            (None, Some(_), _) => {
                return Err(invalid(
                    "particles",
                    "(missing)",
                    "a [contact] table needs [particles]",
                ))
            }
            (None, None, None) => {
                return Err(invalid(
                    "particles",
                    "(missing)",
                    "a scene needs [particles] (with [contact]), a [fluid], or both",
                ))
            }
            (None, None, Some(_)) => {}
        }
        match (&self.fluid, self.domain.geometry) {
            (Some(fluid), Geometry::Axisymmetric) => self.validate_axisymmetric(fluid)?,
            (Some(fluid), Geometry::Cartesian) => {
                self.refuse_axisymmetric_keys(fluid)?;
                self.validate_fluid(fluid)?;
            }
            (None, Geometry::Axisymmetric) => {
                return Err(invalid(
                    "domain.geometry",
                    "axisymmetric",
                    "an axisymmetric scene is one of a fluid: it needs a [fluid] table",
                ))
            }
            (None, Geometry::Cartesian) => {}
        }
        self.validate_coupling()?;
        self.validate_walls_time_output()
    }

    fn validate_checkpoints(&self) -> Result<(), CaseError> {
        let positive = |key: &str, value: Option<f64>| match value {
            Some(v) if !(v > 0.0 && v.is_finite()) => {
                Err(invalid(key, v, "allowed: a positive number of seconds"))
            }
            _ => Ok(()),
        };
        positive("time.wall_limit", self.time.wall_limit)?;
        if let Some(c) = &self.checkpoint {
            positive("checkpoint.interval", c.interval)?;
            positive("checkpoint.wall_interval", c.wall_interval)?;
            if c.steps == Some(0) {
                return Err(invalid("checkpoint.steps", 0, "allowed: at least 1"));
            }
            if c.keep == 0 {
                return Err(invalid(
                    "checkpoint.keep",
                    0,
                    "allowed: at least 1 (the checkpoint a run resumes from)",
                ));
            }
        }
        Ok(())
    }

    fn validate_walls_time_output(&self) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        if !self.walls.is_empty() && !self.has_grains() {
            return Err(invalid(
                "walls",
                self.walls.len(),
                "[[walls]] are particle walls; a fluid-only scene sets fluid.boundary",
            ));
        }

        if self.walls.len() > 64 {
            return Err(invalid(
                "walls",
                self.walls.len(),
                "allowed: at most 64 walls",
            ));
        }
        for (k, w) in self.walls.iter().enumerate() {
            let key = |name: &str| format!("walls[{k}].{name}");
            check_len(&key("point"), &w.point, dim, &need)?;
            check_len(&key("normal"), &w.normal, dim, &need)?;
            if w.normal.iter().map(|x| x * x).sum::<f64>() == 0.0 {
                return Err(invalid(
                    &key("normal"),
                    format!("{:?}", w.normal),
                    "allowed: a non-zero vector",
                ));
            }
            if let Some(f) = w.friction {
                non_negative(&key("friction"), f)?;
            }
        }

        let t = &self.time;
        positive("time.end", t.end)?;
        let coupled = self.fluid.is_some() && self.has_grains();
        match (t.dt, t.dt_over_contact_time) {
            (Some(dt), Some(f)) if coupled => {
                positive("time.dt", dt)?;
                positive("time.dt_over_contact_time", f)?;
            }
            (Some(dt), Some(f)) => {
                return Err(invalid(
                    "time.dt",
                    format!("{dt} beside time.dt_over_contact_time = {f}"),
                    "allowed: one of the two in a dry scene (the other gives the step)",
                ))
            }
            (Some(dt), None) => positive("time.dt", dt)?,
            (None, Some(f)) => positive("time.dt_over_contact_time", f)?,
            (None, None) => {}
        }
        if let Some(v) = t.rest_speed {
            positive("time.rest_speed", v)?;
        }
        positive("time.overlap_limit", t.overlap_limit)?;

        if let Some(i) = self.output.interval {
            positive("output.interval", i)?;
        }
        if let Some(i) = self.output.tracked_interval {
            positive("output.tracked_interval", i)?;
        }
        if self.output.format == OutputFormat::Hdf5 && !cfg!(feature = "hdf5") {
            return Err(invalid(
                "output.format",
                "\"hdf5\"",
                "this grainflow was built without the HDF5 writers: build it with \
                 `cargo build --release --features hdf5` (needs the system's HDF5 library, e.g. \
                 Debian's libhdf5-dev; with --features mpi too, libhdf5-openmpi-dev), or use \
                 output.format = \"vtk\"",
            ));
        }
        if self.time.cfl.is_some() && self.time.dt.is_some() && !coupled {
            return Err(invalid(
                "time.cfl",
                "(with time.dt)",
                "allowed: one of time.dt and time.cfl",
            ));
        }
        if self.fluid.is_some() && self.time.cfl.is_none() && self.time.dt.is_none() {
            return Err(invalid(
                "time.dt",
                "(missing)",
                "a fluid scene needs time.dt [s] or time.cfl",
            ));
        }
        self.validate_analysis()
    }
}

fn check_len(key: &str, values: &[f64], n: usize, allowed: &str) -> Result<(), CaseError> {
    if values.len() != n || values.iter().any(|v| !v.is_finite()) {
        return Err(invalid(key, format!("{values:?}"), allowed));
    }
    Ok(())
}

fn non_negative(key: &str, value: f64) -> Result<(), CaseError> {
    if value >= 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, value, "allowed: a number ≥ 0"))
    }
}

fn positive(key: &str, value: f64) -> Result<(), CaseError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, value, "allowed: a positive number"))
    }
}

/// Sets `a.b.c = value` in the document; the value is read as TOML (a
/// number, boolean, array, ...) or else taken as a string.
fn apply_override(document: &mut toml::Table, assignment: &str) -> Result<(), CaseError> {
    let err = |message: &str| CaseError::Override {
        assignment: assignment.to_string(),
        message: message.to_string(),
    };
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| err("expected key=value, e.g. time.end=0.1"))?;
    let key = key.trim();
    let value: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {}", raw.trim())) {
        Ok(mut t) => t.remove("v").unwrap(),
        Err(_) => toml::Value::String(raw.trim().to_string()),
    };
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err("empty key segment"));
    }
    // Each segment is `name` or `name[index]` (an entry of an array of tables).
    let mut table = document;
    for (depth, part) in parts.iter().enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((name, rest)) => {
                let index: usize = rest
                    .strip_suffix(']')
                    .and_then(|i| i.parse().ok())
                    .ok_or_else(|| err(&format!("bad index in `{part}`")))?;
                (name, Some(index))
            }
            None => (*part, None),
        };
        let last = depth + 1 == parts.len();
        if last && index.is_none() {
            table.insert(name.to_string(), value);
            return Ok(());
        }
        let entry = table
            .entry(name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let entry = match (entry, index) {
            (toml::Value::Array(items), Some(i)) => items
                .get_mut(i)
                .ok_or_else(|| err(&format!("`{name}` has no entry {i}")))?,
            (entry, None) => entry,
            _ => return Err(err(&format!("`{name}` is not an array"))),
        };
        if last {
            *entry = value;
            return Ok(());
        }
        table = match entry {
            toml::Value::Table(t) => t,
            _ => return Err(err(&format!("`{part}` is not a table"))),
        };
    }
    Ok(())
}
