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
//! principal submatrix, hence SPD) with S ordered last,
//! L(M_i) = [L_ii 0; L_Si Λ_i], on its own thread. The last block gives
//! T_i = Λ_i Λ_iᵀ = K_SS − K_Si K_ii⁻¹ K_iS, so the Schur complement of
//! the whole matrix is
//!
//!   Σ = K_SS − K_S1 K₁₁⁻¹ K₁S − K_S2 K₂₂⁻¹ K₂S = T₁ + T₂ − K_SS,
//!
//! dense and of the separator's size, factorised by a dense Cholesky. A
//! solve K x = r then reads
//!
//! 1. per side, w_i = L(M_i)⁻¹ [r_i; 0], whose last block gives
//!    K_Si K_ii⁻¹ r_i = −Λ_i w_S;
//! 2. x_S = Σ⁻¹ (r_S − Σ_i K_Si K_ii⁻¹ r_i);
//! 3. per side, x_i = top of L(M_i)⁻ᵀ [w_i; Λ_iᵀ x_S]
//!    (= K_ii⁻¹ (r_i − K_iS x_S)).
//!
//! Each side is sequential, and the two sides' arithmetic does not depend
//! on which thread runs it: results are the same on any number of
//! threads, and two threads share the work.

use clarabel::algebra::CscMatrix;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, Par, Side};

/// Unknowns from which a matrix is split in two. On two threads the split
/// took a 2D packing's step from 0.45 to 0.32 s at 24,000 unknowns and
/// from 6.0 to 3.9 s at 150,000; on one thread it costs 7–10 % more than
/// the whole factor.
const SPLIT_FROM_UNKNOWNS: usize = 20_000;

/// Largest separator worth splitting at, as a fraction of the unknowns
/// and in unknowns: its dense Schur complement costs about ns³ flops per
/// factorisation (a 2D packing's grows as √n: 177 unknowns at 24,000,
/// 432 at 150,000).
const LARGEST_SEPARATOR_FRACTION: f64 = 0.02;
const LARGEST_SEPARATOR: usize = 1_500;

/// Whether a normal matrix of `unknowns` is factorised whole, so that the
/// interior point assembles it in a fill-reducing order once per step
/// (larger ones are split, and each half orders its own interior).
pub(crate) fn is_factorised_whole(unknowns: usize) -> bool {
    unknowns < SPLIT_FROM_UNKNOWNS
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

/// The factor of K, whole or split.
pub(crate) enum NormalFactor {
    Whole(Box<WholeFactor>),
    Split(Box<SplitFactor>),
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
    ) -> Result<Self, String> {
        Self::with_split_from(matrix, SPLIT_FROM_UNKNOWNS, ordered, positions)
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

    /// Factorises `matrix` (the pattern given to `new`).
    pub(crate) fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        match self {
            NormalFactor::Whole(whole) => whole.factorise(matrix),
            NormalFactor::Split(split) => split.factorise(matrix),
        }
    }

    /// Overwrites `rhs` with K⁻¹ rhs.
    pub(crate) fn solve(&mut self, rhs: &mut [f64]) {
        match self {
            NormalFactor::Whole(whole) => whole.solve(rhs),
            NormalFactor::Split(split) => split.solve(rhs),
        }
    }
}

/// One sparse Cholesky of the whole matrix, in the order given (the
/// interior point numbers its unknowns by AMD) or by nested dissection:
/// symbolic analysis once,
/// numeric factorisations per iteration, on the threads of the pool it
/// is built in. faer picks simplicial or
/// supernodal by the factor's density; on a 2D packing of 2,000 discs
/// forcing supernodal doubled the step.
pub(crate) struct WholeFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    work: MemBuffer,
    par: Par,
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
            CholeskySymbolicParams::default(),
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

    fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.work),
        );
    }
}

