//! `[analysis] kind = "inclined_bed"`: a granular bed under a fluid that
//! flows down an inclined plane (Izard et al. 2014, section 4.2), the
//! streamwise direction x. At every output:
//!
//! - `bed_profiles.csv`: per layer of cells, the fluid's mean streamwise
//!   velocity (over the x–y plane, inside the grains too, where it is
//!   theirs) and the solid fraction of the grains;
//! - `grain_profiles.csv`: per slab of height `slab`, the mean streamwise
//!   velocity of the moving grains whose centres lie in it, and their count;
//! - `bed_series.csv`: the mean streamwise velocity of the moving grains,
//!   of their lower and upper halves (by height), the bed surface (where
//!   the solid fraction falls to half its largest value), the shear rate of
//!   the fluid over the first diameter above it, and the Shields number
//!   θ = μ γ̇ / ((ρ_p − ρ) g D).
//!
//! Velocities are scaled by (g D)^½ and times by (D/g)^½ in the series, as
//! in the paper. The summary's metrics are the last row's. Erosion moves
//! the upper half of the bed only; an avalanche moves the lower half too.

use crate::case::Case;
use grainflow_core::Communicator;
use grainflow_fluid::Location;
use grainflow_ibm::CoupledSystem;
use grainflow_io::CsvSeries;
use serde_json::{json, Map, Value};
use std::path::Path;

pub struct InclinedBed {
    /// Height of the grains' slabs [m].
    slab: f64,
    /// Mean diameter of the moving grains [m].
    diameter: f64,
    /// |g| [m/s²], for the scales (g D)^½ and (D/g)^½ and the Shields
    /// number.
    gravity: f64,
    viscosity: f64,
    density_difference: f64,
    profiles: Option<CsvSeries>,
    grain_profiles: Option<CsvSeries>,
    series: Option<CsvSeries>,
    last: Option<Vec<f64>>,
}

/// What a checkpoint records of the bed's outputs: the lengths of
/// `bed_profiles.csv`, `grain_profiles.csv` and `bed_series.csv`, and the
/// last row of the series (the summary's metrics).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct BedRecord {
    /// Bytes of each of [`FILES`], in its order.
    pub lengths: [u64; 3],
    pub last: Option<Vec<f64>>,
    /// The mean diameter and slab height measured at the start (a resumed
    /// run's grains come in another order, whose sum differs at round-off).
    pub diameter: f64,
    pub slab: f64,
}

/// The series an inclined bed appends to: profiles of the fluid, of the
/// grains, and the bed's series.
pub const FILES: [&str; 3] = ["bed_profiles.csv", "grain_profiles.csv", "bed_series.csv"];

/// Columns of `bed_series.csv`.
const SERIES: [&str; 9] = [
    "t",
    "t_scaled",
    "grain_velocity",
    "lower_half_velocity",
    "upper_half_velocity",
    "bed_surface",
    "shear_rate",
    "shields_number",
    "surface_fluid_velocity",
];

impl InclinedBed {
    pub fn create(
        dir: &Path,
        case: &Case,
        system: &CoupledSystem,
        slab: Option<f64>,
        resumed: Option<BedRecord>,
    ) -> std::io::Result<Self> {
        let root = system.dem.communicator.is_root();
        let open = |name: &str, header: &[&str], length: Option<u64>| {
            if !root {
                return Ok(None);
            }
            let path = dir.join(name);
            match length {
                Some(length) => CsvSeries::resume(&path, header, length).map(Some),
                None => CsvSeries::create(&path, header).map(Some),
            }
        };
        let lengths = resumed.as_ref().map(|r| r.lengths);
        let mut diameter = system.dem.mean_moving_diameter().unwrap_or(0.0);
        let mut slab = slab.unwrap_or(0.5 * diameter);
        if let Some(record) = &resumed {
            (diameter, slab) = (record.diameter, record.slab);
        }
        let f = case.fluid_section();
        let density = case.particles_section().density;
        Ok(InclinedBed {
            slab,
            diameter,
            gravity: system.dem.domain.gravity.norm(),
            viscosity: f.viscosity,
            density_difference: density - f.density,
            profiles: open(
                FILES[0],
                &["t", "z", "fluid_velocity", "solid_fraction"],
                lengths.map(|l| l[0]),
            )?,
            grain_profiles: open(
                FILES[1],
                &["t", "z", "grain_velocity", "grains"],
                lengths.map(|l| l[1]),
            )?,
            series: open(FILES[2], &SERIES, lengths.map(|l| l[2]))?,
            last: resumed.and_then(|r| r.last),
        })
    }

    /// What a checkpoint records of the bed (the file lengths are the
    /// root's, which writes them; 0 elsewhere).
    pub fn record(&self) -> Option<BedRecord> {
        let length = |s: &Option<CsvSeries>| s.as_ref().map_or(0, CsvSeries::length);
        Some(BedRecord {
            lengths: [
                length(&self.profiles),
                length(&self.grain_profiles),
                length(&self.series),
            ],
            last: self.last.clone(),
            diameter: self.diameter,
            slab: self.slab,
        })
    }

