//! grainflow output writers: VTK PolyData particle files with a ParaView
//! time-series index (`.pvd`), and CSV series written row by row.

pub mod csv;
pub mod vtk;

pub use csv::CsvSeries;
pub use vtk::{ParticleFrame, PvdIndex};
