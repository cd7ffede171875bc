use super::split::{bisect, SEPARATOR};
use super::*;
use faer::linalg::solvers::Solve;
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
    factor.solve(matrix, &mut x);
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

/// The factor shared among ranks, on one rank with a separator (the top
/// row of the grid, its unknowns last), is the Schur-complement solve of
/// the split with the whole diagonal D_S on the rank's separator: as
/// accurate as the whole factor with θ over twelve orders of magnitude
/// (measured: 4.0e-17 shared, 3.8e-17 whole).
#[test]
fn the_factor_shared_among_ranks_solves_as_accurately_as_the_whole_one() {
    let matrix = grid_normal_matrix(60, 40);
    let n = matrix.n;
    let b: Vec<f64> = (0..n)
        .map(|k| ((k * 7919) % 1000) as f64 / 500.0 - 1.0)
        .collect();
    let mass = vec![1.0; n];
    let interior = n - 3 * 60;
    let communicator = grainflow_core::Communicator::serial();
    let mut shared = NormalFactor::shared(&matrix, interior, &mass, &[], &communicator).unwrap();
    let mut whole = NormalFactor::with_split_from(&matrix, usize::MAX, false, &[]).unwrap();
    let x_shared = solve_with(&mut shared, &matrix, &b);
    let x_whole = solve_with(&mut whole, &matrix, &b);
    let (e_whole, e_shared) = (
        backward_error(&matrix, &x_whole, &b),
        backward_error(&matrix, &x_shared, &b),
    );
    println!("backward errors: whole {e_whole:e}, shared {e_shared:e}");
    assert!(e_shared < 1e-14, "shared: {e_shared:e}");
    // Refactorised with other values on the same pattern.
    let mut scaled = matrix.clone();
    scaled.nzval.iter_mut().for_each(|v| *v *= 3.0);
    let x = solve_with(&mut shared, &scaled, &b);
    assert!(backward_error(&scaled, &x, &b) < 1e-14);
}

/// K⁻¹ b on `threads` threads, from a factor splitting matrices from
/// `split_from` unknowns (ordered by nested dissection when whole).
fn solved_on(threads: usize, matrix: &CscMatrix<f64>, b: &[f64], split_from: usize) -> Vec<f64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut factor = NormalFactor::with_split_from(matrix, split_from, false, &[]).unwrap();
        match &factor {
            NormalFactor::Split(_) => assert_eq!(split_from, 0),
            // Dense supernodes, whose blocks faer runs on the threads.
            NormalFactor::Whole(whole) => assert!(matches!(
                whole.symbolic.raw(),
                SymbolicCholeskyRaw::Supernodal(_)
            )),
            NormalFactor::Shared(_) => panic!("a factor shared among ranks"),
        }
        solve_with(&mut factor, matrix, b)
    })
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn the_split_solve_does_not_depend_on_the_number_of_threads() {
    let matrix = grid_normal_matrix(60, 40);
    let b: Vec<f64> = (0..matrix.n).map(|k| (k as f64).sin()).collect();
    assert!(same_bits(
        &solved_on(1, &matrix, &b, 0),
        &solved_on(2, &matrix, &b, 0)
    ));
}

#[test]
fn the_whole_supernodal_factor_is_the_same_on_any_number_of_threads() {
    let matrix = lattice_normal_matrix(
        [14, 14, 14],
        &[[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1]],
    );
    let b: Vec<f64> = (0..matrix.n).map(|k| (k as f64).cos()).collect();
    let one = solved_on(1, &matrix, &b, usize::MAX);
    assert!(backward_error(&matrix, &one, &b) < 1e-14);
    assert!(same_bits(&one, &solved_on(2, &matrix, &b, usize::MAX)));
}

/// A 2D packing's factor, which faer alone would make simplicial, is
/// supernodal too (faster, docs/performance.md) and keeps its bits on
/// any number of threads.
#[test]
fn a_2d_packings_whole_factor_is_supernodal_and_the_same_on_any_number_of_threads() {
    let matrix = grid_normal_matrix(30, 20);
    let b: Vec<f64> = (0..matrix.n).map(|k| (0.3 * k as f64).sin()).collect();
    let one = solved_on(1, &matrix, &b, usize::MAX);
    assert!(backward_error(&matrix, &one, &b) < 1e-14);
    assert!(same_bits(&one, &solved_on(2, &matrix, &b, usize::MAX)));
}

