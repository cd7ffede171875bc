//! Boundary conditions on the faces of the domain and the ghost values that
//! impose them on the staggered grid.
//!
//! A wall condition becomes, for each discrete field and axis, an
//! [`EndCondition`]:
//!
//! - the velocity component normal to a wall lives on the wall face itself:
//!   its value there is prescribed (`DirichletFace`);
//! - a tangential component sits half a cell off the wall, at `h/2`,
//!   `3h/2`, … . No-slip and a moving wall set the ghost (at `−h/2`) so
//!   that an interpolant through the ghost and the first cells takes the
//!   wall velocity at the wall:
//!   - along the last active axis (y in 2D, z in 3D: the wall-normal axis
//!     of a channel, solved by tridiagonal elimination) the interpolant is
//!     the parabola through the ghost and the first two cells,
//!     `u_ghost = (8 u_wall − 6 u_1 + u_2) / 3` (`DirichletCellQuadratic`;
//!     on a stretched axis the same parabola through the actual distances,
//!     [`Grid::wall_ghost_weights`]);
//!     the ghost is exact for any parabola (third order at the wall), so
//!     with the three-point Laplacian, exact for parabolas too, a steady
//!     Poiseuille or open-channel profile is reproduced to round-off;
//!   - along an axis solved by a transform the interpolant is the line
//!     through the ghost and the first cell, `u_ghost = 2 u_wall − u_1`
//!     (`DirichletCell`, second order: for a parabola `u = K y (H − y)` the
//!     steady discrete profile is the exact one shifted by `K h²/4`). That
//!     closure is kept there because the sine transform (DST-II) that
//!     diagonalises the second difference needs the odd reflection
//!     `u_ghost = −u_1` of the homogeneous condition; the quadratic ghost
//!     couples a second cell and has no such modes;
//!
//!   free slip mirrors the first cell, `u_ghost = u_1` (`Neumann`, zero
//!   shear), exact for a profile symmetric about the wall;
//! - pressure (and the projection's correction) has a zero normal
//!   gradient at every wall (`Neumann`), which with the normal velocity
//!   fixed on the wall face makes the projection exact;
//! - an outflow face (upper end of the last axis only) mirrors every
//!   velocity component (`Neumann`: zero normal gradient; the normal
//!   velocity on the face is then an unknown of the solves) and sets the
//!   pressure to zero on the face (`DirichletCell`, ghost `−p_n`), so the
//!   projection adjusts the flux out to what enters.
//!
//! Only the viscous term sees the tangential ghost: the explicit Laplacian
//! reads it and the Helmholtz solver builds the same closure into its
//! first and last rows. Convection reads it only in the flux through the
//! wall, where it is multiplied by the normal velocity on the wall face
//! (zero), and the divergence reads no tangential ghost.

use crate::error::FluidError;
use crate::grid::{Block, Grid, Location};
use crate::partition::Partition;
use grainflow_core::Communicator;

/// The condition on one face of the domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundaryCondition {
    /// The opposite face is the neighbour.
    Periodic,
    /// Wall at rest.
    NoSlip,
    /// Impermeable wall without shear stress.
    FreeSlip,
    /// Wall moving at this velocity (m/s): sliding in its plane, and with
    /// a normal component a porous wall that fluid crosses (blowing,
    /// suction, an inflow), which the opposite face must match unless it is
    /// an [`BoundaryCondition::Outflow`].
    MovingWall([f64; 3]),
    /// An open face the fluid leaves through: zero normal gradient of every
    /// velocity component, zero pressure on the face. Only the upper face
    /// of the last axis (z in 3D, y in 2D), whose lines are solved by
    /// elimination, where the normal velocity on the face is an unknown.
    /// The outflow must stay an outflow: fluid drawn back in through it
    /// carries no prescribed state.
    Outflow,
}

