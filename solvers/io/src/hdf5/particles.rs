//! One particle frame in HDF5: the grains of every rank in one file.
//!
//! The file `particles_NNNNNN.h5` holds, for `n` grains in all:
//! - `position`, `velocity`, `angular_velocity` (the spin), `force`:
//!   float64 `[n, 3]`;
//! - `radius`: float64 `[n]`; `id`: uint64 `[n]`; `contacts` (grain–grain
//!   contacts at the last force evaluation, the coordination number):
//!   uint32 `[n]`; `fixed` (1 for a glued grain): uint8 `[n]`; `group`
//!   (the block of the case file each grain was made in): uint64 `[n]`;
//! - the attributes `time` [s] and `count` (`n`) on the root.
//!
//! On several ranks the grains of rank r follow those of ranks 0..r: its
//! rows start at the sum of the lower ranks' counts (an exclusive prefix
//! sum of the counts, gathered from every rank) and each rank writes its
//! rows into the one file through parallel HDF5.

use super::{block, check_name, invalid, scalar_attribute, write_frame, Writers};
use hdf5_metno::{Dataset, File, H5Type};
use std::path::Path;

/// The grains one writer owns at one output time (each slice one entry per
/// grain, in the same order).
pub struct ParticleFrameH5<'a> {
    /// Simulated time of the frame [s].
    pub time: f64,
    pub id: &'a [u64],
    pub position: &'a [[f64; 3]],
    pub velocity: &'a [[f64; 3]],
    pub angular_velocity: &'a [[f64; 3]],
    pub force: &'a [[f64; 3]],
    pub radius: &'a [f64],
    /// Grain–grain contacts of each grain.
    pub contacts: &'a [u32],
    /// 1 for a fixed (glued) grain, else 0.
    pub fixed: &'a [u8],
    /// The group each grain was made in.
    pub group: &'a [u64],
}

impl ParticleFrameH5<'_> {
    /// Writes the frame to `path` with every writer (collective: each calls
    /// it with the grains it owns). Returns the number of grains in the
    /// file, the sum over the writers.
    pub fn write(&self, path: &Path, writers: &Writers) -> std::io::Result<usize> {
        let n = self.radius.len();
        let lengths = [
            ("id", self.id.len()),
            ("position", self.position.len()),
            ("velocity", self.velocity.len()),
            ("angular_velocity", self.angular_velocity.len()),
            ("force", self.force.len()),
            ("contacts", self.contacts.len()),
            ("fixed", self.fixed.len()),
            ("group", self.group.len()),
        ];
        for (name, len) in lengths {
            check_name(path, name)?;
            if len != n {
                return Err(invalid(
                    path,
                    format!("{name} has {len} entries for {n} grains"),
                ));
            }
        }
        let counts = writers.all_counts(n);
        let start: usize = counts[..writers.rank()].iter().sum();
        let total: usize = counts.iter().sum();
        write_frame(path, writers, |file| {
            for (name, values) in [
                ("position", self.position),
                ("velocity", self.velocity),
                ("angular_velocity", self.angular_velocity),
                ("force", self.force),
            ] {
                let dataset = dataset::<f64>(file, name, &[total, 3])?;
                let values = block(values.as_flattened(), &[n, 3])?;
                writers.write_block(&dataset, values, &[start, 0])?;
            }
            column_of(file, writers, "radius", self.radius, total, start)?;
            column_of(file, writers, "id", self.id, total, start)?;
            column_of(file, writers, "contacts", self.contacts, total, start)?;
            column_of(file, writers, "fixed", self.fixed, total, start)?;
            column_of(file, writers, "group", self.group, total, start)?;
            scalar_attribute(file, "time", &self.time)?;
            scalar_attribute(file, "count", &(total as u64))?;
            Ok(())
        })?;
        Ok(total)
    }
}

fn dataset<T: H5Type>(file: &File, name: &str, shape: &[usize]) -> hdf5_metno::Result<Dataset> {
    file.new_dataset::<T>().shape(shape).create(name)
}

/// A dataset of `total` entries whose rows `start..` are `values`.
fn column_of<T: H5Type>(
    file: &File,
    writers: &Writers,
    name: &str,
    values: &[T],
    total: usize,
    start: usize,
) -> hdf5_metno::Result<()> {
    let dataset = dataset::<T>(file, name, &[total])?;
    writers.write_block(&dataset, block(values, &[values.len()])?, &[start])
}
