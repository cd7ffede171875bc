//! COCD's program solved through its dual by an accelerated projected
//! gradient: no factor, two sparse products an iteration, memory linear
//! in the contacts.
//!
//! The program (see [`crate::cocd`]) is min ½ xᵀPx + qᵀx subject to
//! Ax + s = b, s ∈ K, with P = M̃ diagonal and K the product of the
//! nonnegative rows and the Coulomb cones. For multipliers z ∈ K (K is
//! self-dual) the minimiser over x is x(z) = −P⁻¹(q + Aᵀz), and the dual
//!
//!   min_{z ∈ K} φ(z) = ½ (q + Aᵀz)ᵀ P⁻¹ (q + Aᵀz) + bᵀz,
//!   ∇φ(z) = b − A x(z) = s(z),
//!
//! has as gradient the slack the multipliers leave: the gaps and sliding
//! rates of the contacts at the velocities x(z). Its minimiser is the
//! complementarity z ∈ K, s ∈ K, zᵀs = 0 of the interior point's solution.
//!
//! Nesterov's accelerated projection (FISTA) with the gradient restart of
//! O'Donoghue & Candès (2015), in the metric of one scalar per cone (the
//! largest diagonal entry of its block of N = AP⁻¹Aᵀ, Jacobi's): a cone
//! scaled by a scalar is the same cone, so the projection is still each
//! cone's own, in closed form. The step is 1/L, L the largest eigenvalue of
//! the scaled N by power iteration, widened by [`LIPSCHITZ_MARGIN`] and
//! doubled wherever an iteration raises φ.
//!
//! Every iterate is dual feasible by construction (z ∈ K, x = x(z)); the
//! stopping test is the interior point's: the primal residual, here the
//! distance of s(z) from K, and the gap sᵀz, each relative to the size of
//! the data and the objective, below ε. Each output element of a product
//! sums its terms in one fixed order, and each sum over the rows adds the
//! partial sums of fixed blocks of rows in order ([`ROW_BLOCK`]), so the
//! iterates do not depend on the number of threads.
//!
//! On several ranks ([`Ranks`]) each rank holds its rows of A and the
//! columns they reach, the separator's on every rank (see
//! [`crate::shared_program`]): A x is the rank's own rows, Aᵀz on the
//! separator adds the ranks' parts (one exchange of the separator's
//! unknowns an iteration), and every sum or extreme the iteration decides
//! by is taken over the ranks, so that every rank takes the same steps,
//! restarts and stop. The iterates are one rank's up to the order of the
//! sums.

use super::cone_blocks::ConeBlocks;
use crate::cocd::ConicProgram;
use crate::second_order_cone::Cone3;
use crate::shared_program::Ranks;
use rayon::prelude::*;

/// Power iterations for the largest eigenvalue of the scaled N.
const POWER_ITERATIONS: usize = 30;
/// The step's Lipschitz bound over the power iteration's estimate (which
/// approaches the eigenvalue from below).
const LIPSCHITZ_MARGIN: f64 = 1.1;
/// Iterations between two stopping tests (each costs a product pair).
const TEST_EVERY: u32 = 10;
/// Outputs shorter than this are summed on one thread.
const PARALLEL_ROWS: usize = 20_000;
/// Rows of a block of the passes over the rows: a multiple of 3, so that a
/// block of the cones' rows holds whole cones. The blocks, not the
/// threads, set the order of a sum.
const ROW_BLOCK: usize = 3 * 1024;

/// A in compressed rows and columns, scaled by 1/κ (as the interior point
/// scales it: s in units of V Δt, z of m̄ V). Indices of 32 bits: the
/// products stream every entry with its index each iteration, and a
/// quarter of the bytes less is a quarter less of their memory traffic.
/// In 3D the cone rows are held as one block per contact instead
/// ([`ConeBlocks`], the same bits), the stored entries then only the
/// linear rows'.
struct Operator {
    row_start: Vec<usize>,
    row_column: Vec<u32>,
    row_value: Vec<f64>,
    column_start: Vec<usize>,
    column_row: Vec<u32>,
    column_value: Vec<f64>,
    cones: Option<ConeBlocks>,
}

