//! COCD on several ranks: one conic program over every rank's contacts,
//! each rank holding its own rows and the columns they reach.
//!
//! Each rank holds the pairs of its own grains (a pair across ranks on the
//! lower rank, [`crate::contacts::CrossingPairs::LowerRank`]), hence the
//! rows of A of those pairs, and a body for every grain they reach, its
//! copies of other ranks' grains included
//! ([`crate::contacts::with_bodies_marked`]).
//! The program's columns then fall in two kinds:
//!
//! - the **interior** of a rank: its own grains that no other rank's pairs
//!   reach; only this rank's rows touch them;
//! - the **separator** S: the grains whose columns stand on more than one
//!   rank (a copy reached by the pairs of the rank that holds it, and the
//!   grain on its owner): the higher rank's layer of grains along each
//!   boundary. Every rank holds all of S, in the order of the
//!   grains' ids, with the same values: the owners' masses and free
//!   velocities, and after each Aᵀz the ranks' parts summed.
//!
//! On a rank the unknowns read [x_I; x_S]. Sums over the columns add the
//! ranks' interiors and S once; sums and extremes over the rows add or
//! compare the ranks' rows. The normal matrix K = P + AᵀΘA is the sum of
//! the ranks' parts, and is factorised by the ranks together through the
//! Schur complement of S ([`crate::normal_factor`]). The iterates are those
//! of one rank up to the order of the sums: the same solution to round-off
//! once the tolerance is tight.

use crate::cocd::ConicProgram;
use crate::contacts::Bodies;
use clarabel::algebra::CscMatrix;
use grainflow_core::Communicator;

/// The dense end of a rank's factor over the ns_t separator unknowns its
/// pairs reach, in units of ns_t² numbers: what the most loaded rank's
/// peak resident memory holds beyond its share of the scene (the whole
/// scene's estimate over the ranks) and Σ, one COCD step on packings at
/// rest, ε = 1e-5, one thread a rank (2026-12-05):
///
/// | spheres | ranks | ns | ns_t | measured | estimate |
/// | --- | --- | --- | --- | --- | --- |
/// | 8,748 | 2 | 2,172 | 2,172 | 401 MiB | 365 MiB (−9 %) |
/// | 8,748 | 3 | 4,308 | 4,308 | 571 MiB | 537 MiB (−6 %) |
/// | 8,748 | 4 (2 × 2) | 4,236 | 2,208 | 362 MiB | 330 MiB (−9 %) |
/// | 17,986 | 2 | 3,522 | 3,522 | 954 MiB | 942 MiB (−1 %) |
/// | 17,986 | 3 | 7,032 | 7,032 | 1,282 MiB | 1,414 MiB (+10 %) |
/// | 17,986 | 4 (2 × 2) | 6,954 | 3,588 | 870 MiB | 869 MiB (0 %) |
///
/// The measured excess spans 1.15–2.52 ns_t², the larger at the smaller
/// packing.
pub const SEPARATOR_BLOCK_OVER_SQUARE: f64 = 1.5;

/// The bytes a rank holds for the interior point's dense blocks over a
/// separator of `unknowns`: Σ, and at most its own factor's dense end
/// (ns_t ≤ ns).
pub fn separator_block_bytes(unknowns: usize) -> f64 {
    (1.0 + SEPARATOR_BLOCK_OVER_SQUARE) * 8.0 * (unknowns as f64).powi(2)
}

/// How the interior point's unknowns are shared among ranks: the first
/// `interior` columns are the rank's own, the rest the separator held on
/// every rank (none on one rank).
#[derive(Clone, Copy)]
pub struct Ranks<'a> {
    pub communicator: Option<&'a Communicator>,
    pub interior: usize,
}

impl<'a> Ranks<'a> {
    /// One rank: every column is interior, every reduction the rank's own
    /// value.
    pub fn alone(columns: usize) -> Self {
        Ranks {
            communicator: None,
            interior: columns,
        }
    }

