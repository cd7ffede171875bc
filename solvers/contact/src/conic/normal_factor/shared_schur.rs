//! The separator's Schur complement Σ = LLᵀ factorised by the ranks
//! together ([`super::shared`]).
//!
//! Σ is dense (ns × ns) and costs ns³/3 multiply–adds, the same on one rank
//! as on many; factorised whole on every rank it would be the one part of
//! an iteration that more ranks do not divide (at 64 ranks of the
//! 8,748-sphere packing it is 3.2e12 multiply–adds, more than the whole
//! matrix on one rank). Here the ranks share it by columns: a right-looking
//! blocked Cholesky whose column blocks of [`BLOCK`] are dealt round the
//! ranks, block k to rank k mod p. At step k
//!
//! 1. the owner of block k factorises its diagonal block,
//!    L_kk L_kkᵀ = Σ_kk, and the panel below it, L_ik = Σ_ik L_kk⁻ᵀ;
//! 2. it broadcasts the block column L_{k:,k};
//! 3. every rank updates the later block columns it owns,
//!    Σ_ij −= L_ik L_jkᵀ for i ≥ j > k.
//!
//! Each rank does about 1/p of the multiply–adds, and since every block
//! column reaches every rank, each ends with the whole of L for the
//! triangular solves (two per interior-point iteration, ns² each). The
//! broadcasts carry ns²/2 numbers in all, as the reduction that summed Σ.
//! Every block takes the updates of the block columns before it in their
//! order, whichever rank owns it: the factor is the same on any number of
//! ranks, and on one it is faer's dense Cholesky to the bit (the test).

use super::*;
use grainflow_core::Communicator;

/// Columns per block: wide enough for the dense kernels to run near their
/// peak, narrow enough that ns/BLOCK blocks share out evenly over the ranks
/// (17 blocks at the 2,166 unknowns of the 8,748-sphere packing on 2
/// ranks).
pub(super) const BLOCK: usize = 128;

/// Scratch for [`factorise_together`]: one diagonal block's Cholesky and the
/// broadcast block column.
pub(super) struct Workspace {
    cholesky: MemBuffer,
    column: Vec<f64>,
}

impl Workspace {
    pub(super) fn new(ns: usize) -> Self {
        Workspace {
            cholesky: MemBuffer::new(
                faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                    BLOCK.min(ns.max(1)),
                    Par::Seq,
                    Default::default(),
                ),
            ),
            // A status word, then the first block column (the largest).
            column: vec![0.0; 1 + ns * BLOCK.min(ns)],
        }
    }
}

/// Sums the lower triangles of the ranks' `schur` (each rank's part of Σ)
/// into every rank's, block column by block column through the
/// workspace's buffer (collective): Σ needs no second copy, packed or in
/// the reduction's send buffer, on any rank (the rank's own part is
/// written into Σ by its interior's factor: one dense ns × ns matrix held,
/// against three when the rank kept its part apart and the whole packed
/// triangle was summed at once; 1.2 GB a copy at the 12,414 separator
/// unknowns of the 112,896-sphere packing on 2 ranks).
/// The ranks sum each entry as in one reduction of the whole triangle.
pub(super) fn sum_together(
    schur: &mut Mat<f64>,
    communicator: &Communicator,
    work: &mut Workspace,
) {
    let ns = schur.nrows();
    for start in (0..ns).step_by(BLOCK) {
        let end = (start + BLOCK).min(ns);
        // The block column's lower trapezoid, column by column.
        let mut filled = 0;
        for c in start..end {
            let below = &schur.col_as_slice(c)[c..];
            work.column[filled..filled + below.len()].copy_from_slice(below);
            filled += below.len();
        }
        communicator.sum_each(&mut work.column[..filled]);
        let mut read = 0;
        for c in start..end {
            let below = &mut schur.col_as_slice_mut(c)[c..];
            let len = below.len();
            below.copy_from_slice(&work.column[read..read + len]);
            read += len;
        }
    }
}

/// Σ = LLᵀ in place (L in the lower triangle; the upper one is left as
/// it was), with the other ranks of `communicator`, each holding the same
/// Σ (collective: a block that is not positive definite fails every rank).
pub(super) fn factorise_together(
    schur: &mut Mat<f64>,
    communicator: &Communicator,
    work: &mut Workspace,
) -> Result<(), String> {
    let ns = schur.nrows();
    let (rank, ranks) = (communicator.rank(), communicator.size());
    let blocks = ns.div_ceil(BLOCK);
    for k in 0..blocks {
        let (start, end) = (k * BLOCK, ((k + 1) * BLOCK).min(ns));
        let (width, height) = (end - start, ns - start);
        let owner = k % ranks;
        let message = &mut work.column[..1 + height * width];
        if rank == owner {
            let factorised = factorise_block_column(schur, start, end, &mut work.cholesky);
            message[0] = if factorised.is_ok() { 1.0 } else { 0.0 };
            for c in 0..width {
                message[1 + c * height..1 + (c + 1) * height]
                    .copy_from_slice(&schur.col_as_slice(start + c)[start..]);
            }
        }
        communicator.broadcast(owner, message);
        if message[0] != 1.0 {
            return Err(format!(
                "the separator's Schur complement is not positive definite \
                 (columns {start} to {end} of {ns})"
            ));
        }
        if rank != owner {
            for c in 0..width {
                schur.col_as_slice_mut(start + c)[start..]
                    .copy_from_slice(&message[1 + c * height..1 + (c + 1) * height]);
            }
        }
        // Σ_ij −= L_ik L_jkᵀ over this rank's later block columns j.
        let (done, mut later) = schur.as_mut().split_at_col_mut(end);
        let block_column = done.as_ref().subcols(start, width);
        for j in (k + 1..blocks).filter(|j| j % ranks == rank) {
            let (from, to) = (j * BLOCK, ((j + 1) * BLOCK).min(ns));
            faer::linalg::matmul::matmul(
                later
                    .as_mut()
                    .submatrix_mut(from, from - end, ns - from, to - from),
                Accum::Add,
                block_column.subrows(from, ns - from),
                block_column.subrows(from, to - from).transpose(),
                -1.0,
                Par::Seq,
            );
        }
    }
    Ok(())
}

/// Step 1 on the block column of columns `start..end`, already updated by
/// every block column before it.
fn factorise_block_column(
    schur: &mut Mat<f64>,
    start: usize,
    end: usize,
    work: &mut MemBuffer,
) -> Result<(), String> {
    let ns = schur.nrows();
    let width = end - start;
    let mut column = schur
        .as_mut()
        .submatrix_mut(start, start, ns - start, width);
    let (mut diagonal, mut panel) = column.as_mut().split_at_row_mut(width);
    factorise_schur(diagonal.as_mut(), work)?;
    // L_ik = Σ_ik L_kk⁻ᵀ, i.e. L_ikᵀ = L_kk⁻¹ Σ_ikᵀ.
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        diagonal.as_ref(),
        panel.as_mut().transpose_mut(),
        Par::Seq,
    );
    Ok(())
}
