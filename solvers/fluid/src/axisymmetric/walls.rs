//! Conditions on the boundaries of an (r, z) domain and the ghost values
//! that impose them.
//!
//! The axis is not a boundary: `u_r = 0` there (a regular field has no
//! radial velocity on the axis), and every radial flux through it carries
//! the factor `r = 0`, so no condition is needed for the other fields.
//! At `r = R` the normal velocity `u_r` vanishes; `u_z` meets no-slip, free
//! slip or a wall sliding along z. Along z the two ends are walls (no-slip
//! or free slip, `u_z = 0` on the end faces) or periodic together.
//!
//! Ghosts along z follow the transforms that diagonalise the second
//! difference there (see [`crate::transform`]): a no-slip end sets the
//! tangential `u_r` ghost to `−u_1` (sine modes), a free-slip end mirrors
//! it (cosine modes); pressure mirrors at every wall. Along r the closures
//! live in the radial operators ([`super::radial`]), not in ghosts.

use crate::error::FluidError;
use crate::transform::TransformKind;

use super::grid::RzGrid;

/// An end of the domain along z.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxialEnd {
    /// The other end is the neighbour (both ends periodic together).
    Periodic,
    /// A wall at rest.
    NoSlip,
    /// An impermeable wall without shear stress.
    FreeSlip,
}

/// The cylindrical wall at `r = R`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OuterWall {
    /// A wall at rest.
    NoSlip,
    /// An impermeable wall without shear stress.
    FreeSlip,
    /// A wall sliding along z at this speed (m/s).
    Sliding(f64),
}

/// The boundaries of an (r, z) domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RzWalls {
    pub outer: OuterWall,
    /// Ends at `z_lower` and `z_upper`.
    pub ends: [AxialEnd; 2],
}

impl RzWalls {
    /// Checks that the ends are periodic together or not at all.
    pub fn new(outer: OuterWall, ends: [AxialEnd; 2]) -> Result<Self, FluidError> {
        let periodic = ends.map(|end| end == AxialEnd::Periodic);
        if periodic[0] != periodic[1] {
            return Err(FluidError::Boundary(format!(
                "the ends along z are periodic together or not at all, got {:?} and {:?}",
                ends[0], ends[1]
            )));
        }
        if let OuterWall::Sliding(speed) = outer {
            if !speed.is_finite() {
                return Err(FluidError::Boundary(format!(
                    "the outer wall's sliding speed must be finite, got {speed}"
                )));
            }
        }
        Ok(RzWalls { outer, ends })
    }

    pub fn periodic(&self) -> bool {
        self.ends[0] == AxialEnd::Periodic
    }

    /// The speed along z of the outer wall (0 unless it slides).
    pub fn outer_speed(&self) -> f64 {
        match self.outer {
            OuterWall::Sliding(speed) => speed,
            _ => 0.0,
        }
    }

    /// The transform along z of a field at z centres (`u_r`, or pressure
    /// when `pressure`), and of `u_z` on z faces.
    pub fn z_transform(&self, field: RzField) -> TransformKind {
        if self.periodic() {
            return TransformKind::Periodic;
        }
        match field {
            RzField::Pressure => TransformKind::Neumann,
            RzField::Axial => TransformKind::DirichletFace,
            // u_r is tangential at the ends: odd across a no-slip end,
            // even across a free-slip one.
            RzField::Radial => match self.ends {
                [AxialEnd::FreeSlip, AxialEnd::FreeSlip] => TransformKind::Neumann,
                [AxialEnd::NoSlip, AxialEnd::FreeSlip] => TransformKind::DirichletNeumann,
                [AxialEnd::FreeSlip, AxialEnd::NoSlip] => TransformKind::NeumannDirichlet,
                _ => TransformKind::DirichletCell,
            },
        }
    }

    /// Unknown z indices of a field: centres `1..=n_z`; faces `1..=n_z`
    /// when periodic (face `n_z` is face 0), `1..n_z` between walls.
    pub fn z_unknowns(&self, grid: &RzGrid, field: RzField) -> std::ops::Range<usize> {
        let n = grid.cells[1];
        match field {
            RzField::Axial if !self.periodic() => 1..n,
            _ => 1..n + 1,
        }
    }

    /// Sets the ghosts of a pressure-like field (zero normal gradient at
    /// every wall; periodic ends wrap).
    pub fn fill_centre_ghosts(&self, grid: &RzGrid, field: &mut [f64]) {
        let [nr, nz] = grid.cells;
        for k in 1..=nz {
            field[grid.index(0, k)] = field[grid.index(1, k)];
            field[grid.index(nr + 1, k)] = field[grid.index(nr, k)];
        }
        self.fill_z_centre_ghosts(grid, field, [1.0; 2]);
    }

    /// Sets the ghosts of `u_r`: zero on the axis and the outer wall; along
    /// z as the ends say.
    pub fn fill_radial_ghosts(&self, grid: &RzGrid, radial: &mut [f64]) {
        let [nr, nz] = grid.cells;
        for k in 1..=nz {
            radial[grid.index(0, k)] = 0.0;
            radial[grid.index(nr, k)] = 0.0;
            radial[grid.index(nr + 1, k)] = -radial[grid.index(nr - 1, k)];
        }
        let sign = self
            .ends
            .map(|end| if end == AxialEnd::NoSlip { -1.0 } else { 1.0 });
        self.fill_z_centre_ghosts(grid, radial, sign);
    }

    /// Sets the ghosts of `u_z`: zero on wall ends, wrapped when periodic;
    /// even across the axis; beyond the outer wall the line through the
    /// wall value (read only where a flux through the wall vanishes).
    pub fn fill_axial_ghosts(&self, grid: &RzGrid, axial: &mut [f64]) {
        let [nr, nz] = grid.cells;
        let pr = nr + 2;
        if self.periodic() {
            for i in 0..pr {
                axial[grid.index(i, 0)] = axial[grid.index(i, nz)];
                axial[grid.index(i, nz + 1)] = axial[grid.index(i, 1)];
            }
        } else {
            for i in 0..pr {
                axial[grid.index(i, 0)] = 0.0;
                axial[grid.index(i, nz)] = 0.0;
                axial[grid.index(i, nz + 1)] = -axial[grid.index(i, nz - 1)];
            }
        }
        let wall = self.outer_speed();
        for k in 0..nz + 2 {
            axial[grid.index(0, k)] = axial[grid.index(1, k)];
            axial[grid.index(nr + 1, k)] = match self.outer {
                OuterWall::FreeSlip => axial[grid.index(nr, k)],
                _ => 2.0 * wall - axial[grid.index(nr, k)],
            };
        }
    }

    /// Ghost rows along z of a field at z centres: wrapped when periodic,
    /// `sign[end] ×` the first and last rows at walls.
    fn fill_z_centre_ghosts(&self, grid: &RzGrid, field: &mut [f64], sign: [f64; 2]) {
        let [nr, nz] = grid.cells;
        for i in 0..nr + 2 {
            if self.periodic() {
                field[grid.index(i, 0)] = field[grid.index(i, nz)];
                field[grid.index(i, nz + 1)] = field[grid.index(i, 1)];
            } else {
                field[grid.index(i, 0)] = sign[0] * field[grid.index(i, 1)];
                field[grid.index(i, nz + 1)] = sign[1] * field[grid.index(i, nz)];
            }
        }
    }
}

/// The three discrete fields of an (r, z) flow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RzField {
    /// `u_r`, on the radial faces and z centres.
    Radial,
    /// `u_z`, on radial centres and z faces.
    Axial,
    /// Pressure or the projection's potential, at centres.
    Pressure,
}
