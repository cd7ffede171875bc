//! grainflow output writers: VTK PolyData particle files and ImageData
//! field files with a ParaView time-series index (`.pvd`), and CSV series
//! written row by row. Files written in one go are written whole
//! ([`whole`]): under a temporary name, then renamed. With the cargo
//! feature `hdf5`, [`hdf5`] writes the same frames as HDF5 files indexed
//! by XDMF (one file per frame on any number of MPI ranks).

pub mod csv;
#[cfg(feature = "hdf5")]
pub mod hdf5;
pub mod vtk;
pub mod vtk_reader;
pub mod whole;

pub use csv::CsvSeries;
pub use vtk::{
    write_field_pieces_index, write_particle_pieces_index, CellLayout, FieldFrame, FieldPiece,
    ParticleFrame, PvdIndex,
};
pub use vtk_reader::{read_vtk, RawArray, VtkFile};
pub use whole::{temporary_path, write_whole, write_whole_bytes, TEMPORARY_SUFFIX};
