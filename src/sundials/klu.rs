//! SUNDIALS' KLU linear solver (SuiteSparse) as a [`LinearSolver`], with AMD ordering.
//!
//! It keeps its own CSC `SUNSparseMatrix` whose structure is copied from the pattern once;
//! each factorization copies the values in and calls `SUNLinSolSetup` (KLU analyses on the
//! first call and refactors afterwards, re-factoring fully when its condition estimate
//! degrades).

use sundials_sys as sys;

use super::{Context, NVector};
use crate::dae::Pattern;
use crate::dae::linsolve::{LinearSolver, LinearSolverError, Operand};

/// KLU ordering choice: 0 = AMD (SUNDIALS' default is 1 = COLAMD, measured 2–3× slower
/// on the cell's P2 matrices).
const KLU_ORDERING_AMD: i32 = 0;
/// KLU ordering choice 2: the natural ordering.
const KLU_ORDERING_NATURAL: i32 = 2;

struct KluState {
    // Drop order: solver, matrix, vectors, then the context they were created in.
    ls: sys::SUNLinearSolver,
    a: sys::SUNMatrix,
    x: NVector,
    b: NVector,
    _ctx: Context,
}

impl Drop for KluState {
    fn drop(&mut self) {
        // SAFETY: created in `KluLu::analyse`, owned here only; the vectors and the context
        // are dropped after this (field order).
        unsafe {
            sys::SUNLinSolFree(self.ls);
            sys::SUNMatDestroy(self.a);
        }
    }
}

/// SUNDIALS' KLU behind the [`LinearSolver`] trait.
pub struct KluLu {
    ordering: i32,
    state: Option<KluState>,
    nnz: usize,
    factorized: bool,
}

impl Default for KluLu {
    fn default() -> Self {
        Self {
            ordering: KLU_ORDERING_AMD,
            state: None,
            nnz: 0,
            factorized: false,
        }
    }
}

impl KluLu {
    /// An empty solver; [`LinearSolver::analyse`] allocates.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty solver that keeps the matrix's own order (KLU's natural ordering, after
    /// its block triangular form): for a matrix permuted beforehand (e.g. by nested
    /// dissection, [`crate::dae::linsolve::Permuted`]).
    pub fn natural() -> Self {
        Self {
            ordering: KLU_ORDERING_NATURAL,
            ..Self::default()
        }
    }

    /// nnz(L) + nnz(U) (each with its diagonal) of the last factorization.
    pub fn factor_nnz(&self) -> Option<usize> {
        let st = self.state.as_ref().filter(|_| self.factorized)?;
        // SAFETY: the solver is valid; KLU's numeric object, when there is one, is owned
        // by it and only read here.
        unsafe {
            let num = sys::SUNLinSol_KLUGetNumeric(st.ls);
            (!num.is_null()).then(|| ((*num).lnz + (*num).unz) as usize)
        }
    }
}

