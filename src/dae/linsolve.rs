//! Sparse direct solvers for the iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ`.
//!
//! Shaped as *analyse once, factorize many times*: [`LinearSolver::analyse`] sees the fixed
//! pattern once (fill-reducing ordering, symbolic factorization), [`LinearSolver::factorize`]
//! is called at every Jacobian update with new values in that pattern's order, and
//! [`LinearSolver::solve_in_place`] back-substitutes.
//!
//! Backends: faer's supernodal sparse LU, sequential ([`FaerLu`], the default; measured
//! faster than its 2-thread run and than KLU on P2 elasticity matrices), with faer's
//! COLAMD or another column ordering ([`ColumnOrdering`]), SUNDIALS' KLU with AMD ordering
//! ([`crate::sundials::KluLu`]) or on a matrix permuted beforehand ([`Permuted`], e.g. by
//! METIS's nested dissection), UMFPACK ([`crate::sundials::UmfpackLu`]), and faer's LU on
//! the half-size system left after eliminating the velocities of a first-order (u, v)
//! system ([`super::condensed::CondensedLu`]). docs/benchmarks.md ("Fill-reducing
//! ordering") compares them. Which one an integrator uses is given by a
//! [`LinearSolverFactory`] in its options ([`crate::solver::LinearSolver`] for users).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::{Perm, PermRef};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::lu::{
    LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu, simplicial, supernodal,
};
use faer::sparse::linalg::{LuError, SupernodalThreshold, amd, qr};
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
    /// A slice whose length does not fit what was analysed: the values of the pattern or a
    /// right-hand side for the unknowns.
    #[error("{solver}: {}", operand.describe(*got, *expected))]
    WrongLength {
        /// The backend ("KLU", "UMFPACK", "condensed solver", a permuted solver's name).
        solver: &'static str,
        /// Which slice.
        operand: Operand,
        /// Its length.
        got: usize,
        /// The pattern's entries or the unknowns.
        expected: usize,
    },
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

impl LinearSolverError {
    /// An `operand` of length `got` where `expected` were analysed: an error unless they
    /// agree.
    pub fn check_length(
        solver: &'static str,
        operand: Operand,
        got: usize,
        expected: usize,
    ) -> Result<(), Self> {
        let e = Self::WrongLength {
            solver,
            operand,
            got,
            expected,
        };
        (got == expected).then_some(()).ok_or(e)
    }

    /// The state `s` of a solver, required analysed: `NotReady("analyse")` if it is not.
    pub fn analysed<T>(s: Option<T>) -> Result<T, Self> {
        s.ok_or(Self::NotReady("analyse"))
    }

    /// The state `s` of an analysed solver, required factorized when `factorized` says
    /// not: `NotReady` for the step missing.
    pub fn ready<T>(s: Option<T>, factorized: bool) -> Result<T, Self> {
        let s = Self::analysed(s)?;
        factorized.then_some(s).ok_or(Self::NotReady("factorize"))
    }

    /// A solution `x` from `solver`: an error (a zero pivot spread by back-substitution:
    /// its column is not known here) unless every entry is finite.
    pub fn check_finite(solver: &'static str, x: &[f64], detail: &str) -> Result<(), Self> {
        if x.iter().all(|v| v.is_finite()) {
            return Ok(());
        }
        Err(LinearSolverError::Singular {
            solver,
            column: None,
            detail: detail.into(),
        })
    }
}

/// What a linear solver is given whose length must fit what it analysed
/// ([`LinearSolverError::WrongLength`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Operand {
    /// The matrix values, one per entry of the pattern.
    Values,
    /// A right-hand side, one entry per unknown.
    Rhs,
}

