//! Sparse direct solvers for the iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ`.
//!
//! Shaped as *analyse once, factorize many times*: [`LinearSolver::analyse`] sees the fixed
//! pattern once (fill-reducing ordering, symbolic factorization), [`LinearSolver::factorize`]
//! is called at every Jacobian update with new values in that pattern's order, and
//! [`LinearSolver::solve_in_place`] back-substitutes.
//!
//! Backends: faer's supernodal sparse LU, sequential ([`FaerLu`], the default; measured
//! faster than its 2-thread run and than KLU on P2 elasticity matrices), SUNDIALS' KLU
//! with AMD ordering ([`crate::sundials::KluLu`]), and faer's LU on the half-size system
//! left after eliminating the velocities of a first-order (u, v) system
//! ([`super::condensed::CondensedLu`]). Which one an integrator uses is given by a
//! [`LinearSolverFactory`] in its options ([`crate::lu::LinearSolverKind`] for users).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu,
};
use faer::{Conj, MatMut, Par};

use super::{Dae, Pattern};

/// Why a linear solver failed.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LinearSolverError {
    /// Called out of order (e.g. solve before factorize).
    #[error("linear solver used before {0}")]
    NotReady(&'static str),
    /// The solver needs a structure the problem does not have (e.g. the condensed solver
    /// on a system without (u, v) pairs).
    #[error("{0}")]
    Unsupported(String),
    /// The matrix is singular (structurally or numerically); recoverable by the
    /// integrator (a smaller step changes `cj`).
    #[error("singular matrix in {solver}{}: {detail}", at_column(*column))]
    Singular {
        /// The backend that met it ("faer", "klu", "condensed").
        solver: &'static str,
        /// The column (unknown) with no usable pivot, when the backend tells.
        column: Option<usize>,
        /// What the backend said.
        detail: String,
    },
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

fn at_column(column: Option<usize>) -> String {
    column
        .map(|c| format!(" at column {c}"))
        .unwrap_or_default()
}

/// A sparse direct solver: analyse once, factorize many times, solve.
pub trait LinearSolver {
    /// Analyses the fixed pattern (ordering, symbolic factorization).
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError>;
    /// Numerical factorization with `values` in the pattern's order.
    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError>;
    /// Solves `J x = b`, overwriting `b` with `x`.
    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError>;
    /// Short name for reports ("faer", "klu").
    fn name(&self) -> &'static str;
}

/// Builds the linear solver of an integrator for a problem. The driver chooses the
/// factory (e.g. [`crate::lu::LinearSolverKind`], which knows every backend, KLU from
/// [`crate::sundials`] included); the integrators only call it, so this layer does not
/// depend on the backends above it.
pub trait LinearSolverFactory: std::fmt::Debug + Send + Sync {
    /// A fresh solver for `dae` (its pattern not yet analysed).
    fn build_for(&self, dae: &dyn Dae) -> Result<Box<dyn LinearSolver>, LinearSolverError>;
}

/// A factory as integrator options hold it.
pub type SharedFactory = std::sync::Arc<dyn LinearSolverFactory>;

/// The factory of [`FaerLu`], the default of the integrators' options.
#[derive(Debug, Clone, Copy, Default)]
pub struct FaerFactory;

impl LinearSolverFactory for FaerFactory {
    fn build_for(&self, _dae: &dyn Dae) -> Result<Box<dyn LinearSolver>, LinearSolverError> {
        Ok(Box::new(FaerLu::new()))
    }
}

/// faer's sparse LU (column ordering by COLAMD, partial pivoting), symbolic analysis
/// reused for every numerical factorization.
pub struct FaerLu {
    par: Par,
    threshold: SupernodalThreshold,
    pattern: Option<Pattern>,
    symbolic: Option<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    mem: MemBuffer,
    factorized: bool,
}

impl Default for FaerLu {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerLu {
    /// Sequential supernodal LU (the measured default).
    pub fn new() -> Self {
        Self::with_options(Par::Seq, SupernodalThreshold::FORCE_SUPERNODAL)
    }

    /// Chooses the parallelism and the supernodal/simplicial switch.
    pub fn with_options(par: Par, threshold: SupernodalThreshold) -> Self {
        Self {
            par,
            threshold,
            pattern: None,
            symbolic: None,
            numeric: NumericLu::new(),
            mem: MemBuffer::new(StackReq::EMPTY),
            factorized: false,
        }
    }
}

impl LinearSolver for FaerLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: self.threshold,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(pattern.as_ref(), params)
            .map_err(|e| LinearSolverError::Other(format!("faer symbolic LU: {e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(self.par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, self.par),
        ]);
        self.mem = MemBuffer::try_new(req)
            .map_err(|_| LinearSolverError::Other("out of memory for LU workspace".into()))?;
        self.symbolic = Some(symbolic);
        self.pattern = Some(pattern.clone());
        self.factorized = false;
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        let (Some(pattern), Some(symbolic)) = (&self.pattern, &self.symbolic) else {
            return Err(LinearSolverError::NotReady("analyse"));
        };
        self.factorized = false;
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        let stack = MemStack::new(&mut self.mem);
        symbolic
            .factorize_numeric_lu(&mut self.numeric, a, self.par, stack, Default::default())
            .map_err(|e| match e {
                faer::sparse::linalg::LuError::SymbolicSingular { index } => {
                    LinearSolverError::Singular {
                        solver: "faer",
                        column: Some(index),
                        detail: "no pivot found in the numeric LU".into(),
                    }
                }
                other => LinearSolverError::Other(format!("faer numeric LU: {other:?}")),
            })?;
        self.factorized = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        let Some(symbolic) = &self.symbolic else {
            return Err(LinearSolverError::NotReady("analyse"));
        };
        if !self.factorized {
            return Err(LinearSolverError::NotReady("factorize"));
        }
        let n = b.len();
        let lu = LuRef::new_unchecked(symbolic, &self.numeric);
        let stack = MemStack::new(&mut self.mem);
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, n, 1),
            self.par,
            stack,
        );
        if b.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            // The zero pivot's column is not known here: back-substitution spreads it.
            Err(LinearSolverError::Singular {
                solver: "faer",
                column: None,
                detail: "non-finite solution (zero pivot)".into(),
            })
        }
    }

    fn name(&self) -> &'static str {
        "faer"
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::fem::assembly::{pattern_from_entries, position};

    /// A small unsymmetric matrix: a 1-D convection–diffusion stencil with a dense row.
    fn test_matrix(n: usize) -> (Pattern, Vec<f64>) {
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i));
            if i > 0 {
                entries.push((i, i - 1));
            }
            if i + 1 < n {
                entries.push((i, i + 1));
            }
            entries.push((0, i));
        }
        let p = pattern_from_entries(n, &entries);
        let mut v = vec![0.0; p.compute_nnz()];
        for &(r, c) in &entries {
            let k = position(&p, r, c).unwrap();
            v[k] = if r == c {
                4.0 + r as f64 * 0.01
            } else if r == 0 {
                0.3
            } else if c < r {
                -1.3
            } else {
                -0.7
            };
        }
        (p, v)
    }

    fn matvec(p: &Pattern, v: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for j in 0..x.len() {
            for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                y[p.row_idx()[k]] += v[k] * x[j];
            }
        }
        y
    }

    /// Factorizes and solves a few random sparse systems, checking ‖Ax − b‖.
    pub(crate) fn check_solver(mut s: Box<dyn LinearSolver>) {
        let n = 50;
        let (p, v) = test_matrix(n);
        s.analyse(&p).unwrap();
        for scale in [1.0, 3.0] {
            let vs: Vec<f64> = v.iter().map(|a| a * scale).collect();
            s.factorize(&vs).unwrap();
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut b = matvec(&p, &vs, &x);
            s.solve_in_place(&mut b).unwrap();
            let r = matvec(&p, &vs, &b);
            let bb = matvec(&p, &vs, &x);
            let res: f64 = r
                .iter()
                .zip(&bb)
                .map(|(a, c)| (a - c).abs())
                .fold(0.0, f64::max);
            assert!(res < 1e-12, "{}: residual {res}", s.name());
        }
    }

    #[test]
    fn faer_solves_with_small_residual() {
        check_solver(Box::new(FaerLu::new()));
    }

    #[test]
    fn a_singular_matrix_is_a_typed_singular_error() {
        // [[1, 1], [1, 1]]: the second pivot is zero.
        let p = pattern_from_entries(2, &[(0, 0), (0, 1), (1, 0), (1, 1)]);
        let mut s = FaerLu::new();
        s.analyse(&p).unwrap();
        let r = s
            .factorize(&[1.0, 1.0, 1.0, 1.0])
            .and_then(|_| s.solve_in_place(&mut [1.0, 2.0]));
        match r {
            Err(e @ LinearSolverError::Singular { solver, .. }) => {
                assert_eq!(solver, "faer");
                assert!(e.to_string().starts_with("singular matrix in faer"), "{e}");
            }
            other => panic!("expected a singular-matrix error, got {other:?}"),
        }
    }

    #[test]
    fn solve_before_factorize_is_an_error() {
        let (p, _) = test_matrix(5);
        let mut s = FaerLu::new();
        s.analyse(&p).unwrap();
        assert!(matches!(
            s.solve_in_place(&mut [0.0; 5]),
            Err(LinearSolverError::NotReady(_))
        ));
    }
}
