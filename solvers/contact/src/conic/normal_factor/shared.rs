//! The normal matrix factorised by several ranks together
//! ([`crate::shared_program`]).
//!
//! On rank r the unknowns read [x_I; x_S]: its interior I_r, which only its
//! rows reach, and the separator S, held by every rank. The whole matrix
//! is K = P + Σ_r A_rᵀΘ_rA_r, and its interior blocks are the ranks' own:
//!
//!   K = [K_11 0 … K_1S; 0 K_22 … K_2S; … ; K_S1 K_S2 … K_SS].
//!
//! Each rank assembles its part over its interior and the columns of S its
//! rows reach (its "touched" separator, S_r), and factorises its interior with S_r
//! last, up to S_r ([`super::interior`]). On S_r's diagonal
//! it puts the whole matrix's diagonal, D_S (P and every rank's rows,
//! summed over the ranks at each factorisation): its matrix
//! M_r = [K_rr K_rS; K_Sr K_SS^r + E_r], E_r = D_S − diag(K_SS^r), is then
//! as well conditioned as K. With the mass alone there, a rank's part held
//! by contacts much stiffer than the masses lost its positive pivots to
//! round-off near the solution (a packing of 1,600 spheres slumping on 2
//! ranks at ε = 1e-9: 3 of 10 steps left to Clarabel, none with D_S, none
//! on one rank). S_r's columns are left holding
//! T_r = K_SS^r + E_r − K_Sr K_rr⁻¹ K_rS, and the Schur complement of the
//! whole matrix is
//!
//!   Σ = P_S + Σ_r (T_r − P_{S_r} − E_r),
//!
//! dense over S: each rank adds its part, the ranks sum them (the lower
//! triangle reduced in place, block column by block column, at each
//! factorisation), and the ranks factorise Σ together, each a share of
//! its column blocks ([`super::shared_schur`]), every rank ending with the
//! whole factor.
//! A solve K x = r is that of the split: per rank
//! the forward solve, one reduction of the separator's right-hand side,
//! x_S from Σ on every rank, and per rank the back solve of its interior.

use super::shared_schur::{factorise_together, sum_together, Workspace};
use super::split::Half;
use super::*;
use grainflow_core::Communicator;

/// The factor of the normal matrix shared among ranks.
pub(crate) struct SharedFactor {
    /// Interior columns (the separator's follow, `mass.len()` of them).
    interior: usize,
    /// The rank's interior with its touched separator; None where the rank
    /// has no interior.
    half: Option<Half>,
    /// Separator columns (0-based within S) the rank's rows reach, in
    /// order.
    touched: Vec<usize>,
    /// Where the rank has no interior: (row, column) within `touched` and
    /// the entry of the matrix of each of its K_SS^r values (upper).
    touched_entries: Vec<(usize, usize, usize)>,
    /// Entry of the matrix of each touched column's diagonal, and E_r.
    touched_diagonal: Vec<usize>,
    shift: Vec<f64>,
    /// P on the separator.
    mass: Vec<f64>,
    /// Σ (its lower triangle): the rank's part, then the sum, then L.
    schur: Mat<f64>,
    dense_work: Workspace,
    communicator: Communicator,
}

impl SharedFactor {
    /// The factor of `matrix` (upper triangle over [x_I; x_S], `interior`
    /// columns first), `mass`: P of every column, `positions`: the body of
    /// each (a large interior may be ordered by planes through them).
    pub(super) fn new(
        matrix: &CscMatrix<f64>,
        interior: usize,
        mass: &[f64],
        positions: &[[f64; 3]],
        communicator: &Communicator,
    ) -> Result<Self, String> {
        let n = matrix.n;
        let ns = n - interior;
        // The separator's columns reached by an entry off their diagonal
        // (a column with its mass alone couples to nothing here).
        let mut reached = vec![false; ns];
        for column in 0..n {
            for k in matrix.colptr[column]..matrix.colptr[column + 1] {
                let row = matrix.rowval[k];
                if row != column {
                    for u in [row, column] {
                        if u >= interior {
                            reached[u - interior] = true;
                        }
                    }
                }
            }
        }
        let touched: Vec<usize> = (0..ns).filter(|&k| reached[k]).collect();
        let touched_columns: Vec<usize> = touched.iter().map(|&k| interior + k).collect();
        let (half, touched_entries) = if interior > 0 {
            let own: Vec<usize> = (0..interior).collect();
            // The rank's interior on the threads of its pool (faer runs the
            // dense blocks of each supernode there, in the same order).
            let threads = rayon::current_num_threads();
            let par = if threads > 1 {
                Par::rayon(threads)
            } else {
                Par::Seq
            };
            let positions = (positions.len() == n).then_some(positions);
            let half = Half::new(matrix, &own, &touched_columns, positions, par)?;
            (Some(half), Vec::new())
        } else {
            let mut position = vec![usize::MAX; n];
            for (t, &u) in touched_columns.iter().enumerate() {
                position[u] = t;
            }
            let mut entries = Vec::new();
            for column in 0..n {
                for k in matrix.colptr[column]..matrix.colptr[column + 1] {
                    let (r, c) = (position[matrix.rowval[k]], position[column]);
                    if r != usize::MAX && c != usize::MAX {
                        entries.push((r, c, k));
                    }
                }
            }
            (None, entries)
        };
        let dense_work = Workspace::new(ns);
        // The diagonal closes its column of the upper triangle.
        let touched_diagonal: Vec<usize> = touched_columns
            .iter()
            .map(|&u| matrix.colptr[u + 1] - 1)
            .collect();
        Ok(SharedFactor {
            interior,
            half,
            shift: vec![0.0; touched.len()],
            touched,
            touched_entries,
            touched_diagonal,
            mass: mass[interior..].to_vec(),
            schur: Mat::zeros(ns, ns),
            dense_work,
            communicator: communicator.clone(),
        })
    }