impl Operand {
    /// The mismatch in words, for [`LinearSolverError::WrongLength`].
    fn describe(self, got: usize, expected: usize) -> String {
        match self {
            Operand::Values => format!("{got} values for a pattern of {expected} entries"),
            Operand::Rhs => format!("right-hand side of length {got} for {expected} unknowns"),
        }
    }
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
/// factory (e.g. [`crate::solver::LinearSolver`], which knows every backend, KLU from
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

/// A fill-reducing ordering computed outside faer from the pattern alone: the
/// permutation `perm` (the column eliminated k-th is `perm[k]`), or why it failed.
pub type OrderingFn = fn(&Pattern) -> Result<Vec<usize>, OrderingError>;

/// Why an external ordering ([`OrderingFn`]) failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrderingError {
    /// The pattern is not square.
    #[error("{rows} × {cols} matrix: not square")]
    NotSquare {
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
    },
    /// More unknowns than the library's indices can count.
    #[error("{unknowns} unknowns: too many for {library}'s 32-bit indices")]
    TooLarge {
        /// The unknowns.
        unknowns: usize,
        /// The library ("METIS").
        library: &'static str,
    },
    /// The library's routine returned an error status.
    #[error("{function} returned {status}")]
    Failed {
        /// The routine ("METIS_NodeND").
        function: &'static str,
        /// Its status.
        status: i64,
    },
}

/// The fill-reducing column ordering of [`FaerLu`]. faer's LU pivots rows by partial
/// pivoting within the order of columns chosen here.
#[derive(Debug, Clone, Copy)]
pub enum ColumnOrdering {
    /// faer's own: COLAMD, which orders the columns for the Cholesky factor of AᵀA (the
    /// bound on L and U for any row pivoting).
    Colamd,
    /// Approximate minimum degree on the symmetrized pattern A + Aᵀ (faer's AMD): the
    /// ordering of a Cholesky factorization, right for a structurally symmetric matrix
    /// whose pivots stay near the diagonal.
    Amd,
    /// An ordering computed by `order` (e.g. METIS's nested dissection, from
    /// [`crate::solver`]); the solver is reported as `name`.
    External {
        /// The solver's short name for reports ("faer-metis").
        name: &'static str,
        /// The ordering.
        order: OrderingFn,
    },
}

impl ColumnOrdering {
    /// Short name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            ColumnOrdering::Colamd => "colamd",
            ColumnOrdering::Amd => "amd",
            ColumnOrdering::External { name, .. } => name,
        }
    }
}

/// The state of [`FaerLu`] after `analyse` with faer's own ordering (COLAMD): faer's
/// symbolic and numeric LU objects.
struct FaerOwn {
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
}

/// The numeric factors of a [`Given`] ordering, supernodal or simplicial.
enum GivenFactors {
    Supernodal {
        symbolic: supernodal::SymbolicSupernodalLu<usize>,
        lu: supernodal::SupernodalLu<usize, f64>,
    },
    Simplicial(simplicial::SimplicialLu<usize, f64>),
}

/// The state of [`FaerLu`] after `analyse` with a given column permutation: faer's
/// lower-level LU (column elimination tree, column counts, supernodal symbolic), which,
/// unlike `factorize_symbolic_lu`, takes the permutation from the caller.
struct Given {
    col_perm: Perm<usize>,
    /// The row pivoting of the last factorization (`None` before the first one, or
    /// after one that failed).
    row_perm: Option<Perm<usize>>,
    /// The pattern of Aᵀ, and for each of its entries the position of the same entry in
    /// A's values (the supernodal numeric LU reads the rows of A from Aᵀ).
    at: Pattern,
    at_src: Vec<usize>,
    at_val: Vec<f64>,
    factors: GivenFactors,
}

enum Backend {
    Own(Box<FaerOwn>),
    Given(Box<Given>),
}

/// faer's sparse LU with partial pivoting, the symbolic analysis reused for every
/// numerical factorization, and a choice of fill-reducing column ordering
/// ([`ColumnOrdering`]; faer's COLAMD by default).
pub struct FaerLu {
    par: Par,
    threshold: SupernodalThreshold,
    ordering: ColumnOrdering,
    pattern: Option<Pattern>,
    backend: Option<Backend>,
    mem: MemBuffer,
    factorized: bool,
}

impl Default for FaerLu {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerLu {
    /// Sequential supernodal LU with faer's COLAMD ordering.
    pub fn new() -> Self {
        Self::with_options(Par::Seq, SupernodalThreshold::FORCE_SUPERNODAL)
    }

