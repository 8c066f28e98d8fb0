//! Assembly into a sparse pattern fixed once: the pattern built from (row, col) entries,
//! the position of every entry in the value array, and blocks of element matrices whose
//! positions are computed once so that every later assembly only adds values.
//!
//! A global matrix `A = Σ_e P_eᵀ A_e Q_e` (element matrices `A_e` scattered by the element's
//! row and column numberings `P_e`, `Q_e`) is stored in compressed sparse columns. The
//! pattern depends only on the numbering, so it is built once ([`PatternBuilder`]); each
//! element block keeps, for each of its local entries, the index into the value array
//! ([`BlockPositions`]). Unknowns that are eliminated or absent are marked [`NONE`] and
//! their entries skipped.

use faer::sparse::SymbolicSparseColMat;

/// The fixed sparsity pattern of an assembled matrix (compressed sparse columns).
pub type Pattern = SymbolicSparseColMat<usize>;

/// Marker for an eliminated (or absent) unknown: its rows and columns are not assembled.
pub const NONE: usize = usize::MAX;

/// Position of the (row, col) entry in a pattern's value array, for refilling values by a
/// precomputed permutation. Returns `None` for an entry not in the pattern.
pub fn position(pattern: &Pattern, row: usize, col: usize) -> Option<usize> {
    let cp = pattern.col_ptr();
    let rows = &pattern.row_idx()[cp[col]..cp[col + 1]];
    rows.binary_search(&row).ok().map(|k| cp[col] + k)
}

/// Builds an n × n pattern from (row, col) pairs (duplicates merged, rows sorted in columns).
pub fn pattern_from_entries(n: usize, entries: &[(usize, usize)]) -> Pattern {
    let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &(r, c) in entries {
        cols[c].push(r);
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for mut c in cols {
        c.sort_unstable();
        c.dedup();
        row_idx.extend_from_slice(&c);
        col_ptr.push(row_idx.len());
    }
    Pattern::new_checked(n, n, col_ptr, None, row_idx)
}

/// Collects the entries of a pattern block by block, skipping [`NONE`] rows and columns.
#[derive(Debug, Clone, Default)]
pub struct PatternBuilder {
    entries: Vec<(usize, usize)>,
}

impl PatternBuilder {
    /// An empty collection.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the dense block `rows × cols` (entries with a [`NONE`] index skipped).
    pub fn add_block(&mut self, rows: &[usize], cols: &[usize]) {
        for &r in rows.iter().filter(|&&r| r != NONE) {
            for &c in cols.iter().filter(|&&c| c != NONE) {
                self.entries.push((r, c));
            }
        }
    }

    /// Adds one entry (skipped if either index is [`NONE`]).
    pub fn add(&mut self, row: usize, col: usize) {
        if row != NONE && col != NONE {
            self.entries.push((row, col));
        }
    }

    /// The n × n pattern of the collected entries.
    pub fn build(&self, n: usize) -> Pattern {
        pattern_from_entries(n, &self.entries)
    }
}

/// Position in `pattern`'s value array of (row, col), or [`NONE`] when either index is
/// [`NONE`] or the entry is not in the pattern.
pub fn position_or_none(pattern: &Pattern, row: usize, col: usize) -> usize {
    if row == NONE || col == NONE {
        NONE
    } else {
        position(pattern, row, col).unwrap_or(NONE)
    }
}

/// The positions of a dense element block `rows × cols` in a pattern's value array,
/// row-major (`k = n_cols · r + c`), [`NONE`] where the row or column is eliminated.
/// Empty for a block the element does not have.
#[derive(Debug, Clone, Default)]
pub struct BlockPositions {
    positions: Vec<usize>,
    n_cols: usize,
}

impl BlockPositions {
    /// The positions of `rows × cols` in `pattern`.
    pub fn new(pattern: &Pattern, rows: &[usize], cols: &[usize]) -> Self {
        let positions = rows
            .iter()
            .flat_map(|&r| cols.iter().map(move |&c| position_or_none(pattern, r, c)))
            .collect();
        Self {
            positions,
            n_cols: cols.len(),
        }
    }

    /// A block the element does not have (nothing is scattered).
    pub fn empty() -> Self {
        Self::default()
    }

    /// Whether the block is absent.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The positions, row-major ([`NONE`] where eliminated).
    pub fn positions(&self) -> &[usize] {
        &self.positions
    }

    /// Adds the local block `a` (row-major rows of `N` columns) to `values`:
    /// `values[pos(r, c)] += a[r][c]` for every entry not eliminated.
    #[inline]
    pub fn scatter<const N: usize>(&self, a: &[[f64; N]], values: &mut [f64]) {
        debug_assert_eq!(self.n_cols, N);
        for (row, pos) in a.iter().zip(self.positions.chunks_exact(N)) {
            for (&x, &p) in row.iter().zip(pos) {
                if p != NONE {
                    values[p] += x;
                }
            }
        }
    }

    /// Adds `a + s·b` (both row-major rows of `N` columns) to `values`, entry by entry:
    /// `values[pos(r, c)] += a[r][c] + s b[r][c]`.
    #[inline]
    pub fn scatter_combined<const N: usize>(
        &self,
        a: &[[f64; N]],
        s: f64,
        b: &[[f64; N]],
        values: &mut [f64],
    ) {
        debug_assert_eq!(self.n_cols, N);
        for ((ra, rb), pos) in a.iter().zip(b).zip(self.positions.chunks_exact(N)) {
            for ((&x, &y), &p) in ra.iter().zip(rb).zip(pos) {
                if p != NONE {
                    values[p] += x + s * y;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_find_their_entries_and_skip_eliminated_ones() {
        let mut b = PatternBuilder::new();
        b.add_block(&[0, NONE, 2], &[1, 2]);
        b.add(1, 1);
        b.add(NONE, 0);
        let p = b.build(3);
        assert_eq!(p.compute_nnz(), 5);
        let block = BlockPositions::new(&p, &[0, NONE, 2], &[1, 2]);
        let mut v = vec![0.0; 5];
        block.scatter(&[[1.0, 2.0], [9.0, 9.0], [3.0, 4.0]], &mut v);
        assert_eq!(v[position(&p, 0, 1).unwrap()], 1.0);
        assert_eq!(v[position(&p, 2, 2).unwrap()], 4.0);
        assert_eq!(v[position(&p, 1, 1).unwrap()], 0.0);
        assert_eq!(position(&p, 1, 2), None);
    }
}
