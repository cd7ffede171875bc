//! grainflow's interior point for COCD programs whose cones are linear
//! (2D discs, where each Coulomb cone {|x| ≤ y} is two half-planes, and
//! frictionless contacts): a primal–dual method with Mehrotra's
//! predictor–corrector on
//!
//!   min ½ xᵀPx + qᵀx   subject to   Ax + s = b,  s ≥ 0,
//!
//! P = M̃ diagonal. Each Newton step eliminates s and the multipliers z
//! and solves the normal equations
//!
//!   (P + AᵀΘA) Δx = −r_d + Aᵀ ((r_c − z∘r_p) / s),   Θ = diag(z/s),
//!
//! an SPD matrix of the size of the unknowns (three per disc), at least M̃,
//! whose pattern is the contact graph: a supernodal sparse Cholesky (faer,
//! AMD ordering), its symbolic analysis done once per step and reused by
//! every iteration; from 20,000 unknowns, split in two halves and a
//! separator factorised side by side on two threads
//! ([`crate::normal_factor`]).
//! Clarabel works on the larger quasi-definite system [P Aᵀ; A −Θ⁻¹] of
//! unknowns and rows together.
//!
//! The rows are rescaled by 1/κ (s in units of the distance V Δt a grain
//! covers in a step at the reference speed, z in units of the momentum
//! m̄ V), so that both are of order one in a packing at rest. The stopping
//! test is Clarabel's: primal and dual residuals relative to the size of
//! the data and the duality gap relative to the objective, all below ε.

use crate::cocd::ConicProgram;
use crate::normal_factor::NormalFactor;
use clarabel::algebra::CscMatrix;

/// Fraction of the distance to the boundary of the cone taken by a step.
const STEP_FRACTION: f64 = 0.99;

/// The rows of A as lists of (column, value) with the positions of their
/// products in the upper triangle of the normal matrix.
struct NormalPattern {
    row_start: Vec<usize>,
    row_column: Vec<usize>,
    row_value: Vec<f64>,
    /// Per row, for each pair k ≤ l of its entries, the index in `matrix`.
    pair_start: Vec<usize>,
    pair_position: Vec<usize>,
    diagonal_position: Vec<usize>,
    matrix: CscMatrix<f64>,
}

