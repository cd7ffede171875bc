//! A half's factor stopped at the separator.
//!
//! A half M = [K_ii K_iS; K_Si K_SS] (interior first, separator last) needs
//! only the interior's columns of its Cholesky factor,
//!
//!   L(M) = [L_ii 0; L_Si ·],   K_ii = L_ii L_iiᵀ,   L_Si = K_Si L_ii⁻ᵀ,
//!
//! and the separator's Schur complement T = K_SS − L_Si L_Siᵀ that the
//! separator's columns hold once every interior column has updated them.
//! Factorising the separator's block as well, then multiplying its factor
//! back, cost two dense ns³/3 products per half and iteration for nothing:
//! Σ, the sum of the halves' T, is factorised once.
//!
//! This is a left-looking supernodal Cholesky over the supernodes of faer's
//! symbolic factor of M: each supernode gathers the updates of the
//! supernodes below it in the elimination tree, then factorises its
//! diagonal block and its panel. The separator's supernodes gather and stop.
//! A supernode that holds both interior and separator columns is cut in two
//! at the first separator column.

use super::*;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::MatRef;
use std::ops::Range;

/// Columns of a descendant's update made at a time where it cannot be
/// subtracted in place (see `gather_updates`).
const PRODUCT_COLUMNS: usize = 256;

/// A block of columns of L with the same rows below their diagonal block.
struct Node {
    columns: Range<usize>,
    /// Where the block starts in the values, and the distance between its
    /// columns (column-major, rows in the order of `rows`).
    offset: usize,
    stride: usize,
    /// Its rows in `InteriorFactor::rows`: its own columns, then the rows
    /// below (ascending).
    rows: Range<usize>,
}

impl Node {
    fn width(&self) -> usize {
        self.columns.len()
    }

    fn height(&self) -> usize {
        self.rows.len()
    }

    /// The values the block spans.
    fn span(&self) -> Range<usize> {
        self.offset..self.offset + (self.width() - 1) * self.stride + self.height()
    }
}

/// The interior columns of L(M) and the separator's Schur complement.
pub(super) struct InteriorFactor {
    /// Interior columns (the separator's follow).
    interior: usize,
    nodes: Vec<Node>,
    /// The nodes' rows, one after the other.
    rows: Vec<usize>,
    /// The nodes whose rows below reach each node, in order.
    descendants: Vec<Vec<usize>>,
    /// Each entry of M's upper triangle: the entry of K it copies, and
    /// where it goes in `values`.
    destination: Vec<(usize, usize)>,
    /// Where the diagonal of each separator column stands in `values`.
    separator_diagonal: Vec<usize>,
    values: Vec<f64>,
    /// Scratch: local row of each row of M in the node being updated, the
    /// product of a descendant's rows, the dense Cholesky's work.
    local_row: Vec<usize>,
    /// The node's local row of each row of the descendant being gathered.
    target_rows: Vec<usize>,
    product: Vec<f64>,
    work: MemBuffer,
    par: Par,
}

