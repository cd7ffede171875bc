//! The cone rows of a 3D program's A held as one dense block per contact
//! instead of stored entries: what the projected gradient's products read
//! each iteration.
//!
//! A contact's three rows (the normal and the two tangents, eq. 13) reach
//! the six unknowns (v, ω) of each of its one or two spheres. On the first
//! sphere (the lower column) the rows hold e and the lever term
//! −(l/L) n × e, on the second −e and its own lever term, e ∈ {n, μt₁, μt₂}
//! scaled. Stored as entries, a pair's rows take 36 values and 36 indices,
//! read twice an iteration (in rows for A x, in columns for Aᵀ z); as a
//! block, the 9 translation values (the second sphere's are their
//! negatives, exactly) and the 9 + 9 lever values, and the two spheres.
//! The products sum each output's terms in the order the stored entries
//! have them (a row's columns ascending; a column's rows ascending, the
//! linear rows first), so that both forms give the same bits.

use rayon::prelude::*;

/// Unknowns of a sphere: (v, ω).
const DOFS: usize = 6;
/// No second sphere (a contact with a wall or a fixed grain).
const NONE: u32 = u32::MAX;
/// Outputs shorter than this are summed on one thread.
const PARALLEL: usize = 20_000;

/// Cone rows `first_row..first_row + 3 × count` of A as blocks.
pub(super) struct ConeBlocks {
    first_row: usize,
    /// Each contact's spheres, the lower first ([`NONE`] for no second).
    spheres: Vec<[u32; 2]>,
    /// Row k's translation coefficients on the first sphere, at 3k..3k + 3.
    translation: Vec<[f64; 9]>,
    /// Row k's rotation coefficients on the first and second spheres.
    rotation: Vec<[[f64; 9]; 2]>,
    /// Each sphere's contacts, ascending, as 2 × contact + side.
    sphere_start: Vec<usize>,
    sphere_contact: Vec<u32>,
}

impl ConeBlocks {
    /// The blocks of the cone rows from A's rows (`row_start`,
    /// `row_column`, `row_value`, columns ascending in each row) over
    /// `columns` unknowns, or `None` where a cone's rows do not have the
    /// pattern above (then the stored entries serve).
    pub fn from_rows(
        (row_start, row_column, row_value): (&[usize], &[u32], &[f64]),
        first_row: usize,
        columns: usize,
    ) -> Option<Self> {
        let rows = row_start.len() - 1;
        if !columns.is_multiple_of(DOFS)
            || !(rows - first_row).is_multiple_of(3)
            || columns / DOFS >= NONE as usize
        {
            return None;
        }
        let count = (rows - first_row) / 3;
        let mut blocks = ConeBlocks {
            first_row,
            spheres: Vec::with_capacity(count),
            translation: Vec::with_capacity(count),
            rotation: Vec::with_capacity(count),
            sphere_start: Vec::new(),
            sphere_contact: Vec::new(),
        };
        for c in 0..count {
            let r = first_row + 3 * c;
            let entries = row_start[r + 1] - row_start[r];
            if entries != DOFS && entries != 2 * DOFS {
                return None;
            }
            let first = row_column[row_start[r]] as usize;
            let second = (entries == 2 * DOFS).then(|| row_column[row_start[r] + DOFS] as usize);
            let mut translation = [0.0; 9];
            let mut rotation = [[0.0; 9]; 2];
            for k in 0..3 {
                let start = row_start[r + k];
                if row_start[r + k + 1] - start != entries {
                    return None;
                }
                for (side, base) in [Some(first), second].into_iter().enumerate() {
                    let Some(base) = base else { continue };
                    if base % DOFS != 0 {
                        return None;
                    }
                    for j in 0..DOFS {
                        let at = start + side * DOFS + j;
                        if row_column[at] as usize != base + j {
                            return None;
                        }
                        let value = row_value[at];
                        match (j < 3, side) {
                            (true, 0) => translation[3 * k + j] = value,
                            // The second sphere's translation: the first's negated.
                            (true, _) if value.to_bits() != (-translation[3 * k + j]).to_bits() => {
                                return None
                            }
                            (true, _) => {}
                            (false, _) => rotation[side][3 * k + j - 3] = value,
                        }
                    }
                }
            }
            blocks.spheres.push([
                (first / DOFS) as u32,
                second.map_or(NONE, |s| (s / DOFS) as u32),
            ]);
            blocks.translation.push(translation);
            blocks.rotation.push(rotation);
        }
        // Each sphere's contacts in ascending order (counting sort).
        let spheres = columns / DOFS;
        let mut start = vec![0usize; spheres + 1];
        for pair in &blocks.spheres {
            for &s in pair.iter().filter(|&&s| s != NONE) {
                start[s as usize + 1] += 1;
            }
        }
        for s in 0..spheres {
            start[s + 1] += start[s];
        }
        let mut next = start.clone();
        let mut contact = vec![0u32; start[spheres]];
        for (c, pair) in blocks.spheres.iter().enumerate() {
            for (side, &s) in pair.iter().enumerate().filter(|(_, &s)| s != NONE) {
                contact[next[s as usize]] = (2 * c + side) as u32;
                next[s as usize] += 1;
            }
        }
        blocks.sphere_start = start;
        blocks.sphere_contact = contact;
        Some(blocks)
    }

