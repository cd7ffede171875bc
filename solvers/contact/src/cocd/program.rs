//! The conic program of a COCD step in Clarabel's standard form (the
//! module docs of [`crate::cocd`] state it): its assembly from the
//! contacts and bodies, and the velocities and impulses read back from its
//! solution.

use super::Solution;
use crate::contacts::{tangents, Bodies, ContactSet, Scales, STATIC};
use crate::shared_program::Ranks;
use clarabel::algebra::CscMatrix;
use grainflow_core::{Dimension, Vec3};

/// The rows a contact contributes and the cone they form.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Rows {
    /// y ≥ 0 (frictionless).
    Normal,
    /// y + x ≥ 0, y − x ≥ 0 (2D, frictional).
    HalfPlanes,
    /// (y, x1, x2) in the second-order cone (3D, frictional).
    Cone,
}

impl Rows {
    fn of(dimension: Dimension, friction: f64) -> Rows {
        if friction == 0.0 {
            Rows::Normal
        } else if dimension == Dimension::Two {
            Rows::HalfPlanes
        } else {
            Rows::Cone
        }
    }

    fn count(self) -> usize {
        match self {
            Rows::Normal => 1,
            Rows::HalfPlanes => 2,
            Rows::Cone => 3,
        }
    }
}

/// Degrees of freedom of a body: (v_x, v_y, ω_z) in 2D, (v, ω) in 3D.
pub(super) fn dofs(dimension: Dimension) -> usize {
    match dimension {
        Dimension::Two => 3,
        Dimension::Three => 6,
    }
}

/// Row of the scaled Jacobian of contact α along direction e: the
/// coefficients of e·A_α ũ on the columns of i and j.
fn jacobian_row(
    contacts: &ContactSet,
    a: usize,
    e: &Vec3,
    dimension: Dimension,
    scales: &Scales,
    row: &mut Vec<(usize, f64)>,
) {
    row.clear();
    let d = dofs(dimension);
    let n_cross_e = contacts.normal[a].cross(e);
    for (body, lever, sign) in [
        (contacts.body_i[a], contacts.lever_i[a], 1.0),
        (contacts.body_j[a], contacts.lever_j[a], -1.0),
    ] {
        if body == STATIC {
            continue;
        }
        let first = body as usize * d;
        let kappa = scales.gap_per_velocity();
        let e = kappa * e;
        let rotation = -kappa * (lever / scales.length) * n_cross_e;
        match dimension {
            Dimension::Two => {
                row.push((first, sign * e.x));
                row.push((first + 1, sign * e.y));
                row.push((first + 2, rotation.z));
            }
            Dimension::Three => {
                for k in 0..3 {
                    row.push((first + k, sign * e[k]));
                    row.push((first + 3 + k, rotation[k]));
                }
            }
        }
    }
}
/// The step's program in Clarabel's standard form.
pub struct ConicProgram {
    /// Diagonal of P = M̃ and the free velocity Ũ (q = −M̃Ũ).
    pub mass: Vec<f64>,
    pub free: Vec<f64>,
    /// A = −H̃ (rows: the linear ones first, then the cones) and b.
    pub a_matrix: CscMatrix<f64>,
    pub b: Vec<f64>,
    /// Rows in the nonnegative cone, then second-order cones of size 3.
    pub linear_rows: usize,
    pub cone_count: usize,
    /// The position of each column's body: where the factor's ordering
    /// cuts the packing.
    pub column_position: Vec<[f64; 3]>,
    kinds: Vec<Rows>,
    first_row: Vec<usize>,
    dimension: Dimension,
    scales: Scales,
}

impl ConicProgram {
    pub fn q(&self) -> Vec<f64> {
        self.mass
            .iter()
            .zip(&self.free)
            .map(|(m, u)| -m * u)
            .collect()
    }

    /// ŨᵀM̃Ũ: the size of the objective.
    pub fn size(&self) -> f64 {
        self.mass
            .iter()
            .zip(&self.free)
            .map(|(m, u)| m * u * u)
            .sum()
    }

    /// [`ConicProgram::size`] of a program shared among `ranks`: the
    /// ranks' interiors summed over the ranks, the separator once.
    pub fn size_over(&self, ranks: Ranks<'_>) -> f64 {
        let weighted: Vec<f64> = self
            .mass
            .iter()
            .zip(&self.free)
            .map(|(m, u)| m * u)
            .collect();
        ranks.dot_columns(&weighted, &self.free)
    }

