//! Direct solvers for the discrete Poisson and Helmholtz equations,
//! `(a I + b L) x = r`, with `L` the three-point Laplacian of the staggered
//! grid and its end conditions.
//!
//! All active axes but the last are diagonalised by real transforms
//! ([`crate::transform`]): in modal space `L` along those axes becomes the
//! eigenvalue `λ_k = −(2 − 2 cos θ_k) / h²`. Along the last axis (z in 3D,
//! y in 2D) what remains is one tridiagonal system per mode,
//! `b (x_{j−1} − 2 x_j + x_{j+1}) / h² + (a + b Σ λ) x_j = r_j`, solved by
//! the Thomas algorithm (Sherman–Morrison for a periodic line). The
//! discrete equation is thus solved to round-off, with no iteration. Walls
//! of different kinds on the two faces of an axis (no slip below, free
//! slip above) are allowed along the last axis only, where no transform is
//! needed.
//!
//! The pressure equation `L φ = r` with periodic or zero-gradient ends
//! everywhere is singular: constants are its null space. For the one mode
//! where this happens, the mean of the right-hand side is removed (it is
//! round-off for the divergence of a velocity with no net flux), one value
//! is pinned, and the solution is shifted to zero mean.

use crate::boundary::{unknowns, EndKind, FieldEnds};
use crate::error::FluidError;
use crate::grid::{Block, Grid};
use crate::transform::{AxisTransform, Direction, TransformKind};

/// A planned direct solver for one field's unknowns and end conditions.
pub struct DirectSolver {
    /// The last active axis, solved by tridiagonal elimination.
    line_axis: usize,
    line_spacing: f64,
    line_ends: [EndKind; 2],
    /// Padded indices of the unknowns in the field.
    block: Block,
    /// Unknowns along each axis (1 along an inactive axis).
    shape: [usize; 3],
    transforms: Vec<AxisTransform>,
    /// `λ_k` of every transformed axis.
    eigenvalues: Vec<Vec<f64>>,
    modes: Vec<f64>,
    line: LineWork,
}

