//! The first layer of cells along the walls of the flow domain, which the
//! moving grains leave to the fluid (see [`crate::forcing`]).

use grainflow_fluid::{Boundaries, BoundaryCondition, Grid, Location};

/// The first layer of cells along a wall of the flow domain, whose faces
/// the grains do not force: the tangential components at the cells'
/// centres, half a cell off the wall, and the normal component on their
/// far face, a cell off (the normal component on the wall is not an
/// unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallLayer {
    /// The axis normal to the wall.
    pub axis: usize,
    /// The wall's coordinate along `axis` (m).
    pub wall: f64,
    /// +1 for a lower wall (the fluid on its upper side), −1 for an upper one.
    pub inward: f64,
    /// The layer's depth: one cell along `axis` (m).
    pub depth: f64,
}

impl WallLayer {
    /// The first layer of cells along every wall of the domain
    /// `lower`–`upper` (no-slip, free-slip or moving: every face but the
    /// periodic and open ones), on `grid`, a rank's share of it.
    pub fn along_walls(
        grid: &Grid,
        boundaries: &Boundaries,
        lower: [f64; 3],
        upper: [f64; 3],
    ) -> Vec<WallLayer> {
        let mut layers = Vec::new();
        for axis in 0..grid.dim() {
            for (side, wall, inward) in [(0, lower[axis], 1.0), (1, upper[axis], -1.0)] {
                let is_wall = matches!(
                    boundaries.faces[axis][side],
                    BoundaryCondition::NoSlip
                        | BoundaryCondition::FreeSlip
                        | BoundaryCondition::MovingWall(_)
                );
                if is_wall {
                    layers.push(WallLayer {
                        axis,
                        wall,
                        inward,
                        depth: grid.spacing[axis],
                    });
                }
            }
        }
        layers
    }

    /// Whether the coordinate `x` along the axis lies in the layer (its
    /// far face included, to round-off).
    #[inline]
    pub(crate) fn holds(&self, x: f64) -> bool {
        let distance = self.inward * (x - self.wall);
        distance > 0.0 && self.within(x, 0.0)
    }

    /// Whether the coordinate `x` along the axis lies within `reach` of
    /// the layer or in it (its far face included, to round-off).
    #[inline]
    pub(crate) fn within(&self, x: f64, reach: f64) -> bool {
        self.inward * (x - self.wall) - reach <= self.depth * (1.0 + 1e-9)
    }
}

impl WallLayer {
    /// Sets to zero the fractions `alpha` of the row of faces of
    /// `component` that starts at the flat index `first` that lie in the
    /// layer.
    pub(crate) fn clear_row(&self, grid: &Grid, component: usize, first: usize, alpha: &mut [f64]) {
        let location = Location::Face(component);
        let (line, plane) = (grid.stride(1), grid.stride(2));
        let point = [first % line, first % plane / line, first / plane];
        if self.axis == 0 {
            for (i, value) in (point[0]..).zip(alpha.iter_mut()) {
                if self.holds(grid.coordinate(location, 0, i)) {
                    *value = 0.0;
                }
            }
        } else if self.holds(grid.coordinate(location, self.axis, point[self.axis])) {
            alpha.fill(0.0);
        }
    }
}