    /// Sequential supernodal LU with the column ordering `ordering`.
    pub fn with_ordering(ordering: ColumnOrdering) -> Self {
        Self {
            ordering,
            ..Self::new()
        }
    }

    /// Chooses the parallelism and the supernodal/simplicial switch (COLAMD ordering).
    /// With another ordering, any threshold but `FORCE_SIMPLICIAL` means supernodal.
    pub fn with_options(par: Par, threshold: SupernodalThreshold) -> Self {
        Self {
            par,
            threshold,
            ordering: ColumnOrdering::Colamd,
            pattern: None,
            backend: None,
            mem: MemBuffer::new(StackReq::EMPTY),
            factorized: false,
        }
    }

    /// The same solver with the column ordering `ordering`.
    pub fn ordered_by(mut self, ordering: ColumnOrdering) -> Self {
        self.ordering = ordering;
        self
    }

    /// The column ordering.
    pub fn ordering(&self) -> ColumnOrdering {
        self.ordering
    }

    /// The column permutation of the last analysis (`perm[k]`: the column eliminated
    /// k-th).
    pub fn column_permutation(&self) -> Option<&[usize]> {
        match self.backend.as_ref()? {
            Backend::Own(own) => Some(own.symbolic.col_perm().arrays().0),
            Backend::Given(g) => Some(g.col_perm.arrays().0),
        }
    }

    /// nnz(L) + nnz(U) of the last factorization, where faer exposes the factors: the
    /// simplicial LU with a given ordering (the supernodal one stores its blocks with
    /// their explicit zeros and does not tell). The structural fill of the same ordering
    /// and pivots: run the simplicial LU with [`Self::column_permutation`] to count it.
    pub fn factor_nnz(&self) -> Option<usize> {
        match self.backend.as_ref()? {
            Backend::Given(g) if self.factorized => match &g.factors {
                GivenFactors::Simplicial(lu) => Some(
                    lu.l_factor_unsorted().compute_nnz() + lu.u_factor_unsorted().compute_nnz(),
                ),
                GivenFactors::Supernodal { .. } => None,
            },
            _ => None,
        }
    }

    fn analyse_own(&mut self, pattern: &Pattern) -> Result<StackReq, LinearSolverError> {
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
        self.backend = Some(Backend::Own(Box::new(FaerOwn {
            symbolic,
            numeric: NumericLu::new(),
        })));
        Ok(req)
    }