    /// Factorises `matrix` (the pattern given to `new`), with the other
    /// ranks (collective: a failure on any rank fails them all).
    pub(super) fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        let ns = self.mass.len();
        // D_S, the whole matrix's diagonal on S, and this rank's E_r.
        let mut diagonal = vec![0.0; ns];
        for (&i, &k) in self.touched.iter().zip(&self.touched_diagonal) {
            diagonal[i] = matrix.nzval[k] - self.mass[i];
        }
        self.communicator.sum_each(&mut diagonal);
        for (t, (&i, &k)) in self.touched.iter().zip(&self.touched_diagonal).enumerate() {
            self.shift[t] = diagonal[i] + self.mass[i] - matrix.nzval[k];
        }
        // This rank's part of Σ: T_r − P − E_r over its touched separator
        // (K_SS^r − P where it has no interior), in Σ's lower triangle. The
        // interior's factor hands T_r over entry by entry, so that no rank
        // holds a second dense copy of it.
        for j in 0..ns {
            self.schur.col_as_slice_mut(j)[j..].fill(0.0);
        }
        let (touched, schur) = (&self.touched, &mut self.schur);
        let own = match &mut self.half {
            Some(half) => half.factorise_into(matrix, &self.shift, |a, b, t| {
                schur[(touched[a], touched[b])] += t;
            }),
            None => {
                for &(r, c, k) in &self.touched_entries {
                    let (i, j) = (touched[r.max(c)], touched[r.min(c)]);
                    schur[(i, j)] += matrix.nzval[k];
                }
                Ok(())
            }
        };
        let failed_here = own.is_err();
        if self.communicator.any(failed_here) {
            return Err(own.err().unwrap_or_else(|| {
                "the normal matrix is not positive definite on another rank".into()
            }));
        }
        let touched = &self.touched;
        for (t, &i) in touched.iter().enumerate() {
            let shift = if self.half.is_some() {
                self.shift[t]
            } else {
                0.0
            };
            self.schur[(i, i)] -= self.mass[i] + shift;
        }
        sum_together(&mut self.schur, &self.communicator, &mut self.dense_work);
        for j in 0..ns {
            self.schur[(j, j)] += self.mass[j];
        }
        // Every rank holds the same Σ; each factorises its share of it.
        factorise_together(&mut self.schur, &self.communicator, &mut self.dense_work)
    }

    /// Overwrites `rhs` ([r_I; r_S], r_S the same on every rank) with
    /// K⁻¹ rhs (collective).
    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let (interior, ns) = (self.interior, self.mass.len());
        // 1. −K_Sr K_rr⁻¹ r_r on the touched separator, summed over ranks.
        let mut right = vec![0.0; ns];
        if let Some(half) = &mut self.half {
            for (&i, value) in self.touched.iter().zip(half.forward(rhs)) {
                right[i] = value;
            }
        }
        self.communicator.sum_each(&mut right);
        // 2. x_S = Σ⁻¹ (r_S − Σ_r K_Sr K_rr⁻¹ r_r), on every rank.
        let mut x_s = Mat::<f64>::zeros(ns, 1);
        for k in 0..ns {
            x_s[(k, 0)] = rhs[interior + k] + right[k];
        }
        solve_schur(&self.schur, &mut x_s);
        // 3. The interior's back solve with x_S on the touched separator.
        if let Some(half) = &mut self.half {
            let mut x_touched = Mat::<f64>::zeros(self.touched.len(), 1);
            for (t, &i) in self.touched.iter().enumerate() {
                x_touched[(t, 0)] = x_s[(i, 0)];
            }
            let x_i = half.backward(x_touched.as_ref());
            for (&u, value) in half.unknown.iter().zip(x_i) {
                rhs[u] = value;
            }
        }
        for k in 0..ns {
            rhs[interior + k] = x_s[(k, 0)];
        }
    }
}