    /// κ = VΔt/L, the factor of every row of A.
    pub fn row_scale(&self) -> f64 {
        self.scales.gap_per_velocity()
    }

    /// Whether the bodies are spheres (six unknowns each), not discs.
    pub fn is_three_dimensional(&self) -> bool {
        self.dimension == Dimension::Three
    }

    /// The program of `rows` over `mass.len()` columns, of the same step as
    /// `self` (the ranks' programs gathered into one,
    /// [`crate::shared_program`]): for Clarabel, which needs no more.
    pub(crate) fn gathered(
        &self,
        (mass, free): (Vec<f64>, Vec<f64>),
        a_matrix: CscMatrix<f64>,
        b: Vec<f64>,
        (linear_rows, cone_count): (usize, usize),
    ) -> ConicProgram {
        ConicProgram {
            mass,
            free,
            a_matrix,
            b,
            linear_rows,
            cone_count,
            column_position: Vec::new(),
            kinds: Vec::new(),
            first_row: Vec::new(),
            dimension: self.dimension,
            scales: self.scales,
        }
    }

    /// The same rows over other columns ([`crate::shared_program`]).
    pub(crate) fn with_columns(
        &self,
        mass: Vec<f64>,
        free: Vec<f64>,
        a_matrix: CscMatrix<f64>,
        column_position: Vec<[f64; 3]>,
    ) -> ConicProgram {
        ConicProgram {
            mass,
            free,
            a_matrix,
            b: self.b.clone(),
            linear_rows: self.linear_rows,
            cone_count: self.cone_count,
            column_position,
            kinds: self.kinds.clone(),
            first_row: self.first_row.clone(),
            dimension: self.dimension,
            scales: self.scales,
        }
    }
}
/// Assembles the program of the step.
pub fn build(
    contacts: &ContactSet,
    bodies: &Bodies,
    dimension: Dimension,
    scales: &Scales,
) -> ConicProgram {
    let d = dofs(dimension);
    let columns = bodies.len() * d;
    let (length, velocity) = (scales.length, scales.velocity);

    // P = M̃ (diagonal) and q = −M̃Ũ.
    let mut mass = vec![0.0; columns];
    let mut free = vec![0.0; columns];
    for b in 0..bodies.len() {
        let m = 1.0 / (bodies.inverse_mass[b] * scales.mass);
        let inertia = 1.0 / (bodies.inverse_inertia[b] * scales.mass * length * length);
        let v = bodies.free_velocity[b] / velocity;
        let w = bodies.free_spin[b] * length / velocity;
        let first = b * d;
        match dimension {
            Dimension::Two => {
                mass[first..first + 3].copy_from_slice(&[m, m, inertia]);
                free[first..first + 3].copy_from_slice(&[v.x, v.y, w.z]);
            }
            Dimension::Three => {
                mass[first..first + 3].fill(m);
                mass[first + 3..first + 6].fill(inertia);
                free[first..first + 3].copy_from_slice(v.as_slice());
                free[first + 3..first + 6].copy_from_slice(w.as_slice());
            }
        }
    }

    // Rows: the half-plane and normal rows first, then the cones.
    let kinds: Vec<Rows> = (0..contacts.len())
        .map(|a| Rows::of(dimension, contacts.friction[a]))
        .collect();
    let linear_rows: usize = kinds
        .iter()
        .filter(|k| **k != Rows::Cone)
        .map(|k| k.count())
        .sum();
    let cone_count = kinds.iter().filter(|k| **k == Rows::Cone).count();
    let rows = linear_rows + 3 * cone_count;
    let mut first_row = vec![0usize; contacts.len()];
    let (mut next_linear, mut next_cone) = (0, linear_rows);
    for (a, kind) in kinds.iter().enumerate() {
        if *kind == Rows::Cone {
            first_row[a] = next_cone;
            next_cone += 3;
        } else {
            first_row[a] = next_linear;
            next_linear += kind.count();
        }
    }

    // A in compressed columns, assembled in two passes over the contacts
    // in the order of their rows (the linear ones, then the cones): the
    // first counts each column's entries, the second writes them, so
    // that each column's rows come ascending with no sort and no list of
    // triplets. Entries of one row on one column (a half-plane's normal
    // and tangent parts) are summed in the order they come.
    let mut b = vec![0.0; rows];
    let (mut normal_row, mut tangent_row, mut second_row) = (Vec::new(), Vec::new(), Vec::new());
    let order: Vec<usize> = (0..contacts.len())
        .filter(|&a| kinds[a] != Rows::Cone)
        .chain((0..contacts.len()).filter(|&a| kinds[a] == Rows::Cone))
        .collect();
    let each_entry = |entry: &mut dyn FnMut(usize, usize, f64)| {
        for &a in &order {
            let n = contacts.normal[a];
            let mu = contacts.friction[a];
            let (t1, t2) = tangents(dimension, &n);
            let r = first_row[a];
            let mut push = |r: usize, row: &[(usize, f64)], factor: f64| {
                for &(c, v) in row {
                    entry(r, c, -factor * v); // A = −H̃
                }
            };
            jacobian_row(contacts, a, &n, dimension, scales, &mut normal_row);
            match kinds[a] {
                Rows::Normal => push(r, &normal_row, 1.0),
                Rows::HalfPlanes => {
                    jacobian_row(contacts, a, &t1, dimension, scales, &mut tangent_row);
                    push(r, &normal_row, 1.0);
                    push(r, &tangent_row, mu);
                    push(r + 1, &normal_row, 1.0);
                    push(r + 1, &tangent_row, -mu);
                }
                Rows::Cone => {
                    jacobian_row(contacts, a, &t1, dimension, scales, &mut tangent_row);
                    jacobian_row(contacts, a, &t2, dimension, scales, &mut second_row);
                    push(r, &normal_row, 1.0);
                    push(r + 1, &tangent_row, mu);
                    push(r + 2, &second_row, mu);
                }
            }
        }
    };
    let a_matrix = csc_in_row_order(rows, columns, each_entry);
    for a in 0..contacts.len() {
        let r = first_row[a];
        let gap = contacts.gap[a] / length;
        b[r] = gap;
        if kinds[a] == Rows::HalfPlanes {
            b[r + 1] = gap;
        }
    }
    ConicProgram {
        mass,
        free,
        a_matrix,
        b,
        linear_rows,
        cone_count,
        column_position: (0..columns)
            .map(|c| {
                bodies
                    .position
                    .get(c / d)
                    .map_or([0.0; 3], |x| [x.x, x.y, x.z])
            })
            .collect(),
        kinds,
        first_row,
        dimension,
        scales: *scales,
    }
}

