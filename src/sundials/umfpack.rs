//! SuiteSparse's UMFPACK (multifrontal sparse LU, Debian's libsuitesparse-dev) as a
//! [`LinearSolver`]. On a structurally symmetric matrix with a nonzero diagonal UMFPACK
//! chooses its symmetric strategy: a fill-reducing ordering of A + Aᵀ (AMD or METIS's
//! nested dissection), pivots preferred on the diagonal (threshold 0.001), frontal
//! matrices factorized with the BLAS.

use std::os::raw::{c_long, c_void};
use std::ptr;

use crate::dae::Pattern;
use crate::dae::linsolve::{LinearSolver, LinearSolverError, Operand};

const UMFPACK_CONTROL: usize = 20;
const UMFPACK_INFO: usize = 90;
// Control entries.
const UMFPACK_STRATEGY: usize = 5;
const UMFPACK_ORDERING: usize = 10;
/// Control entry: most iterative refinement steps of a solve.
const UMFPACK_IRSTEP: usize = 7;
// Info entries.
const UMFPACK_SIZE_OF_UNIT: usize = 3;
const UMFPACK_STRATEGY_USED: usize = 18;
const UMFPACK_PEAK_MEMORY_ESTIMATE: usize = 21;
const UMFPACK_PEAK_MEMORY: usize = 41;
const UMFPACK_FLOPS: usize = 42;
const UMFPACK_LNZ: usize = 43;
const UMFPACK_UNZ: usize = 44;
// Strategies and orderings.
const UMFPACK_STRATEGY_UNSYMMETRIC: f64 = 1.0;
const UMFPACK_STRATEGY_SYMMETRIC: f64 = 3.0;
const UMFPACK_ORDERING_AMD: f64 = 1.0;
const UMFPACK_ORDERING_METIS: f64 = 3.0;
// Status.
const UMFPACK_OK: c_long = 0;
const UMFPACK_WARNING_SINGULAR_MATRIX: c_long = 1;
const UMFPACK_A: c_long = 0;

// The `dl` routines: 64-bit indices (SuiteSparse_long, `long` on 64-bit Linux). The `di`
// ones index the factors' memory with 32-bit ints and fail with "out of memory" past
// 2^31 units (16 GB) however much the machine has.
#[link(name = "umfpack")]
unsafe extern "C" {
    fn umfpack_dl_defaults(control: *mut f64);
    fn umfpack_dl_symbolic(
        n_row: c_long,
        n_col: c_long,
        ap: *const c_long,
        ai: *const c_long,
        ax: *const f64,
        symbolic: *mut *mut c_void,
        control: *const f64,
        info: *mut f64,
    ) -> c_long;
    fn umfpack_dl_numeric(
        ap: *const c_long,
        ai: *const c_long,
        ax: *const f64,
        symbolic: *mut c_void,
        numeric: *mut *mut c_void,
        control: *const f64,
        info: *mut f64,
    ) -> c_long;
    #[allow(clippy::too_many_arguments)]
    fn umfpack_dl_wsolve(
        sys: c_long,
        ap: *const c_long,
        ai: *const c_long,
        ax: *const f64,
        x: *mut f64,
        b: *const f64,
        numeric: *mut c_void,
        control: *const f64,
        info: *mut f64,
        wi: *mut c_long,
        w: *mut f64,
    ) -> c_long;
    fn umfpack_dl_free_symbolic(symbolic: *mut *mut c_void);
    fn umfpack_dl_free_numeric(numeric: *mut *mut c_void);
}

/// UMFPACK's fill-reducing ordering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UmfpackOrdering {
    /// AMD on A + Aᵀ (symmetric strategy) or COLAMD (unsymmetric): UMFPACK's default.
    Amd,
    /// METIS's nested dissection (through CHOLMOD).
    Metis,
}

/// UMFPACK behind the [`LinearSolver`] trait (64-bit indices).
pub struct UmfpackLu {
    ordering: UmfpackOrdering,
    control: [f64; UMFPACK_CONTROL],
    info: [f64; UMFPACK_INFO],
    ap: Vec<c_long>,
    ai: Vec<c_long>,
    ax: Vec<f64>,
    symbolic: *mut c_void,
    numeric: *mut c_void,
    wi: Vec<c_long>,
    w: Vec<f64>,
    x: Vec<f64>,
}

