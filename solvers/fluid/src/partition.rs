//! How the cells of a flow are shared among ranks.
//!
//! The ranks form a process grid over the axes the direct solvers
//! transform (x, and y in 3D): each rank owns a box of whole cells with the
//! full extent of the last axis (z in 3D, y in 2D), the one solved by
//! elimination, so that walls, stretching and the quadratic wall closure of
//! that axis stay local. Cells are shared as evenly as whole numbers allow:
//! rank `c` of `p` along an axis of `N` cells owns cells `⌊cN/p⌋ ..
//! ⌊(c+1)N/p⌋`.
//!
//! A rank keeps one ghost layer on each side, as on one rank; across a
//! face shared with another rank (or a periodic end split among ranks) the
//! ghosts are the neighbour's cells next to the face, exchanged by
//! [`crate::boundary::fill_ghosts_on`]. Faces normal to a split axis on a
//! shared face belong to the lower rank: a rank owns the faces `1..=n` of
//! its cells, its face 0 is a ghost (the lower neighbour's face n).

use crate::error::FluidError;
use crate::grid::Grid;
use grainflow_core::{grid_coords, grid_neighbour, grid_rank};

/// One rank's share of the cells of a global grid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Partition {
    /// Ranks along each axis (1 along the last axis and inactive ones).
    pub ranks: [usize; 3],
    /// This rank's position in the process grid.
    pub coords: [usize; 3],
    /// Cells of the global grid along each axis.
    pub global_cells: [usize; 3],
}

impl Partition {
    /// One rank owning every cell.
    pub fn serial(global: &Grid) -> Self {
        Partition {
            ranks: [1; 3],
            coords: [0; 3],
            global_cells: global.cells,
        }
    }

    /// The share of `rank` in a process grid of `ranks` (x fastest). Refuses
    /// a split of the last axis, a rank with fewer than two cells along a
    /// split axis, and a grid whose last axis has fewer cells than ranks
    /// along another (the solvers' pencils split it among them).
    pub fn new(global: &Grid, ranks: [usize; 3], rank: usize) -> Result<Self, FluidError> {
        let line = global.line_axis();
        for axis in 0..3 {
            if ranks[axis] == 0 || (ranks[axis] > 1 && axis >= line) {
                return Err(FluidError::Parameter(format!(
                    "the flow's process grid {ranks:?} splits axis {axis}; allowed: ranks along \
                     x{} only, the last axis whole on every rank",
                    if line == 2 { " and y" } else { "" }
                )));
            }
            if axis < line && global.cells[axis] < 2 * ranks[axis] {
                return Err(FluidError::Parameter(format!(
                    "{} cells along axis {axis} cannot be shared by {} ranks (two cells each at \
                     least)",
                    global.cells[axis], ranks[axis]
                )));
            }
        }
        let widest = ranks.iter().copied().max().unwrap_or(1);
        if global.cells[line] <= widest {
            return Err(FluidError::Parameter(format!(
                "{} cells along the last axis cannot be shared by {widest} ranks in the direct \
                 solvers' pencils (more cells than ranks along an axis are needed)",
                global.cells[line]
            )));
        }
        Ok(Partition {
            ranks,
            coords: grid_coords(ranks, rank),
            global_cells: global.cells,
        })
    }

    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.ranks.iter().product()
    }

    /// The rank at process-grid coordinates `coords`.
    pub fn rank_at(&self, coords: [usize; 3]) -> usize {
        grid_rank(self.ranks, coords)
    }

    /// First global cell of the rank at `coord` along `axis` (`coord =
    /// ranks` gives the cell count).
    pub fn cell_start(&self, axis: usize, coord: usize) -> usize {
        coord * self.global_cells[axis] / self.ranks[axis]
    }

    /// This rank's first global cell along each axis.
    pub fn offset(&self) -> [usize; 3] {
        self.share_at(self.coords).0
    }

    /// This rank's cells along each axis.
    pub fn cells(&self) -> [usize; 3] {
        self.share_at(self.coords).1
    }

    /// Whether this rank's box reaches the lower (`side` 0) or upper (1)
    /// face of the domain along `axis`.
    pub fn at_domain_face(&self, axis: usize, side: usize) -> bool {
        match side {
            0 => self.coords[axis] == 0,
            _ => self.coords[axis] + 1 == self.ranks[axis],
        }
    }

    /// The rank across this box's `side` face along `axis`, wrapping across
    /// a periodic end; None at a wall of the domain or along an axis of one
    /// rank (whose periodic ghosts are local copies).
    pub fn neighbour(&self, axis: usize, side: usize, periodic: bool) -> Option<usize> {
        if self.ranks[axis] == 1 {
            return None;
        }
        grid_neighbour(self.ranks, self.coords, axis, side == 1, periodic)
    }

    /// The first cell and the cells of `rank` along each axis.
    pub fn share_of(&self, rank: usize) -> ([usize; 3], [usize; 3]) {
        self.share_at(grid_coords(self.ranks, rank))
    }

    /// The first cell and the cells of the rank at `coords`.
    fn share_at(&self, coords: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let start = [0, 1, 2].map(|axis| self.cell_start(axis, coords[axis]));
        let end = [0, 1, 2].map(|axis| self.cell_start(axis, coords[axis] + 1));
        (start, [0, 1, 2].map(|axis| end[axis] - start[axis]))
    }

    /// This rank's grid: its cells of `global`, with the same spacing.
    pub fn local_grid(&self, global: &Grid) -> Grid {
        global.sub_grid(self.offset(), self.cells())
    }
}

