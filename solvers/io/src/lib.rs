//! grainflow output writers: VTK PolyData particle files and ImageData
//! field files with a ParaView time-series index (`.pvd`), and CSV series
//! written row by row. Files written in one go are written whole
//! ([`whole`]): under a temporary name, then renamed.

pub mod csv;
pub mod vtk;
pub mod whole;

pub use csv::CsvSeries;
pub use vtk::{
    write_field_pieces_index, write_particle_pieces_index, CellLayout, FieldFrame, FieldPiece,
    ParticleFrame, PvdIndex,
};
pub use whole::{temporary_path, write_whole, write_whole_bytes, TEMPORARY_SUFFIX};