/// A in compressed columns from its entries (row, column, value), which
/// `visit` hands to its argument in ascending rows, the same each time it
/// is called (twice: to count each column's entries, then to write them).
/// A column's rows then come ascending with no sort; entries of one row on
/// one column are summed in the order they come, as Clarabel's builder
/// sums repeated triplets.
fn csc_in_row_order(
    rows: usize,
    columns: usize,
    mut visit: impl FnMut(&mut dyn FnMut(usize, usize, f64)),
) -> CscMatrix<f64> {
    let mut last_row = vec![usize::MAX; columns];
    let mut colptr = vec![0usize; columns + 1];
    visit(&mut |r, c, _| {
        if last_row[c] != r {
            last_row[c] = r;
            colptr[c + 1] += 1;
        }
    });
    for c in 0..columns {
        colptr[c + 1] += colptr[c];
    }
    let entries = colptr[columns];
    let (mut rowval, mut nzval) = (vec![0usize; entries], vec![0.0; entries]);
    let mut next = colptr.clone();
    last_row.fill(usize::MAX);
    visit(&mut |r, c, v| {
        if last_row[c] == r {
            nzval[next[c] - 1] += v;
        } else {
            last_row[c] = r;
            rowval[next[c]] = r;
            nzval[next[c]] = v;
            next[c] += 1;
        }
    });
    CscMatrix::new(rows, columns, colptr, rowval, nzval)
}
/// The multipliers z of the program whose contacts' impulses are
/// `impulses` (normal, tangential): the inverse of [`recover`]'s, the
/// tangential impulse's part out of the contact's tangent plane dropped.
pub(super) fn multipliers(
    contacts: &ContactSet,
    program: &ConicProgram,
    impulses: &[(f64, Vec3)],
) -> Vec<f64> {
    let unit = program.scales.impulse();
    let mut z = vec![0.0; program.b.len()];
    for (a, &(normal, tangential)) in impulses.iter().enumerate() {
        let r = program.first_row[a];
        let mu = contacts.friction[a];
        let (t1, t2) = tangents(program.dimension, &contacts.normal[a]);
        let (normal, along) = (normal / unit, tangential / unit);
        match program.kinds[a] {
            Rows::Normal => z[r] = normal,
            Rows::HalfPlanes => {
                let across = along.dot(&t1) / mu;
                z[r] = 0.5 * (normal + across);
                z[r + 1] = 0.5 * (normal - across);
            }
            Rows::Cone => {
                z[r] = normal;
                z[r + 1] = along.dot(&t1) / mu;
                z[r + 2] = along.dot(&t2) / mu;
            }
        }
    }
    z
}

