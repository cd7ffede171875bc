//! grainflow's interior point for COCD programs: linear cones (2D discs,
//! where each Coulomb cone {|x| ≤ y} is two half-planes; frictionless
//! contacts) and second-order cones of size 3 (3D Coulomb cones), a
//! primal–dual method with Nesterov–Todd scaling and Mehrotra's
//! predictor–corrector on
//!
//!   min ½ xᵀPx + qᵀx   subject to   Ax + s = b,  s ∈ K,
//!
//! P = M̃ diagonal. Each Newton step eliminates s and the multipliers z
//! and solves the normal equations
//!
//!   (P + AᵀW⁻²A) Δx = rhs,   W⁻² = diag(z/s) on the linear rows and a
//!   3 × 3 block per cone ([`crate::second_order_cone`]),
//!
//! an SPD matrix of the size of the unknowns (three per disc), at least M̃,
//! whose pattern is the contact graph: a sparse Cholesky (faer) with the
//! unknowns numbered once per step by AMD, so that the matrix is assembled
//! in the factor's order (no permutation per iteration: 20 % of a 2D step
//! at 2,000 discs), its symbolic analysis done once per step and reused by
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
use crate::normal_factor::{is_factorised_whole, NormalFactor};
use crate::second_order_cone::{self, Cone3, NtScaling};
use crate::shared_program::Ranks;
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
    /// Unknown of the program of each column (the AMD order where the
    /// factor is whole, else the program's).
    order: Vec<usize>,
    ordered: bool,
}