/// One half of a split: M_i = [K_ii K_iS; K_Si K_SS] in its own ordering
/// (its interior by AMD, then the separator).
pub(crate) struct Half {
    /// Unknown of K of each column of M_i.
    unknown: Vec<usize>,
    /// Interior columns (the separator's follow).
    interior: usize,
    /// M_i's upper pattern and values, and the entry of K each value
    /// copies.
    matrix: CscMatrix<f64>,
    source: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    work: MemBuffer,
    /// Λ_i (lower triangular) and T_i = Λ_i Λ_iᵀ.
    lambda: Mat<f64>,
    schur_part: Mat<f64>,
    /// w_i of the last forward solve.
    forward_solution: Vec<f64>,
}

/// The matrix split in two halves and a dense separator.
pub(crate) struct SplitFactor {
    halves: [Half; 2],
    /// Unknowns of the separator, in the order of Σ's rows.
    separator: Vec<usize>,
    /// (row, column) of Σ and entry of K of each K_SS value (upper).
    separator_entries: Vec<(usize, usize, usize)>,
    /// Σ's Cholesky factor (lower).
    schur: Mat<f64>,
    dense_work: MemBuffer,
}

impl SplitFactor {
    /// The split of `matrix`, or None where no separator small enough is
    /// found.
    fn new(matrix: &CscMatrix<f64>) -> Result<Option<Self>, String> {
        let n = matrix.n;
        let neighbours = adjacency(matrix);
        let Some(side_of) = bisect(&neighbours) else {
            return Ok(None);
        };
        let separator: Vec<usize> = (0..n).filter(|&u| side_of[u] == SEPARATOR).collect();
        if separator.len() > LARGEST_SEPARATOR
            || separator.len() as f64 > LARGEST_SEPARATOR_FRACTION * n as f64
        {
            return Ok(None);
        }
        let ns = separator.len();
        let mut position_in_separator = vec![usize::MAX; n];
        for (k, &u) in separator.iter().enumerate() {
            position_in_separator[u] = k;
        }
        let half = |which: u8| -> Result<Half, String> {
            let interior: Vec<usize> = (0..n).filter(|&u| side_of[u] == which).collect();
            Half::new(matrix, &interior, &separator)
        };
        let halves = [half(0)?, half(1)?];
        let mut separator_entries = Vec::new();
        for column in 0..n {
            let c = position_in_separator[column];
            if c == usize::MAX {
                continue;
            }
            for k in matrix.colptr[column]..matrix.colptr[column + 1] {
                let r = position_in_separator[matrix.rowval[k]];
                if r != usize::MAX {
                    separator_entries.push((r, c, k));
                }
            }
        }
        let dense_work = MemBuffer::new(
            faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                ns,
                Par::Seq,
                Default::default(),
            ),
        );
        Ok(Some(SplitFactor {
            halves,
            separator,
            separator_entries,
            schur: Mat::zeros(ns, ns),
            dense_work,
        }))
    }

    fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        let [first, second] = &mut self.halves;
        let (a, b) = rayon::join(|| first.factorise(matrix), || second.factorise(matrix));
        a?;
        b?;
        // Σ = T₁ + T₂ − K_SS (lower triangle).
        let ns = self.separator.len();
        let (t1, t2) = (&self.halves[0].schur_part, &self.halves[1].schur_part);
        for j in 0..ns {
            for i in j..ns {
                self.schur[(i, j)] = t1[(i, j)] + t2[(i, j)];
            }
        }
        for &(r, c, k) in &self.separator_entries {
            let (i, j) = (r.max(c), r.min(c));
            self.schur[(i, j)] -= matrix.nzval[k];
        }
        faer::linalg::cholesky::llt::factor::cholesky_in_place(
            self.schur.as_mut(),
            no_regularisation(),
            Par::Seq,
            MemStack::new(&mut self.dense_work),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| format!("the separator's Schur complement is not positive definite: {e:?}"))
    }

    fn solve(&mut self, rhs: &mut [f64]) {
        let ns = self.separator.len();
        // 1. Forward solves, giving Λ_i w_S = −K_Si K_ii⁻¹ r_i.
        let [first, second] = &mut self.halves;
        let r: &[f64] = rhs;
        let (lambda_w1, lambda_w2) = rayon::join(|| first.forward(r), || second.forward(r));
        // 2. x_S = Σ⁻¹ (r_S − K_S1 K₁₁⁻¹ r₁ − K_S2 K₂₂⁻¹ r₂).
        let mut x_s = Mat::<f64>::zeros(ns, 1);
        for (k, &u) in self.separator.iter().enumerate() {
            x_s[(k, 0)] = rhs[u] + lambda_w1[k] + lambda_w2[k];
        }
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            self.schur.as_ref(),
            x_s.as_mut(),
            Par::Seq,
        );
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            self.schur.transpose(),
            x_s.as_mut(),
            Par::Seq,
        );
        // 3. Back solves of each side's interior.
        let [first, second] = &mut self.halves;
        let (x1, x2) = rayon::join(
            || first.backward(x_s.as_ref()),
            || second.backward(x_s.as_ref()),
        );
        for (half, x) in self.halves.iter().zip([x1, x2]) {
            for (k, &u) in half.unknown[..half.interior].iter().enumerate() {
                rhs[u] = x[k];
            }
        }
        for (k, &u) in self.separator.iter().enumerate() {
            rhs[u] = x_s[(k, 0)];
        }
    }
}