/// The velocities and impulses of a solution (x, z) of the program.
pub(super) fn recover(
    contacts: &ContactSet,
    program: &ConicProgram,
    x: &[f64],
    z: &[f64],
    iterations: u32,
    reduced_accuracy: bool,
) -> Solution {
    let (dimension, scales) = (program.dimension, &program.scales);
    let (length, velocity) = (scales.length, scales.velocity);
    let d = dofs(dimension);
    let bodies = program.mass.len() / d;
    let (kinds, first_row) = (&program.kinds, &program.first_row);

    let mut out = Solution {
        velocity: Vec::with_capacity(bodies),
        spin: Vec::with_capacity(bodies),
        normal_impulse: vec![0.0; contacts.len()],
        tangential_impulse: vec![Vec3::zeros(); contacts.len()],
        iterations,
        reduced_accuracy,
        fallback_reason: None,
    };
    for body in 0..bodies {
        let first = body * d;
        let (v, w) = match dimension {
            Dimension::Two => (
                Vec3::new(x[first], x[first + 1], 0.0),
                Vec3::new(0.0, 0.0, x[first + 2]),
            ),
            Dimension::Three => (
                Vec3::new(x[first], x[first + 1], x[first + 2]),
                Vec3::new(x[first + 3], x[first + 4], x[first + 5]),
            ),
        };
        out.velocity.push(v * velocity);
        out.spin.push(w * velocity / length);
    }
    let unit = scales.impulse();
    for a in 0..contacts.len() {
        let r = first_row[a];
        let mu = contacts.friction[a];
        let (t1, t2) = tangents(dimension, &contacts.normal[a]);
        let (normal, tangential) = match kinds[a] {
            Rows::Normal => (z[r], Vec3::zeros()),
            Rows::HalfPlanes => (z[r] + z[r + 1], mu * (z[r] - z[r + 1]) * t1),
            Rows::Cone => (z[r], mu * (z[r + 1] * t1 + z[r + 2] * t2)),
        };
        out.normal_impulse[a] = normal * unit;
        out.tangential_impulse[a] = tangential * unit;
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;

    /// Repeated entries summed in the same order as Clarabel's builder, so
    /// that a program is bitwise the same whichever builds it.
    #[test]
    fn entries_in_row_order_make_the_same_matrix_as_clarabels_builder() {
        let (rows, columns) = (7, 5);
        let mut state = 12345u64;
        let mut next = |bound: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as usize) % bound
        };
        let (mut r, mut c, mut v) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..60 {
            r.push(next(rows));
            c.push(next(columns));
            v.push(0.1 + k as f64 / 7.0);
        }
        // In ascending rows (a stable sort keeps repeated entries' order).
        let mut order: Vec<usize> = (0..r.len()).collect();
        order.sort_by_key(|&k| r[k]);
        let (r, c, v): (Vec<usize>, Vec<usize>, Vec<f64>) = (
            order.iter().map(|&k| r[k]).collect(),
            order.iter().map(|&k| c[k]).collect(),
            order.iter().map(|&k| v[k]).collect(),
        );
        let ours = csc_in_row_order(rows, columns, |entry| {
            for k in 0..r.len() {
                entry(r[k], c[k], v[k]);
            }
        });
        let clarabels = CscMatrix::new_from_triplets(rows, columns, r, c, v);
        assert_eq!(ours.colptr, clarabels.colptr);
        assert_eq!(ours.rowval, clarabels.rowval);
        assert_eq!(ours.nzval, clarabels.nzval);
    }
}