impl UmfpackLu {
    /// A solver with the given ordering; [`LinearSolver::analyse`] allocates.
    pub fn new(ordering: UmfpackOrdering) -> Self {
        let mut control = [0.0; UMFPACK_CONTROL];
        // SAFETY: writes UMFPACK_CONTROL entries.
        unsafe { umfpack_dl_defaults(control.as_mut_ptr()) };
        control[UMFPACK_ORDERING] = match ordering {
            UmfpackOrdering::Amd => UMFPACK_ORDERING_AMD,
            UmfpackOrdering::Metis => UMFPACK_ORDERING_METIS,
        };
        // UMFPACK's default iterative refinement (up to UMFPACK_IRSTEP = 2 steps) is kept:
        // its pivoting accepts diagonal pivots down to 1e-3 of the column's largest entry,
        // and without refinement the backward error reached 2.4e-14 on the cell Jacobian
        // (test `every_backend_and_ordering_solves_the_cell_jacobian`), above the other
        // backends' 1e-16 to 1e-15.
        Self {
            ordering,
            control,
            info: [0.0; UMFPACK_INFO],
            ap: Vec::new(),
            ai: Vec::new(),
            ax: Vec::new(),
            symbolic: ptr::null_mut(),
            numeric: ptr::null_mut(),
            wi: Vec::new(),
            w: Vec::new(),
            x: Vec::new(),
        }
    }

    /// The same solver with UMFPACK's iterative refinement off: a solve is one forward and
    /// one backward substitution (a third of the default's cost on the 3-D cell), at a
    /// larger backward error (2.4e-14 on the 2-D cell Jacobian). For Newton iterations,
    /// which correct what a solve leaves.
    pub fn without_refinement(mut self) -> Self {
        self.control[UMFPACK_IRSTEP] = 0.0;
        self
    }

    /// The same solver with UMFPACK's strategy fixed instead of chosen from the pattern:
    /// `true` the symmetric one (the ordering, AMD or METIS, of A + Aᵀ; diagonal pivots
    /// preferred), `false` the unsymmetric one (a column ordering of A).
    pub fn with_symmetric_strategy(mut self, symmetric: bool) -> Self {
        self.control[UMFPACK_STRATEGY] = if symmetric {
            UMFPACK_STRATEGY_SYMMETRIC
        } else {
            UMFPACK_STRATEGY_UNSYMMETRIC
        };
        self
    }

    /// Whether the last analysis used the symmetric strategy (`None` before one).
    pub fn used_symmetric_strategy(&self) -> Option<bool> {
        (!self.symbolic.is_null())
            .then(|| self.info[UMFPACK_STRATEGY_USED] == UMFPACK_STRATEGY_SYMMETRIC)
    }

    /// Floating-point operations of the last numeric factorization.
    pub fn factor_flops(&self) -> Option<f64> {
        (!self.numeric.is_null()).then(|| self.info[UMFPACK_FLOPS])
    }

    /// UMFPACK's upper bound on the memory \[bytes\] of the symbolic and numeric
    /// factorizations together, from the last analysis (before any factorization).
    pub fn peak_memory_estimate(&self) -> Option<f64> {
        (!self.symbolic.is_null())
            .then(|| self.info[UMFPACK_PEAK_MEMORY_ESTIMATE] * self.info[UMFPACK_SIZE_OF_UNIT])
    }

    /// The memory \[bytes\] the last numeric factorization used at its peak (with the
    /// symbolic analysis'), as UMFPACK counts it.
    pub fn peak_memory(&self) -> Option<f64> {
        (!self.numeric.is_null())
            .then(|| self.info[UMFPACK_PEAK_MEMORY] * self.info[UMFPACK_SIZE_OF_UNIT])
    }

    /// nnz(L) + nnz(U) (both with their diagonal) of the last factorization.
    pub fn factor_nnz(&self) -> Option<usize> {
        (!self.numeric.is_null())
            .then(|| (self.info[UMFPACK_LNZ] + self.info[UMFPACK_UNZ]) as usize)
    }

    fn free(&mut self) {
        // SAFETY: each pointer is null or was created by UMFPACK and is owned here only;
        // the free functions null it.
        unsafe {
            if !self.numeric.is_null() {
                umfpack_dl_free_numeric(&mut self.numeric);
            }
            if !self.symbolic.is_null() {
                umfpack_dl_free_symbolic(&mut self.symbolic);
            }
        }
        self.numeric = ptr::null_mut();
        self.symbolic = ptr::null_mut();
    }
}

impl Drop for UmfpackLu {
    fn drop(&mut self) {
        self.free();
    }
}

