//! Compressed sparse columns from entries sorted by column, and the rows
//! of such a matrix.

use clarabel::algebra::CscMatrix;

/// The column pointers of a CSC matrix of `columns` columns whose entries,
/// sorted by column, lie in the columns `sorted_columns`: `colptr[c]` is
/// where column `c` starts, `colptr[columns]` the number of entries.
pub(crate) fn column_pointers(
    columns: usize,
    sorted_columns: impl IntoIterator<Item = usize>,
) -> Vec<usize> {
    let mut colptr = vec![0usize; columns + 1];
    for c in sorted_columns {
        colptr[c + 1] += 1;
    }
    for c in 0..columns {
        colptr[c + 1] += colptr[c];
    }
    colptr
}

/// The rows of `a` divided by `scale`, each in column order: where row `r`
/// starts (`row_start[r]..row_start[r + 1]`), the column and the value of
/// each of its entries.
pub(crate) fn scaled_rows(a: &CscMatrix<f64>, scale: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let mut row_start = vec![0usize; a.m + 1];
    for &r in &a.rowval {
        row_start[r + 1] += 1;
    }
    for r in 0..a.m {
        row_start[r + 1] += row_start[r];
    }
    let mut fill = row_start.clone();
    let mut row_column = vec![0usize; a.rowval.len()];
    let mut row_value = vec![0.0; a.rowval.len()];
    for c in 0..a.n {
        for k in a.colptr[c]..a.colptr[c + 1] {
            let r = a.rowval[k];
            row_column[fill[r]] = c;
            row_value[fill[r]] = a.nzval[k] / scale;
            fill[r] += 1;
        }
    }
    (row_start, row_column, row_value)
}