impl Operator {
    /// The operator of `program` scaled by 1/`scale`, and the diagonal of
    /// N = AP⁻¹Aᵀ (the metric's source), read from the rows before the
    /// blocks take the cones' over.
    fn new(program: &ConicProgram, scale: f64) -> (Self, Vec<f64>) {
        let a = &program.a_matrix;
        let rows = a.m;
        let (mut row_start, row_column, mut row_value) = crate::csc::scaled_rows(a, scale);
        // Both counts below 2^32 (checked by `solve`).
        let narrow = |indices: &[usize]| indices.iter().map(|&i| i as u32).collect::<Vec<u32>>();
        let mut row_column = narrow(&row_column);
        let mass = &program.mass;
        let diagonal: Vec<f64> = (0..rows)
            .map(|r| {
                (row_start[r]..row_start[r + 1])
                    .map(|k| row_value[k].powi(2) / mass[row_column[k] as usize])
                    .sum()
            })
            .collect();
        let linear = program.linear_rows;
        let cones = program
            .is_three_dimensional()
            .then(|| ConeBlocks::from_rows((&row_start, &row_column, &row_value), linear, a.n))
            .flatten();
        // Aᵀ's entries: every row's, or where the blocks hold the cones
        // only the linear rows' (the first rows, so each column's first
        // entries, its rows ascending).
        let stored_rows = if cones.is_some() { linear } else { rows };
        let kept = row_start[stored_rows];
        if cones.is_some() {
            row_start.truncate(linear + 1);
            row_column.truncate(kept);
            row_value.truncate(kept);
            row_column.shrink_to_fit();
            row_value.shrink_to_fit();
        }
        let mut column_start = Vec::with_capacity(a.n + 1);
        column_start.push(0);
        let (mut column_row, mut column_value) =
            (Vec::with_capacity(kept), Vec::with_capacity(kept));
        for c in 0..a.n {
            for k in a.colptr[c]..a.colptr[c + 1] {
                if a.rowval[k] < stored_rows {
                    column_row.push(a.rowval[k] as u32);
                    column_value.push(a.nzval[k] / scale);
                }
            }
            column_start.push(column_row.len());
        }
        let operator = Operator {
            row_start,
            row_column,
            row_value,
            column_start,
            column_row,
            column_value,
            cones,
        };
        (operator, diagonal)
    }

    /// out = A x.
    fn times(&self, x: &[f64], out: &mut [f64]) {
        let stored = self.row_start.len() - 1;
        sums(
            &self.row_start,
            &self.row_column,
            &self.row_value,
            x,
            &mut out[..stored],
        );
        if let Some(cones) = &self.cones {
            cones.times(x, out);
        }
    }

    /// out = Aᵀ z.
    fn transpose_times(&self, z: &[f64], out: &mut [f64]) {
        let columns = (
            &self.column_start[..],
            &self.column_row[..],
            &self.column_value[..],
        );
        match &self.cones {
            Some(cones) => cones.transpose_times(z, out, columns),
            None => sums(columns.0, columns.1, columns.2, z, out),
        }
    }
}

/// `out[i] = Σ_k value[k] v[index[k]]` over `k` in `start[i]..start[i + 1]`,
/// each sum in that order (on threads for long outputs: the same bits).
fn sums(start: &[usize], index: &[u32], value: &[f64], v: &[f64], out: &mut [f64]) {
    let sum = |i: usize| -> f64 {
        (start[i]..start[i + 1])
            .map(|k| value[k] * v[index[k] as usize])
            .sum()
    };
    if out.len() < PARALLEL_ROWS {
        out.iter_mut().enumerate().for_each(|(i, o)| *o = sum(i));
    } else {
        out.par_iter_mut()
            .enumerate()
            .with_min_len(512)
            .for_each(|(i, o)| *o = sum(i));
    }
}

/// The cones of the rows: `linear` nonnegative rows, then cones of three.
#[derive(Clone, Copy)]
struct Cones {
    linear: usize,
    count: usize,
}

impl Cones {
    /// Projects `v` onto K in place.
    fn project(&self, v: &mut [f64]) {
        let (linear, cones) = v.split_at_mut(self.linear);
        project_linear(linear);
        project_cones(cones);
    }