impl DirectSolver {
    /// Plans a solver for a field with these end conditions (only their
    /// kinds matter: the solver works on homogeneous conditions; prescribed
    /// values enter through the right-hand side or an increment form).
    pub fn new(grid: &Grid, ends: &FieldEnds) -> Result<Self, FluidError> {
        let dim = grid.dim();
        let line_axis = dim - 1;
        let block = unknowns(grid, ends);
        let shape = [0, 1, 2].map(|a| block.end[a] - block.start[a]);
        let mut transforms = Vec::new();
        let mut eigenvalues = Vec::new();
        for (axis, end) in ends.iter().enumerate().take(line_axis) {
            let kind = match (end[0].kind, end[1].kind) {
                (EndKind::Periodic, EndKind::Periodic) => TransformKind::Periodic,
                (EndKind::Neumann, EndKind::Neumann) => TransformKind::Neumann,
                (EndKind::DirichletCell, EndKind::DirichletCell) => TransformKind::DirichletCell,
                (EndKind::DirichletFace, EndKind::DirichletFace) => TransformKind::DirichletFace,
                (lower, upper) => {
                    return Err(FluidError::Boundary(format!(
                        "axis {axis} is solved by a transform and needs the same kind of end on \
                         both faces, got {lower:?} and {upper:?}"
                    )))
                }
            };
            let transform = AxisTransform::new(kind, shape[axis]);
            let h2 = grid.spacing[axis] * grid.spacing[axis];
            eigenvalues.push(
                transform
                    .angles()
                    .iter()
                    .map(|theta| -(2.0 - 2.0 * theta.cos()) / h2)
                    .collect(),
            );
            transforms.push(transform);
        }
        let line_ends = [ends[line_axis][0].kind, ends[line_axis][1].kind];
        let periodic_line = line_ends.map(|k| k == EndKind::Periodic);
        if periodic_line[0] != periodic_line[1] {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: periodic on one end only"
            )));
        }
        if periodic_line[0] && shape[line_axis] < 3 {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: a periodic line needs at least 3 cells"
            )));
        }
        let total = shape.iter().product();
        Ok(DirectSolver {
            line_axis,
            line_spacing: grid.spacing[line_axis],
            line_ends,
            block,
            shape,
            transforms,
            eigenvalues,
            modes: vec![0.0; total],
            line: LineWork::new(shape[line_axis]),
        })
    }

    /// The padded indices of the unknowns this solver owns in a field.
    pub fn unknowns(&self) -> &Block {
        &self.block
    }

    /// Solves the Poisson equation `L x = r`. On entry `field` holds `r`
    /// on the unknowns; on exit `x`. Ghosts are not touched. When the
    /// system is singular (no Dirichlet end anywhere) the solution has
    /// zero mean.
    pub fn solve_poisson(&mut self, grid: &Grid, field: &mut [f64]) {
        self.solve(grid, field, 0.0, 1.0);
    }

    /// Solves the Helmholtz equation `(I − c L) x = r` in place, `c ≥ 0`
    /// (the implicit half of a Crank–Nicolson viscous step, `c = ν Δt / 2`).
    pub fn solve_helmholtz(&mut self, grid: &Grid, field: &mut [f64], c: f64) {
        self.solve(grid, field, 1.0, -c);
    }

    /// Solves `(identity I + laplacian L) x = r` in place.
    pub fn solve(&mut self, grid: &Grid, field: &mut [f64], identity: f64, laplacian: f64) {
        self.gather(grid, field);
        for (axis, transform) in self.transforms.iter_mut().enumerate() {
            transform.apply_along(&mut self.modes, self.shape, axis, Direction::Forward);
        }
        self.solve_lines(identity, laplacian);
        for (axis, transform) in self.transforms.iter_mut().enumerate().rev() {
            transform.apply_along(&mut self.modes, self.shape, axis, Direction::Backward);
        }
        self.scatter(grid, field);
    }

    fn gather(&mut self, grid: &Grid, field: &[f64]) {
        let mut compact = 0;
        let modes = &mut self.modes;
        grid.for_each(&self.block, |index, _| {
            modes[compact] = field[index];
            compact += 1;
        });
    }

    fn scatter(&self, grid: &Grid, field: &mut [f64]) {
        let mut compact = 0;
        grid.for_each(&self.block, |index, _| {
            field[index] = self.modes[compact];
            compact += 1;
        });
    }

    /// One tridiagonal solve along the line axis per transformed mode.
    fn solve_lines(&mut self, identity: f64, laplacian: f64) {
        let length = self.shape[self.line_axis];
        let stride: usize = self.shape[..self.line_axis].iter().product();
        let coupling = laplacian / (self.line_spacing * self.line_spacing);
        let end_shift = self.line_ends.map(|kind| match kind {
            EndKind::Neumann => coupling,
            EndKind::DirichletCell => -coupling,
            EndKind::DirichletFace | EndKind::Periodic => 0.0,
        });
        let periodic = self.line_ends[0] == EndKind::Periodic;
        let can_be_singular = identity == 0.0
            && self
                .line_ends
                .iter()
                .all(|&kind| matches!(kind, EndKind::Periodic | EndKind::Neumann));
        for mode in 0..stride {
            // Modal eigenvalue of the transformed axes.
            let mut remainder = mode;
            let mut modal = 0.0;
            for (axis, eigenvalues) in self.eigenvalues.iter().enumerate() {
                modal += eigenvalues[remainder % self.shape[axis]];
                remainder /= self.shape[axis];
            }
            let diagonal = identity + laplacian * modal - 2.0 * coupling;
            let work = &mut self.line;
            for j in 0..length {
                work.rhs[j] = self.modes[mode + j * stride];
                work.diagonal[j] = diagonal;
            }
            work.diagonal[0] += end_shift[0];
            work.diagonal[length - 1] += end_shift[1];
            if can_be_singular && laplacian * modal == 0.0 {
                work.solve_singular(coupling);
            } else if periodic {
                work.solve_cyclic(coupling);
            } else {
                work.solve_open(coupling);
            }
            for j in 0..length {
                self.modes[mode + j * stride] = work.rhs[j];
            }
        }
    }
}

