//! Boundary conditions on the faces of the domain and the ghost values that
//! impose them on the staggered grid.
//!
//! A wall condition becomes, for each discrete field and axis, an
//! [`EndCondition`]:
//!
//! - the velocity component normal to a wall lives on the wall face itself:
//!   its value there is prescribed (`DirichletFace`);
//! - a tangential component sits half a cell off the wall: no-slip and a
//!   moving wall set the ghost so that the linear interpolation to the wall
//!   equals the wall velocity, `u_ghost = 2 u_wall − u_first`
//!   (`DirichletCell`); free slip mirrors it, `u_ghost = u_first`
//!   (`Neumann`, zero shear);
//! - pressure (and the projection's correction) has a zero normal
//!   gradient at every wall (`Neumann`), which with the normal velocity
//!   fixed on the wall face makes the projection exact.

use crate::error::FluidError;
use crate::grid::{Block, Grid, Location};

/// The condition on one face of the domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundaryCondition {
    /// The opposite face is the neighbour.
    Periodic,
    /// Wall at rest.
    NoSlip,
    /// Impermeable wall without shear stress.
    FreeSlip,
    /// Wall sliding in its own plane at this velocity (m/s); the component
    /// normal to the wall must be zero.
    MovingWall([f64; 3]),
}

/// Which discrete relation closes a line of unknowns at one end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndKind {
    Periodic,
    /// Zero gradient: the ghost equals the first unknown.
    Neumann,
    /// Value prescribed half a cell beyond the first unknown, by the ghost.
    DirichletCell,
    /// Value prescribed on the boundary face, which is not an unknown.
    DirichletFace,
}

/// An end kind and the prescribed value (unused for periodic and Neumann ends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndCondition {
    pub kind: EndKind,
    pub value: f64,
}

/// End conditions of one field: `[axis][0 lower, 1 upper]`.
pub type FieldEnds = [[EndCondition; 2]; 3];

/// The conditions on the six faces of the domain: `faces[axis][side]`,
/// side 0 the lower face, 1 the upper face. In 2D the z entries are unused.
#[derive(Clone, Debug, PartialEq)]
pub struct Boundaries {
    pub faces: [[BoundaryCondition; 2]; 3],
}

impl Boundaries {
    /// Periodic along every axis.
    pub fn periodic() -> Self {
        Boundaries {
            faces: [[BoundaryCondition::Periodic; 2]; 3],
        }
    }

    /// The same conditions with `lower` and `upper` on the faces normal to `axis`.
    pub fn with(mut self, axis: usize, lower: BoundaryCondition, upper: BoundaryCondition) -> Self {
        self.faces[axis] = [lower, upper];
        self
    }

    /// Checks what the solvers rely on: periodicity on both faces of an
    /// axis or neither, moving walls that slide in their plane, and on the
    /// axes solved by transforms (all but the last active one) the same
    /// kind of condition on both faces.
    pub fn validate(&self, grid: &Grid) -> Result<(), FluidError> {
        let dim = grid.dim();
        for axis in 0..dim {
            let [lower, upper] = self.faces[axis];
            let periodic = [lower, upper].map(|c| c == BoundaryCondition::Periodic);
            if periodic[0] != periodic[1] {
                return Err(FluidError::Boundary(format!(
                    "axis {axis}: periodic on one face only ({lower:?}, {upper:?})"
                )));
            }
            for condition in [lower, upper] {
                if let BoundaryCondition::MovingWall(velocity) = condition {
                    if velocity[axis] != 0.0 {
                        return Err(FluidError::Boundary(format!(
                            "axis {axis}: a moving wall slides in its plane; its normal velocity {} must be 0",
                            velocity[axis]
                        )));
                    }
                }
            }
        }
        let line_axis = dim - 1;
        for component in 0..dim {
            let ends = self.velocity_ends(grid, component);
            for (axis, end) in ends.iter().enumerate().take(line_axis) {
                if end[0].kind != end[1].kind {
                    return Err(FluidError::Boundary(format!(
                        "axis {axis}: faces {:?} and {:?} differ in kind; walls of different kinds \
                         are allowed only along the last axis ({line_axis})",
                        self.faces[axis][0], self.faces[axis][1]
                    )));
                }
            }
        }
        Ok(())
    }

