//! HDF5 frames of a run (`output.format = "hdf5"`, cargo feature `hdf5`):
//! `fields/fields_NNNNNN.h5` indexed by `fields.xdmf` and
//! `particles/particles_NNNNNN.h5` indexed by `particles.xdmf`, one file
//! per output time on any number of MPI ranks (parallel HDF5 with the
//! feature `mpi`: every rank writes its share of the one file). The
//! datasets are described in `grainflow_io::hdf5`; the indices open in
//! ParaView and VisIt (XDMF 3), the frames in h5py
//! (`postprocess/read_output.py` reads both formats).
//!
//! The writers of the run loop (`output::writers`) call, on every rank
//! (the writes are collective):
//!
//! ```text
//! // fluid scenes, beside or instead of FieldFiles:
//! let mut fields = Hdf5Fields::create(dir, case, &communicator)?;  // None unless
//!                                     // output.fields and output.format = "hdf5"
//! if let Some(f) = &mut fields { f.write(&mut solver, density, &[("solid_fraction", &phi)])?; }
//! // scenes with grains, at each particle output:
//! let mut particles = Hdf5Particles::create(dir, case, &communicator)?;  // likewise
//! if let Some(p) = &mut particles { p.write(&system)?; }
//! ```
//!
//! An error on one rank leaves the others in a collective call: the run
//! loop stops the job with `Communicator::abort_others`, as for the VTK
//! files.

use crate::case::{Case, OutputFormat};
use crate::output::fields::{cell_layout, CellFields};
use grainflow_core::Communicator;
use grainflow_dem::DemSystem;
use grainflow_fluid::FlowSolver;
use grainflow_io::hdf5::{FieldFrameH5, FieldGridDescription, ParticleFrameH5, Writers, XdmfIndex};
use std::path::{Path, PathBuf};

/// Whether `case` asks for HDF5 frames.
fn wants_hdf5(case: &Case) -> bool {
    case.output.format == OutputFormat::Hdf5
}

/// The writers of a frame: every rank of `communicator` together.
fn writers(communicator: &Communicator) -> Writers<'_> {
    #[cfg(feature = "mpi")]
    if let Some(world) = communicator.mpi() {
        return Writers::mpi(world);
    }
    let _ = communicator;
    Writers::serial()
}

/// The field frames of a scene with a fluid: at each output the
/// cell-centred velocity, pressure [Pa], vorticity and any extra cell
/// scalars (e.g. `solid_fraction`) of the whole grid in
/// `fields/fields_NNNNNN.h5`, listed in `fields.xdmf`.
pub struct Hdf5Fields {
    dir: PathBuf,
    communicator: Communicator,
    /// `fields.xdmf` (the root's).
    index: Option<XdmfIndex>,
    /// Lower corner of the domain: the origin of a uniform grid.
    origin: [f64; 3],
    frames: usize,
    cell_fields: CellFields,
}

impl Hdf5Fields {
    /// The field frames in `dir` if `output.fields` is set and
    /// `output.format` is `"hdf5"` (else `None`); creates `dir/fields`.
    /// Called on every rank.
    pub fn create(
        dir: &Path,
        case: &Case,
        communicator: &Communicator,
        resumed: (usize, Vec<String>),
    ) -> std::io::Result<Option<Self>> {
        if !case.output.fields || !wants_hdf5(case) {
            return Ok(None);
        }
        let folder = dir.join("fields");
        std::fs::create_dir_all(&folder)
            .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", folder.display())))?;
        let mut origin = [0.0; 3];
        origin[..case.domain.lower.len()].copy_from_slice(&case.domain.lower);
        Ok(Some(Hdf5Fields {
            dir: dir.to_path_buf(),
            communicator: communicator.clone(),
            index: communicator.is_root().then(|| {
                XdmfIndex::with_grids(dir.join("fields.xdmf"), "fields", resumed.1.clone())
            }),
            origin,
            frames: resumed.0,
            cell_fields: CellFields::default(),
        }))
    }

    /// What a checkpoint records: the frames written and the index's grids
    /// (the root's).
    pub fn record(&self) -> (usize, Vec<String>) {
        let grids = self
            .index
            .as_ref()
            .map_or_else(Vec::new, |i| i.grids().to_vec());
        (self.frames, grids)
    }