    fn analyse_given(
        &mut self,
        pattern: &Pattern,
        col_fwd: Vec<usize>,
    ) -> Result<StackReq, LinearSolverError> {
        let n = pattern.ncols();
        if pattern.nrows() != n {
            return Err(LinearSolverError::Other(format!(
                "faer LU: the matrix is {} × {n}, not square",
                pattern.nrows()
            )));
        }
        let mut col_inv = vec![usize::MAX; n];
        if col_fwd.len() != n {
            return Err(LinearSolverError::Other(format!(
                "{} ordering: {} entries for {n} columns",
                self.ordering.name(),
                col_fwd.len()
            )));
        }
        for (k, &j) in col_fwd.iter().enumerate() {
            if j >= n || col_inv[j] != usize::MAX {
                return Err(LinearSolverError::Other(format!(
                    "{} ordering is not a permutation (column {j} at {k})",
                    self.ordering.name()
                )));
            }
            col_inv[j] = k;
        }
        let (at, at_src) = transpose_pattern(pattern);
        let nnz = at_src.len();
        let oom = |_| LinearSolverError::Other("out of memory for the LU analysis".into());
        let factors = if self.threshold == SupernodalThreshold::FORCE_SIMPLICIAL {
            GivenFactors::Simplicial(simplicial::SimplicialLu::new())
        } else {
            let perm = PermRef::new_checked(&col_fwd, &col_inv, n);
            let mut etree = vec![0usize; n];
            let mut post = vec![0usize; n];
            let mut col_counts = vec![0usize; n];
            let mut min_col = vec![0usize; n];
            let mut mem = MemBuffer::try_new(StackReq::any_of(&[
                qr::col_etree_scratch::<usize>(n, n),
                qr::postorder_scratch::<usize>(n),
                qr::column_counts_aat_scratch::<usize>(n, n),
                supernodal::factorize_supernodal_symbolic_lu_scratch::<usize>(n, n),
            ]))
            .map_err(oom)?;
            let stack = MemStack::new(&mut mem);
            let etree = qr::col_etree(pattern.as_ref(), Some(perm), &mut etree, stack);
            qr::postorder(&mut post, etree, stack);
            qr::column_counts_ata(
                &mut col_counts,
                &mut min_col,
                at.as_ref(),
                Some(perm),
                etree,
                &post,
                stack,
            );
            let symbolic = supernodal::factorize_supernodal_symbolic_lu(
                pattern.as_ref(),
                Some(perm),
                &min_col,
                etree,
                &col_counts,
                stack,
                Default::default(),
            )
            .map_err(|e| LinearSolverError::Other(format!("faer symbolic LU: {e:?}")))?;
            GivenFactors::Supernodal {
                symbolic,
                lu: supernodal::SupernodalLu::new(),
            }
        };
        let req = match &factors {
            GivenFactors::Supernodal { symbolic, .. } => StackReq::any_of(&[
                supernodal::factorize_supernodal_numeric_lu_scratch::<usize, f64>(
                    symbolic,
                    Default::default(),
                ),
                supernodal::solve_in_place_scratch::<usize, f64>(n, 1, self.par),
            ]),
            GivenFactors::Simplicial(_) => StackReq::any_of(&[
                simplicial::factorize_simplicial_numeric_lu_scratch::<usize, f64>(n, n),
                simplicial::solve_in_place_scratch::<usize, f64>(n, 1, self.par),
            ]),
        };
        let col_perm = Perm::new_checked(col_fwd.into_boxed_slice(), col_inv.into_boxed_slice(), n);
        self.backend = Some(Backend::Given(Box::new(Given {
            col_perm,
            row_perm: None,
            at,
            at_src,
            at_val: vec![0.0; nnz],
            factors,
        })));
        Ok(req)
    }
}

/// The pattern of Aᵀ (sorted) and, for each of its entries, the position of the same
/// entry in A's values.
fn transpose_pattern(a: &Pattern) -> (Pattern, Vec<usize>) {
    let (m, n) = (a.nrows(), a.ncols());
    let (cp, ri) = (a.col_ptr(), a.row_idx());
    let nnz = cp[n] - cp[0];
    let mut col_ptr = vec![0usize; m + 1];
    for j in 0..n {
        for &i in &ri[cp[j]..cp[j + 1]] {
            col_ptr[i + 1] += 1;
        }
    }
    for i in 0..m {
        col_ptr[i + 1] += col_ptr[i];
    }
    let mut next = col_ptr.clone();
    let mut row_idx = vec![0usize; nnz];
    let mut src = vec![0usize; nnz];
    // Columns of A in increasing order: each column of Aᵀ gets its rows sorted.
    for j in 0..n {
        for k in cp[j]..cp[j + 1] {
            let i = ri[k];
            row_idx[next[i]] = j;
            src[next[i]] = k;
            next[i] += 1;
        }
    }
    (Pattern::new_checked(n, m, col_ptr, None, row_idx), src)
}

fn lu_error(e: LuError) -> LinearSolverError {
    match e {
        LuError::SymbolicSingular { index } => LinearSolverError::Singular {
            solver: "faer",
            column: Some(index),
            detail: "no pivot found in the numeric LU".into(),
        },
        other => LinearSolverError::Other(format!("faer numeric LU: {other:?}")),
    }
}

impl LinearSolver for FaerLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        self.backend = None;
        self.pattern = None;
        self.factorized = false;
        let req = match self.ordering {
            ColumnOrdering::Colamd => self.analyse_own(pattern)?,
            ColumnOrdering::Amd => {
                let n = pattern.ncols();
                if pattern.nrows() != n {
                    return Err(LinearSolverError::Other(
                        "AMD ordering of a non-square matrix".into(),
                    ));
                }
                let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
                let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
                    n,
                    pattern.compute_nnz(),
                ))
                .map_err(|_| LinearSolverError::Other("out of memory for AMD".into()))?;
                amd::order_maybe_unsorted(
                    &mut fwd,
                    &mut inv,
                    pattern.as_ref(),
                    amd::Control::default(),
                    MemStack::new(&mut mem),
                )
                .map_err(|e| LinearSolverError::Other(format!("faer AMD: {e:?}")))?;
                self.analyse_given(pattern, fwd)?
            }
            ColumnOrdering::External { name, order } => {
                let perm = order(pattern)
                    .map_err(|e| LinearSolverError::Other(format!("{name} ordering: {e}")))?;
                self.analyse_given(pattern, perm)?
            }
        };
        self.mem = MemBuffer::try_new(req)
            .map_err(|_| LinearSolverError::Other("out of memory for LU workspace".into()))?;
        self.pattern = Some(pattern.clone());
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        let (Some(pattern), Some(backend)) = (&self.pattern, &mut self.backend) else {
            return Err(LinearSolverError::NotReady("analyse"));
        };
        self.factorized = false;
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        let stack = MemStack::new(&mut self.mem);
        match backend {
            Backend::Own(own) => {
                own.symbolic
                    .factorize_numeric_lu(&mut own.numeric, a, self.par, stack, Default::default())
                    .map_err(lu_error)?;
            }
            Backend::Given(g) => {
                let n = pattern.ncols();
                let (mut row_fwd, mut row_inv) = match g.row_perm.take() {
                    Some(p) => p.into_arrays(),
                    None => (vec![0; n].into_boxed_slice(), vec![0; n].into_boxed_slice()),
                };
                let col_perm = g.col_perm.as_ref();
                match &mut g.factors {
                    GivenFactors::Supernodal { symbolic, lu } => {
                        for (v, &k) in g.at_val.iter_mut().zip(&g.at_src) {
                            *v = values[k];
                        }
                        let at = SparseColMatRef::new(g.at.as_ref(), &g.at_val);
                        supernodal::factorize_supernodal_numeric_lu(
                            &mut row_fwd,
                            &mut row_inv,
                            lu,
                            a,
                            at,
                            col_perm,
                            symbolic,
                            self.par,
                            stack,
                            Default::default(),
                        )
                        .map_err(lu_error)?;
                    }
                    GivenFactors::Simplicial(lu) => {
                        simplicial::factorize_simplicial_numeric_lu(
                            &mut row_fwd,
                            &mut row_inv,
                            lu,
                            a,
                            col_perm,
                            stack,
                        )
                        .map_err(lu_error)?;
                    }
                }
                g.row_perm = Some(Perm::new_checked(row_fwd, row_inv, n));
            }
        }
        self.factorized = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        let Some(backend) = &self.backend else {
            return Err(LinearSolverError::NotReady("analyse"));
        };
        if !self.factorized {
            return Err(LinearSolverError::NotReady("factorize"));
        }
        let n = b.len();
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        let stack = MemStack::new(&mut self.mem);
        match backend {
            Backend::Own(own) => {
                LuRef::new_unchecked(&own.symbolic, &own.numeric).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    self.par,
                    stack,
                );
            }
            Backend::Given(g) => {
                let Some(row_perm) = &g.row_perm else {
                    return Err(LinearSolverError::NotReady("factorize"));
                };
                let (row_perm, col_perm) = (row_perm.as_ref(), g.col_perm.as_ref());
                // The one solve on either kind of factors (two types with no common trait).
                macro_rules! solve_with {
                    ($lu:expr) => {
                        $lu.solve_in_place_with_conj(
                            row_perm,
                            col_perm,
                            Conj::No,
                            rhs,
                            self.par,
                            stack,
                        )
                    };
                }
                match &g.factors {
                    GivenFactors::Supernodal { lu, .. } => solve_with!(lu),
                    GivenFactors::Simplicial(lu) => solve_with!(lu),
                }
            }
        }
        LinearSolverError::check_finite("faer", b, "non-finite solution (zero pivot)")
    }

    fn name(&self) -> &'static str {
        match self.ordering {
            ColumnOrdering::Colamd => "faer",
            ColumnOrdering::Amd => "faer-amd",
            ColumnOrdering::External { name, .. } => name,
        }
    }
}