/// Work arrays of one tridiagonal line with constant off-diagonal
/// `coupling` and a per-row `diagonal`.
struct LineWork {
    diagonal: Vec<f64>,
    rhs: Vec<f64>,
    modified: Vec<f64>,
    correction: Vec<f64>,
}

impl LineWork {
    fn new(length: usize) -> Self {
        LineWork {
            diagonal: vec![0.0; length],
            rhs: vec![0.0; length],
            modified: vec![0.0; length],
            correction: vec![0.0; length],
        }
    }

    /// Thomas algorithm: `rhs` is overwritten with the solution of the
    /// tridiagonal system (`coupling`, `diagonal`, `coupling`).
    fn thomas(diagonal: &[f64], coupling: f64, rhs: &mut [f64], modified: &mut [f64]) {
        let n = rhs.len();
        let mut pivot = diagonal[0];
        modified[0] = coupling / pivot;
        rhs[0] /= pivot;
        for j in 1..n {
            pivot = diagonal[j] - coupling * modified[j - 1];
            modified[j] = coupling / pivot;
            rhs[j] = (rhs[j] - coupling * rhs[j - 1]) / pivot;
        }
        for j in (0..n - 1).rev() {
            rhs[j] -= modified[j] * rhs[j + 1];
        }
    }

    fn solve_open(&mut self, coupling: f64) {
        Self::thomas(&self.diagonal, coupling, &mut self.rhs, &mut self.modified);
    }

    /// Periodic line: the corner entries `coupling` are a rank-one update
    /// `u vᵀ` of a tridiagonal matrix (Sherman–Morrison).
    fn solve_cyclic(&mut self, coupling: f64) {
        let n = self.rhs.len();
        let gamma = -self.diagonal[0];
        let first = self.diagonal[0];
        let last = self.diagonal[n - 1];
        self.diagonal[0] = first - gamma;
        self.diagonal[n - 1] = last - coupling * coupling / gamma;
        Self::thomas(&self.diagonal, coupling, &mut self.rhs, &mut self.modified);
        self.correction.fill(0.0);
        self.correction[0] = gamma;
        self.correction[n - 1] = coupling;
        Self::thomas(
            &self.diagonal,
            coupling,
            &mut self.correction,
            &mut self.modified,
        );
        let factor = (self.rhs[0] + coupling / gamma * self.rhs[n - 1])
            / (1.0 + self.correction[0] + coupling / gamma * self.correction[n - 1]);
        for j in 0..n {
            self.rhs[j] -= factor * self.correction[j];
        }
        self.diagonal[0] = first;
        self.diagonal[n - 1] = last;
    }

    /// The singular mode of a pure Neumann or periodic Laplacian: remove
    /// the mean of the right-hand side (the compatibility condition), pin
    /// the first value to zero and drop its row (implied by the others),
    /// then shift the solution to zero mean.
    fn solve_singular(&mut self, coupling: f64) {
        let n = self.rhs.len() as f64;
        let mean = self.rhs.iter().sum::<f64>() / n;
        self.rhs.iter_mut().for_each(|r| *r -= mean);
        // Rows 1..n with x_0 = 0: for a periodic line the wrap-around
        // coupling of the last row to x_0 vanishes too.
        self.rhs[0] = 0.0;
        Self::thomas(
            &self.diagonal[1..],
            coupling,
            &mut self.rhs[1..],
            &mut self.modified[1..],
        );
        let mean = self.rhs.iter().sum::<f64>() / n;
        self.rhs.iter_mut().for_each(|x| *x -= mean);
    }
}