    /// Samples the bed and the fluid (collective) and writes the rows.
    pub fn sample(&mut self, system: &CoupledSystem) -> std::io::Result<()> {
        let communicator: &Communicator = &system.dem.communicator;
        let grid = &system.flow.grid;
        let time = system.flow.time;
        // The fluid, layer by layer of cells along z (whole on every rank).
        let cells = grid.cell_block();
        let layers = cells.end[2] - cells.start[2];
        let mut fluid = vec![0.0; 2 * layers];
        let faces = system.flow.velocity_unknowns(0);
        let velocity = &system.flow.velocity[0];
        grid.for_each(faces, |index, [_, _, k]| {
            fluid[k - cells.start[2]] += velocity[index];
            fluid[layers + k - cells.start[2]] += 1.0;
        });
        let solid = system
            .immersed
            .cell_solid_fraction(grid, &system.dem.particles);
        let mut fraction = vec![0.0; 2 * layers];
        let per_layer = solid.len() / layers.max(1);
        for (layer, values) in solid.chunks(per_layer.max(1)).enumerate().take(layers) {
            fraction[layer] += values.iter().sum::<f64>();
            fraction[layers + layer] += values.len() as f64;
        }
        communicator.sum_each(&mut fluid);
        communicator.sum_each(&mut fraction);
        let z: Vec<f64> = (cells.start[2]..cells.end[2])
            .map(|k| grid.coordinate(Location::Centre, 2, k))
            .collect();
        let fluid_velocity: Vec<f64> = (0..layers)
            .map(|l| fluid[l] / fluid[layers + l].max(1.0))
            .collect();
        let solid_fraction: Vec<f64> = (0..layers)
            .map(|l| fraction[l] / fraction[layers + l].max(1.0))
            .collect();

        // The moving grains, slab by slab, and their lower and upper halves.
        let p = &system.dem.particles;
        let lower = system.dem.domain.lower[2];
        let height = system.dem.domain.upper[2] - lower;
        let slabs = (height / self.slab).ceil() as usize;
        let mut grains = vec![0.0; 2 * slabs + 2];
        let mut heights = Vec::new();
        for k in 0..p.n_owned {
            if p.is_fixed(k) {
                continue;
            }
            let slab =
                (((p.position[k].z - lower) / self.slab).floor().max(0.0) as usize).min(slabs - 1);
            grains[slab] += p.velocity[k].x;
            grains[slabs + slab] += 1.0;
            heights.push(p.position[k].z);
        }
        communicator.sum_each(&mut grains);
        let total: f64 = grains[slabs..2 * slabs].iter().sum();
        let mean = grains[..slabs].iter().sum::<f64>() / total.max(1.0);
        // The halves by height: the median of the centres' heights.
        let gathered = communicator.gather(&heights);
        let mut median = [0.0];
        if let Some(all) = gathered {
            let mut all: Vec<f64> = all.concat();
            all.sort_by(f64::total_cmp);
            median[0] = all.get(all.len() / 2).copied().unwrap_or(lower);
        }
        communicator.sum_each(&mut median);
        let mut halves = [0.0; 4];
        for k in 0..p.n_owned {
            if p.is_fixed(k) {
                continue;
            }
            let upper = usize::from(p.position[k].z >= median[0]);
            halves[upper] += p.velocity[k].x;
            halves[2 + upper] += 1.0;
        }
        communicator.sum_each(&mut halves);
        let lower_half = halves[0] / halves[2].max(1.0);
        let upper_half = halves[1] / halves[3].max(1.0);

        // The bed surface: the highest layer whose solid fraction is half
        // the largest; the shear rate over the first diameter above it.
        let largest = solid_fraction.iter().copied().fold(0.0, f64::max);
        let surface_layer = (0..layers)
            .rev()
            .find(|&l| solid_fraction[l] >= 0.5 * largest)
            .unwrap_or(0);
        let surface = z[surface_layer];
        let above = (surface_layer..layers)
            .find(|&l| z[l] >= surface + self.diameter)
            .unwrap_or(layers - 1);
        let shear_rate = (fluid_velocity[above] - fluid_velocity[surface_layer])
            / (z[above] - surface).max(f64::MIN_POSITIVE);
        let shields =
            self.viscosity * shear_rate / (self.density_difference * self.gravity * self.diameter);

        let velocity_scale = (self.gravity * self.diameter).sqrt();
        let time_scale = (self.diameter / self.gravity).sqrt();
        let t_scaled = time / time_scale;
        let row = vec![
            time,
            t_scaled,
            mean / velocity_scale,
            lower_half / velocity_scale,
            upper_half / velocity_scale,
            (surface - lower) / self.diameter,
            shear_rate,
            shields,
            fluid_velocity[surface_layer] / velocity_scale,
        ];
        if let Some(series) = &mut self.series {
            series.row(&row)?;
        }
        if let Some(profiles) = &mut self.profiles {
            for l in 0..layers {
                profiles.row(&[time, z[l], fluid_velocity[l], solid_fraction[l]])?;
            }
        }
        if let Some(profiles) = &mut self.grain_profiles {
            for s in 0..slabs {
                let count = grains[slabs + s];
                if count > 0.0 {
                    let centre = lower + (s as f64 + 0.5) * self.slab;
                    profiles.row(&[time, centre, grains[s] / count, count])?;
                }
            }
        }
        self.last = Some(row);
        Ok(())
    }

    pub fn metrics(&self) -> Map<String, Value> {
        let mut metrics = Map::new();
        let Some(last) = &self.last else {
            return metrics;
        };
        for (name, value) in SERIES.iter().zip(last).skip(1) {
            metrics.insert(name.to_string(), json!(value));
        }
        metrics.insert("diameter".to_string(), json!(self.diameter));
        metrics
    }
}
