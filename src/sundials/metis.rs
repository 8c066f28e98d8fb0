//! METIS's nested-dissection ordering (`METIS_NodeND`, METIS 5 built from source by
//! `metis-sys`) of a sparse matrix's symmetrized pattern A + Aᵀ.

use std::sync::Mutex;

use metis_sys as sys;

use crate::dae::Pattern;
use crate::dae::linsolve::OrderingError;

/// METIS keeps its random-number state in globals (GKlib), so concurrent calls from the
/// runs of `paper`, `study` or `sweep` would race on it and give orderings that depend on
/// timing: calls are serialised, ours and those UMFPACK makes through CHOLMOD.
static METIS: Mutex<()> = Mutex::new(());

/// Runs `f` as the only user of METIS in this process (a poisoned lock only means another
/// call panicked outside METIS: its state is still whole).
pub(super) fn exclusive<R>(f: impl FnOnce() -> R) -> R {
    let _only_caller = METIS.lock().unwrap_or_else(|e| e.into_inner());
    f()
}

/// The nested-dissection permutation of the square pattern `a` computed by METIS on the
/// graph of A + Aᵀ (diagonal dropped): `perm[k]` is the unknown eliminated k-th.
/// Deterministic (METIS's default seed).
pub fn nested_dissection(a: &Pattern) -> Result<Vec<usize>, OrderingError> {
    let (n, entries) = square_entries(a)?;
    // Adjacency of A + Aᵀ without the diagonal.
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in entries.filter(|(i, j)| i != j) {
        adj[j].push(i);
        adj[i].push(j);
    }
    node_nd(adj)
}

/// The nested-dissection permutation of the columns of `a` computed by METIS on the graph
/// of AᵀA (columns adjacent when they share a row): the ordering of the Cholesky factor
/// of AᵀA, which bounds the L and U of an LU with partial pivoting.
pub fn nested_dissection_ata(a: &Pattern) -> Result<Vec<usize>, OrderingError> {
    let (n, entries) = square_entries(a)?;
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in entries {
        rows[i].push(j);
    }
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for cols in &rows {
        for &j in cols {
            adj[j].extend(cols.iter().copied().filter(|&k| k != j));
        }
    }
    node_nd(adj)
}

/// The order n of the square pattern `a` and its entries (i, j), column by column.
fn square_entries(
    a: &Pattern,
) -> Result<(usize, impl Iterator<Item = (usize, usize)> + '_), OrderingError> {
    let n = a.ncols();
    if a.nrows() != n {
        return Err(OrderingError::NotSquare {
            rows: a.nrows(),
            cols: n,
        });
    }
    let (cp, ri) = (a.col_ptr(), a.row_idx());
    let column = move |j: usize| ri[cp[j]..cp[j + 1]].iter().map(move |&i| (i, j));
    Ok((n, (0..n).flat_map(column)))
}

/// METIS_NodeND on the symmetric graph `adj` (no self-loops; lists deduplicated here).
fn node_nd(mut adj: Vec<Vec<usize>>) -> Result<Vec<usize>, OrderingError> {
    let n = adj.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let too_big = || OrderingError::TooLarge {
        unknowns: n,
        library: "METIS",
    };
    let mut xadj: Vec<sys::idx_t> = Vec::with_capacity(n + 1);
    let mut adjncy: Vec<sys::idx_t> = Vec::new();
    xadj.push(0);
    for list in &mut adj {
        list.sort_unstable();
        list.dedup();
        for &i in list.iter() {
            adjncy.push(sys::idx_t::try_from(i).map_err(|_| too_big())?);
        }
        xadj.push(sys::idx_t::try_from(adjncy.len()).map_err(|_| too_big())?);
    }
    let mut nvtxs = sys::idx_t::try_from(n).map_err(|_| too_big())?;
    let mut options = [0 as sys::idx_t; sys::METIS_NOPTIONS as usize];
    let mut perm: Vec<sys::idx_t> = vec![0; n];
    let mut iperm: Vec<sys::idx_t> = vec![0; n];
    // SAFETY: METIS reads nvtxs + 1 entries of xadj and xadj[n] of adjncy (a valid CSR
    // graph built above, symmetric, no self-loops) and writes n entries of perm and iperm;
    // a null vwgt means unit weights. It keeps no pointer after returning.
    let status = exclusive(|| unsafe {
        let s = sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        if s != sys::rstatus_et_METIS_OK {
            s
        } else {
            sys::METIS_NodeND(
                &mut nvtxs,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        }
    });
    if status != sys::rstatus_et_METIS_OK {
        return Err(OrderingError::Failed {
            function: "METIS_NodeND",
            status: status.into(),
        });
    }
    // METIS computes `iperm[i]`, the new position of unknown i, and from it `perm[k]`,
    // the unknown at position k: the elimination order.
    Ok(perm.iter().map(|&k| k as usize).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::pattern_from_entries;

    /// The 5-point Laplacian on an m × m grid.
    fn grid(m: usize) -> Pattern {
        let mut e = Vec::new();
        for i in 0..m {
            for j in 0..m {
                let k = i * m + j;
                e.push((k, k));
                if i + 1 < m {
                    e.push((k, k + m));
                    e.push((k + m, k));
                }
                if j + 1 < m {
                    e.push((k, k + 1));
                    e.push((k + 1, k));
                }
            }
        }
        pattern_from_entries(m * m, &e)
    }

    fn is_permutation(p: &[usize], n: usize) -> bool {
        let mut s = p.to_vec();
        s.sort_unstable();
        s == (0..n).collect::<Vec<_>>()
    }

    #[test]
    fn nested_dissection_is_a_deterministic_permutation() {
        let a = grid(20);
        let p = nested_dissection(&a).unwrap();
        assert!(is_permutation(&p, 400));
        assert_eq!(p, nested_dissection(&a).unwrap());
        let q = nested_dissection_ata(&a).unwrap();
        assert!(is_permutation(&q, 400));
        assert!(
            nested_dissection(&pattern_from_entries(0, &[]))
                .unwrap()
                .is_empty()
        );
        assert!(nested_dissection(&Pattern::new_checked(2, 1, vec![0, 0], None, vec![])).is_err());
    }
}