    /// The largest distance of a cone's (or a row's) `v` from K.
    fn distance(&self, v: &[f64]) -> f64 {
        let linear = v[..self.linear].iter().fold(0.0_f64, |m, &e| m.max(-e));
        v[self.linear..]
            .chunks_exact(3)
            .map(|c| {
                let cone = [c[0], c[1], c[2]];
                let p = project_on_cone(&cone);
                ((cone[0] - p[0]).powi(2) + (cone[1] - p[1]).powi(2) + (cone[2] - p[2]).powi(2))
                    .sqrt()
            })
            .fold(linear, f64::max)
    }

    /// The metric's scalar of each row: 1 over the largest `diagonal`
    /// entry of N = AP⁻¹Aᵀ on the row's cone (its own entry on a linear
    /// row).
    fn jacobi(&self, diagonal: &[f64]) -> Vec<f64> {
        let mut scale: Vec<f64> = diagonal[..self.linear].to_vec();
        for c in 0..self.count {
            let r = self.linear + 3 * c;
            let largest = diagonal[r].max(diagonal[r + 1]).max(diagonal[r + 2]);
            scale.extend([largest; 3]);
        }
        // A row no body moves (none in a program) keeps a unit metric.
        scale
            .into_iter()
            .map(|d| if d > 0.0 { 1.0 / d } else { 1.0 })
            .collect()
    }
}

/// Projects nonnegative rows onto their half-line.
fn project_linear(v: &mut [f64]) {
    v.iter_mut().for_each(|e| *e = e.max(0.0));
}

/// Projects consecutive cones of three rows onto theirs.
fn project_cones(v: &mut [f64]) {
    for cone in v.chunks_exact_mut(3) {
        let projected = project_on_cone(&[cone[0], cone[1], cone[2]]);
        cone.copy_from_slice(&projected);
    }
}

/// The projection of (y, x) onto {|x| ≤ y}.
fn project_on_cone(v: &Cone3) -> Cone3 {
    let across = (v[1] * v[1] + v[2] * v[2]).sqrt();
    if across <= v[0] {
        *v
    } else if across <= -v[0] {
        [0.0; 3]
    } else {
        let half = 0.5 * (v[0] + across);
        [half, half * v[1] / across, half * v[2] / across]
    }
}

/// Work arrays of the dual's gradient.
struct Gradient<'a> {
    operator: &'a Operator,
    ranks: Ranks<'a>,
    mass: &'a [f64],
    q: &'a [f64],
    b: &'a [f64],
    atz: Vec<f64>,
    x: Vec<f64>,
}

impl Gradient<'_> {
    /// x(z) = −P⁻¹(q + Aᵀz) into `self.x`, s(z) = b − A x(z) into `slack`;
    /// returns (½ x(z)ᵀP x(z), bᵀz), whose sum is φ(z), each over the
    /// ranks where `reduce`; the rank's own parts where not (the
    /// iterations between two tests need no φ).
    fn at(&mut self, z: &[f64], slack: &mut [f64], reduce: bool) -> (f64, f64) {
        self.operator.transpose_times(z, &mut self.atz);
        self.ranks.sum_separator(&mut self.atz);
        let (q, atz, mass) = (self.q, &self.atz, self.mass);
        each(&mut self.x, |c, x| *x = -(q[c] + atz[c]) / mass[c]);
        self.operator.times(&self.x, slack);
        let b = self.b;
        each(slack, |r, s| *s = b[r] - *s);
        if !reduce {
            return (0.0, 0.0);
        }
        // ½ xᵀPx: the rank's interior summed over the ranks, the separator
        // once.
        let (mass, x) = (self.mass, &self.x);
        let quadratic = |columns: std::ops::Range<usize>| -> f64 {
            columns.map(|c| mass[c] * x[c] * x[c]).sum()
        };
        let interior = self.ranks.interior;
        let mut sums = [0.5 * quadratic(0..interior), dot(self.b, z)];
        self.ranks.sum_each(&mut sums);
        sums[0] += 0.5 * quadratic(interior..x.len());
        (sums[0], sums[1])
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `set(i, &mut v[i])` for every element, on threads for long vectors.
fn each(v: &mut [f64], set: impl Fn(usize, &mut f64) + Sync) {
    if v.len() < PARALLEL_ROWS {
        v.iter_mut().enumerate().for_each(|(i, e)| set(i, e));
    } else {
        v.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, e)| set(i, e));
    }
}

