//! One field frame in HDF5: cell-centred arrays over the global grid,
//! each rank writing its block.
//!
//! The file `fields_NNNNNN.h5` holds, for a grid of `[nx, ny, nz]` cells
//! (one cell along z in 2D):
//! - each scalar as a dataset `NAME` of shape `[nz, ny, nx]` (float64);
//! - each vector as a dataset `NAME` of shape `[nz, ny, nx, 3]`,
//!   components x, y, z;
//! - the group `grid`: datasets `x`, `y`, `z` of the face coordinates
//!   along each axis (`nx + 1`, … values), the attribute `layout`
//!   (`"uniform"` or `"rectilinear"`), and on a uniform grid the
//!   attributes `origin` and `spacing` (x, y, z);
//! - the attributes `time` [s] and `cells` (`[nx, ny, nz]`) on the root.
//!
//! Cell `(i, j, k)` is at `[k][j][i]`: the arrays are C-ordered with x
//! fastest, which is XDMF's and the solver's order, so a rank's block is a
//! hyperslab written as it is held.

use super::{block, check_name, invalid, scalar_attribute, text_attribute, write_frame, Writers};
use crate::vtk::CellLayout;
use hdf5_metno::Group;
use std::path::Path;

/// Cell-centred fields at one output time, seen from one writer: its block
/// of `cells` cells starting at cell `offset` of a global grid of
/// `global_cells` (the whole grid on one rank).
pub struct FieldFrameH5<'a> {
    /// Simulated time of the frame [s].
    pub time: f64,
    /// Cells of the whole grid along x, y, z (1 along z in 2D).
    pub global_cells: [usize; 3],
    /// This writer's first cell in the whole grid.
    pub offset: [usize; 3],
    /// This writer's cells along x, y, z.
    pub cells: [usize; 3],
    /// The cells' geometry: a uniform grid's origin and spacing (the same
    /// on every writer), or this writer's face coordinates (`cells + 1`
    /// along each axis, from its first face).
    pub layout: CellLayout<'a>,
    /// Scalar fields, one value per cell of the block, x fastest.
    pub scalars: &'a [(&'a str, &'a [f64])],
    /// Vector fields, one `[x, y, z]` per cell of the block, x fastest.
    pub vectors: &'a [(&'a str, &'a [[f64; 3]])],
}

impl FieldFrameH5<'_> {
    /// Writes the frame to `path` with every writer (collective: each calls
    /// it with its own block, the same names and the same global grid).
    pub fn write(&self, path: &Path, writers: &Writers) -> std::io::Result<()> {
        self.check(path)?;
        write_frame(path, writers, |file| self.fill(file, writers))
    }

    /// Refuses a frame whose arrays do not match its block.
    fn check(&self, path: &Path) -> std::io::Result<()> {
        let n: usize = self.cells.iter().product();
        for axis in 0..3 {
            if self.offset[axis] + self.cells[axis] > self.global_cells[axis] {
                return Err(invalid(
                    path,
                    format!(
                        "block {:?} + {:?} beyond the grid {:?}",
                        self.offset, self.cells, self.global_cells
                    ),
                ));
            }
            if let CellLayout::Rectilinear { faces } = self.layout {
                if faces[axis].len() != self.cells[axis] + 1 {
                    return Err(invalid(
                        path,
                        format!(
                            "{} face coordinates along axis {axis} for {} cells",
                            faces[axis].len(),
                            self.cells[axis]
                        ),
                    ));
                }
            }
        }
        let lengths = self
            .scalars
            .iter()
            .map(|(name, v)| (*name, v.len()))
            .chain(self.vectors.iter().map(|(name, v)| (*name, v.len())));
        for (name, len) in lengths {
            check_name(path, name)?;
            if len != n {
                return Err(invalid(
                    path,
                    format!("{name} has {len} values for {n} cells"),
                ));
            }
        }
        Ok(())
    }

    fn fill(&self, file: &hdf5_metno::File, writers: &Writers) -> hdf5_metno::Result<()> {
        let [gx, gy, gz] = self.global_cells;
        let [ox, oy, oz] = self.offset;
        let [nx, ny, nz] = self.cells;
        for (name, values) in self.scalars {
            let dataset = file
                .new_dataset::<f64>()
                .shape([gz, gy, gx])
                .create(*name)?;
            writers.write_block(&dataset, block(values, &[nz, ny, nx])?, &[oz, oy, ox])?;
        }
        for (name, values) in self.vectors {
            let dataset = file
                .new_dataset::<f64>()
                .shape([gz, gy, gx, 3])
                .create(*name)?;
            let values = block(values.as_flattened(), &[nz, ny, nx, 3])?;
            writers.write_block(&dataset, values, &[oz, oy, ox, 0])?;
        }
        self.fill_grid(&file.create_group("grid")?, writers)?;
        scalar_attribute(file, "time", &self.time)?;
        file.new_attr::<u64>()
            .shape([3])
            .create("cells")?
            .write(&self.global_cells.map(|c| c as u64))?;
        Ok(())
    }

    /// The group `grid`: face coordinates along each axis. Along an axis,
    /// the ranks at the lower end of the other two axes write their faces
    /// (every face once: a rank also writes its upper face only at the
    /// grid's upper end); the others take part with nothing.
    fn fill_grid(&self, grid: &Group, writers: &Writers) -> hdf5_metno::Result<()> {
        let faces: [Vec<f64>; 3] = [0, 1, 2].map(|axis| match self.layout {
            CellLayout::Uniform { origin, spacing } => (0..=self.cells[axis])
                .map(|i| origin[axis] + (self.offset[axis] + i) as f64 * spacing[axis])
                .collect(),
            CellLayout::Rectilinear { faces } => faces[axis].to_vec(),
        });
        for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
            let dataset = grid
                .new_dataset::<f64>()
                .shape([self.global_cells[axis] + 1])
                .create(name)?;
            let others_at_start = (0..3).filter(|&a| a != axis).all(|a| self.offset[a] == 0);
            let start = self.offset[axis];
            let at_end = start + self.cells[axis] == self.global_cells[axis];
            let count = if others_at_start {
                self.cells[axis] + usize::from(at_end)
            } else {
                0
            };
            writers.write_block(&dataset, block(&faces[axis][..count], &[count])?, &[start])?;
        }
        match self.layout {
            CellLayout::Uniform { origin, spacing } => {
                text_attribute(grid, "layout", "uniform")?;
                grid.new_attr::<f64>()
                    .shape([3])
                    .create("origin")?
                    .write(&origin)?;
                grid.new_attr::<f64>()
                    .shape([3])
                    .create("spacing")?
                    .write(&spacing)?;
            }
            CellLayout::Rectilinear { .. } => text_attribute(grid, "layout", "rectilinear")?,
        }
        Ok(())
    }
}