impl Half {
    fn new(
        matrix: &CscMatrix<f64>,
        interior: &[usize],
        separator: &[usize],
    ) -> Result<Self, String> {
        let n = matrix.n;
        // The interior's own pattern, ordered by AMD.
        let mut local = vec![usize::MAX; n];
        for (k, &u) in interior.iter().enumerate() {
            local[u] = k;
        }
        let (colptr, rowval, _) = restrict(matrix, &local, interior.len());
        let ni = interior.len();
        let mut forward = vec![0usize; ni];
        let mut inverse = vec![0usize; ni];
        let mut amd_work = MemBuffer::new(amd::order_scratch::<usize>(ni, rowval.len()));
        amd::order(
            &mut forward,
            &mut inverse,
            SymbolicSparseColMatRef::new_checked(ni, ni, &colptr, None, &rowval),
            amd::Control::default(),
            MemStack::new(&mut amd_work),
        )
        .map_err(|e| format!("ordering: {e:?}"))?;
        // Columns of M_i: the interior in AMD order, then the separator.
        let unknown: Vec<usize> = forward
            .iter()
            .map(|&k| interior[k])
            .chain(separator.iter().copied())
            .collect();
        let mut local = vec![usize::MAX; n];
        for (k, &u) in unknown.iter().enumerate() {
            local[u] = k;
        }
        let size = unknown.len();
        let (colptr, rowval, source) = restrict(matrix, &local, size);
        let nnz = rowval.len();
        let local_matrix = CscMatrix::new(size, size, colptr, rowval, vec![0.0; nnz]);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            symbolic_pattern(&local_matrix),
            faer::Side::Upper,
            SymmetricOrdering::Identity,
            params,
        )
        .map_err(|e| format!("symbolic factorisation: {e:?}"))?;
        let SymbolicCholeskyRaw::Supernodal(supernodal) = symbolic.raw() else {
            return Err("the split factor needs a supernodal factorisation".into());
        };
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            supernodal.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let ns = separator.len();
        Ok(Half {
            unknown,
            interior: ni,
            matrix: local_matrix,
            source,
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            work: MemBuffer::new(scratch),
            lambda: Mat::zeros(ns, ns),
            schur_part: Mat::zeros(ns, ns),
            forward_solution: vec![0.0; size],
        })
    }

    fn supernodal(&self) -> SupernodalLltRef<'_, usize, f64> {
        let SymbolicCholeskyRaw::Supernodal(supernodal) = self.symbolic.raw() else {
            unreachable!("forced supernodal")
        };
        SupernodalLltRef::new(supernodal, &self.values)
    }

    /// Factorises M_i, then reads Λ_i and forms T_i = Λ_i Λ_iᵀ.
    fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        for (value, &k) in self.matrix.nzval.iter_mut().zip(&self.source) {
            *value = matrix.nzval[k];
        }
        factorise_numeric(
            &self.symbolic,
            &mut self.values,
            &mut self.work,
            &self.matrix,
            Par::Seq,
        )?;
        let first = self.interior;
        let mut lambda = std::mem::replace(&mut self.lambda, Mat::new());
        lambda.as_mut().fill(0.0);
        let factor = self.supernodal();
        let symbolic = factor.symbolic();
        for s in 0..symbolic.n_supernodes() {
            let node = factor.supernode(s);
            let (start, columns) = (node.start(), node.val().ncols());
            if start + columns <= first {
                continue;
            }
            let rows: Vec<usize> = (start..start + columns)
                .chain(node.pattern().iter().copied())
                .collect();
            for c in 0..columns {
                let column = start + c;
                if column < first {
                    continue;
                }
                for (r, &row) in rows.iter().enumerate().skip(c) {
                    lambda[(row - first, column - first)] = node.val()[(r, c)];
                }
            }
        }
        self.lambda = lambda;
        faer::linalg::matmul::triangular::matmul(
            self.schur_part.as_mut(),
            faer::linalg::matmul::triangular::BlockStructure::TriangularLower,
            Accum::Replace,
            self.lambda.as_ref(),
            faer::linalg::matmul::triangular::BlockStructure::TriangularLower,
            self.lambda.transpose(),
            faer::linalg::matmul::triangular::BlockStructure::TriangularUpper,
            1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// w_i = L(M_i)⁻¹ [r_i; 0]; returns −(K_Si K_ii⁻¹ r_i) = Λ_i w_S.
    fn forward(&mut self, rhs: &[f64]) -> Vec<f64> {
        let size = self.unknown.len();
        let mut w = std::mem::take(&mut self.forward_solution);
        for (k, &u) in self.unknown.iter().enumerate() {
            w[k] = if k < self.interior { rhs[u] } else { 0.0 };
        }
        let mut work = std::mem::replace(&mut self.work, MemBuffer::new(StackReq::empty()));
        self.supernodal().l_solve_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut w, size, 1),
            Par::Seq,
            MemStack::new(&mut work),
        );
        self.work = work;
        let ns = size - self.interior;
        let w_s = faer::MatRef::from_column_major_slice(&w[self.interior..], ns, 1);
        let mut product = Mat::<f64>::zeros(ns, 1);
        faer::linalg::matmul::matmul(
            product.as_mut(),
            Accum::Replace,
            self.lambda.as_ref(),
            w_s,
            1.0,
            Par::Seq,
        );
        self.forward_solution = w;
        (0..ns).map(|k| product[(k, 0)]).collect()
    }

    /// The interior's x_i from the last forward solve and x_S.
    fn backward(&mut self, x_s: faer::MatRef<'_, f64>) -> Vec<f64> {
        let size = self.unknown.len();
        let ns = size - self.interior;
        let mut w = std::mem::take(&mut self.forward_solution);
        let mut top = faer::MatMut::from_column_major_slice_mut(&mut w[self.interior..], ns, 1);
        faer::linalg::matmul::matmul(
            top.as_mut(),
            Accum::Replace,
            self.lambda.transpose(),
            x_s,
            1.0,
            Par::Seq,
        );
        let mut work = std::mem::replace(&mut self.work, MemBuffer::new(StackReq::empty()));
        self.supernodal().l_transpose_solve_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut w, size, 1),
            Par::Seq,
            MemStack::new(&mut work),
        );
        self.work = work;
        let x = w[..self.interior].to_vec();
        self.forward_solution = w;
        x
    }
}