impl NormalPattern {
    fn new(a: &CscMatrix<f64>, scale: f64, columns: usize) -> Self {
        let rows = a.m;
        let mut row_start = vec![0usize; rows + 1];
        for &r in &a.rowval {
            row_start[r + 1] += 1;
        }
        for r in 0..rows {
            row_start[r + 1] += row_start[r];
        }
        let mut fill = row_start.clone();
        let mut row_column = vec![0usize; a.rowval.len()];
        let mut row_value = vec![0.0; a.rowval.len()];
        for c in 0..a.n {
            for k in a.colptr[c]..a.colptr[c + 1] {
                let r = a.rowval[k];
                row_column[fill[r]] = c;
                row_value[fill[r]] = a.nzval[k] / scale;
                fill[r] += 1;
            }
        }
        // Entries (row ≤ column) of the upper triangle, sorted by column.
        let mut entries: Vec<(usize, usize)> = (0..columns).map(|c| (c, c)).collect();
        for r in 0..rows {
            let cols = &row_column[row_start[r]..row_start[r + 1]];
            for (k, &ck) in cols.iter().enumerate() {
                for &cl in &cols[k..] {
                    entries.push((ck.max(cl), ck.min(cl)));
                }
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let mut colptr = vec![0usize; columns + 1];
        for &(c, _) in &entries {
            colptr[c + 1] += 1;
        }
        for c in 0..columns {
            colptr[c + 1] += colptr[c];
        }
        let rowval: Vec<usize> = entries.iter().map(|&(_, r)| r).collect();
        let position = |row: usize, col: usize| -> usize {
            let range = colptr[col]..colptr[col + 1];
            range.start
                + rowval[range]
                    .binary_search(&row)
                    .expect("entry in the pattern")
        };
        let mut pair_start = vec![0usize; rows + 1];
        let mut pair_position = Vec::new();
        for r in 0..rows {
            let cols = &row_column[row_start[r]..row_start[r + 1]];
            for (k, &ck) in cols.iter().enumerate() {
                for &cl in &cols[k..] {
                    pair_position.push(position(ck.min(cl), ck.max(cl)));
                }
            }
            pair_start[r + 1] = pair_position.len();
        }
        let diagonal_position = (0..columns).map(|c| position(c, c)).collect();
        let nnz = rowval.len();
        NormalPattern {
            row_start,
            row_column,
            row_value,
            pair_start,
            pair_position,
            diagonal_position,
            matrix: CscMatrix::new(columns, columns, colptr, rowval, vec![0.0; nnz]),
        }
    }

    /// Sets the values of P + AᵀΘA.
    fn assemble(&mut self, mass: &[f64], theta: &[f64]) {
        let values = &mut self.matrix.nzval;
        values.fill(0.0);
        for (c, &p) in self.diagonal_position.iter().enumerate() {
            values[p] = mass[c];
        }
        for (r, &t) in theta.iter().enumerate() {
            let entries = self.row_start[r]..self.row_start[r + 1];
            let vals = &self.row_value[entries];
            let mut pair = self.pair_start[r];
            for (k, &vk) in vals.iter().enumerate() {
                for &vl in &vals[k..] {
                    values[self.pair_position[pair]] += t * vk * vl;
                    pair += 1;
                }
            }
        }
    }

    /// y = A x (rescaled rows).
    fn times(&self, x: &[f64], y: &mut [f64]) {
        for (r, yr) in y.iter_mut().enumerate() {
            let entries = self.row_start[r]..self.row_start[r + 1];
            *yr = self.row_column[entries.clone()]
                .iter()
                .zip(&self.row_value[entries])
                .map(|(&c, &v)| v * x[c])
                .sum();
        }
    }

    /// y = Aᵀ z (rescaled rows).
    fn transpose_times(&self, z: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (r, &zr) in z.iter().enumerate() {
            for k in self.row_start[r]..self.row_start[r + 1] {
                y[self.row_column[k]] += self.row_value[k] * zr;
            }
        }
    }
}

fn infinity_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Largest α ≤ 1 keeping v + α Δv ≥ 0.
fn step_to_boundary(v: &[f64], dv: &[f64]) -> f64 {
    v.iter()
        .zip(dv)
        .filter(|(_, &d)| d < 0.0)
        .map(|(&x, &d)| -x / d)
        .fold(1.0, f64::min)
}

/// Solves a program with linear cones only: (x, z, iterations, reduced
/// accuracy) in Clarabel's units, so that the two solvers are
/// interchangeable.
pub fn solve(
    program: &ConicProgram,
    tolerance: f64,
    max_iterations: u32,
) -> Result<(Vec<f64>, Vec<f64>, u32, bool), String> {
    assert_eq!(program.cone_count, 0, "linear cones only");
    let n = program.mass.len();
    let m = program.b.len();
    let kappa = program.row_scale();
    let mass = &program.mass;
    let q = program.q();
    let b: Vec<f64> = program.b.iter().map(|v| v / kappa).collect();
    let mut pattern = NormalPattern::new(&program.a_matrix, kappa, n);
    let fail = |what: String| format!("the interior point ({m} rows, {n} unknowns): {what}");

    // The ordering and symbolic factorisation, once per step.
    pattern.assemble(mass, &vec![1.0; m]);
    let mut factor = NormalFactor::new(&pattern.matrix).map_err(fail)?;
    factor.factorise(&pattern.matrix).map_err(fail)?;

    // Start: the minimiser of ½xᵀPx + qᵀx + ½|Ax − b|², then s and z
    // shifted into the interior (as in CVXOPT's coneqp).
    let mut x = vec![0.0; n];
    pattern.transpose_times(&b, &mut x);
    for (xc, qc) in x.iter_mut().zip(&q) {
        *xc -= qc;
    }
    factor.solve(&mut x);
    let mut ax = vec![0.0; m];
    pattern.times(&x, &mut ax);
    let mut s: Vec<f64> = b.iter().zip(&ax).map(|(bi, axi)| bi - axi).collect();
    let mut z: Vec<f64> = s.iter().map(|v| -v).collect();
    for v in [&mut s, &mut z] {
        let lowest = v.iter().cloned().fold(f64::INFINITY, f64::min);
        if lowest <= 0.0 {
            v.iter_mut().for_each(|e| *e += 1.0 - lowest);
        }
    }

    let size = program.size();
    let norm_b = infinity_norm(&b);
    let norm_q = infinity_norm(&q);
    let (mut r_p, mut r_d, mut px, mut atz) =
        (vec![0.0; m], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut theta, mut rhs, mut dx, mut ds, mut dz) = (
        vec![0.0; m],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; m],
        vec![0.0; m],
    );
    let mut rc = vec![0.0; m];
    let mut adx = vec![0.0; m];
    for iteration in 0..=max_iterations {
        // Residuals and the stopping test.
        pattern.times(&x, &mut ax);
        pattern.transpose_times(&z, &mut atz);
        for c in 0..n {
            px[c] = mass[c] * x[c];
            r_d[c] = px[c] + q[c] + atz[c];
        }
        for i in 0..m {
            r_p[i] = ax[i] + s[i] - b[i];
        }
        let gap = dot(&s, &z);
        let quadratic = 0.5 * dot(&x, &px);
        let primal = quadratic + dot(&q, &x);
        let dual = -quadratic - dot(&b, &z);
        let primal_ok = infinity_norm(&r_p)
            <= tolerance * (1.0 + norm_b.max(infinity_norm(&ax)).max(infinity_norm(&s)));
        let dual_ok = infinity_norm(&r_d)
            <= tolerance * (1.0 + norm_q.max(infinity_norm(&px)).max(infinity_norm(&atz)));
        let gap_ok = gap <= tolerance * size.max(primal.abs().min(dual.abs()));
        if primal_ok && dual_ok && gap_ok {
            let z_out = z.iter().map(|v| v / kappa).collect();
            return Ok((x, z_out, iteration, false));
        }
        if iteration == max_iterations {
            break;
        }
        let mu = gap / m as f64;

        // Normal matrix for this iterate.
        for i in 0..m {
            theta[i] = z[i] / s[i];
        }
        pattern.assemble(mass, &theta);
        factor
            .factorise(&pattern.matrix)
            .map_err(|e| fail(format!("iteration {iteration}: {e}")))?;

        // Predictor (affine) then corrector with the same factor.
        let mut direction =
            |rc: &[f64], dx: &mut Vec<f64>, ds: &mut Vec<f64>, dz: &mut Vec<f64>| {
                for i in 0..m {
                    theta[i] = (rc[i] - z[i] * r_p[i]) / s[i];
                }
                pattern.transpose_times(&theta, &mut rhs);
                for c in 0..n {
                    dx[c] = rhs[c] - r_d[c];
                }
                factor.solve(dx);
                pattern.times(dx, &mut adx);
                for i in 0..m {
                    ds[i] = -r_p[i] - adx[i];
                    dz[i] = (-rc[i] - z[i] * ds[i]) / s[i];
                }
            };
        for i in 0..m {
            rc[i] = s[i] * z[i];
        }
        direction(&rc, &mut dx, &mut ds, &mut dz);
        let alpha = step_to_boundary(&s, &ds).min(step_to_boundary(&z, &dz));
        let affine_gap: f64 = (0..m)
            .map(|i| (s[i] + alpha * ds[i]) * (z[i] + alpha * dz[i]))
            .sum();
        let sigma = (affine_gap / gap).powi(3).min(1.0);
        for i in 0..m {
            rc[i] = s[i] * z[i] + ds[i] * dz[i] - sigma * mu;
        }
        direction(&rc, &mut dx, &mut ds, &mut dz);
        let alpha =
            (STEP_FRACTION * step_to_boundary(&s, &ds).min(step_to_boundary(&z, &dz))).min(1.0);
        for c in 0..n {
            x[c] += alpha * dx[c];
        }
        for i in 0..m {
            s[i] += alpha * ds[i];
            z[i] += alpha * dz[i];
        }
    }
    Err(fail(format!(
        "no solution to ε = {tolerance:.1e} within {max_iterations} iterations"
    )))
}