/// K's block on `rows` × `columns`, dense, from its upper triangle.
fn dense_block(matrix: &CscMatrix<f64>, rows: &[usize], columns: &[usize]) -> Mat<f64> {
    let position = |of: &[usize]| {
        let mut at = vec![usize::MAX; matrix.n];
        for (k, &u) in of.iter().enumerate() {
            at[u] = k;
        }
        at
    };
    let (row_at, column_at) = (position(rows), position(columns));
    let mut block = Mat::<f64>::zeros(rows.len(), columns.len());
    for c in 0..matrix.n {
        for k in matrix.colptr[c]..matrix.colptr[c + 1] {
            let r = matrix.rowval[k];
            for (i, j) in [(r, c), (c, r)] {
                if row_at[i] != usize::MAX && column_at[j] != usize::MAX {
                    block[(row_at[i], column_at[j])] = matrix.nzval[k];
                }
            }
        }
    }
    block
}

/// A half factorised up to its separator gives the separator's Schur
/// complement T = K_SS + shift − K_Si K_ii⁻¹ K_iS and, through its forward
/// and backward solves, K⁻¹ b: against dense algebra, on a dense matrix
/// (one supernode, cut at the separator's first column), on a 3D lattice
/// cut by a plane of nodes, and on a column of nodes cut by three planes, whose
/// T couples neighbouring planes only, through the interior between them (the
/// separator in several supernodes, the first reaching the second).
/// Measured: T within 8.5e-18, 1.4e-15, 2.2e-15 relative; backward errors
/// 2.4e-16 and below. (Gathering from the separator's first supernode as well
/// put T off by 5 % in the last case.)
#[test]
fn a_half_factorised_up_to_its_separator_gives_the_dense_schur_complement() {
    let dense = {
        let n = 12;
        let value = |i: usize, j: usize| ((i * 31 + j * 17) % 23) as f64 / 23.0 - 0.5;
        let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
        for c in 0..n {
            for r in 0..=c {
                let product: f64 = (0..n).map(|k| value(r, k) * value(c, k)).sum();
                rowval.push(r);
                nzval.push(product + if r == c { n as f64 } else { 0.0 });
            }
            colptr.push(rowval.len());
        }
        (
            CscMatrix::new(n, n, colptr, rowval, nzval),
            (7..12).collect::<Vec<_>>(),
        )
    };
    let plane = |size: [usize; 3], planes: &[usize]| {
        let matrix = lattice_normal_matrix(size, &[[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]]);
        let layer = size[0] * size[1];
        let separator = (0..matrix.n)
            .filter(|&u| planes.contains(&((u / 3) / layer)))
            .collect::<Vec<_>>();
        (matrix, separator)
    };
    for (matrix, separator) in [
        dense,
        plane([14, 14, 14], &[7]),
        plane([5, 5, 25], &[10, 12, 14]),
    ] {
        let n = matrix.n;
        let interior: Vec<usize> = (0..n).filter(|u| !separator.contains(u)).collect();
        let ns = separator.len();
        let mut half = split::Half::new(&matrix, &interior, &separator, None, Par::Seq).unwrap();
        let k_ii = dense_block(&matrix, &interior, &interior);
        let k_is = dense_block(&matrix, &interior, &separator);
        let k_ss = dense_block(&matrix, &separator, &separator);
        let llt = k_ii.llt(Side::Lower).unwrap();
        let t = &k_ss - k_is.transpose() * llt.solve(&k_is);
        // With a shift on the separator's diagonal, as the ranks' parts have.
        let shift: Vec<f64> = (0..ns).map(|k| 0.5 + k as f64 / 7.0).collect();
        half.factorise_shifted(&matrix, &shift).unwrap();
        let scale = (0..ns).map(|i| t[(i, i)].abs()).fold(0.0, f64::max);
        let mut largest = 0.0f64;
        for j in 0..ns {
            for i in j..ns {
                let expected = t[(i, j)] + if i == j { shift[i] } else { 0.0 };
                largest = largest.max((half.schur_part[(i, j)] - expected).abs());
            }
        }
        println!("n = {n}: T within {:e}", largest / scale);
        assert!(largest < 1e-12 * scale, "T off by {largest:e} of {scale:e}");
        // K⁻¹ b through the half: forward, T⁻¹ on the separator, backward.
        half.factorise(&matrix).unwrap();
        let b: Vec<f64> = (0..n)
            .map(|k| ((k * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect();
        let right = half.forward(&b);
        let rhs = Mat::from_fn(ns, 1, |k, _| b[separator[k]] + right[k]);
        let x_s = t.llt(Side::Lower).unwrap().solve(&rhs);
        let x_i = half.backward(x_s.as_ref());
        let mut x = vec![0.0; n];
        for (k, &u) in half.unknown.iter().take(interior.len()).enumerate() {
            x[u] = x_i[k];
        }
        for (k, &u) in separator.iter().enumerate() {
            x[u] = x_s[(k, 0)];
        }
        let error = backward_error(&matrix, &x, &b);
        println!("n = {n}: backward error {error:e}");
        assert!(error < 1e-14, "backward error {error:e}");
    }
}

/// The blocked Cholesky that ranks share ([`super::shared_schur`]), on one
/// rank: the same factor as the dense one of faer, over two full blocks
/// and a part one, and a matrix that is not positive definite refused
/// with the columns of the block where it fails.
#[test]
fn the_schur_complement_factorised_by_blocks_is_the_dense_cholesky() {
    use super::shared_schur::{factorise_together, Workspace, BLOCK};
    use grainflow_core::Communicator;
    let n = 2 * BLOCK + 37;
    // Σ = B Bᵀ + n I, B with entries in [−1, 1): well conditioned, dense.
    let mut pseudo_random = 7u64;
    let mut next = || {
        pseudo_random = pseudo_random
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        2.0 * ((pseudo_random >> 11) as f64 / (1u64 << 53) as f64) - 1.0
    };
    let b = Mat::<f64>::from_fn(n, n, |_, _| next());
    let schur = Mat::<f64>::from_fn(n, n, |i, j| {
        (0..n).map(|k| b[(i, k)] * b[(j, k)]).sum::<f64>() + if i == j { n as f64 } else { 0.0 }
    });
    let mut dense = schur.clone();
    let mut work = MemBuffer::new(
        faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
            n,
            Par::Seq,
            Default::default(),
        ),
    );
    factorise_schur(dense.as_mut(), &mut work).unwrap();
    let mut blocked = schur.clone();
    factorise_together(
        &mut blocked,
        &Communicator::serial(),
        &mut Workspace::new(n),
    )
    .unwrap();
    let (mut largest, mut scale) = (0.0f64, 0.0f64);
    for j in 0..n {
        for i in j..n {
            largest = largest.max((blocked[(i, j)] - dense[(i, j)]).abs());
            scale = scale.max(dense[(i, j)].abs());
        }
    }
    // And L Lᵀ gives Σ back.
    let mut residual = 0.0f64;
    for j in 0..n {
        for i in j..n {
            let product: f64 = (0..=j).map(|k| blocked[(i, k)] * blocked[(j, k)]).sum();
            residual = residual.max((product - schur[(i, j)]).abs());
        }
    }
    let schur_scale = (0..n).map(|i| schur[(i, i)]).fold(0.0, f64::max);
    println!(
        "blocked against dense Cholesky: {:.2e} relative; L Lᵀ − Σ: {:.2e} relative",
        largest / scale,
        residual / schur_scale
    );
    assert!(largest <= 1e-13 * scale, "{largest} of {scale}");
    assert!(
        residual <= 1e-14 * schur_scale,
        "{residual} of {schur_scale}"
    );
    // Negative on a diagonal of the second block: refused there.
    let mut indefinite = schur.clone();
    indefinite[(BLOCK + 5, BLOCK + 5)] = -1.0;
    let error = factorise_together(
        &mut indefinite,
        &Communicator::serial(),
        &mut Workspace::new(n),
    )
    .unwrap_err();
    assert!(
        error.contains(&format!("columns {BLOCK} to {}", 2 * BLOCK)),
        "{error}"
    );
}