    /// Whether the program is shared (a separator factorised together).
    pub fn shared(&self) -> Option<&'a Communicator> {
        self.communicator
    }

    /// Sum over the ranks of a sum over their rows.
    pub fn sum(&self, local: f64) -> f64 {
        self.communicator.map_or(local, |c| c.sum(local))
    }

    pub fn max(&self, local: f64) -> f64 {
        self.communicator.map_or(local, |c| c.max(local))
    }

    pub fn min(&self, local: f64) -> f64 {
        -self.max(-local)
    }

    /// aᵀb over the columns: the ranks' interiors and the separator once.
    pub fn dot_columns(&self, a: &[f64], b: &[f64]) -> f64 {
        let i = self.interior;
        self.sum(dot(&a[..i], &b[..i])) + dot(&a[i..], &b[i..])
    }

    /// Sums over the ranks of several sums over their rows, in one exchange.
    pub fn sum_each(&self, local: &mut [f64]) {
        if let Some(communicator) = self.communicator {
            communicator.sum_each(local);
        }
    }

    /// Adds up the ranks' parts of a column vector on the separator (Aᵀz
    /// from each rank's rows).
    pub fn sum_separator(&self, values: &mut [f64]) {
        if let Some(communicator) = self.communicator {
            communicator.sum_each(&mut values[self.interior..]);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The rank's program with its columns as the ranks share them, and where
/// each of the rank's bodies stands in it.
pub struct SharedProgram {
    pub program: ConicProgram,
    /// Interior columns (the separator's follow).
    pub interior: usize,
    /// First column of each body of the rank's program.
    pub body_column: Vec<usize>,
}

impl SharedProgram {
    /// Shares `program` (over `bodies`, `d` unknowns each) among the
    /// ranks: `separator[b]` says whether body b's columns stand on another
    /// rank too; `ids` are the local grains' ids (collective).
    pub fn new(
        program: &ConicProgram,
        bodies: &Bodies,
        d: usize,
        separator: &[bool],
        ids: &[u64],
        communicator: &Communicator,
    ) -> Result<Self, String> {
        // The owners tell every rank the separator's grains: id, then the
        // columns' masses and free velocities, then the position.
        let record = 1 + 2 * d + 3;
        let mut mine = Vec::new();
        for b in 0..bodies.owned {
            if separator[b] {
                mine.push(ids[bodies.grain[b] as usize] as f64);
                mine.extend_from_slice(&program.mass[b * d..(b + 1) * d]);
                mine.extend_from_slice(&program.free[b * d..(b + 1) * d]);
                mine.extend_from_slice(&program.column_position[b * d]);
            }
        }
        let received = communicator.exchange(vec![mine; communicator.size()]);
        let mut records: Vec<&[f64]> = received.iter().flat_map(|m| m.chunks(record)).collect();
        records.sort_by_key(|r| r[0] as u64);
        let place: std::collections::HashMap<u64, usize> = records
            .iter()
            .enumerate()
            .map(|(k, r)| (r[0] as u64, k))
            .collect();

        let interior_bodies: Vec<usize> = (0..bodies.len()).filter(|&b| !separator[b]).collect();
        let interior = d * interior_bodies.len();
        let columns = interior + d * records.len();
        let mut body_column = vec![0usize; bodies.len()];
        for (k, &b) in interior_bodies.iter().enumerate() {
            body_column[b] = d * k;
        }
        for b in (0..bodies.len()).filter(|&b| separator[b]) {
            let id = ids[bodies.grain[b] as usize];
            let Some(&k) = place.get(&id) else {
                return Err(format!(
                    "grain {id}, reached by the pairs of rank {}, is not announced by its owner",
                    communicator.rank()
                ));
            };
            body_column[b] = interior + d * k;
        }

        let (mut mass, mut free) = (vec![0.0; columns], vec![0.0; columns]);
        let mut column_position = vec![[0.0; 3]; columns];
        for &b in &interior_bodies {
            let (from, to) = (b * d, body_column[b]);
            mass[to..to + d].copy_from_slice(&program.mass[from..from + d]);
            free[to..to + d].copy_from_slice(&program.free[from..from + d]);
            column_position[to..to + d].copy_from_slice(&program.column_position[from..from + d]);
        }
        for (k, r) in records.iter().enumerate() {
            let to = interior + d * k;
            mass[to..to + d].copy_from_slice(&r[1..1 + d]);
            free[to..to + d].copy_from_slice(&r[1 + d..1 + 2 * d]);
            column_position[to..to + d].fill([r[1 + 2 * d], r[2 + 2 * d], r[3 + 2 * d]]);
        }

        // A's columns renumbered; two bodies of one grain (a grain and its
        // periodic copy on the same rank) add into the same column.
        let a = &program.a_matrix;
        let mut entries: Vec<(usize, usize, f64)> = Vec::with_capacity(a.nzval.len());
        for c in 0..a.n {
            let to = body_column[c / d] + c % d;
            for k in a.colptr[c]..a.colptr[c + 1] {
                entries.push((to, a.rowval[k], a.nzval[k]));
            }
        }
        entries.sort_unstable_by_key(|&(c, r, _)| (c, r));
        let mut colptr = vec![0usize; columns + 1];
        let (mut rowval, mut nzval): (Vec<usize>, Vec<f64>) = (Vec::new(), Vec::new());
        let mut last = (usize::MAX, usize::MAX);
        for (c, r, v) in entries {
            if (c, r) == last {
                *nzval.last_mut().expect("an entry before") += v;
                continue;
            }
            last = (c, r);
            colptr[c + 1] += 1;
            rowval.push(r);
            nzval.push(v);
        }
        for c in 0..columns {
            colptr[c + 1] += colptr[c];
        }
        let a_matrix = CscMatrix::new(a.m, columns, colptr, rowval, nzval);
        Ok(SharedProgram {
            program: program.with_columns(mass, free, a_matrix, column_position),
            interior,
            body_column,
        })
    }

    /// The solution's unknowns in the layout of the rank's own program.
    pub fn local_unknowns(&self, x: &[f64], d: usize) -> Vec<f64> {
        let mut local = vec![0.0; d * self.body_column.len()];
        for (b, &c) in self.body_column.iter().enumerate() {
            local[b * d..(b + 1) * d].copy_from_slice(&x[c..c + d]);
        }
        local
    }
}

/// Where a rank's columns and rows stand in the program gathered from
/// every rank ([`SharedProgram::gathered`]).
pub struct GatheredLayout {
    /// First column of the rank's interior, its length, and the first
    /// column of the separator.
    interior_start: usize,
    interior: usize,
    separator_start: usize,
    /// Row of the gathered program of each of the rank's rows.
    rows: Vec<usize>,
}

impl GatheredLayout {
    /// The rank's part of the gathered program's solution: x over its
    /// interior then the separator, z over its rows.
    pub fn rank_part(&self, x: &[f64], z: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut own = x[self.interior_start..self.interior_start + self.interior].to_vec();
        own.extend_from_slice(&x[self.separator_start..]);
        (own, self.rows.iter().map(|&r| z[r]).collect())
    }
}

impl SharedProgram {
    /// The whole program, every rank's rows and interior with the
    /// separator, on every rank (collective): the ranks' interiors in rank
    /// order then the separator; the ranks' linear rows in rank order, then
    /// their cones. For Clarabel, which factorises it whole.
    pub fn gathered(&self, communicator: &Communicator) -> (ConicProgram, GatheredLayout) {
        let own = &self.program;
        let (ni, a) = (self.interior, &own.a_matrix);
        // The rank's message: its sizes, interior masses and free
        // velocities, b, then A's entries as (row, column, value).
        let mut message = vec![
            ni as f64,
            own.linear_rows as f64,
            own.cone_count as f64,
            a.nzval.len() as f64,
        ];
        message.extend_from_slice(&own.mass[..ni]);
        message.extend_from_slice(&own.free[..ni]);
        message.extend_from_slice(&own.b);
        for c in 0..a.n {
            for k in a.colptr[c]..a.colptr[c + 1] {
                message.extend([a.rowval[k] as f64, c as f64, a.nzval[k]]);
            }
        }
        let received = communicator.exchange(vec![message; communicator.size()]);
        let sizes: Vec<[usize; 4]> = received
            .iter()
            .map(|m| [0, 1, 2, 3].map(|k| m[k] as usize))
            .collect();
        let total = |k: usize| sizes.iter().map(|s| s[k]).sum::<usize>();
        let (interiors, linear, cones) = (total(0), total(1), total(2));
        let separator = own.mass.len() - ni;
        let columns = interiors + separator;
        let rows = linear + 3 * cones;
        let (mut mass, mut free, mut b) =
            (Vec::with_capacity(columns), Vec::new(), vec![0.0; rows]);
        let mut entries: Vec<(usize, usize, f64)> = Vec::new();
        let (mut column_start, mut linear_start, mut cone_start) = (0, 0, 0);
        let mut layout = None;
        for (rank, (message, &[n_i, n_linear, n_cones, nnz])) in
            received.iter().zip(&sizes).enumerate()
        {
            let row_of = |r: usize| {
                if r < n_linear {
                    linear_start + r
                } else {
                    linear + 3 * cone_start + (r - n_linear)
                }
            };
            let column_of = |c: usize| {
                if c < n_i {
                    column_start + c
                } else {
                    interiors + (c - n_i)
                }
            };
            let n_rows = n_linear + 3 * n_cones;
            let body = &message[4..];
            mass.extend_from_slice(&body[..n_i]);
            free.extend_from_slice(&body[n_i..2 * n_i]);
            for (r, &value) in body[2 * n_i..2 * n_i + n_rows].iter().enumerate() {
                b[row_of(r)] = value;
            }
            for e in body[2 * n_i + n_rows..].chunks_exact(3).take(nnz) {
                entries.push((column_of(e[1] as usize), row_of(e[0] as usize), e[2]));
            }
            if rank == communicator.rank() {
                layout = Some(GatheredLayout {
                    interior_start: column_start,
                    interior: n_i,
                    separator_start: interiors,
                    rows: (0..n_rows).map(row_of).collect(),
                });
            }
            column_start += n_i;
            linear_start += n_linear;
            cone_start += n_cones;
        }
        mass.extend_from_slice(&own.mass[ni..]);
        free.extend_from_slice(&own.free[ni..]);
        entries.sort_unstable_by_key(|&(c, r, _)| (c, r));
        let colptr = crate::csc::column_pointers(columns, entries.iter().map(|e| e.0));
        let rowval = entries.iter().map(|e| e.1).collect();
        let nzval = entries.iter().map(|e| e.2).collect();
        let a_matrix = CscMatrix::new(rows, columns, colptr, rowval, nzval);
        let whole = own.gathered((mass, free), a_matrix, b, (linear, cones));
        (
            whole,
            layout.expect("this rank's message among the gathered"),
        )
    }
}