impl InteriorFactor {
    /// The factor of the pattern `matrix` (M's upper triangle, CSC, its
    /// first `interior` columns the interior; `source`: the entry of K each
    /// of its entries copies) on the supernodes of `symbolic`, factorised on
    /// `par`.
    pub(super) fn new(
        symbolic: &SymbolicSupernodalCholesky<usize>,
        matrix: &CscMatrix<f64>,
        source: &[usize],
        interior: usize,
        par: Par,
    ) -> Self {
        let size = matrix.n;
        let (begin, row_pointers, value_pointers, pattern) = (
            symbolic.supernode_begin(),
            symbolic.col_ptr_for_row_idx(),
            symbolic.col_ptr_for_val(),
            symbolic.row_idx(),
        );
        let (mut nodes, mut rows) = (Vec::new(), Vec::new());
        for s in 0..symbolic.n_supernodes() {
            let columns = begin[s]..symbolic.supernode_end()[s];
            let below = &pattern[row_pointers[s]..row_pointers[s + 1]];
            let height = columns.len() + below.len();
            let offset = value_pointers[s];
            // A supernode across the separator's first column is cut
            // there: the interior part has the separator part's columns
            // among its rows; the separator part's block starts on its own
            // diagonal.
            let pieces = if columns.start < interior && interior < columns.end {
                let cut = interior - columns.start;
                vec![
                    (columns.start..interior, offset),
                    (interior..columns.end, offset + cut * height + cut),
                ]
            } else {
                vec![(columns.clone(), offset)]
            };
            for (own, offset) in pieces {
                let start = rows.len();
                rows.extend(own.start..columns.end);
                rows.extend_from_slice(below);
                nodes.push(Node {
                    columns: own,
                    offset,
                    stride: height,
                    rows: start..rows.len(),
                });
            }
        }
        let mut node_of_column = vec![0; size];
        for (n, node) in nodes.iter().enumerate() {
            node_of_column[node.columns.clone()].fill(n);
        }
        // Only the interior's nodes update others: the separator's are
        // gathered, not factorised.
        let mut descendants = vec![Vec::new(); nodes.len()];
        for (d, node) in nodes
            .iter()
            .enumerate()
            .take_while(|(_, n)| n.columns.start < interior)
        {
            let mut last = usize::MAX;
            for &row in &rows[node.rows.start + node.width()..node.rows.end] {
                let target = node_of_column[row];
                if target != last {
                    descendants[target].push(d);
                    last = target;
                }
            }
        }
        // Entry (row r ≤ column c) of the upper triangle is L's (c, r).
        let at = |row: usize, column: usize| -> usize {
            let node = &nodes[node_of_column[column]];
            let own = &rows[node.rows.clone()];
            let local = own
                .binary_search(&row)
                .expect("the symbolic factor holds every entry of the matrix");
            node.offset + (column - node.columns.start) * node.stride + local
        };
        let mut destination = Vec::with_capacity(matrix.nzval.len());
        for column in 0..size {
            let entries = matrix.colptr[column]..matrix.colptr[column + 1];
            for (&from, &row) in source[entries.clone()].iter().zip(&matrix.rowval[entries]) {
                destination.push((from, at(column, row)));
            }
        }
        let separator_diagonal = (interior..size).map(|c| at(c, c)).collect();
        let widest = nodes.iter().map(Node::width).max().unwrap_or(0);
        let work = MemBuffer::new(
            faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                widest,
                par,
                Default::default(),
            ),
        );
        InteriorFactor {
            interior,
            nodes,
            rows,
            descendants,
            destination,
            separator_diagonal,
            values: vec![0.0; symbolic.len_val()],
            local_row: vec![0; size],
            target_rows: Vec::new(),
            product: Vec::new(),
            work,
            par,
        }
    }

    /// Factorises the interior of M, its entries read from K's `values`,
    /// `shift` added to the separator's diagonal, and hands each entry of
    /// T's lower triangle to `write(i, j, T_ij)` (i ≥ j, within the
    /// separator): the caller puts it where it belongs (a half's own T, or
    /// straight into the ranks' Σ, which spares a rank a dense ns × ns
    /// copy).
    pub(super) fn factorise(
        &mut self,
        values: &[f64],
        shift: &[f64],
        mut write: impl FnMut(usize, usize, f64),
    ) -> Result<(), String> {
        self.values.fill(0.0);
        for &(from, to) in &self.destination {
            self.values[to] += values[from];
        }
        for (&to, &added) in self.separator_diagonal.iter().zip(shift) {
            self.values[to] += added;
        }
        for t in 0..self.nodes.len() {
            self.gather_updates(t);
            let node = &self.nodes[t];
            if node.columns.start >= self.interior {
                continue;
            }
            let (width, height) = (node.width(), node.height());
            let mut block = MatMut::from_column_major_slice_with_stride_mut(
                &mut self.values[node.span()],
                height,
                width,
                node.stride,
            );
            let (mut top, mut below) = block.as_mut().split_at_row_mut(width);
            faer::linalg::cholesky::llt::factor::cholesky_in_place(
                top.as_mut(),
                no_regularisation(),
                self.par,
                MemStack::new(&mut self.work),
                Default::default(),
            )
            .map_err(|e| {
                format!(
                    "the normal matrix is not positive definite (column {}): {e:?}",
                    node.columns.start
                )
            })?;
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                top.as_ref(),
                below.as_mut().transpose_mut(),
                self.par,
            );
        }
        let interior = self.interior;
        for node in self.nodes.iter().filter(|n| n.columns.start >= interior) {
            let block = MatRef::from_column_major_slice_with_stride(
                &self.values[node.span()],
                node.height(),
                node.width(),
                node.stride,
            );
            let rows = &self.rows[node.rows.clone()];
            for c in 0..node.width() {
                let column = node.columns.start + c - interior;
                for (r, &row) in rows.iter().enumerate().skip(c) {
                    write(row - interior, column, block[(r, c)]);
                }
            }
        }
        Ok(())
    }

    /// Subtracts from node `t` the products of the rows of each of its
    /// descendants that fall on its columns and below. Where those rows are
    /// consecutive rows of the node (and the columns they fall on
    /// consecutive columns) the product goes into the node's block in
    /// place; elsewhere through a scratch block, scattered row by row.
    fn gather_updates(&mut self, t: usize) {
        let target = &self.nodes[t];
        for (local, &row) in self.rows[target.rows.clone()].iter().enumerate() {
            self.local_row[row] = local;
        }
        let (head, tail) = self.values.split_at_mut(target.offset);
        let mut block = MatMut::from_column_major_slice_with_stride_mut(
            &mut tail[..target.span().len()],
            target.height(),
            target.width(),
            target.stride,
        );
        for &d in &self.descendants[t] {
            let node = &self.nodes[d];
            let rows = &self.rows[node.rows.clone()];
            let below = &rows[node.width()..];
            // Its rows on the target's columns, and from there down.
            let first = node.width() + below.partition_point(|&r| r < target.columns.start);
            let on = rows[first..].partition_point(|&r| r < target.columns.end);
            let down = rows.len() - first;
            let lower = MatRef::from_column_major_slice_with_stride(
                &head[node.span()],
                node.height(),
                node.width(),
                node.stride,
            )
            .subrows(first, down);
            let targets = &rows[first..];
            self.target_rows.clear();
            self.target_rows
                .extend(targets.iter().map(|&r| self.local_row[r]));
            let local = &self.target_rows;
            let in_place =
                local[down - 1] - local[0] == down - 1 && targets[on - 1] - targets[0] == on - 1;
            if in_place {
                // The rows are the node's rows local[0].., its columns
                // targets[0] − start..: L_t −= L_d L_dᵀ there directly.
                let column = targets[0] - target.columns.start;
                let update = block.as_mut().submatrix_mut(local[0], column, down, on);
                rows_times_facing(update, lower, on, Accum::Add, -1.0, self.par);
                continue;
            }
            // Through the scratch a block of PRODUCT_COLUMNS columns at a
            // time: the rows of a descendant below a rank's separator can
            // reach most of it, and the whole product would then be a
            // dense copy of the separator's block.
            for from in (0..on).step_by(PRODUCT_COLUMNS) {
                let to = (from + PRODUCT_COLUMNS).min(on);
                let (height, width) = (down - from, to - from);
                self.product.resize(height * width, 0.0);
                let product = MatMut::from_column_major_slice_mut(&mut self.product, height, width);
                rows_times_facing(
                    product,
                    lower.subrows(from, height),
                    width,
                    Accum::Replace,
                    1.0,
                    self.par,
                );
                for (j, &row) in targets.iter().enumerate().take(to).skip(from) {
                    let column = row - target.columns.start;
                    let destination = block
                        .as_mut()
                        .col_mut(column)
                        .try_as_col_major_mut()
                        .unwrap();
                    let destination = destination.as_slice_mut();
                    let source = &self.product[(j - from) * height..(j - from + 1) * height];
                    for i in j..down {
                        destination[local[i]] -= source[i - from];
                    }
                }
            }
        }
    }

    /// w = L_ii⁻¹ r_i on the interior (`w` holds r_i there and zeros on
    /// the separator), and −L_Si w_i = −K_Si K_ii⁻¹ r_i on the separator.
    pub(super) fn forward(&self, w: &mut [f64]) {
        let mut product = Vec::new();
        for node in self
            .nodes
            .iter()
            .take_while(|n| n.columns.start < self.interior)
        {
            let block = self.block(node);
            let (top, below) = block.split_at_row(node.width());
            let own =
                MatMut::from_column_major_slice_mut(&mut w[node.columns.clone()], node.width(), 1);
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(top, own, Par::Seq);
            product.resize(below.nrows(), 0.0);
            let mut out = MatMut::from_column_major_slice_mut(&mut product, below.nrows(), 1);
            let own = MatRef::from_column_major_slice(&w[node.columns.clone()], node.width(), 1);
            faer::linalg::matmul::matmul(out.as_mut(), Accum::Replace, below, own, 1.0, Par::Seq);
            for (&row, value) in self.rows[node.rows.start + node.width()..node.rows.end]
                .iter()
                .zip(&product)
            {
                w[row] -= value;
            }
        }
    }

    /// x_i = L_ii⁻ᵀ (w_i − L_Siᵀ x_S) in place, `w` holding w_i on the
    /// interior and x_S on the separator.
    pub(super) fn backward(&self, w: &mut [f64]) {
        let mut gathered = Vec::new();
        for node in self
            .nodes
            .iter()
            .rev()
            .filter(|n| n.columns.start < self.interior)
        {
            let block = self.block(node);
            let (top, below) = block.split_at_row(node.width());
            gathered.clear();
            gathered.extend(
                self.rows[node.rows.start + node.width()..node.rows.end]
                    .iter()
                    .map(|&row| w[row]),
            );
            let gathered = MatRef::from_column_major_slice(&gathered, below.nrows(), 1);
            let mut own =
                MatMut::from_column_major_slice_mut(&mut w[node.columns.clone()], node.width(), 1);
            faer::linalg::matmul::matmul(
                own.as_mut(),
                Accum::Add,
                below.transpose(),
                gathered,
                -1.0,
                Par::Seq,
            );
            faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                top.transpose(),
                own,
                Par::Seq,
            );
        }
    }

    fn block(&self, node: &Node) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice_with_stride(
            &self.values[node.span()],
            node.height(),
            node.width(),
            node.stride,
        )
    }
}

/// `destination` (accumulated as `accum`) of `alpha` times the products of
/// the rows of `lower` with its first `on` rows, L_d L_d,facingᵀ: the first
/// `on` rows of the product are the lower triangle of a symmetric block,
/// the rest rectangular.
fn rows_times_facing(
    mut destination: MatMut<'_, f64>,
    lower: MatRef<'_, f64>,
    on: usize,
    accum: Accum,
    alpha: f64,
    par: Par,
) {
    use faer::linalg::matmul::triangular::BlockStructure;
    let facing = lower.subrows(0, on);
    let (top, bottom) = destination.as_mut().split_at_row_mut(on);
    faer::linalg::matmul::triangular::matmul(
        top,
        BlockStructure::TriangularLower,
        accum,
        facing,
        BlockStructure::Rectangular,
        facing.transpose(),
        BlockStructure::Rectangular,
        alpha,
        par,
    );
    faer::linalg::matmul::matmul(
        bottom,
        accum,
        lower.subrows(on, lower.nrows() - on),
        facing.transpose(),
        alpha,
        par,
    );
}