/// One accelerated step over the rows, z ← Π_K(y − t D s) with the last
/// z kept in `previous`, in blocks of [`ROW_BLOCK`] rows (on threads for
/// many rows); returns the rank's (y − z)·(z − previous), the blocks'
/// sums added in order.
fn project_step(
    cones: Cones,
    step: f64,
    (metric, slack, y): (&[f64], &[f64], &[f64]),
    z: &mut [f64],
    previous: &mut [f64],
) -> f64 {
    let linear = cones.linear;
    let (z_linear, z_cones) = z.split_at_mut(linear);
    let (previous_linear, previous_cones) = previous.split_at_mut(linear);
    let block = |z: &mut [f64], previous: &mut [f64], from: usize, is_cone: bool| -> f64 {
        previous.copy_from_slice(z);
        for (k, e) in z.iter_mut().enumerate() {
            let r = from + k;
            *e = y[r] - step * metric[r] * slack[r];
        }
        if is_cone {
            project_cones(z);
        } else {
            project_linear(z);
        }
        z.iter()
            .zip(previous.iter())
            .enumerate()
            .map(|(k, (z, p))| (y[from + k] - z) * (z - p))
            .sum()
    };
    let blocks = |z: &mut [f64], previous: &mut [f64], offset: usize, is_cone: bool| -> f64 {
        let partials: Vec<f64> = if z.len() < PARALLEL_ROWS {
            z.chunks_mut(ROW_BLOCK)
                .zip(previous.chunks_mut(ROW_BLOCK))
                .enumerate()
                .map(|(k, (z, p))| block(z, p, offset + k * ROW_BLOCK, is_cone))
                .collect()
        } else {
            z.par_chunks_mut(ROW_BLOCK)
                .zip(previous.par_chunks_mut(ROW_BLOCK))
                .enumerate()
                .map(|(k, (z, p))| block(z, p, offset + k * ROW_BLOCK, is_cone))
                .collect()
        };
        partials.iter().sum()
    };
    blocks(z_linear, previous_linear, 0, false) + blocks(z_cones, previous_cones, linear, true)
}