/// The process grid of a flow on `size` ranks: among the splits of x (2D)
/// or of x and y (3D) whose ranks hold at least two cells along each split
/// axis, the one with the least area of cuts between ranks; among equal
/// areas, the one with more ranks along x (a slab along x on one node
/// solves without transposes, `poisson`).
pub fn flow_process_grid(global: &Grid, size: usize) -> Result<[usize; 3], FluidError> {
    let line = global.line_axis();
    let mut best: Option<(f64, [usize; 3])> = None;
    for nx in (1..=size).rev().filter(|&n| size.is_multiple_of(n)) {
        let ny = size / nx;
        if line == 1 && ny > 1 {
            continue;
        }
        let ranks = [nx, ny, 1];
        if Partition::new(global, ranks, 0).is_err() {
            continue;
        }
        // Cut areas in cells: a cut normal to x crosses ny·nz cells.
        let [cx, cy, cz] = global.cells.map(|c| c as f64);
        let area = (nx - 1) as f64 * cy * cz + (ny - 1) as f64 * cx * cz;
        if best.is_none_or(|(a, _)| area < a) {
            best = Some((area, ranks));
        }
    }
    best.map(|(_, ranks)| ranks).ok_or_else(|| {
        FluidError::Parameter(format!(
            "{size} ranks cannot share the grid {:?}: each needs two cells along the split axes \
             (x{}), and the last axis at least as many cells as ranks along one of them",
            &global.cells[..global.dim()],
            if line == 2 { ", y" } else { "" }
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_core::Dimension;

    #[test]
    fn the_flow_process_grid_cuts_least_and_prefers_x_among_equals() {
        let grid = |cells: [usize; 3]| Grid::new(Dimension::Three, cells, [0.0; 3], [1.0; 3]);
        // A cube on 2 ranks: either cut has the same area; x is taken.
        assert_eq!(
            flow_process_grid(&grid([32, 32, 32]), 2).unwrap(),
            [2, 1, 1]
        );
        // Longer along y: the cut across y is the smaller one.
        assert_eq!(
            flow_process_grid(&grid([32, 64, 32]), 2).unwrap(),
            [1, 2, 1]
        );
        // 4 ranks on a cube: two cuts of area 32² beat three.
        assert_eq!(
            flow_process_grid(&grid([32, 32, 32]), 4).unwrap(),
            [2, 2, 1]
        );
        // Thin along x: cuts across y are the smallest.
        assert_eq!(flow_process_grid(&grid([4, 32, 32]), 4).unwrap(), [1, 4, 1]);
    }
}