    /// End conditions of velocity component `component`.
    pub fn velocity_ends(&self, grid: &Grid, component: usize) -> FieldEnds {
        let mut ends = [[PERIODIC; 2]; 3];
        for axis in 0..grid.dim() {
            for side in 0..2 {
                ends[axis][side] = match self.faces[axis][side] {
                    BoundaryCondition::Periodic => PERIODIC,
                    condition if axis == component => EndCondition {
                        kind: EndKind::DirichletFace,
                        value: wall_velocity(condition)[component],
                    },
                    BoundaryCondition::FreeSlip => EndCondition {
                        kind: EndKind::Neumann,
                        value: 0.0,
                    },
                    condition => EndCondition {
                        kind: EndKind::DirichletCell,
                        value: wall_velocity(condition)[component],
                    },
                };
            }
        }
        ends
    }

    /// End conditions of pressure: zero normal gradient at every wall.
    pub fn pressure_ends(&self, grid: &Grid) -> FieldEnds {
        let mut ends = [[PERIODIC; 2]; 3];
        for axis in 0..grid.dim() {
            for side in 0..2 {
                if self.faces[axis][side] != BoundaryCondition::Periodic {
                    ends[axis][side] = EndCondition {
                        kind: EndKind::Neumann,
                        value: 0.0,
                    };
                }
            }
        }
        ends
    }
}

const PERIODIC: EndCondition = EndCondition {
    kind: EndKind::Periodic,
    value: 0.0,
};

fn wall_velocity(condition: BoundaryCondition) -> [f64; 3] {
    match condition {
        BoundaryCondition::MovingWall(velocity) => velocity,
        _ => [0.0; 3],
    }
}

/// The same ends with every prescribed value set to zero: the conditions
/// met by an increment of a field whose boundary values do not change.
pub fn homogeneous(ends: &FieldEnds) -> FieldEnds {
    ends.map(|pair| pair.map(|end| EndCondition { value: 0.0, ..end }))
}

/// The padded indices of a field's unknowns: every owned cell, except that
/// along an axis with prescribed face values the boundary faces (0 and n)
/// are not unknowns.
pub fn unknowns(grid: &Grid, ends: &FieldEnds) -> Block {
    let mut block = grid.cell_block();
    for (axis, end) in ends.iter().enumerate().take(grid.dim()) {
        if end[0].kind == EndKind::DirichletFace {
            debug_assert_eq!(end[1].kind, EndKind::DirichletFace);
            block.end[axis] -= 1;
        }
    }
    block
}