impl NormalPattern {
    /// `reorder`: whether a factor of the whole matrix may renumber the
    /// unknowns (not where the ranks share the separator, which stays last).
    fn new(
        a: &CscMatrix<f64>,
        scale: f64,
        columns: usize,
        reorder: bool,
        three_dimensional: bool,
    ) -> Self {
        let rows = a.m;
        let (row_start, mut row_column, row_value) = crate::csc::scaled_rows(a, scale);
        // The unknowns renumbered by a fill-reducing ordering (AMD) of the
        // normal matrix's graph, once per step: the factor then takes the
        // matrix as assembled, with no permutation at each iteration.
        // A split factor orders each half itself: the unknowns keep their
        // numbers.
        let (mut colptr, mut rowval) = upper_pattern(&row_start, &row_column, columns);
        let ordered = reorder && is_factorised_whole(columns, three_dimensional);
        let order = if ordered {
            let order = minimum_degree_order(&colptr, &rowval, columns);
            let mut label = vec![0usize; columns];
            for (new, &old) in order.iter().enumerate() {
                label[old] = new;
            }
            for c in row_column.iter_mut() {
                *c = label[*c];
            }
            (colptr, rowval) = upper_pattern(&row_start, &row_column, columns);
            order
        } else {
            (0..columns).collect()
        };
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
            order,
            ordered,
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

    /// Adds `fraction` of the mass `mass` to the diagonal.
    fn add_mass(&mut self, mass: &[f64], fraction: f64) {
        for (c, &p) in self.diagonal_position.iter().enumerate() {
            self.matrix.nzval[p] += fraction * mass[c];
        }
    }

    /// Adds the blocks of the second-order cones, Aᵀ_c W_c⁻² A_c for the
    /// three rows of cone c from `first_cone_row` on, as the Gram matrix
    /// (W_c⁻¹ A_c)ᵀ (W_c⁻¹ A_c): W⁻² formed explicitly loses its small
    /// eigenvalue to cancellation near the cone's boundary and made the
    /// normal matrix indefinite. The three rows share their columns (a
    /// contact's two bodies), so their pairs are those of the first row.
    fn add_cone_blocks(&mut self, first_cone_row: usize, scaling: &[NtScaling]) {
        let values = &mut self.matrix.nzval;
        let mut scaled: Vec<Cone3> = Vec::new();
        for (c, w) in scaling.iter().enumerate() {
            let r = first_cone_row + 3 * c;
            let len = self.row_start[r + 1] - self.row_start[r];
            let rows = [r, r + 1, r + 2].map(|q| &self.row_value[self.row_start[q]..][..len]);
            scaled.clear();
            scaled.extend((0..len).map(|k| w.inverse_times(&[rows[0][k], rows[1][k], rows[2][k]])));
            let mut pair = self.pair_start[r];
            for (k, b_k) in scaled.iter().enumerate() {
                for b_l in &scaled[k..] {
                    values[self.pair_position[pair]] +=
                        b_k[0] * b_l[0] + b_k[1] * b_l[1] + b_k[2] * b_l[2];
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

/// The upper triangle's pattern (CSC, rows sorted) of P + AᵀΘA for the
/// rows of A listed by `row_start`/`row_column`, the diagonal included.
fn upper_pattern(
    row_start: &[usize],
    row_column: &[usize],
    columns: usize,
) -> (Vec<usize>, Vec<usize>) {
    let rows = row_start.len() - 1;
    let pairs = |r: usize| {
        let cols = &row_column[row_start[r]..row_start[r + 1]];
        cols.iter()
            .enumerate()
            .flat_map(move |(k, &ck)| cols[k..].iter().map(move |&cl| (ck.min(cl), ck.max(cl))))
    };
    // A counting sort by column, then each short column sorted.
    let mut start = vec![1usize; columns + 1];
    start[0] = 0;
    for r in 0..rows {
        for (_, c) in pairs(r) {
            start[c + 1] += 1;
        }
    }
    for c in 0..columns {
        start[c + 1] += start[c];
    }
    let mut next = start.clone();
    let mut entry_rows = vec![0usize; start[columns]];
    for c in 0..columns {
        entry_rows[next[c]] = c;
        next[c] += 1;
    }
    for r in 0..rows {
        for (row, c) in pairs(r) {
            entry_rows[next[c]] = row;
            next[c] += 1;
        }
    }
    let mut colptr = vec![0usize; columns + 1];
    let mut rowval = Vec::new();
    for c in 0..columns {
        let column = &mut entry_rows[start[c]..start[c + 1]];
        column.sort_unstable();
        let first = rowval.len();
        rowval.extend_from_slice(column);
        let mut kept = first;
        for k in first..rowval.len() {
            if k == first || rowval[k] != rowval[kept - 1] {
                rowval[kept] = rowval[k];
                kept += 1;
            }
        }
        rowval.truncate(kept);
        colptr[c + 1] = rowval.len();
    }
    (colptr, rowval)
}

/// AMD ordering of the symmetric pattern given by its upper triangle:
/// the unknown placed at each position.
pub(crate) fn minimum_degree_order(
    colptr: &[usize],
    rowval: &[usize],
    columns: usize,
) -> Vec<usize> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::amd;
    let pattern =
        faer::sparse::SymbolicSparseColMatRef::new_checked(columns, columns, colptr, None, rowval);
    let (mut order, mut inverse) = (vec![0usize; columns], vec![0usize; columns]);
    let mut work = MemBuffer::new(amd::order_scratch::<usize>(columns, rowval.len()));
    match amd::order(
        &mut order,
        &mut inverse,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut work),
    ) {
        Ok(_) => order,
        // Only on an index overflow: keep the given order.
        Err(_) => (0..columns).collect(),
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

/// The three entries of cone c of a vector whose cones follow `linear`
/// rows.
fn cone_of(v: &[f64], linear: usize, c: usize) -> Cone3 {
    let r = linear + 3 * c;
    [v[r], v[r + 1], v[r + 2]]
}

fn set_cone(v: &mut [f64], linear: usize, c: usize, value: &Cone3) {
    let r = linear + 3 * c;
    v[r..r + 3].copy_from_slice(value);
}

/// Largest α ≤ 1 keeping v + α Δv in the cones (linear rows first).
fn step_in_cones(v: &[f64], dv: &[f64], linear: usize, cones: usize) -> f64 {
    (0..cones).fold(step_to_boundary(&v[..linear], &dv[..linear]), |alpha, c| {
        alpha.min(second_order_cone::step_to_boundary(
            &cone_of(v, linear, c),
            &cone_of(dv, linear, c),
        ))
    })
}

/// Shifts v into the interior of the cones along their identity where its
/// lowest eigenvalue, over every rank's rows, is not positive (as CVXOPT's
/// coneqp starts).
fn shift_inside(v: &mut [f64], linear: usize, cones: usize, ranks: &Ranks) {
    let lowest = (0..cones)
        .map(|c| second_order_cone::lowest_eigenvalue(&cone_of(v, linear, c)))
        .chain(v[..linear].iter().copied())
        .fold(f64::INFINITY, f64::min);
    let lowest = ranks.min(lowest);
    if lowest <= 0.0 {
        v[..linear].iter_mut().for_each(|e| *e += 1.0 - lowest);
        for c in 0..cones {
            v[linear + 3 * c] += 1.0 - lowest;
        }
    }
}

/// Solves a COCD program, linear rows first and then second-order cones
/// of size 3: (x, z, iterations, reduced accuracy) in Clarabel's units,
/// so that the two solvers are interchangeable.
///
/// Each Newton step scales the cones by Nesterov–Todd (W, with
/// W⁻¹s = Wz = λ; W = diag(√(s/z)) on the linear rows), linearises the
/// complementarity as λ ∘ (W Δz + W⁻¹ Δs) = −r_c, and eliminates Δs and Δz:
///
///   (P + AᵀW⁻²A) Δx = −r_d − Aᵀ (W⁻² r_p − W⁻¹ (λ ∘⁻¹ r_c)),
///   Δs = −r_p − A Δx,   Δz = −W⁻¹ (λ ∘⁻¹ r_c) − W⁻² Δs,
///
/// with r_c = λ ∘ λ for the predictor and λ ∘ λ + (W⁻¹Δs_a) ∘ (WΔz_a) − σμe
/// for Mehrotra's corrector.
///
/// On several ranks (`ranks`, [`crate::shared_program`]) each holds its
/// rows and its columns then the separator's; every sum and extreme is
/// taken over all ranks, so that each takes the same steps and stops
/// together.
pub fn solve(
    program: &ConicProgram,
    tolerance: f64,
    max_iterations: u32,
    ranks: Ranks,
) -> Result<(Vec<f64>, Vec<f64>, u32, bool), String> {
    let n = program.mass.len();
    let m = program.b.len();
    let linear = program.linear_rows;
    let cones = program.cone_count;
    let degree = ranks.sum((linear + cones) as f64);
    let kappa = program.row_scale();
    let b: Vec<f64> = program.b.iter().map(|v| v / kappa).collect();
    let shared = ranks.shared();
    let mut pattern = NormalPattern::new(
        &program.a_matrix,
        kappa,
        n,
        shared.is_none(),
        program.is_three_dimensional(),
    );
    let fail = |what: String| format!("the interior point ({m} rows, {n} unknowns): {what}");
    for c in 0..cones {
        let r = linear + 3 * c;
        let columns =
            |q: usize| &pattern.row_column[pattern.row_start[q]..pattern.row_start[q + 1]];
        if columns(r + 1) != columns(r) || columns(r + 2) != columns(r) {
            return Err(fail(format!(
                "the rows of cone {c} do not share their columns"
            )));
        }
    }
    // x, P and q in the pattern's order of the unknowns.
    let order = pattern.order.clone();
    let mass: Vec<f64> = order.iter().map(|&u| program.mass[u]).collect();
    let q_program = program.q();
    let q: Vec<f64> = order.iter().map(|&u| q_program[u]).collect();

    // The symbolic factorisation, once per step.
    let unit = NtScaling::new(&[1.0, 0.0, 0.0], &[1.0, 0.0, 0.0]);
    pattern.assemble(&mass, &vec![1.0; linear]);
    pattern.add_cone_blocks(linear, &vec![unit; cones]);
    let mut factor = match shared {
        None => NormalFactor::new(
            &pattern.matrix,
            pattern.ordered,
            &program.column_position,
            program.is_three_dimensional(),
        ),
        Some(communicator) => {
            // Planes cut a 3D interior well; a 2D one fills less in AMD's
            // order (docs/performance.md).
            let positions: &[[f64; 3]] = if program.is_three_dimensional() {
                &program.column_position
            } else {
                &[]
            };
            NormalFactor::shared(
                &pattern.matrix,
                ranks.interior,
                &mass,
                positions,
                communicator,
            )
        }
    }
    .map_err(fail)?;
    factor.factorise(&pattern.matrix).map_err(fail)?;

    // Start: the minimiser of ½xᵀPx + qᵀx + ½|Ax − b|², then s and z
    // shifted into the interior (as in CVXOPT's coneqp).
    let mut x = vec![0.0; n];
    pattern.transpose_times(&b, &mut x);
    ranks.sum_separator(&mut x);
    for (xc, qc) in x.iter_mut().zip(&q) {
        *xc -= qc;
    }
    factor.solve(&pattern.matrix, &mut x);
    let mut ax = vec![0.0; m];
    pattern.times(&x, &mut ax);
    let mut s: Vec<f64> = b.iter().zip(&ax).map(|(bi, axi)| bi - axi).collect();
    let mut z: Vec<f64> = s.iter().map(|v| -v).collect();
    shift_inside(&mut s, linear, cones, &ranks);
    shift_inside(&mut z, linear, cones, &ranks);

    // ŨᵀM̃Ũ, the size of the objective.
    let size = program.size_over(ranks);
    let norm_b = ranks.max(infinity_norm(&b));
    let norm_q = ranks.max(infinity_norm(&q));
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
    let mut scaling = vec![NtScaling::default(); cones];
    let mut lambda = vec![[0.0; 3]; cones];
    let mut cone_theta = vec![[[0.0; 3]; 3]; cones];
    // W⁻¹ (λ ∘⁻¹ r_c) of each cone in the last direction.
    let mut scaled_rc = vec![[0.0; 3]; cones];
    for iteration in 0..=max_iterations {
        // Residuals and the stopping test.
        pattern.times(&x, &mut ax);
        pattern.transpose_times(&z, &mut atz);
        ranks.sum_separator(&mut atz);
        for c in 0..n {
            px[c] = mass[c] * x[c];
            r_d[c] = px[c] + q[c] + atz[c];
        }
        for i in 0..m {
            r_p[i] = ax[i] + s[i] - b[i];
        }
        let gap = ranks.sum(dot(&s, &z));
        let quadratic = 0.5 * ranks.dot_columns(&x, &px);
        let primal = quadratic + ranks.dot_columns(&q, &x);
        let dual = -quadratic - ranks.sum(dot(&b, &z));
        let norm = |v: &[f64]| ranks.max(infinity_norm(v));
        let primal_ok = norm(&r_p) <= tolerance * (1.0 + norm_b.max(norm(&ax)).max(norm(&s)));
        let dual_ok = norm(&r_d) <= tolerance * (1.0 + norm_q.max(norm(&px)).max(norm(&atz)));
        let gap_ok = gap <= tolerance * size.max(primal.abs().min(dual.abs()));
        if primal_ok && dual_ok && gap_ok {
            let z_out = z.iter().map(|v| v / kappa).collect();
            let mut x_out = vec![0.0; n];
            for (k, &u) in order.iter().enumerate() {
                x_out[u] = x[k];
            }
            return Ok((x_out, z_out, iteration, false));
        }
        if iteration == max_iterations {
            break;
        }
        let mu = gap / degree;

        // Normal matrix for this iterate: Θ = z/s on the linear rows, W⁻²
        // on the cones.
        for i in 0..linear {
            theta[i] = z[i] / s[i];
        }
        for c in 0..cones {
            let (s_c, z_c) = (cone_of(&s, linear, c), cone_of(&z, linear, c));
            scaling[c] = NtScaling::new(&s_c, &z_c);
            lambda[c] = scaling[c].times(&z_c);
            cone_theta[c] = scaling[c].inverse_squared();
        }
        pattern.assemble(&mass, &theta[..linear]);
        pattern.add_cone_blocks(linear, &scaling);
        factorise_or_stiffen(&mut factor, &mut pattern, &mass)
            .map_err(|e| fail(format!("iteration {iteration}: {e}")))?;

        // Predictor (affine) then corrector with the same factor.
        let mut direction =
            |rc: &[f64], dx: &mut Vec<f64>, ds: &mut Vec<f64>, dz: &mut Vec<f64>| {
                // theta = −(W⁻² r_p − W⁻¹ (λ ∘⁻¹ r_c)), row by row.
                for i in 0..linear {
                    theta[i] = (rc[i] - z[i] * r_p[i]) / s[i];
                }
                for c in 0..cones {
                    let d = second_order_cone::jordan_divide(&lambda[c], &cone_of(rc, linear, c));
                    let w_inv_d = scaling[c].inverse_times(&d);
                    let r = cone_of(&r_p, linear, c);
                    let t = &cone_theta[c];
                    let value: Cone3 = [0, 1, 2]
                        .map(|p| w_inv_d[p] - (t[p][0] * r[0] + t[p][1] * r[1] + t[p][2] * r[2]));
                    set_cone(&mut theta, linear, c, &value);
                    scaled_rc[c] = w_inv_d;
                }
                pattern.transpose_times(&theta, &mut rhs);
                ranks.sum_separator(&mut rhs);
                for c in 0..n {
                    dx[c] = rhs[c] - r_d[c];
                }
                factor.solve(&pattern.matrix, dx);
                pattern.times(dx, &mut adx);
                for i in 0..m {
                    ds[i] = -r_p[i] - adx[i];
                }
                for i in 0..linear {
                    dz[i] = (-rc[i] - z[i] * ds[i]) / s[i];
                }
                for c in 0..cones {
                    let ds_c = cone_of(ds, linear, c);
                    let t = &cone_theta[c];
                    let value: Cone3 = [0, 1, 2].map(|p| {
                        -scaled_rc[c][p]
                            - (t[p][0] * ds_c[0] + t[p][1] * ds_c[1] + t[p][2] * ds_c[2])
                    });
                    set_cone(dz, linear, c, &value);
                }
            };
        for i in 0..linear {
            rc[i] = s[i] * z[i];
        }
        for (c, l) in lambda.iter().enumerate() {
            set_cone(&mut rc, linear, c, &second_order_cone::jordan_product(l, l));
        }
        direction(&rc, &mut dx, &mut ds, &mut dz);
        let alpha = ranks
            .min(step_in_cones(&s, &ds, linear, cones).min(step_in_cones(&z, &dz, linear, cones)));
        let affine_gap: f64 = ranks.sum(
            (0..m)
                .map(|i| (s[i] + alpha * ds[i]) * (z[i] + alpha * dz[i]))
                .sum(),
        );
        let sigma = (affine_gap / gap).powi(3).min(1.0);
        for i in 0..linear {
            rc[i] = s[i] * z[i] + ds[i] * dz[i] - sigma * mu;
        }
        for c in 0..cones {
            let w = &scaling[c];
            let second = second_order_cone::jordan_product(
                &w.inverse_times(&cone_of(&ds, linear, c)),
                &w.times(&cone_of(&dz, linear, c)),
            );
            let first = second_order_cone::jordan_product(&lambda[c], &lambda[c]);
            let value = [
                first[0] + second[0] - sigma * mu,
                first[1] + second[1],
                first[2] + second[2],
            ];
            set_cone(&mut rc, linear, c, &value);
        }
        direction(&rc, &mut dx, &mut ds, &mut dz);
        let alpha = (STEP_FRACTION
            * ranks.min(
                step_in_cones(&s, &ds, linear, cones).min(step_in_cones(&z, &dz, linear, cones)),
            ))
        .min(1.0);
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

/// Factorises the normal matrix K = P + AᵀΘA of `pattern`; where round-off
/// loses a pivot, factorises K + δP instead, δ = 1e-6, 1e-4, 1e-2 in turn.
///
/// Every pivot of K is at least the mass of its column (a Schur complement
/// of K dominates P's), but late in the interior point Θ spans twenty
/// orders of magnitude and a pivot computed by cancelling entries of 1e12
/// can come out at or below zero: a heap of 100 spheres at μ = 0.9 lost one
/// at iteration 19 (`tests/cones_3d.rs`) once the dense kernels changed
/// their order of operations. The step from K + δP is a Newton step with a
/// heavier mass: the residuals stay those of the true program, so the
/// next iterations correct it, and the certificates judge the result. A
/// factorisation that succeeds at once is untouched.
fn factorise_or_stiffen(
    factor: &mut NormalFactor,
    pattern: &mut NormalPattern,
    mass: &[f64],
) -> Result<(), String> {
    let first = match factor.factorise(&pattern.matrix) {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    let mut added = 0.0;
    for fraction in [1e-6, 1e-4, 1e-2] {
        pattern.add_mass(mass, fraction - added);
        added = fraction;
        if factor.factorise(&pattern.matrix).is_ok() {
            return Ok(());
        }
    }
    Err(format!(
        "{first} (also with 1 % of the mass added to its diagonal)"
    ))
}