/// Neighbours of each unknown in the graph of the matrix.
fn adjacency(matrix: &CscMatrix<f64>) -> Vec<Vec<usize>> {
    let mut neighbours = vec![Vec::new(); matrix.n];
    for column in 0..matrix.n {
        for &row in &matrix.rowval[matrix.colptr[column]..matrix.colptr[column + 1]] {
            if row != column {
                neighbours[column].push(row);
                neighbours[row].push(column);
            }
        }
    }
    neighbours
}

const SEPARATOR: u8 = 2;

/// Sides 0 and 1 and the separator (2) of each unknown: breadth-first
/// levels from a peripheral unknown of the largest connected part (the
/// last one reached from its first unknown), the first side holding the
/// levels up to the one that reaches half the unknowns, the separator its
/// unknowns of that level with a neighbour beyond. None if that part holds
/// less than half the unknowns.
fn bisect(neighbours: &[Vec<usize>]) -> Option<Vec<u8>> {
    let n = neighbours.len();
    let levels = |start: usize| -> Vec<usize> {
        let mut level = vec![usize::MAX; n];
        let mut queue = std::collections::VecDeque::from([start]);
        level[start] = 0;
        while let Some(u) = queue.pop_front() {
            for &v in &neighbours[u] {
                if level[v] == usize::MAX {
                    level[v] = level[u] + 1;
                    queue.push_back(v);
                }
            }
        }
        level
    };
    // Start in the largest connected part (a grain touching only walls or
    // glued grains is a part of its own).
    let mut reached = vec![false; n];
    let (mut largest, mut largest_size) = (0, 0);
    for start in 0..n {
        if reached[start] {
            continue;
        }
        reached[start] = true;
        let (mut queue, mut size) = (vec![start], 0);
        while let Some(u) = queue.pop() {
            size += 1;
            for &v in &neighbours[u] {
                if !reached[v] {
                    reached[v] = true;
                    queue.push(v);
                }
            }
        }
        if size > largest_size {
            (largest, largest_size) = (start, size);
        }
    }
    let from_start = levels(largest);
    let peripheral = (0..n)
        .filter(|&u| from_start[u] != usize::MAX)
        .max_by_key(|&u| (from_start[u], std::cmp::Reverse(u)))?;
    let level = levels(peripheral);
    let deepest = level.iter().filter(|&&l| l != usize::MAX).max().copied()?;
    let mut count = vec![0usize; deepest + 1];
    for &l in level.iter().filter(|&&l| l != usize::MAX) {
        count[l] += 1;
    }
    let mut reached = 0;
    let mut cut = None;
    for (l, &c) in count.iter().enumerate() {
        reached += c;
        if 2 * reached >= n {
            cut = Some(l);
            break;
        }
    }
    let cut = cut?;
    if cut == 0 || cut >= deepest {
        return None;
    }
    // Unreached unknowns (other components) join the second side.
    let side_of = (0..n)
        .map(|u| {
            if level[u] == usize::MAX || level[u] > cut {
                1
            } else if level[u] == cut && neighbours[u].iter().any(|&v| level[v] == cut + 1) {
                SEPARATOR
            } else {
                0
            }
        })
        .collect();
    Some(side_of)
}