impl LinearSolver for KluLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        self.state = None;
        let n = pattern.nrows();
        let nnz = pattern.compute_nnz();
        let err = |what: &str| LinearSolverError::Other(format!("KLU: {what} failed"));
        let ctx = Context::new().map_err(LinearSolverError::Other)?;
        let x = NVector::new(n, &ctx).map_err(LinearSolverError::Other)?;
        let b = NVector::new(n, &ctx).map_err(LinearSolverError::Other)?;
        // SAFETY: plain constructors; results NULL-checked; the index arrays are written
        // within their allocated lengths (n + 1 pointers, nnz indices).
        unsafe {
            let a = sys::SUNSparseMatrix(
                n as sys::sunindextype,
                n as sys::sunindextype,
                nnz.max(1) as sys::sunindextype,
                sys::CSC_MAT as i32,
                ctx.0,
            );
            if a.is_null() {
                return Err(err("SUNSparseMatrix"));
            }
            let cp = std::slice::from_raw_parts_mut(sys::SUNSparseMatrix_IndexPointers(a), n + 1);
            for (d, s) in cp.iter_mut().zip(pattern.col_ptr()) {
                *d = *s as sys::sunindextype;
            }
            let ri = std::slice::from_raw_parts_mut(sys::SUNSparseMatrix_IndexValues(a), nnz);
            for (d, s) in ri.iter_mut().zip(pattern.row_idx()) {
                *d = *s as sys::sunindextype;
            }
            let ls = sys::SUNLinSol_KLU(x.0, a, ctx.0);
            if ls.is_null() {
                sys::SUNMatDestroy(a);
                return Err(err("SUNLinSol_KLU"));
            }
            let state = KluState {
                ls,
                a,
                x,
                b,
                _ctx: ctx,
            };
            if sys::SUNLinSol_KLUSetOrdering(ls, self.ordering) != 0 {
                return Err(err("SUNLinSol_KLUSetOrdering"));
            }
            if sys::SUNLinSolInitialize(ls) != 0 {
                return Err(err("SUNLinSolInitialize"));
            }
            self.state = Some(state);
        }
        self.nnz = nnz;
        self.factorized = false;
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        let st = LinearSolverError::analysed(self.state.as_mut())?;
        LinearSolverError::check_length("KLU", Operand::Values, values.len(), self.nnz)?;
        self.factorized = false;
        // SAFETY: the data array holds nnz values (allocated in analyse).
        let flag = unsafe {
            std::slice::from_raw_parts_mut(sys::SUNSparseMatrix_Data(st.a), self.nnz)
                .copy_from_slice(values);
            sys::SUNLinSolSetup(st.ls, st.a)
        };
        if flag != 0 {
            return Err(LinearSolverError::Singular {
                solver: "klu",
                column: None,
                detail: format!("KLU setup returned {flag}"),
            });
        }
        self.factorized = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        let st = LinearSolverError::ready(self.state.as_mut(), self.factorized)?;
        st.b.as_mut_slice().copy_from_slice(b);
        // SAFETY: all handles valid; x and b are distinct serial vectors of length n.
        let flag = unsafe { sys::SUNLinSolSolve(st.ls, st.a, st.x.0, st.b.0, 0.0) };
        if flag != 0 {
            return Err(LinearSolverError::Singular {
                solver: "klu",
                column: None,
                detail: format!("KLU solve returned {flag}"),
            });
        }
        b.copy_from_slice(st.x.as_slice());
        LinearSolverError::check_finite("klu", b, "non-finite solution")
    }

    fn name(&self) -> &'static str {
        "klu"
    }
}

#[cfg(test)]
mod tests {
    use super::KluLu;
    use crate::dae::linsolve::tests::{check_singular, check_solver};
    use crate::dae::linsolve::{LinearSolver, Permuted};
    use crate::sundials::nested_dissection;

    fn klu_metis() -> Box<Permuted> {
        Box::new(Permuted::new(
            "klu-metis",
            nested_dissection,
            Box::new(KluLu::natural()),
        ))
    }

    #[test]
    fn klu_solves_with_small_residual() {
        check_solver(Box::new(KluLu::new()));
        check_solver(Box::new(KluLu::natural()));
        check_solver(klu_metis());
    }

    #[test]
    fn klu_reports_a_singular_matrix() {
        check_singular(Box::new(KluLu::new()), "klu");
        check_singular(klu_metis(), "klu");
    }

    #[test]
    fn klu_counts_its_fill() {
        let p = crate::fem::assembly::pattern_from_entries(2, &[(0, 0), (1, 0), (1, 1)]);
        let mut s = KluLu::natural();
        s.analyse(&p).unwrap();
        assert_eq!(s.factor_nnz(), None);
        s.factorize(&[2.0, 1.0, 3.0]).unwrap();
        assert!(s.factor_nnz().unwrap() >= 3);
    }
}