    /// The cone rows of A x into `out` (those rows only).
    pub fn times(&self, x: &[f64], out: &mut [f64]) {
        let zero = empty_sum();
        let cone = |(c, out): (usize, &mut [f64])| {
            let [first, second] = self.spheres[c];
            let (t, [r1, r2]) = (&self.translation[c], &self.rotation[c]);
            let x1: &[f64; DOFS] = x[first as usize * DOFS..][..DOFS].try_into().unwrap();
            let mut row = [zero; 3];
            for (k, sum) in row.iter_mut().enumerate() {
                for j in 0..3 {
                    *sum += t[3 * k + j] * x1[j];
                }
                for j in 0..3 {
                    *sum += r1[3 * k + j] * x1[3 + j];
                }
            }
            if second != NONE {
                let x2: &[f64; DOFS] = x[second as usize * DOFS..][..DOFS].try_into().unwrap();
                for (k, sum) in row.iter_mut().enumerate() {
                    for j in 0..3 {
                        *sum += -t[3 * k + j] * x2[j];
                    }
                    for j in 0..3 {
                        *sum += r2[3 * k + j] * x2[3 + j];
                    }
                }
            }
            out.copy_from_slice(&row);
        };
        let out = &mut out[self.first_row..];
        if out.len() < PARALLEL {
            out.chunks_exact_mut(3).enumerate().for_each(cone);
        } else {
            out.par_chunks_exact_mut(3)
                .enumerate()
                .with_min_len(256)
                .for_each(cone);
        }
    }

    /// Aᵀz into `out`: each unknown's terms of the linear rows (`linear`:
    /// their entries by column, rows ascending) and then of the cones, in
    /// one sum.
    pub fn transpose_times(
        &self,
        z: &[f64],
        out: &mut [f64],
        (column_start, column_row, column_value): (&[usize], &[u32], &[f64]),
    ) {
        let zero = empty_sum();
        let sphere = |(s, out): (usize, &mut [f64])| {
            let mut sum = [zero; DOFS];
            for (j, sum) in sum.iter_mut().enumerate() {
                let column = s * DOFS + j;
                for e in column_start[column]..column_start[column + 1] {
                    *sum += column_value[e] * z[column_row[e] as usize];
                }
            }
            for &entry in &self.sphere_contact[self.sphere_start[s]..self.sphere_start[s + 1]] {
                let (c, side) = ((entry / 2) as usize, (entry % 2) as usize);
                let z: &[f64; 3] = z[self.first_row + 3 * c..][..3].try_into().unwrap();
                let (t, rotation) = (&self.translation[c], &self.rotation[c][side]);
                let sign = if side == 0 { 1.0 } else { -1.0 };
                for k in 0..3 {
                    for j in 0..3 {
                        sum[j] += (sign * t[3 * k + j]) * z[k];
                    }
                    for j in 0..3 {
                        sum[3 + j] += rotation[3 * k + j] * z[k];
                    }
                }
            }
            out.copy_from_slice(&sum);
        };
        if out.len() < PARALLEL {
            out.chunks_exact_mut(DOFS).enumerate().for_each(sphere);
        } else {
            out.par_chunks_exact_mut(DOFS)
                .enumerate()
                .with_min_len(64)
                .for_each(sphere);
        }
    }
}