/// Another solver applied to the symmetrically permuted matrix A' = P A Pᵀ, with P from an
/// ordering function: for a backend that takes no ordering from the caller (KLU with its
/// natural ordering, given the nested dissection of A + Aᵀ).
pub struct Permuted {
    name: &'static str,
    order: OrderingFn,
    inner: Box<dyn LinearSolver>,
    /// `perm[k]`: the unknown of A at position k of A'.
    perm: Vec<usize>,
    /// For each entry of A', the position of the same entry in A's values.
    src: Vec<usize>,
    values: Vec<f64>,
    work: Vec<f64>,
    analysed: bool,
}

impl Permuted {
    /// `inner` on P A Pᵀ, P computed by `order`, reported as `name`.
    pub fn new(name: &'static str, order: OrderingFn, inner: Box<dyn LinearSolver>) -> Self {
        Self {
            name,
            order,
            inner,
            perm: Vec::new(),
            src: Vec::new(),
            values: Vec::new(),
            work: Vec::new(),
            analysed: false,
        }
    }
}

impl LinearSolver for Permuted {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        self.analysed = false;
        let n = pattern.ncols();
        if pattern.nrows() != n {
            return Err(LinearSolverError::Other(format!(
                "{}: the matrix is {} × {n}, not square",
                self.name,
                pattern.nrows()
            )));
        }
        let perm = (self.order)(pattern)
            .map_err(|e| LinearSolverError::Other(format!("{} ordering: {e}", self.name)))?;
        let mut inv = vec![usize::MAX; n];
        for (k, &i) in perm.iter().enumerate() {
            if i >= n || inv[i] != usize::MAX {
                return Err(LinearSolverError::Other(format!(
                    "{} ordering is not a permutation",
                    self.name
                )));
            }
            inv[i] = k;
        }
        if perm.len() != n {
            return Err(LinearSolverError::Other(format!(
                "{} ordering: {} entries for {n} unknowns",
                self.name,
                perm.len()
            )));
        }
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(cp[n]);
        let mut src = Vec::with_capacity(cp[n]);
        let mut col: Vec<(usize, usize)> = Vec::new();
        col_ptr.push(0);
        for &j in &perm {
            col.clear();
            col.extend((cp[j]..cp[j + 1]).map(|k| (inv[ri[k]], k)));
            col.sort_unstable();
            for &(r, k) in &col {
                row_idx.push(r);
                src.push(k);
            }
            col_ptr.push(row_idx.len());
        }
        let permuted = Pattern::new_checked(n, n, col_ptr, None, row_idx);
        self.inner.analyse(&permuted)?;
        self.values = vec![0.0; src.len()];
        self.src = src;
        self.work = vec![0.0; n];
        self.perm = perm;
        self.analysed = true;
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        if !self.analysed {
            return Err(LinearSolverError::NotReady("analyse"));
        }
        LinearSolverError::check_length(self.name, Operand::Values, values.len(), self.src.len())?;
        for (v, &k) in self.values.iter_mut().zip(&self.src) {
            *v = values[k];
        }
        self.inner.factorize(&self.values)
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        if !self.analysed {
            return Err(LinearSolverError::NotReady("analyse"));
        }
        LinearSolverError::check_length(self.name, Operand::Rhs, b.len(), self.perm.len())?;
        // A x = b ⇔ A' (P x) = P b.
        for (w, &i) in self.work.iter_mut().zip(&self.perm) {
            *w = b[i];
        }
        self.inner.solve_in_place(&mut self.work)?;
        for (&w, &i) in self.work.iter().zip(&self.perm) {
            b[i] = w;
        }
        Ok(())
    }

    fn name(&self) -> &'static str {
        self.name
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

    /// The unknowns in reverse order: an external ordering for the tests.
    fn reversed(p: &Pattern) -> Result<Vec<usize>, OrderingError> {
        Ok((0..p.ncols()).rev().collect())
    }

    const REVERSED: ColumnOrdering = ColumnOrdering::External {
        name: "faer-reversed",
        order: reversed,
    };

    /// faer's LU with every ordering, supernodal and simplicial, and the permuting
    /// wrapper.
    pub(crate) fn faer_variants() -> Vec<Box<dyn LinearSolver>> {
        let mut v: Vec<Box<dyn LinearSolver>> = Vec::new();
        for threshold in [
            SupernodalThreshold::FORCE_SUPERNODAL,
            SupernodalThreshold::FORCE_SIMPLICIAL,
        ] {
            for o in [ColumnOrdering::Colamd, ColumnOrdering::Amd, REVERSED] {
                v.push(Box::new(
                    FaerLu::with_options(Par::Seq, threshold).ordered_by(o),
                ));
            }
        }
        v.push(Box::new(Permuted::new(
            "permuted-faer",
            reversed,
            Box::new(FaerLu::new()),
        )));
        v
    }

    #[test]
    fn every_ordering_solves_with_small_residual() {
        for s in faer_variants() {
            check_solver(s);
        }
    }

    #[test]
    fn simplicial_lu_counts_its_fill() {
        let (p, v) = test_matrix(30);
        let mut s = FaerLu::with_options(Par::Seq, SupernodalThreshold::FORCE_SIMPLICIAL)
            .ordered_by(ColumnOrdering::Amd);
        s.analyse(&p).unwrap();
        assert_eq!(s.factor_nnz(), None);
        s.factorize(&v).unwrap();
        let fill = s.factor_nnz().unwrap();
        // At least A's own entries (L and U both hold the diagonal), at most dense.
        assert!(fill >= p.compute_nnz() && fill <= 30 * 31, "fill {fill}");
        let perm = s.column_permutation().unwrap();
        let mut sorted = perm.to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..30).collect::<Vec<_>>());
    }

    #[test]
    fn an_ordering_that_is_not_a_permutation_is_refused() {
        fn twice_zero(p: &Pattern) -> Result<Vec<usize>, OrderingError> {
            Ok(vec![0; p.ncols()])
        }
        let (p, _) = test_matrix(5);
        let bad = ColumnOrdering::External {
            name: "bad",
            order: twice_zero,
        };
        assert!(matches!(
            FaerLu::with_ordering(bad).analyse(&p),
            Err(LinearSolverError::Other(_))
        ));
        assert!(matches!(
            Permuted::new("bad", twice_zero, Box::new(FaerLu::new())).analyse(&p),
            Err(LinearSolverError::Other(_))
        ));
    }

    /// Factorizes [[1, 1], [1, 1]] (the second pivot is zero) and solves: the solver
    /// must report a typed singular-matrix error naming `solver`.
    pub(crate) fn check_singular(mut s: Box<dyn LinearSolver>, solver: &str) {
        let p = pattern_from_entries(2, &[(0, 0), (0, 1), (1, 0), (1, 1)]);
        s.analyse(&p).unwrap();
        let r = s
            .factorize(&[1.0, 1.0, 1.0, 1.0])
            .and_then(|_| s.solve_in_place(&mut [1.0, 2.0]));
        match r {
            Err(e @ LinearSolverError::Singular { solver: got, .. }) => {
                assert_eq!(got, solver);
                assert!(
                    e.to_string()
                        .starts_with(&format!("singular matrix in {solver}")),
                    "{e}"
                );
            }
            other => panic!("{solver}: expected a singular-matrix error, got {other:?}"),
        }
    }

    #[test]
    fn a_singular_matrix_is_a_typed_singular_error() {
        check_singular(Box::new(FaerLu::new()), "faer");
        for s in faer_variants() {
            check_singular(s, "faer");
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
