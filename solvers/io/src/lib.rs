//! grainflow output writers: VTK PolyData particle files and ImageData
//! field files with a ParaView time-series index (`.pvd`), and CSV series
//! written row by row.

pub mod csv;
pub mod vtk;

pub use csv::CsvSeries;
pub use vtk::{
    write_field_pieces_index, write_particle_pieces_index, CellLayout, FieldFrame, FieldPiece,
    ParticleFrame, PvdIndex,
};
