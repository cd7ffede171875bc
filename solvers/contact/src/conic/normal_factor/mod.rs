//! The Cholesky factor of the interior point's normal matrix
//! K = P + AᵀΘA (SPD, three unknowns per disc, the contact graph's
//! pattern), refactorised at every iteration with the same pattern.
//!
//! Small programs are factorised whole: one sparse Cholesky (faer) in the
//! order the interior point gave the unknowns (AMD). Large ones that no
//! small separator splits (3D packings, whose separators are slices of
//! grains) are factorised whole too, in nested-dissection order
//! ([`crate::dissection`]), faer running the dense blocks on the threads.
//!
//! Large ones (2D packings) are split in two by a separator S of the matrix graph (a
//! level of a breadth-first search from a peripheral unknown, cut at half
//! the unknowns): K = [K₁₁ 0 K₁S; 0 K₂₂ K₂S; K_S1 K_S2 K_SS]. Each side
//! i = 1, 2 factorises its own matrix M_i = [K_ii K_iS; K_Si K_SS] (a
//! principal submatrix, hence SPD) with S ordered last, up to S
//! ([`interior`]): L(M_i) = [L_ii 0; L_Si ·], and S's columns are left
//! holding T_i = K_SS − L_Si L_Siᵀ = K_SS − K_Si K_ii⁻¹ K_iS, on its own
//! thread. The Schur complement of the whole matrix is
//!
//!   Σ = K_SS − K_S1 K₁₁⁻¹ K₁S − K_S2 K₂₂⁻¹ K₂S = T₁ + T₂ − K_SS,
//!
//! dense and of the separator's size, factorised by a dense Cholesky. A
//! solve K x = r then reads
//!
//! 1. per side, w_i = L_ii⁻¹ r_i, and K_Si K_ii⁻¹ r_i = L_Si w_i;
//! 2. x_S = Σ⁻¹ (r_S − Σ_i K_Si K_ii⁻¹ r_i);
//! 3. per side, x_i = L_ii⁻ᵀ (w_i − L_Siᵀ x_S) (= K_ii⁻¹ (r_i − K_iS x_S)).
//!
//! Each side is sequential, and the two sides' arithmetic does not depend
//! on which thread runs it: results are the same on any number of
//! threads, and two threads share the work.
//!
//! On several MPI ranks the same algebra runs with one side per rank and
//! the separator the grains whose columns stand on two ranks
//! ([`shared`]): each rank factorises its side, the ranks sum their parts
//! of Σ.

use clarabel::algebra::CscMatrix;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, Par, Side};

mod interior;
mod shared;
mod shared_schur;
mod split;
#[cfg(test)]
mod tests;

use shared::SharedFactor;
use split::SplitFactor;

/// Unknowns from which a matrix is split in two. On two threads the split
/// took a 2D packing's step from 0.45 to 0.32 s at 24,000 unknowns and
/// from 6.0 to 3.9 s at 150,000. A matrix this large that is not split (a
/// 3D packing) is ordered by nested dissection: from about this size it
/// fills less than AMD (a 16³ lattice of spheres, 24,576 unknowns: 22.3e6
/// entries against 41.4e6; a spread 3D heap of 16,200 unknowns: 9.6e6
/// against AMD's 7.5e6).
const SPLIT_FROM_UNKNOWNS: usize = 20_000;

/// In 2D the split is faster on one thread too from a few thousand
/// unknowns: its halves, each in AMD's order, fill less than the whole in
/// it. On one thread, split against whole (supernodal): a step of the
/// compact 2D packings of `scripts/bench/cocd_step.py` at rest 1.08,
/// 1.10, 1.14 and 1.10 times faster at 2,000, 5,000, 8,000 and 20,000
/// discs; whole runs of the 8 mm and 4 mm erodible beds (3,960 and 14,088
/// unknowns, long strips) 1.13 and 1.18; but a box of 400 discs and a
/// column of 410 (1,200 unknowns) 0.91 and 0.87. In 3D the whole factor
/// stays ahead below [`SPLIT_FROM_UNKNOWNS`] (the static box of 1,600
/// spheres and a column of 2,100: 0.96 split).
const SPLIT_FROM_UNKNOWNS_2D: usize = 3_000;

/// Unknowns from which a matrix of a 2D or 3D program is split.
fn split_from(three_dimensional: bool) -> usize {
    if three_dimensional {
        SPLIT_FROM_UNKNOWNS
    } else {
        SPLIT_FROM_UNKNOWNS_2D
    }
}

/// Largest separator worth splitting at, as a fraction of the unknowns
/// and in unknowns: its dense Schur complement costs about ns³ flops per
/// factorisation (a 2D packing's grows as √n: 177 unknowns at 24,000,
/// 432 at 150,000).
const LARGEST_SEPARATOR_FRACTION: f64 = 0.02;
const LARGEST_SEPARATOR: usize = 1_500;

/// Whether a normal matrix of `unknowns` is factorised whole, so that the
/// interior point assembles it in a fill-reducing order once per step
/// (larger ones are split, and each half orders its own interior).
pub(crate) fn is_factorised_whole(unknowns: usize, three_dimensional: bool) -> bool {
    unknowns < split_from(three_dimensional)
}