/// The upper pattern of `matrix` restricted to the unknowns with a local
/// index (`local[u] < size`), in local numbering: (colptr, rowval, index
/// in `matrix` of each entry), rows sorted in each column.
fn restrict(
    matrix: &CscMatrix<f64>,
    local: &[usize],
    size: usize,
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let mut entries: Vec<(usize, usize, usize)> = Vec::new();
    for column in 0..matrix.n {
        let c = local[column];
        if c >= size {
            continue;
        }
        for k in matrix.colptr[column]..matrix.colptr[column + 1] {
            let r = local[matrix.rowval[k]];
            if r < size {
                entries.push((r.max(c), r.min(c), k));
            }
        }
    }
    entries.sort_unstable();
    let mut colptr = vec![0usize; size + 1];
    for &(c, _, _) in &entries {
        colptr[c + 1] += 1;
    }
    for c in 0..size {
        colptr[c + 1] += colptr[c];
    }
    let rowval = entries.iter().map(|e| e.1).collect();
    let source = entries.iter().map(|e| e.2).collect();
    (colptr, rowval, source)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// The upper CSC of D + Σ θ_r a_r a_rᵀ: three unknowns on each node of
    /// an nx × ny grid, unit diagonal D, and for each pair of neighbouring
    /// nodes (right, up and diagonal) a row a_r over their six unknowns with
    /// θ_r spread over twelve orders of magnitude, as late in an interior
    /// point.
    fn grid_normal_matrix(nx: usize, ny: usize) -> CscMatrix<f64> {
        lattice_normal_matrix([nx, ny, 1], &[[1, 0, 0], [0, 1, 0], [1, 1, 0]])
    }

    /// The same on an nx × ny × nz lattice with the given neighbours.
    fn lattice_normal_matrix(size: [usize; 3], offsets: &[[usize; 3]]) -> CscMatrix<f64> {
        let [nx, ny, nz] = size;
        let node = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let nodes = nx * ny * nz;
        let mut entries: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for u in 0..3 * nodes {
            entries.insert((u, u), 1.0);
        }
        let mut pseudo_random = 12345u64;
        let mut next = || {
            pseudo_random = pseudo_random
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (pseudo_random >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    for &[di, dj, dk] in offsets {
                        if i + di >= nx || j + dj >= ny || k + dk >= nz {
                            continue;
                        }
                        let (a, b) = (node(i, j, k), node(i + di, j + dj, k + dk));
                        let theta = 10f64.powf(12.0 * next() - 6.0);
                        let mut row = Vec::with_capacity(6);
                        for d in 0..3 {
                            row.push((3 * a + d, next() - 0.5));
                        }
                        for d in 0..3 {
                            row.push((3 * b + d, next() - 0.5));
                        }
                        for &(c, vc) in &row {
                            for &(r, vr) in &row {
                                if r <= c {
                                    *entries.entry((c, r)).or_insert(0.0) += theta * vc * vr;
                                }
                            }
                        }
                    }
                }
            }
        }
        let n = 3 * nodes;
        let mut colptr = vec![0usize; n + 1];
        for &(c, _) in entries.keys() {
            colptr[c + 1] += 1;
        }
        for c in 0..n {
            colptr[c + 1] += colptr[c];
        }
        let rowval = entries.keys().map(|&(_, r)| r).collect();
        let nzval = entries.values().copied().collect();
        CscMatrix::new(n, n, colptr, rowval, nzval)
    }

    /// K x from the upper triangle.
    fn times(matrix: &CscMatrix<f64>, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; matrix.n];
        for c in 0..matrix.n {
            for k in matrix.colptr[c]..matrix.colptr[c + 1] {
                let (r, v) = (matrix.rowval[k], matrix.nzval[k]);
                y[r] += v * x[c];
                if r != c {
                    y[c] += v * x[r];
                }
            }
        }
        y
    }

    fn infinity_norm(v: &[f64]) -> f64 {
        v.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// ‖K x − b‖∞ / (‖K‖∞ ‖x‖∞), the backward error of a solve.
    fn backward_error(matrix: &CscMatrix<f64>, x: &[f64], b: &[f64]) -> f64 {
        let residual: Vec<f64> = times(matrix, x).iter().zip(b).map(|(y, b)| y - b).collect();
        let abs = CscMatrix::new(
            matrix.n,
            matrix.n,
            matrix.colptr.clone(),
            matrix.rowval.clone(),
            matrix.nzval.iter().map(|v| v.abs()).collect(),
        );
        let norm = infinity_norm(&times(&abs, &vec![1.0; matrix.n]));
        infinity_norm(&residual) / (norm * infinity_norm(x))
    }

    fn solve_with(factor: &mut NormalFactor, matrix: &CscMatrix<f64>, b: &[f64]) -> Vec<f64> {
        factor.factorise(matrix).unwrap();
        let mut x = b.to_vec();
        factor.solve(&mut x);
        x
    }

    #[test]
    fn a_path_is_split_at_its_middle() {
        let n: usize = 101;
        let neighbours: Vec<Vec<usize>> = (0..n)
            .map(|u: usize| {
                [u.checked_sub(1), (u + 1 < n).then_some(u + 1)]
                    .into_iter()
                    .flatten()
                    .collect()
            })
            .collect();
        let side_of = bisect(&neighbours).unwrap();
        // From the far end (100): levels ≤ 50 hold half the path.
        assert_eq!(side_of[50], SEPARATOR);
        assert!(side_of[51..].iter().all(|&s| s == 0));
        assert!(side_of[..50].iter().all(|&s| s == 1));
    }

    #[test]
    fn an_isolated_first_unknown_does_not_prevent_the_split() {
        // Unknown 0 alone (a grain touching only a wall), then a path.
        let n: usize = 102;
        let neighbours: Vec<Vec<usize>> = (0..n)
            .map(|u: usize| {
                if u == 0 {
                    return Vec::new();
                }
                [(u > 1).then(|| u - 1), (u + 1 < n).then_some(u + 1)]
                    .into_iter()
                    .flatten()
                    .collect()
            })
            .collect();
        let side_of = bisect(&neighbours).unwrap();
        assert_eq!(side_of.iter().filter(|&&s| s == SEPARATOR).count(), 1);
        assert_eq!(side_of[0], 1);
    }

    #[test]
    fn the_split_factor_solves_as_accurately_as_the_whole_one() {
        let matrix = grid_normal_matrix(60, 40);
        let n = matrix.n;
        let b: Vec<f64> = (0..n)
            .map(|k| ((k * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect();
        let mut whole = NormalFactor::with_split_from(&matrix, usize::MAX, false, &[]).unwrap();
        let mut split = NormalFactor::with_split_from(&matrix, 0, false, &[]).unwrap();
        let NormalFactor::Split(parts) = &split else {
            panic!("the grid was not split");
        };
        // A 60 × 40 grid cut across its 40-node height: one line of nodes
        // (measured: 120 unknowns).
        let separator = parts.separator.len();
        assert!(separator <= 3 * 40, "separator of {separator} unknowns");
        let x_whole = solve_with(&mut whole, &matrix, &b);
        let x_split = solve_with(&mut split, &matrix, &b);
        // Both backward stable to round-off, θ spanning 1e-6 to 1e6
        // (measured: 4e-17 whole, 9e-17 split).
        let (e_whole, e_split) = (
            backward_error(&matrix, &x_whole, &b),
            backward_error(&matrix, &x_split, &b),
        );
        assert!(e_whole < 1e-14, "whole: {e_whole:e}");
        assert!(e_split < 1e-14, "split: {e_split:e}");
    }

    #[test]
    fn the_split_solve_does_not_depend_on_the_number_of_threads() {
        let matrix = grid_normal_matrix(60, 40);
        let b: Vec<f64> = (0..matrix.n).map(|k| (k as f64).sin()).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut split = NormalFactor::with_split_from(&matrix, 0, false, &[]).unwrap();
                assert!(matches!(split, NormalFactor::Split(_)));
                solve_with(&mut split, &matrix, &b)
            })
        };
        let (one, two) = (on(1), on(2));
        assert!(one
            .iter()
            .zip(&two)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn the_whole_supernodal_factor_is_the_same_on_any_number_of_threads() {
        // A 3D lattice: dense supernodes, whose blocks faer runs on the threads.
        let matrix = lattice_normal_matrix(
            [14, 14, 14],
            &[[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1]],
        );
        let b: Vec<f64> = (0..matrix.n).map(|k| (k as f64).cos()).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut whole =
                    NormalFactor::with_split_from(&matrix, usize::MAX, false, &[]).unwrap();
                let NormalFactor::Whole(factor) = &whole else {
                    panic!("split");
                };
                assert!(matches!(
                    factor.symbolic.raw(),
                    SymbolicCholeskyRaw::Supernodal(_)
                ));
                solve_with(&mut whole, &matrix, &b)
            })
        };
        let (one, two) = (on(1), on(2));
        assert!(backward_error(&matrix, &one, &b) < 1e-14);
        assert!(one
            .iter()
            .zip(&two)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