/// Which discrete relation closes a line of unknowns at one end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndKind {
    Periodic,
    /// Zero gradient: the ghost equals the first unknown.
    Neumann,
    /// Value prescribed half a cell beyond the first unknown, by a ghost
    /// extrapolated linearly: `ghost = 2 value − u_1`.
    DirichletCell,
    /// Value prescribed half a cell beyond the first unknown, by a ghost
    /// extrapolated quadratically: `ghost = (8 value − 6 u_1 + u_2) / 3`,
    /// exact for parabolas. Only along the last active axis, whose lines
    /// are solved by elimination (it has no transform); a line needs two
    /// unknowns, which every grid has (at least two cells per axis).
    DirichletCellQuadratic,
    /// Value prescribed on the boundary face, which is not an unknown.
    DirichletFace,
    /// Another rank's cells lie beyond: the ghosts are copies of them
    /// ([`fill_ghosts_on`]). Only along an axis split among ranks
    /// ([`crate::Partition`]), never the last one.
    Halo,
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
            let line_axis = dim - 1;
            if lower == BoundaryCondition::Outflow
                || (upper == BoundaryCondition::Outflow && axis != line_axis)
            {
                return Err(FluidError::Boundary(format!(
                    "axis {axis}: an outflow is allowed only on the upper face of the last axis \
                     ({line_axis})"
                )));
            }
            // Fluid may cross the faces of an axis (blowing through one,
            // suction through the other) if as much leaves as enters: the
            // projection's Neumann problem then has a solution. An outflow
            // takes whatever enters.
            let through = [lower, upper].map(|condition| wall_velocity(condition)[axis]);
            if upper != BoundaryCondition::Outflow && through[0] != through[1] {
                return Err(FluidError::Boundary(format!(
                    "axis {axis}: the normal velocities of its faces, {} and {}, differ: as much \
                     fluid must leave through one as enters through the other",
                    through[0], through[1]
                )));
            }
        }
        let line_axis = dim - 1;
        if !grid.is_uniform(line_axis) && self.faces[line_axis][0] == BoundaryCondition::Periodic {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis} is stretched and needs walls on both faces, not periodic \
                 ends"
            )));
        }
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

    /// End conditions of velocity component `component`. A component
    /// tangential to a no-slip or moving wall is closed by the quadratic
    /// ghost along the last active axis and the linear one along the
    /// others (see the module documentation).
    pub fn velocity_ends(&self, grid: &Grid, component: usize) -> FieldEnds {
        let mut ends = [[PERIODIC; 2]; 3];
        let line_axis = grid.dim() - 1;
        for axis in 0..grid.dim() {
            let wall_cell_kind = if axis == line_axis {
                EndKind::DirichletCellQuadratic
            } else {
                EndKind::DirichletCell
            };
            for side in 0..2 {
                ends[axis][side] = match self.faces[axis][side] {
                    BoundaryCondition::Periodic => PERIODIC,
                    BoundaryCondition::Outflow => EndCondition {
                        kind: EndKind::Neumann,
                        value: 0.0,
                    },
                    condition if axis == component => EndCondition {
                        kind: EndKind::DirichletFace,
                        value: wall_velocity(condition)[component],
                    },
                    BoundaryCondition::FreeSlip => EndCondition {
                        kind: EndKind::Neumann,
                        value: 0.0,
                    },
                    condition => EndCondition {
                        kind: wall_cell_kind,
                        value: wall_velocity(condition)[component],
                    },
                };
            }
        }
        ends
    }

    /// End conditions of pressure: zero normal gradient at every wall, zero
    /// value on an outflow face.
    pub fn pressure_ends(&self, grid: &Grid) -> FieldEnds {
        let mut ends = [[PERIODIC; 2]; 3];
        for axis in 0..grid.dim() {
            for side in 0..2 {
                ends[axis][side] = match self.faces[axis][side] {
                    BoundaryCondition::Periodic => PERIODIC,
                    BoundaryCondition::Outflow => EndCondition {
                        kind: EndKind::DirichletCell,
                        value: 0.0,
                    },
                    _ => EndCondition {
                        kind: EndKind::Neumann,
                        value: 0.0,
                    },
                };
            }
        }
        ends
    }

    /// Whether the upper face of the last axis is an outflow.
    pub fn has_outflow(&self, grid: &Grid) -> bool {
        self.faces[grid.line_axis()][1] == BoundaryCondition::Outflow
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

/// A rank's end conditions from those of the domain: along an axis split
/// among ranks every end that is not a face of the domain, and both ends
/// of a periodic axis, become [`EndKind::Halo`].
pub fn local_ends(ends: &FieldEnds, partition: &Partition) -> FieldEnds {
    let mut local = *ends;
    for axis in 0..3 {
        if partition.ranks[axis] == 1 {
            continue;
        }
        for side in 0..2 {
            let shared = !partition.at_domain_face(axis, side);
            if shared || ends[axis][side].kind == EndKind::Periodic {
                local[axis][side] = EndCondition {
                    kind: EndKind::Halo,
                    value: 0.0,
                };
            }
        }
    }
    local
}

/// What a rank needs to fill [`EndKind::Halo`] ghosts: its place among the
/// ranks, which axes are periodic, and the communicator.
#[derive(Clone, Debug)]
pub struct HaloExchange {
    pub partition: Partition,
    pub periodic: [bool; 3],
    pub communicator: Communicator,
}

/// The padded indices of a field's unknowns: every owned cell, except that
/// along an axis with prescribed face values the boundary faces (0 and n)
/// are not unknowns; at an outflow face the normal velocity on the face is
/// one.
pub fn unknowns(grid: &Grid, ends: &FieldEnds) -> Block {
    let mut block = grid.cell_block();
    for (axis, end) in ends.iter().enumerate().take(grid.dim()) {
        // Face n is an unknown unless its value is prescribed (face 0, the
        // lower end, never is one: the block starts at face 1).
        if end[1].kind == EndKind::DirichletFace {
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
    fill_ghosts_on(grid, field, location, ends, None);
}

/// [`fill_ghosts`] on one rank of several: the ghosts beyond a
/// [`EndKind::Halo`] end are the neighbouring rank's planes next to the
/// shared face (collective among the ranks of `halo`; each axis in turn, so
/// edge and corner ghosts come from the diagonal neighbours).
pub fn fill_ghosts_on(
    grid: &Grid,
    field: &mut [f64],
    location: Location,
    ends: &FieldEnds,
    halo: Option<&HaloExchange>,
) {
    fill_ghosts_together(
        grid,
        &mut [GhostedField {
            values: field,
            location,
            ends,
        }],
        halo,
    );
}

/// A field whose ghosts [`fill_ghosts_together`] fills.
pub struct GhostedField<'a> {
    pub values: &'a mut [f64],
    pub location: Location,
    pub ends: &'a FieldEnds,
}

/// [`fill_ghosts_on`] for several fields at once: along each axis split
/// among ranks, one message each way carries the planes of all of them.
pub fn fill_ghosts_together(grid: &Grid, fields: &mut [GhostedField], halo: Option<&HaloExchange>) {
    for axis in 0..grid.dim() {
        let split = |f: &GhostedField| f.ends[axis].iter().any(|end| end.kind == EndKind::Halo);
        if fields.iter().any(split) {
            let halo = halo.expect("a halo end needs the ranks' exchange");
            debug_assert!(
                fields.iter().all(split),
                "every field shares the same faces"
            );
            exchange_planes(grid, fields, axis, halo);
        }
        for field in fields.iter_mut() {
            fill_axis(grid, field.values, field.location, field.ends, axis);
        }
    }
}

/// The ghosts (and prescribed boundary-face values) of `field` along
/// `axis` from its end conditions, over the whole padded extent of the
/// other axes; [`EndKind::Halo`] ends are left to the exchange.
fn fill_axis(grid: &Grid, field: &mut [f64], location: Location, ends: &FieldEnds, axis: usize) {
    let padded = grid.padded();
    let n = grid.cells[axis];
    let stride = grid.stride(axis);
    let mut line_block = Block {
        start: [0; 3],
        end: padded,
    };
    line_block.end[axis] = 1;
    let [lower, upper] = ends[axis];
    if matches!(lower.kind, EndKind::DirichletFace) || matches!(upper.kind, EndKind::DirichletFace)
    {
        debug_assert_eq!(location, Location::Face(axis));
    }
    // The quadratic ghost reads the second unknown from the wall; a grid
    // has at least two cells per axis, so it is never a ghost.
    debug_assert!(n >= 2);
    let quadratic = if axis == grid.line_axis() {
        [0, 1].map(|side| grid.wall_ghost_weights(side))
    } else {
        [[0.0; 3]; 2]
    };
    grid.for_each(&line_block, |first, _| {
        let at = |i: usize| first + i * stride;
        match lower.kind {
            EndKind::Halo => {}
            EndKind::Periodic => field[at(0)] = field[at(n)],
            EndKind::Neumann => field[at(0)] = field[at(1)],
            EndKind::DirichletCell => field[at(0)] = 2.0 * lower.value - field[at(1)],
            EndKind::DirichletCellQuadratic => {
                let [wall, near, far] = quadratic[0];
                field[at(0)] = wall * lower.value + near * field[at(1)] + far * field[at(2)]
            }
            EndKind::DirichletFace => field[at(0)] = lower.value,
        }
        match upper.kind {
            EndKind::Halo => {}
            EndKind::Periodic => field[at(n + 1)] = field[at(1)],
            EndKind::Neumann => field[at(n + 1)] = field[at(n)],
            EndKind::DirichletCell => field[at(n + 1)] = 2.0 * upper.value - field[at(n)],
            EndKind::DirichletCellQuadratic => {
                let [wall, near, far] = quadratic[1];
                field[at(n + 1)] = wall * upper.value + near * field[at(n)] + far * field[at(n - 1)]
            }
            EndKind::DirichletFace => {
                field[at(n)] = upper.value;
                // Odd reflection about the wall face; no stencil of an
                // unknown reaches it, it only keeps the ghost finite.
                field[at(n + 1)] = 2.0 * upper.value - field[at(n - 1)];
            }
        }
    });
}

/// The ghost planes along `axis` of every field from the neighbouring
/// ranks: plane n goes to the upper neighbour (its plane 0), plane 1 to the
/// lower neighbour (its plane n + 1), each over the whole padded extent of
/// the other axes; one message each way holds the planes of all fields.
fn exchange_planes(grid: &Grid, fields: &mut [GhostedField], axis: usize, halo: &HaloExchange) {
    let n = grid.cells[axis];
    let padded = grid.padded();
    let mut plane = Block {
        start: [0; 3],
        end: padded,
    };
    let ends = fields[0].ends;
    let neighbour = |side: usize| {
        (ends[axis][side].kind == EndKind::Halo)
            .then(|| halo.partition.neighbour(axis, side, halo.periodic[axis]))
            .flatten()
    };
    let (lower, upper) = (neighbour(0), neighbour(1));
    // Upwards: this rank's plane n becomes the upper neighbour's plane 0.
    for (send, receive, destination, source, tag) in [
        (n, 0, upper, lower, 2 * axis as u16),
        (1, n + 1, lower, upper, 2 * axis as u16 + 1),
    ] {
        plane.start[axis] = send;
        plane.end[axis] = send + 1;
        let mut message = Vec::new();
        if destination.is_some() {
            for field in fields.iter() {
                grid.for_each(&plane, |index, _| message.push(field.values[index]));
            }
        }
        let received = halo
            .communicator
            .shift(HALO_TAG + tag, &message, destination, source);
        if source.is_some() {
            plane.start[axis] = receive;
            plane.end[axis] = receive + 1;
            let mut values = received.into_iter();
            for field in fields.iter_mut() {
                grid.for_each(&plane, |index, _| {
                    field.values[index] = values.next().expect("whole planes from the neighbour")
                });
            }
        }
    }
}

/// First message tag of the halo exchanges.
const HALO_TAG: u16 = 1000;

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
        assert_eq!(u[1][0].kind, EndKind::DirichletCellQuadratic);
        assert_eq!(u[1][1].kind, EndKind::DirichletCellQuadratic);
        assert_eq!(u[1][1].value, 2.0);
        let v = boundaries.velocity_ends(&grid, 1);
        assert_eq!(v[1][1].kind, EndKind::DirichletFace);
        assert_eq!(v[1][1].value, 0.0);
        assert_eq!(boundaries.pressure_ends(&grid)[1][0].kind, EndKind::Neumann);
        assert_eq!(unknowns(&grid, &v).end, [5, 4, 1]);
    }

    #[test]
    fn transformed_axes_keep_the_linear_wall_closure() {
        let grid = Grid::new(Dimension::Three, [4, 4, 4], [0.0; 3], [1.0; 3]);
        let boundaries = Boundaries::periodic()
            .with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
            .with(
                2,
                BoundaryCondition::NoSlip,
                BoundaryCondition::MovingWall([0.0, 1.0, 0.0]),
            );
        boundaries.validate(&grid).unwrap();
        let v = boundaries.velocity_ends(&grid, 1);
        assert_eq!(
            v[0],
            [EndKind::DirichletCell; 2].map(|kind| EndCondition { kind, value: 0.0 })
        );
        assert_eq!(v[2][0].kind, EndKind::DirichletCellQuadratic);
        assert_eq!(v[2][1].kind, EndKind::DirichletCellQuadratic);
        assert_eq!(v[2][1].value, 1.0);
        let w = boundaries.velocity_ends(&grid, 2);
        assert_eq!(w[0][0].kind, EndKind::DirichletCell);
        assert_eq!(w[2][0].kind, EndKind::DirichletFace);
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
        let through_flow = Boundaries::periodic().with(
            2,
            BoundaryCondition::MovingWall([0.0, 0.0, 0.5]),
            BoundaryCondition::MovingWall([1.0, 0.0, 0.5]),
        );
        assert!(through_flow.validate(&grid).is_ok());
        let inflow_outflow = Boundaries::periodic().with(
            2,
            BoundaryCondition::MovingWall([0.0, 0.0, 0.5]),
            BoundaryCondition::Outflow,
        );
        assert!(inflow_outflow.validate(&grid).is_ok());
        for (axis, lower, upper) in [
            (2, BoundaryCondition::Outflow, BoundaryCondition::NoSlip),
            (0, BoundaryCondition::NoSlip, BoundaryCondition::Outflow),
        ] {
            let misplaced = Boundaries::periodic().with(axis, lower, upper);
            assert!(misplaced.validate(&grid).is_err(), "{misplaced:?}");
        }
    }

    /// The value at the wall, half a cell beyond the first unknown, of the
    /// parabola through the ghost (at −h/2) and the first two unknowns (at
    /// h/2 and 3h/2): Lagrange weights 3/8, 3/4, −1/8.
    fn parabola_at_wall(ghost: f64, first: f64, second: f64) -> f64 {
        0.375 * ghost + 0.75 * first - 0.125 * second
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
            u[index] = (i + 10 * j) as f64 + 0.7 * (j * j) as f64
        });
        fill_ghosts(&grid, &mut u, Location::Face(0), &ends);
        for i in 0..5 {
            let at = |j: usize| u[grid.index(i, j, 0)];
            let wall = parabola_at_wall(at(0), at(1), at(2));
            assert!((wall - 1.5).abs() <= 1e-13, "{wall}");
            assert_eq!(at(5), at(4));
        }
        // Periodic in x, including the corners.
        assert_eq!(u[grid.index(0, 2, 0)], u[grid.index(3, 2, 0)]);
        assert_eq!(u[grid.index(4, 0, 0)], u[grid.index(1, 0, 0)]);
    }

    /// Along the last axis the ghost of a parabola that takes the wall
    /// values is the parabola itself, at both ends; along a transformed
    /// axis the ghost is the linear one, `2 u_wall − u_1`.
    #[test]
    fn the_quadratic_ghost_is_exact_for_a_parabola() {
        let grid = Grid::new(Dimension::Two, [4, 6, 1], [0.0; 3], [1.0, 1.5, 1.0]);
        let (lower_speed, upper_speed) = (0.5, -1.0);
        let boundaries = Boundaries::periodic()
            .with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
            .with(
                1,
                BoundaryCondition::MovingWall([lower_speed, 0.0, 0.0]),
                BoundaryCondition::MovingWall([upper_speed, 0.0, 0.0]),
            );
        boundaries.validate(&grid).unwrap();
        // The Couette line between the wall velocities plus a Poiseuille bump.
        let height = 1.5;
        let parabola = |y: f64| {
            lower_speed + (upper_speed - lower_speed) * y / height + 3.0 * y * (height - y)
        };
        let ends = boundaries.velocity_ends(&grid, 0);
        let mut u = grid.zeros();
        grid.for_each(&grid.cell_block(), |index, [i, j, k]| {
            u[index] = parabola(grid.position(Location::Face(0), i, j, k)[1])
        });
        fill_ghosts(&grid, &mut u, Location::Face(0), &ends);
        for i in 1..4 {
            for j in [0, 7] {
                let y = grid.position(Location::Face(0), i, j, 0)[1];
                let ghost = u[grid.index(i, j, 0)];
                assert!(
                    (ghost - parabola(y)).abs() <= 1e-13,
                    "j = {j}: {ghost} vs {}",
                    parabola(y)
                );
            }
        }
        // v is tangential to the x walls, a transformed axis: linear ghost.
        let ends = boundaries.velocity_ends(&grid, 1);
        let mut v = grid.zeros();
        grid.for_each(&grid.cell_block(), |index, [i, j, _]| {
            v[index] = (i * i + j) as f64
        });
        fill_ghosts(&grid, &mut v, Location::Face(1), &ends);
        for j in 1..6 {
            assert_eq!(v[grid.index(0, j, 0)], -v[grid.index(1, j, 0)]);
            assert_eq!(v[grid.index(5, j, 0)], -v[grid.index(4, j, 0)]);
        }
    }
}