fn infinity_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Solves `program` to the interior point's test at `tolerance` within
/// `max_iterations`, from the multipliers `start` (in the program's units,
/// as returned; zero where `None`), shared among `ranks` as the interior
/// point's. Returns (x, z, iterations, false) in the program's units, as
/// [`crate::interior_point::solve`] does; on several ranks every rank
/// returns or fails alike.
pub fn solve(
    program: &ConicProgram,
    tolerance: f64,
    max_iterations: u32,
    start: Option<&[f64]>,
    ranks: Ranks<'_>,
) -> Result<(Vec<f64>, Vec<f64>, u32, bool), String> {
    let (n, m) = (program.mass.len(), program.b.len());
    if n.max(m) > u32::MAX as usize {
        return Err(format!(
            "the projected gradient: {m} rows and {n} unknowns, more than its 32-bit indices \
             hold ({}); share the scene among ranks",
            u32::MAX
        ));
    }
    let kappa = program.row_scale();
    let (operator, diagonal) = Operator::new(program, kappa);
    let cones = Cones {
        linear: program.linear_rows,
        count: program.cone_count,
    };
    let b: Vec<f64> = program.b.iter().map(|v| v / kappa).collect();
    let q = program.q();
    let mass = &program.mass;
    let metric = cones.jacobi(&diagonal);
    let fail = |what: String| format!("the projected gradient ({m} rows, {n} unknowns): {what}");
    let mut gradient = Gradient {
        operator: &operator,
        ranks,
        mass,
        q: &q,
        b: &b,
        atz: vec![0.0; n],
        x: vec![0.0; n],
    };

    // L: the largest eigenvalue of S = D^½ A P⁻¹ Aᵀ D^½, by power iteration
    // (w ← S w/|S w|, the estimate wᵀ S w at |w| = 1), from a start that
    // depends on each row's place in its cone alone, not on how the rows
    // are numbered or shared among ranks.
    let lipschitz = {
        let linear = cones.linear;
        let mut w: Vec<f64> = (0..m)
            .map(|r| match r.checked_sub(linear) {
                None => 1.0,
                Some(k) => 1.0 + 0.1 * (k % 3) as f64,
            })
            .collect();
        let (mut u, mut atu, mut sw) = (vec![0.0; m], vec![0.0; n], vec![0.0; m]);
        let mut estimate: f64 = 0.0;
        for _ in 0..POWER_ITERATIONS {
            let norm = ranks.sum(dot(&w, &w)).sqrt();
            if norm == 0.0 {
                break;
            }
            for r in 0..m {
                w[r] /= norm;
                u[r] = metric[r].sqrt() * w[r];
            }
            operator.transpose_times(&u, &mut atu);
            ranks.sum_separator(&mut atu);
            atu.iter_mut().zip(mass).for_each(|(e, p)| *e /= p);
            operator.times(&atu, &mut sw);
            sw.iter_mut().zip(&metric).for_each(|(e, d)| *e *= d.sqrt());
            estimate = ranks.sum(dot(&w, &sw));
            std::mem::swap(&mut w, &mut sw);
        }
        LIPSCHITZ_MARGIN * estimate.max(f64::MIN_POSITIVE)
    };
    let mut step = 1.0 / lipschitz;

    // The sizes the stopping test is relative to, as the interior point's.
    let size = program.size_over(ranks);
    let norm_b = ranks.max(infinity_norm(&b));

    let mut z: Vec<f64> = match start {
        Some(start) => start.iter().map(|v| v * kappa).collect(),
        None => vec![0.0; m],
    };
    cones.project(&mut z);
    let mut y = z.clone();
    let mut previous = z.clone();
    let mut slack = vec![0.0; m];
    let mut theta: f64 = 1.0;
    let mut value_at_z = f64::INFINITY;
    for iteration in 0..=max_iterations {
        if iteration % TEST_EVERY == 0 || iteration == max_iterations {
            let (quadratic, bz) = gradient.at(&z, &mut slack, true);
            let value = quadratic + bz;
            // s = Π_K(s(z)) and its distance; the gap sᵀz of the projected s.
            let distance = ranks.max(cones.distance(&slack));
            let mut projected = slack.clone();
            cones.project(&mut projected);
            let gap = ranks.sum(dot(&projected, &z)).abs();
            let primal = quadratic + ranks.dot_columns(&q, &gradient.x);
            let dual = -quadratic - bz;
            // |A x(z)| = |b − s(z)|, and φ(z) = ½ xᵀPx + bᵀz: no product again.
            let ax = b
                .iter()
                .zip(&slack)
                .fold(0.0_f64, |m, (b, s)| m.max((b - s).abs()));
            let largest = ranks.max(ax.max(infinity_norm(&projected)));
            let primal_ok = distance <= tolerance * (1.0 + norm_b.max(largest));
            let gap_ok = gap <= tolerance * size.max(primal.abs().min(dual.abs()));
            if primal_ok && gap_ok {
                let z_out = z.iter().map(|v| v / kappa).collect();
                return Ok((gradient.x.clone(), z_out, iteration, false));
            }
            if !value.is_finite() {
                return Err(fail(format!("φ is not finite at iteration {iteration}")));
            }
            // A rise of φ between tests: the step was too long for the
            // curvature met; halve it and restart the momentum.
            if value > value_at_z + 1e-12 * value_at_z.abs() {
                step *= 0.5;
                theta = 1.0;
                y.copy_from_slice(&z);
            }
            value_at_z = value;
        }
        if iteration == max_iterations {
            break;
        }
        // z_{k+1} = Π_K(y − t D ∇φ(y)), and the restart where the step
        // goes against the momentum (the gradient scheme of O'Donoghue &
        // Candès): (y − z_{k+1})·(z_{k+1} − z_k) > 0.
        gradient.at(&y, &mut slack, false);
        let against = ranks.sum(project_step(
            cones,
            step,
            (&metric, &slack, &y),
            &mut z,
            &mut previous,
        ));
        if against > 0.0 {
            theta = 1.0;
            y.copy_from_slice(&z);
            continue;
        }
        let next = 0.5 * (-theta * theta + theta * (theta * theta + 4.0).sqrt());
        let beta = theta * (1.0 - theta) / (theta * theta + next);
        theta = next;
        let (z, previous) = (&z, &previous);
        each(&mut y, |r, y| *y = z[r] + beta * (z[r] - previous[r]));
    }
    Err(fail(format!(
        "no solution to ε = {tolerance:.1e} within {max_iterations} iterations"
    )))
}