/// Sets the ghost values (and the prescribed boundary-face values) of
/// `field` from its end conditions. Axes are filled one after the other
/// over the whole padded extent of the others, so edge and corner ghosts
/// are consistent (periodic corners wrap twice).
pub fn fill_ghosts(grid: &Grid, field: &mut [f64], location: Location, ends: &FieldEnds) {
    let padded = grid.padded();
    for axis in 0..grid.dim() {
        let n = grid.cells[axis];
        let stride = grid.stride(axis);
        let mut line_block = Block {
            start: [0; 3],
            end: padded,
        };
        line_block.end[axis] = 1;
        let [lower, upper] = ends[axis];
        if matches!(lower.kind, EndKind::DirichletFace)
            || matches!(upper.kind, EndKind::DirichletFace)
        {
            debug_assert_eq!(location, Location::Face(axis));
        }
        grid.for_each(&line_block, |first, _| {
            let at = |i: usize| first + i * stride;
            match lower.kind {
                EndKind::Periodic => field[at(0)] = field[at(n)],
                EndKind::Neumann => field[at(0)] = field[at(1)],
                EndKind::DirichletCell => field[at(0)] = 2.0 * lower.value - field[at(1)],
                EndKind::DirichletFace => field[at(0)] = lower.value,
            }
            match upper.kind {
                EndKind::Periodic => field[at(n + 1)] = field[at(1)],
                EndKind::Neumann => field[at(n + 1)] = field[at(n)],
                EndKind::DirichletCell => field[at(n + 1)] = 2.0 * upper.value - field[at(n)],
                EndKind::DirichletFace => {
                    field[at(n)] = upper.value;
                    // Odd reflection about the wall face; no stencil of an
                    // unknown reaches it, it only keeps the ghost finite.
                    field[at(n + 1)] = 2.0 * upper.value - field[at(n - 1)];
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_core::Dimension;

    #[test]
    fn wall_conditions_become_end_conditions_per_component() {
        let grid = Grid::new(Dimension::Two, [4, 4, 1], [0.0; 3], [1.0; 3]);
        let boundaries = Boundaries::periodic().with(
            1,
            BoundaryCondition::NoSlip,
            BoundaryCondition::MovingWall([2.0, 0.0, 0.0]),
        );
        boundaries.validate(&grid).unwrap();
        let u = boundaries.velocity_ends(&grid, 0);
        assert_eq!(u[0][0].kind, EndKind::Periodic);
        assert_eq!(u[1][0].kind, EndKind::DirichletCell);
        assert_eq!(u[1][1].value, 2.0);
        let v = boundaries.velocity_ends(&grid, 1);
        assert_eq!(v[1][1].kind, EndKind::DirichletFace);
        assert_eq!(v[1][1].value, 0.0);
        assert_eq!(boundaries.pressure_ends(&grid)[1][0].kind, EndKind::Neumann);
        assert_eq!(unknowns(&grid, &v).end, [5, 4, 1]);
    }

    #[test]
    fn invalid_conditions_are_refused() {
        let grid = Grid::new(Dimension::Three, [4, 4, 4], [0.0; 3], [1.0; 3]);
        let one_sided =
            Boundaries::periodic().with(0, BoundaryCondition::Periodic, BoundaryCondition::NoSlip);
        assert!(one_sided.validate(&grid).is_err());
        let mixed_transformed =
            Boundaries::periodic().with(0, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip);
        assert!(mixed_transformed.validate(&grid).is_err());
        let mixed_last =
            Boundaries::periodic().with(2, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip);
        assert!(mixed_last.validate(&grid).is_ok());
        let leaking = Boundaries::periodic().with(
            2,
            BoundaryCondition::NoSlip,
            BoundaryCondition::MovingWall([1.0, 0.0, 0.5]),
        );
        assert!(leaking.validate(&grid).is_err());
    }

    #[test]
    fn ghosts_interpolate_to_the_wall_value() {
        let grid = Grid::new(Dimension::Two, [3, 4, 1], [0.0; 3], [1.0; 3]);
        let boundaries = Boundaries::periodic().with(
            1,
            BoundaryCondition::MovingWall([1.5, 0.0, 0.0]),
            BoundaryCondition::FreeSlip,
        );
        let ends = boundaries.velocity_ends(&grid, 0);
        let mut u = grid.zeros();
        grid.for_each(&grid.cell_block(), |index, [i, j, _]| {
            u[index] = (i + 10 * j) as f64
        });
        fill_ghosts(&grid, &mut u, Location::Face(0), &ends);
        for i in 0..5 {
            // Wall value is the mean of ghost and first cell.
            assert_eq!(0.5 * (u[grid.index(i, 0, 0)] + u[grid.index(i, 1, 0)]), 1.5);
            assert_eq!(u[grid.index(i, 5, 0)], u[grid.index(i, 4, 0)]);
        }
        // Periodic in x, including the corners.
        assert_eq!(u[grid.index(0, 2, 0)], u[grid.index(3, 2, 0)]);
        assert_eq!(u[grid.index(4, 0, 0)], u[grid.index(1, 0, 0)]);
    }
}
