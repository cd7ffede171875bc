//! The outputs of a scene's grains: `series.csv` (energies, contacts,
//! overlap), the particle files `particles/*.vtp` with their index
//! `particles.pvd`, `tracked.csv` and `final_particles.csv`.
//!
//! On several ranks the root writes the series and indices from global
//! reductions and gathers; each rank writes its own piece of every particle
//! file (`particles/particles_NNNNNN_RRRR.vtp`), which the root's
//! `particles_NNNNNN.pvtp` assembles for ParaView once every rank has
//! written its piece.

use grainflow_core::{Communicator, Vec3};
use grainflow_dem::DemSystem;
use grainflow_io::{write_particle_pieces_index, write_whole, CsvSeries, ParticleFrame, PvdIndex};
use std::io::Write;
use std::path::Path;

/// Columns of the grains' `series.csv`.
pub const GRAIN_SERIES: [&str; 10] = [
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
];

/// Columns of `tracked.csv`.
pub const TRACKED: [&str; 11] = ["t", "id", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz"];

/// A row of the grains' `series.csv` per output (collective; the root
/// writes).
pub fn grain_series_row(system: &DemSystem, dt: f64) -> [f64; 10] {
    let (translational, rotational) = system.particles.kinetic_energy();
    let c = &system.communicator;
    let last = system.last;
    [
        system.time,
        dt,
        system.steps as f64,
        c.sum(translational),
        c.sum(rotational),
        last.particle_contacts as f64,
        last.wall_contacts as f64,
        last.max_overlap_ratio,
        system.max_speed(),
        system.neighbours.builds as f64,
    ]
}

/// The particle files and their ParaView index.
pub struct ParticleFiles {
    dir: std::path::PathBuf,
    communicator: Communicator,
    /// `particles.pvd` (the root's).
    index: Option<PvdIndex>,
    pub frames: usize,
}

impl ParticleFiles {
    /// The particle files of a run in `dir` (their folder is made here);
    /// a resumed run passes the index entries it had.
    pub fn create(
        dir: &Path,
        communicator: Communicator,
        entries: Vec<(f64, String)>,
    ) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir.join("particles"))?;
        let index = communicator
            .is_root()
            .then(|| PvdIndex::with_entries(dir.join("particles.pvd"), entries.clone()));
        Ok(ParticleFiles {
            dir: dir.to_path_buf(),
            communicator,
            index,
            frames: entries.len(),
        })
    }

    /// The index entries so far (the root's; empty elsewhere).
    pub fn entries(&self) -> Vec<(f64, String)> {
        self.index
            .as_ref()
            .map_or_else(Vec::new, |i| i.entries().to_vec())
    }

    /// A particle file of the owned grains (collective).
    pub fn write(&mut self, system: &DemSystem) -> std::io::Result<()> {
        let p = &system.particles;
        let n = p.n_owned;
        let as_arrays = |v: &[Vec3]| v[..n].iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>();
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
            group: &p.group[..n],
        }
        .write(&self.dir.join(&name))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{name}: {e}")))?;
        // Every rank's piece is whole before the root's index lists it.
        if ranks > 1 {
            self.communicator.barrier();
        }
        if let Some(index) = &mut self.index {
            if ranks == 1 {
                index.add(system.time, &name)?;
            } else {
                let pieces: Vec<String> = (0..ranks)
                    .map(|r| format!("particles_{:06}_{r:04}.vtp", self.frames))
                    .collect();
                let name = format!("particles/particles_{:06}.pvtp", self.frames);
                write_particle_pieces_index(&self.dir.join(&name), &pieces)?;
                index.add(system.time, &name)?;
            }
        }
        self.frames += 1;
        Ok(())
    }
}

/// Rows of `tracked.csv` for the tracked ids, in the order of `ids`
/// (collective: each rank hands the root the tracked grains it owns;
/// `tracked` is the root's file).
pub fn write_tracked(
    tracked: Option<&mut CsvSeries>,
    system: &DemSystem,
    ids: &[u64],
) -> std::io::Result<()> {
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
    let Some(pieces) = system.communicator.gather(&local) else {
        return Ok(());
    };
    let rows: std::collections::HashMap<u64, &[f64]> = pieces
        .iter()
        .flat_map(|m| m.chunks_exact(10))
        .map(|r| (r[0] as u64, r))
        .collect();
    let tracked = tracked.expect("the root writes tracked.csv");
    for id in ids {
        if let Some(state) = rows.get(id) {
            let mut row = vec![system.time];
            row.extend_from_slice(state);
            tracked.row(&row)?;
        }
    }
    Ok(())
}

/// `final_particles.csv`: the mobile grains at the end, in the format a
/// `file` block reads (`x,y[,z],radius,vx,vy[,vz],group`), so that a deposit
/// made by one run is the initial state of others, each grain keeping the
/// group it was made in (collective).
pub fn write_final_particles(dir: &Path, system: &DemSystem) -> std::io::Result<()> {
    let p = &system.particles;
    let dim = system.domain.dimension.count();
    // [id, x, y, z, radius, vx, vy, vz, group] of each mobile grain, on the
    // root.
    let mut local = Vec::new();
    for k in (0..p.n_owned).filter(|&k| !p.is_fixed(k)) {
        local.push(f64::from_bits(p.id[k]));
        local.extend(p.position[k].iter());
        local.push(p.radius[k]);
        local.extend(p.velocity[k].iter());
        local.push(f64::from_bits(p.group[k]));
    }
    let Some(pieces) = system.communicator.gather(&local) else {
        return Ok(());
    };
    let mut grains: Vec<&[f64]> = pieces.iter().flat_map(|m| m.chunks_exact(9)).collect();
    grains.sort_by_key(|g| g[0].to_bits());
    let header = if dim == 2 {
        "x,y,radius,vx,vy,group"
    } else {
        "x,y,z,radius,vx,vy,vz,group"
    };
    write_whole(&dir.join("final_particles.csv"), |file| {
        writeln!(file, "{header}")?;
        for grain in grains {
            let mut row: Vec<String> = (0..dim).map(|a| format!("{:.17e}", grain[1 + a])).collect();
            row.push(format!("{:.17e}", grain[4]));
            row.extend((0..dim).map(|a| format!("{:.17e}", grain[5 + a])));
            row.push(grain[8].to_bits().to_string());
            writeln!(file, "{}", row.join(","))?;
        }
        Ok(())
    })
}