/// faer's view of the upper-triangle pattern of a CSC matrix.
fn symbolic_pattern(matrix: &CscMatrix<f64>) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(matrix.n, matrix.n, &matrix.colptr, None, &matrix.rowval)
}

fn no_regularisation() -> LltRegularization<f64> {
    LltRegularization {
        dynamic_regularization_delta: 0.0,
        dynamic_regularization_epsilon: 0.0,
    }
}

/// A dense symmetric block = LLᵀ in place (L in the lower triangle): the
/// separator's Schur complement Σ, or a diagonal block of it
/// ([`shared_schur`]).
fn factorise_schur(schur: MatMut<'_, f64>, work: &mut MemBuffer) -> Result<(), String> {
    faer::linalg::cholesky::llt::factor::cholesky_in_place(
        schur,
        no_regularisation(),
        Par::Seq,
        MemStack::new(work),
        Default::default(),
    )
    .map(|_| ())
    .map_err(|e| format!("the separator's Schur complement is not positive definite: {e:?}"))
}

/// x ← Σ⁻¹ x with the factor of [`factorise_schur`].
fn solve_schur(schur: &Mat<f64>, x: &mut Mat<f64>) {
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        schur.as_ref(),
        x.as_mut(),
        Par::Seq,
    );
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(
        schur.transpose(),
        x.as_mut(),
        Par::Seq,
    );
}

/// The numeric factorisation of `matrix` into `values`, sequential.
fn factorise_numeric(
    symbolic: &SymbolicCholesky<usize>,
    values: &mut [f64],
    work: &mut MemBuffer,
    matrix: &CscMatrix<f64>,
    par: Par,
) -> Result<(), String> {
    symbolic
        .factorize_numeric_llt(
            values,
            SparseColMatRef::new(symbolic_pattern(matrix), &matrix.nzval),
            Side::Upper,
            no_regularisation(),
            par,
            MemStack::new(work),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| format!("the normal matrix is not positive definite: {e:?}"))
}

/// The factor of K, whole, split, or shared among ranks.
pub(crate) enum NormalFactor {
    Whole(Box<WholeFactor>),
    Split(Box<SplitFactor>),
    Shared(Box<SharedFactor>),
}

impl NormalFactor {
    /// Ordering and symbolic analysis for the pattern of `matrix` (upper
    /// triangle, CSC). `ordered`: its unknowns are already in a
    /// fill-reducing order (see [`is_factorised_whole`]); otherwise a
    /// whole factor orders them by nested dissection (by planes through
    /// `positions`, each unknown's body, when given) and permutes at each
    /// factorisation.
    pub(crate) fn new(
        matrix: &CscMatrix<f64>,
        ordered: bool,
        positions: &[[f64; 3]],
        three_dimensional: bool,
    ) -> Result<Self, String> {
        Self::with_split_from(matrix, split_from(three_dimensional), ordered, positions)
    }

    /// As `new`, splitting matrices of at least `split_from` unknowns.
    pub(crate) fn with_split_from(
        matrix: &CscMatrix<f64>,
        split_from: usize,
        ordered: bool,
        positions: &[[f64; 3]],
    ) -> Result<Self, String> {
        if matrix.n >= split_from {
            if let Some(split) = SplitFactor::new(matrix)? {
                return Ok(NormalFactor::Split(Box::new(split)));
            }
        }
        Ok(NormalFactor::Whole(Box::new(WholeFactor::new(
            matrix, ordered, positions,
        )?)))
    }

    /// The factor shared among the ranks of `communicator`: `matrix` over
    /// the rank's `interior` columns then the separator's, `mass` the
    /// diagonal P of every column ([`shared`]; collective).
    pub(crate) fn shared(
        matrix: &CscMatrix<f64>,
        interior: usize,
        mass: &[f64],
        positions: &[[f64; 3]],
        communicator: &grainflow_core::Communicator,
    ) -> Result<Self, String> {
        let shared = SharedFactor::new(matrix, interior, mass, positions, communicator);
        // A rank that cannot build its part fails every rank.
        if communicator.any(shared.is_err()) {
            return Err(shared
                .err()
                .unwrap_or_else(|| "the symbolic factorisation failed on another rank".into()));
        }
        shared.map(|s| NormalFactor::Shared(Box::new(s)))
    }

    /// Factorises `matrix` (the pattern given to `new`).
    pub(crate) fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        match self {
            NormalFactor::Whole(whole) => whole.factorise(matrix),
            NormalFactor::Split(split) => split.factorise(matrix),
            NormalFactor::Shared(shared) => shared.factorise(matrix),
        }
    }

    /// Overwrites `rhs` with K⁻¹ rhs, `matrix` being K as last factorised
    /// (the whole factor refines its solve with it).
    pub(crate) fn solve(&mut self, matrix: &CscMatrix<f64>, rhs: &mut [f64]) {
        match self {
            NormalFactor::Whole(whole) => whole.solve(matrix, rhs),
            NormalFactor::Split(split) => split.solve(rhs),
            NormalFactor::Shared(shared) => shared.solve(rhs),
        }
    }
}