impl LinearSolver for UmfpackLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        self.free();
        let n = pattern.ncols();
        let nnz = pattern.compute_nnz();
        let too_big = || LinearSolverError::Other(format!("UMFPACK: {nnz} entries: too many"));
        if pattern.nrows() != n {
            return Err(LinearSolverError::Other(
                "UMFPACK: matrix not square".into(),
            ));
        }
        let int = |v: usize| c_long::try_from(v).map_err(|_| too_big());
        self.ap = pattern
            .col_ptr()
            .iter()
            .map(|&v| int(v))
            .collect::<Result<_, _>>()?;
        self.ai = pattern.row_idx()[..nnz]
            .iter()
            .map(|&v| int(v))
            .collect::<Result<_, _>>()?;
        self.ax = vec![0.0; nnz];
        self.x = vec![0.0; n];
        self.wi = vec![0; n];
        self.w = vec![0.0; 5 * n];
        // SAFETY: a valid CSC pattern of n columns (ap n + 1 entries, ai nnz); no values
        // (null Ax: the analysis uses the pattern only); Symbolic written on success. The
        // METIS ordering runs inside (through CHOLMOD), on METIS's global state: exclusive.
        let n_c = int(n)?;
        let status = super::metis::exclusive(|| unsafe {
            umfpack_dl_symbolic(
                n_c,
                n_c,
                self.ap.as_ptr(),
                self.ai.as_ptr(),
                ptr::null(),
                &mut self.symbolic,
                self.control.as_ptr(),
                self.info.as_mut_ptr(),
            )
        });
        if status != UMFPACK_OK {
            self.symbolic = ptr::null_mut();
            return Err(LinearSolverError::Other(format!(
                "UMFPACK symbolic analysis returned {status}"
            )));
        }
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        if self.symbolic.is_null() {
            return Err(LinearSolverError::NotReady("analyse"));
        }
        LinearSolverError::check_length("UMFPACK", Operand::Values, values.len(), self.ax.len())?;
        self.ax.copy_from_slice(values);
        // SAFETY: the previous Numeric (if any) is freed; the arrays are those analysed.
        let status = unsafe {
            if !self.numeric.is_null() {
                umfpack_dl_free_numeric(&mut self.numeric);
            }
            umfpack_dl_numeric(
                self.ap.as_ptr(),
                self.ai.as_ptr(),
                self.ax.as_ptr(),
                self.symbolic,
                &mut self.numeric,
                self.control.as_ptr(),
                self.info.as_mut_ptr(),
            )
        };
        match status {
            UMFPACK_OK => Ok(()),
            UMFPACK_WARNING_SINGULAR_MATRIX => {
                // SAFETY: the (singular) factors are freed: no solve with them.
                unsafe { umfpack_dl_free_numeric(&mut self.numeric) };
                self.numeric = ptr::null_mut();
                Err(LinearSolverError::Singular {
                    solver: "umfpack",
                    column: None,
                    detail: "zero pivot in the numeric factorization".into(),
                })
            }
            s => {
                self.numeric = ptr::null_mut();
                Err(LinearSolverError::Other(format!(
                    "UMFPACK numeric factorization returned {s}"
                )))
            }
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        if self.symbolic.is_null() {
            return Err(LinearSolverError::NotReady("analyse"));
        }
        if self.numeric.is_null() {
            return Err(LinearSolverError::NotReady("factorize"));
        }
        LinearSolverError::check_length("UMFPACK", Operand::Rhs, b.len(), self.x.len())?;
        // SAFETY: x, b of length n, Wi n and W 5n as wsolve requires; Numeric valid.
        let status = unsafe {
            umfpack_dl_wsolve(
                UMFPACK_A,
                self.ap.as_ptr(),
                self.ai.as_ptr(),
                self.ax.as_ptr(),
                self.x.as_mut_ptr(),
                b.as_ptr(),
                self.numeric,
                self.control.as_ptr(),
                self.info.as_mut_ptr(),
                self.wi.as_mut_ptr(),
                self.w.as_mut_ptr(),
            )
        };
        if status != UMFPACK_OK {
            return Err(LinearSolverError::Singular {
                solver: "umfpack",
                column: None,
                detail: format!("UMFPACK solve returned {status}"),
            });
        }
        b.copy_from_slice(&self.x);
        LinearSolverError::check_finite("umfpack", b, "non-finite solution")
    }

    fn name(&self) -> &'static str {
        match self.ordering {
            UmfpackOrdering::Amd => "umfpack",
            UmfpackOrdering::Metis => "umfpack-metis",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::dae::linsolve::tests::{check_singular, check_solver};

    #[test]
    fn umfpack_solves_with_small_residual() {
        for o in [UmfpackOrdering::Amd, UmfpackOrdering::Metis] {
            check_solver(Box::new(UmfpackLu::new(o)));
        }
    }

    #[test]
    fn umfpack_reports_a_singular_matrix() {
        for o in [UmfpackOrdering::Amd, UmfpackOrdering::Metis] {
            check_singular(Box::new(UmfpackLu::new(o)), "umfpack");
        }
    }

    #[test]
    fn umfpack_counts_its_fill() {
        let p = crate::fem::assembly::pattern_from_entries(2, &[(0, 0), (1, 0), (1, 1)]);
        let mut s = UmfpackLu::new(UmfpackOrdering::Amd);
        s.analyse(&p).unwrap();
        assert_eq!(s.factor_nnz(), None);
        s.factorize(&[2.0, 1.0, 3.0]).unwrap();
        // L: 2 diagonal + 1 below (or none, if UMFPACK pivots the other way), U: 2.
        let f = s.factor_nnz().unwrap();
        assert!((4..=5).contains(&f), "fill {f}");
    }
}