    /// A frame of the current flow with `extra` cell scalars (one value per
    /// cell of this rank, x fastest, as `FieldFiles::write` takes them);
    /// collective. The frame is listed in `fields.xdmf` once whole.
    pub fn write(
        &mut self,
        solver: &mut FlowSolver,
        density: f64,
        extra: &[(&str, &[f64])],
    ) -> std::io::Result<()> {
        let fields = self.cell_fields.compute(solver, density);
        let grid = &solver.grid;
        let partition = solver.partition();
        let faces = [0, 1, 2].map(|axis| grid.face_coordinates(axis));
        let uniform = grid.is_uniform(grid.line_axis());
        let layout = cell_layout(grid, self.origin, &faces);
        let mut scalars: Vec<(&str, &[f64])> = vec![("pressure", &fields.pressure)];
        scalars.extend_from_slice(extra);
        let vectors: [(&str, &[[f64; 3]]); 2] = [
            ("velocity", &fields.velocity),
            ("vorticity", &fields.vorticity),
        ];
        let name = format!("fields/fields_{:06}.h5", self.frames);
        FieldFrameH5 {
            time: solver.time,
            global_cells: partition.global_cells,
            offset: partition.offset(),
            cells: grid.cells,
            layout,
            scalars: &scalars,
            vectors: &vectors,
        }
        .write(&self.dir.join(&name), &writers(&self.communicator))?;
        if let Some(index) = &mut self.index {
            let names: Vec<&str> = scalars.iter().map(|(n, _)| *n).collect();
            let description = FieldGridDescription {
                cells: partition.global_cells,
                uniform: uniform.then_some((self.origin, grid.spacing)),
                scalars: &names,
                vectors: &["velocity", "vorticity"],
            };
            index.add_fields(solver.time, &name, &description)?;
        }
        self.frames += 1;
        Ok(())
    }
}

/// The particle frames of a scene with grains: at each output every
/// grain's position, radius, velocity, spin, force, id, contact count and
/// fixed flag in `particles/particles_NNNNNN.h5`, listed in
/// `particles.xdmf`.
pub struct Hdf5Particles {
    dir: PathBuf,
    communicator: Communicator,
    /// `particles.xdmf` (the root's).
    index: Option<XdmfIndex>,
    frames: usize,
}

impl Hdf5Particles {
    /// The particle frames in `dir` if `output.particles` is set and
    /// `output.format` is `"hdf5"` (else `None`); creates `dir/particles`.
    /// Called on every rank.
    pub fn create(
        dir: &Path,
        case: &Case,
        communicator: &Communicator,
        resumed: (usize, Vec<String>),
    ) -> std::io::Result<Option<Self>> {
        if !case.output.particles || !wants_hdf5(case) {
            return Ok(None);
        }
        let folder = dir.join("particles");
        std::fs::create_dir_all(&folder)
            .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", folder.display())))?;
        Ok(Some(Hdf5Particles {
            dir: dir.to_path_buf(),
            communicator: communicator.clone(),
            index: communicator.is_root().then(|| {
                XdmfIndex::with_grids(dir.join("particles.xdmf"), "particles", resumed.1.clone())
            }),
            frames: resumed.0,
        }))
    }

    /// What a checkpoint records: the frames written and the index's grids
    /// (the root's).
    pub fn record(&self) -> (usize, Vec<String>) {
        let grids = self
            .index
            .as_ref()
            .map_or_else(Vec::new, |i| i.grids().to_vec());
        (self.frames, grids)
    }

    /// A frame of the grains each rank owns (collective); listed in
    /// `particles.xdmf` once whole.
    pub fn write(&mut self, system: &DemSystem) -> std::io::Result<()> {
        let p = &system.particles;
        let n = p.n_owned;
        let as_arrays =
            |v: &[grainflow_core::Vec3]| v[..n].iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>();
        let fixed: Vec<u8> = (0..n).map(|k| u8::from(p.is_fixed(k))).collect();
        // The count of the last force evaluation (none before the first).
        let contacts: Vec<u32> = (0..n)
            .map(|k| system.contacts.get(k).copied().unwrap_or(0))
            .collect();
        let name = format!("particles/particles_{:06}.h5", self.frames);
        let count = ParticleFrameH5 {
            time: system.time,
            id: &p.id[..n],
            position: &as_arrays(&p.position),
            velocity: &as_arrays(&p.velocity),
            angular_velocity: &as_arrays(&p.angular_velocity),
            force: &as_arrays(&p.force),
            radius: &p.radius[..n],
            contacts: &contacts,
            fixed: &fixed,
            group: &p.group[..n],
        }
        .write(&self.dir.join(&name), &writers(&self.communicator))?;
        if let Some(index) = &mut self.index {
            index.add_particles(system.time, &name, count)?;
        }
        self.frames += 1;
        Ok(())
    }
}
