//! Compressed sparse columns from entries sorted by column.

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