/// The value a sum of no terms has (`Iterator::sum` starts from it): the
/// stored entries' products sum through it, and these start where they do.
fn empty_sum() -> f64 {
    std::iter::empty::<f64>().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A's rows for contacts (first, second sphere or none) with linear
    /// rows first: (row_start, row_column, row_value), the linear rows'
    /// entries by column (column_start, column_row, column_value), rows.
    #[allow(clippy::type_complexity)]
    fn program(
        linear: &[(usize, f64)],
        contacts: &[(usize, Option<usize>)],
        spheres: usize,
    ) -> (
        (Vec<usize>, Vec<u32>, Vec<f64>),
        (Vec<usize>, Vec<u32>, Vec<f64>),
    ) {
        let value = |a: usize, k: usize, j: usize| -> f64 {
            // Irrational-looking coefficients of both signs, and the normal
            // row's exact zeros on the levers.
            if k == 0 && j >= 3 {
                0.0
            } else {
                ((a * 31 + k * 7 + j) as f64 * 0.7390851).sin()
            }
        };
        let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
        for &(column, v) in linear {
            rows.push(vec![(column, v)]);
        }
        for (a, &(first, second)) in contacts.iter().enumerate() {
            for k in 0..3 {
                let mut row = Vec::new();
                let sides = [Some(first), second];
                let mut order: Vec<(usize, usize)> = sides
                    .iter()
                    .enumerate()
                    .filter_map(|(s, b)| b.map(|b| (b, s)))
                    .collect();
                order.sort();
                for (sphere, side) in order {
                    for j in 0..DOFS {
                        let v = value(a, k, j);
                        let v = match (j < 3, side) {
                            (true, 1) => -v,
                            (false, 1) => v * 1.3,
                            _ => v,
                        };
                        row.push((sphere * DOFS + j, v));
                    }
                }
                rows.push(row);
            }
        }
        let mut row_start = vec![0];
        let (mut row_column, mut row_value) = (Vec::new(), Vec::new());
        for row in &rows {
            for &(c, v) in row {
                row_column.push(c as u32);
                row_value.push(v);
            }
            row_start.push(row_column.len());
        }
        let columns = spheres * DOFS;
        let mut column_start = vec![0];
        let (mut column_row, mut column_value) = (Vec::new(), Vec::new());
        for c in 0..columns {
            for (r, row) in rows.iter().enumerate().take(linear.len()) {
                for &(column, v) in row {
                    if column == c {
                        column_row.push(r as u32);
                        column_value.push(v);
                    }
                }
            }
            column_start.push(column_row.len());
        }
        (
            (row_start, row_column, row_value),
            (column_start, column_row, column_value),
        )
    }

    #[test]
    fn the_blocks_give_the_stored_entries_products_bit_for_bit() {
        // Spheres 0..4; pairs in both orders of their columns, a wall
        // contact, and two linear rows (frictionless walls).
        let contacts = [
            (0, Some(1)),
            (2, Some(1)),
            (3, None),
            (1, Some(3)),
            (0, None),
        ];
        let linear = [(2 * DOFS + 2, 0.37), (3 * DOFS + 1, -1.1)];
        let spheres = 4;
        let ((row_start, row_column, row_value), columns) = program(&linear, &contacts, spheres);
        // The second contact lists sphere 2 first: its lower column's sphere
        // carries the negated translation, as a program's rows do where
        // body j has the lower index.
        let blocks =
            ConeBlocks::from_rows((&row_start, &row_column, &row_value), 2, spheres * DOFS)
                .expect("the cone rows have the block pattern");
        let rows = row_start.len() - 1;
        let x: Vec<f64> = (0..spheres * DOFS)
            .map(|i| (i as f64 * 1.618).cos())
            .collect();
        let z: Vec<f64> = (0..rows).map(|i| (i as f64 * 2.5).sin()).collect();
        let stored: Vec<f64> = (0..rows)
            .map(|r| {
                (row_start[r]..row_start[r + 1])
                    .map(|k| row_value[k] * x[row_column[k] as usize])
                    .sum()
            })
            .collect();
        let mut out = vec![f64::NAN; rows];
        out[..2].copy_from_slice(&stored[..2]);
        blocks.times(&x, &mut out);
        for r in 0..rows {
            assert_eq!(out[r].to_bits(), stored[r].to_bits(), "row {r}");
        }
        // Aᵀz against the whole matrix's columns (rows ascending).
        let (row_start, row_column, row_value) = (&row_start, &row_column, &row_value);
        let transposed: Vec<f64> = (0..spheres * DOFS)
            .map(|c| {
                (0..rows)
                    .flat_map(move |r| {
                        (row_start[r]..row_start[r + 1])
                            .filter(move |&k| row_column[k] as usize == c)
                            .map(move |k| (r, k))
                    })
                    .map(|(r, k)| row_value[k] * z[r])
                    .sum()
            })
            .collect();
        let mut out = vec![f64::NAN; spheres * DOFS];
        blocks.transpose_times(&z, &mut out, (&columns.0, &columns.1, &columns.2));
        for c in 0..spheres * DOFS {
            assert_eq!(out[c].to_bits(), transposed[c].to_bits(), "column {c}");
        }
    }

    #[test]
    fn rows_off_the_block_pattern_keep_the_stored_entries() {
        let ((row_start, row_column, mut row_value), _) = program(&[], &[(0, Some(1))], 2);
        assert!(ConeBlocks::from_rows((&row_start, &row_column, &row_value), 0, 12).is_some());
        // The second sphere's translation no longer the first's negated.
        row_value[DOFS + 1] *= 1.5;
        assert!(ConeBlocks::from_rows((&row_start, &row_column, &row_value), 0, 12).is_none());
        // Discs: three unknowns a body.
        assert!(ConeBlocks::from_rows((&row_start, &row_column, &row_value), 0, 9).is_none());
    }
}
