//! The factor split in two halves and a dense separator (see the parent
//! module for the algebra).

use super::interior::InteriorFactor;
use super::*;

/// One half of a split: M_i = [K_ii K_iS; K_Si K_SS] in its own ordering
/// (its interior by AMD or nested dissection, then the separator),
/// factorised up to the separator.
pub(crate) struct Half {
    /// Unknown of K of each column of M_i.
    pub(super) unknown: Vec<usize>,
    /// Interior columns (the separator's follow).
    interior: usize,
    factor: InteriorFactor,
    /// T_i = K_SS − K_Si K_ii⁻¹ K_iS (lower triangle), made by `factorise`
    /// (empty until then: a rank's half writes its T straight into Σ,
    /// [`Half::factorise_into`]).
    pub(super) schur_part: Mat<f64>,
    /// w_i of the last forward solve.
    forward_solution: Vec<f64>,
}

/// The matrix split in two halves and a dense separator.
pub(crate) struct SplitFactor {
    halves: [Half; 2],
    /// Unknowns of the separator, in the order of Σ's rows.
    pub(super) separator: Vec<usize>,
    /// (row, column) of Σ and entry of K of each K_SS value (upper).
    separator_entries: Vec<(usize, usize, usize)>,
    /// Σ's Cholesky factor (lower).
    schur: Mat<f64>,
    dense_work: MemBuffer,
}

impl SplitFactor {
    /// The split of `matrix`, or None where no separator small enough is
    /// found.
    pub(super) fn new(matrix: &CscMatrix<f64>) -> Result<Option<Self>, String> {
        let n = matrix.n;
        let neighbours = crate::dissection::neighbours(&matrix.colptr, &matrix.rowval, matrix.n);
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
            Half::new(matrix, &interior, &separator, None, Par::Seq)
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

    pub(super) fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
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
        factorise_schur(self.schur.as_mut(), &mut self.dense_work)
    }

    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let ns = self.separator.len();
        // 1. Forward solves, giving −L_Si w_i = −K_Si K_ii⁻¹ r_i.
        let [first, second] = &mut self.halves;
        let r: &[f64] = rhs;
        let (lambda_w1, lambda_w2) = rayon::join(|| first.forward(r), || second.forward(r));
        // 2. x_S = Σ⁻¹ (r_S − K_S1 K₁₁⁻¹ r₁ − K_S2 K₂₂⁻¹ r₂).
        let mut x_s = Mat::<f64>::zeros(ns, 1);
        for (k, &u) in self.separator.iter().enumerate() {
            x_s[(k, 0)] = rhs[u] + lambda_w1[k] + lambda_w2[k];
        }
        solve_schur(&self.schur, &mut x_s);
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
    /// The half over `interior` then `separator` (unknowns of `matrix`),
    /// its interior ordered by AMD, or where `positions` (of each unknown
    /// of `matrix`) are given and the interior is large, by nested
    /// dissection if that fills less; factorised on `par`.
    pub(super) fn new(
        matrix: &CscMatrix<f64>,
        interior: &[usize],
        separator: &[usize],
        positions: Option<&[[f64; 3]]>,
        par: Par,
    ) -> Result<Self, String> {
        let n = matrix.n;
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
        if let Some(positions) = positions.filter(|_| ni >= SPLIT_FROM_UNKNOWNS) {
            let own: Vec<[f64; 3]> = interior.iter().map(|&u| positions[u]).collect();
            let dissected = crate::dissection::order(&colptr, &rowval, ni, Some(&own));
            if fill(&colptr, &rowval, &dissected)? < fill(&colptr, &rowval, &forward)? {
                forward = dissected;
            }
        }
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
        let factor = InteriorFactor::new(supernodal, &local_matrix, &source, ni, par);
        Ok(Half {
            unknown,
            interior: ni,
            factor,
            schur_part: Mat::zeros(0, 0),
            forward_solution: vec![0.0; size],
        })
    }

    /// Factorises M_i's interior and forms T_i.
    pub(super) fn factorise(&mut self, matrix: &CscMatrix<f64>) -> Result<(), String> {
        self.factorise_shifted(matrix, &[])
    }

    /// As `factorise`, with `shift` (one per separator unknown, or none)
    /// added to K_SS's diagonal.
    pub(super) fn factorise_shifted(
        &mut self,
        matrix: &CscMatrix<f64>,
        shift: &[f64],
    ) -> Result<(), String> {
        let ns = self.unknown.len() - self.interior;
        if self.schur_part.nrows() != ns {
            self.schur_part = Mat::zeros(ns, ns);
        }
        let schur = &mut self.schur_part;
        self.factor
            .factorise(&matrix.nzval, shift, |i, j, t| schur[(i, j)] = t)
    }

    /// As `factorise_shifted`, adding each T_ij to `write(i, j, T_ij)`
    /// instead of keeping T (i ≥ j, within the half's separator).
    pub(super) fn factorise_into(
        &mut self,
        matrix: &CscMatrix<f64>,
        shift: &[f64],
        write: impl FnMut(usize, usize, f64),
    ) -> Result<(), String> {
        self.factor.factorise(&matrix.nzval, shift, write)
    }

    /// w_i = L_ii⁻¹ r_i; returns −(K_Si K_ii⁻¹ r_i) = −L_Si w_i.
    pub(super) fn forward(&mut self, rhs: &[f64]) -> Vec<f64> {
        let w = &mut self.forward_solution;
        for (k, &u) in self.unknown.iter().enumerate() {
            w[k] = if k < self.interior { rhs[u] } else { 0.0 };
        }
        self.factor.forward(w);
        w[self.interior..].to_vec()
    }

    /// The interior's x_i from the last forward solve and x_S.
    pub(super) fn backward(&mut self, x_s: faer::MatRef<'_, f64>) -> Vec<f64> {
        let interior = self.interior;
        let w = &mut self.forward_solution;
        for (k, value) in w[interior..].iter_mut().enumerate() {
            *value = x_s[(k, 0)];
        }
        self.factor.backward(w);
        w[..interior].to_vec()
    }
}

pub(super) const SEPARATOR: u8 = 2;

/// Sides 0 and 1 and the separator (2) of each unknown: breadth-first
/// levels from a peripheral unknown of the largest connected part (the
/// last one reached from its first unknown), the first side holding the
/// levels up to the one that reaches half the unknowns, the separator its
/// unknowns of that level with a neighbour beyond. None if that part holds
/// less than half the unknowns.
pub(super) fn bisect(neighbours: &[Vec<usize>]) -> Option<Vec<u8>> {
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

/// Entries of the Cholesky factor of the pattern (upper triangle, CSC) in
/// the order `forward` (the unknown at each position).
fn fill(colptr: &[usize], rowval: &[usize], forward: &[usize]) -> Result<usize, String> {
    let n = forward.len();
    let mut inverse = vec![0usize; n];
    for (new, &old) in forward.iter().enumerate() {
        inverse[old] = new;
    }
    let symbolic = factorize_symbolic_cholesky(
        SymbolicSparseColMatRef::new_checked(n, n, colptr, None, rowval),
        faer::Side::Upper,
        SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(forward, &inverse, n)),
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| format!("symbolic factorisation: {e:?}"))?;
    Ok(symbolic.len_val())
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
    let colptr = crate::csc::column_pointers(size, entries.iter().map(|e| e.0));
    let rowval = entries.iter().map(|e| e.1).collect();
    let source = entries.iter().map(|e| e.2).collect();
    (colptr, rowval, source)
}