/// Where a whole factor turns supernodal: from about 14 multiply–adds per
/// entry of the factor, 0.35 of faer's default (40), which kept every 2D
/// packing simplicial; the supernodal factor's dense kernels (AVX-512
/// since faer 0.24) win from there. Whole runs on one thread, the two
/// kinds alternated (docs/performance.md, *Moderate 2D packings*): a box
/// of 400 discs at rest (16.5 an entry) 1.28 times faster supernodal, the
/// 4 mm erodible bed factorised whole (22.9) 1.33, but the 8 mm bed whole
/// (11.7) 0.92. Whole factors are now 2D packings below
/// [`SPLIT_FROM_UNKNOWNS_2D`] and 3D ones (hundreds of multiply–adds an
/// entry: supernodal either way).
const SUPERNODAL_FROM: SupernodalThreshold = SupernodalThreshold(0.35);

/// One sparse Cholesky of the whole matrix, in the order given (the
/// interior point numbers its unknowns by AMD) or by nested dissection:
/// symbolic analysis once,
/// numeric factorisations per iteration, on the threads of the pool it
/// is built in. Supernodal or simplicial by the factor's multiply–adds
/// per entry ([`SUPERNODAL_FROM`]).
pub(crate) struct WholeFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    work: MemBuffer,
    par: Par,
    /// The solve's residual, for its refinement.
    residual: Vec<f64>,
}

impl WholeFactor {
    fn new(matrix: &CscMatrix<f64>, ordered: bool, positions: &[[f64; 3]]) -> Result<Self, String> {
        // Below the split's size the interior point has ordered the
        // unknowns by AMD; above it nested dissection, by planes where the
        // bodies' positions are known (see [`crate::dissection`]).
        let dissected = (!ordered).then(|| {
            let positions = (positions.len() == matrix.n).then_some(positions);
            let forward =
                crate::dissection::order(&matrix.colptr, &matrix.rowval, matrix.n, positions);
            let mut inverse = vec![0usize; matrix.n];
            for (new, &old) in forward.iter().enumerate() {
                inverse[old] = new;
            }
            (forward, inverse)
        });
        let ordering = match &dissected {
            None => SymmetricOrdering::Identity,
            Some((forward, inverse)) => SymmetricOrdering::Custom(
                faer::perm::PermRef::new_checked(forward, inverse, matrix.n),
            ),
        };
        let symbolic = factorize_symbolic_cholesky(
            symbolic_pattern(matrix),
            Side::Upper,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SUPERNODAL_FROM,
                ..Default::default()
            },
        )
        .map_err(|e| format!("symbolic factorisation: {e:?}"))?;
        // faer runs the dense blocks of a supernodal factor on the threads
        // (the supernodes in turn): the same arithmetic in the same order,
        // so the factor is the same bit for bit on any number of threads.
        // On the 3D column of 2,700 spheres (16,000 unknowns, not split) 8
        // steps took 41 s against 45 s sequential on two threads.
        let threads = rayon::current_num_threads();
        let par = if threads > 1 {
            Par::rayon(threads)
        } else {
            Par::Seq
        };
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        Ok(WholeFactor {
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            work: MemBuffer::new(scratch),
            par,
            residual: Vec::with_capacity(matrix.n),
        })
    }

    fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        factorise_numeric(
            &self.symbolic,
            &mut self.values,
            &mut self.work,
            matrix,
            self.par,
        )
    }

    /// K⁻¹ rhs, with one step of iterative refinement: x = L⁻ᵀL⁻¹ r, then
    /// x += L⁻ᵀL⁻¹ (r − K x). Late in the interior point K's entries span
    /// twenty orders of magnitude and the factor's solve alone loses digits
    /// the next iterations need: without the step, a heap of 100 spheres
    /// at μ = 0.9 (`tests/cones_3d.rs`) wandered from iteration 13 on and
    /// lost a pivot at 19 with the supernodal kernels of faer 0.24.
    /// `matrix` is K, the matrix last factorised.
    fn solve(&mut self, matrix: &CscMatrix<f64>, rhs: &mut [f64]) {
        self.residual.clear();
        self.residual.extend_from_slice(rhs);
        self.solve_once(rhs);
        symmetric_subtract_product(matrix, rhs, &mut self.residual);
        let mut correction = std::mem::take(&mut self.residual);
        self.solve_once(&mut correction);
        for (x, d) in rhs.iter_mut().zip(&correction) {
            *x += d;
        }
        self.residual = correction;
    }

    fn solve_once(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.work),
        );
    }
}

/// r −= K x for K given by its upper triangle (CSC).
fn symmetric_subtract_product(matrix: &CscMatrix<f64>, x: &[f64], r: &mut [f64]) {
    for column in 0..matrix.n {
        for k in matrix.colptr[column]..matrix.colptr[column + 1] {
            let (row, value) = (matrix.rowval[k], matrix.nzval[k]);
            r[row] -= value * x[column];
            if row != column {
                r[column] -= value * x[row];
            }
        }
    }
}
